//! Host speed, side by side in one run (criterion): `cargo bench -p host-sim`.
//!
//! - `rk4_step`: one step of the core's RK4 in f32 (as on the target) and f64, against a
//!   baseline, a textbook RK4 on the same right-hand side with none of the integrator's
//!   checks (range guard, finiteness, tick time). Goal: f32 under 150 ns.
//! - `one_second`: one simulated second of the reference device (6000 V bias, 600 V AC at
//!   0.9·f0) by the reference DOP853 at 1e-10 (goal under 2 ms), by BDF at 1e-10, and by the
//!   core's RK4 in f64 at 64 steps a period.
//! - `guaranteed`: a batch's certified limit (model.md §10) for the reference device with 4
//!   and with 8 parameters toleranced (goal under 1 s each), against the uncertified peer
//!   an engineer would write: the limit at every corner of the box (2⁴ and 2⁸ devices).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use de_resonator::{Device, Drive, Integrator, Method, Real, State, REFERENCE_DEVICE};
use host_sim::engine::solver::{solve, Solver, Tolerance};

const BIAS_VOLTS: f64 = 6000.0;
const AC_VOLTS: f64 = 600.0;

/// The reference device at the bench's bias: the device, the equilibrium stretch, f0 (Hz).
fn operating_point() -> (Device<f64>, f64, f64) {
    let device = Device::new(REFERENCE_DEVICE).expect("reference device");
    let stretch = device
        .stretch_for_bias(BIAS_VOLTS, device.scan_end_stretch())
        .expect("equilibrium");
    (device, stretch, device.natural_frequency_hz(stretch))
}

fn integrator<T: Real>(method: Method) -> Integrator<T> {
    let (device64, stretch, f0) = operating_point();
    let device = Device::new(REFERENCE_DEVICE.cast::<T>()).expect("reference device");
    let drive = Drive::from_volts(&device, T::of(BIAS_VOLTS), T::of(AC_VOLTS), T::of(0.9 * f0));
    let range = device64.model_range();
    let start = State {
        stretch: T::of(stretch),
        velocity: T::zero(),
    };
    let step = T::of(1.0 / (64.0 * f0));
    Integrator::new(
        device,
        drive,
        method,
        step,
        (T::of(range.0), T::of(range.1)),
        start,
        false,
    )
    .expect("a stable step")
}

/// Textbook RK4 on the same equation of motion, no checks: the baseline.
fn textbook_rk4(
    device: &Device<f64>,
    drive: &Drive<f64>,
    s: State<f64>,
    tau: f64,
    h: f64,
) -> State<f64> {
    let f = |s: State<f64>, t: f64| {
        let a = device.acceleration(s, drive.bias_dimless_squared_at(t));
        (s.velocity, a)
    };
    let at = |s: State<f64>, k: (f64, f64), c: f64| State {
        stretch: s.stretch + c * k.0,
        velocity: s.velocity + c * k.1,
    };
    let k1 = f(s, tau);
    let k2 = f(at(s, k1, 0.5 * h), tau + 0.5 * h);
    let k3 = f(at(s, k2, 0.5 * h), tau + 0.5 * h);
    let k4 = f(at(s, k3, h), tau + h);
    State {
        stretch: s.stretch + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
        velocity: s.velocity + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
    }
}

fn rk4_step(c: &mut Criterion) {
    // Every measured step starts from the same fresh state: stepping on for the hundreds of
    // millions of iterations criterion runs would push the drive phase τ·Ω past 1e6 rad,
    // where libm's argument reduction for sin takes its slow path.
    let mut group = c.benchmark_group("rk4_step");
    fn one<T: Real>(b: &mut criterion::Bencher, method: Method) {
        let fresh = integrator::<T>(method);
        b.iter_batched_ref(|| fresh, |it| black_box(it.step()), BatchSize::SmallInput)
    }
    group.bench_function("core_f32", |b| one::<f32>(b, Method::Rk4));
    group.bench_function("core_f64", |b| one::<f64>(b, Method::Rk4));
    group.bench_function("verlet_f32", |b| one::<f32>(b, Method::Verlet));
    group.bench_function("implicit_midpoint_f32", |b| {
        one::<f32>(b, Method::ImplicitMidpoint)
    });
    let (device, stretch, f0) = operating_point();
    let drive = Drive::from_volts(&device, BIAS_VOLTS, AC_VOLTS, 0.9 * f0);
    let h = device.rad_per_s_per_unit() / (64.0 * f0);
    let state = State {
        stretch,
        velocity: 0.0,
    };
    group.bench_function("baseline_textbook_f64", |b| {
        b.iter(|| textbook_rk4(&device, &drive, black_box(state), black_box(h), h))
    });
    group.finish();
}

fn one_second(c: &mut Criterion) {
    let (device, stretch, f0) = operating_point();
    let drive = Drive::from_volts(&device, BIAS_VOLTS, AC_VOLTS, 0.9 * f0);
    let end = device.rad_per_s_per_unit();
    let y0 = [stretch, 0.0];
    let mut group = c.benchmark_group("one_second");
    group.bench_function("reference_dop853_1e-10", |b| {
        b.iter(|| {
            solve(
                Solver::Dop853,
                &device,
                drive,
                black_box(y0),
                end,
                end,
                Tolerance::both(1e-10),
            )
        })
    });
    // BDF is in builds with the `bdf` feature (`cargo bench -p host-sim --features bdf`).
    #[cfg(feature = "bdf")]
    group.bench_function("reference_bdf_1e-10", |b| {
        let tolerance = Tolerance::both(1e-10);
        b.iter(|| {
            solve(
                Solver::Bdf,
                &device,
                drive,
                black_box(y0),
                end,
                end,
                tolerance,
            )
        })
    });
    let steps = (64.0 * f0).round() as u64;
    group.bench_function("core_rk4_f64_64_per_period", |b| {
        b.iter(|| {
            let mut it = integrator::<f64>(Method::Rk4);
            for _ in 0..steps {
                let _ = black_box(it.step());
            }
            it.state()
        })
    });
    group.finish();
}

/// The main job's scene: 10 s of the reference scene, the controller in the loop at 1 kHz
/// against the plant (DOP853 at 1e-10 between ticks, the amplifier's 2 kHz response taken
/// out in closed form: `engine::lift`); beside it, the same scene with an ideal amplifier
/// (no bandwidth, no slew limit), the floor the real one is measured against.
fn reference_scene(c: &mut Criterion) {
    let scene = host_sim::scene::parse(host_sim::scene::REFERENCE).expect("reference scene");
    let mut ideal = scene.run.clone();
    ideal.plant.amplifier.bandwidth_hz = f64::INFINITY;
    ideal.plant.amplifier.slew_volts_per_second = f64::INFINITY;
    let mut g = c.benchmark_group("scene");
    g.sample_size(10);
    g.bench_function("reference_10s_controller_in_loop", |b| {
        b.iter(|| black_box(scene.run.run().expect("runs")))
    });
    g.bench_function("reference_10s_ideal_amplifier", |b| {
        b.iter(|| black_box(ideal.run().expect("runs")))
    });
    g.finish();
}

/// The reference device with the first `count` of these tolerances (model.md §10).
fn batch(count: usize) -> de_resonator::model::tolerance::DeviceBox {
    use de_resonator::model::tolerance::{DeviceBox, Spread};
    use de_resonator::Field;
    let spreads = [
        (Field::ShearModulus, Spread::Relative(0.10)),
        (Field::Thickness, Spread::Relative(0.05)),
        (Field::Prestretch1, Spread::Relative(0.03)),
        (Field::Prestretch2, Spread::Relative(0.03)),
        (
            Field::RelativePermittivity,
            Spread::Range {
                low: 4.7,
                high: 4.8,
            },
        ),
        (Field::Jlim, Spread::Relative(0.10)),
        (Field::LengthActive, Spread::Relative(0.01)),
        (
            Field::BreakdownField,
            Spread::Range {
                low: 35e6,
                high: 200e6,
            },
        ),
    ];
    spreads
        .into_iter()
        .take(count)
        .fold(DeviceBox::exact(REFERENCE_DEVICE), |b, (f, s)| {
            b.with(f, s).expect("a valid tolerance")
        })
}

/// The certified guaranteed limit against the limit at every corner (not certified).
fn guaranteed(c: &mut Criterion) {
    use de_resonator::Limit;
    let mut g = c.benchmark_group("guaranteed");
    g.sample_size(10);
    for count in [4, 8] {
        let b = batch(count);
        let mut leaves = host_sim::cmd::safe::search_leaves();
        g.bench_function(format!("certified_{count}_parameters"), |bench| {
            bench.iter(|| black_box(b.guaranteed_limit(&mut leaves).expect("a limit")))
        });
        let spread: Vec<_> = b.spread_fields().collect();
        g.bench_function(format!("corners_{count}_parameters"), |bench| {
            bench.iter(|| {
                let mut lowest = f64::INFINITY;
                for corner in 0..1u32 << spread.len() {
                    let mut p = b.nominal;
                    for (bit, &f) in spread.iter().enumerate() {
                        let end = if corner & (1 << bit) == 0 {
                            &b.low
                        } else {
                            &b.high
                        };
                        p.set(f, end.get(f));
                    }
                    let d = Device::new(p).expect("a device of the box");
                    lowest = lowest.min(Limit::of(&d).at.volts);
                }
                black_box(lowest)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, rk4_step, one_second, reference_scene, guaranteed);
criterion_main!(benches);
