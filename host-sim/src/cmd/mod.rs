//! host-sim's commands, one module each: its arguments, the work, and a typed report (JSON
//! through `Serialize`, text through `Display`, CSV from the same rows where it writes one).

pub mod bifurcation;
pub mod console;
pub mod curve;
pub mod drive_map;
pub mod image;
pub mod lut;
pub mod lyapunov;
pub mod poincare;
pub mod record;
pub mod report;
pub mod run;
pub mod safe;
pub mod serve;
pub mod simulate;
pub mod stress;
pub mod sweep;

use std::fmt::Display;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use clap::Args;
use de_resonator::model::tolerance::DeviceBox;
use de_resonator::{Device, DeviceParams, Tuner, DEFAULT_MARGIN, REFERENCE_DEVICE};
use serde::Serialize;

use crate::device_file;

/// What a command found: printed as text (`Display`) or one JSON object (`Serialize`).
pub trait Report: Serialize + Display {
    /// A run that finished but failed (exit status 1), with why.
    fn failure(&self) -> Option<String> {
        None
    }

    /// Whether stdout carries the data itself (`--csv -`): the report then goes to stderr.
    fn data_on_stdout(&self) -> bool {
        false
    }
}

/// `-` as a file: stdout, as Unix tools take it.
pub fn is_stdout(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// Where a file goes, made ready before the work: its folder created and checked writable
/// (the one rule for every output: `--out`, `--csv`, `--plot`); nothing for stdout (`-`).
pub fn prepare_file(path: &Path) -> Result<(), String> {
    match path.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) if !is_stdout(path) => prepare_dir(dir),
        _ => Ok(()),
    }
}

/// The device a command works on, as its flag names it.
#[derive(Args, Debug, Clone, Default)]
pub struct DeviceArgs {
    /// Device file (TOML, SI units, flat keys; absent keys take the reference device's values, an
    /// absent `jlim` means neo-Hookean).
    ///
    /// Default: the built-in reference device.
    #[arg(long, value_name = "FILE")]
    pub device: Option<PathBuf>,
}

impl DeviceArgs {
    /// The device the flag names.
    pub fn source(&self) -> DeviceSource {
        self.device
            .clone()
            .map_or(DeviceSource::Reference, DeviceSource::File)
    }
}

/// Where a device comes from, whoever asks (the CLI's `--device`, the Python package's
/// `Device`): the built-in reference, a device file, or a batch given as values.
#[derive(Debug, Clone, Default)]
pub enum DeviceSource {
    /// The built-in reference device.
    #[default]
    Reference,
    /// A device file (TOML; its `[tolerance]` table makes it a batch).
    File(PathBuf),
    /// A batch given as values, with what it is called (boxed: the batch is large).
    Given { batch: Box<DeviceBox>, name: String },
}

impl DeviceSource {
    /// The device's parameters (the reference's without a file) and what it is.
    pub fn params(&self) -> Result<(DeviceParams<f64>, DeviceInfo), String> {
        let (b, info) = self.batch()?;
        Ok((b.nominal, info))
    }

    /// The batch the device file declares with its `[tolerance]` table (model.md §10): the
    /// nominal device alone without one; the batch itself when given as values.
    pub fn batch(&self) -> Result<(DeviceBox, DeviceInfo), String> {
        let (b, source) = match self {
            Self::Given { batch, name } => (**batch, name.clone()),
            Self::File(path) => (device_file::load_box(path)?, path.display().to_string()),
            Self::Reference => (
                DeviceBox::exact(REFERENCE_DEVICE),
                "reference device (built in)".into(),
            ),
        };
        Ok((b, DeviceInfo::new(source, &b.nominal).with_tolerance(&b)))
    }

    /// The batch, its nominal device validated with its limit found, and what it is.
    pub fn batch_tuner(&self) -> Result<(DeviceBox, Tuner<f64>, DeviceInfo), String> {
        let (b, name) = self.batch()?;
        let device = Device::new(b.nominal).map_err(|e| format!("{name}: {e}"))?;
        Ok((b, Tuner::new(device), name))
    }
}

/// Which device a command ran on, and its material model (JSON: `device`): an absent `jlim`
/// is neo-Hookean, which a reader should not have to guess.
#[derive(Serialize, Debug, Clone)]
pub struct DeviceInfo {
    /// The device file, or `reference device (built in)`.
    pub source: String,
    /// `gent` or `neo_hookean` (model.md §3).
    pub material: &'static str,
    /// Gent's limit on I1 − 3 (`null`: neo-Hookean).
    pub jlim: Option<f64>,
    /// The `[tolerance]` table as ranges, `{key: [low, high]}` in SI units (absent: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<std::collections::BTreeMap<&'static str, [f64; 2]>>,
}

impl DeviceInfo {
    pub fn new(source: String, params: &DeviceParams<f64>) -> Self {
        Self {
            source,
            material: if params.jlim.is_some() {
                "gent"
            } else {
                "neo_hookean"
            },
            jlim: params.jlim,
            tolerance: None,
        }
    }

    /// With the batch's ranges, where it has any.
    pub fn with_tolerance(mut self, b: &DeviceBox) -> Self {
        if !b.is_exact() {
            self.tolerance = Some(
                b.spread_fields()
                    .map(|f| (f.key(), [b.low.get(f), b.high.get(f)]))
                    .collect(),
            );
        }
        self
    }
}

impl DeviceInfo {
    /// The device's name for a figure's title: the file's name without its folder and
    /// extension (`soft-vhb`), or `reference device`.
    pub fn title(&self) -> String {
        if self.source.starts_with("reference device") {
            return "reference device".into();
        }
        std::path::Path::new(&self.source)
            .file_stem()
            .map_or(self.source.clone(), |s| s.to_string_lossy().into_owned())
    }
}

impl Display for DeviceInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.jlim {
            Some(jlim) => write!(f, "{} (Gent, jlim {})", self.source, short(jlim)),
            None => write!(f, "{} (neo-Hookean: no jlim)", self.source),
        }
    }
}

/// The voltage margin.
#[derive(Args, Debug, Clone)]
pub struct MarginArgs {
    /// Voltage margin: the bias may not exceed (1 − margin) × the limit voltage.
    #[arg(long, value_name = "M", default_value_t = DEFAULT_MARGIN, allow_negative_numbers = true)]
    pub margin: f64,
}

pub use crate::text::{finite, short, sig, Crossing};

/// Create `dir` and check it takes files, before the work that fills it (not after).
pub fn prepare_dir(dir: &Path) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let probe = dir.join(".host-sim-write-test");
    std::fs::write(&probe, b"")
        .and_then(|()| std::fs::remove_file(&probe))
        .map_err(|e| format!("cannot write into {}: {e}", dir.display()))
}

/// Write `bytes` to `dir/file`, creating `dir`; the path written, or why not.
pub fn write_file(dir: &Path, file: &str, bytes: &[u8]) -> Result<String, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    write_path(&dir.join(file), bytes)
}

/// Write `bytes` to `path` (`-`: stdout); the path written, or why not.
pub fn write_path(path: &Path, bytes: &[u8]) -> Result<String, String> {
    if is_stdout(path) {
        let mut out = std::io::stdout().lock();
        // A reader that stops early is not an error.
        let _ = out.write_all(bytes).and_then(|()| out.flush());
        return Ok("-".into());
    }
    std::fs::write(path, bytes).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path.display().to_string())
}

/// A study's two files in `dir`: `<stem>.csv` (the rows) and `<stem>.svg` (the panels); the
/// paths written.
pub fn write_csv_and_plot<R: Serialize>(
    dir: &Path,
    stem: &str,
    rows: &[R],
    panels: &[crate::plot::Panel],
) -> Result<Vec<String>, String> {
    Ok(vec![
        write_file(dir, &format!("{stem}.csv"), &csv(rows)?)?,
        write_file(
            dir,
            &format!("{stem}.svg"),
            crate::plot::svg(panels).as_bytes(),
        )?,
    ])
}

/// Rows as CSV: a header from the row type's field names, a line a row (serde).
pub fn csv<R: Serialize>(rows: &[R]) -> Result<Vec<u8>, String> {
    let mut writer = csv::Writer::from_writer(Vec::new());
    for row in rows {
        writer.serialize(row).map_err(|e| e.to_string())?;
    }
    writer.into_inner().map_err(|e| e.to_string())
}

/// Numbers given on the command line: one, a comma list `a,b,c`, or `low:high:count` (count ≥
/// 2, evenly spaced from low to high); at most `most`, each finite.
pub fn values(flag: &str, text: &str, most: usize) -> Result<Vec<f64>, String> {
    let number = |s: &str| {
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{flag} {text}: `{s}` is not a finite number"))
    };
    let parts: Vec<&str> = text.split(':').collect();
    let out: Vec<f64> = match parts[..] {
        [list] => list.split(',').map(number).collect::<Result<_, _>>()?,
        [low, high, count] => {
            let (low, high) = (number(low)?, number(high)?);
            let count: usize = count
                .trim()
                .parse()
                .ok()
                .filter(|n| (2..=most).contains(n))
                .ok_or_else(|| {
                    format!("{flag} {text}: the count must be a whole number from 2 to {most}")
                })?;
            (0..count)
                .map(|k| low + (high - low) * k as f64 / (count - 1) as f64)
                .collect()
        }
        _ => return Err(format!("{flag} {text}: give a,b,c or low:high:count")),
    };
    if out.len() > most {
        return Err(format!("{flag}: {} values, at most {most}", out.len()));
    }
    Ok(out)
}

/// States given on the command line: `S,V` (a stretch and dλ/dt in 1/s), `;` between several.
pub fn states(flag: &str, text: &str) -> Result<Vec<[f64; 2]>, String> {
    text.split(';')
        .map(|one| match values(flag, one, 2)?[..] {
            [stretch, velocity] => Ok([stretch, velocity]),
            _ => Err(format!(
                "{flag} {text}: each state is a stretch and dλ/dt (1/s), `S,V`"
            )),
        })
        .collect()
}

/// One state given on the command line (`states`).
pub fn state(flag: &str, text: &str) -> Result<[f64; 2], String> {
    match states(flag, text)?[..] {
        [one] => Ok(one),
        _ => Err(format!("{flag} {text}: one state, `S,V`")),
    }
}
