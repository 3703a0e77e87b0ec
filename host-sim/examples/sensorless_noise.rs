//! How good the sensorless trim is against the current monitor's noise, and where it stops:
//! the `sensorless-soft` scene (plant μ 20% below nominal, no displacement sensor) at noise
//! levels from 0.1 to 1000 µA rms a sample (10 kHz, averaged over 1 kHz ticks), several
//! seeds each; the plant's final frequency error, or the fault. Prints a table and writes
//! docs/plots/sensorless-noise.svg.
//!
//! `cargo run --release -p host-sim --example sensorless_noise`

use std::path::Path;

use host_sim::plot::{svg, Panel, Series, Style, RED};
use host_sim::scene;

fn main() -> Result<(), String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let base = scene::load(&root.join("scenes/sensorless-soft.toml"))?;
    let per_tick = base
        .run
        .current_monitor
        .ok_or("the scene has a current monitor")?;
    let stated = 1e-6;
    let levels: Vec<f64> = (0..=16)
        .map(|k| 1e-7 * 10f64.powf(k as f64 / 4.0))
        .collect();
    let seeds = 8u64;
    let jobs: Vec<(f64, u64)> = levels
        .iter()
        .flat_map(|&n| (1..=seeds).map(move |seed| (n, seed)))
        .collect();
    let results = host_sim::work::map("noise", &jobs, |&(noise, seed)| {
        let mut s = base.clone();
        s.run.history = false;
        s.run.seed = seed;
        if let Some(m) = s.run.current_monitor.as_mut() {
            m.noise_amps = per_tick.noise_amps * noise / stated;
        }
        let r = s.run.run().expect("the scene runs");
        let target = f64::from(s.run.settings.target_hz);
        let error = (r.natural_frequency_hz - target) / target;
        (
            noise,
            r.fault.is_none().then_some(error.abs()),
            r.plant_crossing.is_some(),
        )
    });
    println!("noise A rms/sample   tuned   worst |error|   faulted   plant crossed");
    let (mut worst, mut faults) = (Vec::new(), Vec::new());
    for &noise in &levels {
        let at: Vec<_> = results.iter().filter(|r| r.0 == noise).collect();
        let tuned: Vec<f64> = at.iter().filter_map(|r| r.1).collect();
        let crossed = at.iter().filter(|r| r.2).count();
        let w = tuned.iter().copied().fold(f64::NAN, f64::max);
        println!(
            "{noise:>18.2e}   {:>5}   {:>13.2e}   {:>7}   {crossed:>13}",
            tuned.len(),
            w,
            at.len() - tuned.len()
        );
        if w.is_finite() {
            worst.push((noise, w));
        }
        faults.push((noise, (at.len() - tuned.len()) as f64 / at.len() as f64));
    }
    let panels = [
        Panel {
            title: "sensorless trim: frequency error".into(),
            x_label: "current monitor noise, A rms a sample at 10 kHz".into(),
            y_label: "worst |f − target| / target of the tuned runs".into(),
            log_x: true,
            log_y: true,
            series: vec![Series {
                name: format!("{seeds} seeds a level"),
                points: worst,
                ..Series::default()
            }],
            guides: vec![(stated, "scene's noise".into())],
            levels: vec![(5e-3, "0.5%".into())],
            ..Panel::default()
        },
        Panel {
            title: "where it stops: faults (safe, 0 V)".into(),
            x_label: "current monitor noise, A rms a sample at 10 kHz".into(),
            y_label: "fraction of runs faulted".into(),
            log_x: true,
            series: vec![Series {
                name: "faulted".into(),
                points: faults,
                style: Style {
                    colour: Some(RED),
                    ..Style::default()
                },
            }],
            guides: vec![(stated, "scene's noise".into())],
            ..Panel::default()
        },
    ];
    let out = root.join("docs/plots/sensorless-noise.svg");
    std::fs::write(&out, svg(&panels)).map_err(|e| e.to_string())?;
    println!("wrote {}", out.display());
    Ok(())
}
