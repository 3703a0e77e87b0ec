//! Resonance tracking while driving: a lock-in on the stretch at the drive's frequency.
//!
//! Over each drive cycle the stretch is fitted as m + A·sin θ + B·cos θ (θ the drive's
//! phase at the sample). Near the equilibrium the membrane is the linear resonator
//! λ'' + (ω0/Q)·λ' + ω0²·λ = F·sin Ωt (model.md §5; F from the bias times the AC in the
//! Φ² term of §4), so its response Z = A + jB obeys F/Z = ω0² − Ω² + j·Ω·ω0/Q: one cycle
//! gives the natural frequency and Q. The drive moves toward the estimate each cycle (a
//! phase-locked loop): its fixed point is the phase quadrature (A = 0, Ω = ω0 whatever the
//! damping), where an error in the model's F drops out.

use core::f32::consts::TAU;

use crate::numerics::real::{sin_cos_turns, sqrt_f32};

/// The drive's frequency moves at most this fraction a cycle (a wild cycle cannot throw the
/// drive off the resonance).
pub const MAX_STEP: f32 = 0.01;

/// Fewest samples a cycle for a fit (three unknowns, and some to spare).
pub const MIN_SAMPLES: f32 = 6.0;

/// The fit's determinant against its bound below which the samples cannot tell m, A and B
/// apart.
const SINGULAR: f32 = 1e-4;

/// The tracked drive may stray this fraction of the target at most: further, the lock is
/// lost (`Fault::TrackLost`).
pub const MAX_DETUNING: f32 = 0.2;

/// What one drive cycle measured.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Lock {
    /// The natural frequency the cycle gives, Hz.
    pub natural_hz: f32,
    /// The drive's frequency over the cycle, Hz.
    pub drive_hz: f32,
    /// The quality factor (`NaN` when the response does not lag the force: no damping seen).
    pub quality_factor: f32,
    /// The stretch's amplitude at the drive's frequency.
    pub amplitude: f32,
    /// The mean stretch over the cycle.
    pub mean_stretch: f32,
}

/// The sums of a least-squares fit of m + A·s + B·c to x over one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Sums {
    n: f32,
    s: f32,
    c: f32,
    ss: f32,
    cc: f32,
    sc: f32,
    x: f32,
    xs: f32,
    xc: f32,
}

impl Sums {
    fn add(&mut self, x: f32, s: f32, c: f32) {
        self.n += 1.0;
        self.s += s;
        self.c += c;
        self.ss += s * s;
        self.cc += c * c;
        self.sc += s * c;
        self.x += x;
        self.xs += x * s;
        self.xc += x * c;
    }

    /// (m, A, B) from the normal equations by Cramer's rule; `None` if singular.
    fn fit(&self) -> Option<(f32, f32, f32)> {
        let Sums {
            n,
            s,
            c,
            ss,
            cc,
            sc,
            x,
            xs,
            xc,
        } = *self;
        let det3 = |a: [f32; 9]| {
            a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6])
                + a[2] * (a[3] * a[7] - a[4] * a[6])
        };
        let d = det3([n, s, c, s, ss, sc, c, sc, cc]);
        // Singular, or so near it that f32's rounding decides: the determinant against its
        // bound n·Σs²·Σc² (Hadamard's; about 1 over a whole cycle, 0 at one angle).
        if !(n >= MIN_SAMPLES && d.abs() > SINGULAR * n * ss * cc) {
            return None;
        }
        let m = det3([x, s, c, xs, ss, sc, xc, sc, cc]) / d;
        let a = det3([n, x, c, s, xs, sc, c, xc, cc]) / d;
        let b = det3([n, s, x, s, ss, xs, c, sc, xc]) / d;
        Some((m, a, b))
    }
}

/// A cycle's least squares m + A·sin θ + B·cos θ, with |Z|² = A² + B², |Z| and the cycle's
/// reference stretch.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Solved {
    mab: (f32, f32, f32),
    z2: f32,
    amplitude: f32,
    reference: f32,
}

/// The tracker between ticks: the drive's frequency and the cycle being summed.
///
/// Besides a sample's sum, a tick does one small thing (the tick's budget): at a cycle's
/// end, set its sums aside (`observe` says so) and solve their least squares (`solve`); on
/// a later tick, fit them (`fit`), its inputs worked out by the caller between.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tracker {
    /// The drive's frequency, Hz.
    drive_hz: f32,
    sums: Sums,
    /// The stretch subtracted from every sample of this cycle before summing (a recent
    /// cycle's mean), so that f32 keeps the ring's digits.
    reference: f32,
    /// The last fit's mean stretch: the next cycle's reference.
    next_reference: f32,
    /// The cycle that ended, and its reference, until fitted.
    pending: Option<(Sums, f32)>,
    /// Its least squares, once solved (`solve`), until fitted: the fit in two ticks' parts
    /// (the tick's budget).
    solved: Option<Solved>,
    /// The last sample's phase: a smaller one starts a new cycle.
    last_phase: Option<u32>,
    lock: Option<Lock>,
}

impl Tracker {
    /// A tracker driving at `drive_hz`, about a stretch near `stretch`.
    pub fn new(drive_hz: f32, stretch: f32) -> Self {
        Self {
            drive_hz,
            sums: Sums::default(),
            reference: stretch,
            next_reference: stretch,
            pending: None,
            solved: None,
            last_phase: None,
            lock: None,
        }
    }

    /// The drive's frequency now, Hz.
    pub fn drive_hz(&self) -> f32 {
        self.drive_hz
    }

    /// The last cycle's measurement, if any.
    pub fn lock(&self) -> Option<Lock> {
        self.lock
    }

    /// Whether a cycle waits for `fit`.
    pub fn pending(&self) -> bool {
        self.pending.is_some() || self.solved.is_some()
    }

    /// The least squares of the cycle set aside, if one waits unsolved (the first part of
    /// `fit`, on a tick of its own): whether there was one. A singular cycle is dropped.
    pub fn solve(&mut self) -> bool {
        let Some((sums, reference)) = self.pending.take() else {
            return false;
        };
        self.solved = sums.fit().map(|(m, a, b)| {
            let z2 = a * a + b * b;
            Solved {
                mab: (m, a, b),
                z2,
                amplitude: sqrt_f32(z2),
                reference,
            }
        });
        true
    }

    /// A stretch sample taken at the drive's phase `phase` (turns in units of 2⁻³²); when
    /// the phase wraps, the cycle just ended is set aside for `fit` first (true).
    pub fn observe(&mut self, phase: u32, stretch: f32) -> bool {
        let wrapped = self.last_phase.is_some_and(|last| phase < last);
        self.last_phase = Some(phase);
        if wrapped {
            self.pending = Some((self.sums, self.reference));
            self.sums = Sums::default();
            self.reference = self.next_reference;
        }
        let (s, c) = sin_cos_turns(phase);
        self.sums.add(stretch - self.reference, s, c);
        wrapped
    }

    /// Fit the cycle set aside, if any. `force_per_stretch` is F/λ̄ in (rad/s)²: the Φ²
    /// term's part at the drive's frequency per unit of the mean stretch
    /// (`drive_force_per_stretch`). The drive moves `gain` (0..1] of the way to the natural
    /// frequency found, at most `MAX_STEP` of itself. The cycle's measurement.
    pub fn fit(&mut self, force_per_stretch: f32, gain: f32) -> Option<Lock> {
        self.solve();
        let Solved {
            mab: (m, a, b),
            z2,
            amplitude,
            reference,
        } = self.solved.take()?;
        let mean_stretch = reference + m;
        let force = force_per_stretch * mean_stretch;
        let omega = TAU * self.drive_hz;
        // F/Z = F·(A − jB)/|Z|².
        let omega0_squared = omega * omega + force * a / z2;
        let damping = -force * b / z2;
        if !(omega0_squared > 0.0 && mean_stretch.is_finite()) {
            return None;
        }
        let omega0 = sqrt_f32(omega0_squared);
        let natural_hz = omega0 / TAU;
        let quality_factor = if damping > 0.0 {
            omega * omega0 / damping
        } else {
            f32::NAN
        };
        let lock = Lock {
            natural_hz,
            drive_hz: self.drive_hz,
            quality_factor,
            amplitude,
            mean_stretch,
        };
        let step = (gain * (natural_hz - self.drive_hz))
            .clamp(-MAX_STEP * self.drive_hz, MAX_STEP * self.drive_hz);
        self.drive_hz += step;
        self.next_reference = mean_stretch;
        self.lock = Some(lock);
        Some(lock)
    }
}

/// F/λ̄ of the drive (model.md §4): the Φ² term ε(Φ/H)²·λ·λ2p² per unit mass holds
/// 2·Φdc·Φac·sin Ωt; in the model's units that is ω_unit²·2·Φ̄dc·Φ̄ac·λ2p², (rad/s)².
pub fn drive_force_per_stretch(
    device: &crate::model::device::Device<f32>,
    bias_volts: f32,
    ac_volts: f32,
) -> f32 {
    let w = device.rad_per_s_per_unit();
    let v = device.volts_per_unit();
    let l2 = device.prestretch_2();
    w * w * 2.0 * (bias_volts / v) * (ac_volts / v) * l2 * l2
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // a test fails by panicking
mod tests {
    use super::*;

    /// Sums of `x = m + A·sin θ + B·cos θ` at the angles `angles`.
    fn sums(angles: impl Iterator<Item = f32>, (m, a, b): (f32, f32, f32)) -> Sums {
        let mut sums = Sums::default();
        for theta in angles {
            let (s, c) = (libm::sinf(theta), libm::cosf(theta));
            sums.add(m + a * s + b * c, s, c);
        }
        sums
    }

    /// The least-squares fit is exact on exact data at any angles, not only over whole
    /// cycles (where the sums of sin and cos vanish and half the normal equations with them).
    #[test]
    fn the_fit_is_exact_at_any_angles() {
        let truth = (0.25, -1.5, 0.75);
        let angles = (0..9).map(|i| 0.3 + 0.45 * i as f32);
        let (m, a, b) = sums(angles, truth).fit().unwrap();
        assert!(
            (m - truth.0).abs() < 1e-4 && (a - truth.1).abs() < 1e-4,
            "{m} {a} {b}"
        );
        assert!((b - truth.2).abs() < 1e-4, "{m} {a} {b}");
    }

    /// Fewer samples than `MIN_SAMPLES`, or samples that cannot tell the three apart (all at
    /// one angle: a singular system), give no fit.
    #[test]
    fn too_few_or_singular_samples_give_no_fit() {
        let truth = (0.25, -1.5, 0.75);
        let five = (0..5).map(|i| 0.3 + 0.9 * i as f32);
        assert_eq!(sums(five, truth).fit(), None);
        let one_angle = (0..12).map(|_| 0.7f32);
        assert_eq!(sums(one_angle, truth).fit(), None);
    }

    /// A tracker that has summed one cycle of `x(θ)` sampled 26 times (a 40 Hz drive at
    /// 1 kHz), set aside for its fit.
    fn one_cycle(x: impl Fn(f32) -> f32) -> Tracker {
        let mut t = Tracker::new(40.0, 2.2);
        let step = (40.0f64 / 1000.0 * 4_294_967_296.0) as u32;
        for k in 0..27u32 {
            let phase = k.wrapping_mul(step);
            let theta = phase as f32 * (core::f32::consts::TAU / 4_294_967_296.0);
            t.observe(phase, x(theta));
        }
        assert!(t.pending());
        t
    }

    /// The drive moves `gain` of the way to the natural frequency found (within the step's
    /// bound): here F/Z with Z = −A (a response in antiphase) gives ω0² = Ω² − F/A, and the
    /// drive moves half of that way.
    #[test]
    fn the_drive_moves_its_gain_of_the_way() {
        let amplitude = 1e-3f32;
        let mut t = one_cycle(|theta| 2.2 - amplitude * libm::sinf(theta));
        let omega = core::f32::consts::TAU * 40.0;
        // F = force_per_stretch·λ̄ chosen so that ω0 is 1% below Ω: ω0² = Ω² − F/A.
        let omega0 = 0.99 * omega;
        let force = (omega * omega - omega0 * omega0) * amplitude;
        let lock = t.fit(force / 2.2, 0.5).unwrap();
        assert!((lock.natural_hz / 39.6 - 1.0).abs() < 1e-4, "{lock:?}");
        assert!((t.drive_hz() - (40.0 + 0.5 * (lock.natural_hz - 40.0))).abs() < 1e-4);
    }

    /// A response that no positive stiffness explains (ω0² ≤ 0: F/Z's real part below −Ω²)
    /// gives no lock, and the drive stays.
    #[test]
    fn no_positive_stiffness_no_lock() {
        let amplitude = 1e-3f32;
        let mut t = one_cycle(|theta| 2.2 - amplitude * libm::sinf(theta));
        let omega = core::f32::consts::TAU * 40.0;
        let force = 2.0 * omega * omega * amplitude;
        assert_eq!(t.fit(force / 2.2, 0.5), None);
        assert_eq!(t.drive_hz(), 40.0);
    }

    /// A cycle ends when the drive's phase goes back (wraps), not when it holds; the last
    /// fit is the tracker's lock.
    #[test]
    fn a_cycle_ends_when_the_phase_wraps() {
        let mut t = Tracker::new(44.0, 2.2);
        assert!(!t.observe(1 << 30, 2.2));
        assert!(!t.observe(1 << 30, 2.2));
        assert!(!t.pending());
        let step = 1u32 << 28;
        let mut phase = 0u32;
        let mut wrapped = false;
        for _ in 0..40 {
            phase = phase.wrapping_add(step);
            let theta = phase as f32 * (core::f32::consts::TAU / 4_294_967_296.0);
            wrapped |= t.observe(phase, 2.2 + 1e-3 * libm::sinf(theta));
        }
        assert!(wrapped && t.pending());
        let lock = t.fit(2000.0, 0.0).unwrap();
        // (Compared bit for bit: a pure sine has no damping term, and its Q may be NaN.)
        let bits = |l: Lock| {
            [
                l.natural_hz,
                l.drive_hz,
                l.quality_factor,
                l.amplitude,
                l.mean_stretch,
            ]
            .map(f32::to_bits)
        };
        assert_eq!(t.lock().map(bits), Some(bits(lock)));
    }
}
