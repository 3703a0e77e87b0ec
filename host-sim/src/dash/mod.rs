//! `dash`: a live page for the board, served by host-sim on loopback. The page talks to the
//! board only through this server, and the server only through the board's command port
//! (one request a time, the protocol's own lines, replies verbatim) and its telemetry stream:
//! nothing the page does goes around the board's checks.
//!
//! - [`board`]: the board's side: the command port's session shared by the page's requests
//!   and the status poll, the stream's reader, what the page is told first (the `hello`).
//! - [`http`]: the page's side: the assets built into the binary, the requests, the events
//!   (server-sent events: one thread a page, no async runtime).

mod board;
mod http;

use std::fmt;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use clap::Args;
use serde::Serialize;

use crate::cmd::Report;
use crate::command_port::{PortArgs, StreamArgs};

#[derive(Args, Debug)]
pub struct DashArgs {
    #[command(flatten)]
    pub board: PortArgs,
    #[command(flatten)]
    pub stream: StreamArgs,
    /// Records a second asked of the board (`stream <HZ>`) for the live plots.
    #[arg(
        long,
        value_name = "HZ",
        default_value_t = 250.0,
        allow_negative_numbers = true
    )]
    pub stream_hz: f64,
    /// Where the page is served, HOST:PORT (port 0: any free one, printed). Loopback by
    /// default: the page drives high voltage, so anything else is warned of.
    #[arg(long, value_name = "HOST:PORT", default_value = "127.0.0.1:8080")]
    pub listen: SocketAddr,
    /// How often the page's status is asked of the board (`status`), s.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 0.25,
        allow_negative_numbers = true
    )]
    pub poll_seconds: f64,
    /// Stop after this many seconds (wall time), then report; default: until Ctrl-C.
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub seconds: Option<f64>,
}

/// What a dashboard session did (printed as it ends).
#[derive(Serialize, Debug)]
pub struct DashReport {
    pub url: String,
    pub requests: u64,
    pub records: u64,
    pub lost: u64,
    pub bad_frames: u64,
    /// Records a page could not take in time (its queue full): must stay 0.
    pub dropped_to_pages: u64,
    /// What the board is doing as the dashboard leaves (it keeps its own rules).
    pub leaving: String,
    /// Why the session ended early (the board went away).
    pub stopped: Option<String>,
}

impl fmt::Display for DashReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "dash at {}: {} requests from pages, {} records ({} lost, {} bad frames, {} dropped \
             to pages)\n{}",
            self.url,
            self.requests,
            self.records,
            self.lost,
            self.bad_frames,
            self.dropped_to_pages,
            self.leaving
        )
    }
}

impl Report for DashReport {
    fn failure(&self) -> Option<String> {
        self.stopped.clone()
    }
}

/// Serve the page until Ctrl-C (or `--seconds`), then say what the board is still doing.
/// With `json`, the page's address goes to stderr (stdout carries the report alone).
pub fn dash(args: &DashArgs, json: bool) -> Result<DashReport, String> {
    for (name, value) in [
        ("--stream-hz", args.stream_hz),
        ("--poll-seconds", args.poll_seconds),
    ] {
        if !(value > 0.0 && value.is_finite()) {
            return Err(format!("{name} {value}: must be a positive number"));
        }
    }
    if let Some(s) = args.seconds.filter(|s| !(*s > 0.0 && s.is_finite())) {
        return Err(format!(
            "--seconds {s}: must be a positive number of seconds"
        ));
    }
    if !args.listen.ip().is_loopback() {
        eprintln!(
            "warning: serving the page on {}, beyond this machine: anyone who reaches it can \
             drive the board's high voltage (the default is 127.0.0.1)",
            args.listen
        );
    }
    let server = tiny_http::Server::http(args.listen)
        .map_err(|e| format!("cannot listen on {}: {e}", args.listen))?;
    let url = match server.server_addr().to_ip() {
        Some(address) => format!("http://{address}/"),
        None => format!("http://{}/", args.listen),
    };
    eprintln!("connecting to the board at {}...", args.board.describe());
    let shared = board::Shared::connect(args)?;
    let interrupted = Arc::new(AtomicBool::new(false));
    let _ = signal_hook::flag::register(signal_hook::consts::SIGINT, interrupted.clone());
    let _ = signal_hook::flag::register(signal_hook::consts::SIGTERM, interrupted.clone());
    let workers = board::start(&shared, args)?;
    let address = server.server_addr().to_ip().unwrap_or(args.listen);
    let guard = Arc::new(http::Guard::for_address(address));
    // The address on stdout, alone on its line: a script (or a person) opens it.
    if json {
        eprintln!("dash: open {url}");
    } else {
        use std::io::Write;
        let mut out = std::io::stdout().lock();
        let _ = writeln!(out, "dash: open {url}").and_then(|()| out.flush());
    }
    eprintln!(
        "serving the page at {url} for the board at {}; Ctrl-C leaves (the board keeps its own \
         rules and state)",
        args.board.describe()
    );
    let end = args
        .seconds
        .map(|s| std::time::Instant::now() + Duration::from_secs_f64(s));
    let mut failed = None;
    while !interrupted.load(Ordering::Relaxed)
        && end.is_none_or(|end| std::time::Instant::now() < end)
        && shared.stopped().is_none()
    {
        match server.recv_timeout(Duration::from_millis(100)) {
            Ok(Some(request)) => {
                let (shared, guard) = (shared.clone(), guard.clone());
                std::thread::spawn(move || http::handle(request, &shared, &guard));
            }
            Ok(None) => {}
            Err(e) => {
                failed = Some(format!("the page's server failed: {e}"));
                break;
            }
        }
    }
    // The stream stopped and the board's state said, however the loop ended.
    let leaving = workers.finish(&shared);
    if let Some(why) = failed {
        return Err(format!("{why}; {leaving}"));
    }
    let counts = shared.counts();
    Ok(DashReport {
        url,
        requests: shared.requests(),
        records: counts.records,
        lost: counts.lost,
        bad_frames: counts.bad_frames,
        dropped_to_pages: shared.dropped(),
        leaving,
        stopped: shared.stopped(),
    })
}
