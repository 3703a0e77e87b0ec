//! Scenes: a TOML file names the device the controller is told about, the plant as it is
//! (mismatch and the extras of model.md §8), the amplifier, the sensor, the controller's
//! settings, faults to inject, and what to output. `host-sim run [SCENE]`.

use std::path::{Path, PathBuf};

use de_resonator::acquire::Stall;
use de_resonator::{DeviceParams, Setting};
use serde::Deserialize;

use crate::engine::closed_loop::{Analog, CurrentMonitor, Loop, Scripted, Sensor};
use crate::engine::plant::{AmplifierModel, Branch, Leakage, Plant, MAX_BRANCHES};
use crate::engine::solver::{Solver, Tolerance};
use de_resonator::wire::protocol::MAX_LINE;

/// The reference scene, built in: the main job.
pub const REFERENCE: &str = include_str!("../../scenes/reference.toml");

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: String,
    #[serde(default)]
    description: String,
    #[serde(default = "ten")]
    duration_seconds: f64,
    #[serde(default)]
    seed: u64,
    /// The device the controller is told about: device-file keys (none: the reference).
    #[serde(default)]
    device: toml::Table,
    #[serde(default)]
    plant: PlantFile,
    #[serde(default)]
    amplifier: AmplifierFile,
    sensor: Option<SensorFile>,
    current_monitor: Option<CurrentMonitorFile>,
    /// The board's analog front end (the settings file's `[front_end]`, and the ADC's
    /// `noise_codes`): the sensors read through the ADC, as the firmware reads them.
    front_end: Option<toml::Table>,
    /// The controller's settings: `Setting::ALL`'s keys (the core's one list), `target_hz`
    /// required, the rest `Settings::for_target`'s when absent.
    controller: toml::Table,
    #[serde(default)]
    faults: FaultsFile,
    /// Command-port lines sent at times (`[[commands]]`).
    #[serde(default)]
    commands: Vec<CommandFile>,
    #[serde(default)]
    output: OutputFile,
}

fn ten() -> f64 {
    10.0
}
fn one() -> f64 {
    1.0
}
fn infinite() -> f64 {
    f64::INFINITY
}

/// The plant against the nominal device: scale factors, extras.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlantFile {
    #[serde(default = "one")]
    shear_modulus_scale: f64,
    #[serde(default = "one")]
    permittivity_scale: f64,
    #[serde(default = "one")]
    bar_mass_scale: f64,
    #[serde(default = "one")]
    prestretch_scale: f64,
    /// `vhb-4910`: the equilibrium modulus and three branches of model.md §9.
    preset: Option<String>,
    /// Viscous damping c, N·s; or a quality factor at the target frequency.
    damping: Option<f64>,
    quality_factor: Option<f64>,
    #[serde(default)]
    branches: Vec<BranchFile>,
    #[serde(default = "dop853")]
    solver: Solver,
    /// The plant solver's relative and absolute tolerance.
    #[serde(default = "tolerance")]
    rtol: f64,
    #[serde(default = "tolerance")]
    atol: f64,
    /// The membrane's leakage resistance, Ω (default: none); it may fall geometrically to
    /// `leakage_final_ohms` over `leakage_ramp_seconds`; below `breakdown_below_ohms` under
    /// voltage the membrane breaks down.
    #[serde(default = "infinite")]
    leakage_ohms: f64,
    leakage_final_ohms: Option<f64>,
    #[serde(default)]
    leakage_ramp_seconds: f64,
    #[serde(default)]
    breakdown_below_ohms: f64,
}

impl Default for PlantFile {
    fn default() -> Self {
        toml::from_str("").unwrap_or_else(|_| unreachable!("every key has a default"))
    }
}

fn dop853() -> Solver {
    Solver::Dop853
}
fn tolerance() -> f64 {
    1e-10
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BranchFile {
    modulus: f64,
    relaxation_seconds: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AmplifierFile {
    #[serde(default = "reference_volts")]
    dac_reference_volts: f64,
    #[serde(default = "gain")]
    gain: f64,
    #[serde(default = "infinite")]
    bandwidth_hz: f64,
    #[serde(default = "infinite")]
    slew_volts_per_second: f64,
    #[serde(default = "infinite")]
    rail_volts: f64,
}

impl Default for AmplifierFile {
    fn default() -> Self {
        toml::from_str("").unwrap_or_else(|_| unreachable!("every key has a default"))
    }
}

fn reference_volts() -> f64 {
    2.5
}
fn gain() -> f64 {
    4000.0
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SensorFile {
    #[serde(default)]
    noise: f64,
    #[serde(default)]
    resolution: f64,
    #[serde(default = "one_tick")]
    every_ticks: u32,
    stuck_after_seconds: Option<f64>,
    #[serde(default)]
    amplifier_monitor: bool,
}

fn one_tick() -> u32 {
    1
}

/// The amplifier's current monitor: its noise at its own sample rate, averaged over a tick.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CurrentMonitorFile {
    /// RMS noise of one sample, A.
    #[serde(default)]
    noise_amps: f64,
    /// Its sample rate, Hz (the tick averages its samples).
    #[serde(default = "ten_khz")]
    sample_hz: f64,
    /// The quantum of the tick's mean, A (0: none).
    #[serde(default)]
    resolution_amps: f64,
}

fn ten_khz() -> f64 {
    1e4
}

/// A command-port line the scene sends, before the tick at `at_seconds`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CommandFile {
    at_seconds: f64,
    line: String,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct FaultsFile {
    dac_bus_fails_after_seconds: Option<f64>,
    /// From this time on the stretch input's code repeats its last (a stuck sensor read
    /// through `[front_end]`), s.
    stretch_stuck_after_seconds: Option<f64>,
    /// When the ADC overruns (its DMA requests stop until re-armed), s.
    #[serde(default)]
    adc_overrun_at_seconds: Vec<f64>,
    /// When the ADC's DMA stream has a transfer error (the stream stops until re-armed), s.
    #[serde(default)]
    dma_error_at_seconds: Vec<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct OutputFile {
    /// The time history as CSV (t, stretch, volts).
    #[serde(default)]
    history: bool,
    /// A plot of the run (SVG).
    #[serde(default = "yes")]
    plot: bool,
}

impl Default for OutputFile {
    fn default() -> Self {
        toml::from_str("").unwrap_or_else(|_| unreachable!("every key has a default"))
    }
}

fn yes() -> bool {
    true
}

/// A scene, ready to run.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub description: String,
    /// What the `[device]` section is: the reference device, or its keys.
    pub device_source: String,
    pub run: Loop,
    /// Write the time history as CSV.
    pub history: bool,
    /// Write a plot of the run.
    pub plot: bool,
}

/// The VHB 4910 data of model.md §9 (Wang et al. 2016): equilibrium modulus, branches.
const VHB_4910: (f64, [(f64, f64); 3]) = (15e3, [(26.1e3, 0.61), (26.5e3, 6.6), (10.8e3, 61.0)]);

/// Parse a scene's text. Errors are one line.
pub fn parse(text: &str) -> Result<Scene, String> {
    let file: SceneFile = toml::from_str(text).map_err(|e| {
        let message = e.message().trim().replace('\n', " ");
        match e.span() {
            Some(span) => {
                let line = text.get(..span.start).unwrap_or(text).matches('\n').count() + 1;
                format!("line {line}: {message}")
            }
            None => message,
        }
    })?;
    // No [device]: the reference device; else a device file's keys (absent jlim: neo-Hookean).
    let batch = if file.device.is_empty() {
        de_resonator::model::tolerance::DeviceBox::exact(de_resonator::REFERENCE_DEVICE)
    } else {
        let text = toml::to_string(&file.device).map_err(|e| e.to_string())?;
        crate::device_file::parse_box(&text).map_err(|e| format!("[device]: {e}"))?
    };
    let nominal = batch.nominal;
    // The device told must itself be valid: its errors name [device], not the plant made
    // from it.
    de_resonator::Device::new(nominal).map_err(|e| format!("[device]: {e}"))?;
    let mut settings = crate::settings_file::from_table(&file.controller, "[controller]", None)?;
    // The board's settings declare the amplifier the scene fits (its slew rate and
    // bandwidth), unless the [controller] table says otherwise.
    for (declared, value) in [
        (
            Setting::AmplifierSlewVoltsPerSecond,
            file.amplifier.slew_volts_per_second,
        ),
        (Setting::AmplifierBandwidthHz, file.amplifier.bandwidth_hz),
    ] {
        let value = value as f32;
        if file.controller.get(declared.key()).is_none() && value.is_finite() && value > 0.0 {
            settings.set(declared, value);
        }
    }
    let plant = plant(&nominal, &file, settings.target_hz)?;
    if !(settings.tick_hz.is_finite() && settings.tick_hz > 0.0) {
        return Err(format!(
            "[controller] tick_hz {} must be positive",
            settings.tick_hz
        ));
    }
    if !(file.duration_seconds.is_finite() && file.duration_seconds > 0.0) {
        return Err(format!(
            "duration_seconds {} must be positive",
            file.duration_seconds
        ));
    }
    let sensor = file.sensor.as_ref().map(|s| Sensor {
        noise: s.noise,
        resolution: s.resolution,
        every_ticks: s.every_ticks,
        stuck_after_seconds: s.stuck_after_seconds,
        amplifier_monitor: s.amplifier_monitor,
    });
    let current_monitor = match &file.current_monitor {
        None => None,
        Some(m) => {
            let per_tick = m.sample_hz / f64::from(settings.tick_hz);
            if !(m.noise_amps >= 0.0 && m.resolution_amps >= 0.0 && per_tick >= 1.0) {
                return Err(
                    "[current_monitor] noise_amps and resolution_amps must be ≥ 0, \
                            sample_hz at least the tick rate"
                        .into(),
                );
            }
            Some(CurrentMonitor {
                noise_amps: m.noise_amps / per_tick.floor().sqrt(),
                resolution_amps: m.resolution_amps,
            })
        }
    };
    if let Some(s) = &sensor {
        if !(s.noise >= 0.0 && s.resolution >= 0.0 && s.every_ticks >= 1) {
            return Err("[sensor] noise and resolution must be ≥ 0, every_ticks ≥ 1".into());
        }
    }
    let analog = match &file.front_end {
        None => None,
        Some(table) => Some(analog(table, &settings, &sensor, &current_monitor)?),
    };
    let analog = match (analog, file.faults.stretch_stuck_after_seconds) {
        (_, Some(s)) if !(s >= 0.0) => {
            return Err(format!(
                "[faults] stretch_stuck_after_seconds {s} must be ≥ 0"
            ))
        }
        (None, Some(_)) => {
            return Err(
                "[faults] stretch_stuck_after_seconds needs a [front_end] (or \
                        [sensor] stuck_after_seconds without one)"
                    .into(),
            )
        }
        (Some(a), stuck) => Some(Analog {
            stretch_stuck_after_seconds: stuck,
            ..a
        }),
        (None, None) => None,
    };
    let analog = with_stalls(analog, &file.faults)?;
    let commands = commands(&file, f64::from(settings.tick_hz))?;
    let tolerance = Tolerance {
        rtol: file.plant.rtol,
        atol: file.plant.atol,
    };
    tolerance.check().map_err(|e| format!("[plant] {e}"))?;
    check_name(&file.name)?;
    let scene = Scene {
        name: file.name.clone(),
        description: file.description.clone(),
        device_source: if file.device.is_empty() {
            "reference device (built in)".into()
        } else {
            "the scene's [device]".into()
        },
        history: file.output.history,
        plot: file.output.plot,
        run: Loop {
            batch,
            plant,
            solver: file.plant.solver,
            tolerance,
            dac_reference_volts: file.amplifier.dac_reference_volts,
            settings,
            sensor,
            current_monitor,
            analog,
            bus_fails_after_seconds: file.faults.dac_bus_fails_after_seconds,
            duration_seconds: file.duration_seconds,
            seed: file.seed,
            commands,
            history: file.output.history || file.output.plot,
            stream_hz: None,
        },
    };
    // Bounded work, refused before it starts.
    scene.run.ticks()?;
    Ok(scene)
}

/// The scene's `[[commands]]`, each at the tick its time falls on: a line the command port
/// reads (no `reset` or `save`: a run does not start again or keep settings), in the scene's
/// time.
fn commands(file: &SceneFile, tick_hz: f64) -> Result<Vec<Scripted>, String> {
    let mut out = Vec::new();
    for c in &file.commands {
        let at = c.at_seconds;
        if !(at >= 0.0 && at < file.duration_seconds) {
            return Err(format!(
                "[[commands]] at_seconds {at}: a time within the scene's {} s",
                file.duration_seconds
            ));
        }
        let line = c.line.trim();
        if line.is_empty() || line.contains(['\n', '\r']) || line.len() > MAX_LINE {
            return Err(format!(
                "[[commands]] line {:?}: one line of at most {MAX_LINE} bytes",
                c.line
            ));
        }
        // A run keeps no settings and does not start again.
        if let Some(word @ ("reset" | "save")) = line.split_whitespace().next() {
            return Err(format!(
                "[[commands]] line \"{line}\": a scene cannot script a {word}"
            ));
        }
        let tick = (at * tick_hz).round();
        if tick >= (file.duration_seconds * tick_hz).round() {
            return Err(format!(
                "[[commands]] at_seconds {at}: after the scene's last tick"
            ));
        }
        out.push(Scripted {
            tick: tick as u64,
            line: line.to_string(),
        });
    }
    out.sort_by_key(|c| c.tick);
    Ok(out)
}

/// The scene's `[front_end]`: the board's (the settings file's keys) and `noise_codes`, the
/// ADC's RMS noise a conversion in the plant (default 1 code), which each channel's image
/// declares too unless the channel says otherwise (its own `noise_codes`: a board whose maker
/// measured another figure). The sensors are then read through it:
/// `[sensor]` and `[current_monitor]` are for scenes without one.
fn analog(
    table: &toml::Table,
    settings: &de_resonator::Settings,
    sensor: &Option<Sensor>,
    monitor: &Option<CurrentMonitor>,
) -> Result<Analog, String> {
    if sensor.is_some() || monitor.is_some() {
        return Err(
            "[front_end] reads the sensors through the ADC: leave out [sensor] and \
                    [current_monitor]"
                .into(),
        );
    }
    let mut table = table.clone();
    let noise_codes = match table.remove("noise_codes") {
        None => 1.0,
        Some(v) => v
            .as_float()
            .or_else(|| v.as_integer().map(|i| i as f64))
            .filter(|x| x.is_finite() && *x >= 0.0)
            .ok_or_else(|| format!("[front_end] noise_codes {v}: a number of codes ≥ 0"))?,
    };
    let front_end = crate::settings_file::front_end(&table, "[front_end]", noise_codes as f32)?;
    front_end
        .check(settings.tick_hz)
        .map_err(|e| format!("[front_end]: {e}"))?;
    Ok(Analog {
        front_end,
        noise_codes,
        stretch_stuck_after_seconds: None,
        stalls: Vec::new(),
    })
}

/// The scene's stalls of the acquisition (`[faults]` adc_overrun_at_seconds,
/// dma_error_at_seconds), in time order, on its front end.
fn with_stalls(analog: Option<Analog>, faults: &FaultsFile) -> Result<Option<Analog>, String> {
    let mut stalls: Vec<(f64, Stall)> = (faults.adc_overrun_at_seconds.iter())
        .map(|&at| (at, Stall::Overrun))
        .chain((faults.dma_error_at_seconds.iter()).map(|&at| (at, Stall::TransferError)))
        .collect();
    if let Some(&(at, _)) = stalls
        .iter()
        .find(|(at, _)| !(*at >= 0.0 && at.is_finite()))
    {
        return Err(format!(
            "[faults] adc_overrun_at_seconds, dma_error_at_seconds: {at} must be a time ≥ 0, s"
        ));
    }
    match analog {
        None if !stalls.is_empty() => Err("[faults] adc_overrun_at_seconds and \
                                           dma_error_at_seconds need a [front_end] (the ADC \
                                           they stall)"
            .into()),
        None => Ok(None),
        Some(a) => {
            stalls.sort_by(|a, b| a.0.total_cmp(&b.0));
            Ok(Some(Analog { stalls, ..a }))
        }
    }
}

/// A scene's name names its folder under `--out`: one plain path component (letters, digits,
/// `-`, `_`, `.`, not starting with `.`), so no scene writes outside `--out` or into it.
fn check_name(name: &str) -> Result<(), String> {
    let plain = name
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'));
    if name.is_empty() || name.len() > 64 || name.starts_with('.') || !plain {
        return Err(format!(
            "name {name:?}: a scene's name is its folder under --out: 1 to 64 letters, digits, \
             '-', '_' or '.', not starting with '.'"
        ));
    }
    Ok(())
}

/// The plant: the nominal device scaled, with the extras.
fn plant(nominal: &DeviceParams<f64>, file: &SceneFile, target_hz: f32) -> Result<Plant, String> {
    let p = &file.plant;
    for (key, v) in [
        ("shear_modulus_scale", p.shear_modulus_scale),
        ("permittivity_scale", p.permittivity_scale),
        ("bar_mass_scale", p.bar_mass_scale),
        ("prestretch_scale", p.prestretch_scale),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(format!("[plant] {key} = {v} must be positive"));
        }
    }
    let mut params = DeviceParams {
        shear_modulus: nominal.shear_modulus * p.shear_modulus_scale,
        relative_permittivity: nominal.relative_permittivity * p.permittivity_scale,
        bar_mass: nominal.bar_mass * p.bar_mass_scale,
        prestretch_1: nominal.prestretch_1 * p.prestretch_scale,
        prestretch_2: nominal.prestretch_2 * p.prestretch_scale,
        ..*nominal
    };
    let mut branches: Vec<Branch> = p
        .branches
        .iter()
        .map(|b| Branch {
            modulus: b.modulus,
            relaxation_seconds: b.relaxation_seconds,
        })
        .collect();
    match p.preset.as_deref() {
        None => {}
        Some("vhb-4910") => {
            params.shear_modulus = VHB_4910.0 * p.shear_modulus_scale;
            branches.extend(
                VHB_4910
                    .1
                    .iter()
                    .map(|&(modulus, relaxation_seconds)| Branch {
                        modulus,
                        relaxation_seconds,
                    }),
            );
        }
        Some(other) => {
            return Err(format!(
                "[plant] preset `{other}`: the one preset is vhb-4910"
            ))
        }
    }
    if branches.len() > MAX_BRANCHES {
        return Err(format!("[plant] at most {MAX_BRANCHES} branches"));
    }
    for b in &branches {
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if !(positive(b.modulus) && positive(b.relaxation_seconds)) {
            return Err("[plant] a branch needs a positive modulus and relaxation time".into());
        }
    }
    let a = &file.amplifier;
    let amplifier = AmplifierModel {
        gain: a.gain,
        bandwidth_hz: a.bandwidth_hz,
        slew_volts_per_second: a.slew_volts_per_second,
        rail_volts: a.rail_volts,
    };
    if !(a.gain > 0.0
        && a.bandwidth_hz > 0.0
        && a.slew_volts_per_second > 0.0
        && a.rail_volts > 0.0)
    {
        return Err("[amplifier] gain, bandwidth, slew and rail must be positive".into());
    }
    let leakage = Leakage {
        ohms: p.leakage_ohms,
        final_ohms: p.leakage_final_ohms.unwrap_or(p.leakage_ohms),
        ramp_seconds: p.leakage_ramp_seconds,
        breakdown_below_ohms: p.breakdown_below_ohms,
    };
    if !(leakage.ohms > 0.0
        && leakage.final_ohms > 0.0
        && leakage.ramp_seconds >= 0.0
        && leakage.breakdown_below_ohms >= 0.0)
    {
        return Err(
            "[plant] leakage_ohms and leakage_final_ohms must be positive (inf: none), \
                    leakage_ramp_seconds and breakdown_below_ohms ≥ 0"
                .into(),
        );
    }
    let mut plant = Plant {
        params,
        branches,
        amplifier,
        leakage,
    };
    plant.params.damping = match (p.damping, p.quality_factor) {
        (Some(_), Some(_)) => return Err("[plant] give damping or quality_factor, not both".into()),
        (Some(c), None) => c,
        (None, Some(q)) if q.is_finite() && q > 0.0 => {
            plant.mass() * std::f64::consts::TAU * f64::from(target_hz) / q
        }
        (None, Some(q)) => return Err(format!("[plant] quality_factor {q} must be positive")),
        (None, None) => nominal.damping,
    };
    de_resonator::Device::new(plant.params)
        .map_err(|e| format!("[plant]: the device scaled by [plant] is not valid: {e}"))?;
    Ok(plant)
}

/// Load a scene file.
pub fn load(path: &Path) -> Result<Scene, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read scene {}: {e}", path.display()))?;
    parse(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Where a scene's files go.
pub fn out_dir(base: &Path, scene: &Scene) -> PathBuf {
    base.join(&scene.name)
}
