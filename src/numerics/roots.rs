//! Bracketed root finding and extremum search to full precision of the float type.
//!
//! Bisection halves until the midpoint is no longer distinct from an end, so the answer is
//! exact to the last bit the type can hold, and it cannot loop: the iteration count is bounded.

use crate::numerics::real::Real;

/// Enough halvings to reach adjacent floats on any bracket `f64` can hold.
const MAX_HALVINGS: usize = 2100;

/// Given `inside(lo)` true and `inside(hi)` false, the last point before `inside` turns false,
/// to full precision. Returns `(lo, hi)`: `lo` still inside, `hi` not, adjacent floats.
pub fn bisect<T: Real>(mut lo: T, mut hi: T, mut inside: impl FnMut(T) -> bool) -> (T, T) {
    for _ in 0..MAX_HALVINGS {
        let mid = lo + (hi - lo) * T::of(0.5);
        if !(mid > lo.min(hi) && mid < lo.max(hi)) {
            break;
        }
        if inside(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo, hi)
}

/// The point in `[lo, hi]` where `f` is largest, for `f` unimodal there (golden section).
pub fn argmax<T: Real>(mut lo: T, mut hi: T, mut f: impl FnMut(T) -> T) -> T {
    let r = T::of(0.618_033_988_749_894_8);
    let mut a = hi - (hi - lo) * r;
    let mut b = lo + (hi - lo) * r;
    let (mut fa, mut fb) = (f(a), f(b));
    for _ in 0..MAX_HALVINGS {
        if !(hi - lo > (lo.abs() + hi.abs()) * T::EPSILON) {
            break;
        }
        if fa < fb {
            lo = a;
            a = b;
            fa = fb;
            b = lo + (hi - lo) * r;
            fb = f(b);
        } else {
            hi = b;
            b = a;
            fb = fa;
            a = hi - (hi - lo) * r;
            fa = f(a);
        }
    }
    if fa < fb {
        b
    } else {
        a
    }
}
