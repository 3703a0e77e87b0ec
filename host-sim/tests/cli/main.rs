//! The `host-sim` command line, run as a user runs it.

use std::io::Write;
use std::process::{Command, Output};

use serde_json::Value;

mod dynamics;
mod image;

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

/// Exit status 1 (done, but a limit was crossed or the controller refused): the report on
/// stdout as JSON, and the last line of stderr says why.
fn crossed(args: &[&str]) -> (Value, String) {
    let out = host_sim(args);
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    let last = err.lines().last().unwrap_or("").to_string();
    assert!(last.starts_with("error: "), "{err}");
    let v = serde_json::from_slice(&out.stdout).expect("the report on stdout");
    (v, last)
}

/// Done (exit status 0, or 1 if a limit was crossed): the report.
fn ran(args: &[&str]) -> Value {
    let out = host_sim(args);
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object on stdout")
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

/// A neo-Hookean device from a file: f at zero bias in closed form (model.md §5),
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
/// A device file with tolerances (model.md §10): `safe` gives the guaranteed limit, which no
/// corner device's own `safe` (a device file each, no tolerances) lies below, and which the
/// lowest corner's lies within 3% of; `tune` gives the band, which holds the nominal
/// device's frequency. The same file without the table answers as before, with no `guaranteed`.
#[test]
fn a_batch_has_a_guaranteed_limit_and_band() {
    let nominal = "jlim = 120\nprestretch_1 = 2.0\nprestretch_2 = 2.0\n";
    let batch = DeviceFile::new(
        "batch.toml",
        &format!(
            "{nominal}[tolerance]\nshear_modulus = 0.1\nthickness = 0.05\n\
             prestretch_1 = 0.02\nbreakdown_field = [35e6, 200e6]\n"
        ),
    );
    let v = json(&["safe", "--device", batch.path(), "--json"]);
    let g = &v["guaranteed"];
    let guaranteed = g["limit"]["volts"].as_f64().unwrap();
    assert_eq!(g["limit"]["at"].as_object().unwrap().len(), 4);
    let mut lowest = f64::INFINITY;
    for corner in 0..16 {
        let pick =
            |bit: u32, low: f64, high: f64| if corner & (1 << bit) == 0 { low } else { high };
        let text = format!(
            "jlim = 120\nprestretch_2 = 2.0\nshear_modulus = {}\nthickness = {}\n\
             prestretch_1 = {}\nbreakdown_field = {}\n",
            pick(0, 40.5e3, 49.5e3),
            pick(1, 0.95e-3, 1.05e-3),
            pick(2, 1.96, 2.04),
            pick(3, 35e6, 200e6)
        );
        let file = DeviceFile::new(&format!("corner{corner}.toml"), &text);
        let c = json(&["safe", "--device", file.path(), "--json"]);
        let volts = c["limit"]["volts"].as_f64().unwrap();
        assert!(
            volts >= guaranteed,
            "corner {corner}: {volts} V < {guaranteed} V"
        );
        lowest = lowest.min(volts);
    }
    assert!(guaranteed >= 0.97 * lowest, "{guaranteed} vs {lowest}");
    let cap = g["max_bias_volts"].as_f64().unwrap();
    assert!((cap - 0.95 * guaranteed).abs() <= 1e-9 * cap);

    let t = json(&[
        "tune",
        "--device",
        batch.path(),
        "--target-hz",
        "45",
        "--json",
    ]);
    let bias = t["bias_volts"].as_f64().unwrap();
    let band: Vec<f64> = t["band_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    // The nominal device is in the batch: its 45 Hz at that bias lies in the band.
    assert!(band[0] < 45.0 && 45.0 < band[1], "{band:?} at {bias} V");
    assert_eq!(t["every_device_reaches"], false);

    let plain = DeviceFile::new("plain.toml", nominal);
    let p = json(&["safe", "--device", plain.path(), "--json"]);
    assert!(p.get("guaranteed").is_none() && p["device"].get("tolerance").is_none());
    assert_eq!(p["limit"], v["limit"]);
}

/// Every key of the reference device (a file that leaves none out: nothing noted on stderr).
const REFERENCE_KEYS: &str = "shear_modulus = 45e3\njlim = 120\nrelative_permittivity = 4.7\n\
    density = 960\nbreakdown_field = 1e8\nthickness = 1e-3\nlength_active = 0.02\n\
    length_passive = 0.02\nwidth = 0.04\nbar_mass = 2e-3\nprestretch_1 = 2.0\n\
    prestretch_2 = 2.0\ndamping = 0\n";

/// `curve` on a batch: band.csv's band holds the file's device's own curve below the
/// guaranteed cap, and both guides are drawn; a family of pre-stretches with tolerances is
/// refused, saying what to do.
#[test]
fn a_batch_curve_draws_its_band() {
    let batch = DeviceFile::new(
        "batch-curve.toml",
        &format!("{REFERENCE_KEYS}[tolerance]\nshear_modulus = 0.05\nthickness = 0.02\n"),
    );
    let dir = std::env::temp_dir().join(format!("host-sim-cli-curve-{}", std::process::id()));
    let out = dir.to_str().unwrap();
    let v = json(&[
        "curve",
        "--device",
        batch.path(),
        "--points",
        "50",
        "--out",
        out,
        "--json",
    ]);
    let cap = v["guaranteed"]["max_bias_volts"].as_f64().unwrap();
    let band = v["band"].as_array().unwrap();
    assert_eq!(band.last().unwrap()["bias_volts"].as_f64().unwrap(), cap);
    // The nominal device's own frequency at each band point's bias, from its curve's points
    // (the nearest below and above, f monotone there): inside the band.
    let points = v["curves"][0]["points"].as_array().unwrap();
    for b in band {
        let bias = b["bias_volts"].as_f64().unwrap();
        let (low, high) = (
            b["low_hz"].as_f64().unwrap(),
            b["high_hz"].as_f64().unwrap(),
        );
        for p in points.windows(2) {
            let (v0, v1) = (
                p[0]["bias_volts"].as_f64().unwrap(),
                p[1]["bias_volts"].as_f64().unwrap(),
            );
            if v0 <= bias && bias <= v1 {
                for q in p {
                    let f = q["natural_frequency_hz"].as_f64().unwrap();
                    assert!(
                        low < f && f < high,
                        "{f} Hz outside {low}..{high} at {bias} V"
                    );
                }
            }
        }
    }
    let svg = std::fs::read_to_string(dir.join("curve.svg")).unwrap();
    assert!(svg.contains("batch's guaranteed limit") && svg.contains("every device of the batch"));
    assert!(dir.join("band.csv").exists());
    let err = refused(&[
        "curve",
        "--device",
        batch.path(),
        "--prestretch-1",
        "1.5:2.5:3",
        "--out",
        out,
    ]);
    assert!(err.contains("[tolerance]"), "{err}");
    let _ = std::fs::remove_dir_all(dir);
}

/// A target beyond the guaranteed cap is refused, naming both figures.
#[test]
fn a_batch_refuses_a_target_only_its_nominal_device_reaches_safely() {
    let batch = DeviceFile::new(
        "batch-low.toml",
        &format!("{REFERENCE_KEYS}[tolerance]\nbreakdown_field = [35e6, 200e6]\n"),
    );
    let err = refused(&["tune", "--device", batch.path(), "--target-hz", "43.1"]);
    assert!(err.contains("above the guaranteed cap"), "{err}");
    assert!(err.contains("breakdown"), "{err}");
}

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

/// Issue 29, 7: a device file's left-out keys are noted and values no membrane has are
/// warned of on stderr (the report unchanged on stdout); a tunable range closed at 0 V is
/// said as such, with the mode that closes it.
#[test]
fn device_files_are_read_aloud() {
    let dir = std::env::temp_dir().join(format!("host-sim-notes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let metres = dir.join("metres.toml");
    std::fs::write(&metres, "thickness = 50\njlim = 120\n").unwrap();
    let out = host_sim(&["safe", "--device", metres.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning: device file") && err.contains("`thickness` = 50 m is outside"),
        "{err}"
    );
    assert!(err.contains("values taken: shear_modulus,"), "{err}");
    assert!(!err.contains("neo-Hookean"), "{err}");
    let closed = dir.join("closed.toml");
    std::fs::write(&closed, "breakdown_field = 1\n").unwrap();
    let out = host_sim(&["safe", "--device", closed.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("tunable range   none: only ")
            && text.contains("the breakdown limit closes it"),
        "{text}"
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no `jlim`: the material is neo-Hookean"),
        "{err}"
    );
    assert!(
        err.contains("`breakdown_field` = 1 V/m is outside"),
        "{err}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// Issue 29, 10: the command line's rules, one each. `--csv -` is stdout (the report then on
/// stderr); every output's folder is made before the work, for every command; the curve's
/// columns never run together; a sweep that measures nothing does not exit 0.
#[test]
fn one_rule_for_outputs_and_columns() {
    let dir = std::env::temp_dir().join(format!("host-sim-rules-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    // stdout: the CSV alone, its header first, as many rows as steps + 1.
    let out = host_sim(&[
        "simulate",
        "--bias-volts",
        "5000",
        "--duration-seconds",
        "0.01",
        "--step-seconds",
        "0.001",
        "--csv",
        "-",
    ]);
    assert!(out.status.success());
    let csv = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "time_seconds,stretch,velocity_per_second,volts");
    assert_eq!(lines.len(), 12, "{csv}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("method          reference"));
    assert!(!std::path::Path::new("-").exists());
    // Folders made for every output, before the work.
    let lut = dir.join("a/b/table.bin");
    let image = dir.join("c/d/reference.img");
    let plot = dir.join("e/f/x.svg");
    for args in [
        vec!["lut", "--out", lut.to_str().unwrap()],
        vec!["image", "--out", image.to_str().unwrap()],
        vec![
            "simulate",
            "--bias-volts",
            "5000",
            "--duration-seconds",
            "0.01",
            "--plot",
            plot.to_str().unwrap(),
        ],
    ] {
        let out = host_sim(&args);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    assert!(lut.is_file() && image.is_file() && plot.is_file());
    // A neo-Hookean device read back from an image: `jlim = none`, not 0 (which a device
    // file refuses).
    let neo = dir.join("neo.toml");
    std::fs::write(&neo, "shear_modulus = 45000\n").unwrap();
    let neo_image = dir.join("neo.img");
    let out = host_sim(&[
        "image",
        "--device",
        neo.to_str().unwrap(),
        "--target-hz",
        "42",
        "--out",
        neo_image.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text =
        String::from_utf8(host_sim(&["image", "--check", neo_image.to_str().unwrap()]).stdout)
            .unwrap();
    assert!(
        text.contains("jlim = none") && !text.contains("jlim = 0"),
        "{text}"
    );
    // Columns: the longest limit (`loss_of_tension_2a at … V`) still has two spaces after it,
    // and every row's next column starts where the header's does.
    let out = host_sim(&[
        "curve",
        "--device",
        neo.to_str().unwrap(),
        "--prestretch-1",
        "3",
        "--prestretch-2",
        "0.8:1.0:2",
        "--out",
        dir.join("curve").to_str().unwrap(),
    ]);
    let text = String::from_utf8(out.stdout).unwrap();
    let header = text.lines().find(|l| l.starts_with("λ1p")).unwrap();
    // In characters: the header's λ is two bytes.
    let column = header[..header.find("max bias V").unwrap()].chars().count();
    let rows: Vec<&str> = text.lines().filter(|l| l.contains(" at ")).collect();
    assert!(
        rows.iter().any(|r| r.contains("loss_of_tension_2a")),
        "{text}"
    );
    for row in rows {
        let chars: Vec<char> = row.chars().collect();
        assert_eq!(chars[column - 2..column], [' ', ' '], "{row}");
        assert!(chars[column].is_ascii_digit(), "{row}");
    }
    // A sweep damped past any measurement is refused (the guard), not a silent exit 0.
    let out = host_sim(&[
        "sweep",
        "--quality-factor",
        "1e-9",
        "--out",
        dir.join("s").to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    std::fs::remove_dir_all(dir).unwrap();
}

/// Issue 29, 13: `run`'s events carry fields, not only words: the reference scene's
/// `at_bias` holds the f64 solve's bias for 44 Hz (`tune`, an independent path) within a DAC
/// step, and the AC comes on after it.
#[test]
fn run_events_have_kinds_and_values() {
    let dir = out_dir("run-events");
    let v = ran(&["--json", "run", "--out", &dir]);
    let events = v["events"].as_array().unwrap();
    let kinds: Vec<&str> = events.iter().map(|e| e["kind"].as_str().unwrap()).collect();
    let at = kinds.iter().position(|k| *k == "at_bias").unwrap();
    let on = kinds.iter().position(|k| *k == "drive_on").unwrap();
    assert!(at < on, "{kinds:?}");
    let volts = events[at]["values"]["volts"].as_f64().unwrap();
    let tuned = json(&["tune", "--target-hz", "44", "--json"])["bias_volts"]
        .as_f64()
        .unwrap();
    // One step of the 16-bit DAC at 2.5 V × 4000.
    assert!(
        (volts - tuned).abs() <= 1e4 / 65536.0 + 1e-3,
        "{volts} vs {tuned}"
    );
    assert_eq!(events[on]["values"], serde_json::json!({}));
    assert!(events[at]["what"].as_str().unwrap().starts_with("at bias"));
    // The board's cap: (1 − margin) of the limit `safe` finds in f64, less the f32 guard.
    let cap = v["cap_volts"].as_f64().unwrap();
    let safe = json(&["safe", "--json"])["max_bias_volts"]
        .as_f64()
        .unwrap();
    assert!(
        (cap / safe - 1.0).abs() < 1e-4 && cap <= safe,
        "{cap} vs {safe}"
    );
}

/// A fresh output folder for a command that writes files.
fn out_dir(name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("host-sim-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir.to_str().unwrap().to_string()
}

/// A reader that stops early is not a crash: host-sim writing into a pipe nobody reads
/// (its read end closed before host-sim starts) ends with status 0, not a "Broken pipe"
/// panic (101).
#[test]
fn a_closed_pipe_is_not_a_panic() {
    let sweep = out_dir("pipe-sweep");
    let curve = out_dir("pipe-curve");
    for args in [
        &["safe"][..],
        &["safe", "--json"],
        &["tune", "--target-hz", "44"],
        &[
            "sweep",
            "--json",
            "--points",
            "5",
            "--periods",
            "8",
            "--ac-volts",
            "100",
            "--out",
            &sweep,
        ],
        &["curve", "--json", "--out", &curve],
        &[
            "simulate",
            "--bias-volts",
            "7000",
            "--duration-seconds",
            "0.1",
        ],
        &["lut", "--out", "/dev/null", "--json"],
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

/// A scene file in a scratch folder (its own folder per test), and that folder for `--out`.
fn scene_file(test: &str, text: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let dir = std::env::temp_dir().join(format!("host-sim-cli-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    (path, dir.join("out"))
}

/// The exit-status rule (`host-sim --help`): 0 done and safe; 1 done, report on stdout, but
/// a limit was crossed or the controller refused; 2 bad input, nothing on stdout. The same
/// unreachable target is 2 in `tune` (nothing done) and 1 in a scene (the controller ran
/// and refused, 0 V throughout).
#[test]
fn one_exit_status_rule() {
    assert_eq!(host_sim(&["safe"]).status.code(), Some(0));
    refused(&["tune", "--target-hz", "50"]);
    refused(&["safe", "--margin", "2"]);
    refused(&["simulate", "--bias-volts", "7000"]);
    let (scene, out) = scene_file(
        "refusing-scene",
        "name = \"unreachable\"\nduration_seconds = 0.2\n[controller]\ntarget_hz = 50.0\n",
    );
    let (v, why) = crossed(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(!v["refused"].is_null(), "{v}");
    assert!(why.contains("refused"), "{why}");
    assert_eq!(v["final_membrane_volts"], 0.0);
    // A fault is the controller refusing to go on: 1, the report on stdout.
    let scenes = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/");
    let (v, why) = crossed(&[
        "run",
        &format!("{scenes}fault-dac-bus.toml"),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(!v["fault"].is_null() && why.contains("faulted"), "{why}");
}

/// Work beyond the bounds is refused before it starts, with an estimate, never aborted:
/// 1e9 s of simulation, a scene of 1e9 s or at 1e9 Hz, 1e8 sweep points.
#[test]
fn work_beyond_the_bounds_is_refused_up_front() {
    let err = refused(&[
        "simulate",
        "--bias-volts",
        "100",
        "--duration-seconds",
        "1e9",
    ]);
    assert!(err.contains("steps"), "{err}");
    let err = refused(&[
        "simulate",
        "--bias-volts",
        "100",
        "--duration-seconds",
        "1",
        "--step-seconds",
        "1e-12",
    ]);
    assert!(err.contains("1.00000e12 steps"), "{err}");
    for (test, text) in [
        (
            "long-scene",
            "name = \"long\"\nduration_seconds = 1e9\n[controller]\ntarget_hz = 44.0\n",
        ),
        (
            "fast-scene",
            "name = \"fast\"\n[controller]\ntarget_hz = 44.0\ntick_hz = 1e9\n",
        ),
    ] {
        let (scene, out) = scene_file(test, text);
        let err = refused(&[
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(err.contains("ticks") && err.contains("work"), "{err}");
        assert!(!out.exists(), "nothing written");
    }
    let err = refused(&["sweep", "--points", "100000000", "--out", &out_dir("huge")]);
    assert!(err.contains("at most"), "{err}");
    let err = refused(&["sweep", "--points", "100000", "--out", &out_dir("huge")]);
    assert!(err.contains("RK4 steps") && err.contains("work"), "{err}");
}

/// A scene's name is its folder under --out: one plain component, or the scene is refused
/// (nothing written anywhere). An --out that cannot take files is refused before the work.
#[test]
fn scene_names_and_output_folders_are_checked_first() {
    for name in ["../../escape", "a/b", "", ".hidden", "a\\\\b"] {
        let (scene, out) = scene_file(
            "names",
            &format!("name = \"{name}\"\n[controller]\ntarget_hz = 44.0\n"),
        );
        let err = refused(&[
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(err.contains("name"), "{name}: {err}");
        let parent = scene.parent().unwrap();
        let written: Vec<_> = std::fs::read_dir(parent).unwrap().collect();
        assert_eq!(written.len(), 1, "{name}: only the scene file");
    }
    // --out is a file, not a folder: refused at once, not after the run.
    let (scene, _) = scene_file(
        "out-is-a-file",
        "name = \"ok\"\n[controller]\ntarget_hz = 44.0\n",
    );
    let err = refused(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        scene.to_str().unwrap(),
    ]);
    assert!(err.contains("cannot"), "{err}");
    let err = refused(&["sweep", "--out", scene.to_str().unwrap()]);
    assert!(err.contains("cannot"), "{err}");
}

/// A plant softer than the device told (μ halved): its limit is √0.5 of the device's (Φ
/// scales with √μ, model.md §5), below the bias tuned for the device; the report gives that
/// limit and a negative margin, not 0% "below" a limit searched upward from the bias.
#[test]
fn a_bias_past_a_softer_plants_limit_shows_a_negative_margin() {
    let (scene, out) = scene_file(
        "soft-plant",
        "name = \"soft\"\nduration_seconds = 1.0\n[plant]\nshear_modulus_scale = 0.5\n\
         [controller]\ntarget_hz = 44.0\n",
    );
    let v = ran(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    let device_limit = 9854.73;
    let plant_limit = device_limit * 0.5f64.sqrt();
    let limit = v["limit"]["volts"].as_f64().unwrap();
    assert!(
        (limit - plant_limit).abs() < 1e-3 * plant_limit,
        "{limit} vs {plant_limit}"
    );
    let bias = v["bias_volts"].as_f64().unwrap();
    assert!((bias - 7449.88).abs() < 0.5, "{bias}");
    let margin = v["limit"]["margin"].as_f64().unwrap();
    assert!(
        (margin - (1.0 - bias / plant_limit)).abs() < 1e-3,
        "{margin}"
    );
    assert!(margin < -0.06, "{margin}");
    let text = String::from_utf8(
        host_sim(&[
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout,
    )
    .unwrap();
    assert!(text.contains("ABOVE the plant's limit"), "{text}");
}

/// Which material model ran is said: Gent with its jlim, or neo-Hookean when a file leaves
/// `jlim` out (a copied file without it is another device).
#[test]
fn the_material_model_is_named() {
    let v = json(&["safe", "--json"]);
    assert_eq!(v["device"]["material"], "gent");
    assert_eq!(v["device"]["jlim"], 120.0);
    let file = DeviceFile::new("no-jlim.toml", "shear_modulus = 45e3\n");
    let v = json(&["safe", "--device", file.path(), "--json"]);
    assert_eq!(v["device"]["material"], "neo_hookean");
    assert!(v["device"]["jlim"].is_null());
    let text = String::from_utf8(host_sim(&["safe", "--device", file.path()]).stdout).unwrap();
    assert!(text.contains("neo-Hookean"), "{text}");
    let text = String::from_utf8(host_sim(&["run", "--out", &out_dir("material")]).stdout).unwrap();
    assert!(text.contains("Gent, jlim 120"), "{text}");
}

/// Flags take negative numbers as values (the check then says what is wrong), an AC
/// amplitude needs its frequency, and `lut` writes what the file's extension says.
#[test]
fn flags_say_what_is_wrong() {
    let err = refused(&[
        "simulate",
        "--bias-volts",
        "7000",
        "--ac-hz",
        "-44",
        "--duration-seconds",
        "0.1",
    ]);
    assert!(err.contains("(--ac-hz) -44"), "{err}");
    let err = refused(&[
        "simulate",
        "--bias-volts",
        "7000",
        "--ac-volts",
        "100",
        "--duration-seconds",
        "0.1",
    ]);
    assert!(err.contains("needs ac_hz (--ac-hz)"), "{err}");
    let dir = out_dir("lut-ext");
    std::fs::create_dir_all(&dir).unwrap();
    let csv = format!("{dir}/table.csv");
    let v = json(&["lut", "--out", &csv, "--json"]);
    assert_eq!(v["format"], "csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(
        text.starts_with("natural_frequency_hz,bias_volts"),
        "{text}"
    );
    refused(&["lut", "--out", &csv, "--format", "bin"]);
}

/// The tuning curve agrees with `safe` and `tune` (published figures of the reference
/// device: f(0) = 45.9527 Hz, the limit EMI at 9854.73 V, 44 Hz at 7449.88 V), falls
/// monotonically to the limit on the reference device, and a family over λ1p draws one
/// curve a pre-stretch, each ending at its own `safe` limit.
#[test]
fn the_tuning_curve_and_its_family() {
    let dir = out_dir("curve");
    let v = json(&["curve", "--target-hz", "44", "--out", &dir, "--json"]);
    let c = &v["curves"][0];
    rounds_to(&c["limit"]["volts"], 9854.73, 2);
    assert_eq!(c["limit"]["mode"], "emi");
    rounds_to(&c["target"]["bias_volts"], 7449.88, 2);
    let points = c["points"].as_array().unwrap();
    rounds_to(&points[0]["natural_frequency_hz"], 45.9527, 4);
    assert_eq!(points[0]["bias_volts"], 0.0);
    let f: Vec<f64> = points
        .iter()
        .map(|p| p["natural_frequency_hz"].as_f64().unwrap())
        .collect();
    assert!(f.windows(2).all(|w| w[1] <= w[0]), "f falls with bias here");
    let max = c["max_bias_volts"].as_f64().unwrap();
    assert!(points
        .iter()
        .all(|p| p["beyond_margin"] == (p["bias_volts"].as_f64().unwrap() > max)));
    let v = json(&[
        "curve",
        "--prestretch-1",
        "1.5:3:4",
        "--out",
        &dir,
        "--json",
    ]);
    let curves = v["curves"].as_array().unwrap();
    assert_eq!(curves.len(), 4);
    for (k, c) in curves.iter().enumerate() {
        let l1 = 1.5 + 0.5 * k as f64;
        assert!((c["prestretch_1"].as_f64().unwrap() - l1).abs() < 1e-12);
        let file = DeviceFile::new(
            &format!("l1-{k}.toml"),
            &format!("jlim = 120\nprestretch_1 = {l1}\n"),
        );
        let safe = json(&["safe", "--device", file.path(), "--json"]);
        assert_eq!(c["limit"]["volts"], safe["limit"]["volts"]);
        let last = c["points"].as_array().unwrap().last().unwrap()["bias_volts"]
            .as_f64()
            .unwrap();
        assert!((last - safe["limit"]["volts"].as_f64().unwrap()).abs() < 1e-6 * last);
    }
    refused(&["curve", "--prestretch-1", "1:2"]);
    refused(&["curve", "--prestretch-1", "1:2:100000"]);
}
