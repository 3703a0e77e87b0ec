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
    let said = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{said}");
    assert!(said.contains("--target-hz"), "{said}");
    // A target outside the device's range: the firmware would refuse, so nothing is written.
    let _ = std::fs::remove_file(&out_path);
    let out = host_sim(&["image", "--device", d, "--target-hz", "5", "--out", o]);
    let said = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{said}");
    assert!(said.contains("would refuse"), "{said}");
    assert!(!out_path.exists(), "{} written: {said}", out_path.display());
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

/// The board's analog front end from a settings file's `[front_end]`: written into the image
/// and read back as given (JSON and text); a front end the board cannot read (a channel on the
/// command port's pin, a range reaching a rail) or a table with a key missing is refused by
/// name and nothing is written.
#[test]
fn an_images_front_end_is_written_read_back_and_refused_when_wrong() {
    let settings = scratch("front-end.toml");
    let front_end = "target_hz = 44.0\n\
        [front_end]\nscan_hz = 10000\n\
        [front_end.current]\ninput = 10\nzero_code = 2047.5\nper_count = 1e-7\nlow = -1.9e-4\nhigh = 1.9e-4\n\
        [front_end.stretch]\ninput = 12\nzero_code = -4116.6667\nper_count = 3.2432432e-4\nlow = 1.4\nhigh = 2.6\n";
    std::fs::write(&settings, front_end).unwrap();
    let s = settings.to_str().unwrap();
    let path = scratch("front-end.img");
    let p = path.to_str().unwrap();
    let out = host_sim(&["image", "--settings", s, "--out", p]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read = stdout_json(&host_sim(&["--json", "image", "--check", p]));
    let fe = &read["front_end"];
    assert_eq!(fe["scan_hz"].as_f64(), Some(10_000.0));
    let channels = fe["channels"].as_array().unwrap();
    assert_eq!(channels.len(), 2, "{fe}");
    assert_eq!(channels[0]["channel"], "current");
    assert_eq!(channels[0]["input"], 10);
    assert_eq!(channels[0]["per_count"].as_f64().unwrap() as f32, 1e-7);
    assert_eq!(channels[1]["channel"], "stretch");
    assert_eq!(channels[1]["low"].as_f64().unwrap() as f32, 1.4);
    assert_eq!(channels[1]["high"].as_f64().unwrap() as f32, 2.6);
    let text = String::from_utf8_lossy(&host_sim(&["image", "--check", p]).stdout).to_string();
    assert!(text.contains("current       ADC IN10"), "{text}");
    assert!(!text.contains("amplifier     ADC"), "{text}");
    // The default image: no analog input, said so.
    let plain = scratch("plain.img");
    host_sim(&[
        "image",
        "--target-hz",
        "44",
        "--out",
        plain.to_str().unwrap(),
    ]);
    let text =
        String::from_utf8_lossy(&host_sim(&["image", "--check", plain.to_str().unwrap()]).stdout)
            .to_string();
    assert!(text.contains("none fitted: open loop"), "{text}");

    for (wrong, words) in [
        (
            front_end.replace("input = 12", "input = 3"),
            "not an analog input",
        ),
        (
            front_end.replace("zero_code = 2047.5", "zero_code = 0"),
            "live zero",
        ),
        (front_end.replace("low = 1.4\n", ""), "needs `low`"),
        (
            front_end.replace("scan_hz = 10000", "scan_hz = 10500"),
            "whole number of scans",
        ),
    ] {
        std::fs::write(&settings, &wrong).unwrap();
        let bad = scratch("bad-front-end.img");
        let _ = std::fs::remove_file(&bad);
        let out = host_sim(&["image", "--settings", s, "--out", bad.to_str().unwrap()]);
        let said = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{said}");
        assert!(said.contains(words), "{words}: {said}");
        assert!(!bad.exists());
    }
}
