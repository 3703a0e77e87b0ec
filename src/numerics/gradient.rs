//! Intervals with their partial derivatives (forward mode): a formula written over [`Real`]
//! run on [`Gradient`] gives an enclosure of its value and of each partial over a box. The
//! mean-value form built from them (`f(X) ⊆ f(c) + Σ ∂f/∂xᵢ(X)·(Xᵢ − cᵢ)`) is far tighter
//! than the plain interval value where terms cancel, as the checks of model.md §6 do near
//! the limit.

use core::cmp::Ordering;
use core::ops::{Add, Div, Mul, Neg, Sub};

use crate::numerics::interval::Interval;
use crate::numerics::real::Real;

/// A value's enclosure over a box and the enclosures of its partials along N variables.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gradient<const N: usize> {
    pub value: Interval,
    pub partials: [Interval; N],
}

impl<const N: usize> Gradient<N> {
    /// A constant (no partials).
    pub fn constant(value: Interval) -> Self {
        Self {
            value,
            partials: [Interval::point(0.0); N],
        }
    }

    /// The variable number `index` ranging over `value`.
    pub fn variable(value: Interval, index: usize) -> Self {
        let mut out = Self::constant(value);
        if let Some(p) = out.partials.get_mut(index) {
            *p = Interval::point(1.0);
        }
        out
    }

    /// The chain rule through a function of one variable: value `value`, derivative
    /// `derivative` (both enclosed over this one's value).
    fn through(self, value: Interval, derivative: Interval) -> Self {
        Self {
            value,
            partials: self.partials.map(|p| p * derivative),
        }
    }

    /// The mean-value enclosure over the box `ranges` with `at_centre` the function's value
    /// enclosed at the box's centre `centres`, intersected with the plain enclosure.
    pub fn mean_value(
        &self,
        at_centre: Interval,
        ranges: &[Interval; N],
        centres: &[f64; N],
    ) -> Interval {
        let mut sum = at_centre;
        for ((p, r), c) in self.partials.iter().zip(ranges).zip(centres) {
            if r.width() > 0.0 {
                sum = sum + *p * (*r - Interval::point(*c));
            }
        }
        sum.intersect(self.value).unwrap_or(self.value)
    }
}

impl<const N: usize> Add for Gradient<N> {
    type Output = Self;
    fn add(self, rhs: Self) -> Self {
        let mut partials = self.partials;
        for (p, q) in partials.iter_mut().zip(rhs.partials) {
            *p = *p + q;
        }
        Self {
            value: self.value + rhs.value,
            partials,
        }
    }
}

impl<const N: usize> Sub for Gradient<N> {
    type Output = Self;
    fn sub(self, rhs: Self) -> Self {
        self + (-rhs)
    }
}

impl<const N: usize> Neg for Gradient<N> {
    type Output = Self;
    fn neg(self) -> Self {
        Self {
            value: -self.value,
            partials: self.partials.map(|p| -p),
        }
    }
}

impl<const N: usize> Mul for Gradient<N> {
    type Output = Self;
    fn mul(self, rhs: Self) -> Self {
        let mut partials = self.partials;
        for (p, q) in partials.iter_mut().zip(rhs.partials) {
            *p = *p * rhs.value + q * self.value;
        }
        Self {
            value: self.value * rhs.value,
            partials,
        }
    }
}

impl<const N: usize> Div for Gradient<N> {
    type Output = Self;
    fn div(self, rhs: Self) -> Self {
        // (a/b)' = (a' − (a/b)·b')/b.
        let value = self.value / rhs.value;
        let mut partials = self.partials;
        for (p, q) in partials.iter_mut().zip(rhs.partials) {
            *p = (*p - value * q) / rhs.value;
        }
        Self { value, partials }
    }
}

/// Certain order of the values (as [`Interval`]'s).
impl<const N: usize> PartialOrd for Gradient<N> {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        self.value.partial_cmp(&other.value)
    }
}

impl<const N: usize> Real for Gradient<N> {
    const EPSILON: Self = Self {
        value: Interval::point(f64::EPSILON),
        partials: [Interval::point(0.0); N],
    };
    const DIGITS: u32 = 12;
    fn of(x: f64) -> Self {
        Self::constant(Interval::point(x))
    }
    fn to_f64(self) -> f64 {
        self.value.mid()
    }
    fn sqrt(self) -> Self {
        let value = self.value.sqrt();
        self.through(value, Interval::point(0.5) / value)
    }
    fn ln(self) -> Self {
        self.through(self.value.ln(), Interval::point(1.0) / self.value)
    }
    fn exp(self) -> Self {
        let value = self.value.exp();
        self.through(value, value)
    }
    fn abs(self) -> Self {
        let sign = if self.value.lo >= 0.0 {
            Interval::point(1.0)
        } else if self.value.hi <= 0.0 {
            Interval::point(-1.0)
        } else {
            Interval::new(-1.0, 1.0)
        };
        self.through(self.value.abs(), sign)
    }
    fn sin(self) -> Self {
        self.through(Interval::new(-1.0, 1.0), Interval::new(-1.0, 1.0))
    }
    fn is_finite(self) -> bool {
        self.value.is_finite()
    }
    fn next_down(self) -> Self {
        Self {
            value: self.value.next_down(),
            partials: self.partials,
        }
    }
    fn angle_of_phase(phase: u64) -> Self {
        Self::constant(Interval::angle_of_phase(phase))
    }
    fn is_nan(self) -> bool {
        self.value.is_nan()
    }
    fn squared(self) -> Self {
        let value = self.value.square();
        self.through(value, Interval::point(2.0) * self.value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The partials of a product and a quotient hold the calculus' values at a point.
    #[test]
    fn partials_at_a_point() {
        let x = Gradient::<2>::variable(Interval::point(3.0), 0);
        let y = Gradient::<2>::variable(Interval::point(2.0), 1);
        let f = x * x / y + y.sqrt(); // ∂x = 2x/y = 3, ∂y = −x²/y² + 1/(2√y)
        assert!(f.partials[0].contains(3.0));
        let dy = -9.0 / 4.0 + 0.5 / 2f64.sqrt();
        assert!(f.partials[1].contains(dy), "{:?}", f.partials[1]);
    }

    /// The mean-value form encloses f over a box (checked on a grid) and is tighter than
    /// the plain interval where the terms cancel: f = x − x² on [0.4, 0.6].
    #[test]
    fn mean_value_encloses_and_tightens() {
        let range = Interval::new(0.4, 0.6);
        let x = Gradient::<1>::variable(range, 0);
        let f = x - x * x;
        let c = Interval::point(0.5);
        let at_centre = c - c * c;
        let mv = f.mean_value(at_centre, &[range], &[0.5]);
        for i in 0..=20 {
            let t = 0.4 + 0.01 * i as f64;
            assert!(mv.contains(t - t * t));
        }
        assert!(mv.width() < 0.5 * (range - range * range).width(), "{mv:?}");
    }
}
