//! A batch of membranes: the device file's values with a tolerance on each (model.md §10).
//!
//! A [`DeviceBox`] holds every parameter in a closed range [low, high] around the nominal
//! device; the exact box (no tolerance) is the nominal device alone, and every answer for it
//! is the nominal answer to the last digit.

use core::fmt;

use crate::model::device::{Device, DeviceParams, Field, ParamError};

/// A tolerance as a device file writes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spread {
    /// ± this fraction of the nominal value (0.10 for ±10%), in [0, 1).
    Relative(f64),
    /// An absolute range [low, high] in the field's SI unit, holding the nominal value.
    Range { low: f64, high: f64 },
}

/// What is wrong with a tolerance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ToleranceError {
    /// A relative tolerance outside [0, 1) or not a number.
    RelativeOutOfRange { field: Field, fraction: f64 },
    /// A range whose ends are not finite or are out of order.
    BadRange { field: Field, low: f64, high: f64 },
    /// A range that does not hold the device's own value.
    NominalOutside {
        field: Field,
        nominal: f64,
        low: f64,
        high: f64,
    },
    /// A tolerance on `jlim` for a neo-Hookean device (no `jlim` to vary).
    NoJlim,
    /// An end of a range is not a valid value for the field (a device there would be refused).
    BadEnd { error: ParamError, value: f64 },
}

impl fmt::Display for ToleranceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ToleranceError::RelativeOutOfRange { field, fraction } => write!(
                f,
                "tolerance `{}` = {fraction}: a relative tolerance is a fraction in [0, 1) \
                 (0.1 for ±10%), or write a range [low, high]",
                field.key()
            ),
            ToleranceError::BadRange { field, low, high } => write!(
                f,
                "tolerance `{}` = [{low}, {high}]: a range needs finite ends, low ≤ high",
                field.key()
            ),
            ToleranceError::NominalOutside {
                field,
                nominal,
                low,
                high,
            } => write!(
                f,
                "tolerance `{}` = [{low}, {high}] does not hold the device's own value {nominal}",
                field.key()
            ),
            ToleranceError::NoJlim => write!(
                f,
                "tolerance `jlim`: the device is neo-Hookean (no jlim); give jlim to vary it"
            ),
            ToleranceError::BadEnd { error, value } => {
                write!(f, "the tolerance's end {value}: {error}")
            }
        }
    }
}

impl core::error::Error for ToleranceError {}

/// Every device a batch can produce: each parameter independently anywhere in
/// [`low`, `high`], SI units, the nominal device inside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeviceBox {
    pub nominal: DeviceParams<f64>,
    pub low: DeviceParams<f64>,
    pub high: DeviceParams<f64>,
}

impl DeviceBox {
    /// The nominal device alone (no tolerance).
    pub fn exact(nominal: DeviceParams<f64>) -> Self {
        Self {
            nominal,
            low: nominal,
            high: nominal,
        }
    }

    /// This box with `field` spread as given; each end must be a valid value of the field
    /// (checked with the nominal device's other values).
    pub fn with(mut self, field: Field, spread: Spread) -> Result<Self, ToleranceError> {
        let nominal = self.nominal.get(field);
        if field == Field::Jlim && self.nominal.jlim.is_none() {
            return Err(ToleranceError::NoJlim);
        }
        let (low, high) = match spread {
            Spread::Relative(fraction) => {
                if !(0.0..1.0).contains(&fraction) {
                    return Err(ToleranceError::RelativeOutOfRange { field, fraction });
                }
                (nominal * (1.0 - fraction), nominal * (1.0 + fraction))
            }
            Spread::Range { low, high } => {
                if !(low.is_finite() && high.is_finite() && low <= high) {
                    return Err(ToleranceError::BadRange { field, low, high });
                }
                if !(low <= nominal && nominal <= high) {
                    return Err(ToleranceError::NominalOutside {
                        field,
                        nominal,
                        low,
                        high,
                    });
                }
                (low, high)
            }
        };
        for value in [low, high] {
            let mut end = self.nominal;
            end.set(field, value);
            if let Err(error) = Device::new(end) {
                return Err(ToleranceError::BadEnd { error, value });
            }
        }
        self.low.set(field, low);
        self.high.set(field, high);
        Ok(self)
    }

    /// Whether the box is the nominal device alone.
    pub fn is_exact(&self) -> bool {
        self.low == self.nominal && self.high == self.nominal
    }

    /// The fields with a tolerance (a range of non-zero width).
    pub fn spread_fields(&self) -> impl Iterator<Item = Field> + '_ {
        Field::ALL
            .into_iter()
            .filter(|&f| self.high.get(f) > self.low.get(f))
    }

    /// The box with `field` held at one value (its low or high end, for a parameter whose
    /// worst end is known).
    pub fn pinned(&self, field: Field, value: f64) -> Self {
        let mut out = *self;
        out.low.set(field, value);
        out.high.set(field, value);
        out
    }
}
