//! `host-sim image` and `host-sim console`, run as a user runs them: the image written, read
//! back and refused when wrong; the console without a board. The console against a board is
//! in `serve.rs` (the virtual board).

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

fn host_sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .expect("host-sim runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("host-sim-image-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn stdout_json(out: &Output) -> Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "{e}: {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    })
}

#[test]
fn an_image_is_written_checked_and_read_back() {
    let path = scratch("reference.img");
    let p = path.to_str().unwrap();
    let out = host_sim(&["--json", "image", "--target-hz", "44", "--out", p]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let written = stdout_json(&out);
    // The boot's bias is the f64 solve's (host-sim tune) within the f32 solve's 1e-4.
    let tuned = stdout_json(&host_sim(&["--json", "tune", "--target-hz", "44"]));
    let bias = written["verdict"]["bias_volts"].as_f64().unwrap();
    let expected = tuned["bias_volts"].as_f64().unwrap();
    assert!(
        (bias - expected).abs() <= 1e-4 * expected,
        "{bias} vs {expected}"
    );
    assert_eq!(written["verdict"]["verdict"], "drives");
    // Read back: the same report, from the file.
    let read = stdout_json(&host_sim(&["--json", "image", "--check", p]));
    assert_eq!(read["verdict"], written["verdict"]);
    assert_eq!(read["settings"], written["settings"]);
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(read["bytes"].as_u64().unwrap() as usize, bytes.len());
    // Corrupted: status 1, the firmware's words.
    let mut bad = bytes.clone();
    bad[100] ^= 1;
    let bad_path = scratch("bad.img");
    std::fs::write(&bad_path, &bad).unwrap();
    let out = host_sim(&["image", "--check", bad_path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stdout).contains("CRC"));
}

#[test]
fn an_image_needs_a_target_for_another_device_and_refuses_what_the_firmware_would() {
    let device = scratch("stiff.toml");
    std::fs::write(&device, "shear_modulus = 60000.0\n").unwrap();
    let d = device.to_str().unwrap();
    let out_path = scratch("stiff.img");
    let o = out_path.to_str().unwrap();
    let out = host_sim(&["image", "--device", d, "--out", o]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--target-hz"));
    // A target outside the device's range: the firmware would refuse, so nothing is written.
    let _ = std::fs::remove_file(&out_path);
    let out = host_sim(&["image", "--device", d, "--target-hz", "5", "--out", o]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("would refuse"));
    assert!(!out_path.exists());
}

#[test]
fn a_console_without_a_firmware_says_so() {
    let out = host_sim(&[
        "console",
        "--unix",
        "/nonexistent/fw.sock",
        "--script",
        "/dev/null",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot connect"));
    let out = host_sim(&["console", "--script", "/dev/null"]);
    assert_eq!(out.status.code(), Some(2));
}
