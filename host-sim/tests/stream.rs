//! The telemetry stream end to end: `host-sim serve` streams the reference scene's board,
//! `console --record` writes it to CSV, and each row is held against the same scene's own
//! history (`run --history`, the same board and plant without a stream): the DAC code, the
//! enable line and the phase at the same tick, the voltage commanded within one DAC step of
//! the code's. Then with bytes dropped on the way: the gaps counted, the receiver back in
//! step at the next frame.

mod common;

use std::collections::HashMap;
use std::io::{Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::Path;

use common::{host_sim, scratch, Served};
use serde_json::Value;

/// The reference scene, long enough that a recording started late still falls inside it.
fn scene(dir: &Path) -> String {
    let text = host_sim_reference().replace("duration_seconds = 10.0", "duration_seconds = 40.0");
    assert!(text.contains("duration_seconds = 40.0"));
    let path = dir.join("reference-40s.toml");
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_string()
}

fn host_sim_reference() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/reference.toml"
    ))
    .unwrap()
}

/// A CSV's rows as maps from column to cell (`#` lines skipped), and its `#` lines.
fn read_csv(path: &Path) -> (Vec<String>, Vec<HashMap<String, String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let comments = text
        .lines()
        .filter(|l| l.starts_with('#'))
        .map(String::from)
        .collect();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows = lines
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                .map(|(h, c)| (h.to_string(), c.to_string()))
                .collect()
        })
        .collect();
    (comments, rows)
}

/// `host-sim` with `args`, which must succeed: its stdout.
fn succeeds(args: &[&str]) -> Vec<u8> {
    let out = host_sim().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// `run` of the scene `args` name (none: the reference), with `--history` into `dir`, and
/// whatever else `args` say: the reference scene's history, by tick.
fn history(args: &[&str], dir: &Path) -> HashMap<String, HashMap<String, String>> {
    let out = ["--out", dir.to_str().unwrap(), "--history"];
    succeeds(&[&["--json", "run"][..], args, &out].concat());
    let (_, rows) = read_csv(&dir.join("reference").join("history.csv"));
    rows.into_iter().map(|r| (r["tick"].clone(), r)).collect()
}

/// `console --record` for `wall_seconds` from `stream` (a Unix socket): its report.
fn record(board: &Served, stream: &str, csv: &Path, wall_seconds: &str) -> Value {
    let connection: Vec<&str> = board.connection.iter().map(String::as_str).collect();
    let record = ["--record", csv.to_str().unwrap(), "--stream-unix", stream];
    let duration = ["--duration-seconds", wall_seconds];
    let args = [&["--json", "console"][..], &connection, &record, &duration].concat();
    let report: Value = serde_json::from_slice(&succeeds(&args)).unwrap();
    report["recording"].clone()
}

/// Every row against the history's row of its tick.
fn check_rows(
    rows: &[HashMap<String, String>],
    history: &HashMap<String, HashMap<String, String>>,
) {
    // One DAC step: the reference amplifier's 2.5 V reference × 4000 V/V over 65,535 codes.
    let step_volts = 2.5 * 4000.0 / 65_535.0;
    for row in rows {
        let h = history
            .get(&row["tick"])
            .unwrap_or_else(|| panic!("tick {} is not in the history", row["tick"]));
        for column in ["dac_code", "enable", "phase"] {
            assert_eq!(row[column], h[column], "{column} at tick {}", row["tick"]);
        }
        let code: f64 = row["dac_code"].parse().unwrap();
        let volts: f64 = row["volts"].parse().unwrap();
        assert!(
            (volts - code * step_volts).abs() <= step_volts,
            "tick {}: {volts} V commanded, code {code}",
            row["tick"]
        );
    }
}

#[test]
fn a_recording_matches_the_scenes_own_history_record_for_record() {
    let dir = scratch("stream-whole");
    let scene = scene(&dir);
    let board = Served::streaming(Some(&scene), "5", "stream-whole");
    let csv = dir.join("recorded.csv");
    // 0.4 s of wall time at 5× real time: 2 s of the scene at 100 records a second.
    let recording = record(&board, board.stream.as_ref().unwrap(), &csv, "0.4");
    assert_eq!(recording["lost"], 0, "{recording}");
    assert_eq!(recording["bad_frames"], 0, "{recording}");
    let (comments, rows) = read_csv(&csv);
    assert_eq!(recording["records"].as_u64().unwrap() as usize, rows.len());
    assert!(rows.len() >= 190, "{} records in 2 s at 100 Hz", rows.len());
    for (a, b) in rows.iter().zip(&rows[1..]) {
        let n = |r: &HashMap<String, String>, c: &str| r[c].parse::<u64>().unwrap();
        assert_eq!(n(b, "sequence"), n(a, "sequence") + 1);
        assert_eq!(n(b, "tick"), n(a, "tick") + 10, "every 10th tick of 1 kHz");
    }
    let header = comments.join("\n");
    for named in [
        "image_crc=0x",
        "firmware=de-resonator",
        "device.shear_modulus=",
        "device.jlim=",
        "target_hz=44",
        "stream hz=100",
    ] {
        assert!(header.contains(named), "the header lacks {named}: {header}");
    }
    check_rows(&rows, &history(&[&scene], &dir.join("run")));
}

/// A proxy between the board's stream and the console that drops one byte in every `every`.
fn lossy_proxy(upstream: String, at: &Path, every: usize) {
    let listener = UnixListener::bind(at).unwrap();
    std::thread::spawn(move || {
        let (mut down, _) = listener.accept().unwrap();
        let mut up = UnixStream::connect(upstream).unwrap();
        let (mut buf, mut count) = ([0u8; 4096], 0usize);
        while let Ok(n) = up.read(&mut buf) {
            if n == 0 {
                return;
            }
            let kept: Vec<u8> = buf[..n]
                .iter()
                .filter(|_| {
                    count += 1;
                    count % every != every / 2
                })
                .copied()
                .collect();
            if down.write_all(&kept).is_err() {
                return;
            }
        }
    });
}

#[test]
fn bytes_dropped_from_the_stream_are_counted_as_gaps_and_the_receiver_resyncs() {
    let dir = scratch("stream-lossy");
    let scene = scene(&dir);
    let board = Served::streaming(Some(&scene), "5", "stream-lossy");
    let proxy = dir.join("lossy.sock");
    // One byte in 1,000: about one frame in fifteen damaged.
    lossy_proxy(board.stream.clone().unwrap(), &proxy, 1000);
    let csv = dir.join("lossy.csv");
    let recording = record(&board, proxy.to_str().unwrap(), &csv, "0.4");
    let (_, rows) = read_csv(&csv);
    let lost = recording["lost"].as_u64().unwrap();
    let bad = recording["bad_frames"].as_u64().unwrap();
    // 66-byte frames, a byte in 1,000 dropped: 13,000 bytes hold 13 drops.
    assert!(lost >= 8 && bad >= 8, "{recording}");
    // Every record missing from the sequence is counted, none more: read and lost add up to
    // the sequence's span.
    let sequence = |r: &HashMap<String, String>| r["sequence"].parse::<u64>().unwrap();
    let span = sequence(rows.last().unwrap()) - sequence(&rows[0]) + 1;
    assert_eq!(rows.len() as u64 + lost, span, "{recording}");
    // Back in step after each drop: the rows after a gap are the board's, at their ticks.
    assert!(rows.len() as u64 > span - 2 * bad, "{recording}");
    check_rows(&rows, &history(&[&scene], &dir.join("run")));
}

/// `run --record`: the scene's board streams the same records through a run (the core's
/// board here; the firmware's under QEMU in scripts/firmware_loop.py, compared record for
/// record): one every 10 ticks from the first, none lost, each the history's at its tick.
#[test]
fn a_run_records_the_stream_beside_its_history() {
    let dir = scratch("stream-run");
    let history = history(&["--record"], &dir);
    let (comments, rows) = read_csv(&dir.join("reference").join("telemetry.csv"));
    assert!(
        comments.iter().any(|c| c
            == "# records=1000 lost=0 bad_frames=0 (lost records are missing rows, not filled in)"),
        "{comments:?}"
    );
    let ticks: Vec<u64> = rows.iter().map(|r| r["tick"].parse().unwrap()).collect();
    assert_eq!(ticks, (0..1000).map(|k| 10 * k).collect::<Vec<_>>());
    check_rows(&rows, &history);
}
