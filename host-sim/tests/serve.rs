//! `host-sim serve`, the virtual board, through `host-sim console --script` as an engineer
//! would use them: every request of the command port and its reply, the start-up line, a
//! fault's latch and `clear`, settings saved across `reset`. The board is the core's (the
//! firmware's logic); the plant is the scene's.

mod common;

use common::refused_with;
use de_resonator::wire::protocol::ErrorCode;

use common::{number, Served};
use serde_json::Value;

/// The bias `host-sim tune` (the f64 solve, a second method) gives for `hz`, V.
fn tuned_bias(hz: f64) -> f64 {
    let out = common::host_sim()
        .args(["--json", "tune", "--target-hz", &hz.to_string()])
        .output()
        .unwrap();
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    report["bias_volts"].as_f64().unwrap()
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a / b - 1.0).abs() <= rel
}

fn settled(status: &str) -> bool {
    status.contains("phase=holding") || status.contains("phase=driving")
}

#[test]
fn the_virtual_board_answers_every_request_as_the_firmware() {
    let board = Served::start(None, "20", "reference");
    // The start-up line to each client as it connects; the image's 44 Hz at f64's bias.
    let (report, ok) = board.console(&["status", "get target_hz", "help"]);
    assert!(ok, "{report}");
    let ready = report["notices"][0].as_str().unwrap();
    assert!(ready.starts_with("# ready target_hz=44 "), "{ready}");
    // A scene's board drives at power-up (the scene runs from t = 0).
    assert!(
        ready.ends_with(" settings=image power_up=drive output=on"),
        "{ready}"
    );
    assert!(
        close(number(ready, "bias_volts"), tuned_bias(44.0), 1e-4),
        "{ready}"
    );
    let replies: Vec<&str> = report["exchanges"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["reply"].as_str().unwrap())
        .collect();
    assert!(replies[0].starts_with("ok phase="), "{}", replies[0]);
    assert_eq!(replies[1], "ok target_hz=44");
    assert!(replies[2].starts_with("ok commands: help [command | setting] | status"));

    board.wait_for("driving", |s| s.contains("phase=driving"));
    // In range: the bias of the f64 solve for 45 Hz, ramped from 44 Hz's.
    let moved = board.replies(&["target 45"]).remove(0);
    assert!(moved.starts_with("ok target_hz=45 "), "{moved}");
    assert!(
        close(number(&moved, "bias_volts"), tuned_bias(45.0), 1e-4),
        "{moved}"
    );
    assert!(
        close(number(&moved, "from_volts"), tuned_bias(44.0), 1e-4),
        "{moved}"
    );
    board.wait_for("at the new bias", settled);
    let replies = board.replies(&[
        "target 300",
        "ac 20 41",
        "get ac_volts",
        "set tick_hz 2000",
        "frobnicate",
        "get target_hz",
    ]);
    // Out of range: refused by the checks (code 2), the plan in force kept.
    assert!(
        replies[0].starts_with(&refused_with(ErrorCode::Refused)),
        "{}",
        replies[0]
    );
    assert!(
        replies[1].starts_with("ok target_hz=45 ") && replies[1].ends_with("ac_volts=20 ac_hz=41")
    );
    assert_eq!(replies[2], "ok ac_volts=20");
    assert!(
        replies[3].starts_with(&format!("{}tick_hz", refused_with(ErrorCode::Refused))),
        "{}",
        replies[3]
    );
    assert!(
        replies[4].starts_with(&refused_with(ErrorCode::Syntax)),
        "{}",
        replies[4]
    );
    assert_eq!(replies[5], "ok target_hz=45");
    board.wait_for("settled after the AC", settled);
    let replies = board.replies(&["set margin 0.1", "save", "reset"]);
    assert!(replies[0].starts_with("ok target_hz=45 "), "{}", replies[0]);
    // A save and a reset under the bias are refused, as on the chip (whose flash erase
    // stalls it): at 0 V only.
    assert!(
        replies[1].starts_with(&format!(
            "{}`save` erases flash",
            refused_with(ErrorCode::State)
        )),
        "{}",
        replies[1]
    );
    assert!(
        replies[2].starts_with(&format!(
            "{}reset at 0 V only",
            refused_with(ErrorCode::State)
        )),
        "{}",
        replies[2]
    );
    assert!(board.replies(&["stop"])[0].starts_with("ok stop: ramp from "));
    board.wait_for("at 0 V", |s| {
        s.contains("phase=holding") && number(s, "volts") == 0.0
    });
    assert_eq!(
        board.replies(&["save"])[0],
        "ok save: the settings in force boot from now on"
    );
    let (report, ok) = board.console(&["reset", "get margin", "get target_hz", "status"]);
    assert!(ok, "{report}");
    let exchanges = report["exchanges"].as_array().unwrap();
    assert_eq!(exchanges[0]["reply"], "ok reset: output off, restarting");
    // The restart says so, and boots the saved settings.
    let notices: Vec<&str> = report["notices"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    assert_eq!(notices[1], "# reset: asked", "{notices:?}");
    assert!(
        notices[2].starts_with("# ready target_hz=45 ") && notices[2].contains(" settings=saved ")
    );
    assert_eq!(exchanges[1]["reply"], "ok margin=0.1");
    assert_eq!(exchanges[2]["reply"], "ok target_hz=45");
    let status = exchanges[3]["reply"].as_str().unwrap();
    assert!(status.ends_with("fault=none"), "{status}");
}

/// The stuck sensor's scene (stuck at 3 s): the fault latches, requests answer `err 4`,
/// `clear` waits for 0 V and then boots again (the output left off until `start`), and the
/// sensor, still stuck, faults the new controller as it did the first.
#[test]
fn a_fault_latches_on_the_virtual_board_until_clear() {
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/fault-sensor-stuck.toml"
    );
    let board = Served::start(Some(scene), "20", "stuck");
    let faulted = board.wait_for("faulted", |s| !s.ends_with("fault=none"));
    assert!(faulted.contains("phase=faulted"), "{faulted}");
    assert!(faulted.contains("fault=stretch sensor stuck"), "{faulted}");
    let replies = board.replies(&["target 45", "trim"]);
    assert!(
        replies[0].starts_with(&format!("{}faulted", refused_with(ErrorCode::Faulted))),
        "{}",
        replies[0]
    );
    assert!(
        replies[1].starts_with(&refused_with(ErrorCode::Faulted)),
        "{}",
        replies[1]
    );
    board.wait_for("at 0 V", |s| number(s, "volts") == 0.0);
    let cleared = board.replies(&["clear", "status"]);
    assert!(
        cleared[0].starts_with("ok clear: boot checks pass; the output off at 0 V until `start`"),
        "{}",
        cleared[0]
    );
    let bias = common::last_volts(&cleared[0]);
    assert!(close(bias, tuned_bias(44.0), 1e-4), "{bias}");
    // A fresh controller (its tick count from 0) on a sensor still stuck: it faults again,
    // on the same watch (100 equal samples).
    let before = number(&faulted, "ticks");
    assert!(
        number(&cleared[1], "ticks") < before,
        "{} after {faulted}",
        cleared[1]
    );
    let again = board.wait_for("faulted again", |s| !s.ends_with("fault=none"));
    assert!(again.contains("fault=stretch sensor stuck"), "{again}");
    assert!(again.ends_with("for 100 samples"), "{again}");
}

/// The fault log: the stuck sensor's fault logged as it latches, with its data; after its
/// descent and a `reset` the log still holds it (`faults`, `faults <n>`), and `faults clear`
/// empties it.
#[test]
fn a_fault_is_in_the_log_after_a_reset_with_its_data() {
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/fault-sensor-stuck.toml"
    );
    let board = Served::start(Some(scene), "20", "fault-log");
    assert_eq!(board.replies(&["faults"])[0], "ok faults=0");
    let faulted = board.wait_for("faulted", |s| !s.ends_with("fault=none"));
    board.wait_for("at 0 V", |s| number(s, "volts") == 0.0);
    // The sensor sticks at 3 s and the watch counts 100 equal samples at 1 kHz.
    let at = number(&faulted, "ticks");
    let replies = board.replies(&["reset", "faults", "faults 1", "faults 2"]);
    assert!(replies[0].starts_with("ok reset"), "{}", replies[0]);
    let list = &replies[1];
    assert!(
        list.starts_with("ok faults=1 | 1 sensor_stuck t="),
        "{list}"
    );
    let one = &replies[2];
    let tick = number(one, "tick");
    // The stuck code is the last scan's before 3 s: that tick's mean may equal it by chance,
    // and count as the first of the 100.
    assert!(
        (3098.0..=at).contains(&tick),
        "logged at tick {tick}: 100 samples after 3 s, by the time status saw it ({at}): {one}"
    );
    assert!(close(number(one, "seconds"), tick / 1000.0, 1e-6), "{one}");
    assert!(
        number(one, "volts") > 7000.0,
        "at the drive's voltage: {one}"
    );
    let said = faulted.split(" fault=").nth(1).unwrap();
    assert!(
        one.ends_with(&format!("words={said}")) && said.len() > 32,
        "the fault's sentence whole, with its figures, as status said it before the reset: \
         {one}"
    );
    let stuck_at = said.split_whitespace().nth(4).unwrap();
    assert!(
        one.contains(&format!(" stretch={stuck_at} ")),
        "the stretch sample that stuck: {one}"
    );
    assert!(
        replies[3].starts_with(&format!("{}no fault 2", refused_with(ErrorCode::Refused))),
        "{}",
        replies[3]
    );
    let cleared = board.replies(&["faults clear", "faults"]);
    assert_eq!(cleared, ["ok faults cleared", "ok faults=0"]);
}

/// `console` against the board on TCP: a script's replies in order, status 1 and the first
/// `err` named on stderr when one fails.
#[test]
fn a_console_script_reports_each_reply_and_fails_on_an_err() {
    let board = Served::start(None, "max", "tcp");
    let out = board.script("ok", "# a comment\nhelp\n\nget target_hz\n");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("> get target_hz\nok target_hz=44\n"),
        "{text}"
    );
    assert!(text.ends_with("2 requests, 0 answered `err`\n"), "{text}");
    let out = board.script("err", "help\ntarget 300\nhelp\n");
    assert_eq!(out.status.code(), Some(1));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("> target 300\nerr "), "{text}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("`target 300` got `err "));
}

/// Lines sent in one write are each answered, in order, those after a `reset` by the board
/// booted anew (its start-up line between them), as a terminal pasting lines would see.
#[test]
fn lines_in_one_write_are_answered_in_order_across_a_reset() {
    use std::io::{BufRead, BufReader, Write};
    let board = Served::start(None, "max", "pasted");
    assert!(board.replies(&["stop"])[0].starts_with("ok stop"));
    board.wait_for("at rest at 0 V", |s| {
        s.contains("phase=holding") && number(s, "volts") == 0.0
    });
    let mut stream = std::os::unix::net::UnixStream::connect(&board.connection[1]).unwrap();
    stream
        .set_read_timeout(Some(std::time::Duration::from_secs(10)))
        .unwrap();
    stream.write_all(b"help\nreset\nget target_hz\n").unwrap();
    let mut lines = BufReader::new(stream).lines().map(Result::unwrap);
    let mut next = || lines.next().unwrap();
    // Asked `stop` since its boot: the start-up line is not the state now; the status is.
    let now = next();
    assert!(
        now.starts_with("# now phase=") && now.contains(" output="),
        "{now}"
    );
    assert!(next().starts_with("ok commands:"));
    assert_eq!(next(), "ok reset: output off, restarting");
    assert_eq!(next(), "# reset: asked");
    assert!(next().starts_with("# ready target_hz=44 "));
    assert_eq!(next(), "ok target_hz=44");
}

/// Issue 29, 2: at a prompt, what the board says on its own (its start-up line) shows as it
/// arrives, before any request; each reply follows its request.
#[test]
fn the_console_shows_what_the_board_says_as_it_arrives() {
    use std::io::{BufRead, BufReader, Write};
    use std::process::Stdio;
    let board = Served::start(None, "5", "console-live");
    let mut child = common::host_sim()
        .arg("console")
        .args(&board.connection)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    assert!(line.starts_with("# ready target_hz=44 "), "{line}");
    stdin.write_all(b"get target_hz\n").unwrap();
    line.clear();
    out.read_line(&mut line).unwrap();
    assert_eq!(line, "ok target_hz=44\n");
    drop(stdin);
    let done = child.wait_with_output().unwrap();
    assert!(done.status.success());
    let said = String::from_utf8_lossy(&done.stderr);
    assert!(said.starts_with("connected to unix:"), "{said}");
}

/// Issue 29, 3 and 13: a script waits for a state instead of meeting `busy`; replies come
/// parsed into fields; a wait that cannot hold fails the script (status 1, why said).
#[test]
fn a_script_waits_for_a_state_and_fails_when_it_never_comes() {
    let board = Served::start(None, "5", "console-wait");
    let (report, ok) = board.console(&[
        "wait phase=holding|driving 30",
        "target 45",
        "wait phase=driving 30",
        "ac 100 40",
        "wait phase=driving 30",
        "status",
    ]);
    assert!(ok, "{report}");
    let exchanges = report["exchanges"].as_array().unwrap();
    assert_eq!(exchanges.len(), 3, "waits are the console's, not requests");
    let ac = &exchanges[1]["fields"];
    assert_eq!(ac["ac_volts"], 100.0, "{ac}");
    let status = &exchanges[2]["fields"];
    assert_eq!(status["phase"], "driving", "{status}");
    assert_eq!(status["target_hz"], 45.0, "{status}");
    assert_eq!(status["fault"], "none", "{status}");
    let err = board.console(&["target 300"]).0;
    assert_eq!(err["exchanges"][0]["fields"]["code"], 2.0, "{err}");
    // A number waited for as the board writes it, or as a number equal to it.
    let (report, ok) = board.console(&["stop", "wait volts=0 30", "wait volts=0.0 1"]);
    assert!(ok, "{report}");
    // A state that never comes.
    let (report, ok) = board.console(&["wait phase=nowhere 0.3", "status"]);
    assert!(!ok);
    assert!(
        report["stopped"]
            .as_str()
            .unwrap()
            .starts_with("wait phase=nowhere: not within 0.3 s"),
        "{report}"
    );
    assert_eq!(report["exchanges"].as_array().unwrap().len(), 0);
    // A malformed wait is refused before anything is sent.
    let out = board.script("bad-wait", "status\nwait phase\n");
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
}

/// Issue 29, 2: a board that goes away mid-script is said as such (not "Broken pipe"), and
/// the script fails.
#[test]
fn the_console_says_when_the_board_went_away() {
    let mut board = Served::start(None, "5", "console-gone");
    let script = common::scratch("serve").join("gone.txt");
    std::fs::write(&script, "status\nsleep 1.5\nstatus\nstatus\n").unwrap();
    let child = common::host_sim()
        .args(["--json", "console"])
        .args(&board.connection)
        .args(["--script", script.to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(700));
    board.kill();
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["closed_by_board"], true, "{report}");
    assert_eq!(report["exchanges"].as_array().unwrap().len(), 1);
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(said.contains("the board closed the connection"), "{said}");
}

/// Issue 46, 2: one connection controls the board; another connected meanwhile reads (its
/// requests that change the board get `err 8`, but for `stop`), is told so and by whom on
/// connecting, and takes over when the first leaves. A new connection to a faulted board hears the fault, not the
/// start-up line.
#[test]
fn one_connection_controls_the_board_and_a_new_one_hears_the_state_now() {
    use std::io::{BufRead, BufReader, Write};
    use std::os::unix::net::UnixStream;
    let board = Served::start(None, "max", "two-clients");
    let connect = || {
        let stream = UnixStream::connect(&board.connection[1]).unwrap();
        stream
            .set_read_timeout(Some(std::time::Duration::from_secs(10)))
            .unwrap();
        let reader = BufReader::new(stream.try_clone().unwrap());
        (stream, reader.lines().map(Result::unwrap))
    };
    let (mut a, mut a_lines) = connect();
    assert!(a_lines.next().unwrap().starts_with("# ready "));
    let (mut b, mut b_lines) = connect();
    let first = b_lines.next().unwrap();
    assert!(first.starts_with("# "), "{first}");
    let told = b_lines.next().unwrap();
    assert!(
        told.starts_with("# another connection controls the board"),
        "{told}"
    );
    b.write_all(b"start\nstatus\nfaults clear\n").unwrap();
    let refused = b_lines.next().unwrap();
    assert!(
        refused.starts_with(&format!(
            "{}another connection controls the board (unix socket client 1)",
            refused_with(ErrorCode::NotInControl)
        )),
        "{refused}"
    );
    let status = b_lines.next().unwrap();
    assert!(
        status.starts_with("ok phase=driving")
            || status.starts_with("ok phase=ramping")
            || status.starts_with("ok phase=holding"),
        "{status}"
    );
    assert!(status.contains(" output=on "), "{status}");
    assert!(
        b_lines
            .next()
            .unwrap()
            .starts_with(&refused_with(ErrorCode::NotInControl)),
        "faults clear changes the log"
    );
    // Issue 58: a stop is an emergency stop, taken from any connection; the one that
    // controls is told who stopped the board.
    b.write_all(b"stop\n").unwrap();
    let stopped = b_lines.next().unwrap();
    assert!(stopped.starts_with("ok stop: ramp from "), "{stopped}");
    let told = a_lines.next().unwrap();
    assert!(
        told.starts_with("# stop from another connection (unix socket client 2): ramp from "),
        "{told}"
    );
    a.write_all(b"status\n").unwrap();
    let status = a_lines.next().unwrap();
    assert!(
        (status.contains("phase=ramping ") || status.contains("phase=holding "))
            && number(&status, "bias_volts") == 0.0,
        "B's stop did not bring A's drive down: {status}"
    );
    drop(a_lines);
    drop(a);
    assert_eq!(
        b_lines.next().unwrap(),
        "# this connection now controls the board"
    );
    b.write_all(b"start\n").unwrap();
    let started = b_lines.next().unwrap();
    assert!(
        !started.starts_with(&refused_with(ErrorCode::NotInControl)),
        "B controls now: {started}"
    );
}

/// Issue 46, 2: a new connection starts from a clean line. A connection that leaves with
/// `start` half sent (no line end) switches nothing on; the next console's requests are
/// answered as sent, never glued to it (on a chip's one UART, the console refuses the half
/// line first: `scripts/firmware_e2e.py`, "one port, one line").
#[test]
fn a_half_line_left_behind_runs_nothing_and_glues_to_nothing() {
    use std::io::Write;
    use std::os::unix::net::UnixStream;
    let board = Served::start(None, "5", "half-line");
    assert!(board.replies(&["stop"])[0].starts_with("ok stop"));
    board.wait_for("at rest", |s| s.contains(" output=off "));
    let mut a = UnixStream::connect(&board.connection[1]).unwrap();
    a.write_all(b"start").unwrap();
    drop(a);
    let replies = board.replies(&["status", "get target_hz"]);
    assert!(
        replies[0].starts_with("ok phase=") && replies[0].contains(" output=off "),
        "the half `start` ran: {replies:?}"
    );
    assert!(replies[1].starts_with("ok target_hz="), "{replies:?}");
}

/// Issue 46, 2: a new connection to a faulted board hears the fault now (not `# ready`).
/// `serve --power-up wait` boots the scene's image as a board flashed with `image`'s default
/// boots: the start-up line says the output is off, nothing is driven while it waits (1 s of
/// simulated time), and `start` ramps to the bias of the f64 solve, then drives the scene's
/// AC.
#[test]
fn a_board_that_waits_at_power_up_drives_only_after_start() {
    let board = Served::with(None, "20", "waits", &["--power-up", "wait"]);
    let (report, ok) = board.console(&["status"]);
    assert!(ok, "{report}");
    let ready = report["notices"][0].as_str().unwrap();
    assert!(ready.contains(" power_up=wait output=off"), "{ready}");
    let resting = board.wait_for("a second at rest", |s| {
        s.contains("phase=holding") && number(s, "ticks") >= 1000.0
    });
    assert!(
        resting.contains(" volts=0 ") && resting.contains(" output=off"),
        "{resting}"
    );
    let (report, ok) = board.console(&["start"]);
    assert!(ok, "{report}");
    let driving = board.wait_for("the drive", |s| s.contains("phase=driving"));
    assert!(
        close(number(&driving, "bias_volts"), tuned_bias(44.0), 1e-4)
            && driving.contains(" output=on"),
        "{driving}"
    );
}

#[test]
fn a_new_connection_to_a_faulted_board_hears_the_fault() {
    let board = Served::start(
        Some(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenes/fault-sensor-stuck.toml"
        )),
        "max",
        "faulted-hears",
    );
    board.wait_for("the fault", |s| s.contains("phase=faulted"));
    let (report, ok) = board.console(&["status"]);
    assert!(ok, "{report}");
    let first = report["notices"][0].as_str().unwrap();
    assert!(
        first.starts_with("# now phase=faulted") && first.contains(" output="),
        "{first}"
    );
    assert!(!first.contains("fault=none"), "{first}");
}

/// Issue 46, 2: Ctrl-C in a `wait` cancels the wait, not the session; leaving says what the
/// board is still doing (here: driving, the output on).
#[test]
fn ctrl_c_cancels_a_wait_and_leaving_says_the_output_is_on() {
    use nix::sys::signal::{kill, Signal};
    use nix::unistd::Pid;
    use std::process::Stdio;
    let board = Served::start(None, "1", "console-interrupt");
    let script = common::scratch("console-interrupt").join("script.txt");
    std::fs::write(&script, "wait phase=faulted 60\nstatus\n").unwrap();
    let child = common::host_sim()
        .arg("console")
        .args(&board.connection)
        .arg("--script")
        .arg(&script)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_secs(3));
    kill(Pid::from_raw(child.id() as i32), Signal::SIGINT).unwrap();
    let started = std::time::Instant::now();
    let done = child.wait_with_output().unwrap();
    assert!(
        started.elapsed().as_secs() < 20,
        "the wait was not cancelled"
    );
    let out = String::from_utf8_lossy(&done.stdout);
    let err = String::from_utf8_lossy(&done.stderr);
    assert!(
        err.contains("wait phase=faulted: cancelled (Ctrl-C)"),
        "{err}"
    );
    assert!(
        out.contains("> status\nok phase="),
        "the session went on: {out}"
    );
    assert!(err.contains("leaving with the output ON"), "{err}");
}

/// Issue 58: a board that waits at power-up is said at rest (not "at bias, 0 V"), and the
/// session's end says what the board was doing (its last status).
#[test]
fn a_waiting_board_is_said_at_rest_and_its_end_says_its_state() {
    let socket = common::scratch("serve").join("at-rest.sock");
    let out = common::host_sim()
        .args(["--json", "serve", "--unix"])
        .arg(&socket)
        .args(["--power-up", "wait", "--seconds", "1", "--speed", "max"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    let events = report["events"].as_array().unwrap();
    assert_eq!(events.len(), 1, "{report}");
    assert!(
        events[0].as_str().unwrap().ends_with("s: at rest, 0 V"),
        "{report}"
    );
    let leaving = report["leaving"].as_str().unwrap();
    assert!(
        leaving.starts_with("its time over at 1")
            && leaving.contains("phase=holding")
            && leaving.contains(" output=off"),
        "{leaving}"
    );
}
