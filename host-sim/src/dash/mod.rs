//! `dash`: a live page for the board, served by host-sim (on loopback by default), every
//! request with the token its URL carries. The page talks to the board only through this
//! server, and the server only through the board's command port
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
    /// A name the page is also served as, HOST or HOST:PORT, as a TLS reverse proxy in front
    /// passes it (`Host`); repeatable. On loopback, only 127.0.0.1, localhost and [::1] are
    /// taken otherwise (a site that points its name at this machine is refused).
    #[arg(long, value_name = "HOST")]
    pub allow_host: Vec<String>,
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
    /// Times the board was lost while dash ran (dash reconnects, with growing waits).
    pub board_lost: u64,
    /// Why the board was out of reach as dash ended, if it was.
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
        )?;
        if self.board_lost > 0 {
            write!(f, "\nthe board was lost {} times", self.board_lost)?;
        }
        Ok(())
    }
}

impl Report for DashReport {
    fn failure(&self) -> Option<String> {
        self.stopped.clone()
    }
}

/// The page's URLs, its token in each: the address served, or (served on every address) the
/// loopback one first, then the machine's own addresses, as others would open it.
fn urls(address: SocketAddr, token: &str) -> Vec<String> {
    let port = address.port();
    let url = |ip: std::net::IpAddr| match ip {
        std::net::IpAddr::V4(ip) => format!("http://{ip}:{port}/?token={token}"),
        std::net::IpAddr::V6(ip) => format!("http://[{ip}]:{port}/?token={token}"),
    };
    if !address.ip().is_unspecified() {
        return vec![url(address.ip())];
    }
    let v6 = address.is_ipv6();
    let loopback = if v6 {
        std::net::Ipv6Addr::LOCALHOST.into()
    } else {
        std::net::Ipv4Addr::LOCALHOST.into()
    };
    let mut urls = vec![url(loopback)];
    if let Ok(interfaces) = nix::ifaddrs::getifaddrs() {
        for interface in interfaces {
            let Some(storage) = interface.address else {
                continue;
            };
            let ip: Option<std::net::IpAddr> =
                match (storage.as_sockaddr_in(), storage.as_sockaddr_in6()) {
                    (Some(v4), _) => Some(std::net::Ipv4Addr::from(v4.ip()).into()),
                    (_, Some(six)) if v6 => Some(six.ip().into()),
                    _ => None,
                };
            // Link-local IPv6 needs its interface named: left out.
            if let Some(ip) = ip.filter(|ip| {
                !ip.is_loopback()
                    && !matches!(ip, std::net::IpAddr::V6(six) if six.segments()[0] & 0xffc0 == 0xfe80)
            }) {
                let u = url(ip);
                if !urls.contains(&u) {
                    urls.push(u);
                }
            }
        }
    }
    urls
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
    let token = http::new_token()?;
    let server = tiny_http::Server::http(args.listen)
        .map_err(|e| format!("cannot listen on {}: {e}", args.listen))?;
    let address = server.server_addr().to_ip().unwrap_or(args.listen);
    let urls = urls(address, &token);
    let url = urls[0].clone();
    if !address.ip().is_loopback() {
        eprintln!(
            "warning: serving the page on {address}, beyond this machine: whoever holds its URL \
             (the token in it) can switch the board's high voltage on. Give it only to those \
             who may operate the board; over plain HTTP anyone on the network's path can read \
             it: put TLS in front (docs/host-sim.md, \"The live page beyond this machine\"). \
             The default, 127.0.0.1, serves this machine alone"
        );
    }
    eprintln!("connecting to the board at {}...", args.board.describe());
    let shared = board::Shared::connect(args)?;
    let interrupted = Arc::new(AtomicBool::new(false));
    // A second Ctrl-C ends the process at once.
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        let _ = signal_hook::flag::register_conditional_shutdown(signal, 1, interrupted.clone());
        let _ = signal_hook::flag::register(signal, interrupted.clone());
    }
    let workers = board::start(&shared, args)?;
    let guard = Arc::new(http::Guard::for_address(address, token, &args.allow_host));
    // The address on stdout, alone on its line: a script (or a person) opens it.
    if json {
        eprintln!("dash: open {url}");
    } else {
        use std::io::Write;
        let mut out = std::io::stdout().lock();
        let _ = writeln!(out, "dash: open {url}").and_then(|()| out.flush());
    }
    for other in &urls[1..] {
        eprintln!("dash: also at {other}");
    }
    eprintln!(
        "serving the page at {url} for the board at {}; the URL carries the page's token (a \
         new one at every start). Ctrl-C leaves (the board keeps its own rules and state)",
        args.board.describe()
    );
    let end = args
        .seconds
        .map(|s| std::time::Instant::now() + Duration::from_secs_f64(s));
    let mut failed = None;
    while !interrupted.load(Ordering::Relaxed)
        && end.is_none_or(|end| std::time::Instant::now() < end)
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
        board_lost: shared.losses(),
        stopped: shared.stopped(),
    })
}
