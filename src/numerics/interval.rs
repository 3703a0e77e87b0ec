//! Interval arithmetic in f64 with outward rounding: every operation's result contains every
//! value the operation takes on its operands' intervals, so a bound computed here cannot lie.
//!
//! Each IEEE operation (+, −, ×, ÷, √) is correctly rounded, within half a unit in the last
//! place; widening each end by one unit (`next_down`/`next_up`) encloses the exact result.
//! `ln` and `exp` come from libm (under one unit of error) and are widened by two. The type
//! implements [`Real`] so the model's formulas (the material of model.md §3) run on it as
//! written; its comparisons are certain ones (`a < b` only when every value of `a` is below
//! every value of `b`), which is what a check that must hold over a whole box asks.

use core::cmp::Ordering;
use core::ops::{Add, Div, Mul, Neg, Sub};

use crate::numerics::real::Real;

/// The closed interval [lo, hi]; `lo > hi` or a NaN end never arises from finite operands
/// except where said (a division by an interval holding zero gives the whole line).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
}

impl Interval {
    /// Every real number.
    pub const ENTIRE: Interval = Interval {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };

    /// [lo, hi] as given (the caller orders them).
    pub const fn new(lo: f64, hi: f64) -> Self {
        Self { lo, hi }
    }

    /// The single point x.
    pub const fn point(x: f64) -> Self {
        Self { lo: x, hi: x }
    }

    /// The ends rounded outward by one unit in the last place.
    fn outward(lo: f64, hi: f64) -> Self {
        if lo.is_nan() || hi.is_nan() {
            return Self::ENTIRE;
        }
        Self {
            lo: lo.next_down(),
            hi: hi.next_up(),
        }
    }

    /// hi − lo.
    pub fn width(&self) -> f64 {
        self.hi - self.lo
    }

    /// The midpoint.
    pub fn mid(&self) -> f64 {
        0.5 * self.lo + 0.5 * self.hi
    }

    /// Whether `x` lies in the interval.
    pub fn contains(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }

    /// The common part, `None` when the two do not meet.
    pub fn intersect(&self, other: Interval) -> Option<Interval> {
        let (lo, hi) = (self.lo.max(other.lo), self.hi.min(other.hi));
        (lo <= hi).then_some(Interval { lo, hi })
    }

    /// The smallest interval holding both.
    pub fn hull(&self, other: Interval) -> Interval {
        Interval {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
        }
    }

    /// The part at or above zero (for a quantity known not to be negative, such as Φ̄² on
    /// the loading branch): [max(lo, 0), hi].
    pub fn non_negative(&self) -> Interval {
        Interval {
            lo: self.lo.max(0.0),
            hi: self.hi.max(0.0),
        }
    }

    /// x² (tighter than x·x when the interval holds zero).
    pub fn square(self) -> Interval {
        let (a, b) = (self.lo * self.lo, self.hi * self.hi);
        if self.lo <= 0.0 && self.hi >= 0.0 {
            Self::outward(0.0, a.max(b)).non_negative()
        } else {
            Self::outward(a.min(b), a.max(b)).non_negative()
        }
    }

    /// Widen by `units` units in the last place at each end.
    fn widened(self, units: u32) -> Interval {
        let mut out = self;
        for _ in 0..units {
            out = Self::outward(out.lo, out.hi);
        }
        out
    }
}

impl Add for Interval {
    type Output = Interval;
    fn add(self, rhs: Interval) -> Interval {
        Interval::outward(self.lo + rhs.lo, self.hi + rhs.hi)
    }
}

impl Sub for Interval {
    type Output = Interval;
    fn sub(self, rhs: Interval) -> Interval {
        Interval::outward(self.lo - rhs.hi, self.hi - rhs.lo)
    }
}

impl Neg for Interval {
    type Output = Interval;
    fn neg(self) -> Interval {
        Interval {
            lo: -self.hi,
            hi: -self.lo,
        }
    }
}

impl Mul for Interval {
    type Output = Interval;
    fn mul(self, rhs: Interval) -> Interval {
        let products = [
            self.lo * rhs.lo,
            self.lo * rhs.hi,
            self.hi * rhs.lo,
            self.hi * rhs.hi,
        ];
        // 0·∞ (an unbounded operand) is NaN: the whole line.
        if products.iter().any(|p| p.is_nan()) {
            return Interval::ENTIRE;
        }
        let lo = products.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        let hi = products.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        Interval::outward(lo, hi)
    }
}

impl Div for Interval {
    type Output = Interval;
    fn div(self, rhs: Interval) -> Interval {
        if !(rhs.lo > 0.0 || rhs.hi < 0.0) {
            return Interval::ENTIRE;
        }
        let quotients = [
            self.lo / rhs.lo,
            self.lo / rhs.hi,
            self.hi / rhs.lo,
            self.hi / rhs.hi,
        ];
        if quotients.iter().any(|q| q.is_nan()) {
            return Interval::ENTIRE;
        }
        let lo = quotients.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        let hi = quotients.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        Interval::outward(lo, hi)
    }
}

/// Certain order: `Less` when every value of `self` is below every value of `other`,
/// `Equal` for the same single point, otherwise `None` (so `<`, `>` and `==` hold only
/// when they hold for every pair of values).
impl PartialOrd for Interval {
    fn partial_cmp(&self, other: &Interval) -> Option<Ordering> {
        if self.hi < other.lo {
            Some(Ordering::Less)
        } else if self.lo > other.hi {
            Some(Ordering::Greater)
        } else if self.lo == self.hi && other.lo == other.hi && self.lo == other.lo {
            Some(Ordering::Equal)
        } else {
            None
        }
    }
}

impl Real for Interval {
    const EPSILON: Self = Interval::point(f64::EPSILON);
    const DIGITS: u32 = 12;
    fn of(x: f64) -> Self {
        Interval::point(x)
    }
    /// The midpoint (an interval has no single value; the model's formulas do not call this).
    fn to_f64(self) -> f64 {
        self.mid()
    }
    /// √ of the non-negative part (NaN-free: a negative part has no root to enclose).
    fn sqrt(self) -> Self {
        if self.hi < 0.0 {
            return Interval::new(f64::NAN, f64::NAN);
        }
        let x = self.non_negative();
        let lo = libm::sqrt(x.lo);
        Interval {
            lo: if lo > 0.0 { lo.next_down() } else { 0.0 },
            hi: libm::sqrt(x.hi).next_up(),
        }
    }
    fn ln(self) -> Self {
        if !(self.lo > 0.0) {
            return Interval::ENTIRE;
        }
        Interval::new(libm::log(self.lo), libm::log(self.hi)).widened(2)
    }
    fn exp(self) -> Self {
        let out = Interval::new(libm::exp(self.lo), libm::exp(self.hi)).widened(2);
        out.non_negative()
    }
    fn abs(self) -> Self {
        if self.lo >= 0.0 {
            self
        } else if self.hi <= 0.0 {
            -self
        } else {
            Interval::new(0.0, (-self.lo).max(self.hi))
        }
    }
    /// [−1, 1]: an enclosure, not a tight one (the statics never take a sine).
    fn sin(self) -> Self {
        Interval::new(-1.0, 1.0)
    }
    fn is_finite(self) -> bool {
        self.lo.is_finite() && self.hi.is_finite()
    }
    fn next_down(self) -> Self {
        Interval::new(self.lo.next_down(), self.hi.next_down())
    }
    fn angle_of_phase(phase: u64) -> Self {
        Interval::point(f64::angle_of_phase(phase)).widened(2)
    }
    /// The interval of min(x, y) over both intervals.
    fn min(self, other: Self) -> Self {
        Interval::new(self.lo.min(other.lo), self.hi.min(other.hi))
    }
    fn min_margin(self, other: Self) -> Self {
        if self.is_nan() || other.is_nan() {
            return Interval::new(f64::NAN, f64::NAN);
        }
        self.min(other)
    }
    fn is_nan(self) -> bool {
        self.lo.is_nan() || self.hi.is_nan()
    }
    fn max(self, other: Self) -> Self {
        Interval::new(self.lo.max(other.lo), self.hi.max(other.hi))
    }
    fn squared(self) -> Self {
        self.square()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Operations on points enclose the exact result: the doubles 0.1 and 0.2 sum exactly to
    /// 0.3000000000000000166…, between the double 0.3 (just below) and the rounded sum
    /// 0.30000000000000004 (just above), both inside; 1/3 times 3 holds 1.
    #[test]
    fn points_are_enclosed() {
        let sum = Interval::point(0.1) + Interval::point(0.2);
        assert!(sum.lo <= 0.3 && 0.1 + 0.2 < sum.hi, "{sum:?}");
        let third = Interval::point(1.0) / Interval::point(3.0);
        let one = third * Interval::point(3.0);
        assert!(one.contains(1.0) && one.width() > 0.0, "{one:?}");
        let root = Interval::point(2.0).sqrt();
        assert!((root * root).contains(2.0));
    }

    /// Every value drawn from the operands lands inside the result, for each operation.
    #[test]
    fn samples_land_inside() {
        let xs = [
            Interval::new(-2.0, 3.0),
            Interval::new(0.5, 1.5),
            Interval::new(-4.0, -1.0),
            Interval::new(1e-3, 2e-3),
        ];
        for a in xs {
            for b in xs {
                for i in 0..=8 {
                    for j in 0..=8 {
                        let x = a.lo + (a.hi - a.lo) * i as f64 / 8.0;
                        let y = b.lo + (b.hi - b.lo) * j as f64 / 8.0;
                        assert!((a + b).contains(x + y));
                        assert!((a - b).contains(x - y));
                        assert!((a * b).contains(x * y));
                        let q = a / b;
                        assert!(q.contains(x / y) || y == 0.0, "{a:?}/{b:?}");
                        assert!(a.square().contains(x * x));
                        assert!(Real::abs(a).contains(x.abs()));
                        if x > 0.0 {
                            assert!(a.sqrt().contains(libm::sqrt(x)));
                        }
                    }
                }
            }
        }
    }

    /// Dividing by an interval that holds zero gives the whole line, not a wrong bound.
    #[test]
    fn division_through_zero_is_entire() {
        let q = Interval::point(1.0) / Interval::new(-1.0, 1.0);
        assert_eq!(q, Interval::ENTIRE);
    }

    /// Comparisons hold only when certain.
    #[test]
    fn comparisons_are_certain() {
        let a = Interval::new(0.0, 1.0);
        let b = Interval::new(0.5, 2.0);
        assert!(!(a < b) && !(a > b) && a != b);
        assert!(a < Interval::new(1.5, 2.0));
        assert!(Interval::new(0.1, 0.2) > Interval::point(0.0));
    }
}
