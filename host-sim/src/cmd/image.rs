//! `image`: the configuration image the firmware reads from its own flash sector (layout: the
//! core's `image` module): the device, the amplifier, the default settings and the tuning
//! table; and `image --check FILE`, which reads an image (or a table) back and runs the
//! firmware's own boot checks on it, saying what they say.

use std::fmt;
use std::path::PathBuf;

use clap::Args;
use de_resonator::acquire::{Channel, FrontEnd};
use de_resonator::image::{AmplifierSpec, Image, PowerUp, DAC_BITS};
use de_resonator::table::{self, Table};
use de_resonator::{Controller, DeviceParams, Field, Setting, Settings};
use serde::Serialize;

use super::{prepare_file, sig, write_path, DeviceArgs, DeviceSource, Report};
use crate::lut;

/// The reference job's target (model.md §9, scenes/reference.toml), Hz.
pub const REFERENCE_TARGET_HZ: f32 = 44.0;
/// The DAC8551's reference, V: an image's default.
pub const DEFAULT_DAC_REFERENCE_VOLTS: f32 = 2.5;
/// The high-voltage amplifier's gain, V/V: an image's default.
pub const DEFAULT_GAIN: f32 = 4000.0;

#[derive(Args, Debug)]
pub struct ImageArgs {
    /// Where to write the image (flash it at 0x080E0000, sector 11).
    #[arg(long, value_name = "FILE", required_unless_present = "check")]
    pub out: Option<PathBuf>,
    /// Read FILE (an image or a table) back instead: what it holds, and whether the
    /// firmware's boot checks accept it (status 1 if not).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["out", "settings", "target_hz", "power_up"])]
    pub check: Option<PathBuf>,
    /// The image a scene's board boots from (`run`, `serve`: its device, amplifier, front
    /// end and settings; it drives at power-up unless --power-up says `wait`, as `serve
    /// --power-up wait` boots it), to flash the same board under QEMU or on a chip.
    #[arg(long, value_name = "SCENE.toml", conflicts_with_all = ["check", "settings", "target_hz", "device", "rail_volts"])]
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub device: DeviceArgs,
    /// Default settings (TOML, the keys of a scene's [controller] table).
    ///
    /// Default: `Settings::for_target` (5% margin, 10 kV/s, 1 kHz, no AC).
    #[arg(long, value_name = "FILE")]
    pub settings: Option<PathBuf>,
    /// The target the firmware tunes to at power-up, Hz (over the settings file's).
    ///
    /// Needed for a device other than the reference (whose default is 44 Hz).
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub target_hz: Option<f32>,
    /// The DAC's reference, V (the DAC8551's VREF).
    #[arg(
        long,
        value_name = "V",
        default_value_t = DEFAULT_DAC_REFERENCE_VOLTS,
        allow_negative_numbers = true
    )]
    pub dac_reference_volts: f32,
    /// The high-voltage amplifier's gain, V/V.
    #[arg(
        long,
        value_name = "V/V",
        default_value_t = DEFAULT_GAIN,
        allow_negative_numbers = true
    )]
    pub gain: f32,
    /// The amplifier's output rail, V.
    ///
    /// Default: the DAC's full scale times the gain.
    #[arg(long, value_name = "V", allow_negative_numbers = true)]
    pub rail_volts: Option<f32>,
    /// What the board does once its boot checks pass: `wait` with the output off at 0 V
    /// for `start` (an HV supply's way), or `drive` at once (a bench run).
    ///
    /// Default: `wait`; a --scene's image `drive`, as `run` and `serve` boot it.
    #[arg(long, value_name = "WHEN", value_enum)]
    pub power_up: Option<PowerUpArg>,
}

impl ImageArgs {
    /// The image the flags ask for.
    pub fn spec(&self) -> ImageSpec {
        ImageSpec {
            scene: self.scene.clone(),
            device: self.device.source(),
            settings: self.settings.clone(),
            target_hz: self.target_hz,
            dac_reference_volts: self.dac_reference_volts,
            gain: self.gain,
            rail_volts: self.rail_volts,
            power_up: self.power_up.map(PowerUp::from),
        }
    }
}

/// What an image is made of, whoever asks (the CLI's `image`, the Python package's `image`,
/// `drive-map`'s board): a scene's, or a device's with its settings and amplifier.
#[derive(Debug, Clone)]
pub struct ImageSpec {
    /// A scene whose board's image it is (its device, amplifier, front end and settings).
    pub scene: Option<PathBuf>,
    pub device: DeviceSource,
    /// A settings file (the keys of a scene's [controller] table).
    pub settings: Option<PathBuf>,
    /// The target at power-up, Hz, over the settings' (`None` on the reference device without
    /// settings: the reference job's).
    pub target_hz: Option<f32>,
    pub dac_reference_volts: f32,
    /// V/V.
    pub gain: f32,
    /// `None`: the DAC's full scale times the gain.
    pub rail_volts: Option<f32>,
    /// `None`: `wait` for a device's image, `drive` for a scene's.
    pub power_up: Option<PowerUp>,
}

impl ImageSpec {
    /// The target asked, or on the reference device without settings the reference job's.
    pub fn target_or_reference_hz(&self) -> Option<f32> {
        self.target_hz.or_else(|| {
            (matches!(self.device, DeviceSource::Reference) && self.settings.is_none())
                .then_some(REFERENCE_TARGET_HZ)
        })
    }
}

impl Default for ImageSpec {
    /// The reference device's image, as `image --out FILE` makes it.
    fn default() -> Self {
        Self {
            scene: None,
            device: DeviceSource::Reference,
            settings: None,
            target_hz: None,
            dac_reference_volts: DEFAULT_DAC_REFERENCE_VOLTS,
            gain: DEFAULT_GAIN,
            rail_volts: None,
            power_up: None,
        }
    }
}

/// `--power-up` (`image`, `serve`): the image's [`PowerUp`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PowerUpArg {
    /// The output off at 0 V until `start`.
    Wait,
    /// Ramp to the bias at power-up.
    Drive,
}

impl From<PowerUpArg> for PowerUp {
    fn from(arg: PowerUpArg) -> Self {
        match arg {
            PowerUpArg::Wait => PowerUp::Wait,
            PowerUpArg::Drive => PowerUp::Drive,
        }
    }
}

/// One device parameter or setting, for the report (`null`: none, as `jlim` of a
/// neo-Hookean device, which the image holds as 0).
#[derive(Serialize, Debug)]
pub struct Entry {
    pub key: &'static str,
    pub value: Option<f32>,
}

/// What the table inside holds.
#[derive(Serialize, Debug)]
pub struct TableSummary {
    pub points: usize,
    pub bytes: usize,
    pub margin: f32,
    /// The maker's measured interpolation error (relative, in f).
    pub interpolation_error: f32,
    pub frequency_range_hz: [f32; 2],
    pub top_volts: f32,
}

/// The firmware's boot checks on what the file holds.
#[derive(Serialize, Debug)]
#[serde(tag = "verdict", rename_all = "snake_case")]
pub enum Verdict {
    /// The firmware would drive: to this bias, capped here.
    Drives {
        bias_volts: f32,
        max_volts: f32,
        limit: Option<&'static str>,
        /// A batch's image (model.md §10): its guaranteed limit, V, and which bound set the
        /// cap (`limit`: the device's own, `batch`: the batch's).
        #[serde(skip_serializing_if = "Option::is_none")]
        batch_limit_volts: Option<f32>,
        #[serde(skip_serializing_if = "Option::is_none")]
        cap_by: Option<&'static str>,
    },
    /// The firmware would refuse, saying this (its own words).
    Refuses { reason: String },
}

/// What `image` wrote, or `image --check` read.
#[derive(Serialize, Debug)]
pub struct ImageReport {
    pub file: String,
    /// `image` or `table`.
    pub kind: &'static str,
    pub bytes: usize,
    /// The device parameters the image holds, in `Field::ALL` order.
    pub device_parameters: Vec<Entry>,
    pub amplifier: Option<AmplifierSummary>,
    /// What the board does at power-up once the checks pass: `wait` or `drive` (`null`: a table).
    pub power_up: Option<&'static str>,
    /// The board's analog inputs (empty: none fitted, open loop).
    pub front_end: Option<FrontEndSummary>,
    pub settings: Vec<Entry>,
    /// The settings the image does not hold (made by a host-sim before they were added): the
    /// board boots them at their defaults, and says so.
    pub defaulted: Vec<&'static str>,
    pub table: Option<TableSummary>,
    pub verdict: Verdict,
    #[serde(skip)]
    pub written: bool,
}

#[derive(Serialize, Debug)]
pub struct AmplifierSummary {
    pub dac_reference_volts: f32,
    pub gain: f32,
    pub rail_volts: f32,
    pub dac_bits: u16,
}

/// The front end an image states.
#[derive(Serialize, Debug)]
pub struct FrontEndSummary {
    pub scan_hz: f32,
    pub channels: Vec<ChannelSummary>,
}

/// One fitted channel: `reading = (code − zero_code) · per_count`, plausible in [low, high].
#[derive(Serialize, Debug)]
pub struct ChannelSummary {
    pub channel: &'static str,
    pub unit: &'static str,
    pub input: u8,
    pub zero_code: f32,
    pub per_count: f32,
    pub low: f32,
    pub high: f32,
    /// The RMS noise of a conversion it declares, codes (0: not declared).
    pub noise_codes: f32,
}

impl FrontEndSummary {
    fn of(front_end: &FrontEnd) -> Self {
        FrontEndSummary {
            scan_hz: front_end.scan_hz,
            channels: front_end
                .fitted()
                .map(|(c, s): (Channel, _)| ChannelSummary {
                    channel: c.name(),
                    unit: c.unit(),
                    input: s.input,
                    zero_code: s.zero_code,
                    per_count: s.per_count,
                    low: s.low,
                    high: s.high,
                    noise_codes: s.noise_codes,
                })
                .collect(),
        }
    }
}

impl fmt::Display for ImageReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let verb = if self.written { "wrote" } else { "read" };
        writeln!(
            f,
            "{verb} {} ({}, {} bytes)",
            self.file, self.kind, self.bytes
        )?;
        let list = |entries: &[Entry]| {
            entries
                .iter()
                .map(|e| match e.value {
                    Some(value) => format!("{} = {value}", e.key),
                    None => format!("{} = none", e.key),
                })
                .collect::<Vec<_>>()
                .join(", ")
        };
        if !self.device_parameters.is_empty() {
            writeln!(f, "device          {}", list(&self.device_parameters))?;
        }
        if let Some(a) = &self.amplifier {
            writeln!(
                f,
                "amplifier       {}-bit DAC, reference {} V, gain {}, rail {} V",
                a.dac_bits, a.dac_reference_volts, a.gain, a.rail_volts
            )?;
        }
        match self.power_up {
            Some("wait") => writeln!(
                f,
                "power-up        wait: the output off at 0 V until `start`"
            )?,
            Some(_) => writeln!(f, "power-up        drive: ramp to the bias at once")?,
            None => {}
        }
        if let Some(fe) = &self.front_end {
            if fe.channels.is_empty() {
                writeln!(
                    f,
                    "front end       none fitted: open loop (no trim, no monitor of the motion)"
                )?;
            } else {
                writeln!(f, "front end       {} scans/s", fe.scan_hz)?;
            }
            for c in &fe.channels {
                let n = |x: f32| sig(f64::from(x));
                writeln!(
                    f,
                    "  {:<13} ADC IN{}: {} {} a count, 0 at code {}, plausible {} .. {}, {}",
                    c.channel,
                    c.input,
                    n(c.per_count),
                    c.unit,
                    n(c.zero_code),
                    n(c.low),
                    n(c.high),
                    if c.noise_codes > 0.0 {
                        format!("noise {} codes rms", n(c.noise_codes))
                    } else {
                        "noise not declared".to_string()
                    }
                )?;
            }
        }
        if !self.settings.is_empty() {
            writeln!(f, "settings        {}", list(&self.settings))?;
        }
        if !self.defaulted.is_empty() {
            writeln!(
                f,
                "not in the image (made before they were added; the board boots them at their \
                 defaults): {}",
                self.defaulted.join(" ")
            )?;
        }
        if let Some(t) = &self.table {
            writeln!(
                f,
                "table           {} points, {} .. {} Hz, top {} V (margin {}), \
                 interpolation error {:.2e}",
                t.points,
                sig(f64::from(t.frequency_range_hz[0])),
                sig(f64::from(t.frequency_range_hz[1])),
                sig(f64::from(t.top_volts)),
                t.margin,
                t.interpolation_error
            )?;
        }
        match &self.verdict {
            Verdict::Drives {
                bias_volts,
                max_volts,
                limit,
                batch_limit_volts,
                cap_by,
            } => write!(
                f,
                "boot checks     pass: bias {} V, commands at or below {} V{}{}",
                sig(f64::from(*bias_volts)),
                sig(f64::from(*max_volts)),
                limit.map_or(String::new(), |m| format!(" (limit: {m})")),
                match (batch_limit_volts, cap_by) {
                    (Some(volts), Some(by)) => format!(
                        "\n                the batch's guaranteed limit {} V; the cap set by the {by}",
                        sig(f64::from(*volts))
                    ),
                    _ => String::new(),
                }
            ),
            Verdict::Refuses { reason } => write!(f, "boot checks     refuse: {reason}"),
        }
    }
}

impl Report for ImageReport {
    fn data_on_stdout(&self) -> bool {
        self.written && self.file == "-"
    }

    fn failure(&self) -> Option<String> {
        match &self.verdict {
            Verdict::Refuses { reason } => Some(format!("the firmware would refuse: {reason}")),
            Verdict::Drives { .. } => None,
        }
    }
}

pub fn image(args: &ImageArgs) -> Result<ImageReport, String> {
    if let Some(path) = &args.check {
        return check(path);
    }
    let out = args
        .out
        .as_ref()
        .ok_or("give --out FILE (or --check FILE)")?;
    prepare_file(out)?;
    let spec = args.spec();
    if spec.scene.is_none() {
        for warning in amplifier_warnings(&spec) {
            eprintln!("warning: {warning}");
        }
    }
    let (bytes, mut report) = build(&spec, out.display().to_string())?;
    for warning in noise_warnings(&report) {
        eprintln!("warning: {warning}");
    }
    write_path(out, &bytes)?;
    report.written = true;
    Ok(report)
}

/// The channels whose noise the image does not declare: the trim's ring is then weighed
/// against their quantisation alone before any voltage (and against the noise heard after).
pub fn noise_warnings(report: &ImageReport) -> Vec<String> {
    let channels = report.front_end.iter().flat_map(|fe| fe.channels.iter());
    channels
        .filter(|c| c.noise_codes == 0.0 && c.channel != "amplifier")
        .map(|c| {
            format!(
                "[front_end.{}] declares no noise_codes: before any voltage the trim weighs its \
                 ring against the quantisation alone (give the RMS noise of a conversion, as \
                 measured on the board)",
                c.channel
            )
        })
        .collect()
}

/// What no real amplifier stage has, each with its unit and the range any has: a unit slip
/// (millivolts typed as volts), warned of as a device file's implausible values are.
pub fn amplifier_warnings(spec: &ImageSpec) -> Vec<String> {
    let mut said = Vec::new();
    let mut check = |flag: &str, value: f32, low: f32, high: f32, unit: &str, slip: &str| {
        if value.is_finite() && !(low..=high).contains(&value) {
            said.push(format!(
                "`{flag}` = {value} {unit} is outside what any {slip} ({low} .. {high} {unit})"
            ));
        }
    };
    check(
        "--dac-reference-volts",
        spec.dac_reference_volts,
        0.5,
        10.0,
        "V",
        "DAC's reference has: millivolts typed as volts?",
    );
    check(
        "--gain",
        spec.gain,
        1.0,
        1e5,
        "V/V",
        "high-voltage amplifier has",
    );
    if let Some(rail) = spec.rail_volts {
        check(
            "--rail-volts",
            rail,
            1.0,
            1e5,
            "V",
            "amplifier's output rail has",
        );
    }
    said
}

/// The image `spec` asks for and what it holds, `file` its name in the report; refused (not
/// made) if the firmware's boot would refuse it.
pub fn build(spec: &ImageSpec, file: String) -> Result<(Vec<u8>, ImageReport), String> {
    if let Some(path) = &spec.scene {
        let scene = crate::scene::load(path)?;
        let bytes = scene.run.image(spec.power_up.unwrap_or(PowerUp::Drive))?;
        let report = describe(&bytes, file)?;
        if let Verdict::Refuses { reason } = &report.verdict {
            return Err(format!(
                "scene {}: the firmware would refuse its image: {reason}",
                scene.name
            ));
        }
        return Ok((bytes, report));
    }
    let (batch, name) = spec.device.batch()?;
    let target_hz = spec.target_or_reference_hz();
    let (settings, front_end) = match &spec.settings {
        Some(path) => crate::settings_file::load(path, target_hz)?,
        None => (
            Settings::for_target(target_hz.ok_or_else(|| {
                format!("{name}: give the target the firmware tunes to (--target-hz or --settings)")
            })?),
            FrontEnd::NONE,
        ),
    };
    let settings = match spec.target_hz {
        Some(hz) => Settings {
            target_hz: hz,
            ..settings
        },
        None => settings,
    };
    let full_scale = spec.dac_reference_volts * spec.gain;
    let amplifier = AmplifierSpec {
        dac_reference_volts: spec.dac_reference_volts,
        gain: spec.gain,
        rail_volts: spec.rail_volts.unwrap_or(full_scale),
        dac_bits: DAC_BITS,
    };
    let bytes = lut::image(
        &batch,
        &amplifier,
        &front_end,
        &settings,
        spec.power_up.unwrap_or(PowerUp::Wait),
    )
    .map_err(|e| format!("{name}: {e}"))?;
    // Checked before writing: an image the firmware would refuse is not made.
    let report = describe(&bytes, file)?;
    if let Verdict::Refuses { reason } = &report.verdict {
        return Err(format!(
            "{name}: the firmware would refuse this image: {reason}"
        ));
    }
    Ok((bytes, report))
}

fn check(path: &PathBuf) -> Result<ImageReport, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    describe(&bytes, path.display().to_string())
}

fn entries(params: &DeviceParams<f32>) -> Vec<Entry> {
    Field::ALL
        .iter()
        .map(|&field| Entry {
            key: field.key(),
            value: match field {
                Field::Jlim => params.jlim,
                _ => Some(params.get(field)),
            },
        })
        .collect()
}

fn summary(table: &Table<'_>, bytes: usize) -> TableSummary {
    TableSummary {
        points: table.points(),
        bytes,
        margin: table.margin(),
        interpolation_error: table.interpolation_error(),
        frequency_range_hz: [table.point(0).0, table.point(table.points() - 1).0],
        top_volts: table.max_volts(),
    }
}

/// What `bytes` hold (an image, or a bare table), and what the firmware's boot says of it.
pub fn describe(bytes: &[u8], file: String) -> Result<ImageReport, String> {
    let refuse = |reason: String| Verdict::Refuses { reason };
    if bytes.starts_with(&table::MAGIC) {
        // A bare table: what it holds, and its own checks (it has no settings to boot with).
        let parsed = Table::parse(bytes).map_err(|e| format!("{file}: {e}"))?;
        return Ok(ImageReport {
            file,
            kind: "table",
            bytes: bytes.len(),
            device_parameters: entries(&parsed.params()),
            amplifier: None,
            power_up: None,
            front_end: None,
            settings: Vec::new(),
            defaulted: Vec::new(),
            table: Some(summary(&parsed, bytes.len())),
            verdict: refuse(
                "a bare table: flash an image (`host-sim image`) holding it with its settings"
                    .into(),
            ),
            written: false,
        });
    }
    let parsed = match Image::parse(bytes) {
        Ok(parsed) => parsed,
        Err(e) => {
            return Ok(ImageReport {
                file,
                kind: "image",
                bytes: bytes.len(),
                device_parameters: Vec::new(),
                amplifier: None,
                power_up: None,
                front_end: None,
                settings: Vec::new(),
                defaulted: Vec::new(),
                table: None,
                verdict: refuse(e.to_string()),
                written: false,
            })
        }
    };
    let table = Table::parse(parsed.table).map_err(|e| format!("{file}: {e}"))?;
    let a = parsed.amplifier;
    // The firmware's boot, the same calls: the amplifier, then every boot stage.
    let verdict = match a
        .amplifier()
        .map_err(|e| e.to_string())
        .and_then(|amplifier| {
            // With the noise its front end declares, as the board boots it.
            let board = parsed.board(amplifier, parsed.settings.tick_hz);
            let mut slot = None;
            Controller::start_in(
                &mut slot,
                parsed.params,
                parsed.table,
                board,
                parsed.settings,
            )
            .map(|boot| (boot, amplifier.max_volts()))
            .map_err(|e| e.to_string())
        }) {
        // The most it commands: the cap, or the amplifier's top where lower (as `status`).
        Ok((boot, top_volts)) => Verdict::Drives {
            bias_volts: boot.bias_volts,
            max_volts: boot.max_volts.min(top_volts),
            limit: boot.limit.map(|l| l.mode.name()),
            batch_limit_volts: boot.batch_limit_volts,
            cap_by: boot.batch_limit_volts.map(|_| boot.cap_by.name()),
        },
        Err(reason) => refuse(reason),
    };
    Ok(ImageReport {
        file,
        kind: "image",
        bytes: bytes.len(),
        device_parameters: entries(&parsed.params),
        amplifier: Some(AmplifierSummary {
            dac_reference_volts: a.dac_reference_volts,
            gain: a.gain,
            rail_volts: a.rail_volts,
            dac_bits: a.dac_bits,
        }),
        power_up: Some(parsed.power_up.name()),
        front_end: Some(FrontEndSummary::of(&parsed.front_end)),
        settings: Setting::ALL
            .iter()
            .map(|&s| Entry {
                key: s.key(),
                value: Some(parsed.settings.get(s)),
            })
            .collect(),
        defaulted: parsed.defaulted.iter().map(Setting::key).collect(),
        table: Some(summary(&table, parsed.table.len())),
        verdict,
        written: false,
    })
}
