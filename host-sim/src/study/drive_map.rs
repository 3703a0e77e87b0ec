//! The safe drive map (model.md §6, §7): over AC amplitude × drive frequency at the bias a
//! board tunes to, the largest swing of the full simulation (the reference's DOP853 from rest
//! at the bias's equilibrium, the AC switched on at t = 0) and whether it stays inside §6,
//! beside the board's own acceptance of that `ac`: every boot check of `start` with it
//! (`Controller::start` on the image's device, table, amplifier and settings, in f32 as on
//! the target). The two agree when every drive the board accepts stays inside (a run that
//! leaves the model's range before its end counts as not inside).

use de_resonator::controller::{Controller, Settings};
use de_resonator::image::Image;
use de_resonator::{DeviceParams, FailureMode};

use crate::engine::solver::Tolerance;
use crate::study::stroboscopic::{self, Driven, Point, STUDY_TOLERANCE};

/// One drive of the map.
#[derive(Clone, Debug)]
pub struct Cell {
    pub ac_volts: f64,
    pub ac_hz: f64,
    /// The board's verdict: `None` accepted, else its refusal in its own words.
    pub refused: Option<String>,
    /// The largest |λ − λ*| of the full simulation (λ* the bias's equilibrium), up to where
    /// it ran.
    pub max_swing: f64,
    /// The first check of model.md §6 the simulation failed, and when (s).
    pub first_limit: Option<(FailureMode, f64)>,
    /// Why the simulation ended early: the motion left the model's range (after a crossing,
    /// or before any).
    pub stopped: Option<String>,
}

impl Cell {
    /// The full simulation ran to its end inside model.md §6.
    pub fn safe(&self) -> bool {
        self.first_limit.is_none() && self.stopped.is_none()
    }

    /// Accepted by the board yet not safe in the full simulation: the two disagree.
    pub fn disagrees(&self) -> bool {
        self.refused.is_none() && !self.safe()
    }
}

/// The map and where it was drawn.
#[derive(Clone, Debug)]
pub struct Map {
    /// The bias the board tunes to for the image's target, V.
    pub bias_volts: f64,
    /// λ* there, and the small-oscillation frequency there.
    pub stretch: f64,
    pub natural_frequency_hz: f64,
    pub duration_seconds: f64,
    /// Row by row: each amplitude over every frequency.
    pub cells: Vec<Cell>,
}

/// Where the board holds: the bias it tunes to for the image's target (no AC), the plant's
/// equilibrium stretch there and its small-oscillation frequency, Hz.
pub fn operating_point(image: &[u8], plant: DeviceParams<f64>) -> Result<(f64, f64, f64), String> {
    let image = Image::parse(image).map_err(|e| e.to_string())?;
    let amplifier = image.amplifier.amplifier().map_err(|e| e.to_string())?;
    let at_rest = Settings {
        ac_volts: 0.0,
        ac_hz: 0.0,
        ..image.settings
    };
    let (_, boot) = Controller::start(image.params, image.table, amplifier, at_rest)
        .map_err(|e| format!("the board refuses its target: {e}"))?;
    let bias_volts = f64::from(boot.bias_volts);
    let device = de_resonator::Device::new(plant).map_err(|e| e.to_string())?;
    let stretch = de_resonator::Limit::of(&device)
        .stretch_for_bias(&device, bias_volts)
        .ok_or_else(|| format!("the plant holds no equilibrium at {bias_volts} V"))?;
    let natural_hz = device.natural_frequency_hz(stretch);
    if !(natural_hz.is_finite() && natural_hz > 0.0) {
        return Err(format!(
            "the plant has no small oscillation at {bias_volts} V (stretch {stretch})"
        ));
    }
    Ok((bias_volts, stretch, natural_hz))
}

/// The map of `amplitudes` × `frequencies` for the board `image` describes, its plant the
/// device `plant` (f64: the image's own, or a device of its batch), each run `periods` of
/// the natural frequency at the bias long.
pub fn drive_map(
    image: &[u8],
    plant: DeviceParams<f64>,
    amplitudes: &[f64],
    frequencies: &[f64],
    periods: f64,
) -> Result<Map, String> {
    let (bias_volts, stretch, natural_hz) = operating_point(image, plant)?;
    let image = Image::parse(image).map_err(|e| e.to_string())?;
    let amplifier = image.amplifier.amplifier().map_err(|e| e.to_string())?;
    let board = |settings: Settings| {
        Controller::start(image.params, image.table, amplifier, settings).map(|(_, boot)| boot)
    };
    if !(periods.is_finite() && periods > 0.0) {
        return Err(format!("periods {periods}: need a positive number"));
    }
    let duration_seconds = periods / natural_hz;
    for (what, values) in [("ac_volts", amplitudes), ("ac_hz", frequencies)] {
        if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(format!("{what} {v}: need finite values ≥ 0"));
        }
    }
    let drives: Vec<(f64, f64)> = amplitudes
        .iter()
        .flat_map(|&a| frequencies.iter().map(move |&f| (a, f)))
        .collect();
    let cells = crate::progress::map("drive map", &drives, |&(ac_volts, ac_hz)| {
        let asked = Settings {
            ac_volts: ac_volts as f32,
            ac_hz: ac_hz as f32,
            ..image.settings
        };
        let refused = board(asked).err().map(|e| e.to_string());
        let driven = Driven {
            params: plant,
            bias_volts,
            ac_volts,
            ac_hz,
            tolerance: Tolerance::both(STUDY_TOLERANCE),
        };
        let rest = Point {
            stretch,
            velocity_per_second: 0.0,
        };
        // No section: the extremes and the crossing come from the watched path.
        let (max_swing, first_limit, stopped) =
            match stroboscopic::watched(&driven, rest, &[], duration_seconds) {
                Ok(run) => (
                    (run.extremes.max - stretch).max(stretch - run.extremes.min),
                    run.first_limit,
                    run.stopped,
                ),
                Err(e) => (f64::NAN, None, Some(e)),
            };
        Cell {
            ac_volts,
            ac_hz,
            refused,
            max_swing,
            first_limit,
            stopped,
        }
    });
    crate::progress::interrupted(cells.iter().map(|c| c.stopped.as_deref()))?;
    Ok(Map {
        bias_volts,
        stretch,
        natural_frequency_hz: natural_hz,
        duration_seconds,
        cells,
    })
}
