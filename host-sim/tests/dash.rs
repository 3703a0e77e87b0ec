//! `host-sim dash`, the live page's server, against the virtual board as a page uses it
//! (plain HTTP from the test): the page and its assets served, requests passed verbatim and
//! one line at a time, the events a page opens with, the report as it leaves. The page
//! itself in Chromium: scripts/dash_test.py.

mod common;

use common::refused_with;
use de_resonator::wire::protocol::ErrorCode;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Stdio};
use std::time::Duration;

use common::{number, Served};
use serde_json::Value;

/// `dash --json` on a board: the process, the page's `host:port` and its token (said on
/// stderr; stdout carries the report).
fn dash(board: &Served, extra: &[&str]) -> (Child, String, String) {
    let mut command = common::host_sim();
    command.arg("dash").args(&board.connection);
    if let Some(stream) = &board.stream {
        command.args(["--stream-unix", stream]);
    }
    let mut child = command
        .args(["--json", "--listen", "127.0.0.1:0"])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("host-sim dash starts");
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    while !line.starts_with("dash: open ") {
        line.clear();
        if stderr.read_line(&mut line).unwrap() == 0 {
            panic!("dash ended before it served");
        }
    }
    std::thread::spawn(move || for _ in stderr.lines() {});
    let (address, token) = line
        .trim()
        .strip_prefix("dash: open http://")
        .and_then(|rest| rest.split_once("/?token="))
        .unwrap_or_else(|| panic!("dash's first line: {line:?}"));
    (child, address.to_string(), token.to_string())
}

/// One HTTP/1.0 request as the page sends it (a body in one piece, not chunked; a POST with
/// the page's header; the token as the page's cookie): the status code and the body.
fn http(address: &str, token: &str, method: &str, path: &str, body: &str) -> (u16, String) {
    let act = if method == "POST" {
        "X-Dash-Request: 1\r\n"
    } else {
        ""
    };
    let port = address.rsplit(':').next().unwrap();
    raw(
        address,
        &format!("Host: {address}\r\nCookie: dash_token_{port}={token}\r\n{act}"),
        method,
        path,
        body,
    )
}

/// A request with the headers given: the status code and the body.
fn raw(address: &str, headers: &str, method: &str, path: &str, body: &str) -> (u16, String) {
    let mut s = TcpStream::connect(address).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    write!(
        s,
        "{method} {path} HTTP/1.0\r\n{headers}Content-Length: {}\r\n\r\n{body}",
        body.len()
    )
    .unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).unwrap();
    let code = text[9..12].parse().unwrap();
    let body = text
        .split_once("\r\n\r\n")
        .map_or("", |(_, b)| b)
        .to_string();
    (code, body)
}

/// The first event a page gets: `hello`'s data.
fn hello(address: &str, token: &str) -> Value {
    let mut s = TcpStream::connect(address).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    write!(
        s,
        "GET /api/events HTTP/1.1\r\nHost: {address}\r\nAuthorization: Token {token}\r\n\r\n"
    )
    .unwrap();
    let reader = BufReader::new(s);
    let mut event = String::new();
    for line in reader.lines() {
        let line = line.unwrap();
        if let Some(kind) = line.strip_prefix("event: ") {
            event = kind.to_string();
        } else if let Some(data) = line.strip_prefix("data: ") {
            assert_eq!(event, "hello", "the first event");
            return serde_json::from_str(data).unwrap();
        }
    }
    panic!("no hello event");
}

#[test]
fn the_page_talks_to_the_board_only_in_its_protocol() {
    let board = Served::streaming(None, "5", "dash");
    let (child, address, token) = dash(
        &board,
        &["--seconds", "20", "--allow-host", "proxy.example"],
    );
    // The page (its token from the URL kept as its cookie) and its vendored plotting library.
    let (code, page) = raw(
        &address,
        &format!("Host: {address}\r\n"),
        "GET",
        &format!("/?token={token}"),
        "",
    );
    assert_eq!(code, 200);
    assert!(page.contains("id=\"stop\""), "a Stop on the page");
    let (code, uplot) = http(&address, &token, "GET", "/uPlot.iife.min.js", "");
    assert_eq!(code, 200);
    assert!(uplot.contains("uPlot"));

    // What a page opens with: the board's device, its curve and settings with their rules.
    let first = hello(&address, &token);
    assert!(first["info"].as_str().unwrap().starts_with("ok firmware="));
    let range = first["curve"]["tunable_range_hz"].as_array().unwrap();
    let (low, high) = (range[0].as_f64().unwrap(), range[1].as_f64().unwrap());
    // The image's target (44 Hz) is one the board tunes to: inside the curve's range.
    assert!(low < 44.0 && 44.0 < high, "{low}..{high}");
    let settings = first["settings"].as_array().unwrap();
    let margin = settings.iter().find(|s| s["key"] == "margin").unwrap();
    assert!(margin["help"]
        .as_str()
        .unwrap()
        .starts_with("margin (fraction)"));

    // Only the page's own requests: one without the token (or with another), another site's
    // page (its Origin), a name pointed at this machine (DNS rebinding: its Host), or a
    // request without the page's header cannot start the board; the board never hears them.
    let port = address.rsplit(':').next().unwrap();
    let key = format!("Authorization: Token {token}\r\n");
    // Another token of the same length, its last digit changed.
    let wrong = format!(
        "{}{}",
        &token[..token.len() - 1],
        if token.ends_with('0') { '1' } else { '0' }
    );
    for (headers, code_said, why) in [
        (
            format!("Host: {address}\r\nX-Dash-Request: 1\r\n"),
            401,
            "no token",
        ),
        (
            format!(
                "Host: {address}\r\nX-Dash-Request: 1\r\nCookie: dash_token_{port}={wrong}\r\n"
            ),
            401,
            "wrong token",
        ),
        (format!("Host: {address}\r\n{key}"), 403, "X-Dash-Request"),
        (
            format!("Host: {address}\r\n{key}X-Dash-Request: 1\r\nOrigin: http://evil.example\r\n"),
            403,
            "may not use",
        ),
        (
            format!("Host: evil.example:{port}\r\n{key}X-Dash-Request: 1\r\n"),
            403,
            "not served as",
        ),
    ] {
        let (code, body) = raw(&address, &headers, "POST", "/api/command", "start");
        assert_eq!(code, code_said, "{headers}: {body}");
        assert!(body.contains(why), "{body}");
    }
    let (code, _) = raw(&address, "Host: evil.example\r\n", "GET", "/api/state", "");
    assert_eq!(code, 403, "a rebinding page reads nothing either");
    // A name allowed (a TLS reverse proxy's), its page over https, with the token.
    let proxied = format!("Host: proxy.example\r\nOrigin: https://proxy.example\r\n{key}");
    let (code, body) = raw(&address, &proxied, "GET", "/api/state", "");
    assert_eq!(code, 200, "{body}");
    for path in ["/", "/api/state", "/api/events", "/dash.js"] {
        let (code, _) = raw(&address, &format!("Host: {address}\r\n"), "GET", path, "");
        assert_eq!(code, 401, "{path} read without the token");
    }

    // One line at a time, verbatim: a line end inside is refused before the board.
    let (code, body) = http(&address, &token, "POST", "/api/command", "status\nstop");
    assert_eq!(code, 400, "{body}");
    assert!(body.contains("one request a time"), "{body}");
    let (code, body) = http(&address, &token, "POST", "/api/command", "status");
    assert_eq!(code, 200, "{body}");
    let reply: Value = serde_json::from_str(&body).unwrap();
    let line = reply["reply"].as_str().unwrap();
    assert!(
        line.starts_with("ok phase=") && line.contains(" output="),
        "{line}"
    );
    // A target past the range: the board's own refusal, its code and words.
    board.wait_for("at the bias", |s| s.contains("phase=driving"));
    let (_, body) = http(
        &address,
        &token,
        "POST",
        "/api/command",
        &format!("target {}", high + 5.0),
    );
    let reply: Value = serde_json::from_str(&body).unwrap();
    assert_eq!(reply["ok"], false, "{body}");
    assert!(
        reply["reply"]
            .as_str()
            .unwrap()
            .starts_with(&refused_with(ErrorCode::Refused)),
        "{body}"
    );

    // A recording: refused while none runs, then the CSV with `console --record`'s header.
    let (code, _) = http(&address, &token, "POST", "/api/record/stop", "");
    assert_eq!(code, 409);
    let (code, _) = http(&address, &token, "POST", "/api/record/start", "");
    assert_eq!(code, 200);
    std::thread::sleep(Duration::from_millis(500));
    let (code, said) = http(&address, &token, "POST", "/api/record/stop", "");
    assert_eq!(code, 200, "{said}");
    let (code, csv) = http(&address, &token, "GET", "/api/recording.csv", "");
    assert_eq!(code, 200);
    assert!(
        csv.starts_with("# de-resonator telemetry, record layout "),
        "{}",
        &csv[..200.min(csv.len())]
    );
    assert!(csv.contains("\nsequence,tick,time_seconds,volts,"), "{csv}");

    // The board's state as dash leaves: said, not changed (the output still on).
    let (code, _) = http(&address, &token, "POST", "/api/command", "stop");
    assert_eq!(code, 200);
    let _ = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let out = child.wait_with_output().unwrap();
    let report: Value = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&out.stderr)));
    assert!(report["records"].as_u64().unwrap() > 0, "{report}");
    assert_eq!(report["lost"], 0, "{report}");
    // status, target, stop: the line refused before the board is not one.
    assert_eq!(report["requests"], 3, "{report}");
    let leaving = report["leaving"].as_str().unwrap();
    assert!(leaving.contains("output off"), "{leaving}");
    // The board is where the page left it: stopped, and a second client reads so.
    let status = board.replies(&["status"]).remove(0);
    assert!(status.contains("output=off"), "{status}");
    assert_eq!(number(&status, "volts"), 0.0, "{status}");
}

#[test]
fn beyond_loopback_is_warned_of_and_bad_flags_refused() {
    let board = Served::start(None, "5", "dash-warn");
    let out = common::host_sim()
        .arg("dash")
        .args(&board.connection)
        .args(["--listen", "0.0.0.0:0", "--seconds", "0.5"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("warning: serving the page on 0.0.0.0")
            && stderr.contains("whoever holds its URL")
            && stderr.contains("can switch the board's high voltage on"),
        "{stderr}"
    );
    // The URL to open is this machine's loopback one, its token in it (not 0.0.0.0).
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.starts_with("dash: open http://127.0.0.1:") && stdout.contains("/?token="),
        "{stdout}"
    );
    assert!(out.status.success(), "{stderr}");
    let out = common::host_sim()
        .arg("dash")
        .args(&board.connection)
        .args(["--stream-hz", "-3"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--stream-hz"));
}

/// Issue 58: a board lost is said as lost, its status gone (never the last one), and dash
/// stays up and connects again when the board is back (on the same sockets).
#[test]
fn a_lost_board_is_said_lost_and_found_again() {
    let mut board = Served::streaming(None, "5", "dash-lost");
    let (child, address, token) = dash(&board, &["--seconds", "60", "--poll-seconds", "0.1"]);
    let state = || {
        let (code, body) = http(&address, &token, "GET", "/api/state", "");
        assert_eq!(code, 200, "{body}");
        serde_json::from_str::<Value>(&body).unwrap()
    };
    let until = |what: &str, done: &dyn Fn(&Value) -> bool| {
        let end = std::time::Instant::now() + Duration::from_secs(30);
        loop {
            let now = state();
            if done(&now) {
                return now;
            }
            assert!(std::time::Instant::now() < end, "{what}: {now}");
            std::thread::sleep(Duration::from_millis(50));
        }
    };
    until("the board's status", &|s| {
        s["status"]["fields"]["output"] == "on"
    });
    board.kill();
    let lost = until("the board said lost", &|s| s["board"]["state"] == "lost");
    assert!(
        lost["status"].is_null(),
        "a lost board's last status kept: {lost}"
    );
    assert_eq!(lost["losses"], 1, "{lost}");
    // The page's requests are refused with why, not sent into the void.
    let (code, body) = http(&address, &token, "POST", "/api/command", "stop");
    assert_eq!(code, 503, "{body}");
    assert!(body.contains("not connected"), "{body}");
    let _board = Served::streaming(None, "5", "dash-lost");
    let back = until("the board found again", &|s| {
        s["board"]["state"] == "up" && s["status"]["fields"]["output"] == "on"
    });
    assert_eq!(back["losses"], 1, "{back}");
    // Its stream read again: the records counted on from the first connection's.
    let before = lost["link"]["records"].as_u64().unwrap();
    until("the stream read again", &|s| {
        s["link"]["records"].as_u64().unwrap() > before + 10
    });
    let _ = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let out = child.wait_with_output().unwrap();
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["board_lost"], 1, "{report}");
    assert!(report["stopped"].is_null(), "{report}");
}
