//! How good the sensorless path is against the current monitor's noise, and where it stops:
//! the `sensorless-soft` scene (plant μ 20% below nominal, no displacement sensor, the probe
//! on) at noise levels from 0.1 to 1000 µA rms a conversion of the ADC (averaged over each
//! tick's scans), several seeds each; the plant's final frequency error, or the fault; and the
//! stretch from C: its rms error against the plant's mean stretch over each window, and the
//! standard error it reports. Prints a table and writes docs/plots/sensorless-noise.svg (or
//! the file given; scripts/plots.sh).
//!
//! `cargo run --release -p host-sim --example sensorless_noise [-- FILE.svg]`

use std::path::Path;

use host_sim::plot::{svg, Panel, Series, Style, COLOURS};
use host_sim::scene;

fn main() -> Result<(), String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let base = scene::load(&root.join("scenes/sensorless-soft.toml"))?;
    // The current input's amps a code: the noise levels are set in codes of the ADC.
    let analog = base
        .run
        .analog
        .as_ref()
        .ok_or("the scene has an analog front end")?;
    let per_count = analog
        .front_end
        .fitted()
        .find(|(c, _)| *c == de_resonator::acquire::Channel::Current)
        .map(|(_, spec)| f64::from(spec.per_count).abs())
        .ok_or("the scene's front end has a current input")?;
    let stated = analog.noise_codes * per_count;
    let levels: Vec<f64> = (0..=16)
        .map(|k| 1e-7 * 10f64.powf(k as f64 / 4.0))
        .collect();
    let seeds = 8u64;
    let jobs: Vec<(f64, u64)> = levels
        .iter()
        .flat_map(|&n| (1..=seeds).map(move |seed| (n, seed)))
        .collect();
    let results = host_sim::progress::map("noise", &jobs, |&(noise, seed)| {
        let mut s = base.clone();
        s.run.history = false;
        s.run.seed = seed;
        if let Some(a) = s.run.analog.as_mut() {
            a.noise_codes = noise / per_count;
        }
        let r = s.run.run().expect("the scene runs");
        let target = f64::from(s.run.settings.target_hz);
        let error = (r.natural_frequency_hz - target) / target;
        // The stretch from C over the windows: Σ(relative error)², Σ relative σ, count.
        // Windows that read no number (C ≤ 0 in the noise) are the monitor's faults.
        let finite = r
            .sensed
            .iter()
            .filter(|w| w.stretch.is_finite() && w.sigma.is_finite());
        let sensed = finite.fold((0.0, 0.0, 0usize), |(e2, sd, n), w| {
            let e = (w.stretch - w.plant_stretch) / w.plant_stretch;
            (e2 + e * e, sd + w.sigma / w.plant_stretch, n + 1)
        });
        (
            noise,
            r.fault.is_none().then_some(error.abs()),
            r.plant_crossing.is_some(),
            sensed,
        )
    });
    println!(
        "noise A rms/sample   tuned   worst |error|   faulted   plant crossed   λ from C: rms error   mean σ"
    );
    let (mut worst, mut none_tuned, mut faults) = (Vec::new(), Vec::new(), Vec::new());
    let (mut stretch_error, mut stretch_sigma) = (Vec::new(), Vec::new());
    for &noise in &levels {
        let at: Vec<_> = results.iter().filter(|r| r.0 == noise).collect();
        let tuned: Vec<f64> = at.iter().filter_map(|r| r.1).collect();
        let crossed = at.iter().filter(|r| r.2).count();
        let w = tuned.iter().copied().fold(f64::NAN, f64::max);
        let (e2, sd, n) = at.iter().fold((0.0, 0.0, 0usize), |(a, b, c), r| {
            (a + r.3 .0, b + r.3 .1, c + r.3 .2)
        });
        let (rms, sigma) = ((e2 / n as f64).sqrt(), sd / n as f64);
        println!(
            "{noise:>18.2e}   {:>5}   {:>13.2e}   {:>7}   {crossed:>13}   {rms:>19.2e}   {sigma:>6.1e}",
            tuned.len(),
            w,
            at.len() - tuned.len()
        );
        if n > 0 {
            stretch_error.push((noise, rms));
            stretch_sigma.push((noise, sigma));
        }
        if w.is_finite() {
            worst.push((noise, w));
        } else {
            none_tuned.push((noise, 0.0));
        }
        faults.push((noise, (at.len() - tuned.len()) as f64 / at.len() as f64));
    }
    // One x range for the three stacked panels, so a noise level is at one place on each.
    let span = levels.first().zip(levels.last()).map(|(a, b)| (*a, *b));
    let panels = [
        Panel {
            title: "λ from C (probe ±20 V, 500 Hz): error against the plant".into(),
            x_label: "current monitor noise, A rms a conversion".into(),
            y_label: "relative to λ, over every 0.1 s window".into(),
            log_x: true,
            log_y: true,
            series: vec![
                Series {
                    name: "rms error".into(),
                    points: stretch_error,
                    ..Series::default()
                },
                Series {
                    name: "standard error reported".into(),
                    points: stretch_sigma,
                    style: Style {
                        colour: Some(COLOURS[1]),
                        dashed: true,
                        ..Style::default()
                    },
                    ..Series::default()
                },
            ],
            guides: vec![(stated, "scene's noise".into())],
            x_span: span,
            ..Panel::default()
        },
        Panel {
            title: "sensorless trim: frequency error".into(),
            x_label: "current monitor noise, A rms a conversion".into(),
            y_label: "worst |f − target| / target of the tuned runs".into(),
            log_x: true,
            log_y: true,
            series: vec![
                Series {
                    name: format!("{seeds} seeds a level"),
                    points: worst,
                    ..Series::default()
                },
                Series {
                    name: "none tuned: every run faulted".into(),
                    points: none_tuned,
                    style: Style {
                        colour: Some(COLOURS[6]),
                        on_axis: true,
                        ..Style::default()
                    },
                    ..Series::default()
                },
            ],
            guides: vec![(stated, "scene's noise".into())],
            x_span: span,
            levels: vec![(5e-3, "0.5%".into())],
            ..Panel::default()
        },
        Panel {
            title: "where it stops: faults (safe, 0 V)".into(),
            x_label: "current monitor noise, A rms a conversion".into(),
            y_label: "fraction of runs faulted".into(),
            log_x: true,
            series: vec![Series {
                name: "faulted".into(),
                points: faults,
                style: Style {
                    colour: Some(COLOURS[6]),
                    ..Style::default()
                },
                ..Series::default()
            }],
            guides: vec![(stated, "scene's noise".into())],
            x_span: span,
            ..Panel::default()
        },
    ];
    let out = std::env::args()
        .nth(1)
        .map_or_else(|| root.join("docs/plots/sensorless-noise.svg"), Into::into);
    std::fs::write(&out, svg(&panels)).map_err(|e| e.to_string())?;
    println!("wrote {}", out.display());
    Ok(())
}
