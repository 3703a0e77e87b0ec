//! host-sim's commands, one module each: its arguments, the work, and a typed report (JSON
//! through `Serialize`, text through `Display`, CSV from the same rows where it writes one).

pub mod console;
pub mod image;
pub mod lut;
pub mod precision;
pub mod run;
pub mod safe;
pub mod simulate;
pub mod stress;
pub mod sweep;

use std::fmt::Display;
use std::path::{Path, PathBuf};

use clap::Args;
use de_resonator::{Device, DeviceParams, FailureMode, Tuner, DEFAULT_MARGIN, REFERENCE_DEVICE};
use serde::Serialize;

use crate::device_file;

/// What a command found: printed as text (`Display`) or one JSON object (`Serialize`).
pub trait Report: Serialize + Display {
    /// A run that finished but failed (exit status 1), with why.
    fn failure(&self) -> Option<String> {
        None
    }
}

/// The device a command works on.
#[derive(Args, Debug, Clone, Default)]
pub struct DeviceArgs {
    /// Device file (TOML, SI units, flat keys; absent keys take the reference device's
    /// values, an absent `jlim` means neo-Hookean). Default: the built-in reference device.
    #[arg(long, value_name = "FILE")]
    pub device: Option<PathBuf>,
}

impl DeviceArgs {
    /// The device's parameters (the reference's without a file) and a name for it.
    pub fn params(&self) -> Result<(DeviceParams<f64>, String), String> {
        Ok(match &self.device {
            Some(path) => (device_file::load(path)?, path.display().to_string()),
            None => (REFERENCE_DEVICE, "reference device (built in)".into()),
        })
    }

    /// The device validated, with its limit found, and its name.
    pub fn tuner(&self) -> Result<(Tuner<f64>, String), String> {
        let (params, name) = self.params()?;
        let device = Device::new(params).map_err(|e| format!("{name}: {e}"))?;
        Ok((Tuner::new(device), name))
    }
}

/// The voltage margin.
#[derive(Args, Debug, Clone)]
pub struct MarginArgs {
    /// Voltage margin: the bias may not exceed (1 − margin) × the limit voltage.
    #[arg(long, value_name = "M", default_value_t = DEFAULT_MARGIN, allow_negative_numbers = true)]
    pub margin: f64,
}

/// A check that failed along a run, and when (JSON: `{mode, time}`).
#[derive(Serialize, Debug, Clone, Copy)]
pub struct Crossing {
    pub mode: &'static str,
    /// s.
    pub time: f64,
}

impl Crossing {
    pub fn of(first: Option<(FailureMode, f64)>) -> Option<Self> {
        first.map(|(mode, time)| Crossing {
            mode: mode.name(),
            time,
        })
    }
}

/// Six significant figures, for people.
pub fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let exponent = x.abs().log10().floor() as i32;
    if !(-4..9).contains(&exponent) {
        // Tiny or huge: scientific, not a row of zeros.
        return format!("{x:.5e}");
    }
    let decimals = (5 - exponent).max(0) as usize;
    format!("{x:.decimals$}")
}

/// A number for JSON: `None` (null) when not finite, as JSON has no NaN.
pub fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// Write `bytes` to `dir/file`, creating `dir`; the path written, or why not.
pub fn write_file(dir: &Path, file: &str, bytes: &[u8]) -> Result<String, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let path = dir.join(file);
    std::fs::write(&path, bytes).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path.display().to_string())
}

/// Rows as CSV: a header from the row type's field names, a line a row (serde).
pub fn csv<R: Serialize>(rows: &[R]) -> Result<Vec<u8>, String> {
    let mut writer = csv::Writer::from_writer(Vec::new());
    for row in rows {
        writer.serialize(row).map_err(|e| e.to_string())?;
    }
    writer.into_inner().map_err(|e| e.to_string())
}
