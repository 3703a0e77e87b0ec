//! Numbers in messages, written without the core library's float formatting (about 20 KB of
//! flash on the target: Grisu, Dragon4 and their tables): `Decimal(x)` writes x with
//! `Real::DIGITS` significant digits (7 for f32, 12 for f64), trailing zeros dropped, plain
//! from 10⁻⁵ to 10^DIGITS and in scientific notation beyond.

use core::fmt;

use crate::numerics::real::Real;

/// Powers of ten exact in f64 (10²² is the last).
const POWERS: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// `x` times 10^`e` (exact steps of at most 10²²: one rounding for |e| ≤ 22).
pub(crate) fn scale10(mut x: f64, mut e: i32) -> f64 {
    while e > 0 {
        let step = e.min(22);
        x *= POWERS.get(step as usize).copied().unwrap_or(1.0);
        e -= step;
    }
    while e < 0 {
        let step = (-e).min(22);
        x /= POWERS.get(step as usize).copied().unwrap_or(1.0);
        e += step;
    }
    x
}

/// A number for a message: `Real::DIGITS` significant digits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decimal<T>(pub T);

impl<T: Real> fmt::Display for Decimal<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0.to_f64();
        if x.is_nan() {
            return f.write_str("NaN");
        }
        if x.is_sign_negative() && x != 0.0 {
            f.write_str("-")?;
        }
        let a = x.abs();
        if a == f64::INFINITY {
            return f.write_str("inf");
        }
        if a == 0.0 {
            return f.write_str("0");
        }
        let digits = T::DIGITS as i32;
        let top = scale10(1.0, digits) as u64;
        // The decimal exponent from the binary one (times log10 2), then corrected.
        let binary = ((a.to_bits() >> 52) & 0x7FF) as i32 - 1023;
        let mut e = (f64::from(binary) * core::f64::consts::LOG10_2) as i32;
        let mut m = 0u64;
        for _ in 0..4 {
            m = libm::round(scale10(a, digits - 1 - e)) as u64;
            if m >= top {
                e += 1;
            } else if m < top / 10 {
                e -= 1;
            } else {
                break;
            }
        }
        // Trailing zeros dropped: `m` holds `kept` digits, the first at 10^e.
        let mut kept = digits;
        while kept > 1 && m.is_multiple_of(10) {
            m /= 10;
            kept -= 1;
        }
        if e >= -5 && e < digits {
            if e >= kept - 1 {
                // An integer: the digits, then zeros.
                write!(f, "{m}")?;
                for _ in 0..(e - (kept - 1)) {
                    f.write_str("0")?;
                }
                Ok(())
            } else if e >= 0 {
                let split = scale10(1.0, kept - 1 - e) as u64;
                let (whole, frac) = (m / split, m % split);
                write!(f, "{whole}.{frac:0width$}", width = (kept - 1 - e) as usize)
            } else {
                f.write_str("0.")?;
                for _ in 0..(-e - 1) {
                    f.write_str("0")?;
                }
                write!(f, "{m}")
            }
        } else {
            let split = scale10(1.0, kept - 1) as u64;
            let (lead, rest) = (m / split, m % split);
            if kept > 1 {
                write!(f, "{lead}.{rest:0width$}e{e}", width = (kept - 1) as usize)
            } else {
                write!(f, "{lead}e{e}")
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::panic)]
mod tests {
    use super::*;

    fn text<T: Real>(x: T) -> heapless::String<64> {
        let mut s = heapless::String::new();
        let _ = fmt::Write::write_fmt(&mut s, format_args!("{}", Decimal(x)));
        s
    }

    /// Against hand-written expectations, and (for every case) read back within the digits.
    #[test]
    fn writes_numbers_people_read() {
        let cases: [(f32, &str); 14] = [
            (44.0, "44"),
            (0.05, "0.05"),
            (7449.8784, "7449.878"),
            (9361.898, "9361.898"),
            (1e-4, "0.0001"),
            (-3.25, "-3.25"),
            (1_000_000.0, "1000000"),
            (12_345_678.0, "1.234568e7"),
            (2.5e-7, "2.5e-7"),
            (0.0, "0"),
            (100.5, "100.5"),
            (f32::NAN, "NaN"),
            (f32::NEG_INFINITY, "-inf"),
            (9.9999999, "10"),
        ];
        for (x, want) in cases {
            assert_eq!(text(x).as_str(), want, "{x:e}");
        }
        assert_eq!(text(45.952724764627106f64).as_str(), "45.9527247646");
        let mut x = 1.234_567e-30f64;
        while x < 1e30 {
            for v in [x, -x] {
                let s = text(v);
                let back: f64 = s.parse().unwrap_or_else(|_| panic!("{s}"));
                assert!((back - v).abs() <= 1e-11 * v.abs(), "{v:e} -> {s}");
            }
            x *= 7.3;
        }
    }
}
