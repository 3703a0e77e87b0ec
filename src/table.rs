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
//! | 68 | 8·N | points (frequency Hz, bias V), bias strictly rising; frequency turns at most `MAX_TURNS` times |
//! | 68 + 8·N | 4 | CRC-32 (IEEE 802.3) of every byte before it, u32 |
//!
//! A table for a batch of membranes (model.md §10) is version 2: after the error, at 68, the
//! batch's 13 low and 13 high parameters (104 bytes, each range holding the device's value),
//! its guaranteed limit in V (4 bytes), and at `BATCH_BIASES` biases from 0 V to the top
//! (12 bytes each: bias V, then the lowest and highest capacitance of membrane A any device
//! of the batch has there, F, model.md §8), the points after them. Its margin and top are
//! against that limit. A device without tolerances is written as version 1, byte for byte.
//!
//! Between points the bias is interpolated as Φ² linear in f: Φ² enters the model linearly
//! (model.md §5), so near zero bias, where f − f(0) ∝ Φ², this is exact to first order.
//! f(Φ) need not be monotone (model.md §5): the lookup takes the first interval, in rising
//! bias, that holds the target, which is the smallest bias (model.md §7), as `Tuner::tune`
//! takes; the maker puts f's turning points in as points, so extrema are not cut off.

use core::fmt;

use crate::bytes::{crc32, f32_at, u16_at, u32_at};
use crate::numerics::decimal::Decimal;

use crate::model::device::{Device, DeviceParams, Field};
use crate::model::guaranteed::{BoxError, Leaf};
use crate::model::statics::Equilibrium;
use crate::model::tolerance::DeviceBox;
use crate::numerics::real::Real;

/// The first four bytes of a table.
pub const MAGIC: [u8; 4] = *b"DERT";
/// The layout version of a table for one device.
pub const VERSION: u16 = 1;
/// The layout version of a table for a batch (model.md §10).
pub const VERSION_BATCH: u16 = 2;
/// Bytes before the first point (version 1).
pub const HEADER_BYTES: usize = 68;
/// The biases a batch's table gives the capacitance at, evenly spaced in Φ² from 0 V to the
/// top: the board's self-sensing checks the membrane against the batch between two of them.
pub const BATCH_BIASES: usize = 16;
/// Bytes before the first point (version 2): the batch's ranges, limit and capacitances
/// besides.
pub const BATCH_HEADER_BYTES: usize = HEADER_BYTES + 2 * 52 + 4 + 12 * BATCH_BIASES;
/// Bytes per point.
pub const POINT_BYTES: usize = 8;
/// The most points a table may hold.
pub const MAX_POINTS: usize = 1024;
/// The most times the frequency column may change direction: f(Φ) of model.md §5 turns
/// once or twice at most on the devices tried; more is corruption.
pub const MAX_TURNS: usize = 4;

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

/// The length in bytes of a batch's table of `points` points.
pub const fn batch_table_bytes(points: usize) -> usize {
    BATCH_HEADER_BYTES + POINT_BYTES * points + 4
}

/// What a version-2 table holds of its batch (model.md §10): every device between `low`
/// and `high` has its limit at or above `limit_volts` (the host's certified bound), and at
/// each bias of `capacitance` membrane A's capacitance within its band.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TableBatch {
    pub low: DeviceParams<f32>,
    pub high: DeviceParams<f32>,
    /// The guaranteed limit, V.
    pub limit_volts: f32,
    /// The capacitance band at `BATCH_BIASES` rising biases, from 0 V to the table's top.
    pub capacitance: CapacitanceBands,
}

/// The capacitance bands of a batch at `BATCH_BIASES` rising biases, from 0 V to the top.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CapacitanceBands(pub [CapacitanceBand; BATCH_BIASES]);

/// The capacitance (F, model.md §8) every device of a batch has at one bias: certified.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CapacitanceBand {
    pub volts: f32,
    pub low_farads: f32,
    pub high_farads: f32,
}

impl TableBatch {
    /// The batch `b` with its guaranteed limit `limit_volts` as a table keeps them in f32:
    /// the ranges rounded outward, the limit down (never a narrower batch, never a higher
    /// limit than the f64 ones), and the capacitance bands up to `top_volts` (the table's
    /// top) rounded outward. `leaves`: the band search's storage.
    pub fn of(
        b: &DeviceBox,
        limit_volts: f64,
        top_volts: f64,
        leaves: &mut [Leaf],
    ) -> Result<Self, BoxError> {
        let (mut low, mut high) = (b.low.cast::<f32>(), b.high.cast::<f32>());
        for f in Field::ALL {
            low.set(f, f32_below(b.low.get(f)));
            high.set(f, f32_above(b.high.get(f)));
        }
        let mut capacitance = CapacitanceBands::default();
        let last = (BATCH_BIASES - 1) as f64;
        for (j, band) in capacitance.0.iter_mut().enumerate() {
            // Φ² evenly spaced; the last at or above the top as f32 holds it.
            let volts = if j + 1 == BATCH_BIASES {
                f32_above(top_volts)
            } else {
                (top_volts * libm::sqrt(j as f64 / last)) as f32
            };
            let (low_farads, high_farads) = b.capacitance_farads(f64::from(volts), leaves)?;
            *band = CapacitanceBand {
                volts,
                low_farads: f32_below(low_farads),
                high_farads: f32_above(high_farads),
            };
        }
        Ok(Self {
            low,
            high,
            limit_volts: f32_below(limit_volts),
            capacitance,
        })
    }
}

impl CapacitanceBands {
    /// The capacitance every device of the batch has at the bias `volts`, (low, high) F:
    /// between the bands of the biases about it (each device's capacitance rises with the
    /// bias on its loading branch, model.md §5: the first equilibrium moves up with Φ);
    /// `None` outside the biases the table gives.
    pub fn farads_at(&self, volts: f32) -> Option<(f32, f32)> {
        let bands = &self.0;
        let above = bands.iter().position(|b| b.volts >= volts)?;
        let at = bands.get(above)?;
        if at.volts == volts {
            return Some((at.low_farads, at.high_farads));
        }
        let below = bands.get(above.checked_sub(1)?)?;
        Some((below.low_farads, at.high_farads))
    }
}

/// The largest f32 at or below `x`.
fn f32_below(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) > x {
        y.next_down()
    } else {
        y
    }
}

/// The smallest f32 at or above `x`.
fn f32_above(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) < x {
        y.next_up()
    } else {
        y
    }
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
    /// Point `index` does not continue the strictly rising bias, or is the frequency's
    /// turn past `MAX_TURNS`.
    NotMonotone { index: u16 },
    /// The table was made for other device parameters: the first that differs.
    OtherDevice { field: Field },
    /// The target is NaN or outside the table's frequency range.
    OutOfRange {
        target_hz: f32,
        low_hz: f32,
        high_hz: f32,
    },
    /// The output buffer is too small for the table (writing).
    BufferTooSmall { needed: usize },
    /// A batch's range for `field` is not a range holding the device's value, or its
    /// guaranteed limit is not a positive number.
    BadBatch { field: Option<Field> },
    /// A batch's capacitance band `index` is not a positive range, its bias does not rise
    /// from 0 V, or the last is below the table's top.
    BadCapacitance { index: u16 },
}

impl core::error::Error for TableError {}

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
            TableError::NotMonotone { index } => write!(
                f,
                "table point {index} breaks the order (bias strictly rising, frequency turning \
                 at most {MAX_TURNS} times)"
            ),
            TableError::OtherDevice { field } => write!(
                f,
                "table was made for another device (`{}` differs)",
                field.key()
            ),
            TableError::OutOfRange {
                target_hz,
                low_hz,
                high_hz,
            } => write!(
                f,
                "target {} Hz is outside the table's range [{}, {}] Hz",
                Decimal(target_hz),
                Decimal(low_hz),
                Decimal(high_hz)
            ),
            TableError::BufferTooSmall { needed } => {
                write!(f, "table needs a buffer of {needed} bytes")
            }
            TableError::BadBatch { field: Some(field) } => write!(
                f,
                "table's batch range for `{}` does not hold the device's value",
                field.key()
            ),
            TableError::BadBatch { field: None } => {
                write!(f, "table's guaranteed limit is not a positive number")
            }
            TableError::BadCapacitance { index } => write!(
                f,
                "table's batch capacitance {index} is not a positive range at a bias rising \
                 from 0 V to the table's top"
            ),
        }
    }
}

/// A checked table, borrowed from flash or a buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Table<'a> {
    bytes: &'a [u8],
    points: usize,
    /// Bytes before the first point (its version's).
    header: usize,
}

impl<'a> Table<'a> {
    /// Check a table's bytes: magic, version, count, length, CRC, every value finite and
    /// positive, bias strictly rising, the frequency turning at most `MAX_TURNS` times.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, TableError> {
        if bytes.len() < table_bytes(0) {
            return Err(TableError::TooShort { bytes: bytes.len() });
        }
        if bytes.get(0..4) != Some(&MAGIC[..]) {
            return Err(TableError::BadMagic);
        }
        let version = u16_at(bytes, 4);
        let header = match version {
            VERSION => HEADER_BYTES,
            VERSION_BATCH => BATCH_HEADER_BYTES,
            _ => return Err(TableError::UnsupportedVersion { version }),
        };
        let count = u16_at(bytes, 6);
        let points = usize::from(count);
        if !(2..=MAX_POINTS).contains(&points) {
            return Err(TableError::BadCount { points: count });
        }
        let expected = header + POINT_BYTES * points + 4;
        if bytes.len() != expected {
            return Err(TableError::WrongLength {
                expected,
                bytes: bytes.len(),
            });
        }
        let body = expected - 4;
        let stored = u32_at(bytes, body);
        let computed = crc32(bytes.get(..body).unwrap_or(&[]));
        if stored != computed {
            return Err(TableError::BadCrc { stored, computed });
        }
        let table = Table {
            bytes,
            points,
            header,
        };
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
        let mut previous: Option<(f32, f32)> = None;
        let mut rising: Option<bool> = None;
        let mut turns = 0;
        for (k, (hz, volts)) in table.each_point().enumerate() {
            let index = k as u16;
            if !(hz.is_finite() && hz > 0.0 && volts.is_finite() && volts >= 0.0) {
                return Err(TableError::NotFinite { index });
            }
            if let Some((hz0, volts0)) = previous {
                let step = (hz != hz0).then_some(hz > hz0);
                if rising.is_some() && step.is_some() && step != rising {
                    turns += 1;
                }
                rising = step.or(rising);
                if !(volts > volts0) || turns > MAX_TURNS {
                    return Err(TableError::NotMonotone { index });
                }
            }
            previous = Some((hz, volts));
        }
        if let Some(batch) = table.batch() {
            table.check_batch(&batch)?;
        }
        Ok(table)
    }

    /// A version-2 table's batch against its device and points: each range holding the
    /// device's value, the limit a positive number, the capacitance bands positive ranges at
    /// biases rising from 0 V to at least the top.
    fn check_batch(&self, batch: &TableBatch) -> Result<(), TableError> {
        let nominal = self.params();
        for field in Field::ALL {
            let (low, x, high) = (
                batch.low.get(field),
                nominal.get(field),
                batch.high.get(field),
            );
            if !(low <= x && x <= high && low.is_finite() && high.is_finite() && low >= 0.0) {
                return Err(TableError::BadBatch { field: Some(field) });
            }
        }
        // A Gent device's jlim range stays Gent; a neo-Hookean one has none.
        if (nominal.jlim.is_some()) != (batch.low.jlim.is_some()) {
            return Err(TableError::BadBatch {
                field: Some(Field::Jlim),
            });
        }
        if !(batch.limit_volts.is_finite() && batch.limit_volts > 0.0) {
            return Err(TableError::BadBatch { field: None });
        }
        let mut below = -1.0f32;
        for (k, band) in batch.capacitance.0.iter().enumerate() {
            let index = k as u16;
            let first = k == 0;
            let CapacitanceBand {
                volts,
                low_farads: low,
                high_farads: high,
            } = *band;
            if !(volts > below && (!first || volts == 0.0) && low > 0.0 && low <= high)
                || !high.is_finite()
            {
                return Err(TableError::BadCapacitance { index });
            }
            below = volts;
        }
        let last = BATCH_BIASES - 1;
        match batch.capacitance.0.get(last) {
            Some(band) if band.volts >= self.max_volts() => Ok(()),
            _ => Err(TableError::BadCapacitance { index: last as u16 }),
        }
    }

    /// Number of points.
    pub fn points(&self) -> usize {
        self.points
    }

    /// Point `k` as (frequency Hz, bias V); `k` below `points()`.
    pub fn point(&self, k: usize) -> (f32, f32) {
        let at = self.header + POINT_BYTES * k;
        (f32_at(self.bytes, at), f32_at(self.bytes, at + 4))
    }

    /// The points in order, (frequency Hz, bias V): one pass over the bytes.
    fn each_point(&self) -> impl Iterator<Item = (f32, f32)> + '_ {
        let end = self.header + POINT_BYTES * self.points;
        let word = |w: Option<&[u8; 4]>| w.copied().map_or(f32::NAN, f32::from_le_bytes);
        self.bytes
            .get(self.header..end)
            .unwrap_or(&[])
            .chunks_exact(POINT_BYTES)
            .map(move |p| (word(p.first_chunk()), word(p.last_chunk())))
    }

    /// The device parameters the table was made for.
    pub fn params(&self) -> DeviceParams<f32> {
        self.params_at(8)
    }

    /// The 13 parameters stored from byte `at`.
    fn params_at(&self, at: usize) -> DeviceParams<f32> {
        let mut values = [0.0f32; 13];
        for (k, value) in values.iter_mut().enumerate() {
            *value = f32_at(self.bytes, at + 4 * k);
        }
        DeviceParams::from_values(values)
    }

    /// The batch a version-2 table was made for (model.md §10); `None` for one device.
    pub fn batch(&self) -> Option<TableBatch> {
        (self.header == BATCH_HEADER_BYTES).then(|| {
            let mut capacitance = CapacitanceBands::default();
            for (j, band) in capacitance.0.iter_mut().enumerate() {
                let at = HEADER_BYTES + 108 + 12 * j;
                *band = CapacitanceBand {
                    volts: f32_at(self.bytes, at),
                    low_farads: f32_at(self.bytes, at + 4),
                    high_farads: f32_at(self.bytes, at + 8),
                };
            }
            TableBatch {
                low: self.params_at(HEADER_BYTES),
                high: self.params_at(HEADER_BYTES + 52),
                limit_volts: f32_at(self.bytes, HEADER_BYTES + 104),
                capacitance,
            }
        })
    }

    /// Check that the table was made for `params` (bit for bit, as f32), but for the
    /// damping, which no static of model.md §5–§7 reads: a device told its damping after its
    /// table was made keeps the table.
    pub fn check_device(&self, params: &DeviceParams<f32>) -> Result<(), TableError> {
        let ours = self.params();
        match Field::ALL
            .into_iter()
            .filter(|&field| field != Field::Damping)
            .find(|&field| ours.get(field).to_bits() != params.get(field).to_bits())
        {
            Some(field) => Err(TableError::OtherDevice { field }),
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

    /// The table's frequency range, (low, high) Hz: the least and greatest of its points.
    pub fn range_hz(&self) -> (f32, f32) {
        self.each_point().fold(
            (f32::INFINITY, f32::NEG_INFINITY),
            |(low, high), (hz, _)| (low.min(hz), high.max(hz)),
        )
    }

    /// The highest bias in the table, V.
    pub fn max_volts(&self) -> f32 {
        self.point(self.points.saturating_sub(1)).1
    }

    /// The bias for a target frequency: the first interval, in rising bias, whose two points
    /// bracket the target (the smallest bias, model.md §7), with Φ² interpolated linearly in
    /// f between them.
    pub fn bias_volts(&self, target_hz: f32) -> Result<f32, TableError> {
        let mut points = self.each_point();
        let mut previous = points.next();
        for (f1, v1) in points {
            if let Some((f0, v0)) = previous {
                if target_hz >= f0.min(f1) && target_hz <= f0.max(f1) {
                    // f0 = f1 only when the target is that frequency: take the lower bias.
                    let t = if f1 == f0 {
                        0.0
                    } else {
                        (target_hz - f0) / (f1 - f0)
                    };
                    let squared = v0 * v0 + t * (v1 * v1 - v0 * v0);
                    return Ok(Real::sqrt(squared.max(0.0)));
                }
            }
            previous = Some((f1, v1));
        }
        // No interval holds it: NaN, or outside the points' range.
        let (low_hz, high_hz) = self.range_hz();
        Err(TableError::OutOfRange {
            target_hz,
            low_hz,
            high_hz,
        })
    }
}

/// Fill `out` with table points (frequency Hz, bias V) from zero bias up to `top` (the
/// highest allowed equilibrium, `Tuner::max_bias`): f's turning points below `top`
/// (`Tuner::for_each_turning_point`, in rising bias) and, around them, points evenly spaced
/// in Φ². A point whose equilibrium cannot be found is reported as `NotFinite` at its index.
pub fn fill<T: Real>(
    device: &Device<T>,
    top: &Equilibrium<T>,
    turns: &[Equilibrium<T>],
    out: &mut [(f32, f32)],
) -> Result<(), TableError> {
    let below_top = |turn: &&Equilibrium<T>| turn.volts < top.volts;
    let grid = out
        .len()
        .saturating_sub(turns.iter().filter(below_top).count());
    if grid < 2 {
        return Err(TableError::BadCount {
            points: out.len().min(usize::from(u16::MAX)) as u16,
        });
    }
    let last = grid - 1;
    // Grid point k: Φ² = (k/last)·Φtop², the last one the top itself.
    let grid_point = |k: usize| {
        if k >= last {
            return Some((top.natural_frequency_hz, top.volts));
        }
        let volts = (top.volts * top.volts * T::of(k as f64) / T::of(last as f64)).sqrt();
        let offset = device.offset_for_bias(volts, top.offset)?;
        Some((device.natural_frequency_hz_at(offset), volts))
    };
    let mut turns = turns.iter().filter(below_top).peekable();
    let mut k = 0;
    for (index, point) in out.iter_mut().enumerate() {
        let next = grid_point(k);
        let turn = turns.next_if(|turn| next.is_none_or(|(_, volts)| turn.volts < volts));
        let (hz, volts) = match turn {
            Some(turn) => (turn.natural_frequency_hz, turn.volts),
            None => {
                k += 1;
                let index = index.min(usize::from(u16::MAX)) as u16;
                next.ok_or(TableError::NotFinite { index })?
            }
        };
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
    write_batch(out, params, None, margin, interpolation_error, points)
}

/// [`write`] for a batch (`Some`: version 2, its ranges and guaranteed limit kept).
pub fn write_batch(
    out: &mut [u8],
    params: &DeviceParams<f32>,
    batch: Option<&TableBatch>,
    margin: f32,
    interpolation_error: f32,
    points: &[(f32, f32)],
) -> Result<usize, TableError> {
    if !(2..=MAX_POINTS).contains(&points.len()) {
        return Err(TableError::BadCount {
            points: points.len().min(usize::from(u16::MAX)) as u16,
        });
    }
    let (version, needed) = match batch {
        None => (VERSION, table_bytes(points.len())),
        Some(_) => (VERSION_BATCH, batch_table_bytes(points.len())),
    };
    let Some(out) = out.get_mut(..needed) else {
        return Err(TableError::BufferTooSmall { needed });
    };
    let header = MAGIC
        .into_iter()
        .chain(version.to_le_bytes())
        .chain((points.len() as u16).to_le_bytes());
    let ranges = batch.into_iter().flat_map(|b| {
        b.low
            .values()
            .into_iter()
            .chain(b.high.values())
            .chain([b.limit_volts])
            .chain(
                b.capacitance
                    .0
                    .iter()
                    .flat_map(|c| [c.volts, c.low_farads, c.high_farads]),
            )
    });
    let values = params
        .values()
        .into_iter()
        .chain([margin, interpolation_error])
        .chain(ranges)
        .chain(points.iter().flat_map(|&(hz, volts)| [hz, volts]))
        .flat_map(f32::to_le_bytes);
    let (body, crc_bytes) = out.split_at_mut(needed - 4);
    for (slot, byte) in body.iter_mut().zip(header.chain(values)) {
        *slot = byte;
    }
    let crc = crc32(body);
    crc_bytes.copy_from_slice(&crc.to_le_bytes());
    Table::parse(out)?;
    Ok(needed)
}
