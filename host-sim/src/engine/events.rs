//! Events between samples: where the stretch turns (its true extremes) and where a check of
//! model.md §6 first fails, located on a continuous path of the state (a solver's dense
//! output, or a quintic Hermite through step ends), not at the nearest output sample.

use de_resonator::numerics::roots;
use de_resonator::{Device, Drive, State};

/// Where the velocity changes sign in `[t0, t1]` (it has opposite signs, or is 0, at the
/// ends): the core's bracketed root of `velocity(t)`, to adjacent times (there the stretch is
/// flat: its error is ½·λ''·δt²).
pub fn turn(t0: f64, t1: f64, mut velocity: impl FnMut(f64) -> f64) -> f64 {
    // Before the turn the velocity has the sign of t0's: signed so that it is negative there
    // and rises through zero (a velocity of exactly 0 counts as after the turn).
    let rising = velocity(t0) < 0.0 || velocity(t1) > 0.0;
    let sign = if rising { 1.0 } else { -1.0 };
    let (low, high) = roots::root(t0, t1, |t| sign * velocity(t));
    0.5 * (low + high)
}

/// Whether the velocity turns in an interval whose ends have velocities `v0`, `v1`.
pub fn turns(v0: f64, v1: f64) -> bool {
    (v0 < 0.0 && v1 >= 0.0) || (v0 > 0.0 && v1 <= 0.0)
}

/// The first failure between a time that passes and a later one that fails: bisection on
/// `fails(t)` until they are `resolution` apart; the failing end and what failed there.
pub fn first_failing<M>(
    passes: f64,
    (fails_at, mode): (f64, M),
    resolution: f64,
    mut fails: impl FnMut(f64) -> Option<M>,
) -> (f64, M) {
    let (mut low, mut high, mut mode) = (passes, fails_at, mode);
    while high - low > resolution {
        let mid = 0.5 * (low + high);
        if mid <= low || mid >= high {
            break;
        }
        match fails(mid) {
            Some(m) => (high, mode) = (mid, m),
            None => low = mid,
        }
    }
    (high, mode)
}

/// The lowest and highest stretch seen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extremes {
    pub min: f64,
    pub max: f64,
}

impl Default for Extremes {
    fn default() -> Self {
        Self {
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        }
    }
}

impl Extremes {
    pub fn include(&mut self, stretch: f64) {
        self.min = self.min.min(stretch);
        self.max = self.max.max(stretch);
    }

    /// Half the swing, max − min over 2.
    pub fn amplitude(&self) -> f64 {
        0.5 * (self.max - self.min)
    }
}

/// The stretch and its velocity, and its acceleration, at one time: the ends of a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jet {
    pub t: f64,
    pub stretch: f64,
    pub velocity: f64,
    pub acceleration: f64,
}

impl Jet {
    /// The core model's jet at `t` s, from its state (stretch, dλ/dτ), with the acceleration
    /// of model.md §4 under the drive's bias then: velocity in 1/s, acceleration in 1/s².
    pub fn of_model(device: &Device<f64>, drive: &Drive<f64>, t: f64, state: State<f64>) -> Self {
        let scale = device.rad_per_s_per_unit();
        let p2 = drive.bias_dimless_squared_at(t * scale);
        Jet {
            t,
            stretch: state.stretch,
            velocity: state.velocity * scale,
            acceleration: device.acceleration(state, p2) * scale * scale,
        }
    }
}

/// The stretch where a path turns between two step ends whose velocities differ in sign: on
/// the quintic through their jets.
pub fn turn_stretch(a: Jet, b: Jet) -> f64 {
    let path = Hermite::new(a, b);
    path.at(turn(a.t, b.t, |t| path.at(t).1)).0
}

/// The quintic through two `Jet`s (value, slope and curvature at both ends): the path of a
/// fixed-step method or of a solver step without dense output, error O(h⁶) (for an
/// oscillation of ω, (ωh)⁶/46080 of its amplitude).
#[derive(Clone, Copy, Debug)]
pub struct Hermite {
    t0: f64,
    h: f64,
    /// Coefficients of s⁰..s⁵, s = (t − t0)/h.
    c: [f64; 6],
}

impl Hermite {
    pub fn new(a: Jet, b: Jet) -> Self {
        let h = b.t - a.t;
        let (p0, p1) = (a.stretch, b.stretch);
        let (d0, d1) = (a.velocity * h, b.velocity * h);
        let (e0, e1) = (a.acceleration * h * h, b.acceleration * h * h);
        // The quintic Hermite basis in s ∈ [0, 1].
        let c3 = 10.0 * (p1 - p0) - 6.0 * d0 - 4.0 * d1 - 1.5 * e0 + 0.5 * e1;
        let c4 = -15.0 * (p1 - p0) + 8.0 * d0 + 7.0 * d1 + 1.5 * e0 - e1;
        let c5 = 6.0 * (p1 - p0) - 3.0 * d0 - 3.0 * d1 - 0.5 * e0 + 0.5 * e1;
        Self {
            t0: a.t,
            h,
            c: [p0, d0, 0.5 * e0, c3, c4, c5],
        }
    }

    /// The stretch and its velocity at `t`.
    pub fn at(&self, t: f64) -> (f64, f64) {
        let s = (t - self.t0) / self.h;
        let c = &self.c;
        let value = c[0] + s * (c[1] + s * (c[2] + s * (c[3] + s * (c[4] + s * c[5]))));
        let slope = c[1] + s * (2.0 * c[2] + s * (3.0 * c[3] + s * (4.0 * c[4] + s * 5.0 * c[5])));
        (value, slope / self.h)
    }
}

/// The events along a path, step by step: the stretch's extremes (ends, midpoints and every
/// turn, located), and the first time a check fails, with what failed and the state there.
/// A step is probed at its end, its midpoint and each turn (a brief excursion peaks where
/// the stretch turns), then bisected on the path to `resolution`.
#[derive(Clone, Copy, Debug)]
pub struct Watch<M, S> {
    pub extremes: Extremes,
    /// The first failure: its time, what failed, and the state there.
    pub first: Option<(f64, M, S)>,
    resolution: f64,
    started: bool,
}

impl<M: Copy, S: Copy> Watch<M, S> {
    /// Times located to `resolution` (the path's own unit of time).
    pub fn new(resolution: f64) -> Self {
        Self {
            extremes: Extremes::default(),
            first: None,
            resolution,
            started: false,
        }
    }

    /// One step of the path from `(t0, s0)` to `(t1, s1)`: `at(t)` is the state on it,
    /// `key(s)` its stretch and velocity, `fails(t, s)` the check that fails there, if any.
    pub fn step(
        &mut self,
        (t0, s0): (f64, S),
        (t1, s1): (f64, S),
        mut at: impl FnMut(f64) -> S,
        key: impl Fn(&S) -> (f64, f64),
        mut fails: impl FnMut(f64, &S) -> Option<M>,
    ) {
        if !self.started {
            self.started = true;
            self.extremes.include(key(&s0).0);
            if let Some(mode) = fails(t0, &s0) {
                self.first = Some((t0, mode, s0));
            }
        }
        let tm = 0.5 * (t0 + t1);
        let sm = at(tm);
        // The probes in time order: a turn in each half, the midpoint, the end.
        let mut probes: [Option<(f64, S)>; 4] = [None; 4];
        for (k, ((a, sa), (b, sb))) in [((t0, s0), (tm, sm)), ((tm, sm), (t1, s1))]
            .into_iter()
            .enumerate()
        {
            if turns(key(&sa).1, key(&sb).1) {
                let t = turn(a, b, |t| key(&at(t)).1);
                probes[2 * k] = Some((t, at(t)));
            }
            probes[2 * k + 1] = Some((b, sb));
        }
        for (_, s) in probes.iter().flatten() {
            self.extremes.include(key(s).0);
        }
        if self.first.is_some() {
            return;
        }
        let mut passes = t0;
        for (t, s) in probes.into_iter().flatten() {
            match fails(t, &s) {
                Some(mode) => {
                    let (t, mode) =
                        first_failing(passes, (t, mode), self.resolution, |t| fails(t, &at(t)));
                    self.first = Some((t, mode, at(t)));
                    return;
                }
                None => passes = t,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quintic reproduces a quintic exactly, and a cosine over 1/20 of its period to
    /// (ωh)⁶/46080 of its amplitude.
    #[test]
    fn hermite_matches_polynomials_and_an_oscillation() {
        let p = |t: f64| 1.0 + t - 2.0 * t.powi(2) + 0.5 * t.powi(3) + 3.0 * t.powi(5);
        let dp = |t: f64| 1.0 - 4.0 * t + 1.5 * t.powi(2) + 15.0 * t.powi(4);
        let ddp = |t: f64| -4.0 + 3.0 * t + 60.0 * t.powi(3);
        let jet = |t: f64| Jet {
            t,
            stretch: p(t),
            velocity: dp(t),
            acceleration: ddp(t),
        };
        let path = Hermite::new(jet(0.3), jet(1.1));
        for k in 0..=10 {
            let t = 0.3 + 0.08 * f64::from(k);
            let (x, v) = path.at(t);
            assert!((x - p(t)).abs() < 1e-12 && (v - dp(t)).abs() < 1e-11, "{t}");
        }
        let omega = 2.0;
        let h = std::f64::consts::TAU / omega / 20.0;
        let jet = |t: f64| Jet {
            t,
            stretch: (omega * t).cos(),
            velocity: -omega * (omega * t).sin(),
            acceleration: -omega * omega * (omega * t).cos(),
        };
        let path = Hermite::new(jet(0.7), jet(0.7 + h));
        let bound = (omega * h).powi(6) / 46080.0;
        for k in 0..=10 {
            let t = 0.7 + h * f64::from(k) / 10.0;
            assert!((path.at(t).0 - (omega * t).cos()).abs() <= bound, "{t}");
        }
    }

    /// A turn is the velocity's zero; a first failure the predicate's edge.
    #[test]
    fn turns_and_failures_are_located() {
        let at = turn(0.0, 3.0, |t| (t - 1.234_567_890_123).sin());
        assert!((at - 1.234_567_890_123).abs() < 1e-15);
        let at = turn(0.0, 3.0, |t| -(t - 2.5));
        assert!((at - 2.5).abs() < 1e-15);
        assert!(turns(1.0, -1.0) && turns(-1.0, 0.0) && !turns(1.0, 2.0) && !turns(0.0, 0.0));
        let (t, mode) = first_failing(0.0, (1.0, 'a'), 1e-12, |t| (t > 0.3).then_some('b'));
        assert!(t > 0.3 && t - 0.3 <= 1e-12 && mode == 'b');
    }
}
