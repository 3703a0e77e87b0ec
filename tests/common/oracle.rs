//! The oracle: an independent, plain-SI restatement of model.md §§2–4 (no dimensionless
//! scaling, no code shared with the core beyond the parameter struct and ε0), and checks written
//! from the model's rules (the way down at the slew rate). What a test asserts against.

use de_resonator::model::device::VACUUM_PERMITTIVITY;
use de_resonator::DeviceParams;

/// The Gent limit as a number (∞ for neo-Hookean).
fn jlim(p: &DeviceParams<f64>) -> f64 {
    p.jlim.unwrap_or(f64::INFINITY)
}

pub fn first_invariant(l1: f64, l2: f64) -> f64 {
    l1 * l1 + l2 * l2 + 1.0 / (l1 * l1 * l2 * l2)
}

/// Free energy density Ws, J/m³ (model.md §3).
pub fn energy(p: &DeviceParams<f64>, l1: f64, l2: f64) -> f64 {
    let x = first_invariant(l1, l2) - 3.0;
    match p.jlim {
        None => 0.5 * p.shear_modulus * x,
        Some(j) => -0.5 * p.shear_modulus * j * (1.0 - x / j).ln(),
    }
}

/// Nominal stress s1, Pa.
pub fn s1(p: &DeviceParams<f64>, l1: f64, l2: f64) -> f64 {
    p.shear_modulus * (l1 - l1.powi(-3) * l2.powi(-2))
        / (1.0 - (first_invariant(l1, l2) - 3.0) / jlim(p))
}

/// Nominal stress s2, Pa.
pub fn s2(p: &DeviceParams<f64>, l1: f64, l2: f64) -> f64 {
    p.shear_modulus * (l2 - l1.powi(-2) * l2.powi(-3))
        / (1.0 - (first_invariant(l1, l2) - 3.0) / jlim(p))
}

pub fn permittivity(p: &DeviceParams<f64>) -> f64 {
    p.relative_permittivity * VACUUM_PERMITTIVITY
}

pub fn length_1(p: &DeviceParams<f64>) -> f64 {
    p.length_active + p.length_passive
}

/// λB from the fixed total length (model.md §2).
pub fn passive_stretch(p: &DeviceParams<f64>, l: f64) -> f64 {
    (length_1(p) * p.prestretch_1 - p.length_active * l) / p.length_passive
}

/// M = m·L1A + ρ·L2·H·L1A·L1/3, kg·m (model.md §4).
pub fn effective_mass(p: &DeviceParams<f64>) -> f64 {
    p.bar_mass * p.length_active
        + p.density * p.width * p.thickness * p.length_active * length_1(p) / 3.0
}

/// λ'' from model.md §4 at rest (no damping), 1/s².
pub fn acceleration(p: &DeviceParams<f64>, l: f64, volts: f64) -> f64 {
    let l2p = p.prestretch_2;
    let field = volts / p.thickness;
    p.width
        * p.thickness
        * (s1(p, passive_stretch(p, l), l2p) - s1(p, l, l2p)
            + permittivity(p) * field * field * l * l2p * l2p)
        / effective_mass(p)
}

/// ω² = −∂λ''/∂λ at fixed voltage, by a central difference.
pub fn omega_squared_fd(p: &DeviceParams<f64>, l: f64, volts: f64) -> f64 {
    let h = 1e-5 * l;
    -(acceleration(p, l + h, volts) - acceleration(p, l - h, volts)) / (2.0 * h)
}

/// Natural frequency in Hz from `omega_squared_fd`.
pub fn frequency_fd(p: &DeviceParams<f64>, l: f64, volts: f64) -> f64 {
    omega_squared_fd(p, l, volts).sqrt() / std::f64::consts::TAU
}

/// Φ² that holds stretch λ in equilibrium, V² (λ'' = 0 solved for Φ²).
pub fn bias_squared(p: &DeviceParams<f64>, l: f64) -> f64 {
    let l2p = p.prestretch_2;
    (s1(p, l, l2p) - s1(p, passive_stretch(p, l), l2p)) * p.thickness * p.thickness
        / (permittivity(p) * l * l2p * l2p)
}

/// Relative difference.
pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The way down (issue 25): from `from_volts`, never up, at most one slew step (`step_volts`)
/// and one DAC step (`lsb_volts`) down a tick, at 0 V within the ticks the slew needs (and
/// one for the rounding) and there from then on. `volts` are the ticks after `from_volts`.
pub fn assert_way_down(volts: &[f32], from_volts: f32, step_volts: f32, lsb_volts: f32) {
    let needed = (from_volts / step_volts).ceil() as usize + 1;
    let mut last = from_volts;
    for (n, &v) in volts.iter().enumerate() {
        assert!(
            v <= last,
            "tick {n} of the way down: up from {last} V to {v} V"
        );
        assert!(
            last - v <= step_volts + lsb_volts,
            "tick {n} of the way down: {last} V to {v} V, a slew step is {step_volts} V"
        );
        assert!(n < needed || v == 0.0, "tick {n} of the way down: {v} V");
        last = v;
    }
    assert!(volts.len() >= needed, "{} ticks checked", volts.len());
}

/// λ* held by `volts` on the loading branch (model.md §5): Φ²(λ) rises from 0 at λ1p to the
/// fold; found by stepping up from λ1p and halving. `None` past the fold.
pub fn equilibrium_stretch(p: &DeviceParams<f64>, volts: f64) -> Option<f64> {
    let target = volts * volts;
    let (mut below, mut step) = (p.prestretch_1, 1e-3 * p.prestretch_1);
    let mut last = 0.0;
    loop {
        let next = below + step;
        let v2 = bias_squared(p, next);
        if v2.is_nan() || v2 <= last || passive_stretch(p, next) <= 0.0 {
            return None;
        }
        if v2 >= target {
            let mut above = next;
            for _ in 0..200 {
                let mid = 0.5 * (below + above);
                if bias_squared(p, mid) < target {
                    below = mid;
                } else {
                    above = mid;
                }
            }
            return Some(0.5 * (below + above));
        }
        below = next;
        last = v2;
        step *= 1.05;
    }
}

/// ∂λ''/∂(Φ²) at stretch λ, 1/(V²·s²): the electrostatic force per volt squared (model.md
/// §4, linear in Φ², so the difference is exact).
pub fn force_per_volt_squared(p: &DeviceParams<f64>, l: f64) -> f64 {
    acceleration(p, l, 1.0) - acceleration(p, l, 0.0)
}

/// c/M, 1/s: the damping's rate in λ'' (model.md §4).
pub fn damping_rate(p: &DeviceParams<f64>) -> f64 {
    p.damping / effective_mass(p)
}
