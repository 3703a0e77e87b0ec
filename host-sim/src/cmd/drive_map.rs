//! `drive-map`: the safe drive map at the bias a board tunes to (model.md §6, §7): over AC
//! amplitude × drive frequency, the full simulation's largest swing and whether it stays
//! inside §6, beside the board's own acceptance of each `ac`; drive-map.csv and
//! drive-map.svg (the two boundaries over frequency, the drives that crossed in red).

use std::fmt;
use std::path::PathBuf;

use clap::Args;
use de_resonator::model::tolerance::DeviceBox;
use serde::Serialize;

use super::image::ImageSpec;
use super::{
    prepare_dir, short, sig, write_csv_and_plot, DeviceArgs, DeviceInfo, DeviceSource, Report,
};
use crate::plot::{Mark, Panel, Series, Style, COLOURS, GREY, RED};
use crate::study::drive_map::{self, Cell, Map};

/// The most drives of a map.
pub const MAX_CELLS: usize = 100_000;

#[derive(Args, Debug)]
pub struct DriveMapArgs {
    #[command(flatten)]
    pub device: DeviceArgs,
    /// The target the board tunes to, Hz: the map is at its bias.
    ///
    /// Default: 44 Hz on the reference device; required with a device file.
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub target_hz: Option<f32>,
    /// Settings file (TOML) of the board: its margin, slew, the amplifier's slew, …
    #[arg(long, value_name = "FILE")]
    pub settings: Option<PathBuf>,
    /// Quality factor Q of the small oscillation at the bias: the damping the device file
    /// states (the board's checks use it) and the plant has, c = M·ω0/Q.
    ///
    /// Default: the device's damping.
    #[arg(
        long,
        visible_alias = "quality",
        value_name = "Q",
        allow_negative_numbers = true
    )]
    pub quality_factor: Option<f64>,
    /// AC amplitudes, V: `a,b,c` or `from:to:count`.
    ///
    /// Default: 0 to 40% of the bias, 17 values.
    #[arg(long, value_name = "VALUES", allow_hyphen_values = true)]
    pub ac_volts: Option<String>,
    /// Drive frequencies, Hz: `a,b,c` or `from:to:count`.
    ///
    /// Default: 0.3 to 2.4 times f0 at the bias, 43 values.
    #[arg(long, value_name = "VALUES", allow_hyphen_values = true)]
    pub ac_hz: Option<String>,
    /// The amplifier's gain, V/V (its full scale: 2.5 V × gain).
    #[arg(
        long,
        value_name = "G",
        default_value_t = super::image::DEFAULT_GAIN,
        allow_negative_numbers = true
    )]
    pub gain: f32,
    /// Each simulation's length, in periods of f0 at the bias (from rest, the AC switched
    /// on at t = 0).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 200.0,
        allow_negative_numbers = true
    )]
    pub periods: f64,
    /// Folder for drive-map.csv and drive-map.svg (created if needed, checked before the
    /// work).
    #[arg(long, value_name = "DIR", default_value = "out/drive-map")]
    pub out: PathBuf,
}

/// One drive: a JSON cell and a CSV row.
#[derive(Serialize, Debug)]
pub struct Row {
    pub ac_volts: f64,
    pub ac_hz: f64,
    /// The board accepts this `ac` (every boot check of `start` with it passes).
    pub accepted: bool,
    /// Why it refuses, in its words (empty: accepted).
    pub refusal: String,
    /// The full simulation's largest |λ − λ*|.
    pub max_swing: f64,
    /// The simulation stayed inside model.md §6.
    pub safe: bool,
    pub first_limit_mode: Option<&'static str>,
    pub first_limit_time_seconds: Option<f64>,
    /// Why the simulation ended early (the motion left the model's range; empty: it ran to
    /// its end).
    pub stopped: String,
}

/// What `drive-map` reports.
#[derive(Serialize, Debug)]
pub struct DriveMapReport {
    pub device: DeviceInfo,
    pub target_hz: f32,
    pub bias_volts: f64,
    /// λ* at the bias and f0 there.
    pub stretch: f64,
    pub natural_frequency_hz: f64,
    pub damping: f64,
    pub duration_seconds: f64,
    pub accepted: usize,
    pub safe: usize,
    /// Drives the board accepts that are not safe in the full simulation: they cross a limit,
    /// or leave the model's range (0: the two agree).
    pub disagreements: usize,
    pub cells: Vec<Row>,
    pub files: Vec<String>,
}

impl fmt::Display for DriveMapReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "device          {}\n\
             board           target {} Hz: bias {} V (λ* {}, f0 {} Hz), c = {} N·s\n\
             drives          {} in all, {} s each from rest\n\
             safe            {} stay inside model.md §6 in the full simulation\n\
             accepted        {} by the board's checks\n\
             agreement       {}\n\
             wrote           {}",
            self.device,
            sig(f64::from(self.target_hz)),
            sig(self.bias_volts),
            sig(self.stretch),
            sig(self.natural_frequency_hz),
            sig(self.damping),
            self.cells.len(),
            sig(self.duration_seconds),
            self.safe,
            self.accepted,
            if self.disagreements == 0 {
                "every drive the board accepts stays inside".to_string()
            } else {
                format!("{} accepted drives cross a limit", self.disagreements)
            },
            self.files.join(", ")
        )
    }
}

impl Report for DriveMapReport {
    /// An accepted drive that crosses a limit.
    fn failure(&self) -> Option<String> {
        (self.disagreements > 0).then(|| {
            format!(
                "{} drives the board accepts cross a limit of model.md §6",
                self.disagreements
            )
        })
    }
}

/// The image a board holds (the default DAC reference, the amplifier's `gain`) for `device` tuned to
/// `target_hz` (`None`: the reference job's 44 Hz on the reference device) with `settings`,
/// the damping of `quality_factor` at that bias in the device file's place if given; the
/// batch with it, and the device as reports name it.
pub fn board_image(
    device: &DeviceSource,
    target_hz: Option<f32>,
    settings: Option<PathBuf>,
    quality_factor: Option<f64>,
    gain: f32,
) -> Result<(Vec<u8>, DeviceBox, DeviceInfo), String> {
    let (mut batch, info) = device.batch()?;
    let asked = ImageSpec {
        device: device.clone(),
        settings,
        target_hz,
        gain,
        ..ImageSpec::default()
    };
    let target_hz = asked.target_or_reference_hz();
    let image_spec = |batch: DeviceBox| ImageSpec {
        device: DeviceSource::Given {
            batch: Box::new(batch),
            name: info.source.clone(),
        },
        target_hz,
        ..asked.clone()
    };
    if let Some(q) = quality_factor {
        if !(q.is_finite() && q > 0.0) {
            return Err(format!("quality factor {q}: need Q > 0"));
        }
        // The damping of Q at the bias the board tunes to with the device's own damping.
        let (image, _) = super::image::build(&image_spec(batch), "(in memory)".into())?;
        let (_, stretch, _) = drive_map::operating_point(&image, batch.nominal)?;
        let d = de_resonator::Device::new(batch.nominal).map_err(|e| e.to_string())?;
        let c = batch
            .nominal
            .damping_for_quality(d.natural_frequency_hz(stretch), q);
        batch = batch.pinned(de_resonator::Field::Damping, c);
        batch.nominal.damping = c;
    }
    let (image, _) = super::image::build(&image_spec(batch), "(in memory)".into())?;
    Ok((image, batch, info))
}

pub fn drive_map(args: &DriveMapArgs) -> Result<DriveMapReport, String> {
    let (image, batch, device) = board_image(
        &args.device.source(),
        args.target_hz,
        args.settings.clone(),
        args.quality_factor,
        args.gain,
    )?;
    let (bias, _, f0) = drive_map::operating_point(&image, batch.nominal)?;
    let amplitudes = match &args.ac_volts {
        Some(text) => super::values("--ac-volts", text, MAX_CELLS)?,
        None => (0..17).map(|k| 0.4 * bias * f64::from(k) / 16.0).collect(),
    };
    let frequencies = match &args.ac_hz {
        Some(text) => super::values("--ac-hz", text, MAX_CELLS)?,
        None => (0..43)
            .map(|k| f0 * (0.3 + 2.1 * f64::from(k) / 42.0))
            .collect(),
    };
    if amplitudes.len() * frequencies.len() > MAX_CELLS {
        return Err(format!(
            "{} drives: at most {MAX_CELLS}",
            amplitudes.len() * frequencies.len()
        ));
    }
    prepare_dir(&args.out)?;
    let map = drive_map::drive_map(
        &image,
        batch.nominal,
        &amplitudes,
        &frequencies,
        args.periods,
    )?;
    let rows: Vec<Row> = map.cells.iter().map(row).collect();
    let disagreements = map.cells.iter().filter(|c| c.disagrees()).count();
    let panel = plot(&device, &map, &frequencies);
    let files = write_csv_and_plot(&args.out, "drive-map", &rows, &[panel])?;
    let settings = de_resonator::image::Image::parse(&image)
        .map_err(|e| e.to_string())?
        .settings;
    Ok(DriveMapReport {
        device,
        target_hz: settings.target_hz,
        bias_volts: map.bias_volts,
        stretch: map.stretch,
        natural_frequency_hz: map.natural_frequency_hz,
        damping: batch.nominal.damping,
        duration_seconds: map.duration_seconds,
        accepted: rows.iter().filter(|r| r.accepted).count(),
        safe: rows.iter().filter(|r| r.safe).count(),
        disagreements,
        cells: rows,
        files,
    })
}

fn row(c: &Cell) -> Row {
    Row {
        ac_volts: c.ac_volts,
        ac_hz: c.ac_hz,
        accepted: c.refused.is_none(),
        refusal: c.refused.clone().unwrap_or_default(),
        max_swing: c.max_swing,
        safe: c.safe(),
        first_limit_mode: c.first_limit.map(|(m, _)| m.name()),
        first_limit_time_seconds: c.first_limit.map(|(_, t)| t),
        stopped: c.stopped.clone().unwrap_or_default(),
    }
}

/// Amplitude against frequency: the drives that crossed a limit in red, the safe ones grey;
/// over each frequency the largest amplitude below which every simulated drive is safe, and
/// the largest the board accepts.
fn plot(device: &DeviceInfo, map: &Map, frequencies: &[f64]) -> Panel {
    let dots = |crossed: bool| -> Vec<(f64, f64)> {
        map.cells
            .iter()
            .filter(|c| c.safe() != crossed)
            .map(|c| (c.ac_hz, c.ac_volts))
            .collect()
    };
    // Over each frequency: the top of the run of safe (accepted) amplitudes from the lowest.
    let edge = |keep: &dyn Fn(&Cell) -> bool| -> Vec<(f64, f64)> {
        frequencies
            .iter()
            .filter_map(|&hz| {
                let mut column: Vec<&Cell> = map.cells.iter().filter(|c| c.ac_hz == hz).collect();
                column.sort_by(|a, b| a.ac_volts.total_cmp(&b.ac_volts));
                column
                    .iter()
                    .take_while(|c| keep(c))
                    .last()
                    .map(|c| (hz, c.ac_volts))
            })
            .collect()
    };
    let series = vec![
        Series {
            name: "safe in the full simulation".into(),
            points: dots(false),
            style: Style {
                colour: Some(GREY),
                dots_only: true,
                ..Style::default()
            },
            label: String::new(),
        },
        Series {
            name: "crossed a limit of §6 (or left the model)".into(),
            points: dots(true),
            style: Style {
                colour: Some(RED),
                dots_only: true,
                mark: Mark::Square,
                ..Style::default()
            },
            label: String::new(),
        },
        Series {
            name: "largest safe from below".into(),
            points: edge(&|c| c.safe()),
            style: Style {
                colour: Some(COLOURS[0]),
                ..Style::default()
            },
            label: String::new(),
        },
        Series {
            name: "largest the board accepts".into(),
            points: edge(&|c| c.refused.is_none()),
            style: Style {
                colour: Some(COLOURS[2]),
                dashed: true,
                ..Style::default()
            },
            label: String::new(),
        },
    ]
    .into_iter()
    .filter(|s| !s.points.is_empty())
    .collect();
    let f0 = map.natural_frequency_hz;
    Panel {
        title: format!(
            "{}: safe drives at {} V (f0 {} Hz)",
            device.title(),
            short(map.bias_volts),
            short(f0)
        ),
        x_label: "drive frequency, Hz".into(),
        y_label: "AC amplitude, V".into(),
        series,
        guides: vec![
            (0.5 * f0, "f0/2".into()),
            (f0, "f0".into()),
            (2.0 * f0, "2 f0".into()),
        ],
        ..Panel::default()
    }
}
