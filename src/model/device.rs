//! Device parameters in SI units, their validation, and the dimensionless model they give
//! (model.md §§1–4, §9).

use core::fmt;

use super::failure::FailureMode;
use crate::model::material::Gent;
use crate::numerics::real::Real;

/// Vacuum permittivity ε0 in F/m (CODATA 2018).
pub const VACUUM_PERMITTIVITY: f64 = 8.854_187_812_8e-12;

/// The parameters of a resonator, SI units (model.md §1). Field names are the device file's keys.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DeviceParams<T> {
    /// μ, Pa.
    pub shear_modulus: T,
    /// Gent limit Jlim; `None` for neo-Hookean.
    pub jlim: Option<T>,
    /// εr; ε = εr·ε0.
    pub relative_permittivity: T,
    /// ρ, kg/m³.
    pub density: T,
    /// E_B, V/m.
    pub breakdown_field: T,
    /// H, m (undeformed).
    pub thickness: T,
    /// L1A, m: the active membrane, with electrodes.
    pub length_active: T,
    /// L1B, m: the passive membrane.
    pub length_passive: T,
    /// L2, m.
    pub width: T,
    /// m, kg: both bars together.
    pub bar_mass: T,
    /// λ1p.
    pub prestretch_1: T,
    /// λ2p.
    pub prestretch_2: T,
    /// c, N·s: viscous damping of model.md §4.
    pub damping: T,
}

/// The reference device of model.md §9 (VHB-4910-like).
pub const REFERENCE_DEVICE: DeviceParams<f64> = DeviceParams {
    shear_modulus: 45.0e3,
    jlim: Some(120.0),
    relative_permittivity: 4.7,
    density: 960.0,
    breakdown_field: 100.0e6,
    thickness: 1.0e-3,
    length_active: 20.0e-3,
    length_passive: 20.0e-3,
    width: 40.0e-3,
    bar_mass: 2.0e-3,
    prestretch_1: 2.0,
    prestretch_2: 2.0,
    damping: 0.0,
};

/// A parameter, named as in the device file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Field {
    ShearModulus,
    Jlim,
    RelativePermittivity,
    Density,
    BreakdownField,
    Thickness,
    LengthActive,
    LengthPassive,
    Width,
    BarMass,
    Prestretch1,
    Prestretch2,
    Damping,
}

impl Field {
    /// Every field, in `DeviceParams` order: the one list the table layout, device files,
    /// scenes and messages take theirs from.
    pub const ALL: [Field; 13] = [
        Field::ShearModulus,
        Field::Jlim,
        Field::RelativePermittivity,
        Field::Density,
        Field::BreakdownField,
        Field::Thickness,
        Field::LengthActive,
        Field::LengthPassive,
        Field::Width,
        Field::BarMass,
        Field::Prestretch1,
        Field::Prestretch2,
        Field::Damping,
    ];

    /// The field with this device-file key.
    pub fn from_key(key: &str) -> Option<Field> {
        Field::ALL.into_iter().find(|f| f.key() == key)
    }

    /// The device file's key for this field.
    pub fn key(self) -> &'static str {
        match self {
            Field::ShearModulus => "shear_modulus",
            Field::Jlim => "jlim",
            Field::RelativePermittivity => "relative_permittivity",
            Field::Density => "density",
            Field::BreakdownField => "breakdown_field",
            Field::Thickness => "thickness",
            Field::LengthActive => "length_active",
            Field::LengthPassive => "length_passive",
            Field::Width => "width",
            Field::BarMass => "bar_mass",
            Field::Prestretch1 => "prestretch_1",
            Field::Prestretch2 => "prestretch_2",
            Field::Damping => "damping",
        }
    }
}

/// What is wrong with a field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Problem {
    /// NaN or infinite (also: too large for the float type in use).
    NotFinite,
    /// Must be > 0.
    NotPositive,
    /// Must be ≥ 0.
    Negative,
    /// At zero bias membrane B has no tension in direction 1: needs λ1p²·λ2p > 1.
    NoTension1AtZeroBias,
    /// At zero bias the membranes have no tension in direction 2: needs λ2p²·λ1p > 1.
    NoTension2AtZeroBias,
    /// The pre-stretch already reaches the stretch limit: needs I1(λ1p, λ2p) < Jlim.
    StretchLimitAtZeroBias,
    /// A check of model.md §6 already fails at zero bias (a guard behind the specific checks
    /// above; the field named is the likeliest cause).
    UnsafeAtZeroBias { mode: FailureMode },
    /// The parameters are finite but, together, give a scale that is zero or not finite.
    DerivedNotFinite {
        /// The scale, e.g. `H·√(μ/ε)`.
        scale: &'static str,
    },
}

/// The derived scales a device's parameters must keep finite and positive
/// (`Problem::DerivedNotFinite`), in the order they are checked.
pub const SCALES: [&str; 5] = ["H·√(μ/ε)", "μ·L2·H/M", "E_B·√(ε/μ)", "L1A/L1B", "c·T0/M"];

/// A bad device parameter: which field, and what is wrong with it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParamError {
    pub field: Field,
    pub problem: Problem,
}

impl core::error::Error for ParamError {}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let why = match self.problem {
            Problem::NotFinite => "is NaN, infinite or too large",
            Problem::NotPositive => "must be greater than zero",
            Problem::Negative => "must not be negative",
            Problem::NoTension1AtZeroBias => {
                "leaves membrane B slack in direction 1 at zero bias \
                 (needs prestretch_1^2 * prestretch_2 > 1)"
            }
            Problem::NoTension2AtZeroBias => {
                "leaves the membranes slack in direction 2 at zero bias \
                 (needs prestretch_2^2 * prestretch_1 > 1)"
            }
            Problem::StretchLimitAtZeroBias => {
                "is already reached by the pre-stretch (needs I1(prestretch) < jlim)"
            }
            Problem::UnsafeAtZeroBias { mode } => {
                return write!(
                    f,
                    "device parameter `{}`: the device already fails at zero bias by {}",
                    self.field.key(),
                    mode.description()
                );
            }
            Problem::DerivedNotFinite { scale } => {
                return write!(
                    f,
                    "device parameter `{}` is out of proportion with the others: \
                     the scale {scale} is zero or not finite",
                    self.field.key()
                );
            }
        };
        write!(f, "device parameter `{}` {}", self.field.key(), why)
    }
}

/// A validated device: the dimensionless model of model.md §4 and the scales back to SI.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Device<T> {
    params: DeviceParams<T>,
    material: Gent<T>,
    /// L1A/L1B.
    length_ratio: T,
    /// Volts per unit of Φ̄ = (Φ/H)·√(ε/μ): H·√(μ/ε).
    volts_per_unit: T,
    /// Angular frequency per unit of dimensionless ω: 1/T0 = √(μ·L2·H/M), rad/s.
    rad_per_s_per_unit: T,
    /// Breakdown field in units of √(μ/ε).
    breakdown_field_dimless: T,
    /// c·T0/M.
    damping_dimless: T,
    /// s̄1, s̄2 and I1 at the pre-stretch: the checks near λ1p are these plus a factored
    /// difference (`Device::margins_on_branch_at`).
    at_prestretch: AtPrestretch<T>,
}

/// Stresses over μ and the first invariant of a membrane at the pre-stretch (λ1p, λ2p),
/// computed in f64 whatever `T`: near-slack devices (λ1p·λ2p² close to 1) have s̄2 there as
/// a cancellation f32 cannot resolve, and every check near λ1p starts from these values.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AtPrestretch<T> {
    pub stress_1: T,
    pub stress_2: T,
    pub first_invariant: T,
}

impl<T: Real> DeviceParams<T> {
    /// The same parameters in another float type (values too large for it become infinite,
    /// which validation then rejects).
    pub fn cast<U: Real>(&self) -> DeviceParams<U> {
        DeviceParams::from_values(self.values().map(|x| U::of(x.to_f64())))
    }

    /// The values in `Field::ALL` order, `jlim` 0 for neo-Hookean (the table's layout).
    pub fn values(&self) -> [T; 13] {
        Field::ALL.map(|field| self.get(field))
    }

    /// Parameters from values in `Field::ALL` order (`jlim` 0: neo-Hookean).
    pub fn from_values(values: [T; 13]) -> Self {
        let mut params = DeviceParams {
            shear_modulus: T::zero(),
            jlim: None,
            relative_permittivity: T::zero(),
            density: T::zero(),
            breakdown_field: T::zero(),
            thickness: T::zero(),
            length_active: T::zero(),
            length_passive: T::zero(),
            width: T::zero(),
            bar_mass: T::zero(),
            prestretch_1: T::zero(),
            prestretch_2: T::zero(),
            damping: T::zero(),
        };
        for (field, value) in Field::ALL.into_iter().zip(values) {
            params.set(field, value);
        }
        params
    }

    /// One field's value (`jlim` 0 for neo-Hookean).
    pub fn get(&self, field: Field) -> T {
        match field {
            Field::ShearModulus => self.shear_modulus,
            Field::Jlim => self.jlim.unwrap_or(T::zero()),
            Field::RelativePermittivity => self.relative_permittivity,
            Field::Density => self.density,
            Field::BreakdownField => self.breakdown_field,
            Field::Thickness => self.thickness,
            Field::LengthActive => self.length_active,
            Field::LengthPassive => self.length_passive,
            Field::Width => self.width,
            Field::BarMass => self.bar_mass,
            Field::Prestretch1 => self.prestretch_1,
            Field::Prestretch2 => self.prestretch_2,
            Field::Damping => self.damping,
        }
    }

    /// Set one field (`jlim` 0 is neo-Hookean, `None`).
    pub fn set(&mut self, field: Field, value: T) {
        let slot = match field {
            Field::ShearModulus => &mut self.shear_modulus,
            Field::Jlim => {
                self.jlim = (value != T::zero()).then_some(value);
                return;
            }
            Field::RelativePermittivity => &mut self.relative_permittivity,
            Field::Density => &mut self.density,
            Field::BreakdownField => &mut self.breakdown_field,
            Field::Thickness => &mut self.thickness,
            Field::LengthActive => &mut self.length_active,
            Field::LengthPassive => &mut self.length_passive,
            Field::Width => &mut self.width,
            Field::BarMass => &mut self.bar_mass,
            Field::Prestretch1 => &mut self.prestretch_1,
            Field::Prestretch2 => &mut self.prestretch_2,
            Field::Damping => &mut self.damping,
        };
        *slot = value;
    }

    /// Effective mass M = m·L1A + ρ·L2·H·L1A·L1/3 (model.md §4), kg·m.
    pub fn effective_mass(&self) -> T {
        let l1 = self.length_active + self.length_passive;
        self.bar_mass * self.length_active
            + self.density * self.width * self.thickness * self.length_active * l1 / T::of(3.0)
    }

    /// The damping c = M·ω0/Q that gives a small oscillation of `natural_hz` the quality
    /// factor `quality_factor` (model.md §4), N·s.
    pub fn damping_for_quality(&self, natural_hz: T, quality_factor: T) -> T {
        self.effective_mass() * T::of(core::f64::consts::TAU) * natural_hz / quality_factor
    }

    /// ε = εr·ε0, F/m.
    pub fn permittivity(&self) -> T {
        self.relative_permittivity * T::of(VACUUM_PERMITTIVITY)
    }

    /// Membrane A's capacitance per λ², F: C(λ) = this·λ² (model.md §8, paper eq. 1:
    /// C = ε·L1A·L2·λ²·λ2p²/H, λ2 held at λ2p).
    pub fn farads_per_stretch_squared(&self) -> T {
        self.permittivity()
            * self.length_active
            * self.width
            * self.prestretch_2
            * self.prestretch_2
            / self.thickness
    }

    /// Membrane A's capacitance at stretch λ, F (model.md §8).
    pub fn capacitance_farads(&self, stretch: T) -> T {
        self.farads_per_stretch_squared() * stretch * stretch
    }
}

impl<T: Real> Device<T> {
    /// Validate the parameters and build the model; the first bad field is named.
    pub fn new(params: DeviceParams<T>) -> Result<Self, ParamError> {
        let p = &params;
        let err = |field, problem| Err(ParamError { field, problem });
        let strictly_positive = [
            (Field::ShearModulus, p.shear_modulus),
            (Field::RelativePermittivity, p.relative_permittivity),
            (Field::Density, p.density),
            (Field::BreakdownField, p.breakdown_field),
            (Field::Thickness, p.thickness),
            (Field::LengthActive, p.length_active),
            (Field::LengthPassive, p.length_passive),
            (Field::Width, p.width),
            (Field::Prestretch1, p.prestretch_1),
            (Field::Prestretch2, p.prestretch_2),
        ];
        let non_negative = [(Field::BarMass, p.bar_mass), (Field::Damping, p.damping)];
        for (field, value) in strictly_positive {
            if !value.is_finite() {
                return err(field, Problem::NotFinite);
            }
            if !(value > T::zero()) {
                return err(field, Problem::NotPositive);
            }
        }
        for (field, value) in non_negative {
            if !value.is_finite() {
                return err(field, Problem::NotFinite);
            }
            if !(value >= T::zero()) {
                return err(field, Problem::Negative);
            }
        }
        let material = match p.jlim {
            None => Gent::neo_hookean(),
            Some(jlim) if !jlim.is_finite() => return err(Field::Jlim, Problem::NotFinite),
            Some(jlim) if !(jlim > T::zero()) => return err(Field::Jlim, Problem::NotPositive),
            Some(jlim) => Gent::with_jlim(jlim),
        };

        // Zero bias: both membranes at (λ1p, λ2p) must be taut and below the stretch limit.
        let (l1p, l2p) = (p.prestretch_1, p.prestretch_2);
        if !(l1p * l1p * l2p > T::one()) {
            return err(Field::Prestretch1, Problem::NoTension1AtZeroBias);
        }
        if !(l2p * l2p * l1p > T::one()) {
            return err(Field::Prestretch2, Problem::NoTension2AtZeroBias);
        }
        if !(material.lock_up_margin(l1p, l2p) > T::zero()) {
            return err(Field::Jlim, Problem::StretchLimitAtZeroBias);
        }

        // Square roots taken apart, so that μ/ε does not overflow before its root is taken.
        let (sqrt_mu, sqrt_eps) = (p.shear_modulus.sqrt(), p.permittivity().sqrt());
        let mass = p.effective_mass();
        let volts_per_unit = p.thickness * sqrt_mu / sqrt_eps;
        let rad_per_s_per_unit = sqrt_mu * (p.width * p.thickness / mass).sqrt();
        let breakdown_field_dimless = p.breakdown_field * sqrt_eps / sqrt_mu;
        let damping_dimless = p.damping / (mass * rad_per_s_per_unit);
        let length_ratio = p.length_active / p.length_passive;
        let [volts_scale, omega_scale, field_scale, length_scale, damping_scale] = SCALES;
        let derived = [
            (Field::ShearModulus, volts_scale, volts_per_unit),
            // Squared, so that ω² in rad²/s² is finite too.
            (Field::Density, omega_scale, rad_per_s_per_unit.squared()),
            (Field::BreakdownField, field_scale, breakdown_field_dimless),
            (Field::LengthPassive, length_scale, length_ratio),
        ];
        for (field, scale, value) in derived {
            if !value.is_finite() || !(value > T::zero()) {
                return err(field, Problem::DerivedNotFinite { scale });
            }
        }
        if !damping_dimless.is_finite() {
            let scale = damping_scale;
            return err(Field::Damping, Problem::DerivedNotFinite { scale });
        }
        let (a, b) = (l1p.to_f64(), l2p.to_f64());
        let wide = match p.jlim {
            None => Gent::<f64>::neo_hookean(),
            Some(jlim) => Gent::with_jlim(jlim.to_f64()),
        };
        let at_prestretch = AtPrestretch {
            stress_1: T::of(wide.stress_1(a, b)),
            stress_2: T::of(wide.stress_2(a, b)),
            first_invariant: T::of(Gent::<f64>::first_invariant(a, b)),
        };
        let device = Self {
            params,
            material,
            at_prestretch,
            length_ratio,
            volts_per_unit,
            rad_per_s_per_unit,
            breakdown_field_dimless,
            damping_dimless,
        };
        if let Some(mode) = device.margins(l1p, T::zero()).first_failure() {
            let field = match mode {
                FailureMode::LossOfTension2a | FailureMode::LossOfTension2b => Field::Prestretch2,
                FailureMode::Breakdown => Field::BreakdownField,
                FailureMode::StretchLimit => Field::Jlim,
                _ => Field::Prestretch1,
            };
            return err(field, Problem::UnsafeAtZeroBias { mode });
        }
        Ok(device)
    }

    /// The parameters this device was built from.
    pub fn params(&self) -> &DeviceParams<T> {
        &self.params
    }

    /// The membrane material.
    pub fn material(&self) -> &Gent<T> {
        &self.material
    }

    /// λ1p.
    pub fn prestretch_1(&self) -> T {
        self.params.prestretch_1
    }

    /// λ2p.
    pub fn prestretch_2(&self) -> T {
        self.params.prestretch_2
    }

    /// L1A/L1B.
    pub fn length_ratio(&self) -> T {
        self.length_ratio
    }

    /// Volts per unit of the dimensionless voltage Φ̄ = (Φ/H)·√(ε/μ).
    pub fn volts_per_unit(&self) -> T {
        self.volts_per_unit
    }

    /// Rad/s per unit of dimensionless angular frequency (1/T0, model.md §4).
    pub fn rad_per_s_per_unit(&self) -> T {
        self.rad_per_s_per_unit
    }

    /// Breakdown field E_B in units of √(μ/ε).
    pub fn breakdown_field_dimless(&self) -> T {
        self.breakdown_field_dimless
    }

    /// s̄1, s̄2 and I1 at the pre-stretch, computed in f64.
    pub fn at_prestretch(&self) -> &AtPrestretch<T> {
        &self.at_prestretch
    }

    /// Dimensionless damping c̄ = c·T0/M (model.md §4).
    pub fn damping_dimless(&self) -> T {
        self.damping_dimless
    }
}
