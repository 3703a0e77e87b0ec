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

/// As [`bisect`] with `inside(x)` = `f(x) < 0`, for `f(lo) < 0 ≤ f(hi)` and `lo < hi`: where
/// `f`'s sign changes once in the bracket, the same adjacent floats, in a handful of
/// evaluations where `f` is smooth rather than one per bit. Where it changes more than once
/// (rounding noise about the root in f32, say), the floats about one of the changes, as
/// bisection's are, though not necessarily the same one. Secant steps through the last two points (Dekker's), kept inside
/// the bracket, with a midpoint wherever the bracket has not halved in four steps; once a
/// step is within a few units in the last place, a point as far past it closes the bracket,
/// and bisection ends it. Ends the other way round, or a NaN, leave the rest to [`bisect`].
pub fn root<T: Real>(mut lo: T, mut hi: T, mut f: impl FnMut(T) -> T) -> (T, T) {
    let zero = T::zero();
    let (f_lo, f_hi) = (f(lo), f(hi));
    if !(lo < hi && f_lo < zero && f_hi >= zero) {
        return bisect(lo, hi, |x| f(x) < zero);
    }
    // The last two points; the widths before the last four steps.
    let (mut a, mut f_a, mut b, mut f_b) = (lo, f_lo, hi, f_hi);
    let mut widths = [(hi - lo) * T::of(4.0); 4];
    for _ in 0..MAX_HALVINGS {
        let width = hi - lo;
        let mid = lo + width * T::of(0.5);
        if !(mid > lo && mid < hi) {
            break;
        }
        let secant = b - f_b * ((b - a) / (f_b - f_a));
        // Within a few ulps of the last point: past it by as much again, to close the bracket.
        let near = (b.abs() + width) * T::EPSILON * T::of(4.0);
        let step = secant - b;
        let x = if step.abs() <= near {
            b + if step < zero { -near } else { near }
        } else {
            secant
        };
        let x = if width <= widths[0] * T::of(0.5) && x > lo && x < hi {
            x
        } else {
            mid
        };
        let fx = f(x);
        if fx < zero {
            lo = x;
        } else if fx >= zero {
            hi = x;
        } else {
            return bisect(lo, hi, |x| f(x) < zero);
        }
        (a, f_a, b, f_b) = (b, f_b, x, fx);
        widths = [widths[1], widths[2], widths[3], width];
    }
    // Adjacent already (no evaluation), or the halvings left after a long bracket.
    bisect(lo, hi, |x| f(x) < zero)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `root` ends on the same adjacent floats as `bisect` on the same sign, for smooth
    /// increasing functions in f64 and f32 (roots across the bracket, steep and flat ones), in
    /// under half the evaluations (about a third, measured); and on a step function (no slope to follow) it still ends there.
    #[test]
    fn root_finds_what_bisection_finds() {
        let shapes: [fn(f64) -> f64; 4] = [
            |x| x.powi(3) + 0.1 * x,
            |x| (3.0 * x).exp() - 1.0,
            |x| x.sqrt() * (1.0 + x * x),
            |x| x.atan() + 0.001 * x,
        ];
        let mut state = 0x1234_5678_9abc_def0_u64;
        let mut uniform = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut ours, mut halvings) = (0, 0);
        for shape in shapes {
            for _ in 0..200 {
                let (lo, hi) = (0.0, 0.1 + 3.0 * uniform());
                let target = shape(lo + (hi - lo) * (0.001 + 0.998 * uniform()));
                let f = |x: f64| shape(x) - target;
                let mut count = 0;
                let found = root(lo, hi, |x| {
                    count += 1;
                    f(x)
                });
                let mut halved = 0;
                let expected = bisect(lo, hi, |x| {
                    halved += 1;
                    f(x) < 0.0
                });
                assert_eq!(found, expected, "target {target} on [{lo}, {hi}]");
                (ours, halvings) = (ours + count, halvings + halved);
                let f32_of = |x: f32| (shape(f64::from(x)) - target) as f32;
                let (lo32, hi32) = (lo as f32, hi as f32);
                if f32_of(lo32) < 0.0 && f32_of(hi32) >= 0.0 {
                    let found = root(lo32, hi32, f32_of);
                    assert_eq!(found, bisect(lo32, hi32, |x| f32_of(x) < 0.0));
                }
            }
        }
        assert!(
            2 * ours < halvings,
            "{ours} evaluations against bisection's {halvings}"
        );
        let step = |x: f64| if x < 0.3 { -1.0 } else { 1.0 };
        assert_eq!(root(0.0, 1.0, step), bisect(0.0, 1.0, |x| step(x) < 0.0));
    }
}
