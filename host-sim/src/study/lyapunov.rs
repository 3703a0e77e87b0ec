//! The largest Lyapunov exponent of the driven membrane (model.md §4): the variational
//! equation δ'' = −k(λ, Φ̄²)·δ − c̄·δ' (k the local stiffness of model.md §5) solved along the
//! motion by the reference's DOP853 (Radau once DOP853 finds it stiff), the tangent
//! renormalised once a drive period (without a drive, once a period of the small oscillation
//! at the start): the mean of the logarithms of its growth over the time after the
//! transient, 1/s. The checks of model.md §6 run at the solver's step ends; Ctrl-C is heard
//! between periods.

use de_resonator::{Drive, FailureMode};
use differential_equations::prelude::*;

use crate::engine::solver::{Motion, Solver, STIFF_FOR_DOP853};
use crate::study::stroboscopic::{Driven, Point, MAX_SECTION_POINTS};
use crate::text::sig;

/// The exponent and how it converged.
#[derive(Clone, Debug)]
pub struct Exponent {
    /// The estimate over all periods after the transient, 1/s (NaN if none was measured).
    pub per_second: f64,
    /// After each period past the transient: the time since the transient ended (s) and the
    /// estimate up to it (1/s).
    pub convergence: Vec<(f64, f64)>,
    /// The first check of model.md §6 that failed at the solver's steps, and when (s).
    pub first_limit: Option<(FailureMode, f64)>,
    /// Why the run ended early (the estimate is over the periods before).
    pub stopped: Option<String>,
    /// The renormalisation interval, s.
    pub interval_seconds: f64,
}

/// The motion and a tangent to it: [λ, λ', δλ, δλ'] in dimensionless time.
struct Variational<'a>(Motion<'a>);

impl ODE<f64, [f64; 4]> for Variational<'_> {
    fn diff(&self, tau: f64, y: &[f64; 4], dydt: &mut [f64; 4]) {
        let mut motion = [0.0; 2];
        self.0.diff(tau, &[y[0], y[1]], &mut motion);
        let p2 = self.0.drive.bias_dimless_squared_at(tau);
        let stiffness = self.0.device.stiffness_dimless(y[0], p2);
        dydt[0] = motion[0];
        dydt[1] = motion[1];
        dydt[2] = y[3];
        dydt[3] = -stiffness * y[2] - self.0.device.damping_dimless() * y[3];
    }
}

/// The largest exponent of `driven` from `from`, over `periods` renormalisation intervals
/// after `transient` of them.
pub fn lyapunov(
    driven: &Driven,
    from: Point,
    transient: usize,
    periods: usize,
) -> Result<Exponent, String> {
    let device = driven.device()?;
    if periods == 0 {
        return Err("periods must be at least 1".into());
    }
    let all = transient as f64 + periods as f64;
    if all > MAX_SECTION_POINTS {
        return Err(format!(
            "{} periods, more than {}",
            sig(all),
            sig(MAX_SECTION_POINTS)
        ));
    }
    if !(from.stretch.is_finite() && from.velocity_per_second.is_finite()) {
        return Err("the start state must be finite numbers".into());
    }
    let scale = device.rad_per_s_per_unit();
    let interval_seconds = if driven.ac_hz > 0.0 {
        1.0 / driven.ac_hz
    } else {
        let hz = device.natural_frequency_hz(from.stretch);
        if !(hz.is_finite() && hz > 0.0) {
            return Err(format!(
                "no drive and no small oscillation at stretch {} to time the renormalisation \
                 by: give ac_hz",
                sig(from.stretch)
            ));
        }
        1.0 / hz
    };
    let drive = Drive::from_volts(&device, driven.bias_volts, driven.ac_volts, driven.ac_hz);
    let ode = Variational(Motion {
        device: &device,
        drive,
    });
    let dtau = interval_seconds * scale;
    let norm = std::f64::consts::FRAC_1_SQRT_2;
    let mut y = [from.stretch, from.velocity_per_second / scale, norm, norm];
    let (mut sum, mut first_step, mut solver) = (0.0, None, Solver::Dop853);
    let mut out = Exponent {
        per_second: f64::NAN,
        convergence: Vec::with_capacity(periods),
        first_limit: None,
        stopped: None,
        interval_seconds,
    };
    for k in 0..transient.saturating_add(periods) {
        if crate::progress::stopped() {
            out.stopped = Some(crate::progress::INTERRUPTED.into());
            break;
        }
        let span = crate::engine::solver::Span {
            from: k as f64 * dtau,
            to: (k + 1) as f64 * dtau,
            short: false,
        };
        let start = crate::engine::erk::Start { y, rate: None };
        let mut limit = None;
        let mut watch = |_: (f64, [f64; 4]), (t, s): (f64, [f64; 4])| {
            if limit.is_none() {
                let p2 = drive.bias_dimless_squared_at(t);
                limit = device.first_failure(s[0], p2).map(|m| (m, t / scale));
            }
        };
        // DOP853, or Radau for the rest of the run once DOP853 finds the motion stiff.
        let mut advanced =
            solver.advance_watched(&ode, span, start, driven.tolerance, first_step, &mut watch);
        if let Err(why) = &advanced {
            if solver == Solver::Dop853 && why.starts_with(STIFF_FOR_DOP853) {
                solver = Solver::Radau;
                advanced =
                    solver.advance_watched(&ode, span, start, driven.tolerance, None, &mut watch);
            }
        }
        if out.first_limit.is_none() {
            out.first_limit = limit;
        }
        let end = match advanced {
            Ok(end) => end,
            Err(why) => {
                out.stopped = Some(why);
                break;
            }
        };
        first_step = Some(end.first_step);
        y = end.y;
        let growth = y[2].hypot(y[3]);
        if !(growth.is_finite() && growth > 0.0) {
            out.stopped = Some(format!("the tangent's growth {growth} is no number"));
            break;
        }
        y[2] /= growth;
        y[3] /= growth;
        if k >= transient {
            sum += growth.ln();
            let seconds = (k + 1 - transient) as f64 * interval_seconds;
            out.convergence.push((seconds, sum / seconds));
        }
    }
    out.per_second = out.convergence.last().map_or(f64::NAN, |&(_, e)| e);
    Ok(out)
}
