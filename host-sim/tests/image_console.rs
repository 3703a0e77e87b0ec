//! `host-sim image` and `host-sim console`, run as a user runs them: the image written, read
//! back and refused when wrong; the console against a stand-in firmware on a Unix socket that
//! answers in the core's protocol.

use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixListener;
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

/// A stand-in firmware: the start-up notice, then `ok …` to `status`, `err 2 …` to the rest.
fn stand_in(socket: &PathBuf) -> std::thread::JoinHandle<Vec<String>> {
    let _ = std::fs::remove_file(socket);
    let listener = UnixListener::bind(socket).unwrap();
    std::thread::spawn(move || {
        let (stream, _) = listener.accept().unwrap();
        let mut writer = stream.try_clone().unwrap();
        writeln!(writer, "# ready target_hz=44").unwrap();
        let mut seen = Vec::new();
        for line in BufReader::new(stream).lines() {
            let line = line.unwrap();
            let reply = if line == "status" {
                "ok phase=holding fault=none".to_string()
            } else {
                format!("err 2 refused: {line}")
            };
            writeln!(writer, "{reply}").unwrap();
            seen.push(line);
        }
        seen
    })
}

#[test]
fn a_console_script_reports_each_reply_and_fails_on_an_err() {
    let socket = scratch("fw-ok.sock");
    let firmware = stand_in(&socket);
    let script = scratch("ok.txt");
    std::fs::write(&script, "# a comment\nstatus\n\nstatus\n").unwrap();
    let out = host_sim(&[
        "--json",
        "console",
        "--unix",
        socket.to_str().unwrap(),
        "--script",
        script.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = stdout_json(&out);
    assert_eq!(report["exchanges"].as_array().unwrap().len(), 2);
    assert_eq!(report["notices"][0], "# ready target_hz=44");
    assert_eq!(firmware.join().unwrap(), ["status", "status"]);

    let socket = scratch("fw-err.sock");
    let firmware = stand_in(&socket);
    let script = scratch("err.txt");
    std::fs::write(&script, "status\ntarget 47\nstatus\n").unwrap();
    let out = host_sim(&[
        "console",
        "--unix",
        socket.to_str().unwrap(),
        "--script",
        script.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("> target 47\nerr 2 refused: target 47"),
        "{text}"
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("`target 47` got `err 2"));
    assert_eq!(firmware.join().unwrap().len(), 3);
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
