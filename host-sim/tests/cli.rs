//! The `host-sim` command line, run as a user runs it.

use std::io::Write;
use std::process::{Command, Output};

use serde_json::Value;

fn host_sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .expect("host-sim runs")
}

/// Exit status 2, nothing on stdout, one line on stderr: returns that line.
fn refused(args: &[&str]) -> String {
    let out = host_sim(args);
    assert_eq!(out.status.code(), Some(2), "{args:?}");
    assert!(out.stdout.is_empty(), "{args:?}");
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    err
}

fn json(args: &[&str]) -> Value {
    let out = host_sim(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object on stdout")
}

/// A device file in a temporary directory, removed when dropped.
struct DeviceFile(std::path::PathBuf);

impl DeviceFile {
    fn new(name: &str, text: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("host-sim-cli-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::File::create(&path)
            .unwrap()
            .write_all(text.as_bytes())
            .unwrap();
        Self(path)
    }
    fn path(&self) -> &str {
        self.0.to_str().unwrap()
    }
}

impl Drop for DeviceFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// Rounds to the published figure at its number of decimals.
fn rounds_to(v: &Value, published: f64, decimals: i32) {
    let x = v.as_f64().expect("a number");
    assert!(
        (x - published).abs() <= 0.5 * 10f64.powi(-decimals),
        "{x} vs {published}"
    );
}

/// The reference device's published figures (issue 2) through the JSON interface.
#[test]
fn safe_json_on_the_reference_device() {
    let v = json(&["safe", "--json"]);
    rounds_to(&v["zero_bias_frequency_hz"], 45.9527, 4);
    assert_eq!(v["limit"]["mode"], "emi");
    rounds_to(&v["limit"]["volts"], 9854.73, 2);
    rounds_to(&v["limit"]["stretch"], 2.36254, 5);
    rounds_to(&v["limit"]["natural_frequency_hz"], 42.7292, 4);
    let range = v["tunable_range_hz"].as_array().unwrap();
    assert_eq!(range.len(), 2);
    assert!(range[0].as_f64() < range[1].as_f64());
    assert!(v.get("bias_volts").is_none());
}

#[test]
fn tune_json_with_no_margin() {
    let v = json(&["tune", "--target-hz", "44", "--margin", "0", "--json"]);
    rounds_to(&v["bias_volts"], 7449.88, 2);
    for key in [
        "bias_volts",
        "stretch",
        "natural_frequency_hz",
        "zero_bias_frequency_hz",
        "tunable_range_hz",
        "limit",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    rounds_to(&v["natural_frequency_hz"], 44.0, 9);
}

/// A neo-Hookean device from a file: f at zero bias in closed form (MODEL.md §5),
/// ω² = μ·L2·H·(1 + 3λ1p⁻⁴λ2p⁻²)·(1 + L1A/L1B)/M.
#[test]
fn device_file_changes_the_device() {
    let file = DeviceFile::new(
        "neo.toml",
        "# neo-Hookean: no jlim\nprestretch_1 = 3.0\nprestretch_2 = 1.5\nlength_passive = 0.01\n",
    );
    let v = json(&["safe", "--device", file.path(), "--json"]);
    let (mu, w, h, la, lb, m, rho): (f64, f64, f64, f64, f64, f64, f64) =
        (45e3, 0.04, 1e-3, 0.02, 0.01, 2e-3, 960.0);
    let mass = m * la + rho * w * h * la * (la + lb) / 3.0;
    let omega2 = mu * w * h * (1.0 + 3.0 / (81.0 * 2.25)) * (1.0 + la / lb) / mass;
    let f0 = omega2.sqrt() / std::f64::consts::TAU;
    let got = v["zero_bias_frequency_hz"].as_f64().unwrap();
    assert!((got - f0).abs() < 1e-9 * f0, "{got} vs {f0}");
}

/// Exit status 2, one line on stderr with the range, nothing on stdout.
#[test]
fn unreachable_target() {
    let range = json(&["safe", "--json"])["tunable_range_hz"].clone();
    for args in [
        &["tune", "--target-hz", "50", "--json"][..],
        &["tune", "--target-hz", "50"][..],
    ] {
        let err = refused(args);
        assert!(err.contains("tunable range"), "{err}");
        // The range's top as messages write it (12 significant digits), read back.
        let high = range[1].as_f64().unwrap();
        let written = err
            .split(['[', ']', ','])
            .filter_map(|s| s.trim().parse::<f64>().ok())
            .any(|x| (x - high).abs() <= 1e-11 * high);
        assert!(written, "{err} lacks {high}");
    }
}

#[test]
fn nan_target_and_bad_margin() {
    for args in [
        &["tune", "--target-hz", "NaN"][..],
        &["tune", "--target-hz", "inf"][..],
        &["tune", "--target-hz", "44", "--margin", "1.5"][..],
        &["safe", "--margin", "-0.1"][..],
        &["tune", "--target-hz", "-44"][..],
    ] {
        refused(args);
    }
}

#[test]
fn bad_device_files() {
    let cases = [
        (
            "unknown.toml",
            "thickness = 1e-3\nshear_modulos = 4e4\n",
            "shear_modulos",
        ),
        ("negative.toml", "thickness = -1e-3\n", "thickness"),
        ("slack.toml", "prestretch_1 = 0.3\n", "prestretch_1"),
        ("locked.toml", "jlim = 8.0\n", "jlim"),
        ("nan.toml", "width = nan\n", "width"),
        ("syntax.toml", "width = \n", "line 1"),
    ];
    for (name, text, expected) in cases {
        let file = DeviceFile::new(name, text);
        let err = refused(&["safe", "--device", file.path(), "--json"]);
        assert!(err.contains(expected) && err.contains(name), "{err}");
    }
    let out = host_sim(&["safe", "--device", "/nonexistent/device.toml"]);
    assert_eq!(out.status.code(), Some(2));
}

/// The main job: no arguments run the built-in reference scene, print the short report and
/// write its plot under out/run/reference (here in a scratch directory).
#[test]
fn no_arguments_run_the_reference_scene() {
    let dir = std::env::temp_dir().join(format!("host-sim-main-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .current_dir(&dir)
        .output()
        .expect("host-sim runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    for word in [
        "reference",
        "target",
        "44.0000 Hz",
        "plant safe      yes",
        "run time",
    ] {
        assert!(text.contains(word), "{word}: {text}");
    }
    assert!(dir.join("out/run/reference/run.svg").is_file());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn help_explains_the_commands() {
    let text = String::from_utf8(host_sim(&["--help"]).stdout).unwrap();
    for word in ["run", "safe", "tune", "Exit status"] {
        assert!(text.contains(word), "{text}");
    }
    let text = String::from_utf8(host_sim(&["tune", "--help"]).stdout).unwrap();
    for word in ["--target-hz", "--device", "--margin", "--json"] {
        assert!(text.contains(word), "{text}");
    }
}

/// Fixed-step core methods converge to the reference on a driven scene: RK4's error falls
/// 16-fold when its step halves (fourth order), and f32 and Verlet stay close.
#[test]
fn simulate_core_methods_converge_to_the_reference() {
    let scene = |step: &'static str, method: &'static str| {
        let v = json(&[
            "simulate",
            "--bias-volts",
            "7000",
            "--ac-volts",
            "500",
            "--drive-hz",
            "40",
            "--duration",
            "0.2",
            "--step",
            step,
            "--method",
            method,
            "--json",
        ]);
        assert!(v["first_limit"].is_null());
        v["final"]["stretch"].as_f64().unwrap()
    };
    let reference = scene("0.0001", "reference");
    let coarse = (scene("0.0001", "rk4-f64") - reference).abs();
    let fine = (scene("0.00005", "rk4-f64") - reference).abs();
    let ratio = coarse / fine;
    assert!(
        (12.0..20.0).contains(&ratio),
        "RK4 error ratio {ratio}: {coarse} → {fine}"
    );
    for (method, tolerance) in [("rk4-f32", 1e-4), ("verlet-f64", 1e-3)] {
        let got = scene("0.0001", method);
        assert!(
            (got - reference).abs() < tolerance,
            "{method}: {got} vs {reference}"
        );
    }
}

/// A voltage step from the pre-stretch to 95% of the limit voltage crosses EMI dynamically
/// (tests/dynamics.rs derives why from the energy turning point); half of it does not.
#[test]
fn simulate_reports_a_dynamic_crossing() {
    let limit = json(&["safe", "--json"])["limit"]["volts"]
        .as_f64()
        .unwrap();
    for (fraction, crosses) in [(0.95, true), (0.5, false)] {
        let volts = (fraction * limit).to_string();
        for method in ["reference", "rk4-f32"] {
            let v = json(&[
                "simulate",
                "--bias-volts",
                &volts,
                "--start",
                "prestretch",
                "--duration",
                "0.03",
                "--step",
                "1e-5",
                "--method",
                method,
                "--json",
            ]);
            assert_eq!(
                !v["first_limit"].is_null(),
                crosses,
                "{method} {fraction}: {v}"
            );
            if crosses {
                assert_eq!(v["first_limit"]["mode"], "emi");
                assert!(v["first_limit"]["time"].as_f64().unwrap() > 0.0);
            }
        }
    }
}

#[test]
fn simulate_refuses_unstable_steps_and_unknown_methods() {
    for (bias, duration, extra) in [
        (
            "7000",
            "0.1",
            &["--method", "verlet-f64", "--step", "0.01"][..],
        ),
        ("7000", "0.1", &["--method", "euler"][..]),
        ("7000", "-1", &[][..]),
        ("1e6", "0.1", &[][..]),
    ] {
        let mut args = vec!["simulate", "--bias-volts", bias, "--duration", duration];
        args.extend(extra);
        refused(&args);
    }
}

/// The stiff and extreme cases: no run fails silently; the guard refuses the steps past
/// every explicit method's stability limit (2 steps a period), and each case has a step at
/// which RK4 in f32 runs stable or stops after the monitor saw a crossing.
#[test]
fn stress_never_fails_silently() {
    let v = json(&["stress", "--json"]);
    assert_eq!(v["summary"]["failed_silently"], 0, "{}", v["summary"]);
    let cases = v["cases"].as_array().unwrap();
    let names: Vec<_> = cases.iter().map(|c| c["case"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "near_emi_limit",
            "passive_near_slack",
            "gent_lock_up",
            "light_bar",
            "large_ac",
            "fast_step"
        ]
    );
    for case in cases {
        let runs = case["runs"].as_array().unwrap();
        for run in runs {
            let explicit = !run["method"].as_str().unwrap().starts_with("implicit");
            if explicit && run["steps_per_period"] == 2.0 {
                assert_eq!(run["verdict"], "refused", "{run}");
            }
        }
        assert!(
            runs.iter().any(|r| r["method"] == "rk4-f32"
                && (r["verdict"] == "stable" || r["verdict"] == "stopped_after_crossing")),
            "{}",
            case["case"]
        );
    }
}

/// A fresh output folder for a command that writes files.
fn out_dir(name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("host-sim-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir.to_str().unwrap().to_string()
}

/// The frequency response of MODEL.md §7 on the reference device: resonance where the drive
/// meets the natural frequency f0 at the bias (Φ·Φ forcing at Ω), at f0/2 (the Φac² term
/// forces at 2Ω) and at 2·f0 (principal parametric resonance, the stiffness pumped at Ω).
#[test]
fn sweep_finds_resonance_at_half_one_and_twice_f0() {
    let dir = out_dir("sweep");
    let v = json(&["sweep", "--out", &dir, "--json"]);
    // f0 at 6000 V, from the core's statics (tested against an independent force law).
    let device = de_resonator::Device::new(de_resonator::REFERENCE_DEVICE).unwrap();
    let stretch = device.stretch_for_bias(6000.0, 3.0).unwrap();
    let f0 = device.natural_frequency_hz(stretch);
    assert!((v["natural_frequency_hz"].as_f64().unwrap() - f0).abs() < 1e-9 * f0);
    let ratios: Vec<f64> = v["peaks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["drive_hz"].as_f64().unwrap() / f0)
        .collect();
    for expected in [0.5, 1.0, 2.0] {
        assert!(
            ratios
                .iter()
                .any(|r| (r - expected).abs() < 0.05 * expected),
            "no peak near {expected}·f0 in {ratios:?}"
        );
    }
    // Nothing else stands out.
    assert_eq!(ratios.len(), 3, "{ratios:?}");
    let csv = std::fs::read_to_string(v["csv"].as_str().unwrap()).unwrap();
    assert_eq!(csv.lines().count(), 1 + 211);
    let svg = std::fs::read_to_string(v["plot"].as_str().unwrap()).unwrap();
    assert!(svg.starts_with("<svg"));
}

/// Parametric resonance at 2·f0 has a threshold (Mathieu, with damping): the stiffness
/// ω̄² − Φ̄²λ2p² is pumped with relative depth h = 2·Φ̄dc·Φ̄ac·λ2p²/ω̄², and the rest state
/// grows only when h > 2/Q. At twice the threshold amplitude a peak shows at 2·f0; at half
/// of it none does.
#[test]
fn parametric_resonance_needs_the_mathieu_threshold() {
    let device = de_resonator::Device::new(de_resonator::REFERENCE_DEVICE).unwrap();
    let (bias, quality) = (6000.0, 50.0);
    let stretch = device.stretch_for_bias(bias, 3.0).unwrap();
    let l2p = 2.0;
    let dc = bias / device.volts_per_unit();
    let omega2 = device.stiffness_dimless(stretch, dc * dc);
    let threshold_volts =
        (2.0 / quality) * omega2 / (2.0 * dc * l2p * l2p) * device.volts_per_unit();
    assert!(
        threshold_volts > 1000.0 && threshold_volts < 3000.0,
        "{threshold_volts}"
    );
    let peaks_near_two = |ac: f64| {
        let dir = out_dir(&format!("mathieu-{ac}"));
        let v = json(&[
            "sweep",
            "--bias-volts",
            "6000",
            "--ac-volts",
            &ac.to_string(),
            "--quality",
            "50",
            "--from-ratio",
            "1.9",
            "--to-ratio",
            "2.1",
            "--points",
            "41",
            "--out",
            &dir,
            "--json",
        ]);
        let f0 = v["natural_frequency_hz"].as_f64().unwrap();
        v["peaks"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|p| (p["drive_hz"].as_f64().unwrap() / f0 - 2.0).abs() < 0.05)
            .count()
    };
    assert!(peaks_near_two(2.0 * threshold_volts) >= 1);
    assert_eq!(peaks_near_two(0.5 * threshold_volts), 0);
}

/// The work-precision study: the reference's floor is stated and tiny, RK4's error falls
/// 16-fold and Verlet's 4-fold per halving of the step (orders 4 and 2) in f64, and f32 RK4
/// at 64 steps a period keeps the phase within 2e-3 rad.
#[test]
fn report_measures_error_against_run_time() {
    let dir = out_dir("report");
    let v = json(&["report", "--out", &dir, "--json"]);
    assert_eq!(v["reference"]["tolerance"], 1e-12);
    let floor = v["reference"]["floor"].as_f64().unwrap();
    assert!(floor > 0.0 && floor < 1e-10, "{floor}");
    let rows = v["rows"].as_array().unwrap();
    let row = |scene: &str, method: &str, n: u64| {
        rows.iter()
            .find(|r| r["scene"] == scene && r["method"] == method && r["steps_per_period"] == n)
            .unwrap_or_else(|| panic!("{scene} {method} {n}"))
    };
    let error = |scene, method, n| row(scene, method, n)["max_error"].as_f64().unwrap();
    let rk4 = error("small_oscillation", "rk4-f64", 32) / error("small_oscillation", "rk4-f64", 64);
    assert!((10.0..26.0).contains(&rk4), "RK4 ratio {rk4}");
    let verlet = error("small_oscillation", "verlet-f64", 64)
        / error("small_oscillation", "verlet-f64", 128);
    assert!((3.0..5.5).contains(&verlet), "Verlet ratio {verlet}");
    for scene in ["small_oscillation", "parametric", "near_limit"] {
        let phase = row(scene, "rk4-f32", 64)["phase_error_rad"]
            .as_f64()
            .unwrap();
        assert!(phase < 2e-3, "{scene}: {phase}");
        let time = row(scene, "rk4-f64", 64)["run_seconds_per_simulated_second"].as_f64();
        assert!(time.unwrap() > 0.0);
    }
    assert_eq!(rows.len(), 3 * 6 * 7);
    let csv = std::fs::read_to_string(v["csv"].as_str().unwrap()).unwrap();
    assert_eq!(csv.lines().count(), 1 + rows.len());
}

/// A reader that stops early is not a crash: host-sim writing into a pipe nobody reads
/// (its read end closed before host-sim starts) ends with status 0, not a "Broken pipe"
/// panic (101).
#[test]
fn a_closed_pipe_is_not_a_panic() {
    for args in [
        &["safe"][..],
        &["safe", "--json"],
        &["tune", "--target-hz", "44"],
    ] {
        let (reader, writer) = std::io::pipe().expect("a pipe");
        drop(reader);
        let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
            .args(args)
            .stdout(writer)
            .stderr(std::process::Stdio::piped())
            .output()
            .expect("host-sim runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}
