//! The drive's swing (model.md §7, `Device::check_swing`) term by term against values worked
//! out apart from it: the linear response of the oracle's SI model (its stiffness, force and
//! damping by differences of model.md §4's λ''), Mathieu's first tongue, the equilibrium's
//! voltage, the breakdown field, a linear oscillator's ramp ring and its decay.

mod common;

use std::f64::consts::TAU;

use common::oracle::*;
use common::with_quality_factor;
use de_resonator::{
    AcDrive, Device, DeviceParams, FailureMode, Ramp, Resonance, Swing, SwingError, Tuner,
    REFERENCE_DEVICE,
};

/// The ramp's ring is counted at 1.25 times its linear estimate (docs/safety.md).
const RING_ALLOWANCE: f64 = 1.25;

/// `check_swing` with the bias searched up to the first limit but breakdown (so that a
/// bias past breakdown is checked, not refused for its equilibrium).
fn check(
    p: DeviceParams<f64>,
    drive: AcDrive<f64>,
    quality_factor: Option<f64>,
    margin: f64,
) -> Result<Swing<f64>, SwingError<f64>> {
    let unbroken = DeviceParams {
        breakdown_field: 1e12,
        ..p
    };
    let limit = *Tuner::new(Device::new(unbroken).unwrap()).limit();
    Device::new(p)
        .unwrap()
        .check_swing(drive, limit.at.offset, quality_factor, margin)
}

/// An AC of `ac_volts` at `ac_rad_per_s` on `bias_volts`, no ramp.
fn ac(bias_volts: f64, ac_volts: f64, ac_rad_per_s: f64) -> AcDrive<f64> {
    AcDrive {
        ring_stretch: 0.0,
        bias_volts,
        ac_volts,
        ac_hz: ac_rad_per_s / TAU,
        amplifier_bandwidth_hz: f64::INFINITY,
        ramp: None,
    }
}

/// The oracle's linearisation about the equilibrium of `bias_volts` (model.md §§4–5, SI).
struct Linear {
    /// λ*.
    stretch: f64,
    /// ω², 1/s².
    stiffness: f64,
    /// ∂λ''/∂Φ², 1/(V²·s²), and its derivative in λ (∂ω²/∂Φ² with the sign turned).
    force: f64,
    force_slope: f64,
    /// c/M, 1/s.
    damping: f64,
}

impl Linear {
    fn at(p: &DeviceParams<f64>, bias_volts: f64) -> Self {
        let stretch = equilibrium_stretch(p, bias_volts).unwrap();
        let force = force_per_volt_squared(p, stretch);
        Self {
            stretch,
            stiffness: omega_squared_fd(p, stretch, bias_volts),
            force,
            // The force is Φ²·λ times a constant (model.md §4).
            force_slope: force / stretch,
            damping: damping_rate(p),
        }
    }

    fn omega(&self) -> f64 {
        self.stiffness.sqrt()
    }

    /// |ω² − w² + i·(c/M)·w|: a forced term's denominator at `w`.
    fn denominator(&self, w: f64) -> f64 {
        ((self.stiffness - w * w).powi(2) + (self.damping * w).powi(2)).sqrt()
    }

    /// The settled amplitude at Ω of Φa on Φ0: the force 2·Φ0·Φa·∂λ''/∂Φ² over the
    /// denominator.
    fn first(&self, bias: f64, ac: f64, w: f64) -> f64 {
        2.0 * self.force * bias * ac / self.denominator(w)
    }

    /// The force at 2Ω (and the steady push's): Φa²/2 through ∂λ''/∂Φ², and the motion at Ω
    /// times the force's Ω term through its slope in λ (the mean of 2·Φ0·Φa·x1·sin², in
    /// phase below the resonance).
    fn second_force(&self, bias: f64, ac: f64, w: f64) -> f64 {
        self.force * ac * ac / 2.0 + self.force_slope * bias * ac * self.first(bias, ac, w)
    }
}

/// The reference device damped to Q 100 at zero bias.
fn damped() -> DeviceParams<f64> {
    with_quality_factor(REFERENCE_DEVICE, 100.0)
}

/// `damped()` with a breakdown field low enough to be its first limit (near 5.9 kV).
fn breakdown_limited() -> DeviceParams<f64> {
    DeviceParams {
        breakdown_field: 25e6,
        ..damped()
    }
}

/// The field in A, V/m (model.md §6.5).
fn field(p: &DeviceParams<f64>, volts: f64, stretch: f64) -> f64 {
    volts * stretch * p.prestretch_2 / p.thickness
}

#[test]
fn the_equilibrium_frequency_and_q_are_the_oracles() {
    let p = damped();
    for bias in [1000.0, 5000.0, 8000.0] {
        let lin = Linear::at(&p, bias);
        let s = check(p, ac(bias, 0.0, 1.0), None, 0.05).unwrap();
        assert!(
            rel(s.stretch, lin.stretch) < 1e-12,
            "{bias} V: λ* {}",
            s.stretch
        );
        assert!(rel(s.natural_hz, lin.omega() / TAU) < 1e-6, "{bias} V");
        // Q = ω·M/c at the bias, the file's damping.
        assert!(rel(s.quality_factor, lin.omega() / lin.damping) < 1e-6);
        // A measured Q replaces the file's; none (or not positive) leaves it.
        let measured = check(p, ac(bias, 0.0, 1.0), Some(37.0), 0.05).unwrap();
        assert!(rel(measured.quality_factor, 37.0) < 1e-12);
        for q in [0.0, -3.0] {
            let s = check(p, ac(bias, 0.0, 1.0), Some(q), 0.05).unwrap();
            assert!(rel(s.quality_factor, lin.omega() / lin.damping) < 1e-6);
        }
    }
}

/// A small AC: the swing below λ* is the harmonic term, each forced term switched on from
/// rest overshooting by Ω/ω (the undamped beat), the rest of second order.
#[test]
fn the_harmonic_term_is_the_linear_response_with_its_beat() {
    let p = damped();
    for bias in [2000.0, 5000.0, 8000.0] {
        let lin = Linear::at(&p, bias);
        for ratio in [0.1, 0.3, 0.8, 1.5, 3.0] {
            let w = ratio * lin.omega();
            let s = check(p, ac(bias, 1.0, w), None, 0.05).unwrap();
            let expected = lin.first(bias, 1.0, w) * (1.0 + ratio);
            let got = s.stretch - s.low_stretch;
            assert!(
                rel(got, expected) < 2e-3,
                "{bias} V, Ω/ω {ratio}: {got} against {expected}"
            );
        }
    }
    // With Q measured instead: the same term at that damping.
    let lin = Linear::at(&REFERENCE_DEVICE, 5000.0);
    let w = 0.9 * lin.omega();
    let s = check(REFERENCE_DEVICE, ac(5000.0, 1.0, w), Some(20.0), 0.05).unwrap();
    let damped = Linear {
        damping: lin.omega() / 20.0,
        ..lin
    };
    let expected = damped.first(5000.0, 1.0, w) * 1.9;
    assert!(rel(s.stretch - s.low_stretch, expected) < 2e-3);
}

/// Behind a first-order amplifier (`amplifier_bandwidth_hz`), the harmonic term is the lesser
/// of two bounds: as commanded, X·(1 + Ω/ω) (the output a weighted mean of the command's
/// past); at the output, g·X·(1 + max(1, Ω/ω)) (its sine started at phase −φ) and twice the
/// static deflection of its decaying term g·sin φ·e^(−t/τ), X and the statics the oracle's.
/// Against a second method: the linear oscillator of the oracle's ω², c/M and force behind
/// the simulated amplifier from rest (RK4, three envelope times): its largest swing never
/// above the bound, and at least 35% of it (37–99% measured).
#[test]
fn the_harmonic_term_behind_the_amplifier_is_the_lesser_bound() {
    let p = damped();
    let bias = 5000.0;
    let lin = Linear::at(&p, bias);
    let mut lesser_at_output = 0;
    for ratio in [0.3, 0.8, 1.0, 1.5, 3.0] {
        let w = ratio * lin.omega();
        for x in [0.2, 1.0, 5.0] {
            let bandwidth_hz = w / TAU / x;
            let drive = AcDrive {
                amplifier_bandwidth_hz: bandwidth_hz,
                ..ac(bias, 1.0, w)
            };
            let s = check(p, drive, None, 0.05).unwrap();
            let got = s.stretch - s.low_stretch;
            let first = lin.first(bias, 1.0, w);
            let gain = 1.0 / (1.0 + x * x).sqrt();
            let lag_sin = x * gain;
            let statics = 2.0 * lin.force * bias * 1.0 / lin.stiffness;
            let commanded = first * (1.0 + ratio);
            let at_output = gain * first * (1.0 + ratio.max(1.0)) + 2.0 * gain * lag_sin * statics;
            let expected = commanded.min(at_output);
            lesser_at_output += usize::from(at_output < commanded);
            assert!(
                rel(got, expected) < 2e-3,
                "Ω/ω {ratio}, f/f_c {x}: {got} against {expected}"
            );
            // The second method.
            let tau = 1.0 / (TAU * bandwidth_hz);
            let force = 2.0 * lin.force * bias;
            let dt = (TAU / w).min(TAU / lin.omega()).min(tau) / 200.0;
            let steps = (3.0 * 2.0 / lin.damping / dt) as usize;
            let deriv = |t: f64, [x1, v, y]: [f64; 3]| {
                let command = (w * t).sin();
                [
                    v,
                    -lin.stiffness * x1 - lin.damping * v + force * y,
                    (command - y) / tau,
                ]
            };
            let (mut state, mut worst) = ([0.0f64; 3], 0.0f64);
            for k in 0..steps {
                let t = k as f64 * dt;
                let add = |a: [f64; 3], b: [f64; 3], h: f64| {
                    [a[0] + h * b[0], a[1] + h * b[1], a[2] + h * b[2]]
                };
                let k1 = deriv(t, state);
                let k2 = deriv(t + dt / 2.0, add(state, k1, dt / 2.0));
                let k3 = deriv(t + dt / 2.0, add(state, k2, dt / 2.0));
                let k4 = deriv(t + dt, add(state, k3, dt));
                for i in 0..3 {
                    state[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
                }
                worst = worst.max(state[0].abs());
            }
            assert!(
                worst <= expected * (1.0 + 1e-3) && worst >= 0.35 * expected,
                "Ω/ω {ratio}, f/f_c {x}: simulated {worst} against {expected}"
            );
        }
    }
    // The output's bound decides somewhere, the command's elsewhere.
    assert!((1..15).contains(&lesser_at_output), "{lesser_at_output}");
    // A bandwidth that is no bandwidth (0, negative, NaN) is none: the command's bound.
    let none = check(p, ac(bias, 1.0, lin.omega()), None, 0.05).unwrap();
    for bandwidth_hz in [0.0, -45.0, f64::NAN] {
        let drive = AcDrive {
            amplifier_bandwidth_hz: bandwidth_hz,
            ..ac(bias, 1.0, lin.omega())
        };
        assert_eq!(check(p, drive, None, 0.05).unwrap(), none, "{bandwidth_hz}");
    }
}

/// The swing above λ* exceeds the one below by twice the steady push: the drive's mean
/// Φa²/2 and the motion at Ω fed back through the force's slope, over the stiffness under
/// the drive's mean Φ0² + Φa²/2.
#[test]
fn the_steady_push_is_the_drives_mean_over_the_stiffness_under_it() {
    let p = damped();
    for (bias, ac_volts, ratio) in [
        (5000.0, 1000.0, 5.0),
        (5000.0, 300.0, 0.3),
        (3000.0, 1500.0, 4.0),
        (7000.0, 500.0, 0.5),
    ] {
        let lin = Linear::at(&p, bias);
        let w = ratio * lin.omega();
        let s = check(p, ac(bias, ac_volts, w), None, 0.05).unwrap();
        let mean_volts = (bias * bias + ac_volts * ac_volts / 2.0).sqrt();
        let under_mean = omega_squared_fd(&p, lin.stretch, mean_volts);
        let expected = lin.second_force(bias, ac_volts, w) / under_mean;
        let got = ((s.high_stretch - s.stretch) - (s.stretch - s.low_stretch)) / 2.0;
        assert!(
            rel(got, expected) < 0.01,
            "{bias} V + {ac_volts} V at Ω/ω {ratio}: {got} against {expected}"
        );
    }
}

/// Near Ω = ω/2 the force at 2Ω meets the resonance (super-harmonic): the swing is both
/// forced terms with their beats.
#[test]
fn the_super_harmonic_term_is_the_2_omega_force_at_resonance() {
    let p = damped();
    let bias = 5000.0;
    let lin = Linear::at(&p, bias);
    for detuning in [-0.01, 0.0, 0.01] {
        let ratio = 0.5 * (1.0 + detuning);
        let w = ratio * lin.omega();
        let ac_volts = 200.0;
        let s = check(p, ac(bias, ac_volts, w), None, 0.05).unwrap();
        let second = lin.second_force(bias, ac_volts, w) / lin.denominator(2.0 * w);
        let first = lin.first(bias, ac_volts, w);
        assert!(
            second > 0.3 * first,
            "the 2Ω term is a share: {second}, {first}"
        );
        let expected = first * (1.0 + ratio) + second * (1.0 + 2.0 * ratio);
        let got = s.stretch - s.low_stretch;
        assert!(
            rel(got, expected) < 0.01,
            "{detuning}: {got} against {expected}"
        );
    }
}

/// Mathieu's first tongue: a stiffness modulated by the depth h at ν = 2ω(1 + δ) grows the
/// motion at rate ω·√(h²/16 − δ²) against the damping's (c/M)/2, so the swing has no bound
/// from h = 4·√(ζ² + δ²) on. The drive's term at Ω modulates ω² by 2·Φ0·Φa·∂ω²/∂Φ².
#[test]
fn the_parametric_threshold_is_mathieus_first_tongue() {
    let p = damped();
    for bias in [3000.0, 6000.0] {
        let lin = Linear::at(&p, bias);
        let zeta = lin.damping / (2.0 * lin.omega());
        for delta in [0.0, zeta] {
            let w = 2.0 * lin.omega() * (1.0 + delta);
            let depth = 4.0 * (zeta * zeta + delta * delta).sqrt();
            let threshold = depth * lin.stiffness / (2.0 * bias * lin.force_slope);
            let verdict = |ac_volts: f64| check(p, ac(bias, ac_volts, w), None, 0.05);
            let parametric = |r: &Result<_, _>| {
                matches!(
                    r,
                    Err(SwingError::Unbounded {
                        resonance: Resonance::Parametric,
                        ..
                    })
                )
            };
            let above = verdict(1.02 * threshold);
            assert!(parametric(&above), "{bias} V, δ {delta}: {above:?}");
            let below = verdict(0.98 * threshold);
            assert!(!parametric(&below), "{bias} V, δ {delta}: {below:?}");
            let message = above.unwrap_err().to_string();
            assert!(message.contains("parametric resonance"), "{message}");
        }
    }
}

/// Near Ω = 2ω the stiffness is also modulated at Ω by the motion's own swing through its
/// slope, dω²/dλ·x1 (the membrane stiffens as it stretches): the depth the tongue sees is
/// the drive's and that, so any bound ends below the drive's own threshold, where
/// 2·Φ0·Φa·∂ω²/∂Φ² + |dω²/dλ|·x1(Φa) reaches 4·ζ·ω² (δ = 0).
#[test]
fn the_motions_own_modulation_pumps_too() {
    // Gent devices whose lock-up is near: the stiffness's slope is large there.
    for (jlim, share_of_limit) in [(12.0, 0.6), (16.0, 0.6), (12.0, 0.5)] {
        let p = DeviceParams {
            jlim: Some(jlim),
            ..damped()
        };
        let bias = share_of_limit * Tuner::new(Device::new(p).unwrap()).limit().at.volts;
        let lin = Linear::at(&p, bias);
        let h = 1e-3 * lin.stretch;
        let slope = (omega_squared_fd(&p, lin.stretch + h, bias)
            - omega_squared_fd(&p, lin.stretch - h, bias))
            / (2.0 * h);
        let zeta = lin.damping / (2.0 * lin.omega());
        let w = 2.0 * lin.omega();
        // The depth per volt of AC: the drive's and the motion's.
        let per_volt = 2.0 * bias * lin.force_slope + slope.abs() * lin.first(bias, 1.0, w);
        let threshold = 4.0 * zeta * lin.stiffness / per_volt;
        let drive_only = 4.0 * zeta * lin.stiffness / (2.0 * bias * lin.force_slope);
        assert!(
            threshold < 0.9 * drive_only,
            "Jlim {jlim}: the motion's share counts ({threshold} V against {drive_only} V)"
        );
        let unbounded = |ac_volts: f64| {
            matches!(
                check(p, ac(bias, ac_volts, w), None, 0.05),
                Err(SwingError::Unbounded { .. })
            )
        };
        // Near the threshold the swing grows without bound and the stiffness band it spans
        // widens (round by round, until both its ends settle): the check's threshold lies
        // below the linear one (7–9% here, where the stiffness bends most), never above.
        assert!(unbounded(1.03 * threshold), "Jlim {jlim}, {bias} V");
        assert!(
            unbounded(0.97 * threshold),
            "Jlim {jlim}, {bias} V: the band bends"
        );
        assert!(!unbounded(0.85 * threshold), "Jlim {jlim}, {bias} V");
    }
}

/// The drive's mean Φ0² + Φa²/2 takes the stiffness to zero where ω² under it vanishes:
/// Φa² = 2·ω²/(∂ω²/∂Φ²) at λ*, far above any other limit, and said as such.
#[test]
fn a_mean_that_leaves_no_stiffness_is_said() {
    let p = damped();
    for bias in [2000.0, 6000.0] {
        let lin = Linear::at(&p, bias);
        // ∂ω²/∂Φ² = λ2p²·(the force per Φ² per λ): the oracle's ω² at two voltages.
        let per_volt_squared =
            (omega_squared_fd(&p, lin.stretch, 0.0) - lin.stiffness) / (bias * bias);
        let threshold_fd = (2.0 * lin.stiffness / per_volt_squared).sqrt();
        let at = |ac_volts: f64| check(p, ac(bias, ac_volts, 3.0 * lin.omega()), None, 0.05);
        match at(1.01 * threshold_fd) {
            Err(SwingError::Unbounded {
                resonance: Resonance::Static,
                largest_ac_volts,
                ..
            }) => assert!(largest_ac_volts < threshold_fd),
            other => panic!("{bias} V: {other:?}"),
        }
        let message = at(1.01 * threshold_fd).unwrap_err().to_string();
        assert!(message.contains("no stiffness left"), "{message}");
        let below = at(0.7 * threshold_fd);
        assert!(
            !matches!(
                below,
                Err(SwingError::Unbounded {
                    resonance: Resonance::Static,
                    ..
                })
            ),
            "{bias} V: {below:?}"
        );
    }
}

/// No AC: the swing is the point λ*, checked under the bias raised to Φ0/(1 − margin). On a
/// device whose first limit is breakdown the largest bias that passes solves
/// Φ/(1 − m)·λ*(Φ)·λ2p/H = E_B.
#[test]
fn the_margin_raises_the_voltage_the_checks_see() {
    let p = breakdown_limited();
    for margin in [0.0, 0.05, 0.2] {
        let (mut low, mut high) = (0.0, 20_000.0);
        for _ in 0..100 {
            let mid = 0.5 * (low + high);
            let crosses = match equilibrium_stretch(&p, mid) {
                Some(l) => field(&p, mid / (1.0 - margin), l) >= p.breakdown_field,
                None => true,
            };
            if crosses {
                high = mid;
            } else {
                low = mid;
            }
        }
        let ok = check(p, ac(low * (1.0 - 1e-6), 0.0, 1.0), None, margin);
        assert!(ok.is_ok(), "margin {margin}: {ok:?}");
        let crossed = check(p, ac(low * (1.0 + 1e-6), 0.0, 1.0), None, margin);
        assert!(
            matches!(
                crossed,
                Err(SwingError::Crosses {
                    mode: FailureMode::Breakdown,
                    ..
                })
            ),
            "margin {margin}: {crossed:?}"
        );
    }
}

/// With an AC the checks see the peak (Φ0 + Φa)/(1 − m) over the swing's box widened by
/// 1/(1 − m) about λ*: on the breakdown-limited device a drive crosses exactly where the
/// field at the widened box's top under the raised peak reaches E_B (the field grows with
/// λ). The swing's extremes are the function's own (pinned above); the widening, the peak
/// and the verdict are checked here.
#[test]
fn the_peak_and_the_box_are_widened_by_the_margin() {
    let p = breakdown_limited();
    for (bias, ratio, margin) in [(4000.0, 0.7, 0.05), (4500.0, 3.0, 0.1), (3000.0, 0.3, 0.2)] {
        let lin = Linear::at(&p, bias);
        let w = ratio * lin.omega();
        let mut changed = 0;
        let mut last = None;
        for n in 0..400 {
            let ac_volts = 5.0 * n as f64 + 1.0;
            let (low_stretch, high_stretch, fits) =
                match check(p, ac(bias, ac_volts, w), None, margin) {
                    Ok(s) => (s.low_stretch, s.high_stretch, true),
                    Err(SwingError::Crosses {
                        mode: FailureMode::Breakdown,
                        low_stretch,
                        high_stretch,
                        ..
                    }) => (low_stretch, high_stretch, false),
                    Err(other) => panic!("{bias} V + {ac_volts} V: {other:?}"),
                };
            let widen = 1.0 / (1.0 - margin);
            let top = lin.stretch + (high_stretch - lin.stretch) * widen;
            let peak = (bias + ac_volts) * widen;
            let crosses = field(&p, peak, top) / p.breakdown_field;
            assert!(low_stretch < lin.stretch);
            // The verdict agrees with the field except within the box's sampling and the
            // equilibrium's last digits of the threshold.
            if (crosses - 1.0).abs() > 1e-9 {
                assert_eq!(
                    fits,
                    crosses < 1.0,
                    "{bias} V + {ac_volts} V: E/E_B {crosses}"
                );
            }
            if last.is_some_and(|was| was != fits) {
                changed += 1;
            }
            last = Some(fits);
        }
        assert_eq!(
            changed, 1,
            "{bias} V at Ω/ω {ratio}: the verdict turns once ({last:?})"
        );
    }
}

/// The largest AC that fits, given when a drive does not: it fits, and a hair more does not.
#[test]
fn the_largest_ac_that_fits_is_the_edge() {
    let p = breakdown_limited();
    let lin = Linear::at(&p, 4000.0);
    for ratio in [0.5, 0.97, 2.0] {
        let drive = ac(4000.0, 3000.0, ratio * lin.omega());
        let largest = match check(p, drive, None, 0.05) {
            Err(SwingError::Crosses {
                largest_ac_volts, ..
            })
            | Err(SwingError::Unbounded {
                largest_ac_volts, ..
            }) => largest_ac_volts,
            other => panic!("{ratio}: {other:?}"),
        };
        assert!(largest > 0.0 && largest < 3000.0, "{ratio}: {largest}");
        let at = |volts: f64| {
            check(
                p,
                AcDrive {
                    ac_volts: volts,
                    ..drive
                },
                None,
                0.05,
            )
        };
        assert!(at(largest).is_ok(), "{ratio}: {largest} V");
        assert!(at(largest + 3000.0 * 1e-6).is_err(), "{ratio}: {largest} V");
    }
    // Where the bias alone crosses, no AC fits.
    let top = Tuner::new(Device::new(p).unwrap()).limit().at.volts;
    match check(p, ac(0.99 * top, 100.0, lin.omega() * 3.0), None, 0.05) {
        Err(SwingError::Crosses {
            largest_ac_volts, ..
        }) => assert_eq!(largest_ac_volts, 0.0),
        other => panic!("{other:?}"),
    }
}

/// The oracle's dΦ/dλ on the loading branch at λ, V per unit stretch (Φ = √(Φ²(λ))).
fn volts_per_stretch(p: &DeviceParams<f64>, l: f64) -> f64 {
    let h = 1e-7 * l;
    (bias_squared(p, l + h).sqrt() - bias_squared(p, l - h).sqrt()) / (2.0 * h)
}

/// A ramp at the slew rate between two biases, no AC: the swing is the ring it leaves. A
/// linear oscillator whose equilibrium starts (or stops) moving at v leaves a ring of v/ω;
/// the equilibrium moves at slew/(dΦ/dλ). Both ends summed, never more than the step, at
/// the documented allowance.
#[test]
fn a_ramps_ring_is_its_kinks_or_its_step() {
    let p = damped();
    let (from, to) = (2000.0, 5000.0);
    let (l_from, l_to) = (
        equilibrium_stretch(&p, from).unwrap(),
        equilibrium_stretch(&p, to).unwrap(),
    );
    let kink = |l: f64, volts: f64, slew: f64| {
        slew / (volts_per_stretch(&p, l) * omega_squared_fd(&p, l, volts).sqrt())
    };
    let ramp = |slew: f64, settle_seconds: f64, after_descent: bool| AcDrive {
        bias_volts: to,
        ac_volts: 0.0,
        ac_hz: 1.0,
        amplifier_bandwidth_hz: f64::INFINITY,
        ring_stretch: 0.0,
        ramp: Some(Ramp {
            from_volts: from,
            slew_volts_per_second: slew,
            settle_seconds,
            after_descent,
        }),
    };
    let ring = |drive| {
        let s = check(p, drive, None, 0.05).unwrap();
        let (above, below) = (s.high_stretch - s.stretch, s.stretch - s.low_stretch);
        assert!((above - below).abs() < 1e-14, "{above} {below}");
        s.high_stretch - s.stretch
    };
    for slew in [1e3, 1e4, 3e4] {
        let expected = RING_ALLOWANCE * (kink(l_from, from, slew) + kink(l_to, to, slew));
        assert!(expected < l_to - l_from, "a slow ramp");
        let got = ring(ramp(slew, 0.0, false));
        assert!(
            rel(got, expected) < 1e-3,
            "{slew} V/s: {got} against {expected}"
        );
        // Down the same way: the same kinks.
        let down = AcDrive {
            bias_volts: from,
            ramp: Some(Ramp {
                from_volts: to,
                ..ramp(slew, 0.0, false).ramp.unwrap()
            }),
            ..ramp(slew, 0.0, false)
        };
        assert!(rel(ring(down), expected) < 1e-3);
    }
    // Faster than the membrane: the step itself.
    let got = ring(ramp(1e9, 0.0, false));
    assert!(rel(got, RING_ALLOWANCE * (l_to - l_from)) < 1e-6, "{got}");
    // No step, no ring.
    let none = AcDrive {
        ramp: Some(Ramp {
            from_volts: to,
            ..ramp(1e4, 0.0, false).ramp.unwrap()
        }),
        ..ramp(1e4, 0.0, false)
    };
    assert_eq!(ring(none), 0.0);
}

/// The ring decays over the hold as a damped oscillator's envelope, e^(−ω·t/(2Q)); a ring
/// left by a way down before the ramp is counted undecayed.
#[test]
fn a_rings_decay_over_the_hold_and_after_a_descent() {
    let p = damped();
    let (from, to) = (2000.0, 5000.0);
    let lin = Linear::at(&p, to);
    let q = lin.omega() / lin.damping;
    let ring = |settle_seconds: f64, after_descent: bool, quality_factor: Option<f64>| {
        let drive = AcDrive {
            bias_volts: to,
            ac_volts: 0.0,
            ac_hz: 1.0,
            amplifier_bandwidth_hz: f64::INFINITY,
            ring_stretch: 0.0,
            ramp: Some(Ramp {
                from_volts: from,
                slew_volts_per_second: 1e4,
                settle_seconds,
                after_descent,
            }),
        };
        let s = check(p, drive, quality_factor, 0.05).unwrap();
        s.high_stretch - s.stretch
    };
    let fresh = ring(0.0, false, None);
    for t in [0.01, 0.1, 0.5] {
        let expected = fresh * (-lin.omega() * t / (2.0 * q)).exp();
        assert!(rel(ring(t, false, None), expected) < 1e-5, "{t} s");
        // A measured Q sets the rate.
        let measured = fresh * (-lin.omega() * t / (2.0 * 10.0)).exp();
        assert!(
            rel(ring(t, false, Some(10.0)), measured) < 1e-5,
            "{t} s, Q 10"
        );
        // After a way down: that ring undecayed on top.
        assert!(rel(ring(t, true, None), expected + fresh) < 1e-5, "{t} s");
    }
    // A hold below zero is none.
    assert!(rel(ring(-1.0, false, None), fresh) < 1e-12);
    assert!(rel(ring(0.0, true, None), 2.0 * fresh) < 1e-12);
}

/// The rings the oracle's SI model leaves after a ramp at the slew rate (RK4 on model.md
/// §4 with the bias a ramp) stay within the prediction, and the prediction is not loose by
/// more than the ramp's phase and the allowance can explain.
#[test]
fn the_predicted_ring_bounds_the_simulated_one() {
    let p = damped();
    let (from, to) = (2000.0, 5000.0);
    let (l_from, l_to) = (
        equilibrium_stretch(&p, from).unwrap(),
        equilibrium_stretch(&p, to).unwrap(),
    );
    let gamma = damping_rate(&p);
    for slew in [3e3, 1e4, 4e4] {
        let predicted = {
            let drive = AcDrive {
                bias_volts: to,
                ac_volts: 0.0,
                ac_hz: 1.0,
                amplifier_bandwidth_hz: f64::INFINITY,
                ring_stretch: 0.0,
                ramp: Some(Ramp {
                    from_volts: from,
                    slew_volts_per_second: slew,
                    settle_seconds: 0.0,
                    after_descent: false,
                }),
            };
            let s = check(p, drive, None, 0.05).unwrap();
            s.high_stretch - s.stretch
        };
        // RK4 from rest at λ*(from); the ring: the largest |λ − λ*(to)| in the 50 ms after
        // the ramp ends.
        let ramp_seconds = (to - from) / slew;
        let dt = 2e-6;
        let volts = |t: f64| (from + slew * t).min(to);
        let f = |t: f64, (l, v): (f64, f64)| (v, acceleration(&p, l, volts(t)) - gamma * v);
        let (mut t, mut y) = (0.0, (l_from, 0.0));
        let mut ring: f64 = 0.0;
        while t < ramp_seconds + 0.05 {
            let k1 = f(t, y);
            let k2 = f(t + dt / 2.0, (y.0 + dt / 2.0 * k1.0, y.1 + dt / 2.0 * k1.1));
            let k3 = f(t + dt / 2.0, (y.0 + dt / 2.0 * k2.0, y.1 + dt / 2.0 * k2.1));
            let k4 = f(t + dt, (y.0 + dt * k3.0, y.1 + dt * k3.1));
            y.0 += dt / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
            y.1 += dt / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
            t += dt;
            if t >= ramp_seconds {
                ring = ring.max((y.0 - l_to).abs());
            }
        }
        assert!(
            ring < predicted,
            "{slew} V/s: {ring} simulated, {predicted} predicted"
        );
        assert!(
            ring > 0.02 * predicted,
            "{slew} V/s: {ring} simulated, {predicted} predicted"
        );
    }
}

/// The refusal's words: the resonance, the limit and, where no damping is known, how to
/// give one.
#[test]
fn a_refusal_says_what_and_how_to_mend_it() {
    let p = REFERENCE_DEVICE;
    let lin = Linear::at(&p, 5000.0);
    let message = check(p, ac(5000.0, 10.0, lin.omega()), None, 0.05)
        .unwrap_err()
        .to_string();
    assert!(message.contains("harmonic resonance"), "{message}");
    assert!(message.contains("give the device's damping"), "{message}");
    let damped = breakdown_limited();
    let crossed = check(damped, ac(5500.0, 300.0, 0.3 * lin.omega()), None, 0.05)
        .unwrap_err()
        .to_string();
    assert!(crossed.contains("breakdown"), "{crossed}");
    assert!(!crossed.contains("no damping known"), "{crossed}");
    let undamped = DeviceParams {
        damping: 0.0,
        ..damped
    };
    let crossed = check(undamped, ac(5500.0, 300.0, 3.1 * lin.omega()), None, 0.05)
        .unwrap_err()
        .to_string();
    assert!(crossed.contains("no damping known"), "{crossed}");
}

/// A ring already there before a ramp (a drive's before a new plan) rides through it with
/// the ramp's documented allowance of 1.25 (the stiffness changes along the ramp), on top
/// of the ramp's own ring.
#[test]
fn a_ring_through_a_ramp_is_counted_with_the_allowance() {
    let p = damped();
    let ramp = Some(Ramp {
        from_volts: 2000.0,
        slew_volts_per_second: 1e4,
        settle_seconds: 0.0,
        after_descent: false,
    });
    let ring = |ring_stretch: f64| {
        let drive = AcDrive {
            ring_stretch,
            ramp,
            ..ac(5000.0, 0.0, 1.0)
        };
        let s = check(p, drive, None, 0.05).unwrap();
        s.high_stretch - s.stretch
    };
    let own = ring(0.0);
    for carried in [1e-4, 2e-3] {
        assert!(
            rel(ring(carried), own + RING_ALLOWANCE * carried) < 1e-9,
            "{carried}"
        );
    }
}

/// A ring already there when the AC starts (a trim's last pulse) rides under the swing
/// undecayed: alone, it is the swing; under a small AC far from any resonance, it adds to
/// the harmonic term's amplitude as it is.
#[test]
fn a_ring_already_there_adds_to_the_swing() {
    let p = damped();
    let lin = Linear::at(&p, 5000.0);
    for ring_stretch in [1e-4, 3e-3] {
        let alone = check(
            p,
            AcDrive {
                ring_stretch,
                ..ac(5000.0, 0.0, 1.0)
            },
            None,
            0.05,
        )
        .unwrap();
        assert!(rel(alone.high_stretch - alone.stretch, ring_stretch) < 1e-9);
        assert!(rel(alone.stretch - alone.low_stretch, ring_stretch) < 1e-9);
        let w = 0.3 * lin.omega();
        let with = check(
            p,
            AcDrive {
                ring_stretch,
                ..ac(5000.0, 1.0, w)
            },
            None,
            0.05,
        )
        .unwrap();
        let expected = lin.first(5000.0, 1.0, w) * 1.3 + ring_stretch;
        assert!(rel(with.stretch - with.low_stretch, expected) < 2e-3);
    }
}

/// A refusal names the resonance that amplifies the swing most, where one does more than
/// twice: the drive at f0 (harmonic: the forced term over its damping, Q-fold), at f0/2
/// (super-harmonic: the 2Ω term Q-fold), at 2·f0 (parametric: pumped more than twice, from
/// half Mathieu's threshold on), and none far from all three (0.3·f0: 1.1-fold at most).
/// Each at the least AC (in steps of 10%) whose swing crosses breakdown.
#[test]
fn a_refusal_names_the_resonance_that_amplifies_most() {
    let p = breakdown_limited();
    let named = |bias: f64, ratio: f64, from_volts: f64, to_volts: f64| {
        let lin = Linear::at(&p, bias);
        let mut ac_volts = from_volts;
        while ac_volts < to_volts {
            match check(p, ac(bias, ac_volts, ratio * lin.omega()), None, 0.05) {
                Ok(_) => ac_volts *= 1.1,
                Err(SwingError::Crosses { resonance, .. }) => return resonance,
                Err(other) => panic!("Ω/ω {ratio}, {ac_volts} V on {bias} V: {other:?}"),
            }
        }
        panic!("Ω/ω {ratio} on {bias} V: nothing up to {to_volts} V crosses")
    };
    assert_eq!(named(4000.0, 1.0, 1.0, 1e3), Some(Resonance::Harmonic));
    assert_eq!(
        named(4000.0, 0.5, 10.0, 4e3),
        Some(Resonance::SuperHarmonic)
    );
    assert_eq!(named(4000.0, 0.3, 10.0, 4e3), None);
    // Near breakdown, where a swing pumped between half and all of the threshold crosses.
    let bias = 5500.0;
    let lin = Linear::at(&p, bias);
    let zeta = lin.damping / (2.0 * lin.omega());
    let threshold = 4.0 * zeta * lin.stiffness / (2.0 * bias * lin.force_slope);
    assert_eq!(
        named(bias, 2.0, 0.5 * threshold, 0.97 * threshold),
        Some(Resonance::Parametric)
    );
}

/// Where the stiffness changes over the swing (a Gent device near its lock-up stiffens as
/// it stretches), each forced term is taken at the worst stiffness the widened swing
/// visits: below the resonance, the softest, at the box's low end under the drive's mean
/// Φ0² + Φa²/2. The prediction is at least the linear response there.
#[test]
fn a_swing_is_counted_at_the_softest_stiffness_it_visits() {
    let p = DeviceParams {
        jlim: Some(12.0),
        ..damped()
    };
    let bias = 0.6 * Tuner::new(Device::new(p).unwrap()).limit().at.volts;
    let lin = Linear::at(&p, bias);
    let (margin, ratio) = (0.05, 0.85);
    let w = ratio * lin.omega();
    for ac_volts in [300.0, 600.0] {
        let s = check(p, ac(bias, ac_volts, w), None, margin).unwrap();
        let low_end = s.stretch - (s.stretch - s.low_stretch) / (1.0 - margin);
        let mean_volts = (bias * bias + ac_volts * ac_volts / 2.0).sqrt();
        let softest = omega_squared_fd(&p, low_end, mean_volts);
        assert!(
            softest < 0.99 * lin.stiffness,
            "the stiffness changes over the swing"
        );
        let there = Linear {
            stiffness: softest,
            ..Linear::at(&p, bias)
        };
        let least = there.first(bias, ac_volts, w) * (1.0 + w / softest.sqrt());
        assert!(
            s.stretch - s.low_stretch >= 0.999 * least,
            "{ac_volts} V: {} against {least}",
            s.stretch - s.low_stretch
        );
    }
}

/// The long fuzz's membrane (10⁸ ticks, seed 62: pre-stretched 0.967, it lost tension 1 on
/// the rebound after a dead bus's drop), undamped.
fn fuzzed_membrane() -> de_resonator::DeviceParams<f64> {
    de_resonator::DeviceParams {
        shear_modulus: 980050.0,
        jlim: None,
        relative_permittivity: 7.069533348083496,
        density: 815.9725341796875,
        breakdown_field: 274862912.0,
        thickness: 0.000157674599904567,
        length_active: 0.007408554200083017,
        length_passive: 0.02995372749865055,
        width: 0.088212750852108,
        bar_mass: 0.014267484657466412,
        prestretch_1: 0.966606855392456,
        prestretch_2: 1.3772172927856445,
        damping: 0.0,
    }
}

/// The lowest stretch an undamped drop to 0 V from `stretch` moving at `velocity` (dλ/dτ)
/// reaches, by RK4 (f64, 10 µs steps) on the model at no field, to its first turn below the
/// rest (two of its periods at most); and the first check of model.md §6 it fails on the
/// way, if any.
fn simulated_drop(
    device: &de_resonator::Device<f64>,
    stretch: f64,
    velocity: f64,
) -> (f64, Option<de_resonator::FailureMode>) {
    use de_resonator::{Drive, Integrator, Method, State};
    let start = State { stretch, velocity };
    let (drive, range) = (Drive::constant(device, 0.0), device.model_range());
    let mut m = Integrator::new(*device, drive, Method::Rk4, 1e-5, range, start, true).unwrap();
    let period = 1.0 / device.natural_frequency_hz_at(0.0);
    let (mut lowest, mut failed) = (stretch, None);
    for _ in 0..(2.0 * period / 1e-5) as usize {
        if m.step().is_err() {
            return (
                f64::NEG_INFINITY,
                failed.or(Some(de_resonator::FailureMode::LossOfTension1)),
            );
        }
        let now = m.state();
        lowest = lowest.min(now.stretch);
        failed = failed.or(device.first_failure(now.stretch, 0.0));
        if now.velocity > 0.0 && now.stretch < device.prestretch_1() {
            break;
        }
    }
    (lowest, failed)
}

/// The drop with the swing the membrane had (`check_drop`'s `swing_stretch`): from anywhere
/// on a swing of 0.05 about the reference device's equilibrium at 60% of its limit, at the
/// swing's speed there (ω·√(s² − x²), ω at the bias), RK4's rebound never goes below the
/// check's, and the worst of 16 phases comes within 15% of the check's extra depth over the
/// drop from rest. The refusal's figures: the highest stretch the top plus the swing, the
/// lowest the rebound widened by 1/(1 − margin); with the margin, a rebound refused exactly
/// where the one found without it, widened, fails §6 (the long fuzz's membrane, scanned);
/// no drop from 0 V (the rest), and no equilibrium for a voltage that is no number.
#[test]
fn a_dead_bus_drop_counts_the_swing_and_the_margin() {
    use de_resonator::{Device, DeviceParams, SwingError, Tuner, REFERENCE_DEVICE};
    let device = Device::new(DeviceParams {
        damping: 0.0,
        ..REFERENCE_DEVICE
    })
    .unwrap();
    let limit = *Tuner::new(device).limit();
    let volts = 0.6 * limit.at.volts;
    let offset = device.offset_for_bias(volts, limit.at.offset).unwrap();
    let top = device.stretch_at(offset);
    let swing = 0.05;
    let still = device.check_drop(volts, 0.0, limit.at.offset, 0.0).unwrap();
    let moving = device
        .check_drop(volts, swing, limit.at.offset, 0.0)
        .unwrap();
    // In the model's time (`State::velocity` is dλ/dτ): ω̄ at the bias.
    let bias = volts / device.volts_per_unit();
    let omega = device.stiffness_dimless(top, bias * bias).sqrt();
    let mut worst = f64::INFINITY;
    for k in 0..16 {
        let phase = k as f64 * std::f64::consts::TAU / 16.0;
        let (lowest, _) = simulated_drop(
            &device,
            top + swing * phase.cos(),
            -omega * swing * phase.sin(),
        );
        assert!(
            lowest >= moving - 1e-3 * (top - still),
            "{phase}: {lowest} < {moving}"
        );
        worst = worst.min(lowest);
    }
    assert!(worst < still, "{worst} {still}");
    assert!(
        (still - worst) >= 0.85 * (still - moving) - 1e-3,
        "{still} {worst} {moving}"
    );
    // The bound's energy exactly: released at the swing's top, λ* + s, moving at the
    // swing's speed ω·s (up), RK4's rebound is the check's, on this device and 12 random
    // ones, each from 30% and 60% of its limit with a swing of a tenth and a third of the
    // step (the speed's share of the energy, 1–10%).
    let mut rng = common::Rng(0x2545_f491_4f6c_dd1d);
    let mut devices = vec![REFERENCE_DEVICE];
    devices.extend((0..12).map(|_| common::random_device(&mut rng)));
    let mut compared = 0;
    for p in devices {
        let device = Device::new(DeviceParams { damping: 0.0, ..p }).unwrap();
        let limit = *Tuner::new(device).limit();
        for (share, part) in [(0.3, 0.1), (0.6, 0.33)] {
            let volts = share * limit.at.volts;
            let Some(offset) = device.offset_for_bias(volts, limit.at.offset) else {
                continue;
            };
            let top = device.stretch_at(offset);
            let step = top - device.prestretch_1();
            let swing = part * step;
            let bias = volts / device.volts_per_unit();
            let omega = device.stiffness_dimless(top, bias * bias).sqrt();
            let (lowest, failed) = simulated_drop(&device, top + swing, omega * swing);
            let (Ok(turn), Ok(from_rest), None) = (
                device.check_drop(volts, swing, limit.at.offset, 0.0),
                device.check_drop(volts, 0.0, limit.at.offset, 0.0),
                failed,
            ) else {
                continue;
            };
            assert!(
                (turn - lowest).abs() <= 2e-3 * (from_rest - turn).abs().max(step * 0.1),
                "{p:?} from {volts} V, swing {swing}: {turn} against {lowest} (from rest {from_rest})"
            );
            compared += 1;
        }
    }
    assert!(compared >= 16, "{compared}");

    // The figures and the margin, on the long fuzz's membrane.
    let fuzzed = fuzzed_membrane();
    let device = Device::new(fuzzed).unwrap();
    let limit = *Tuner::new(device).limit();
    let rest = device.prestretch_1();
    let margin = 0.05;
    let (mut refused, mut taken) = (0, 0);
    for k in 1..=40 {
        let volts = k as f64 / 40.0 * 0.99 * limit.at.volts;
        let top = device.stretch_at(device.offset_for_bias(volts, limit.at.offset).unwrap());
        let bare = device.check_drop(volts, 0.0, limit.at.offset, 0.0);
        let widened = bare.map(|turn| rest - (rest - turn) / (1.0 - margin));
        let expect_ok = matches!(widened, Ok(low) if device.first_failure(low, 0.0).is_none()
            && device.first_failure(top, 0.0).is_none());
        match device.check_drop(volts, 0.0, limit.at.offset, margin) {
            Ok(_) => {
                assert!(expect_ok, "{volts}");
                taken += 1;
            }
            Err(SwingError::Crosses {
                low_stretch,
                high_stretch,
                ..
            }) => {
                assert!(!expect_ok, "{volts}");
                assert!((high_stretch - top).abs() < 1e-9, "{high_stretch} {top}");
                if let Ok(low) = widened {
                    assert!((low_stretch - low).abs() < 1e-9, "{low_stretch} {low}");
                }
                refused += 1;
            }
            Err(other) => panic!("{volts}: {other:?}"),
        }
    }
    assert!(refused > 0 && taken > 0, "{refused} {taken}");
    assert_eq!(
        device.check_drop(0.0, 0.0, limit.at.offset, margin),
        Ok(rest)
    );
    assert!(matches!(
        device.check_drop(f64::NAN, 0.0, limit.at.offset, margin),
        Err(SwingError::NoEquilibrium { .. })
    ));
}

/// A dead DAC bus's drop (`Device::check_drop`): released from rest at the equilibrium of a
/// bias, at no field, the membrane rebounds to where the elastic energy at no field has
/// taken all it had. Against RK4 on the model (a second method): the reference device, the
/// `sensorless-soft` device and 30 random devices, from 30%, 60% and 90% of their limit:
/// the rebound within 1/500 of the drop's step (the energy's trapezoid steps are 1/128 of
/// it, the turn found inside the last) wherever both reach it; and the long fuzz's membrane (pre-stretched 0.967, seed 62),
/// refused from 90% of its limit for loss of tension 1, which RK4's drop crosses too.
#[test]
fn a_dead_bus_drop_rebounds_where_the_energy_says() {
    use de_resonator::{Device, DeviceParams, FailureMode, SwingError, Tuner, REFERENCE_DEVICE};
    let soft = DeviceParams {
        shear_modulus: 45e3,
        jlim: Some(120.0),
        prestretch_1: 1.5,
        prestretch_2: 3.0,
        length_passive: 0.06,
        damping: 0.0,
        ..REFERENCE_DEVICE
    };
    let mut rng = common::Rng(0x5851_f42d_4c95_7f2d);
    let mut devices = vec![REFERENCE_DEVICE, soft];
    devices.extend((0..30).map(|_| common::random_device(&mut rng)));
    let mut compared = 0;
    for p in devices {
        let device = Device::new(DeviceParams { damping: 0.0, ..p }).unwrap();
        let limit = *Tuner::new(device).limit();
        for share in [0.3, 0.6, 0.9] {
            let volts = share * limit.at.volts;
            let Some(top) = device.offset_for_bias(volts, limit.at.offset) else {
                continue;
            };
            let top = device.stretch_at(top);
            let (lowest, failed) = simulated_drop(&device, top, 0.0);
            if let (Ok(turn), None) = (device.check_drop(volts, 0.0, limit.at.offset, 0.0), failed)
            {
                let step = top - device.prestretch_1();
                assert!(
                    (turn - lowest).abs() <= 2e-3 * step,
                    "{p:?} from {volts} V: {turn} against {lowest}"
                );
                compared += 1;
            }
        }
    }
    assert!(compared >= 60, "{compared}");

    let fuzzed = fuzzed_membrane();
    let device = Device::new(fuzzed).unwrap();
    let limit = *Tuner::new(device).limit();
    let volts = 0.9 * limit.at.volts;
    let refused = device.check_drop(volts, 0.0, limit.at.offset, 0.05);
    assert!(
        matches!(
            refused,
            Err(SwingError::Crosses {
                mode: FailureMode::LossOfTension1,
                ..
            })
        ),
        "{refused:?}"
    );
    let top = device.stretch_at(device.offset_for_bias(volts, limit.at.offset).unwrap());
    assert!(simulated_drop(&device, top, 0.0).1.is_some());
}
