//! The plant: the resonator as it is, not as the controller is told it is. model.md §§2–6
//! written out again in SI units and f64, with the extras of §8 a scene switches on: viscous
//! damping, viscoelastic networks (Zhao–Koh–Suo, several branches), and the amplifier's
//! bandwidth, slew limit and rail. Its safety checks (§6, with the networks' stresses) are
//! the truth host-sim holds the controller to.

use de_resonator::{DeviceParams, FailureMode};
use differential_equations::prelude::*;

use crate::engine::events::{self, Hermite, Jet};
use crate::engine::simulate::{Solver, Tolerance};

/// Most viscoelastic branches a plant may have.
pub const MAX_BRANCHES: usize = 3;

/// State: λ, dλ/dt (1/s), the amplifier's output (V), then ξ1A, ξ2A, ξ1B, ξ2B per branch.
pub const STATE: usize = 3 + 4 * MAX_BRANCHES;

pub type Vector = [f64; STATE];

/// One viscoelastic branch: a network of shear modulus `modulus` (Pa) in series with a
/// dashpot; relaxation time η/μβ in seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Branch {
    pub modulus: f64,
    pub relaxation_seconds: f64,
}

/// The amplifier between the DAC and the membrane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmplifierModel {
    /// Volts out per volt in.
    pub gain: f64,
    /// −3 dB bandwidth, Hz (infinite: the output follows at once).
    pub bandwidth_hz: f64,
    /// Largest |dV/dt|, V/s (infinite: none).
    pub slew_volts_per_second: f64,
    /// The highest output it can give, V (saturation).
    pub rail_volts: f64,
}

/// The plant: the elastic device (its own parameters), the branches and the amplifier.
#[derive(Clone, Debug, PartialEq)]
pub struct Plant {
    pub params: DeviceParams<f64>,
    pub branches: Vec<Branch>,
    pub amplifier: AmplifierModel,
    /// The membrane's leakage resistance over time (model.md §8).
    pub leakage: Leakage,
}

/// The membrane's leakage resistance: from `ohms` it falls geometrically to `final_ohms`
/// over `ramp_seconds` (conduction rising before breakdown), then stays; below
/// `breakdown_below_ohms` under voltage the membrane breaks down (this scene model's
/// stand-in for the end of that precursor).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Leakage {
    pub ohms: f64,
    pub final_ohms: f64,
    pub ramp_seconds: f64,
    pub breakdown_below_ohms: f64,
}

impl Leakage {
    /// No leakage, no breakdown by it.
    pub const NONE: Leakage = Leakage {
        ohms: f64::INFINITY,
        final_ohms: f64::INFINITY,
        ramp_seconds: 0.0,
        breakdown_below_ohms: 0.0,
    };

    /// The resistance at `seconds`, Ω.
    pub fn ohms_at(&self, seconds: f64) -> f64 {
        if self.final_ohms == self.ohms || !(self.ramp_seconds > 0.0) {
            return self.final_ohms;
        }
        let s = (seconds / self.ramp_seconds).clamp(0.0, 1.0);
        self.ohms * (self.final_ohms / self.ohms).powf(s)
    }

    /// Whether the membrane has broken down at `seconds` under `volts`.
    pub fn breaks_down(&self, seconds: f64, volts: f64) -> bool {
        volts.abs() > 1.0 && self.ohms_at(seconds) < self.breakdown_below_ohms
    }
}

/// ε0, F/m (CODATA 2018).
const VACUUM_PERMITTIVITY: f64 = 8.854_187_812_8e-12;

/// Gent nominal stresses (s1, s2) of model.md §3, Pa, and I1 (NaN past lock-up). With
/// q = λ1²λ2² and D = q·(1 − (I1 − 3)/Jlim) = q·(1 − (λ1² + λ2² − 3)/Jlim) − 1/Jlim:
/// s1 = μ(λ1²q − 1)/(λ1·D) and s2 = μ(λ2²q − 1)/(λ2·D), one division each. The dynamics'
/// right-hand side waits on this (its time is the chain of divisions), so it has no more.
#[inline]
fn gent(p: &DeviceParams<f64>, l1: f64, l2: f64) -> (f64, f64, f64) {
    let (a, b) = (l1 * l1, l2 * l2);
    let q = a * b;
    // Off the chain: a constant of the device.
    let inverse_jlim = p.jlim.map_or(0.0, |jlim| 1.0 / jlim);
    let big_d = q * (1.0 - (a + b - 3.0) * inverse_jlim) - inverse_jlim;
    let i1 = a + b + 1.0 / q;
    if !(big_d > 0.0) {
        return (f64::NAN, f64::NAN, i1);
    }
    let mu = p.shear_modulus;
    (
        mu * (a * q - 1.0) / (l1 * big_d),
        mu * (b * q - 1.0) / (l2 * big_d),
        i1,
    )
}

/// A network's nominal stresses (s1, s2) at stretches (λ1, λ2) over viscous ones (ξ1, ξ2):
/// ∂/∂λ of (μβ/2)·((λ1/ξ1)² + (λ2/ξ2)² + (ξ1ξ2/λ1λ2)² − 3).
fn network(modulus: f64, l1: f64, l2: f64, x1: f64, x2: f64) -> (f64, f64) {
    let c = (x1 * x2 / (l1 * l2)).powi(2);
    (
        modulus * (l1 / (x1 * x1) - c / l1),
        modulus * (l2 / (x2 * x2) - c / l2),
    )
}

/// dξ1/dt, dξ2/dt of one branch (model.md §8).
fn flow(b: &Branch, l1: f64, l2: f64, x1: f64, x2: f64) -> (f64, f64) {
    let rate = 1.0 / (6.0 * b.relaxation_seconds);
    let (a1, a2) = ((l1 / x1).powi(2), (l2 / x2).powi(2));
    let c = (x1 * x2 / (l1 * l2)).powi(2);
    (
        x1 * rate * (2.0 * a1 - a2 - c),
        x2 * rate * (2.0 * a2 - a1 - c),
    )
}

impl Plant {
    /// M = m·L1A + ρ·L2·H·L1A·L1/3 (model.md §4), kg.
    pub fn mass(&self) -> f64 {
        let p = &self.params;
        let l1 = p.length_active + p.length_passive;
        p.bar_mass * p.length_active
            + p.density * p.width * p.thickness * p.length_active * l1 / 3.0
    }

    fn permittivity(&self) -> f64 {
        self.params.relative_permittivity * VACUUM_PERMITTIVITY
    }

    /// λB from λ (model.md §2), as λB = L1·λ1p/L1B − (L1A/L1B)·λ: the divisions are of
    /// constants, off the right-hand side's chain.
    pub fn passive_stretch(&self, stretch: f64) -> f64 {
        let p = &self.params;
        let l1 = p.length_active + p.length_passive;
        l1 * p.prestretch_1 / p.length_passive - p.length_active / p.length_passive * stretch
    }

    /// Total nominal stresses (s1, s2) of membrane A (`active`) or B at stretches (λ1, λ2),
    /// with the networks at the viscous stretches in `y`.
    #[inline]
    fn stresses(&self, y: &Vector, l1: f64, l2: f64, active: bool) -> (f64, f64) {
        let (mut s1, mut s2, _) = gent(&self.params, l1, l2);
        for (k, b) in self.branches.iter().enumerate() {
            let at = 3 + 4 * k + if active { 0 } else { 2 };
            let (n1, n2) = network(b.modulus, l1, l2, y[at], y[at + 1]);
            s1 += n1;
            s2 += n2;
        }
        (s1, s2)
    }

    /// λ'' at state `y` under `volts` on A (model.md §4 with the networks), 1/s².
    fn acceleration(&self, y: &Vector, volts: f64) -> f64 {
        let p = &self.params;
        let (l, v) = (y[0], y[1]);
        let e0 = volts / p.thickness;
        let l2 = p.prestretch_2;
        let (sa, _) = self.stresses(y, l, l2, true);
        let (sb, _) = self.stresses(y, self.passive_stretch(l), l2, false);
        let electric = self.permittivity() * e0 * e0 * l * p.prestretch_2 * p.prestretch_2;
        // 1/M of constants, off the chain.
        (p.width * p.thickness * (sb - sa + electric) - p.damping * v) * (1.0 / self.mass())
    }

    /// The amplifier's output from `from_volts` at `t0` with `input` volts held at its input:
    /// its rate, (target − V)·2π·bandwidth clamped to ± the slew rate (target: the input
    /// below the rail), depends on nothing else, so over a tick it has a closed form.
    fn amplifier_path(&self, t0: f64, from_volts: f64, input: f64) -> AmplifierPath {
        let a = &self.amplifier;
        AmplifierPath {
            t0,
            from_volts,
            target_volts: input.min(a.rail_volts),
            rate_per_second: std::f64::consts::TAU * a.bandwidth_hz,
            slew_volts_per_second: a.slew_volts_per_second,
        }
    }

    /// Whether the amplifier's output is a state (finite bandwidth or slew).
    fn amplifier_has_state(&self) -> bool {
        self.amplifier.bandwidth_hz.is_finite() || self.amplifier.slew_volts_per_second.is_finite()
    }

    /// The state at rest at the pre-stretch, networks relaxed, amplifier at 0 V.
    pub fn at_rest(&self) -> Vector {
        let mut y = [0.0; STATE];
        y[0] = self.params.prestretch_1;
        for k in 0..MAX_BRANCHES {
            let at = 3 + 4 * k;
            y[at] = self.params.prestretch_1;
            y[at + 1] = self.params.prestretch_2;
            y[at + 2] = self.params.prestretch_1;
            y[at + 3] = self.params.prestretch_2;
        }
        y
    }

    /// The voltage on the membrane in state `y` with `input` volts at the amplifier's input.
    /// Membrane A's capacitance at stretch λ (λ2 held at λ2p), model.md §8 (paper eq. 1):
    /// C = ε·L1A·L2·λ²·λ2p²/H, F.
    pub fn capacitance(&self, stretch: f64) -> f64 {
        let p = &self.params;
        p.relative_permittivity
            * VACUUM_PERMITTIVITY
            * p.length_active
            * p.width
            * stretch
            * stretch
            * p.prestretch_2
            * p.prestretch_2
            / p.thickness
    }

    /// The amplifier's mean output current over an interval from (λ, Φ) at its start to
    /// (λ, Φ) at its end, `seconds` long, ending at `at_seconds`: the charge's change, dQ/dt
    /// with Q = C(λ)·Φ, plus the leakage at the mean voltage (model.md §8), A.
    pub fn mean_current_amps(
        &self,
        from: (f64, f64),
        to: (f64, f64),
        seconds: f64,
        at_seconds: f64,
    ) -> f64 {
        let charge = |(stretch, volts): (f64, f64)| self.capacitance(stretch) * volts;
        let leakage = self.leakage.ohms_at(at_seconds - 0.5 * seconds);
        (charge(to) - charge(from)) / seconds + 0.5 * (from.1 + to.1) / leakage
    }

    pub fn volts(&self, y: &Vector, input: f64) -> f64 {
        if self.amplifier_has_state() {
            y[2]
        } else {
            input.min(self.amplifier.rail_volts)
        }
    }

    /// The local stiffness −∂λ''/∂λ with the networks frozen (central difference), 1/s².
    fn stiffness(&self, y: &Vector, volts: f64) -> f64 {
        let h = 1e-6 * y[0].abs().max(1.0);
        let (mut up, mut down) = (*y, *y);
        up[0] += h;
        down[0] -= h;
        up[1] = 0.0;
        down[1] = 0.0;
        -(self.acceleration(&up, volts) - self.acceleration(&down, volts)) / (2.0 * h)
    }

    /// The natural frequency of small oscillations about state `y` (networks frozen, as they
    /// are over a period when their relaxation is slow), Hz; NaN where unstable.
    pub fn natural_frequency_hz(&self, y: &Vector, volts: f64) -> f64 {
        self.stiffness(y, volts).sqrt() / std::f64::consts::TAU
    }

    /// The six checks of model.md §6 at state `y` under `volts`, with the networks' stresses
    /// (frozen): the first that fails, if any.
    pub fn first_failure(&self, y: &Vector, volts: f64) -> Option<FailureMode> {
        let p = &self.params;
        let l = y[0];
        let lb = self.passive_stretch(l);
        let l2 = p.prestretch_2;
        let eps = self.permittivity();
        let e0 = volts / p.thickness;
        if !(lb > 0.0 && l > 0.0) {
            return Some(FailureMode::LossOfTension1);
        }
        if !(self.stiffness(y, volts) > 0.0) {
            return Some(FailureMode::DeviceInstability);
        }
        // EMI of A: the Hessian of W − ½ε·E0²·λ1²λ2² in (λ1, λ2), by differences of the
        // analytic stresses.
        let h = 1e-6;
        let s = |a: f64, b: f64| self.stresses(y, a, b, true);
        let (s1p, s2p) = s(l + h, l2);
        let (s1m, s2m) = s(l - h, l2);
        let (t1p, t2p) = s(l, l2 + h);
        let (t1m, t2m) = s(l, l2 - h);
        let e2 = eps * e0 * e0;
        let h11 = (s1p - s1m) / (2.0 * h) - e2 * l2 * l2;
        let h22 = (t2p - t2m) / (2.0 * h) - e2 * l * l;
        let h12 = 0.5 * ((t1p - t1m) / (2.0 * h) + (s2p - s2m) / (2.0 * h)) - 2.0 * e2 * l * l2;
        if !(h11 > 0.0 && h11 * h22 - h12 * h12 > 0.0) {
            return Some(FailureMode::Emi);
        }
        // §6.3 along a trajectory: B's tension in direction 1, and A's less the electrostatic
        // stress (they differ by the bars' inertia).
        let (sb1, sb2) = self.stresses(y, lb, l2, false);
        let (sa1, sa2) = self.stresses(y, l, l2, true);
        if !(sb1 > 0.0 && sa1 - eps * e0 * e0 * l * l2 * l2 > 0.0) {
            return Some(FailureMode::LossOfTension1);
        }
        let field = volts * l * l2 / p.thickness;
        if !(l2 * sa2 - eps * field * field > 0.0) {
            return Some(FailureMode::LossOfTension2a);
        }
        if !(l2 * sb2 > 0.0) {
            return Some(FailureMode::LossOfTension2b);
        }
        if !(field < p.breakdown_field) {
            return Some(FailureMode::Breakdown);
        }
        let (_, _, ia) = gent(p, l, l2);
        let (_, _, ib) = gent(p, lb, l2);
        if let Some(jlim) = p.jlim {
            if !(ia - 3.0 < jlim && ib - 3.0 < jlim) {
                return Some(FailureMode::StretchLimit);
            }
        }
        None
    }

    /// The static equilibrium under `volts` nearest state `y`, the networks frozen at their
    /// viscous stretches in `y` (Newton on λ'' = 0 from y's stretch); `None` if it fails.
    pub fn equilibrium(&self, y: &Vector, volts: f64) -> Option<Vector> {
        let mut z = *y;
        z[1] = 0.0;
        for _ in 0..100 {
            let a = self.acceleration(&z, volts);
            let k = self.stiffness(&z, volts);
            if !(k > 0.0) {
                return None;
            }
            let change = a / k;
            z[0] += change;
            if change.abs() < 1e-14 * z[0] {
                return Some(z);
            }
        }
        None
    }

    /// The voltage above `volts` at which the equilibrium (networks frozen, followed from
    /// `y`) first fails a check of §6, and the check: steps of 1% (from 1 V up), then
    /// bisection. From a state above the limit this finds nothing new: the plant's own
    /// limit is searched from 0 V (`Run`'s `limit`), so a bias past it shows a negative margin.
    pub fn limit_volts(&self, y: &Vector, volts: f64) -> Option<(FailureMode, f64)> {
        // The safe equilibrium at `v` followed from `from`, or the check that fails there.
        let check = |v: f64, from: &Vector| match self.equilibrium(from, v) {
            Some(z) => self.first_failure(&z, v).map_or(Ok(z), Err),
            None => Err(FailureMode::DeviceInstability),
        };
        let (mut low, mut at) = (volts.max(1.0), *y);
        // 1% steps from 1 V reach 10 MV within 1,700.
        for _ in 0..1700 {
            let next = low * 1.01;
            match check(next, &at) {
                Ok(z) => (low, at) = (next, z),
                Err(mut mode) => {
                    let mut high = next;
                    for _ in 0..60 {
                        let mid = 0.5 * (low + high);
                        match check(mid, &at) {
                            Ok(_) => low = mid,
                            Err(m) => (high, mode) = (mid, m),
                        }
                    }
                    return Some((mode, low));
                }
            }
        }
        None
    }
}

/// The amplifier's output over one tick (`Plant::amplifier_path`): a ramp at the slew rate
/// while (target − V)·2π·bandwidth is above it, then the exponential toward the target.
#[derive(Clone, Copy, Debug)]
struct AmplifierPath {
    t0: f64,
    from_volts: f64,
    target_volts: f64,
    /// 2π·bandwidth, 1/s (infinite: no lag but the slew).
    rate_per_second: f64,
    /// Infinite: no slew limit.
    slew_volts_per_second: f64,
}

impl AmplifierPath {
    /// When the ramp at the slew rate ends, if it does after `t0`: the output's second
    /// derivative jumps there, so a solve splits its interval at it.
    fn knee_time(&self) -> Option<f64> {
        let gap = self.target_volts - self.from_volts;
        let knee = self.slew_volts_per_second / self.rate_per_second;
        (gap.abs() > knee).then(|| self.t0 + (gap.abs() - knee) / self.slew_volts_per_second)
    }

    fn volts_at(&self, t: f64) -> f64 {
        let s = (t - self.t0).max(0.0);
        let gap = self.target_volts - self.from_volts;
        let (slew, rate) = (self.slew_volts_per_second, self.rate_per_second);
        // Below this gap the rate is under the slew limit: the exponential (0 without lag).
        let knee = slew / rate;
        let (ramp_seconds, gap_after) = if gap.abs() > knee {
            let ramp_seconds = (gap.abs() - knee) / slew;
            if s <= ramp_seconds {
                return self.from_volts + gap.signum() * slew * s;
            }
            (ramp_seconds, gap.signum() * knee)
        } else {
            (0.0, gap)
        };
        if rate.is_infinite() {
            return self.target_volts;
        }
        self.target_volts - gap_after * (-rate * (s - ramp_seconds)).exp()
    }
}

/// The plant's equations over one controller tick, with the amplifier's input held (the
/// DAC holds its code between ticks), on the first `N` states: 3 and four a branch, so that a
/// plant with fewer branches than `MAX_BRANCHES` does not integrate zeros.
pub struct Motion<'a, const N: usize> {
    pub plant: &'a Plant,
    /// The amplifier's input, V (DAC output × nothing: the gain is applied here).
    pub input_volts: f64,
    /// The amplifier's output over the tick, where it has a lag or a slew limit: in closed
    /// form, not integrated (its fast exponential would bind the solver's step).
    amplifier: Option<AmplifierPath>,
}

impl<const N: usize> ODE<f64, [f64; N]> for Motion<'_, N> {
    fn diff(&self, t: f64, short: &[f64; N], rate: &mut [f64; N]) {
        let plant = self.plant;
        let mut y = [0.0; STATE];
        y[..N].copy_from_slice(short);
        if let Some(path) = &self.amplifier {
            y[2] = path.volts_at(t);
        }
        let volts = plant.volts(&y, self.input_volts);
        let mut dydt = [0.0; STATE];
        dydt[0] = y[1];
        dydt[1] = plant.acceleration(&y, volts);
        let l2 = plant.params.prestretch_2;
        let lb = plant.passive_stretch(y[0]);
        for (k, b) in plant.branches.iter().enumerate() {
            let at = 3 + 4 * k;
            let (a1, a2) = flow(b, y[0], l2, y[at], y[at + 1]);
            let (b1, b2) = flow(b, lb, l2, y[at + 2], y[at + 3]);
            dydt[at] = a1;
            dydt[at + 1] = a2;
            dydt[at + 2] = b1;
            dydt[at + 3] = b2;
        }
        rate.copy_from_slice(&dydt[..N]);
    }
}

/// A tick solved: the state at its end, the first step the solve took after the drive's
/// jump, and where the stretch turned highest and lowest within it (time, state: the
/// extremes a check between tick ends must see; with BDF, a turn between the tick's ends).
#[derive(Clone, Copy, Debug)]
pub struct Solved {
    pub y: Vector,
    pub first_step: f64,
    pub turns: [Option<(f64, Vector)>; 2],
}

/// One tick of the plant: `y` over `[t0, t1]` with the amplifier's input held at
/// `input_volts`.
pub struct Tick<'a> {
    pub plant: &'a Plant,
    pub solver: Solver,
    pub tolerance: Tolerance,
    pub y: Vector,
    pub t0: f64,
    pub t1: f64,
    pub input_volts: f64,
    /// The last tick's first step after the drive's jump, so that a tick neither estimates
    /// its first step again nor starts too long and has it rejected (`None` at the start).
    pub first_step: Option<f64>,
}

impl Tick<'_> {
    /// The state at `t1`, the first step the solve took after the drive's jump, its turns.
    pub fn solve(self) -> Result<Solved, String> {
        let t0 = self.t0;
        match self.plant.branches.len() {
            0 => self.advance::<3>(),
            1 => self.advance::<7>(),
            2 => self.advance::<11>(),
            _ => self.advance::<STATE>(),
        }
        .map_err(|e| {
            format!(
                "the plant's integration at t = {} s: {e}",
                crate::text::sig(t0)
            )
        })
    }
}

impl Tick<'_> {
    fn advance<const N: usize>(self) -> Result<Solved, String> {
        let mut short = [0.0; N];
        short.copy_from_slice(&self.y[..N]);
        let amplifier = self.plant.amplifier_has_state().then(|| {
            self.plant
                .amplifier_path(self.t0, self.y[2], self.input_volts)
        });
        let motion = Motion::<N> {
            plant: self.plant,
            input_volts: self.input_volts,
            amplifier,
        };
        // Split at the amplifier's knee, where its output's second derivative jumps.
        let knee = amplifier
            .and_then(|path| path.knee_time())
            .filter(|&at| at > self.t0 && at < self.t1);
        // The whole state at `t` from the solved part (the amplifier's in closed form).
        let whole = |t: f64, short: &[f64; N]| {
            let mut y = self.y;
            y[..N].copy_from_slice(short);
            if let Some(path) = amplifier {
                y[2] = path.volts_at(t);
            }
            y
        };
        // A step whose ends' velocities differ in sign holds a turn: located on a quintic
        // through its ends (value, slope, and the curvature from the equations), the slow
        // states between them linear.
        let mut turns: [Option<(f64, Vector)>; 2] = [None; 2];
        let mut on_step = |(a, ya): (f64, [f64; N]), (b, yb): (f64, [f64; N])| {
            if !events::turns(ya[1], yb[1]) {
                return;
            }
            let jet = |t: f64, y: &[f64; N]| {
                let mut rate = [0.0; N];
                motion.diff(t, y, &mut rate);
                Jet {
                    t,
                    stretch: y[0],
                    velocity: y[1],
                    acceleration: rate[1],
                }
            };
            let path = Hermite::new(jet(a, &ya), jet(b, &yb));
            let at = events::turn(a, b, |t| path.at(t).1);
            let (stretch, velocity) = path.at(at);
            let w = (at - a) / (b - a);
            let mut y: [f64; N] = std::array::from_fn(|i| ya[i] + w * (yb[i] - ya[i]));
            (y[0], y[1]) = (stretch, velocity);
            // The highest turn and the lowest (however many a long tick holds): where an
            // excursion peaks.
            let turn = Some((at, whole(at, &y)));
            let [high, low] = &mut turns;
            if high.is_none_or(|(_, h)| stretch > h[0]) {
                *high = turn;
            }
            if low.is_none_or(|(_, l)| stretch < l[0]) {
                *low = turn;
            }
        };
        // The ramp at the slew rate (if any) in one step; then the rest from the last tick's
        // first step there.
        let (mut from, mut end, mut h) = (self.t0, short, f64::NAN);
        for to in knee.into_iter().chain([self.t1]) {
            let first = if to == self.t1 {
                self.first_step
            } else {
                Some(to - from)
            };
            (end, h) = self.solver.advance_watched(
                &motion,
                (from, to),
                end,
                self.tolerance,
                first,
                &mut on_step,
            )?;
            from = to;
        }
        Ok(Solved {
            y: whole(self.t1, &end),
            first_step: h,
            turns,
        })
    }
}
