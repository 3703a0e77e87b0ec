//! Tuning: the bias on the loading branch that sets a target natural frequency, inside the
//! safe region with a voltage margin (model.md §7).
//!
//! f(λ) need not be monotone, so the allowed part of the branch is cut into monotone pieces
//! (a scan finds the turning points, golden section refines them) and the first piece that
//! holds the target is bisected: this gives the smallest bias, since Φ rises with λ.

use core::fmt;

use crate::numerics::decimal::Decimal;

use crate::model::device::Device;
use crate::model::safety::Limit;
use crate::model::statics::Equilibrium;
use crate::numerics::real::Real;
use crate::numerics::roots::{argmax, bisect};

/// The voltage margin used unless another is asked for: bias ≤ (1 − 0.05)·Φlimit.
pub const DEFAULT_MARGIN: f64 = 0.05;

/// Grid points of the scan for turning points of f along the allowed branch. Two turning
/// points closer than one grid cell (1/64 of the allowed branch) are not resolved.
pub const TUNING_SCAN_POINTS: usize = 64;

/// Why a target cannot be tuned.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TuneError<T> {
    /// The target frequency is NaN, infinite or not positive.
    InvalidTarget { target_hz: T },
    /// The margin is not in [0, 1).
    InvalidMargin { margin: T },
    /// The target is outside the tunable range `[low_hz, high_hz]`.
    OutOfRange { target_hz: T, low_hz: T, high_hz: T },
}

impl<T: Real> core::error::Error for TuneError<T> {}

impl<T: Real> fmt::Display for TuneError<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            TuneError::InvalidTarget { target_hz } => write!(
                f,
                "target frequency {} Hz is not a finite positive number",
                Decimal(target_hz)
            ),
            TuneError::InvalidMargin { margin } => {
                write!(f, "voltage margin {} is outside [0, 1)", Decimal(margin))
            }
            TuneError::OutOfRange {
                target_hz,
                low_hz,
                high_hz,
            } => write!(
                f,
                "target frequency {} Hz is outside the tunable range [{}, {}] Hz",
                Decimal(target_hz),
                Decimal(low_hz),
                Decimal(high_hz)
            ),
        }
    }
}

/// The frequencies reachable with a margin, and the highest bias allowed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TunableRange<T> {
    pub low_hz: T,
    pub high_hz: T,
    /// The equilibrium at the highest allowed bias, (1 − margin)·Φlimit.
    pub max_bias: Equilibrium<T>,
}

/// One stretch of the branch on which f is monotone, in offsets δ = λ − λ1p.
#[derive(Clone, Copy, Debug)]
struct Piece<T> {
    start: T,
    f_start: T,
    end: T,
    f_end: T,
}

/// A device with its safe limit found once, ready to answer tuning requests.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tuner<T> {
    device: Device<T>,
    limit: Limit<T>,
}

impl<T: Real> Tuner<T> {
    /// Find the device's limit (the costly part; done once).
    pub fn new(device: Device<T>) -> Self {
        let limit = Limit::of(&device);
        Self { device, limit }
    }

    pub fn device(&self) -> &Device<T> {
        &self.device
    }

    /// The limit of the loading branch.
    pub fn limit(&self) -> &Limit<T> {
        &self.limit
    }

    /// The equilibrium at zero bias.
    pub fn zero_bias(&self) -> Equilibrium<T> {
        self.device.equilibrium_at(T::zero())
    }

    /// The equilibrium at the highest bias the margin allows, (1 − margin)·Φlimit.
    pub fn max_bias(&self, margin: T) -> Result<Equilibrium<T>, TuneError<T>> {
        if !(margin >= T::zero() && margin < T::one()) {
            return Err(TuneError::InvalidMargin { margin });
        }
        let volts = (T::one() - margin) * self.limit.at.volts;
        // Never `None`: (1 − margin)·Φlimit ≤ Φlimit = Φ(δlimit), compared as computed.
        Ok(self
            .device
            .offset_for_bias(volts, self.limit.at.offset)
            .map_or(self.limit.at, |offset| self.device.equilibrium_at(offset)))
    }

    /// The range of natural frequencies reachable between zero bias and the margin.
    pub fn tunable_range(&self, margin: T) -> Result<TunableRange<T>, TuneError<T>> {
        let max_bias = self.max_bias(margin)?;
        let mut low_hz = self.zero_bias().natural_frequency_hz;
        let mut high_hz = low_hz;
        self.for_each_piece(max_bias.offset, |piece| {
            low_hz = low_hz.min(piece.f_end);
            high_hz = high_hz.max(piece.f_end);
            false
        });
        Ok(TunableRange {
            low_hz,
            high_hz,
            max_bias,
        })
    }

    /// The turning points of f (its interior extrema) on the branch up to the margin's
    /// highest bias, in order of rising bias: a table holds them as points, so that its
    /// range and its lookup near an extremum follow the model.
    pub fn for_each_turning_point(
        &self,
        margin: T,
        mut visit: impl FnMut(Equilibrium<T>),
    ) -> Result<(), TuneError<T>> {
        let max_bias = self.max_bias(margin)?;
        self.for_each_piece(max_bias.offset, |piece| {
            if piece.end < max_bias.offset && piece.end > T::zero() {
                visit(self.device.equilibrium_at(piece.end));
            }
            false
        });
        Ok(())
    }

    /// The smallest bias on the loading branch, within the margin, whose natural frequency
    /// is `target_hz`.
    pub fn tune(&self, target_hz: T, margin: T) -> Result<Equilibrium<T>, TuneError<T>> {
        if !(target_hz.is_finite() && target_hz > T::zero()) {
            return Err(TuneError::InvalidTarget { target_hz });
        }
        let max_bias = self.max_bias(margin)?;
        let mut found = None;
        self.for_each_piece(max_bias.offset, |p| {
            let (lo, hi) = (p.f_start.min(p.f_end), p.f_start.max(p.f_end));
            if !(target_hz >= lo && target_hz <= hi) {
                return false;
            }
            let rising = p.f_end >= p.f_start;
            let f = |d| self.device.natural_frequency_hz_at(d);
            // Adjacent floats bracket the crossing; which of the two is below f's own rounding
            // noise there, so the lower (the smaller bias) is taken.
            let (a, _) = bisect(p.start, p.end, |d| (f(d) < target_hz) == rising);
            found = Some(a);
            true
        });
        match found {
            Some(offset) => Ok(self.device.equilibrium_at(offset)),
            None => {
                let range = self.tunable_range(margin)?;
                Err(TuneError::OutOfRange {
                    target_hz,
                    low_hz: range.low_hz,
                    high_hz: range.high_hz,
                })
            }
        }
    }

    /// Visit the monotone pieces of f on offsets `[0, max_offset]` (δ = λ − λ1p) in order
    /// of rising stretch, until `visit` returns true.
    fn for_each_piece(&self, max_offset: T, mut visit: impl FnMut(&Piece<T>) -> bool) {
        let f = |d| self.device.natural_frequency_hz_at(d);
        let start = T::zero();
        let x = |i: usize| max_offset * T::of(i as f64) / T::of(TUNING_SCAN_POINTS as f64);
        let mut piece_start = (start, f(start));
        let (mut before, mut prev) = (start, piece_start);
        let mut rising: Option<bool> = None;
        for i in 1..=TUNING_SCAN_POINTS {
            let cur = (x(i), f(x(i)));
            let step_rises = if cur.1 > prev.1 {
                Some(true)
            } else if cur.1 < prev.1 {
                Some(false)
            } else {
                None
            };
            if let (Some(was), Some(now)) = (rising, step_rises) {
                if was != now {
                    // A turning point in [before, cur]: a maximum if f was rising.
                    let sign = if was { T::one() } else { -T::one() };
                    let turn = argmax(before, cur.0, |l| sign * f(l)).max(piece_start.0);
                    let end = (turn, f(turn));
                    if visit(&Piece {
                        start: piece_start.0,
                        f_start: piece_start.1,
                        end: end.0,
                        f_end: end.1,
                    }) {
                        return;
                    }
                    piece_start = end;
                }
            }
            rising = step_rises.or(rising);
            before = prev.0;
            prev = cur;
        }
        visit(&Piece {
            start: piece_start.0,
            f_start: piece_start.1,
            end: prev.0,
            f_end: prev.1,
        });
    }
}
