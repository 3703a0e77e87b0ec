//! `lut`: the tuning table the firmware flashes (layout: the core's `table` module), from the
//! f64 model, with its interpolation error against the direct solve.

use std::fmt;
use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use super::{prepare_file, short, sig, write_path, DeviceArgs, DeviceInfo, MarginArgs, Report};
use crate::lut;

/// How `lut` writes the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LutFormat {
    Bin,
    Csv,
}

#[derive(Args, Debug)]
pub struct LutArgs {
    /// Output file.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Number of points (2 to 1024).
    ///
    /// Default: the fewest of 64, 128, … 1024 that interpolate within 1e-5 in frequency.
    #[arg(long, value_name = "N")]
    pub points: Option<usize>,
    /// `bin` (for flashing) or `csv` (for people).
    ///
    /// Default: from the file's extension (`.csv` is csv, anything else bin); an extension that
    /// says otherwise is refused.
    #[arg(long, value_enum)]
    pub format: Option<LutFormat>,
    #[command(flatten)]
    pub device: DeviceArgs,
    #[command(flatten)]
    pub margin: MarginArgs,
}

/// One point of the table, as the CSV has it.
#[derive(Serialize, Debug, Clone, Copy)]
pub struct Point {
    pub natural_frequency_hz: f32,
    pub bias_volts: f32,
}

/// The table's error against the direct solve.
#[derive(Serialize, Debug)]
pub struct Interpolation {
    /// Largest relative error of f at the table's bias.
    pub frequency: f64,
    pub worst_hz: f64,
    /// Largest bias difference, as a fraction of the top bias.
    pub volts_of_top: f64,
}

/// What `lut` reports.
#[derive(Serialize, Debug)]
pub struct LutReport {
    pub device: DeviceInfo,
    /// The table written.
    pub files: Vec<String>,
    pub format: &'static str,
    pub points: usize,
    pub bytes: usize,
    pub crc32: String,
    pub margin: f64,
    /// First and last point.
    pub frequency_range_hz: [f32; 2],
    pub bias_range_volts: [f32; 2],
    pub interpolation_error: Interpolation,
}

impl fmt::Display for LutReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "device          {}\n\
             table           {} points, {} bytes, CRC-32 {} -> {} ({})\n\
             covers          {} Hz at {} V .. {} Hz at {} V (margin {})\n\
             interpolation   f at the table's bias within {:.2e} of the target (worst at {} Hz);\n\
             \x20               bias within {:.2e} of the top bias from the direct solve",
            self.device,
            self.points,
            self.bytes,
            self.crc32,
            self.files.join(", "),
            self.format,
            sig(f64::from(self.frequency_range_hz[0])),
            sig(f64::from(self.bias_range_volts[0])),
            sig(f64::from(self.frequency_range_hz[1])),
            sig(f64::from(self.bias_range_volts[1])),
            short(self.margin),
            self.interpolation_error.frequency,
            sig(self.interpolation_error.worst_hz),
            self.interpolation_error.volts_of_top,
        )
    }
}

impl Report for LutReport {
    fn data_on_stdout(&self) -> bool {
        self.files.iter().any(|f| f == "-")
    }
}

pub fn lut(args: &LutArgs) -> Result<LutReport, String> {
    let (batch, name) = args.device.source().batch()?;
    let margin = args.margin.margin;
    let csv_named = args
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let bin_named = args
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("bin"));
    let format = match (args.format, csv_named, bin_named) {
        (Some(LutFormat::Bin), true, _) | (Some(LutFormat::Csv), _, true) => {
            return Err(format!(
                "--out {} and --format {}: the extension says the other format",
                args.out.display(),
                if csv_named { "bin" } else { "csv" }
            ))
        }
        (Some(format), _, _) => format,
        (None, true, _) => LutFormat::Csv,
        (None, false, _) => LutFormat::Bin,
    };
    prepare_file(&args.out)?;
    let made = lut::make(&batch, margin, args.points, true).map_err(|e| format!("{name}: {e}"))?;
    write_path(&args.out, &file_bytes(&made, format)?)?;
    Ok(report(
        name,
        &made,
        margin,
        format,
        vec![args.out.display().to_string()],
    ))
}

/// A table made as its file holds it: the bytes to flash, or its points as CSV.
pub fn file_bytes(made: &lut::Made, format: LutFormat) -> Result<Vec<u8>, String> {
    match format {
        LutFormat::Bin => Ok(made.bytes.clone()),
        LutFormat::Csv => {
            let points: Vec<Point> = made
                .points
                .iter()
                .map(|&(natural_frequency_hz, bias_volts)| Point {
                    natural_frequency_hz,
                    bias_volts,
                })
                .collect();
            super::csv(&points)
        }
    }
}

/// What `lut` reports of a table made (`files`: where it was written, as `format`).
pub fn report(
    device: DeviceInfo,
    made: &lut::Made,
    margin: f64,
    format: LutFormat,
    files: Vec<String>,
) -> LutReport {
    let first = made.points.first().copied().unwrap_or((f32::NAN, f32::NAN));
    let last = made.points.last().copied().unwrap_or((f32::NAN, f32::NAN));
    LutReport {
        device,
        files,
        format: match format {
            LutFormat::Bin => "bin",
            LutFormat::Csv => "csv",
        },
        points: made.points.len(),
        bytes: made.bytes.len(),
        crc32: format!("{:#010x}", made.crc),
        margin,
        frequency_range_hz: [first.0, last.0],
        bias_range_volts: [first.1, last.1],
        interpolation_error: Interpolation {
            frequency: made.errors.frequency,
            worst_hz: made.errors.worst_hz,
            volts_of_top: made.errors.volts.unwrap_or(f64::NAN),
        },
    }
}
