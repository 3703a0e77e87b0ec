//! Tuning tables: bias against natural frequency over the tunable range, in a flat
//! little-endian layout the firmware reads straight from flash (no copy, no allocation).
//!
//! Layout (every number little-endian, f32 unless said):
//!
//! | offset | size | what |
//! |---|---|---|
//! | 0 | 4 | magic `DERT` |
//! | 4 | 2 | version, u16 = 1 |
//! | 6 | 2 | N, the number of points, u16, 2..=1024 |
//! | 8 | 52 | the 13 device parameters in `DeviceParams` order (`jlim` 0 = neo-Hookean) |
//! | 60 | 4 | the voltage margin m the table was made with: its top bias ≤ (1 − m)·limit |
//! | 64 | 4 | the largest relative error of f at the table's bias, as the host measured it |
//! | 68 | 8·N | points (frequency Hz, bias V), bias strictly rising, frequency strictly monotone |
//! | 68 + 8·N | 4 | CRC-32 (IEEE 802.3) of every byte before it, u32 |
//!
//! Between points the bias is interpolated as Φ² linear in f: Φ² enters the model linearly
//! (MODEL.md §5), so near zero bias, where f − f(0) ∝ Φ², this is exact to first order.

use core::fmt;

use crate::device::{Device, DeviceParams};
use crate::real::Real;
use crate::statics::Equilibrium;

/// The first four bytes of a table.
pub const MAGIC: [u8; 4] = *b"DERT";
/// The layout version this code reads and writes.
pub const VERSION: u16 = 1;
/// Bytes before the first point.
pub const HEADER_BYTES: usize = 68;
/// Bytes per point.
pub const POINT_BYTES: usize = 8;
/// The most points a table may hold.
pub const MAX_POINTS: usize = 1024;

/// A table stops this fraction below (1 − margin)·Φlimit: the firmware computes the limit
/// again in f32, which was within 7e-4 of f64 on every device tried (README, Accuracy), and
/// refuses a table that reaches above its own safe maximum.
pub const HEADROOM: f64 = 1e-3;

/// The margin to make a table with, for a controller margin: (1 − m_table) = (1 − m)(1 − HEADROOM).
pub fn table_margin(margin: f64) -> f64 {
    1.0 - (1.0 - margin) * (1.0 - HEADROOM)
}

/// The length in bytes of a table of `points` points.
pub const fn table_bytes(points: usize) -> usize {
    HEADER_BYTES + POINT_BYTES * points + 4
}

/// Why a table cannot be used.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TableError {
    /// Shorter than a header and a CRC.
    TooShort { bytes: usize },
    /// Does not start with `DERT`.
    BadMagic,
    /// A layout version this code does not read.
    UnsupportedVersion { version: u16 },
    /// Fewer than 2 or more than `MAX_POINTS` points.
    BadCount { points: u16 },
    /// The length does not match the number of points.
    WrongLength { expected: usize, bytes: usize },
    /// The stored CRC does not match the bytes: corrupted.
    BadCrc { stored: u32, computed: u32 },
    /// A header value or a point is NaN, infinite, or not positive where it must be.
    NotFinite { index: u16 },
    /// Point `index` does not continue the strictly rising bias and monotone frequency.
    NotMonotone { index: u16 },
    /// The table was made for other device parameters (field index in `DeviceParams` order).
    OtherDevice { field: u8 },
    /// The target is NaN or outside the table's frequency range.
    OutOfRange {
        target_hz: f32,
        low_hz: f32,
        high_hz: f32,
    },
    /// The output buffer is too small for the table (writing).
    BufferTooSmall { needed: usize },
}

impl fmt::Display for TableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            TableError::TooShort { bytes } => write!(f, "table of {bytes} bytes is too short"),
            TableError::BadMagic => write!(f, "not a tuning table (no DERT magic)"),
            TableError::UnsupportedVersion { version } => {
                write!(f, "table layout version {version}, expected {VERSION}")
            }
            TableError::BadCount { points } => {
                write!(f, "table has {points} points, expected 2 to {MAX_POINTS}")
            }
            TableError::WrongLength { expected, bytes } => {
                write!(f, "table is {bytes} bytes, its count says {expected}")
            }
            TableError::BadCrc { stored, computed } => write!(
                f,
                "table CRC {stored:#010x} does not match its bytes ({computed:#010x}): corrupted"
            ),
            TableError::NotFinite { index } => {
                write!(f, "table value {index} is NaN, infinite or not positive")
            }
            TableError::NotMonotone { index } => {
                write!(f, "table point {index} breaks the monotone order")
            }
            TableError::OtherDevice { field } => {
                write!(
                    f,
                    "table was made for another device (parameter {field} differs)"
                )
            }
            TableError::OutOfRange {
                target_hz,
                low_hz,
                high_hz,
            } => write!(
                f,
                "target {target_hz} Hz is outside the table's range [{low_hz}, {high_hz}] Hz"
            ),
            TableError::BufferTooSmall { needed } => {
                write!(f, "table needs a buffer of {needed} bytes")
            }
        }
    }
}

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320), bit by bit: no lookup table in flash.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            let mask = (crc & 1).wrapping_neg();
            crc = (crc >> 1) ^ (0xEDB8_8320 & mask);
        }
    }
    !crc
}

/// The 13 parameters in `DeviceParams` order, `jlim` as 0 for neo-Hookean.
fn param_values(p: &DeviceParams<f32>) -> [f32; 13] {
    [
        p.shear_modulus,
        p.jlim.unwrap_or(0.0),
        p.relative_permittivity,
        p.density,
        p.breakdown_field,
        p.thickness,
        p.length_active,
        p.length_passive,
        p.width,
        p.bar_mass,
        p.prestretch_1,
        p.prestretch_2,
        p.damping,
    ]
}

fn f32_at(bytes: &[u8], offset: usize) -> f32 {
    let mut word = [0u8; 4];
    if let Some(src) = bytes.get(offset..offset + 4) {
        word.copy_from_slice(src);
    }
    f32::from_le_bytes(word)
}

/// A checked table, borrowed from flash or a buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Table<'a> {
    bytes: &'a [u8],
    points: usize,
}

impl<'a> Table<'a> {
    /// Check a table's bytes: magic, version, count, length, CRC, every value finite and
    /// positive, bias strictly rising and frequency strictly monotone.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, TableError> {
        if bytes.len() < table_bytes(0) {
            return Err(TableError::TooShort { bytes: bytes.len() });
        }
        if bytes[0..4] != MAGIC {
            return Err(TableError::BadMagic);
        }
        let version = u16::from_le_bytes([bytes[4], bytes[5]]);
        if version != VERSION {
            return Err(TableError::UnsupportedVersion { version });
        }
        let count = u16::from_le_bytes([bytes[6], bytes[7]]);
        let points = usize::from(count);
        if !(2..=MAX_POINTS).contains(&points) {
            return Err(TableError::BadCount { points: count });
        }
        let expected = table_bytes(points);
        if bytes.len() != expected {
            return Err(TableError::WrongLength {
                expected,
                bytes: bytes.len(),
            });
        }
        let body = expected - 4;
        let stored = u32::from_le_bytes([
            bytes[body],
            bytes[body + 1],
            bytes[body + 2],
            bytes[body + 3],
        ]);
        let computed = crc32(&bytes[..body]);
        if stored != computed {
            return Err(TableError::BadCrc { stored, computed });
        }
        let table = Table { bytes, points };
        // Header values: parameters (jlim and damping may be 0), margin in [0, 1), error ≥ 0.
        for k in 0..15u16 {
            let v = f32_at(bytes, 8 + 4 * usize::from(k));
            let may_be_zero = matches!(k, 1 | 9 | 12 | 13 | 14);
            if !(v.is_finite() && (v > 0.0 || (may_be_zero && v == 0.0))) {
                return Err(TableError::NotFinite { index: k });
            }
        }
        if !(table.margin() < 1.0) {
            return Err(TableError::NotFinite { index: 13 });
        }
        let falling = table.point(1).0 < table.point(0).0;
        for k in 0..points {
            let (hz, volts) = table.point(k);
            let index = k as u16;
            if !(hz.is_finite() && hz > 0.0 && volts.is_finite() && volts >= 0.0) {
                return Err(TableError::NotFinite { index });
            }
            if k > 0 {
                let (hz0, volts0) = table.point(k - 1);
                let monotone = if falling { hz < hz0 } else { hz > hz0 };
                if !(volts > volts0 && monotone) {
                    return Err(TableError::NotMonotone { index });
                }
            }
        }
        Ok(table)
    }

    /// Number of points.
    pub fn points(&self) -> usize {
        self.points
    }

    /// Point `k` as (frequency Hz, bias V); `k` below `points()`.
    pub fn point(&self, k: usize) -> (f32, f32) {
        let at = HEADER_BYTES + POINT_BYTES * k;
        (f32_at(self.bytes, at), f32_at(self.bytes, at + 4))
    }

    /// The device parameters the table was made for.
    pub fn params(&self) -> DeviceParams<f32> {
        let v = |k: usize| f32_at(self.bytes, 8 + 4 * k);
        DeviceParams {
            shear_modulus: v(0),
            jlim: (v(1) > 0.0).then(|| v(1)),
            relative_permittivity: v(2),
            density: v(3),
            breakdown_field: v(4),
            thickness: v(5),
            length_active: v(6),
            length_passive: v(7),
            width: v(8),
            bar_mass: v(9),
            prestretch_1: v(10),
            prestretch_2: v(11),
            damping: v(12),
        }
    }

    /// Check that the table was made for `params` (bit for bit, as f32).
    pub fn check_device(&self, params: &DeviceParams<f32>) -> Result<(), TableError> {
        let ours = param_values(&self.params());
        let theirs = param_values(params);
        match (0..13).find(|&k| ours[k].to_bits() != theirs[k].to_bits()) {
            Some(field) => Err(TableError::OtherDevice { field: field as u8 }),
            None => Ok(()),
        }
    }

    /// The voltage margin the table was made with.
    pub fn margin(&self) -> f32 {
        f32_at(self.bytes, 60)
    }

    /// The largest relative error of the natural frequency at the table's bias against the
    /// target, as the host measured it (f64 model).
    pub fn interpolation_error(&self) -> f32 {
        f32_at(self.bytes, 64)
    }

    /// The table's frequency range, (low, high) Hz.
    pub fn range_hz(&self) -> (f32, f32) {
        let (a, b) = (self.point(0).0, self.point(self.points - 1).0);
        (a.min(b), a.max(b))
    }

    /// The highest bias in the table, V.
    pub fn max_volts(&self) -> f32 {
        self.point(self.points - 1).1
    }

    /// The bias for a target frequency: Φ² interpolated linearly in f between the two
    /// points that bracket it (binary search).
    pub fn bias_volts(&self, target_hz: f32) -> Result<f32, TableError> {
        let (low_hz, high_hz) = self.range_hz();
        if !(target_hz >= low_hz && target_hz <= high_hz) {
            return Err(TableError::OutOfRange {
                target_hz,
                low_hz,
                high_hz,
            });
        }
        let falling = self.point(1).0 < self.point(0).0;
        // Invariant: the target lies between points lo and hi.
        let (mut lo, mut hi) = (0, self.points - 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            let past = if falling {
                self.point(mid).0 < target_hz
            } else {
                self.point(mid).0 > target_hz
            };
            if past {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let (f0, v0) = self.point(lo);
        let (f1, v1) = self.point(hi);
        let t = (target_hz - f0) / (f1 - f0);
        let squared = v0 * v0 + t * (v1 * v1 - v0 * v0);
        Ok(Real::sqrt(squared.max(0.0)))
    }
}

/// Fill `out` with table points (frequency Hz, bias V) from zero bias up to `top` (the
/// highest allowed equilibrium, `Tuner::max_bias`), evenly spaced in Φ². A point whose
/// equilibrium cannot be found is reported as `NotFinite` at its index.
pub fn fill<T: Real>(
    device: &Device<T>,
    top: &Equilibrium<T>,
    out: &mut [(f32, f32)],
) -> Result<(), TableError> {
    let last = out.len().saturating_sub(1).max(1);
    for (k, point) in out.iter_mut().enumerate() {
        let squared = top.volts * top.volts * T::of(k as f64) / T::of(last as f64);
        let volts = squared.sqrt();
        let offset = if k == last {
            Some(top.offset)
        } else {
            device.offset_for_bias(volts, top.offset)
        };
        let index = k.min(usize::from(u16::MAX)) as u16;
        let hz = offset
            .map(|d| device.natural_frequency_hz_at(d))
            .ok_or(TableError::NotFinite { index })?;
        *point = (hz.to_f64() as f32, volts.to_f64() as f32);
    }
    Ok(())
}

/// Write a table into `out`: the device, the margin, the measured interpolation error and the
/// points (frequency Hz, bias V). Returns the bytes written. The points are checked as
/// `Table::parse` checks them, so what is written can be read back.
pub fn write(
    out: &mut [u8],
    params: &DeviceParams<f32>,
    margin: f32,
    interpolation_error: f32,
    points: &[(f32, f32)],
) -> Result<usize, TableError> {
    if !(2..=MAX_POINTS).contains(&points.len()) {
        return Err(TableError::BadCount {
            points: points.len().min(usize::from(u16::MAX)) as u16,
        });
    }
    let needed = table_bytes(points.len());
    let Some(out) = out.get_mut(..needed) else {
        return Err(TableError::BufferTooSmall { needed });
    };
    out[0..4].copy_from_slice(&MAGIC);
    out[4..6].copy_from_slice(&VERSION.to_le_bytes());
    out[6..8].copy_from_slice(&(points.len() as u16).to_le_bytes());
    let header = param_values(params)
        .into_iter()
        .chain([margin, interpolation_error]);
    for (k, v) in header.enumerate() {
        out[8 + 4 * k..12 + 4 * k].copy_from_slice(&v.to_le_bytes());
    }
    for (k, (hz, volts)) in points.iter().enumerate() {
        let at = HEADER_BYTES + POINT_BYTES * k;
        out[at..at + 4].copy_from_slice(&hz.to_le_bytes());
        out[at + 4..at + 8].copy_from_slice(&volts.to_le_bytes());
    }
    let body = needed - 4;
    let crc = crc32(&out[..body]);
    out[body..needed].copy_from_slice(&crc.to_le_bytes());
    Table::parse(out)?;
    Ok(needed)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The standard check value of CRC-32/ISO-HDLC: "123456789" → 0xCBF43926.
    #[test]
    fn crc_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }
}
