//! The float type the physics runs in: `f32` on the target, `f64` on the host.
//!
//! One small trait over `libm`, so that every equation is written once.

use core::fmt::Debug;
use core::ops::{Add, Div, Mul, Neg, Sub};

/// A real number: the operations the model needs, for `f32` and `f64`.
pub trait Real:
    Copy
    + Debug
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// Machine epsilon of the type.
    const EPSILON: Self;
    /// Significant digits a message writes (`Decimal`).
    const DIGITS: u32;
    /// The value nearest to `x` (overflows to infinity).
    fn of(x: f64) -> Self;
    /// Widen to `f64` (exact).
    fn to_f64(self) -> f64;
    fn sqrt(self) -> Self;
    fn ln(self) -> Self;
    fn exp(self) -> Self;
    fn abs(self) -> Self;
    fn sin(self) -> Self;
    fn is_finite(self) -> bool;
    /// The largest value below this one (NaN stays NaN, −∞ stays −∞).
    fn next_down(self) -> Self;
    /// The angle of a phase given in units of 2π/2⁶⁴ (a wrapping turn counter), in [−π, π).
    fn angle_of_phase(phase: u64) -> Self;

    /// Zero.
    fn zero() -> Self {
        Self::of(0.0)
    }
    /// One.
    fn one() -> Self {
        Self::of(1.0)
    }
    /// The smaller of two values; `self` when either is NaN (for ordinary arithmetic, not
    /// for safety margins: see [`Real::min_margin`]).
    fn min(self, other: Self) -> Self {
        if other < self {
            other
        } else {
            self
        }
    }
    /// The smaller of two safety margins, NaN when either is NaN: a margin with an undefined
    /// part must fail its check (`!(m > 0)`), never pass on the other part.
    fn min_margin(self, other: Self) -> Self {
        if self.is_nan() || other.is_nan() {
            Self::of(f64::NAN)
        } else if other < self {
            other
        } else {
            self
        }
    }
    /// Whether the value is NaN.
    #[allow(clippy::eq_op)]
    fn is_nan(self) -> bool {
        self != self
    }
    /// The larger of two values; `self` when either is NaN.
    fn max(self, other: Self) -> Self {
        if other > self {
            other
        } else {
            self
        }
    }
    /// `x²`.
    fn squared(self) -> Self {
        self * self
    }
}

impl Real for f64 {
    const EPSILON: Self = f64::EPSILON;
    const DIGITS: u32 = 12;
    fn of(x: f64) -> Self {
        x
    }
    fn to_f64(self) -> f64 {
        self
    }
    fn sqrt(self) -> Self {
        libm::sqrt(self)
    }
    fn ln(self) -> Self {
        libm::log(self)
    }
    fn exp(self) -> Self {
        libm::exp(self)
    }
    fn abs(self) -> Self {
        libm::fabs(self)
    }
    fn sin(self) -> Self {
        libm::sin(self)
    }
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
    fn next_down(self) -> Self {
        f64::next_down(self)
    }
    fn angle_of_phase(phase: u64) -> Self {
        (phase as i64) as f64 * (core::f64::consts::TAU / 18_446_744_073_709_551_616.0)
    }
}

impl Real for f32 {
    const EPSILON: Self = f32::EPSILON;
    const DIGITS: u32 = 7;
    fn of(x: f64) -> Self {
        x as f32
    }
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    fn sqrt(self) -> Self {
        libm::sqrtf(self)
    }
    fn ln(self) -> Self {
        libm::logf(self)
    }
    fn exp(self) -> Self {
        libm::expf(self)
    }
    fn abs(self) -> Self {
        libm::fabsf(self)
    }
    /// An f32 kernel for |x| ≤ 8192 (the drive's phases): libm's `sinf` reduces in f64,
    /// which the Cortex-M4F's FPU does in software (2,000 instructions a call).
    fn sin(self) -> Self {
        sin_f32(self)
    }
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
    fn next_down(self) -> Self {
        f32::next_down(self)
    }
    fn angle_of_phase(phase: u64) -> Self {
        // The top 32 bits resolve 1.5e-9 rad, finer than f32 near π.
        ((phase >> 32) as u32 as i32) as f32 * (core::f32::consts::TAU / 4_294_967_296.0)
    }
}

/// Largest |x| the f32 sine reduces itself; beyond it the three-part π/4 loses accuracy.
const SIN_F32_REDUCED_UP_TO: f32 = 8192.0;

/// sin x in f32: x reduced by π/4 in three parts (Cody–Waite; the first two hold few enough
/// bits that k·part is exact for k < 2¹⁶), then a minimax polynomial for sin or cos on
/// [−π/4, π/4]. Error below 2.5e-7 absolute for |x| ≤ 8192; libm `sinf` beyond (and for NaN).
fn sin_f32(x: f32) -> f32 {
    const FOUR_OVER_PI: f32 = 1.273_239_5;
    // π/4 = PART_1 + PART_2 + PART_3.
    const PART_1: f32 = 0.785_156_25;
    const PART_2: f32 = 2.418_756_5e-4;
    const PART_3: f32 = 3.774_895e-8;
    let size = libm::fabsf(x);
    if !(size <= SIN_F32_REDUCED_UP_TO) {
        return libm::sinf(x);
    }
    // Octant j rounded up to even, so the reduced angle lies in [−π/4, π/4].
    let mut j = (size * FOUR_OVER_PI) as u32;
    j += j & 1;
    let k = j as f32;
    let r = ((size - k * PART_1) - k * PART_2) - k * PART_3;
    let r2 = r * r;
    // Quadrant q = j/2 (mod 4): sin, cos, −sin, −cos of r.
    let q = (j >> 1) & 3;
    let value = if q & 1 == 0 {
        ((-1.951_529_6e-4 * r2 + 8.332_161e-3) * r2 - 1.666_665_5e-1) * r2 * r + r
    } else {
        ((2.443_315_7e-5 * r2 - 1.388_731_6e-3) * r2 + 4.166_664_6e-2) * r2 * r2 - 0.5 * r2 + 1.0
    };
    let negative = (q >= 2) != (x < 0.0);
    if negative {
        -value
    } else {
        value
    }
}

/// √x in f32 for the tick's paths: libm's `sqrtf` is a bit-by-bit loop in software on the
/// M4F (its VSQRT is out of reach without std), some hundred instructions. An inverse root
/// from the exponent's halving, two Newton steps on it, then one on √x itself: within 1 ulp
/// of the correctly rounded root for every positive f32 (tested against libm); 0 at ±0, ∞ at
/// ∞, NaN below 0 and for NaN.
pub fn sqrt_f32(x: f32) -> f32 {
    if !(x > 0.0 && x < f32::INFINITY) {
        return if x == 0.0 || x == f32::INFINITY {
            x
        } else {
            f32::NAN
        };
    }
    // Subnormals scaled into the normal range first (2²⁴ in, 2¹² out).
    let (x, scale) = if x < f32::MIN_POSITIVE {
        (x * 16_777_216.0, 1.0 / 4096.0)
    } else {
        (x, 1.0)
    };
    let half = 0.5 * x;
    let mut y = f32::from_bits(0x5f37_5a86 - (x.to_bits() >> 1));
    y *= 1.5 - half * y * y;
    y *= 1.5 - half * y * y;
    let r = x * y;
    0.5 * (r + x / r) * scale
}

/// (sin θ, cos θ) in f32 of a phase in turns (θ = 2π·phase/2³²), as the drive's and the
/// lock-in's phase accumulators hold it: the quadrant from the top bits, the rest an angle
/// in [−π/4, π/4), `sin_f32`'s polynomials on it. One reduction for both, no float range
/// reduction (the tick's budget). Within 3e-7 of the exact values (tested against f64).
pub fn sin_cos_turns(phase: u32) -> (f32, f32) {
    // An eighth of a turn on, so that each quadrant is centred on its axis.
    let p = phase.wrapping_add(1 << 29);
    let quadrant = p >> 30;
    let within = (p & 0x3FFF_FFFF) as i32 - (1 << 29);
    let r = within as f32 * (core::f32::consts::TAU / 4_294_967_296.0);
    let r2 = r * r;
    let s = ((-1.951_529_6e-4 * r2 + 8.332_161e-3) * r2 - 1.666_665_5e-1) * r2 * r + r;
    let c =
        ((2.443_315_7e-5 * r2 - 1.388_731_6e-3) * r2 + 4.166_664_6e-2) * r2 * r2 - 0.5 * r2 + 1.0;
    match quadrant {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}
