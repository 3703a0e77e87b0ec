//! `host-sim sweep`: the frequency response under parametric drive (model.md §7). Each drive
//! frequency is a run from rest at the bias's equilibrium with the core's RK4 in f64, long
//! enough for the response to settle; its amplitude is half the peak-to-peak stretch over the
//! last quarter, from the true extremes between RK4's steps (a quintic through their ends). Peaks are local maxima that stand out from the valleys on both sides.

use de_resonator::{
    Device, DeviceParams, Drive, FailureMode, Integrator, Limit, Method, Monitor, State, StepError,
};

use crate::engine::events::{self, Extremes, Jet};

/// What to sweep.
#[derive(Clone, Copy, Debug)]
pub struct Sweep {
    pub params: DeviceParams<f64>,
    pub bias_volts: f64,
    pub ac_volts: f64,
    /// Lowest and highest drive frequency as multiples of the natural frequency at the bias.
    pub ratios: (f64, f64),
    pub points: usize,
    /// Run length per point, in small-oscillation periods at the bias.
    pub periods: f64,
    /// RK4 steps per period of the faster of the drive and the natural oscillation.
    pub steps_per_period: f64,
}

/// One drive frequency's response.
#[derive(Clone, Debug)]
pub struct Point {
    pub drive_hz: f64,
    /// Half the peak-to-peak stretch over the last quarter of the run; `None` when the run
    /// stopped (the motion left the model's range: no amplitude was measured).
    pub amplitude: Option<f64>,
    /// The first check of model.md §6 that failed along the run, and when (s).
    pub first_limit: Option<(FailureMode, f64)>,
    /// Why the run ended early (after the monitor's crossing: the motion left the range in
    /// which the model is defined).
    pub stopped: Option<String>,
}

/// A peak of the response.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peak {
    pub drive_hz: f64,
    pub amplitude: f64,
    /// How many times the peak stands above the higher of the valleys on its two sides.
    pub prominence: f64,
}

/// A peak counts when it stands this many times above the valleys on both sides.
pub const MIN_PROMINENCE: f64 = 2.0;

/// A whole sweep's result.
#[derive(Clone, Debug)]
pub struct Response {
    /// Small-oscillation natural frequency at the bias (model.md §5), Hz.
    pub natural_frequency_hz: f64,
    pub points: Vec<Point>,
    pub peaks: Vec<Peak>,
}

/// Steps between two looks at the caller's stop flag (a few microseconds of work each).
const STOP_CHECK_STEPS: u64 = 1024;

/// Run the sweep over all cores, with a progress bar.
pub fn run(sweep: &Sweep) -> Result<Response, String> {
    let (device, start, natural_hz) = operating_point(sweep)?;
    let drives = drive_frequencies(sweep, natural_hz)?;
    let points = crate::progress::map("sweep", &drives, |&hz| {
        respond(sweep, &device, start, natural_hz, hz)
    })
    .into_iter()
    .collect::<Result<Vec<_>, _>>()?;
    let peaks = peaks(&points);
    Ok(Response {
        natural_frequency_hz: natural_hz,
        points,
        peaks,
    })
}

/// The sweep's device, its equilibrium stretch at the bias and the natural frequency there.
pub fn operating_point(sweep: &Sweep) -> Result<(Device<f64>, f64, f64), String> {
    let device = Device::new(sweep.params).map_err(|e| e.to_string())?;
    let stretch = Limit::of(&device)
        .stretch_for_bias(&device, sweep.bias_volts)
        .ok_or_else(|| format!("no equilibrium holds {} V", sweep.bias_volts))?;
    let hz = device.natural_frequency_hz(stretch);
    if !(hz.is_finite() && hz > 0.0) {
        return Err(format!(
            "no oscillation about {} V (f = {hz} Hz)",
            sweep.bias_volts
        ));
    }
    Ok((device, stretch, hz))
}

/// The drive frequencies of the sweep, evenly spaced.
pub fn drive_frequencies(sweep: &Sweep, natural_hz: f64) -> Result<Vec<f64>, String> {
    let (low, high) = sweep.ratios;
    if !(low.is_finite() && high.is_finite() && 0.0 < low && low < high) {
        return Err(format!("ratios {low}..{high}: need 0 < low < high"));
    }
    if sweep.points < 3 {
        return Err(format!("{} points: need at least 3", sweep.points));
    }
    if !(sweep.periods.is_finite() && sweep.periods >= 4.0) {
        return Err(format!(
            "{} periods a point: need at least 4",
            sweep.periods
        ));
    }
    if !(sweep.steps_per_period.is_finite() && sweep.steps_per_period >= 8.0) {
        let n = sweep.steps_per_period;
        return Err(format!("{n} steps a period: need at least 8"));
    }
    let n = sweep.points - 1;
    Ok((0..=n)
        .map(|k| natural_hz * (low + (high - low) * k as f64 / n as f64))
        .collect())
}

/// The response at one drive frequency.
pub fn respond(
    sweep: &Sweep,
    device: &Device<f64>,
    start: f64,
    natural_hz: f64,
    drive_hz: f64,
) -> Result<Point, String> {
    let drive = Drive::from_volts(device, sweep.bias_volts, sweep.ac_volts, drive_hz);
    let step = 1.0 / (sweep.steps_per_period * natural_hz.max(drive_hz));
    let steps = (sweep.periods / (natural_hz * step)).ceil() as u64;
    let range = device.model_range();
    let state = State {
        stretch: start,
        velocity: 0.0,
    };
    let mut it = Integrator::new(*device, drive, Method::Rk4, step, range, state, true)
        .map_err(|e| e.to_string())?;
    // The crossing as the monitor sees it at step ends; the amplitude from the path's true
    // extremes, turns located on a quintic through the step ends (time in s).
    let mut monitor = Monitor::new();
    let mut extremes = Extremes::default();
    let jet = |k: u64, s: State<f64>| Jet::of_model(device, &drive, k as f64 * step, s);
    let settled = steps - steps / 4;
    let mut last = state;
    let mut stopped = None;
    for k in 1..=steps {
        // Ctrl-C within a point, not after the sweep (a point may be thousands of periods).
        if k % STOP_CHECK_STEPS == 0 && crate::progress::stopped() {
            return Err(crate::progress::INTERRUPTED.to_string());
        }
        match it.step() {
            Ok(s) => {
                monitor.observe(device, k, s.stretch, it.bias_dimless_squared());
                // The amplitude is measured over the last quarter only.
                if k >= settled {
                    extremes.include(s.stretch);
                    if k > settled && events::turns(last.velocity, s.velocity) {
                        extremes.include(events::turn_stretch(jet(k - 1, last), jet(k, s)));
                    }
                }
                last = s;
            }
            Err(e @ StepError::LeftGuardedRange { .. }) => {
                stopped = Some(e.to_string());
                break;
            }
            Err(e) => return Err(format!("at {drive_hz} Hz: {e}")),
        }
    }
    Ok(Point {
        drive_hz,
        // A stopped run measured nothing: no filler value that would read as data.
        amplitude: stopped.is_none().then_some(extremes.amplitude()),
        first_limit: monitor
            .first_crossing()
            .map(|c| (c.mode, c.tick as f64 * step)),
        stopped,
    })
}

/// The interior local maxima that stand at least `MIN_PROMINENCE` times above the higher of
/// the lowest points between them and the next higher response on either side (or the end).
/// Stopped points measured nothing: each run of measured points between them is searched
/// on its own, and its ends are not peaks (the response may rise past them).
pub fn peaks(points: &[Point]) -> Vec<Peak> {
    points
        .split(|p| p.amplitude.is_none())
        .flat_map(peaks_in_run)
        .collect()
}

/// `peaks` within consecutive measured points.
fn peaks_in_run(points: &[Point]) -> Vec<Peak> {
    let a: Vec<f64> = points.iter().filter_map(|p| p.amplitude).collect();
    let mut found = Vec::new();
    // The ends are not peaks: the response may go on rising past them.
    for i in 1..a.len().saturating_sub(1) {
        if a[i - 1] >= a[i] || a[i + 1] > a[i] {
            continue;
        }
        let valley = |range: &mut dyn Iterator<Item = usize>| {
            let mut low = a[i];
            for j in range {
                if a[j] > a[i] {
                    break;
                }
                low = low.min(a[j]);
            }
            low
        };
        let left = valley(&mut (0..i).rev());
        let right = valley(&mut (i + 1..a.len()));
        let prominence = a[i] / left.max(right);
        if prominence >= MIN_PROMINENCE {
            found.push(Peak {
                drive_hz: points[i].drive_hz,
                amplitude: a[i],
                prominence,
            });
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(amplitudes: &[f64]) -> Vec<Point> {
        amplitudes
            .iter()
            .enumerate()
            .map(|(k, &amplitude)| Point {
                drive_hz: k as f64,
                amplitude: amplitude.is_finite().then_some(amplitude),
                first_limit: None,
                stopped: None,
            })
            .collect()
    }

    /// The amplitude is the true extremes between RK4's steps: at 256 steps a period it
    /// agrees with DOP853 at 1e-12 over the same last quarter (the turns on its dense output)
    /// to 1e-6, where the samples alone are up to (π/256)²/2 = 7.5e-5 low.
    #[test]
    fn amplitudes_are_the_extremes_between_steps() {
        use crate::engine::events::Watch;
        use crate::engine::solver::{Motion, Solver, Tolerance};
        use de_resonator::REFERENCE_DEVICE;
        let device = Device::new(REFERENCE_DEVICE).unwrap();
        let sweep = Sweep {
            params: REFERENCE_DEVICE,
            bias_volts: 7000.0,
            ac_volts: 300.0,
            ratios: (0.5, 2.5),
            points: 3,
            periods: 12.0,
            steps_per_period: 256.0,
        };
        let start = Limit::of(&device)
            .stretch_for_bias(&device, sweep.bias_volts)
            .unwrap();
        let scale = device.rad_per_s_per_unit();
        let natural_hz = device.natural_frequency_hz(start);
        let drive_hz = 0.93 * natural_hz;
        let point = respond(&sweep, &device, start, natural_hz, drive_hz).unwrap();
        // The same run's times: its step, its length, its last quarter.
        let step = 1.0 / (sweep.steps_per_period * natural_hz);
        let steps = (sweep.periods / (natural_hz * step)).ceil() as u64;
        let settled = (steps - steps / 4) as f64 * step * scale;
        let drive = Drive::from_volts(&device, sweep.bias_volts, sweep.ac_volts, drive_hz);
        let mut watch = Watch::<(), [f64; 2]>::new(1e-12);
        let mut on_step =
            |(a, ya): (f64, [f64; 2]), (b, yb), at: &mut dyn FnMut(f64) -> [f64; 2]| {
                if b <= settled {
                    return;
                }
                let from = if a < settled {
                    (settled, at(settled))
                } else {
                    (a, ya)
                };
                watch.step(from, (b, yb), at, |y| (y[0], y[1]), |_, _| None);
            };
        let times = [0.0, steps as f64 * step * scale];
        Solver::Dop853
            .sample(
                &Motion {
                    device: &device,
                    drive,
                },
                [start, 0.0],
                &times,
                Tolerance::both(1e-12),
                Some(&mut on_step),
            )
            .unwrap();
        let (theirs, ours) = (watch.extremes.amplitude(), point.amplitude.unwrap());
        assert!(theirs > 1e-3, "the drive moves it: {theirs}");
        assert!(
            ((ours - theirs) / theirs).abs() < 1e-6,
            "{ours} vs {theirs}"
        );
    }

    #[test]
    fn peaks_need_prominence_on_both_sides() {
        // 5 stands 5x over its valleys (1 left, 1 right); 3 only 1.5x over the valley of 2
        // towards the higher 5; 4 stands 4x over 1 on both sides; the last point is an end.
        let found = peaks(&at(&[1.0, 5.0, 2.0, 3.0, 2.0, 1.0, 4.0, 1.0, 6.0]));
        let where_: Vec<f64> = found.iter().map(|p| p.drive_hz).collect();
        assert_eq!(where_, vec![1.0, 6.0]);
        assert_eq!(found[0].prominence, 5.0);
        assert_eq!(found[1].prominence, 4.0);
        assert!(peaks(&at(&[1.0, 1.0, 1.0])).is_empty());
    }

    /// Stopped points (NaN here: no amplitude) are no peak and break the response: a
    /// measured point beside them is an end, not a peak, and no valley spans them.
    #[test]
    fn stopped_points_are_not_peaks() {
        let nan = f64::NAN;
        let found = peaks(&at(&[1.0, 2.0, nan, nan, 2.0, 1.0, 5.0, 1.0]));
        let where_: Vec<f64> = found.iter().map(|p| p.drive_hz).collect();
        assert_eq!(where_, vec![6.0]);
        assert!(peaks(&at(&[nan, nan, nan])).is_empty());
    }
}
