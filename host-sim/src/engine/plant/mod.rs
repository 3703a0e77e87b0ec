//! The plant: the resonator as it is, not as the controller is told it is. model.md §§2–6
//! written out again in SI units and f64, with the extras of §8 a scene switches on: viscous
//! damping, viscoelastic networks (Zhao–Koh–Suo, several branches), and the amplifier's
//! bandwidth, slew limit and rail. Its safety checks (§6, with the networks' stresses) are
//! the truth host-sim holds the controller to.

use de_resonator::{DeviceParams, FailureMode};

use crate::engine::lift::{Lift, Local};

mod tick;
pub use tick::{Motion, Solved, Tick};

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
    gent_of(p.shear_modulus, inverse_jlim(p), l1, l2)
}

/// 1/Jlim, 0 for neo-Hookean.
fn inverse_jlim(p: &DeviceParams<f64>) -> f64 {
    p.jlim.map_or(0.0, |jlim| 1.0 / jlim)
}

/// [`gent`] of shear modulus `mu` and 1/Jlim `inverse_jlim`.
#[inline]
fn gent_of(mu: f64, inverse_jlim: f64, l1: f64, l2: f64) -> (f64, f64, f64) {
    let (a, b) = (l1 * l1, l2 * l2);
    let q = a * b;
    let big_d = q * (1.0 - (a + b - 3.0) * inverse_jlim) - inverse_jlim;
    let i1 = a + b + 1.0 / q;
    if !(big_d > 0.0) {
        return (f64::NAN, f64::NAN, i1);
    }
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

    /// The constants of λ'' (model.md §4): worked out once a tick, not at every right-hand
    /// side.
    fn dynamics(&self) -> Dynamics {
        let p = &self.params;
        let per_mass = 1.0 / self.mass();
        let l1 = p.length_active + p.length_passive;
        Dynamics {
            shear_modulus: p.shear_modulus,
            inverse_jlim: inverse_jlim(p),
            prestretch_2: p.prestretch_2,
            passive_offset: l1 * p.prestretch_1 / p.length_passive,
            passive_slope: p.length_active / p.length_passive,
            force_per_stress: p.width * p.thickness * per_mass,
            electric_gain: p.width * self.permittivity() * p.prestretch_2 * p.prestretch_2
                / p.thickness
                * per_mass,
            damping_rate: p.damping * per_mass,
        }
    }

    /// The fast part of the stretch over the amplifier's exponential `path` with gap `gap`
    /// (V = T − g·e^(−rσ)), for a solve from state `y` at the exponential's start, the
    /// plant's constants `dynamics`; `acceleration`: λ'' there (under the output `y[2]`), if
    /// known.
    fn lift(
        &self,
        dynamics: &Dynamics,
        y: &Vector,
        path: &AmplifierPath,
        gap: f64,
        acceleration: Option<f64>,
    ) -> Option<Lift> {
        let (rate, target) = (path.rate_per_second, path.target_volts);
        // λ'' is linear in V² (model.md §4): under the target, β·λ·(T² − V²) more.
        let under_target = acceleration
            .map(|a| a + dynamics.electric_gain * y[0] * (target * target - y[2] * y[2]));
        let local = dynamics.local(&self.branches, y, target, under_target);
        Lift::new(rate, target, gap, dynamics.electric_gain, &local)
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

    /// The natural frequency of small oscillations about state `y` (networks frozen, as they
    /// are over a period when their relaxation is slow), Hz; NaN where unstable.
    pub fn natural_frequency_hz(&self, y: &Vector, volts: f64) -> f64 {
        let stiffness = self.dynamics().stiffness(&self.branches, y, volts);
        stiffness.sqrt() / std::f64::consts::TAU
    }

    /// The six checks of model.md §6 at state `y` under `volts`, with the networks' stresses
    /// (frozen): the first that fails, if any.
    pub fn first_failure(&self, y: &Vector, volts: f64) -> Option<FailureMode> {
        let p = &self.params;
        let dynamics = self.dynamics();
        let l = y[0];
        let lb = dynamics.passive_stretch(l);
        let l2 = p.prestretch_2;
        let eps = self.permittivity();
        let e0 = volts / p.thickness;
        if !(lb > 0.0 && l > 0.0) {
            return Some(FailureMode::LossOfTension1);
        }
        if !(dynamics.stiffness(&self.branches, y, volts) > 0.0) {
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
        let (dynamics, branches) = (self.dynamics(), &self.branches);
        let mut z = *y;
        z[1] = 0.0;
        for _ in 0..100 {
            let a = dynamics.acceleration(branches, &z, volts);
            let k = dynamics.stiffness(branches, &z, volts);
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

/// The constants of the plant's λ'' (model.md §4 with the networks): M·λ'' =
/// W·H·(sB − sA) + ε·W·λ2p²·V²·λ/H − c·λ', divided through by M here once.
#[derive(Clone, Copy, Debug)]
struct Dynamics {
    shear_modulus: f64,
    inverse_jlim: f64,
    prestretch_2: f64,
    /// λB = offset − slope·λ (model.md §2): L1·λ1p/L1B and L1A/L1B.
    passive_offset: f64,
    passive_slope: f64,
    /// W·H/M, m²/kg.
    force_per_stress: f64,
    /// β = ε·W·λ2p²/(H·M) of the electrostatic term β·λ·V², 1/(s²·V²).
    electric_gain: f64,
    /// γ = c/M, 1/s.
    damping_rate: f64,
}

impl Dynamics {
    /// λB from λ (model.md §2).
    fn passive_stretch(&self, stretch: f64) -> f64 {
        self.passive_offset - self.passive_slope * stretch
    }

    /// s1 of membrane A (`active`) or B at λ1 = `l1` (λ2 = λ2p), the networks at `y`'s
    /// viscous stretches.
    #[inline]
    fn stress_1(&self, branches: &[Branch], y: &Vector, l1: f64, active: bool) -> f64 {
        let l2 = self.prestretch_2;
        let (mut s1, _, _) = gent_of(self.shear_modulus, self.inverse_jlim, l1, l2);
        for (k, b) in branches.iter().enumerate() {
            let at = 3 + 4 * k + if active { 0 } else { 2 };
            s1 += network(b.modulus, l1, l2, y[at], y[at + 1]).0;
        }
        s1
    }

    /// The local stiffness −∂λ''/∂λ with the networks frozen (central difference), 1/s².
    fn stiffness(&self, branches: &[Branch], y: &Vector, volts: f64) -> f64 {
        let h = 1e-6 * y[0].abs().max(1.0);
        let (mut up, mut down) = (*y, *y);
        up[0] += h;
        down[0] -= h;
        up[1] = 0.0;
        down[1] = 0.0;
        -(self.acceleration(branches, &up, volts) - self.acceleration(branches, &down, volts))
            / (2.0 * h)
    }

    /// The membrane about state `y` under `volts` held: λ, λ', λ'' (`acceleration`, if
    /// known) and its stiffness (networks frozen), for [`Lift`]. The stiffness is one-sided
    /// from λ'': it sets how well η fits (the solver's steps), not the solve's accuracy.
    fn local(
        &self,
        branches: &[Branch],
        y: &Vector,
        volts: f64,
        acceleration: Option<f64>,
    ) -> Local {
        let acceleration = acceleration.unwrap_or_else(|| self.acceleration(branches, y, volts));
        let h = 1e-6 * y[0].abs().max(1.0);
        let mut up = *y;
        up[0] += h;
        let stiffness = -(self.acceleration(branches, &up, volts) - acceleration) / h;
        Local {
            taylor: [y[0], y[1], acceleration],
            stiffness,
            damping: self.damping_rate,
        }
    }

    /// λ'' at state `y` under `volts` on A (model.md §4 with the networks), 1/s².
    #[inline]
    fn acceleration(&self, branches: &[Branch], y: &Vector, volts: f64) -> f64 {
        let (l, v) = (y[0], y[1]);
        let sa = self.stress_1(branches, y, l, true);
        let sb = self.stress_1(branches, y, self.passive_stretch(l), false);
        self.force_per_stress * (sb - sa) + self.electric_gain * l * volts * volts
            - self.damping_rate * v
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
    /// The exponential's start (after the ramp, if any) and its gap g: V = T − g·e^(−r(t − start)).
    fn exponential(&self) -> (f64, f64) {
        let gap = self.target_volts - self.from_volts;
        let knee = self.slew_volts_per_second / self.rate_per_second;
        match self.knee_time() {
            Some(at) => (at, gap.signum() * knee),
            None => (self.t0, gap),
        }
    }

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::solver::{Solver, Tolerance};
    use de_resonator::REFERENCE_DEVICE;
    use differential_equations::prelude::*;

    /// The plant with its amplifier as a state (dV/dt = (T − V)·2π·bandwidth within ± the
    /// slew rate), nothing in closed form: a second formulation of a tick, for the library's
    /// DOP853 at a tighter tolerance.
    struct Whole<'a> {
        plant: &'a Plant,
        target_volts: f64,
    }

    impl ODE<f64, [f64; 3]> for Whole<'_> {
        fn diff(&self, _: f64, y: &[f64; 3], rate: &mut [f64; 3]) {
            let a = &self.plant.amplifier;
            let mut full = self.plant.at_rest();
            full[..3].copy_from_slice(y);
            let slope = (self.target_volts - y[2]) * std::f64::consts::TAU * a.bandwidth_hz;
            rate[0] = y[1];
            rate[1] = self
                .plant
                .dynamics()
                .acceleration(&self.plant.branches, &full, y[2]);
            rate[2] = slope.clamp(-a.slew_volts_per_second, a.slew_volts_per_second);
        }
    }

    /// The ticks as a scene solves them (the amplifier's ramp and exponential in closed form,
    /// the exponential's fast response lifted out: `engine::lift`) at the scenes' 1e-10,
    /// against the amplifier integrated as a state by the library's DOP853 at 1e-13: on three
    /// devices, a step to 70% of the plant's own limit (a ramp at the slew rate over tens of
    /// ticks) then 2% of it as AC near resonance (DAC steps with and without a ramp), 400
    /// ticks at 1 kHz. The stretch, and its rate and the voltage as fractions of their
    /// largest, agree to 2e-9 at the ticks' ends, the stretch at the turns they found too, the
    /// rate there (near zero) to 1e-6; Radau's to 1e-8 (its turns' rate 1e-6); BDF's, to 1e-6.
    #[test]
    fn lifted_ticks_agree_with_the_amplifier_integrated_as_a_state() {
        let devices = [
            REFERENCE_DEVICE,
            DeviceParams {
                thickness: 0.5e-3,
                bar_mass: 5.0e-3,
                prestretch_1: 2.5,
                ..REFERENCE_DEVICE
            },
            DeviceParams {
                jlim: None,
                shear_modulus: 80.0e3,
                length_passive: 35.0e-3,
                ..REFERENCE_DEVICE
            },
        ];
        // The scenes' DOP853; Radau (the stiff plants' solver); BDF (looser) where built in.
        // The turn's rate is the quintic's through a step a tick long: near zero, to 1e-6.
        let mut solvers = vec![
            (Solver::Dop853, [2e-9, 2e-9, 2e-9, 2e-9, 1e-6]),
            (Solver::Radau, [1e-8, 1e-8, 1e-8, 1e-8, 1e-6]),
        ];
        if cfg!(feature = "bdf") {
            solvers.push((Solver::Bdf, [1e-6; 5]));
        }
        for (solver, within) in solvers {
            for params in devices {
                let worst = against_the_state_solve(params, solver);
                assert!(
                    worst.iter().zip(within).all(|(w, within)| *w < within),
                    "{solver:?} {params:?}: worst stretch, rate, volts, turns' stretch, turns' \
                     rate {worst:?}"
                );
            }
        }
    }

    /// The reference scene's amplifier (`scenes/reference.toml`): gain 4000, 2 kHz, 0.2 V/µs.
    const LAGGING: AmplifierModel = AmplifierModel {
        gain: 4000.0,
        bandwidth_hz: 2000.0,
        slew_volts_per_second: 200_000.0,
        rail_volts: f64::INFINITY,
    };

    /// The worst differences of `solver`'s lifted ticks from the state solve (the stretch, and
    /// the rate and the volts as fractions of their largest), at the ticks' ends and at the
    /// turns the ticks found (the state solve run to each turn's time).
    fn against_the_state_solve(params: DeviceParams<f64>, solver: Solver) -> [f64; 5] {
        let mut plant = Plant {
            params,
            branches: Vec::new(),
            amplifier: LAGGING,
            leakage: Leakage::NONE,
        };
        let rest = plant.at_rest();
        let (_, limit) = plant.limit_volts(&rest, 1.0).expect("a limit");
        let bias = 0.7 * limit;
        let hz = 0.9 * plant.natural_frequency_hz(&plant.equilibrium(&rest, bias).unwrap(), bias);
        // Q = 200 at that frequency: c = M·ω/Q.
        plant.params.damping = plant.mass() * std::f64::consts::TAU * hz / 200.0;
        let exact = Tolerance::both(1e-13);
        let (mut lifted, mut whole) = (rest, [rest[0], rest[1], rest[2]]);
        let (mut first_step, mut rate, mut worst, mut fastest) = (None, None, [0.0f64; 5], 0.0f64);
        let mut turns = 0;
        for k in 0..400 {
            let (t0, t1) = (k as f64 * 1e-3, (k + 1) as f64 * 1e-3);
            let ac = 0.02 * limit * (std::f64::consts::TAU * hz * t0).sin();
            let input = if k < 100 { bias } else { bias + ac };
            let tick = Tick {
                plant: &plant,
                solver,
                tolerance: Tolerance::both(1e-10),
                y: lifted,
                t0,
                t1,
                input_volts: input,
                first_step,
                rate,
            };
            let solved = tick.solve().expect("solves");
            (lifted, first_step, rate) = (solved.y, Some(solved.first_step), solved.rate);
            let ode = Whole {
                plant: &plant,
                target_volts: input,
            };
            for (at, y) in solved.turns.iter().flatten() {
                let there = if *at > t0 {
                    Solver::Dop853
                        .advance(&ode, t0, *at, whole, exact, None)
                        .expect("solves")
                        .0
                } else {
                    whole
                };
                turns += 1;
                worst[3] = worst[3].max((y[0] - there[0]).abs());
                worst[4] = worst[4].max((y[1] - there[1]).abs());
            }
            (whole, _) = Solver::Dop853
                .advance(&ode, t0, t1, whole, exact, None)
                .expect("solves");
            fastest = fastest.max(whole[1].abs());
            for (i, worst) in worst.iter_mut().take(3).enumerate() {
                *worst = worst.max((lifted[i] - whole[i]).abs());
            }
        }
        assert!(turns > 20, "{turns} turns");
        worst[1] /= fastest;
        worst[2] /= limit;
        worst[4] /= fastest;
        worst
    }

    /// The end derivative a tick carries into the next (`Solved::rate`, the next solve's
    /// first stage) with one, two and three viscoelastic branches behind a lagging amplifier:
    /// the ticks carrying it end where ticks that evaluate their first stage afresh do, to
    /// the solve's tolerance (a rate on the wrong states, or stale, would move each step's
    /// result by its first stage's weight, about h/20 times its error).
    #[test]
    fn a_carried_rate_leaves_the_ticks_with_branches_where_they_were() {
        let branches = [
            Branch {
                modulus: 45e3,
                relaxation_seconds: 2e-2,
            },
            Branch {
                modulus: 20e3,
                relaxation_seconds: 3e-3,
            },
            Branch {
                modulus: 10e3,
                relaxation_seconds: 0.2,
            },
        ];
        for count in 1..=branches.len() {
            let mut plant = Plant {
                params: REFERENCE_DEVICE,
                branches: branches[..count].to_vec(),
                amplifier: LAGGING,
                leakage: Leakage::NONE,
            };
            plant.params.damping = 0.05;
            let rest = plant.at_rest();
            let (_, limit) = plant.limit_volts(&rest, 1.0).expect("a limit");
            let (mut carried, mut fresh) = ((rest, None, None), (rest, None));
            let (mut worst, mut carries) = (0.0f64, 0);
            for k in 0..300 {
                let (t0, t1) = (k as f64 * 1e-3, (k + 1) as f64 * 1e-3);
                let ac = 0.02 * limit * (std::f64::consts::TAU * 40.0 * t0).sin();
                let input_volts = if k < 60 {
                    0.6 * limit
                } else {
                    0.6 * limit + ac
                };
                let tick = |y, first_step, rate| Tick {
                    plant: &plant,
                    solver: Solver::Dop853,
                    tolerance: Tolerance::both(1e-10),
                    y,
                    t0,
                    t1,
                    input_volts,
                    first_step,
                    rate,
                };
                let solved = tick(carried.0, carried.1, carried.2)
                    .solve()
                    .expect("solves");
                carries += usize::from(carried.2.is_some());
                carried = (solved.y, Some(solved.first_step), solved.rate);
                let solved = tick(fresh.0, fresh.1, None).solve().expect("solves");
                fresh = (solved.y, Some(solved.first_step));
                for (a, b) in carried.0.iter().zip(&fresh.0) {
                    worst = worst.max((a - b).abs() / b.abs().max(1.0));
                }
            }
            assert!(carries > 250, "{count} branches: carried {carries} times");
            assert!(worst < 1e-8, "{count} branches: {worst}");
        }
    }
}
