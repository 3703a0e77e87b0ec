//! Every command's `--json` against the one documented JSON schema (`host-sim/schema.json`,
//! a definition per command under `$defs`): a key renamed, added, dropped or of another type
//! in either place fails here.

use std::process::Command;

use serde_json::{json, Value};

fn schema() -> Value {
    let text = include_str!("../schema.json");
    serde_json::from_str(text).expect("schema.json is JSON")
}

/// `host-sim args` (exit status 0 or 1: a report), its stdout checked against
/// `$defs/<command>`.
fn conforms(command: &str, args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .arg(command)
        .args(args)
        .arg("--json")
        .output()
        .expect("host-sim runs");
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "{command} {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let mut wrapper = schema();
    wrapper["$ref"] = json!(format!("#/$defs/{command}"));
    let validator = jsonschema::validator_for(&wrapper).expect("a valid JSON Schema");
    let errors: Vec<String> = validator
        .iter_errors(&report)
        .map(|e| format!("{} at {}", e, e.instance_path()))
        .collect();
    assert!(
        errors.is_empty(),
        "{command} {args:?}:\n{}",
        errors.join("\n")
    );
}

fn scratch(name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("host-sim-schema-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.to_str().unwrap().to_string()
}

#[test]
fn every_command_matches_the_schema() {
    let dir = scratch("all");
    let neo = format!("{dir}/neo.toml");
    std::fs::write(&neo, "shear_modulus = 45e3\n").unwrap();
    let stretched = format!("{dir}/stretched.toml");
    std::fs::write(&stretched, "jlim = 120\nprestretch_1 = 2.5\n").unwrap();
    let refusing = format!("{dir}/refusing.toml");
    std::fs::write(
        &refusing,
        "name = \"refusing\"\nduration_seconds = 0.1\n[controller]\ntarget_hz = 50.0\n",
    )
    .unwrap();
    let scenes = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/");
    let (table, image) = (format!("{dir}/t.bin"), format!("{dir}/i.img"));
    conforms("safe", &[]);
    conforms("safe", &["--device", &neo]);
    conforms("tune", &["--target-hz", "44"]);
    let batch = format!("{dir}/batch.toml");
    std::fs::write(
        &batch,
        "jlim = 120\n[tolerance]\nshear_modulus = 0.05\nbreakdown_field = [35e6, 200e6]\n",
    )
    .unwrap();
    conforms("safe", &["--device", &batch]);
    conforms("tune", &["--device", &batch, "--target-hz", "45"]);
    conforms(
        "curve",
        &[
            "--device",
            &batch,
            "--points",
            "5",
            "--out",
            &format!("{dir}/batch-curve"),
        ],
    );
    let batch_image = format!("{dir}/batch.img");
    conforms(
        "image",
        &[
            "--device",
            &batch,
            "--target-hz",
            "45.5",
            "--out",
            &batch_image,
        ],
    );
    conforms(
        "curve",
        &["--target-hz", "44", "--points", "5", "--out", &dir],
    );
    conforms(
        "curve",
        &[
            "--prestretch-1",
            "1.5:3:3",
            "--prestretch-2",
            "0.5:2:2",
            "--target-hz",
            "44",
            "--points",
            "3",
            "--out",
            &dir,
        ],
    );
    conforms(
        "simulate",
        &["--bias-volts", "7000", "--duration-seconds", "0.05"],
    );
    conforms(
        "simulate",
        &[
            "--bias-volts",
            "9400",
            "--start",
            "prestretch",
            "--duration-seconds",
            "0.03",
            "--method",
            "rk4-f32",
        ],
    );
    conforms(
        "sweep",
        &[
            "--points",
            "7",
            "--periods",
            "8",
            "--from-ratio",
            "0.8",
            "--to-ratio",
            "1.2",
            "--out",
            &dir,
        ],
    );
    conforms(
        "simulate",
        &[
            "--bias-volts",
            "7000",
            "--duration-seconds",
            "0.05",
            "--y0",
            "2.2,-1",
            "--t-eval",
            "0:0.05:11",
            "--trajectory",
        ],
    );
    let drive = [
        "--bias-volts",
        "6000",
        "--ac-volts",
        "1500",
        "--ac-hz",
        "85",
    ];
    let with = |more: &[&'static str]| -> Vec<String> {
        drive
            .iter()
            .chain(more)
            .map(|s| s.to_string())
            .chain(["--out".to_string(), dir.clone()])
            .collect()
    };
    let args = with(&["--periods", "5", "--y0", "2.2,0;2.3,0"]);
    conforms(
        "poincare",
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    // A drive that crosses a limit: its crossing in the report.
    let crossing = [
        "--bias-volts",
        "9500",
        "--ac-volts",
        "2500",
        "--ac-hz",
        "80",
        "--periods",
        "20",
        "--out",
        &dir,
    ];
    conforms("poincare", &crossing);
    let args = with(&[
        "--values",
        "0:1500:3",
        "--periods",
        "3",
        "--transient-periods",
        "2",
    ]);
    conforms(
        "bifurcation",
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    let args = with(&["--periods", "10", "--quality-factor", "50"]);
    conforms(
        "lyapunov",
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    conforms(
        "drive-map",
        &[
            "--quality-factor",
            "100",
            "--ac-volts",
            "0,2000",
            "--ac-hz",
            "44,88",
            "--periods",
            "20",
            "--out",
            &dir,
        ],
    );
    conforms("lut", &["--out", &table]);
    conforms("image", &["--out", &image]);
    conforms("image", &["--check", &image]);
    conforms("image", &["--check", &table]);
    conforms("run", &["--out", &dir]);
    conforms("run", &[&refusing, "--out", &dir]);
    conforms(
        "run",
        &[&format!("{scenes}fault-dac-bus.toml"), "--out", &dir],
    );
    conforms("stress", &["--device", &stretched]);
}

/// The report is the slowest command: its own test, so the rest report sooner.
#[test]
fn the_work_precision_report_matches_the_schema() {
    conforms("report", &["--out", &scratch("report")]);
}

mod common;

/// `console --json` against the virtual board (`serve`) on TCP, and `serve --json` itself.
#[test]
fn the_console_the_dash_and_the_virtual_board_match_the_schema() {
    let board = common::Served::start(None, "max", "tcp");
    let dir = scratch("console");
    let script = format!("{dir}/script.txt");
    std::fs::write(
        &script,
        "status
nonsense
",
    )
    .unwrap();
    let mut args: Vec<&str> = board.connection.iter().map(String::as_str).collect();
    args.extend(["--script", &script]);
    conforms("console", &args);
    let mut args: Vec<&str> = board.connection.iter().map(String::as_str).collect();
    args.extend(["--listen", "127.0.0.1:0", "--seconds", "0.5"]);
    conforms("dash", &args);
    drop(board);
    let socket = format!("{dir}/serve.sock");
    conforms(
        "serve",
        &["--unix", &socket, "--speed", "max", "--seconds", "0.5"],
    );
}
