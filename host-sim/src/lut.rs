//! `host-sim lut`: the tuning table the firmware flashes (layout in the core's `table`
//! module), from the f64 model, with its interpolation error against the direct solve.

use de_resonator::acquire::FrontEnd;
use de_resonator::image::{self, AmplifierSpec, Image, PowerUp};
use de_resonator::model::tolerance::DeviceBox;
use de_resonator::table::{self, Table, TableBatch};
use de_resonator::{DeviceParams, Settings, Tuner};

/// Points a table starts with when its size is not asked for; doubled (up to
/// `table::MAX_POINTS`) until the interpolation error is at most `TARGET_ERROR`.
pub const DEFAULT_POINTS: usize = 64;

/// The interpolation error a table is made to (when its size is not asked for): a tenth of
/// the controller's default agreement between table and solve (1e-4), so that every table
/// `lut` makes boots with the default settings.
pub const TARGET_ERROR: f64 = 1e-5;

/// Interpolation error is checked at this many points inside every interval.
const CHECKS_PER_INTERVAL: usize = 8;

/// A table made, with what was measured on it.
pub struct Made {
    pub bytes: Vec<u8>,
    /// (frequency Hz, bias V) as stored.
    pub points: Vec<(f32, f32)>,
    /// The table against the f64 direct solve.
    pub errors: Errors,
    pub crc: u32,
    /// For a batch: its guaranteed limit (model.md §10), V, which the table's top and the
    /// board's cap are (1 − margin) of.
    pub batch_limit_volts: Option<f64>,
}

/// Make the table for the batch `b`'s device up to (1 − margin)·limit less the `HEADROOM`
/// the f32 firmware needs — for a batch with tolerances, the guaranteed limit (model.md §10),
/// kept in the table with the batch's ranges: `points` points, or (`None`) the fewest of 64,
/// 128, … 1024 whose interpolation error is at most `TARGET_ERROR`. `bias_error`: whether to
/// measure the bias against the direct solve too (`Errors::volts`; the image needs only the
/// frequency's).
pub fn make(
    b: &DeviceBox,
    margin: f64,
    points: Option<usize>,
    bias_error: bool,
) -> Result<Made, String> {
    let batch = batch_of(b, margin)?;
    let params = b.nominal;
    if let Some(points) = points {
        return make_with(params, margin, batch, points, bias_error, None);
    }
    let mut points = DEFAULT_POINTS;
    loop {
        // A table with points to spare is given up at its first error above the target.
        let give_up_above = (points < table::MAX_POINTS).then_some(TARGET_ERROR);
        let made = make_with(params, margin, batch, points, bias_error, give_up_above)?;
        if made.errors.frequency <= TARGET_ERROR || points >= table::MAX_POINTS {
            return Ok(made);
        }
        points = (2 * points).min(table::MAX_POINTS);
    }
}

/// The table of `points` points: f's turning points and, around them, points evenly spaced
/// in Φ² (f − f(0) ∝ Φ² near zero bias), so Φ² linear in f interpolates well everywhere.
/// `give_up_above`: an error above which the check stops (the table is not the one made).
fn make_with(
    params: DeviceParams<f64>,
    margin: f64,
    batch: Option<(TableBatch, f64)>,
    points: usize,
    bias_error: bool,
    give_up_above: Option<f64>,
) -> Result<Made, String> {
    if !(2..=table::MAX_POINTS).contains(&points) {
        return Err(format!("{points} points: need 2 to {}", table::MAX_POINTS));
    }
    let device = de_resonator::Device::new(params).map_err(|e| e.to_string())?;
    let tuner = Tuner::new(device);
    // Against the device's own limit, the margin that puts the top at (1 − margin) times the
    // batch's guaranteed one.
    let own = own_margin(&tuner, margin, batch.map(|(_, limit)| limit));
    let top = tuner
        .max_bias(table::table_margin(own))
        .map_err(|e| e.to_string())?;
    let mut turns = Vec::new();
    tuner
        .for_each_turning_point(table::table_margin(own), |turn| turns.push(turn))
        .map_err(|e| e.to_string())?;
    let mut stored = vec![(0.0f32, 0.0f32); points];
    table::fill(&device, &top, &turns, &mut stored).map_err(|e| e.to_string())?;
    // The f32 table is checked against the f64 direct solve, the table's error in its
    // header being found from the table itself: write once with 0, measure, write again.
    let params32 = params.cast::<f32>();
    let kept = batch.as_ref().map(|(b, _)| b);
    let mut bytes = vec![0u8; table::table_bytes(points)];
    if kept.is_some() {
        bytes = vec![0u8; table::batch_table_bytes(points)];
    }
    table::write_batch(&mut bytes, &params32, kept, margin as f32, 0.0, &stored)
        .map_err(|e| e.to_string())?;
    let errors = {
        let t = Table::parse(&bytes).map_err(|e| e.to_string())?;
        let top_volts = bias_error.then_some(top.volts);
        let margin = table::table_margin(own);
        interpolation_error(&t, &tuner, margin, top_volts, give_up_above)?
    };
    let error = errors.frequency as f32;
    table::write_batch(&mut bytes, &params32, kept, margin as f32, error, &stored)
        .map_err(|e| e.to_string())?;
    let crc = u32::from_le_bytes(bytes[bytes.len() - 4..].try_into().unwrap_or([0; 4]));
    Ok(Made {
        bytes,
        points: stored,
        errors,
        crc,
        batch_limit_volts: batch.map(|(_, limit)| limit),
    })
}

/// The margin against the device's own limit that puts a table's top at (1 − `margin`)
/// times the batch's guaranteed limit (`margin` itself for a device alone).
fn own_margin(tuner: &Tuner<f64>, margin: f64, batch_limit_volts: Option<f64>) -> f64 {
    match batch_limit_volts {
        Some(limit) => 1.0 - (1.0 - margin) * limit / tuner.limit().at.volts,
        None => margin,
    }
}

/// What a table made with `margin` keeps of the batch `b` (none for a device alone): its
/// ranges rounded outward to f32, its guaranteed limit rounded down, its capacitance bands up
/// to the table's top; and that limit in f64.
fn batch_of(b: &DeviceBox, margin: f64) -> Result<Option<(TableBatch, f64)>, String> {
    if b.is_exact() {
        return Ok(None);
    }
    let mut leaves = crate::cmd::safe::search_leaves();
    let g = b.guaranteed_limit(&mut leaves).map_err(|e| e.to_string())?;
    if !(g.volts > 0.0) {
        return Err(format!(
            "no bias is safe for every device within the tolerances (the guaranteed limit is \
             0 V; the lowest limit found {} V): narrow them",
            g.lowest_found_volts
        ));
    }
    let tuner = Tuner::new(de_resonator::Device::new(b.nominal).map_err(|e| e.to_string())?);
    let own = own_margin(&tuner, margin, Some(g.volts));
    let top = tuner
        .max_bias(table::table_margin(own))
        .map_err(|e| e.to_string())?;
    let kept = TableBatch::of(b, g.volts, top.volts, &mut leaves).map_err(|e| e.to_string())?;
    Ok(Some((kept, g.volts)))
}

/// How far the table's bias is from the direct solve, at `CHECKS_PER_INTERVAL` points inside
/// every interval and at the points themselves: the largest relative error of the natural
/// frequency the table's bias gives (f64 model) against the target, where it is, and the
/// largest bias difference as a fraction of the top bias. Near zero bias, dΦ/df is unbounded
/// (f − f(0) ∝ Φ²), so the bias difference there is set by f32's rounding of f, not by the
/// interpolation; the frequency error is the one that matters and is well conditioned. The
/// bias difference (a direct solve at every check, as a fraction of the top bias
/// `top_volts`) only where asked for. With `give_up_above`, the check ends at the first
/// frequency error above it (that error returned).
fn interpolation_error(
    t: &Table,
    tuner: &Tuner<f64>,
    margin: f64,
    top_volts: Option<f64>,
    give_up_above: Option<f64>,
) -> Result<Errors, String> {
    let device = tuner.device();
    // The f64 range: the f32 end points may round just outside it.
    let range = tuner.tunable_range(margin).map_err(|e| e.to_string())?;
    let mut errors = Errors {
        frequency: 0.0,
        worst_hz: f64::NAN,
        volts: top_volts.map(|_| 0.0),
    };
    let (low, high) = t.range_hz();
    for k in 0..t.points() - 1 {
        let (f0, f1) = (f64::from(t.point(k).0), f64::from(t.point(k + 1).0));
        for j in 0..=CHECKS_PER_INTERVAL {
            let hz32 = (f0 + (f1 - f0) * j as f64 / CHECKS_PER_INTERVAL as f64) as f32;
            let hz = f64::from(hz32);
            if !(hz32 >= low && hz32 <= high && hz >= range.low_hz && hz <= range.high_hz) {
                continue;
            }
            let table_volts = f64::from(t.bias_volts(hz32).map_err(|e| e.to_string())?);
            // Up to the limit, not the top: the top point's f32 volts may round above it.
            let offset = device
                .offset_for_bias(table_volts, tuner.limit().at.offset)
                .ok_or_else(|| format!("no equilibrium at the table's {table_volts} V"))?;
            let error = (device.natural_frequency_hz_at(offset) - hz).abs() / hz;
            if error > errors.frequency {
                errors.frequency = error;
                errors.worst_hz = hz;
                if give_up_above.is_some_and(|limit| error > limit) {
                    return Ok(errors);
                }
            }
            if let (Some(worst), Some(top)) = (&mut errors.volts, top_volts) {
                let solved = tuner
                    .tune(hz, margin)
                    .map_err(|e| format!("direct solve at {hz} Hz: {e}"))?;
                *worst = worst.max((table_volts - solved.volts).abs() / top);
            }
        }
    }
    Ok(errors)
}

/// A table's measured errors.
pub struct Errors {
    /// Largest relative error of the natural frequency at the table's bias.
    pub frequency: f64,
    /// Where it is, Hz.
    pub worst_hz: f64,
    /// Largest bias difference from the direct solve, as a fraction of the top bias (where
    /// asked for).
    pub volts: Option<f64>,
}

/// The image of a device, an amplifier, a front end and settings, its table made for the
/// settings' margin: the bytes `host-sim image` writes and `host-sim serve` boots from.
pub fn image(
    b: &DeviceBox,
    amplifier: &AmplifierSpec,
    front_end: &FrontEnd,
    settings: &Settings,
    power_up: PowerUp,
) -> Result<Vec<u8>, String> {
    let params = b.nominal;
    let made = make(b, f64::from(settings.margin), None, false)?;
    let mut bytes = vec![0; image::image_bytes(made.bytes.len())];
    let params32: DeviceParams<f32> = params.cast();
    Image::write(
        &mut bytes,
        &params32,
        amplifier,
        front_end,
        settings,
        power_up,
        &made.bytes,
    )
    .map_err(|e| e.to_string())?;
    Ok(bytes)
}
