//! What `safe` and `tune` print: a JSON object for tools, or a short text for people.

use std::path::Path;

use de_resonator::{Equilibrium, FailureMode, TunableRange, Tuner};

use crate::hil::Run;
use crate::plot::{svg, Panel, Series};
use crate::scene::Scene;
use crate::simulate::Outcome;
use serde_json::{json, Value};

/// The keys `safe` and `tune` share: zero-bias frequency, limit, tunable range.
fn region(tuner: &Tuner<f64>, range: &TunableRange<f64>, margin: f64) -> Value {
    let limit = tuner.limit();
    json!({
        "zero_bias_frequency_hz": tuner.zero_bias().natural_frequency_hz,
        "limit": {
            "mode": limit.mode.name(),
            "volts": limit.at.volts,
            "stretch": limit.at.stretch,
            "natural_frequency_hz": limit.at.natural_frequency_hz,
        },
        "margin": margin,
        "max_bias_volts": range.max_bias.volts,
        "tunable_range_hz": [range.low_hz, range.high_hz],
    })
}

/// Six significant figures, for people.
fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let decimals = (5 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}")
}

fn region_text(name: &str, tuner: &Tuner<f64>, range: &TunableRange<f64>, margin: f64) -> String {
    let limit = tuner.limit();
    let zero = tuner.zero_bias();
    format!(
        "device          {name}\n\
         zero bias       f = {} Hz at stretch {}\n\
         limit           {}: {}\n\
         \x20               at {} V, stretch {}, f = {} Hz\n\
         margin {margin:<8} bias at most {} V (stretch {})\n\
         tunable range   {} .. {} Hz",
        sig(zero.natural_frequency_hz),
        sig(zero.stretch),
        limit.mode.name(),
        limit.mode.description(),
        sig(limit.at.volts),
        sig(limit.at.stretch),
        sig(limit.at.natural_frequency_hz),
        sig(range.max_bias.volts),
        sig(range.max_bias.stretch),
        sig(range.low_hz),
        sig(range.high_hz),
    )
}

/// The output of `host-sim safe`.
pub fn safe(
    name: &str,
    tuner: &Tuner<f64>,
    range: &TunableRange<f64>,
    margin: f64,
    as_json: bool,
) -> String {
    if as_json {
        region(tuner, range, margin).to_string()
    } else {
        region_text(name, tuner, range, margin)
    }
}

/// The output of `host-sim tune`.
pub fn tune(
    name: &str,
    tuner: &Tuner<f64>,
    range: &TunableRange<f64>,
    margin: f64,
    target_hz: f64,
    bias: &Equilibrium<f64>,
    as_json: bool,
) -> String {
    if as_json {
        let mut out = region(tuner, range, margin);
        out["target_hz"] = json!(target_hz);
        out["bias_volts"] = json!(bias.volts);
        out["stretch"] = json!(bias.stretch);
        out["natural_frequency_hz"] = json!(bias.natural_frequency_hz);
        out.to_string()
    } else {
        format!(
            "{}\n\ntarget          {} Hz\nbias            {} V (stretch {}, f = {} Hz)",
            region_text(name, tuner, range, margin),
            sig(target_hz),
            sig(bias.volts),
            sig(bias.stretch),
            sig(bias.natural_frequency_hz),
        )
    }
}

/// The output of `host-sim simulate`.
pub fn simulation(name: &str, method: &str, step: f64, out: &Outcome, as_json: bool) -> String {
    let first_limit = first_limit_json(out.first_limit);
    if as_json {
        json!({
            "method": method,
            "step_seconds": step,
            "steps": out.samples.len().saturating_sub(1),
            "final": {
                "stretch": out.final_stretch,
                "velocity": out.final_velocity_per_second,
            },
            "min_stretch": out.min_stretch,
            "max_stretch": out.max_stretch,
            "first_limit": first_limit,
            "run_seconds": out.run_seconds,
        })
        .to_string()
    } else {
        let limit = match out.first_limit {
            Some((mode, time)) => format!("{} at t = {} s", mode.description(), sig(time)),
            None => "none crossed".into(),
        };
        format!(
            "device          {name}\n\
             method          {method}, step {} s, {} steps in {} ms\n\
             final           stretch {}, velocity {} 1/s\n\
             stretch range   {} .. {}\n\
             first limit     {limit}",
            sig(step),
            out.samples.len().saturating_sub(1),
            sig(out.run_seconds * 1e3),
            sig(out.final_stretch),
            sig(out.final_velocity_per_second),
            sig(out.min_stretch),
            sig(out.max_stretch),
        )
    }
}

/// Write `text` to `dir/file`, creating `dir`; the path written, or why not.
pub fn write_file(dir: &Path, file: &str, text: &str) -> Result<String, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let path = dir.join(file);
    std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path.display().to_string())
}

/// The first limit of a run as JSON: null, or {mode, time}.
fn first_limit_json(first: Option<(FailureMode, f64)>) -> Value {
    first.map_or(
        Value::Null,
        |(mode, time)| json!({"mode": mode.name(), "time": time}),
    )
}

/// Run `host-sim sweep`, write sweep.csv and sweep.svg into `dir`, and say what it found.
pub fn sweep(
    name: &str,
    sweep: &crate::sweep::Sweep,
    quality: f64,
    dir: &Path,
    as_json: bool,
) -> Result<String, String> {
    let response = crate::sweep::run(sweep)?;
    let f0 = response.natural_frequency_hz;
    let mut csv = String::from("drive_hz,ratio,amplitude,first_limit,first_limit_time,stopped\n");
    for p in &response.points {
        let (mode, time) = p
            .first_limit
            .map_or((String::new(), String::new()), |(m, t)| {
                (m.name().into(), t.to_string())
            });
        csv += &format!(
            "{},{},{},{mode},{time},{}\n",
            p.drive_hz,
            p.drive_hz / f0,
            p.amplitude,
            p.stopped.is_some()
        );
    }
    let panel = Panel {
        title: format!(
            "Response: {:.0} V bias, {:.0} V AC, Q {quality}",
            sweep.bias_volts, sweep.ac_volts
        ),
        x_label: "drive frequency / f0".into(),
        y_label: "amplitude (stretch)".into(),
        log_y: true,
        series: vec![Series {
            name: format!("f0 = {} Hz", sig(f0)),
            points: response
                .points
                .iter()
                .map(|p| (p.drive_hz / f0, p.amplitude))
                .collect(),
        }],
        guides: vec![
            (0.5, "f0/2".into()),
            (1.0, "f0".into()),
            (2.0, "2 f0".into()),
        ],
        ..Panel::default()
    };
    let csv_path = write_file(dir, "sweep.csv", &csv)?;
    let svg_path = write_file(dir, "sweep.svg", &svg(&[panel]))?;
    let crossed = response
        .points
        .iter()
        .filter(|p| p.first_limit.is_some())
        .count();
    if as_json {
        let points: Vec<Value> = response
            .points
            .iter()
            .map(|p| {
                json!({
                    "drive_hz": p.drive_hz,
                    "amplitude": p.amplitude,
                    "first_limit": first_limit_json(p.first_limit),
                    "stopped": p.stopped,
                })
            })
            .collect();
        let peaks: Vec<Value> = response
            .peaks
            .iter()
            .map(|p| {
                json!({
                    "drive_hz": p.drive_hz,
                    "amplitude": p.amplitude,
                    "ratio": p.drive_hz / f0,
                    "prominence": p.prominence,
                })
            })
            .collect();
        return Ok(json!({
            "bias_volts": sweep.bias_volts,
            "ac_volts": sweep.ac_volts,
            "quality": quality,
            "damping": sweep.params.damping,
            "natural_frequency_hz": f0,
            "peaks": peaks,
            "points": points,
            "crossed_limit": crossed,
            "csv": csv_path,
            "plot": svg_path,
        })
        .to_string());
    }
    let mut text = format!(
        "device          {name}\n\
         drive           {} V bias + {} V AC, Q {} (c = {} N·s)\n\
         f0 at the bias  {} Hz\n\
         peaks           drive Hz    ratio   amplitude\n",
        sig(sweep.bias_volts),
        sig(sweep.ac_volts),
        sig(quality),
        sig(sweep.params.damping),
        sig(f0),
    );
    for p in &response.peaks {
        text += &format!(
            "                {:>9}  {:>7}   {}\n",
            sig(p.drive_hz),
            format!("{:.3}", p.drive_hz / f0),
            sig(p.amplitude)
        );
    }
    text += &format!(
        "limits          {crossed} of {} drive frequencies crossed a limit of MODEL.md §6\n\
         wrote           {csv_path}, {svg_path}",
        response.points.len()
    );
    Ok(text)
}

/// Run `host-sim report`: the work-precision study; write work-precision.csv and .svg into
/// `dir`; a table per scene for people, or one JSON object.
pub fn work_precision(
    name: &str,
    params: de_resonator::DeviceParams<f64>,
    dir: &Path,
    as_json: bool,
) -> Result<String, String> {
    use crate::precision::{reference, rows, studies};
    let studies = studies(params)?;
    let references = crate::work::map("reference", &studies, reference)
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
    // Timed runs one at a time: run times measured side by side must not share the cores.
    let methods = crate::simulate::Choice::core();
    let bar = crate::work::bar("timing", studies.len() * methods.len());
    let mut all = Vec::new();
    for (study, reference) in studies.iter().zip(&references) {
        for &choice in &methods {
            all.extend(rows(study, reference, choice));
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let mut csv = String::from(
        "scene,method,steps_per_period,step_seconds,status,final_relative_error,max_error,\
         phase_error_rad,run_seconds_per_simulated_second\n",
    );
    for r in &all {
        csv += &format!(
            "{},{},{},{},{},{},{},{},{}\n",
            r.scene,
            r.method,
            r.steps_per_period,
            r.step_seconds,
            r.status,
            r.final_relative_error,
            r.max_error,
            r.phase_error_rad,
            r.run_seconds_per_simulated_second
        );
    }
    let panels: Vec<Panel> = studies
        .iter()
        .map(|study| {
            let mut series: Vec<Series> = Vec::new();
            for r in all
                .iter()
                .filter(|r| r.scene == study.name && r.status == "ok")
            {
                let point = (r.run_seconds_per_simulated_second, r.max_error);
                match series.iter_mut().find(|s| s.name == r.method) {
                    Some(s) => s.points.push(point),
                    None => series.push(Series {
                        name: r.method.clone(),
                        points: vec![point],
                    }),
                }
            }
            Panel {
                title: study.name.into(),
                x_label: "run time per simulated second, s".into(),
                y_label: "max stretch error".into(),
                log_x: true,
                log_y: true,
                series,
                guides: Vec::new(),
            }
        })
        .collect();
    let csv_path = write_file(dir, "work-precision.csv", &csv)?;
    let svg_path = write_file(dir, "work-precision.svg", &svg(&panels))?;
    let floor = references.iter().map(|r| r.floor).fold(0.0, f64::max);
    if as_json {
        let scenes: Vec<Value> = studies
            .iter()
            .zip(&references)
            .map(|(s, r)| {
                json!({
                    "name": s.name,
                    "what": s.what,
                    "bias_volts": s.scene.bias_volts,
                    "ac_volts": s.scene.ac_volts,
                    "drive_hz": s.scene.drive_hz,
                    "base_hz": s.base_hz,
                    "duration_seconds": s.scene.duration_seconds,
                    "reference_floor": r.floor,
                })
            })
            .collect();
        let rows: Vec<Value> = all
            .iter()
            .map(|r| {
                json!({
                    "scene": r.scene,
                    "method": r.method,
                    "steps_per_period": r.steps_per_period,
                    "step_seconds": r.step_seconds,
                    "status": r.status,
                    "final_relative_error": finite(r.final_relative_error),
                    "max_error": finite(r.max_error),
                    "phase_error_rad": finite(r.phase_error_rad),
                    "run_seconds_per_simulated_second": finite(r.run_seconds_per_simulated_second),
                })
            })
            .collect();
        return Ok(json!({
            "reference": {"method": "dop853", "tolerance": 1e-12, "floor": floor,
                          "floor_is": "largest stretch difference against tolerance 1e-13"},
            "scenes": scenes,
            "rows": rows,
            "csv": csv_path,
            "plot": svg_path,
        })
        .to_string());
    }
    let mut text = format!(
        "device  {name}\n\
         reference: DOP853 at 1e-12; its error floor (against 1e-13) is {floor:.1e} in stretch\n\
         max error in stretch at 16 / 64 / 256 steps a period; run time per simulated second at 64\n"
    );
    for study in &studies {
        text += &format!("\n{}: {}\n", study.name, study.what);
        text += &format!(
            "  {:<24}{:>10}{:>10}{:>10}{:>13}\n",
            "method", "16", "64", "256", "s/sim s"
        );
        let mut methods: Vec<&str> = Vec::new();
        for r in all.iter().filter(|r| r.scene == study.name) {
            if !methods.contains(&r.method.as_str()) {
                methods.push(&r.method);
            }
        }
        for method in methods {
            let at = |n: u32| {
                all.iter().find(|r| {
                    r.scene == study.name && r.method == method && r.steps_per_period == n
                })
            };
            let cell = |n: u32| match at(n) {
                Some(r) if r.status == "ok" => format!("{:.1e}", r.max_error),
                Some(r) => r.status.to_string(),
                None => "-".into(),
            };
            let time = at(64).filter(|r| r.status == "ok").map_or("-".into(), |r| {
                format!("{:.1e}", r.run_seconds_per_simulated_second)
            });
            text += &format!(
                "  {method:<24}{:>10}{:>10}{:>10}{time:>13}\n",
                cell(16),
                cell(64),
                cell(256)
            );
        }
    }
    text += &format!("\nwrote {csv_path}, {svg_path}");
    Ok(text)
}

/// A number for JSON: null when not finite (JSON has no NaN).
fn finite(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

/// What `host-sim lut` says about the table it wrote.
pub fn lut(name: &str, made: &crate::lut::Made, margin: f64, out: &Path, as_json: bool) -> String {
    let first = made.points.first().copied().unwrap_or((f32::NAN, f32::NAN));
    let last = made.points.last().copied().unwrap_or((f32::NAN, f32::NAN));
    if as_json {
        return json!({
            "file": out.display().to_string(),
            "points": made.points.len(),
            "bytes": made.bytes.len(),
            "crc32": format!("{:#010x}", made.crc),
            "margin": margin,
            "frequency_hz": [first.0, last.0],
            "bias_volts": [first.1, last.1],
            "interpolation_error": {
                "frequency": made.errors.frequency,
                "worst_hz": made.errors.worst_hz,
                "volts_of_top": made.errors.volts,
            },
        })
        .to_string();
    }
    format!(
        "device          {name}\n\
         table           {} points, {} bytes, CRC-32 {:#010x} -> {}\n\
         covers          {} Hz at {} V .. {} Hz at {} V (margin {margin})\n\
         interpolation   f at the table's bias within {:.2e} of the target (worst at {} Hz);\n\
         \x20               bias within {:.2e} of the top bias from the direct solve",
        made.points.len(),
        made.bytes.len(),
        made.crc,
        out.display(),
        sig(f64::from(first.0)),
        sig(f64::from(first.1)),
        sig(f64::from(last.0)),
        sig(f64::from(last.1)),
        made.errors.frequency,
        sig(made.errors.worst_hz),
        made.errors.volts,
    )
}

/// Write what a scene asked for (history CSV, plot) into `dir`; the paths written.
pub fn run_files(dir: &Path, scene: &Scene, run: &Run) -> Result<Vec<String>, String> {
    let mut written = Vec::new();
    if scene.history {
        let mut csv = String::from("time_s,stretch,membrane_volts\n");
        for (t, l, v) in &run.history {
            csv.push_str(&format!("{t},{l},{v}\n"));
        }
        written.push(write_file(dir, "history.csv", &csv)?);
    }
    if scene.plot && !run.history.is_empty() {
        let series = |name: &str, pick: fn(&(f64, f64, f64)) -> f64| Series {
            name: name.into(),
            points: run.history.iter().map(|h| (h.0, pick(h))).collect(),
        };
        let guides: Vec<(f64, String)> = run
            .events
            .iter()
            .map(|e| {
                (
                    e.seconds,
                    e.what.split(',').next().unwrap_or("").to_string(),
                )
            })
            .collect();
        let panels = [
            Panel {
                title: format!("{}: stretch of A", scene.name),
                x_label: "time, s".into(),
                y_label: "stretch λ".into(),
                series: vec![series("plant", |h| h.1)],
                guides: guides.clone(),
                ..Panel::default()
            },
            Panel {
                title: "voltage on the membrane".into(),
                x_label: "time, s".into(),
                y_label: "V".into(),
                series: vec![series("amplifier output", |h| h.2)],
                guides,
                ..Panel::default()
            },
        ];
        written.push(write_file(dir, "run.svg", &svg(&panels))?);
    }
    Ok(written)
}

/// What `host-sim run` prints: a short report a person reads at a glance, or JSON.
pub fn run(scene: &Scene, run: &Run, files: &[String], as_json: bool) -> String {
    let target = f64::from(scene.run.settings.target_hz);
    let f = run.natural_frequency_hz;
    let error = (f - target) / target;
    let margin = run
        .limit
        .map(|(mode, volts)| (mode, volts, 1.0 - run.bias_volts / volts));
    if as_json {
        return json!({
            "scene": scene.name,
            "description": scene.description,
            "simulated_seconds": scene.run.duration_seconds,
            "ticks": run.ticks,
            "target_hz": target,
            "bias_volts": run.bias_volts,
            "nominal_bias_volts": run.boot.map(|b| b.bias_volts),
            "refused": run.refused.map(|f| f.to_string()),
            "fault": run.fault.map(|f| f.to_string()),
            "natural_frequency_hz": finite(f),
            "relative_error": finite(error),
            "limit": margin.map(|(mode, volts, m)| json!({
                "mode": mode.name(), "volts": volts, "margin": m,
            })),
            "plant_crossing": first_limit_json(run.plant_crossing),
            "final_membrane_volts": run.final_membrane_volts,
            "events": run.events.iter().map(|e| json!({"time": e.seconds, "what": e.what}))
                .collect::<Vec<_>>(),
            "run_seconds": run.run_seconds,
            "files": files,
        })
        .to_string();
    }
    let mut text = format!(
        "scene           {} ({} s simulated, controller at {} Hz)\n\
         target          {} Hz\n",
        scene.name,
        sig(scene.run.duration_seconds),
        scene.run.settings.tick_hz,
        sig(target),
    );
    match (run.refused, run.fault) {
        (Some(fault), _) => text.push_str(&format!("refused         {fault}: 0 V throughout\n")),
        (None, Some(fault)) => text.push_str(&format!(
            "fault           {fault}\n\
             \x20               output {:.1} V at the end\n",
            run.final_membrane_volts
        )),
        (None, None) => {
            text.push_str(&format!(
                "bias            {} V\n\
                 natural freq    {} Hz in the plant at that bias: error {:+.1e} ({:+.4}%)\n",
                sig(run.bias_volts),
                sig(f),
                error,
                100.0 * error
            ));
            if let Some((mode, volts, m)) = margin {
                text.push_str(&format!(
                    "margin          {:.1}% below the plant's limit ({}, {} V)\n",
                    100.0 * m,
                    mode.name(),
                    sig(volts)
                ));
            }
        }
    }
    // The frequency freezes the networks over a period: say when a branch is faster.
    for b in &scene.run.plant.branches {
        if b.relaxation_seconds * target < 10.0 {
            text.push_str(&format!(
                "note            a branch relaxes in {} s, under 10 periods: the natural \
                 frequency above (networks frozen) does not hold for it\n",
                sig(b.relaxation_seconds)
            ));
        }
    }
    text.push_str(&match run.plant_crossing {
        None => format!(
            "plant safe      yes: no check of MODEL.md §6 failed at any of {} ticks\n",
            run.ticks
        ),
        Some((mode, t)) => format!(
            "plant safe      NO: {} at {} s ({})\n",
            mode.name(),
            sig(t),
            mode.description()
        ),
    });
    for e in &run.events {
        text.push_str(&format!("  {:>8.3} s     {}\n", e.seconds, e.what));
    }
    text.push_str(&format!("run time        {:.3} s", run.run_seconds));
    for file in files {
        text.push_str(&format!("\nwrote           {file}"));
    }
    text
}
