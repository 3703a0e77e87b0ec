//! `run`: a scene, the firmware's controller against the full plant simulator (model.md §8);
//! a short report, and what the scene asks for (a plot, the time history).

use std::fmt;
use std::path::{Path, PathBuf};

use clap::Args;
use serde::Serialize;

use super::{finite, prepare_dir, short, sig, write_file, Crossing, DeviceInfo, Report};
use crate::engine::closed_loop::{Run, Sample};
use crate::engine::firmware::Qemu;
use crate::plot::{svg, Marker, Panel, Series, RED};
use crate::scene::{self, Scene};
use de_resonator::image::PowerUp;
use de_resonator::{Decimal, EventKind, Setting};

#[derive(Args, Debug, Default)]
pub struct RunArgs {
    /// Scene file (TOML; see scenes/ and the README).
    pub scene: Option<PathBuf>,
    /// Folder for the scene's files (a subfolder per scene).
    #[arg(long, value_name = "DIR", default_value = "out/run")]
    pub out: PathBuf,
    /// Run the firmware binary in the loop instead of the core on the host: the ELF of its
    /// link build (`cd firmware && cargo build --release --no-default-features --features
    /// qemu,log-semihosting,link`) under QEMU, flashed with the scene's image. The scene
    /// needs a `[front_end]` if it reads sensors.
    #[arg(long, value_name = "ELF")]
    pub firmware: Option<PathBuf>,
    /// Write the time history (history.csv: per tick the DAC code, the enable line, the
    /// controller's phase and the plant) even if the scene does not ask for it.
    #[arg(long)]
    pub history: bool,
    /// Record the board's telemetry stream (telemetry.csv: the records `console --record`
    /// writes): `stream <HZ>` sent before the first tick; with --firmware, read from the
    /// firmware's USART1 under QEMU.
    #[arg(long)]
    pub record: bool,
    /// The stream's rate with --record, records a second.
    #[arg(long, value_name = "HZ", default_value_t = 100.0, requires = "record")]
    pub stream_hz: f32,
}

/// The plant's own limit on its loading branch from 0 V, and the final bias's margin to it
/// (negative: the bias is past the plant's limit).
#[derive(Serialize, Debug, Clone, Copy)]
pub struct LimitReport {
    pub mode: &'static str,
    pub volts: f64,
    pub margin: f64,
}

/// A line the scene sent the command port, the board's reply, and when.
#[derive(Serialize, Debug)]
pub struct CommandReport {
    pub time_seconds: f64,
    pub line: String,
    pub reply: String,
}

/// Something the controller said, and when: its kind, its numbers by name (units in the
/// names), and its words.
#[derive(Serialize, Debug)]
pub struct EventReport {
    pub time_seconds: f64,
    /// `at_bias`, `drive_on`, `drive_off`, `trimmed`, `above_ceiling`, `fault`, `bus_fault`.
    pub kind: &'static str,
    pub values: serde_json::Map<String, serde_json::Value>,
    pub what: String,
}

/// The stretch from the capacitance (the probe's lock-in) over the run, against the plant.
#[derive(Serialize, Debug, Clone, Copy)]
pub struct SensedReport {
    pub windows: usize,
    /// The last window's estimate and standard error.
    pub stretch: f64,
    pub sigma: f64,
    /// The largest |estimate − plant's mean stretch over the window| over the windows, and
    /// the largest in standard errors.
    pub worst_error: f64,
    pub worst_sigmas: f64,
}

impl SensedReport {
    fn of(run: &Run) -> Option<Self> {
        let last = run.sensed.last()?;
        let errors = run
            .sensed
            .iter()
            .map(|s| (s.stretch - s.plant_stretch).abs());
        let sigmas = run
            .sensed
            .iter()
            .map(|s| (s.stretch - s.plant_stretch).abs() / s.sigma);
        Some(Self {
            windows: run.sensed.len(),
            stretch: last.stretch,
            sigma: last.sigma,
            worst_error: errors.fold(0.0, f64::max),
            worst_sigmas: sigmas.fold(0.0, f64::max),
        })
    }
}

/// What resonance tracking measured last: the natural frequency and Q, and the parametric
/// threshold of `sweep` that Q gives (the modulation depth h above 2/Q: README, `sweep`).
#[derive(Serialize, Debug, Clone, Copy)]
pub struct TrackedReport {
    pub natural_hz: f64,
    pub quality_factor: f64,
    pub parametric_threshold: f64,
}

impl TrackedReport {
    fn of(run: &Run) -> Option<Self> {
        let last = run
            .tracking
            .iter()
            .rev()
            .find(|t| t.quality_factor.is_finite())?;
        Some(Self {
            natural_hz: last.measured_hz,
            quality_factor: last.quality_factor,
            parametric_threshold: 2.0 / last.quality_factor,
        })
    }
}

/// One tick of the history CSV.
#[derive(Serialize)]
struct HistoryRow {
    tick: u64,
    time_seconds: f64,
    /// The board's last DAC frame's code (0 V when `dac_on` is 0) and the enable line (1:
    /// high).
    dac_code: u16,
    dac_on: u8,
    enable: u8,
    /// The controller's phase (`none`: no controller runs).
    phase: &'static str,
    stretch: f64,
    membrane_volts: f64,
    current_amps: Option<f64>,
}

/// What `run` reports.
#[derive(Serialize, Debug)]
pub struct RunReport {
    pub scene: String,
    pub description: String,
    /// The device the controller is told of (the scene's `[device]`).
    pub device: DeviceInfo,
    pub simulated_seconds: f64,
    #[serde(skip)]
    tick_hz: f32,
    pub ticks: u64,
    pub target_hz: f64,
    pub bias_volts: f64,
    pub nominal_bias_volts: Option<f32>,
    /// The most the board commands after its boot checks (`max_volts`: the cap from the
    /// device's limit or a batch's guaranteed one, or the amplifier's top), V; `None` when
    /// refused.
    pub cap_volts: Option<f32>,
    pub refused: Option<String>,
    pub fault: Option<String>,
    /// The plant's natural frequency at the final bias; `None` where a fault or a refusal
    /// ended the drive (nothing tuned to measure: not the frequency at 0 V after it).
    pub natural_frequency_hz: Option<f64>,
    pub relative_error: Option<f64>,
    /// Where the figures do not hold (the text's `note` lines).
    pub caveats: Vec<String>,
    pub limit: Option<LimitReport>,
    pub plant_crossing: Option<Crossing>,
    #[serde(skip)]
    plant_crossing_description: Option<&'static str>,
    pub final_membrane_volts: f64,
    /// With the probe on: the stretch from the capacitance against the plant.
    pub sensed: Option<SensedReport>,
    /// With tracking on: its last measurement.
    pub tracked: Option<TrackedReport>,
    pub events: Vec<EventReport>,
    /// The scene's command-port lines (`[[commands]]`) and the replies.
    pub commands: Vec<CommandReport>,
    pub run_seconds: f64,
    pub files: Vec<String>,
}

impl fmt::Display for RunReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "scene           {} ({} s simulated, controller at {} Hz)\n\
             device          {}\n\
             target          {} Hz",
            self.scene,
            sig(self.simulated_seconds),
            self.tick_hz,
            self.device,
            sig(self.target_hz),
        )?;
        if let Some(cap) = self.cap_volts {
            writeln!(
                f,
                "cap             {} V: the most the board commands",
                sig(f64::from(cap))
            )?;
        }
        match (&self.refused, &self.fault) {
            (Some(fault), _) => writeln!(f, "refused         {fault}: 0 V throughout")?,
            (None, Some(fault)) => writeln!(
                f,
                "fault           {fault}\n\
                 \x20               output {:.1} V at the end",
                // No "-0.0" for a decay a hair below zero.
                if self.final_membrane_volts.abs() < 0.05 {
                    0.0
                } else {
                    self.final_membrane_volts
                }
            )?,
            (None, None) => {
                let hz = self.natural_frequency_hz.unwrap_or(f64::NAN);
                let error = self.relative_error.unwrap_or(f64::NAN);
                writeln!(
                    f,
                    "bias            {} V\n\
                     natural freq    {} Hz in the plant at that bias: error {:+.1e} ({:+.4}%)",
                    sig(self.bias_volts),
                    sig(hz),
                    error,
                    100.0 * error
                )?;
                match self.limit {
                    Some(l) if l.margin >= 0.0 => writeln!(
                        f,
                        "margin          {:.1}% below the plant's limit ({}, {} V)",
                        100.0 * l.margin,
                        l.mode,
                        sig(l.volts)
                    )?,
                    Some(l) => writeln!(
                        f,
                        "margin          NONE: the bias is {:.1}% ABOVE the plant's limit \
                         ({}, {} V)",
                        -100.0 * l.margin,
                        l.mode,
                        sig(l.volts)
                    )?,
                    None => {}
                }
            }
        }
        for caveat in &self.caveats {
            writeln!(f, "note            {caveat}")?;
        }
        match (self.plant_crossing, self.plant_crossing_description) {
            (Some(c), Some(what)) => writeln!(
                f,
                "plant safe      NO: {} at {} s ({what})",
                c.mode,
                sig(c.time_seconds)
            )?,
            _ => writeln!(
                f,
                "plant safe      yes: no check of model.md §6 failed at any of {} ticks",
                self.ticks
            )?,
        }
        if let Some(t) = self.tracked {
            writeln!(
                f,
                "tracked         f {} Hz, Q {:.1}: parametric threshold h > 2/Q = {:.3} \
                 (sweep --quality-factor {:.1})",
                sig(t.natural_hz),
                t.quality_factor,
                t.parametric_threshold,
                t.quality_factor
            )?;
        }
        if let Some(s) = self.sensed {
            writeln!(
                f,
                "sensed λ        {:.5} ± {:.1e} from C (last of {} windows); worst error \
                 against the plant {:.1e} ({:.1} σ)",
                s.stretch, s.sigma, s.windows, s.worst_error, s.worst_sigmas
            )?;
        }
        // Events and the scene's commands in time order (a command before its tick's event).
        let mut lines: Vec<(f64, String)> = self
            .commands
            .iter()
            .map(|c| (c.time_seconds, format!("> {}  < {}", c.line, c.reply)))
            .collect();
        lines.extend(self.events.iter().map(|e| (e.time_seconds, e.what.clone())));
        lines.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (t, what) in lines {
            writeln!(f, "  {t:>8.3} s     {what}")?;
        }
        write!(f, "run time        {:.3} s", self.run_seconds)?;
        for file in &self.files {
            write!(f, "\nwrote           {file}")?;
        }
        Ok(())
    }
}

impl Report for RunReport {
    /// Done, but the plant left its true safe region, or the controller refused to start
    /// or faulted (exit status 1).
    fn failure(&self) -> Option<String> {
        if let Some(c) = self.plant_crossing {
            return Some(format!(
                "the plant crossed {} at {} s",
                c.mode,
                sig(c.time_seconds)
            ));
        }
        if let Some(why) = &self.refused {
            return Some(format!("the controller refused to start: {why}"));
        }
        self.fault
            .as_ref()
            .map(|why| format!("the controller faulted: {why}"))
    }
}

/// The scene named (or the built-in reference scene), run.
pub fn run(args: &RunArgs, quiet: bool) -> Result<RunReport, String> {
    let mut scene = match &args.scene {
        Some(path) => scene::load(path)?,
        None => {
            scene::parse(scene::REFERENCE).map_err(|e| format!("built-in reference scene: {e}"))?
        }
    };
    if args.history {
        scene.history = true;
        scene.run.history = true;
    }
    if args.record {
        scene.run.stream_hz = Some(args.stream_hz);
    }
    let dir = scene::out_dir(&args.out, &scene);
    if scene.plot || scene.history || args.record {
        prepare_dir(&dir)?;
    }
    if !quiet {
        eprintln!(
            "running scene {} ({} s)...",
            scene.name, scene.run.duration_seconds
        );
    }
    let run = match &args.firmware {
        None => scene.run.run()?,
        Some(elf) => {
            // The firmware reads the plant through its ADC only.
            if scene.run.sensor.is_some() || scene.run.current_monitor.is_some() {
                return Err(format!(
                    "{}: the scene reads its sensors directly ([sensor], [current_monitor]): \
                     give it a [front_end] to run it through the firmware's ADC",
                    scene.name
                ));
            }
            let wires = scene.run.wires();
            let image = scene.run.image(PowerUp::Drive)?;
            let mut board = Qemu::start(elf, &image, &std::env::temp_dir(), &wires)?;
            scene.run.run_on(&mut board, &wires)?
        }
    };
    let mut files = files(&dir, &scene, &run)?;
    if let Some((records, receiver)) = &run.telemetry {
        let board = match &args.firmware {
            Some(elf) => format!("the firmware {} under QEMU (link build)", elf.display()),
            None => "the core's board on the host".to_string(),
        };
        let image = scene.run.image(PowerUp::Drive)?;
        let crc = image
            .get(image.len().saturating_sub(4)..)
            .map_or(0, |b| u32::from_le_bytes(b.try_into().unwrap_or([0; 4])));
        let settings: String = Setting::ALL
            .iter()
            .map(|&k| format!(" {}={}", k.key(), Decimal(scene.run.settings.get(k))))
            .collect();
        let header = [
            format!("scene: {} ({})", scene.name, scene.description),
            format!("board: {board}"),
            format!("image_crc: {crc:#010x}"),
            format!("settings:{settings}"),
        ];
        let path = dir.join("telemetry.csv");
        let tick_hz = f64::from(scene.run.settings.tick_hz);
        let recorded = super::record::write(&path, &header, records, receiver, tick_hz)?;
        files.push(recorded.file);
    }
    Ok(report(&scene, &run, files))
}

/// What a scene's run reports (the files it wrote named in `files`).
pub fn report(scene: &Scene, run: &Run, files: Vec<String>) -> RunReport {
    // The target in force at the end (a scene's command may have changed it).
    let target = run.target_hz;
    // Measured only where the drive ran to the end (after a fault the output is at 0 V).
    let hz = Some(run.natural_frequency_hz)
        .filter(|_| run.fault_words.is_none() && run.refused.is_none())
        .and_then(finite);
    RunReport {
        scene: scene.name.clone(),
        description: scene.description.clone(),
        device: DeviceInfo::new(scene.device_source.clone(), &scene.run.batch.nominal)
            .with_tolerance(&scene.run.batch),
        simulated_seconds: scene.run.duration_seconds,
        tick_hz: scene.run.settings.tick_hz,
        ticks: run.ticks,
        target_hz: target,
        bias_volts: run.bias_volts,
        nominal_bias_volts: run.boot.filter(|b| b.driving).map(|b| b.bias_volts),
        cap_volts: run.boot.filter(|b| b.driving).map(|b| b.max_volts),
        refused: run.refused.clone(),
        fault: run.fault_words.clone(),
        natural_frequency_hz: hz,
        relative_error: hz.and_then(|hz| finite((hz - target) / target)),
        // The frequency freezes the networks over a period: said where a branch is faster.
        caveats: scene
            .run
            .plant
            .branches
            .iter()
            .map(|b| b.relaxation_seconds)
            .filter(|&s| s * target < 10.0)
            .map(|s| {
                format!(
                    "a branch relaxes in {} s, under 10 periods: the natural frequency above \
                     (networks frozen) does not hold for it",
                    sig(s)
                )
            })
            .collect(),
        limit: run.limit.map(|(mode, volts)| LimitReport {
            mode: mode.name(),
            volts,
            margin: 1.0 - run.bias_volts / volts,
        }),
        plant_crossing: Crossing::with_state(run.plant_crossing, run.plant_crossing_state),
        plant_crossing_description: run.plant_crossing.map(|(mode, _)| mode.description()),
        final_membrane_volts: run.final_membrane_volts,
        sensed: SensedReport::of(run),
        tracked: TrackedReport::of(run),
        events: run
            .events
            .iter()
            .map(|e| EventReport {
                time_seconds: e.seconds,
                kind: e.kind.name(),
                values: e
                    .values
                    .iter()
                    .map(|(name, v)| (name.to_string(), serde_json::Value::from(*v)))
                    .collect(),
                what: e.what.clone(),
            })
            .collect(),
        commands: run
            .commands
            .iter()
            .map(|c| CommandReport {
                time_seconds: c.seconds,
                line: c.line.clone(),
                reply: c.reply.clone(),
            })
            .collect(),
        run_seconds: run.run_seconds,
        files,
    }
}

/// Write what a scene asked for (history CSV, plot) into `dir`; the paths written.
fn files(dir: &Path, scene: &Scene, run: &Run) -> Result<Vec<String>, String> {
    let mut written = Vec::new();
    if scene.history {
        let rows: Vec<HistoryRow> = run
            .history
            .iter()
            .map(|h| HistoryRow {
                tick: h.tick,
                time_seconds: h.seconds,
                dac_code: h.dac_code,
                dac_on: h.dac_on.into(),
                enable: h.enable.into(),
                phase: h.phase.map_or("none", |p| p.name()),
                stretch: h.stretch,
                membrane_volts: h.membrane_volts,
                current_amps: finite(h.current_amps),
            })
            .collect();
        written.push(write_file(dir, "history.csv", &super::csv(&rows)?)?);
    }
    if scene.plot && !run.history.is_empty() {
        written.push(write_file(
            dir,
            "run.svg",
            svg(&plot(scene, run)).as_bytes(),
        )?);
    }
    Ok(written)
}

/// The run's panels: the stretch (the plant's crossing marked) and the voltage on the
/// membrane with the controller's cap and the plant's own limit; the controller's events as
/// guides (the first clause of each). Each beside its last `ZOOM_PERIODS` periods of the
/// drive (before the fault, if one came), which the whole run draws as a solid band.
fn plot(scene: &Scene, run: &Run) -> Vec<Panel> {
    let series = |name: &str, pick: fn(&Sample) -> f64| Series {
        name: name.into(),
        points: run.history.iter().map(|h| (h.seconds, pick(h))).collect(),
        ..Series::default()
    };
    let guides: Vec<(f64, String)> = run
        .events
        .iter()
        .map(|e| {
            (
                e.seconds,
                e.what.split([',', ':']).next().unwrap_or("").to_string(),
            )
        })
        .collect();
    let markers = |pick: fn(&Sample) -> f64| -> Vec<Marker> {
        run.plant_crossing
            .and_then(|(mode, t)| {
                // The tick's end after it, with the stretch where the crossing was located.
                let mut at = *run.history.iter().find(|h| h.seconds >= t)?;
                if let Some((stretch, _)) = run.plant_crossing_state {
                    at.stretch = stretch;
                }
                Some(Marker {
                    x: t,
                    y: pick(&at),
                    label: format!("{} at {} s", mode.name(), short(t)),
                    colour: RED,
                })
            })
            .into_iter()
            .collect()
    };
    let mut levels = Vec::new();
    let mut stretch_levels = Vec::new();
    if let Some(boot) = run.boot.filter(|b| b.driving) {
        levels.push((f64::from(boot.max_volts), "controller's cap".into()));
        if let Some((mode, stretch)) = boot.limit {
            stretch_levels.push((
                f64::from(stretch),
                // The static limit (§6 on the loading branch at rest): a drive's swing
                // about its bias may pass it, the monitor checks the dynamic one (§6, §7).
                format!("static limit stretch ({}, at rest)", mode.name()),
            ));
        }
    }
    if let Some((mode, volts)) = run.limit {
        levels.push((volts, format!("static limit ({})", mode.name())));
    }
    let whole = [
        Panel {
            title: format!("{}: stretch of A", scene.name),
            x_label: "time, s".into(),
            y_label: "stretch λ".into(),
            series: vec![series("plant", |h| h.stretch)],
            guides: guides.clone(),
            levels: stretch_levels,
            markers: markers(|h| h.stretch),
            ..Panel::default()
        },
        Panel {
            title: "voltage on the membrane".into(),
            x_label: "time, s".into(),
            y_label: "V".into(),
            series: vec![series("amplifier output", |h| h.membrane_volts)],
            guides,
            levels,
            markers: markers(|h| h.membrane_volts),
            ..Panel::default()
        },
    ];
    // The drive's period: the scene's AC, else the target.
    let hz = [f64::from(scene.run.settings.ac_hz), run.target_hz]
        .into_iter()
        .find(|hz| hz.is_finite() && *hz > 0.0);
    // The run's last periods, or after a fault (the drive off) the last before it.
    let fault_seconds = run
        .events
        .iter()
        .find(|e| matches!(e.kind, EventKind::Fault | EventKind::BusFault))
        .map(|e| e.seconds);
    let end = fault_seconds.unwrap_or(run.history.last().map_or(0.0, |h| h.seconds));
    let from = hz.map(|hz| end - ZOOM_PERIODS / hz);
    let which = if fault_seconds.is_some() {
        "before the fault"
    } else {
        "at the end"
    };
    let mut panels = Vec::new();
    for panel in whole {
        let zoom = match (hz, from) {
            (Some(hz), Some(from)) if from > run.history[0].seconds => Some(panel.zoom(
                from,
                end,
                format!(
                    "{ZOOM_PERIODS} periods of {} Hz {which}: {} to {} s",
                    crate::text::short(hz),
                    crate::text::short(from),
                    crate::text::short(end)
                ),
            )),
            _ => None,
        };
        panels.push(panel);
        panels.extend(zoom);
    }
    panels
}

/// How many of the drive's periods the plot's zoom panels show.
const ZOOM_PERIODS: f64 = 5.0;
