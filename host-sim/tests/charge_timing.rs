//! The trim on the charge's timing error against its resolution, measured in the closed loop
//! (BENCHMARKS.md, "The charge's resolution"): every trim that timed its ring in the charge,
//! its measured frequency against the plant's own at that bias (the model of the plant's
//! parameters), times the resolution it reported. Ignored in the test run: a measurement.
//! `cargo test --release -p host-sim --test charge_timing -- --ignored --nocapture`

use de_resonator::{Device, DeviceParams, REFERENCE_DEVICE};
use host_sim::scene;

/// A sensorless scene: the device's lines, the plant's μ scale, the monitor's noise, the
/// target and the AC.
fn scene_text(device: &str, scale: f64, noise: f64, seed: u32, target: f64, ac: f64) -> String {
    format!(
        "name = \"timing\"\nduration_seconds = 8.0\nseed = {seed}\n[device]\n{device}\n\
         [plant]\nshear_modulus_scale = {scale}\nquality_factor = 200.0\nleakage_ohms = 1e12\n\
         [amplifier]\nbandwidth_hz = 2000.0\nslew_volts_per_second = 200000.0\n\
         [current_monitor]\nnoise_amps = {noise:e}\nsample_hz = 10000.0\nresolution_amps = 1e-7\n\
         [controller]\ntarget_hz = {target}\nac_volts = 100.0\nac_hz = {ac}\n\
         trim_tolerance = 1e-3\nprobe_volts = 20.0\nprobe_hz = 500.0\n"
    )
}

/// (resolution, relative error × resolution) of each trim timed in the charge.
fn timed(text: &str, plant: DeviceParams<f64>) -> Vec<(f64, f64)> {
    let mut s = scene::parse(text).unwrap();
    s.run.history = false;
    let run = s.run.run().unwrap();
    let device = Device::new(plant).unwrap();
    let field = |what: &str, after: &str, until: char| -> f64 {
        let tail = what.split(after).nth(1).unwrap();
        tail[..tail.find(until).unwrap()].parse().unwrap()
    };
    run.events
        .iter()
        .filter(|e| e.what.starts_with("trim: ") && e.what.contains("(resolution "))
        .map(|e| {
            let hz = field(&e.what, "trim: ", ' ');
            let volts = field(&e.what, " measured at ", ' ');
            let resolution = field(&e.what, "(resolution ", ')');
            let at = device.stretch_for_bias(volts, 6.0).unwrap();
            let truth = device.natural_frequency_hz(at);
            (resolution, (hz / truth - 1.0) * resolution)
        })
        .collect()
}

#[test]
#[ignore = "a measurement for BENCHMARKS.md"]
fn timing_error_times_resolution() {
    let gent = DeviceParams {
        jlim: Some(100.0),
        prestretch_1: 4.0,
        prestretch_2: 1.0,
        ..REFERENCE_DEVICE
    };
    let mut all = Vec::new();
    for seed in 1..=10 {
        for (scale, noise) in [
            (0.97, 3e-6),
            (1.03, 3e-6),
            (0.97, 5e-6),
            (1.03, 5e-6),
            (1.0, 1e-6),
        ] {
            let plant = DeviceParams {
                shear_modulus: scale * REFERENCE_DEVICE.shear_modulus,
                ..REFERENCE_DEVICE
            };
            all.extend(timed(
                &scene_text("", scale, noise, seed, 44.0, 40.0),
                plant,
            ));
        }
        for noise in [5e-7, 7e-7] {
            let lines = "jlim = 100.0\nprestretch_1 = 4.0\nprestretch_2 = 1.0\n";
            all.extend(timed(
                &scene_text(lines, 1.0, noise, seed, 53.8, 50.0),
                gent,
            ));
        }
    }
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    println!("resolution   trims   rms of error × resolution   worst");
    for part in all.chunks(all.len().div_ceil(5)) {
        let rms = (part.iter().map(|k| k.1 * k.1).sum::<f64>() / part.len() as f64).sqrt();
        let worst = part.iter().map(|k| k.1.abs()).fold(0.0, f64::max);
        let (low, high) = (part[0].0, part[part.len() - 1].0);
        println!(
            "{low:>4.0}–{high:<5.0}   {:>5}   {rms:>25.4}   {worst:.4}",
            part.len()
        );
    }
}
