//! The f32 math the firmware runs, against f64 (the yardstick): the core's own kernels and
//! libm against micromath (named in the product design), over the arguments the firmware
//! sees. The worst errors printed here are BENCHMARKS.md's "micromath" table (with
//! `-- --nocapture`); the assertions hold the choice it led to.

use de_resonator::Real;
use micromath::F32Ext;

/// Worst absolute and relative error of `f32` against `f64` over `n` points of [lo, hi].
fn worst(
    lo: f64,
    hi: f64,
    n: usize,
    f: impl Fn(f32) -> f32,
    exact: impl Fn(f64) -> f64,
) -> (f64, f64) {
    let (mut abs, mut rel) = (0.0f64, 0.0f64);
    for k in 0..=n {
        let x = (lo + (hi - lo) * k as f64 / n as f64) as f32;
        let want = exact(f64::from(x));
        let got = f64::from(f(x));
        let e = (got - want).abs();
        abs = abs.max(e);
        if want != 0.0 {
            rel = rel.max(e / want.abs());
        }
    }
    (abs, rel)
}

#[test]
fn the_core_kernels_beat_micromath_on_accuracy() {
    let n = 200_000;
    let pi = std::f64::consts::PI;
    // The drive's sine: the phase's angle in [−π, π).
    let core_sin = worst(-pi, pi, n, <f32 as Real>::sin, f64::sin);
    let libm_sin = worst(-pi, pi, n, libm::sinf, f64::sin);
    let micro_sin = worst(-pi, pi, n, F32Ext::sin, f64::sin);
    let micro_cos = worst(-pi, pi, n, F32Ext::cos, f64::cos);
    // Square roots: stretches and their products (0.05 .. 50), volts² scales (1 .. 1e8).
    let libm_sqrt = worst(0.05, 1e8, n, libm::sqrtf, f64::sqrt);
    let micro_sqrt = worst(0.05, 1e8, n, F32Ext::sqrt, f64::sqrt);
    let micro_isqrt = worst(0.05, 1e8, n, F32Ext::invsqrt, |x| 1.0 / x.sqrt());
    let libm_isqrt = worst(0.05, 1e8, n, |x| 1.0 / libm::sqrtf(x), |x| 1.0 / x.sqrt());
    // The Gent model's log: ln(1 − (I1 − 3)/Jlim), argument in (0, 1].
    let libm_ln = worst(1e-6, 1.0, n, libm::logf, f64::ln);
    let micro_ln = worst(1e-6, 1.0, n, F32Ext::ln, f64::ln);
    let libm_exp = worst(-20.0, 20.0, n, libm::expf, f64::exp);
    let micro_exp = worst(-20.0, 20.0, n, F32Ext::exp, f64::exp);
    for (name, (abs, rel)) in [
        ("sin, the core's kernel", core_sin),
        ("sin, libm sinf", libm_sin),
        ("sin, micromath", micro_sin),
        ("cos, micromath", micro_cos),
        ("sqrt, libm sqrtf", libm_sqrt),
        ("sqrt, micromath", micro_sqrt),
        ("1/sqrt, 1 / libm sqrtf", libm_isqrt),
        ("1/sqrt, micromath invsqrt", micro_isqrt),
        ("ln on (0, 1], libm logf", libm_ln),
        ("ln on (0, 1], micromath", micro_ln),
        ("exp on [-20, 20], libm expf", libm_exp),
        ("exp on [-20, 20], micromath", micro_exp),
    ] {
        println!("{name:32} worst absolute {abs:.2e}, relative {rel:.2e}");
    }
    // The choice: micromath loses on accuracy wherever the firmware would use it, by orders
    // of magnitude (its functions are approximations for speed).
    assert!(core_sin.0 <= 3e-7 && micro_sin.0 > 100.0 * core_sin.0);
    assert!(libm_sqrt.1 <= 6e-8 && micro_sqrt.1 > 100.0 * libm_sqrt.1);
    assert!(micro_isqrt.1 > 100.0 * libm_isqrt.1);
    assert!(micro_ln.0 > 10.0 * libm_ln.0);
}

/// The tick's square root (`numerics::real::sqrt_f32`) within 1 ulp of the correctly rounded
/// root (f64's, rounded) on every exponent, subnormals included, and exact at the edges;
/// micromath's `sqrt` beside it for the record.
#[test]
fn the_ticks_square_root_is_within_an_ulp() {
    use de_resonator::numerics::real::sqrt_f32;
    let mut worst_ulps = 0u32;
    let mut worst_micromath = 0.0f64;
    let mut x = f32::from_bits(1);
    let mut rng = 0x2545_f491_4f6c_dd1du64;
    while x < f32::MAX / 4.0 {
        for _ in 0..64 {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            let v = x * (1.0 + (rng >> 41) as f32 / 8_388_608.0);
            let exact = (f64::from(v)).sqrt() as f32;
            let got = sqrt_f32(v);
            let ulps = got.to_bits().abs_diff(exact.to_bits());
            assert!(ulps <= 1, "√{v}: {got} against {exact}");
            worst_ulps = worst_ulps.max(ulps);
            let m = f64::from(F32Ext::sqrt(v));
            worst_micromath = worst_micromath.max((m / f64::from(v).sqrt() - 1.0).abs());
        }
        x *= 2.0;
    }
    assert_eq!(sqrt_f32(0.0), 0.0);
    assert_eq!(sqrt_f32(-0.0).to_bits(), (-0.0f32).to_bits());
    assert_eq!(sqrt_f32(f32::INFINITY), f32::INFINITY);
    assert!(sqrt_f32(-1.0).is_nan() && sqrt_f32(f32::NAN).is_nan());
    assert!(sqrt_f32(f32::NEG_INFINITY).is_nan());
    assert_eq!(sqrt_f32(4.0), 2.0);
    assert_eq!(sqrt_f32(1e-40 * 1e-40), 0.0);
    eprintln!(
        "sqrt_f32: worst {worst_ulps} ulp; micromath sqrt: worst relative {worst_micromath:.1e}"
    );
}

/// The drive's and the lock-in's sine and cosine of a phase in turns
/// (`numerics::real::sin_cos_turns`) against f64's, over every quadrant and its edges.
#[test]
fn sine_and_cosine_of_a_turn_are_within_3e_7() {
    use de_resonator::numerics::real::sin_cos_turns;
    let mut worst = 0.0f64;
    let mut check = |phase: u32| {
        let theta = f64::from(phase) * std::f64::consts::TAU / 4_294_967_296.0;
        let (s, c) = sin_cos_turns(phase);
        let e = (f64::from(s) - theta.sin())
            .abs()
            .max((f64::from(c) - theta.cos()).abs());
        assert!(e <= 3e-7, "phase {phase}: ({s}, {c}) against θ = {theta}");
        worst = worst.max(e);
    };
    for k in 0..=65_536u32 {
        check(k.wrapping_mul(65_537).wrapping_add(k));
    }
    for edge in 0..8u32 {
        for d in [0u32, 1, 2, 1000] {
            check((edge << 29).wrapping_add(d));
            check((edge << 29).wrapping_sub(d));
        }
    }
    assert_eq!(sin_cos_turns(0), (0.0, 1.0));
    eprintln!("sin_cos_turns: worst {worst:.1e}");
}
