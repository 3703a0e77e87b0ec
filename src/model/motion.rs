//! Dynamics (model.md §4, §7): the equation of motion under Φ(t) = Φdc + Φac·sin(Ωt), and
//! fixed-step integrators a microcontroller can afford, one step at a time, behind a guard
//! that refuses a step too large to be stable. Dimensionless time τ = t/T0 throughout.

use core::fmt;

use crate::numerics::decimal::Decimal;

use crate::model::device::Device;
use crate::numerics::real::Real;

/// The voltage Φ(τ) = Φ̄dc + Φ̄ac·sin(Ω̄τ), dimensionless (Φ̄ = (Φ/H)·√(ε/μ), Ω̄ = Ω·T0).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Drive<T> {
    pub bias: T,
    pub ac: T,
    pub omega: T,
}

impl<T: Real> Drive<T> {
    /// A drive in volts and hertz for `device`.
    pub fn from_volts(device: &Device<T>, bias_volts: T, ac_volts: T, drive_hz: T) -> Self {
        let v = device.volts_per_unit();
        Self {
            bias: bias_volts / v,
            ac: ac_volts / v,
            omega: T::of(core::f64::consts::TAU) * drive_hz / device.rad_per_s_per_unit(),
        }
    }

    /// A constant voltage.
    pub fn constant(device: &Device<T>, volts: T) -> Self {
        Self::from_volts(device, volts, T::zero(), T::zero())
    }

    /// Φ̄² at dimensionless time τ.
    pub fn bias_dimless_squared_at(&self, tau: T) -> T {
        self.bias_dimless_squared_at_angle(self.omega * tau)
    }

    /// Φ̄² where the AC phase Ω̄τ is `angle`.
    pub fn bias_dimless_squared_at_angle(&self, angle: T) -> T {
        (self.bias + self.ac * angle.sin()).squared()
    }

    /// All three numbers finite.
    pub fn is_finite(&self) -> bool {
        self.bias.is_finite() && self.ac.is_finite() && self.omega.is_finite()
    }

    /// The AC phase advance over a dimensionless time `dtau`, in units of 2π/2⁶⁴ (wrapping).
    fn phase_step(&self, dtau: T) -> u64 {
        let turns = self.omega.to_f64() * dtau.to_f64() / core::f64::consts::TAU;
        let fraction = turns - libm::floor(turns);
        (fraction * 18_446_744_073_709_551_616.0) as u64
    }

    /// The least Φ̄² the drive reaches (where the stiffness is largest).
    pub fn least_bias_dimless_squared(&self) -> T {
        let gap = self.bias.abs() - self.ac.abs();
        if gap > T::zero() {
            gap.squared()
        } else {
            T::zero()
        }
    }
}

/// Stretch and its rate dλ/dτ.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct State<T> {
    pub stretch: T,
    /// dλ/dτ; dλ/dt = velocity·(1/T0).
    pub velocity: T,
}

impl<T: Real> Device<T> {
    /// The elastic and electric part of λ'' (model.md §4, dimensionless):
    /// s̄1(λB) − s̄1(λ) + Φ̄²·λ·λ2p².
    pub fn restoring_acceleration(&self, stretch: T, bias_dimless_squared: T) -> T {
        let m = self.material();
        let l2p = self.prestretch_2();
        m.stress_1(self.passive_stretch(stretch), l2p) - m.stress_1(stretch, l2p)
            + bias_dimless_squared * stretch * l2p * l2p
    }

    /// λ'' = restoring − c̄·λ' (model.md §4, dimensionless).
    pub fn acceleration(&self, state: State<T>, bias_dimless_squared: T) -> T {
        self.restoring_acceleration(state.stretch, bias_dimless_squared)
            - self.damping_dimless() * state.velocity
    }
}

/// A fixed-step method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Method {
    /// Classical fourth-order Runge–Kutta: four force evaluations a step.
    Rk4,
    /// Velocity Verlet (second order, symplectic when undamped; damping taken implicitly).
    Verlet,
    /// Implicit midpoint (second order, A-stable), Newton on the velocity increment.
    ImplicitMidpoint,
}

impl Method {
    pub const ALL: [Method; 3] = [Method::Rk4, Method::Verlet, Method::ImplicitMidpoint];

    /// The method's name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Method::Rk4 => "rk4",
            Method::Verlet => "verlet",
            Method::ImplicitMidpoint => "implicit-midpoint",
        }
    }

    /// The largest stable h·ω for an undamped oscillator of angular frequency ω (RK4 reaches
    /// 2√2 on the imaginary axis; 2.8 keeps a little room). `None`: stable for any step.
    pub fn stability_limit(self) -> Option<f64> {
        self.stability_radius(false)
    }

    /// The largest stable |h·μ| for the eigenvalues μ of a damped oscillator, which lie in
    /// the left half-plane off the imaginary axis. RK4's region there is not a disk: it
    /// reaches 2√2 at 90°, 2.785 at 180°, and only 2.62 near 122°, so a damped device is
    /// held to 2.6. Verlet takes its damping implicitly (stable for any c ≥ 0), so only
    /// the undamped ω counts for it.
    pub fn stability_radius(self, damped: bool) -> Option<f64> {
        match self {
            Method::Rk4 if damped => Some(2.6),
            Method::Rk4 => Some(2.8),
            Method::Verlet => Some(2.0),
            Method::ImplicitMidpoint => None,
        }
    }
}

/// Why the integrator will not take, or could not finish, a step.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StepError<T> {
    /// The step is NaN, infinite or not positive.
    InvalidStep { step_seconds: T },
    /// The drive's bias, AC amplitude or frequency is NaN or infinite.
    InvalidDrive { drive: Drive<T> },
    /// The stretch range to guard is empty, NaN, or leaves a membrane at zero stretch.
    InvalidRange { low: T, high: T },
    /// Too large a step for the method at the stiffest state of the guarded range.
    Unstable {
        method: Method,
        step_seconds: T,
        max_step_seconds: T,
    },
    /// The state left the stretch range the guard was sized for.
    LeftGuardedRange { tick: u64, stretch: T },
    /// The implicit method's Newton iteration did not converge.
    NewtonFailed { tick: u64 },
    /// The state became NaN or infinite.
    NonFinite { tick: u64 },
    /// A new drive reaches below the least Φ̄² the step was guarded for (stiffer states).
    DriveNotGuarded {
        least_bias_dimless_squared: T,
        guarded_bias_dimless_squared: T,
    },
}

impl<T: Real> core::error::Error for StepError<T> {}

impl<T: Real> fmt::Display for StepError<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            StepError::InvalidStep { step_seconds } => {
                write!(
                    f,
                    "step {} s is not a finite positive number",
                    Decimal(step_seconds)
                )
            }
            StepError::InvalidDrive { drive } => write!(
                f,
                "drive (bias {}, AC {}, Ω̄ {}) is not finite",
                Decimal(drive.bias),
                Decimal(drive.ac),
                Decimal(drive.omega)
            ),
            StepError::InvalidRange { low, high } => write!(
                f,
                "stretch range [{}, {}] is not a valid range of positive stretches",
                Decimal(low),
                Decimal(high)
            ),
            StepError::Unstable {
                method,
                step_seconds,
                max_step_seconds,
            } => write!(
                f,
                "step {} s is unstable for {}: the stiffest reachable state allows at most {} s",
                Decimal(step_seconds),
                method.name(),
                Decimal(max_step_seconds)
            ),
            StepError::LeftGuardedRange { tick, stretch } => write!(
                f,
                "stretch {} at tick {} left the range the step was checked for",
                Decimal(stretch),
                tick
            ),
            StepError::NewtonFailed { tick } => {
                write!(f, "implicit step did not converge at tick {tick}")
            }
            StepError::DriveNotGuarded {
                least_bias_dimless_squared,
                guarded_bias_dimless_squared,
            } => write!(
                f,
                "new drive reaches Φ̄² = {}, below the {} the step was checked for",
                Decimal(least_bias_dimless_squared),
                Decimal(guarded_bias_dimless_squared)
            ),
            StepError::NonFinite { tick } => {
                write!(f, "state became NaN or infinite at tick {tick}")
            }
        }
    }
}

/// Most substeps a subdivided step may take.
pub const MAX_SUBSTEPS: u32 = 1 << 16;

/// Newton iterations of the implicit midpoint step before it gives up.
const NEWTON_ITERATIONS: usize = 40;

/// Halvings of a Newton step while the residual does not fall.
const LINE_SEARCH_HALVINGS: usize = 20;

/// Points at which the guard samples the stiffness across the stretch range.
const GUARD_POINTS: usize = 64;

/// Integrates one device under one drive with one method and a fixed step.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Integrator<T> {
    device: Device<T>,
    drive: Drive<T>,
    method: Method,
    /// Dimensionless step of one substep.
    substep: T,
    substeps: u32,
    step_seconds: T,
    range: (T, T),
    /// The least Φ̄² the step was checked at (the stiffest); a new drive must not go below.
    guarded_bias_dimless_squared: T,
    tick: u64,
    /// The AC phase at the start of the next step and its advance per half substep, in
    /// units of 2π/2⁶⁴: an exact wrapping count, so the phase neither drifts nor loses
    /// precision over long runs, and costs no float work per step.
    phase: u64,
    phase_per_half_substep: u64,
    state: State<T>,
}

/// The largest stable step in seconds for `method` on `device` under `drive`, while the
/// stretch stays in `range`. Linearised about each stretch, λ'' = −k·δλ − c̄·λ' has the
/// eigenvalues μ = (−c̄ ± √(c̄² − 4k))/2 (model.md §4, dimensionless), k = −∂λ''/∂λ the
/// local stiffness. k is largest at the least Φ̄² the drive reaches, and √k bounds |μ| when
/// underdamped; overdamped, the fast root grows as k falls (a higher bias, later drives of
/// a plan), up to c̄ at k = 0: the bound takes c̄ itself, so the damping term h·c/M holds at
/// every bias. Past the device's stability (k < 0) the decaying root at the sampled k is
/// taken. The step keeps h·|μ| inside the method's region. `None`: any step is stable.
pub fn max_stable_step_seconds<T: Real>(
    device: &Device<T>,
    drive: &Drive<T>,
    method: Method,
    range: (T, T),
) -> Option<T> {
    let c = device.damping_dimless();
    // Verlet's damping is implicit: only the undamped ω bounds its step.
    let c = if method == Method::Verlet {
        T::zero()
    } else {
        c
    };
    let limit = T::of(method.stability_radius(c > T::zero())?);
    let p2 = drive.least_bias_dimless_squared();
    let mut fastest = c;
    for i in 0..=GUARD_POINTS {
        let l = range.0 + (range.1 - range.0) * T::of(i as f64) / T::of(GUARD_POINTS as f64);
        let k = device.stiffness_dimless(l, p2);
        // NaN stiffness (outside the model) counts as infinitely stiff.
        fastest = if k.is_finite() {
            fastest.max(fastest_rate(k, c))
        } else {
            T::of(f64::INFINITY)
        };
    }
    Some(limit / (fastest * device.rad_per_s_per_unit()))
}

/// The largest |μ| of μ² + c̄·μ + k = 0: √k when underdamped, (c̄ + √(c̄² − 4k))/2 when
/// not (k < 0, past the device's stability, gives one growing root: the physics', not the
/// method's; the decaying one still bounds the step).
fn fastest_rate<T: Real>(k: T, c: T) -> T {
    let disc = c * c - T::of(4.0) * k;
    if disc < T::zero() {
        k.sqrt()
    } else {
        (c + disc.sqrt()) * T::of(0.5)
    }
}

impl<T: Real> Integrator<T> {
    /// Set up an integration from `start` with steps of `step_seconds`, guarded for
    /// stretches in `range`. A step too large for stability is refused, or, with
    /// `subdivide`, split into the fewest equal substeps that are stable.
    pub fn new(
        device: Device<T>,
        drive: Drive<T>,
        method: Method,
        step_seconds: T,
        range: (T, T),
        start: State<T>,
        subdivide: bool,
    ) -> Result<Self, StepError<T>> {
        if !(step_seconds.is_finite() && step_seconds > T::zero()) {
            return Err(StepError::InvalidStep { step_seconds });
        }
        if !drive.is_finite() {
            return Err(StepError::InvalidDrive { drive });
        }
        let lowest_b = device.passive_stretch(range.1);
        if !(range.0 > T::zero()
            && range.1 >= range.0
            && range.1.is_finite()
            && lowest_b > T::zero())
        {
            return Err(StepError::InvalidRange {
                low: range.0,
                high: range.1,
            });
        }
        let mut substeps = 1u32;
        if let Some(max_step) = max_stable_step_seconds(&device, &drive, method, range) {
            if !(step_seconds < max_step) {
                let needed = step_seconds / max_step;
                if !subdivide || !(needed < T::of(f64::from(MAX_SUBSTEPS))) {
                    return Err(StepError::Unstable {
                        method,
                        step_seconds,
                        max_step_seconds: max_step,
                    });
                }
                // The fewest equal substeps each below the limit (the loop only mends
                // rounding of the estimate).
                substeps = needed.to_f64() as u32 + 1;
                while !(step_seconds / T::of(f64::from(substeps)) < max_step) {
                    substeps += 1;
                }
            }
        }
        let step = step_seconds * device.rad_per_s_per_unit();
        let substep = step / T::of(f64::from(substeps));
        Ok(Self {
            device,
            drive,
            method,
            substep,
            substeps,
            step_seconds,
            range,
            guarded_bias_dimless_squared: drive.least_bias_dimless_squared(),
            tick: 0,
            phase: 0,
            phase_per_half_substep: drive.phase_step(substep * T::of(0.5)),
            state: start,
        })
    }

    /// Change the drive from the next step on (a bias ramp, the AC switched on), keeping
    /// state, time and the AC phase (it runs on continuously, at the new frequency).
    /// Refused if it reaches a lower Φ̄² than the step was checked for.
    pub fn set_drive(&mut self, drive: Drive<T>) -> Result<(), StepError<T>> {
        if !drive.is_finite() {
            return Err(StepError::InvalidDrive { drive });
        }
        let least = drive.least_bias_dimless_squared();
        if !(least >= self.guarded_bias_dimless_squared) {
            return Err(StepError::DriveNotGuarded {
                least_bias_dimless_squared: least,
                guarded_bias_dimless_squared: self.guarded_bias_dimless_squared,
            });
        }
        if drive.omega != self.drive.omega {
            self.phase_per_half_substep = drive.phase_step(self.substep * T::of(0.5));
        }
        self.drive = drive;
        Ok(())
    }

    pub fn state(&self) -> State<T> {
        self.state
    }

    /// Steps taken so far.
    pub fn tick(&self) -> u64 {
        self.tick
    }

    /// Substeps per step (1 unless the step was subdivided).
    pub fn substeps(&self) -> u32 {
        self.substeps
    }

    /// t = tick·h, s.
    pub fn time_seconds(&self) -> T {
        T::of(self.tick as f64) * self.step_seconds
    }

    pub fn device(&self) -> &Device<T> {
        &self.device
    }

    pub fn drive(&self) -> &Drive<T> {
        &self.drive
    }

    /// Φ̄² now (at t = tick·h), for the monitor.
    pub fn bias_dimless_squared(&self) -> T {
        self.bias_dimless_squared_at_phase(self.phase)
    }

    fn bias_dimless_squared_at_phase(&self, phase: u64) -> T {
        self.drive
            .bias_dimless_squared_at_angle(T::angle_of_phase(phase))
    }

    /// Advance one step. On error the state and the phase stay at the last good ones.
    pub fn step(&mut self) -> Result<State<T>, StepError<T>> {
        let mut s = self.state;
        let mut phase = self.phase;
        let half = self.phase_per_half_substep;
        for _ in 0..self.substeps {
            s = match self.method {
                Method::Rk4 => self.rk4(s, phase),
                Method::Verlet => self.verlet(s, phase),
                Method::ImplicitMidpoint => self.implicit_midpoint(s, phase)?,
            };
            phase = phase.wrapping_add(half).wrapping_add(half);
        }
        let tick = self.tick + 1;
        if !(s.stretch.is_finite() && s.velocity.is_finite()) {
            return Err(StepError::NonFinite { tick });
        }
        if !(s.stretch >= self.range.0 && s.stretch <= self.range.1) {
            return Err(StepError::LeftGuardedRange {
                tick,
                stretch: s.stretch,
            });
        }
        self.state = s;
        self.tick = tick;
        self.phase = phase;
        Ok(s)
    }

    /// One RK4 substep from AC phase `phase`.
    fn rk4(&self, s: State<T>, phase: u64) -> State<T> {
        let h = self.substep;
        let half = h * T::of(0.5);
        let at = |s: State<T>, dl: T, dv: T, k: T| State {
            stretch: s.stretch + k * dl,
            velocity: s.velocity + k * dv,
        };
        // The drive at the step's start, middle and end: three sines, not four.
        let p2 = |p| self.bias_dimless_squared_at_phase(p);
        let mid_phase = phase.wrapping_add(self.phase_per_half_substep);
        let end_phase = mid_phase.wrapping_add(self.phase_per_half_substep);
        let (start, middle, end) = (p2(phase), p2(mid_phase), p2(end_phase));
        let a = |s| self.device.acceleration(s, start);
        let (l1, v1) = (s.velocity, a(s));
        let s2 = at(s, l1, v1, half);
        let (l2, v2) = (s2.velocity, self.device.acceleration(s2, middle));
        let s3 = at(s, l2, v2, half);
        let (l3, v3) = (s3.velocity, self.device.acceleration(s3, middle));
        let s4 = at(s, l3, v3, h);
        let (l4, v4) = (s4.velocity, self.device.acceleration(s4, end));
        let two = T::of(2.0);
        let sixth = h / T::of(6.0);
        State {
            stretch: s.stretch + sixth * (l1 + two * (l2 + l3) + l4),
            velocity: s.velocity + sixth * (v1 + two * (v2 + v3) + v4),
        }
    }

    /// One velocity Verlet substep from AC phase `phase`.
    fn verlet(&self, s: State<T>, phase: u64) -> State<T> {
        let h = self.substep;
        let half = h * T::of(0.5);
        let d = &self.device;
        let c = d.damping_dimless();
        let force = |l, p| d.restoring_acceleration(l, self.bias_dimless_squared_at_phase(p));
        let end_phase = phase
            .wrapping_add(self.phase_per_half_substep)
            .wrapping_add(self.phase_per_half_substep);
        let v_half = s.velocity + half * (force(s.stretch, phase) - c * s.velocity);
        let stretch = s.stretch + h * v_half;
        // Damping at the end of the step taken implicitly: stable for any c ≥ 0.
        let velocity = (v_half + half * force(stretch, end_phase)) / (T::one() + half * c);
        State { stretch, velocity }
    }

    /// y₁ = y₀ + h·f((y₀ + y₁)/2): solved for the velocity increment Δv, with
    /// λ₁ = λ₀ + h·(v₀ + Δv/2), by Newton on G(Δv) = Δv − h·a(λ_mid, v_mid).
    fn implicit_midpoint(&self, s: State<T>, phase: u64) -> Result<State<T>, StepError<T>> {
        let h = self.substep;
        let half = h * T::of(0.5);
        let d = &self.device;
        let c = d.damping_dimless();
        let p2 =
            self.bias_dimless_squared_at_phase(phase.wrapping_add(self.phase_per_half_substep));
        let mid = |dv: T| State {
            stretch: s.stretch + half * (s.velocity + dv * T::of(0.5)),
            velocity: s.velocity + dv * T::of(0.5),
        };
        let residual = |dv: T| dv - h * d.acceleration(mid(dv), p2);
        let mut dv = h * d.acceleration(s, p2);
        let mut g = residual(dv);
        for _ in 0..NEWTON_ITERATIONS {
            // G' = 1 + h·(k·h/4 + c/2), k = −∂a/∂λ the local stiffness.
            let k = d.stiffness_dimless(mid(dv).stretch, p2);
            let slope = T::one() + h * (k * h * T::of(0.25) + c * T::of(0.5));
            if !(slope > T::zero()) {
                break;
            }
            // Newton step, halved until |G| falls (a large step on a stiff, curved force
            // overshoots otherwise).
            let mut change = g / slope;
            let mut next = residual(dv - change);
            for _ in 0..LINE_SEARCH_HALVINGS {
                if next.abs() < g.abs() {
                    break;
                }
                change = change * T::of(0.5);
                next = residual(dv - change);
            }
            dv = dv - change;
            g = next;
            // Accelerations are O(1) in these units, so h is the least scale of Δv.
            let scale = dv.abs().max(s.velocity.abs()).max(h);
            if change.abs() <= T::of(16.0) * T::EPSILON * scale || g == T::zero() {
                return Ok(State {
                    stretch: s.stretch + h * (s.velocity + dv * T::of(0.5)),
                    velocity: s.velocity + dv,
                });
            }
        }
        Err(StepError::NewtonFailed {
            tick: self.tick + 1,
        })
    }
}
