//! `serve`: a virtual board. The core's board and controller (the firmware's logic, as the
//! firmware wires it: `de_resonator::board`) at the scene's tick rate against the scene's
//! full plant, in real time or faster, serving the command port on a socket with exactly the
//! firmware's protocol: the start-up line (`# ready …` or `# refused …`) to each client as
//! it connects, one reply a request, `save` kept across `reset` in memory as flash keeps it.

use std::fmt;
use std::io::{ErrorKind, Read, Write};
use std::net::TcpListener;
use std::os::unix::fs::FileTypeExt;
use std::os::unix::net::UnixListener;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Args;
use de_resonator::board::commands::{self, Command};
use de_resonator::board::port::{Extras, TickClock};
use de_resonator::board::runner::{self, Follow, Ticker};
use de_resonator::board::FlashKeeper;
use de_resonator::board::{self, Board, Line, Lines, ReplyLine, ResetCause};
use de_resonator::flash::{RamFlash, RAM_PAGE_BYTES};
use de_resonator::wire::protocol::NOTICE;
use de_resonator::wire::stream::{self, Telemetry};
use de_resonator::{Controller, Dac8551, Image, Inputs, OutputStage};
use serde::Serialize;

use super::image::PowerUpArg;
use super::{sig, Report};
use crate::command_port::control;
use crate::scene;

#[derive(Args, Debug)]
#[command(group(clap::ArgGroup::new("socket").required(true).args(["tcp", "unix", "pty"])))]
pub struct ServeArgs {
    /// The scene (TOML) whose device, image settings and plant the board runs.
    ///
    /// Default: the built-in reference scene (scenes/reference.toml).
    pub scene: Option<PathBuf>,
    /// Serve on a TCP socket, HOST:PORT (e.g. 127.0.0.1:4000).
    #[arg(long, value_name = "HOST:PORT")]
    pub tcp: Option<String>,
    /// Serve on a Unix socket at PATH (a stale socket there is replaced).
    #[arg(long, value_name = "PATH")]
    pub unix: Option<PathBuf>,
    /// Serve on a pseudo-terminal, as a board's USB serial port: its path is printed
    /// (`/dev/pts/N`) for any terminal program (`picocom /dev/pts/N`, screen, minicom).
    #[arg(long)]
    pub pty: bool,
    /// Send the telemetry stream (`stream <hz>` starts it) to clients of a TCP socket,
    /// HOST:PORT: COBS-framed records, as a board's stream UART sends them.
    ///
    /// Without it or --stream-unix, `stream` answers that the board has no stream port.
    #[arg(long, value_name = "HOST:PORT", conflicts_with = "stream_unix")]
    pub stream_tcp: Option<String>,
    /// Send the telemetry stream to clients of a Unix socket at PATH.
    #[arg(long, value_name = "PATH")]
    pub stream_unix: Option<PathBuf>,
    /// Simulated seconds per wall-clock second, or `max`: as fast as it computes.
    #[arg(long, value_name = "X|max", default_value = "1", value_parser = speed)]
    pub speed: Speed,
    /// What the board does once its boot checks pass: `drive` the scene's plan at once (a
    /// scene's image, as `run` boots it), or `wait` with the output off at 0 V for `start`,
    /// as a board flashed with `host-sim image`'s default does (`image --scene S --power-up
    /// wait` writes the same bytes).
    #[arg(long, value_name = "WHEN", value_enum, default_value_t = PowerUpArg::Drive)]
    pub power_up: PowerUpArg,
    /// Stop after this many simulated seconds, then print a report.
    ///
    /// Default: serve until interrupted.
    #[arg(long, value_name = "S")]
    pub seconds: Option<f64>,
}

/// How fast the virtual board runs against the wall clock.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Speed {
    /// This many simulated seconds a wall second.
    Times(f64),
    /// No pacing.
    Max,
}

/// The slowest `--speed`: a thousandth of real time.
const MIN_SPEED: f64 = 1e-3;

fn speed(word: &str) -> Result<Speed, String> {
    if word == "max" {
        return Ok(Speed::Max);
    }
    match word.parse::<f64>() {
        Ok(x) if (MIN_SPEED..=1e9).contains(&x) => Ok(Speed::Times(x)),
        _ => Err(format!(
            "{word}: a number from {MIN_SPEED} to 1e9, or `max`"
        )),
    }
}

/// What a session of the virtual board did (printed when `--seconds` ends it).
#[derive(Serialize, Debug)]
pub struct ServeReport {
    pub scene: String,
    pub ticks: u64,
    pub simulated_seconds: f64,
    pub wall_seconds: f64,
    pub clients: usize,
    pub requests: usize,
    /// What the controller said, with the simulated time.
    pub events: Vec<String>,
    /// The first check of the true plant that failed, and when: must stay `null`.
    pub plant_crossing: Option<super::Crossing>,
    /// What the board was doing as the session ended (its `status`), and how it ended.
    pub leaving: String,
}

impl fmt::Display for ServeReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "served scene {}: {} ticks ({} s simulated in {} s), {} clients, {} requests",
            self.scene,
            self.ticks,
            sig(self.simulated_seconds),
            sig(self.wall_seconds),
            self.clients,
            self.requests
        )
    }
}

impl Report for ServeReport {
    fn failure(&self) -> Option<String> {
        self.plant_crossing
            .as_ref()
            .map(|c| format!("the plant crossed {} at {} s", c.mode, sig(c.time_seconds)))
    }
}

/// The settings' and the fault log's flash, as the firmware's QEMU build has them: two RAM
/// pages for the settings, four for the log (kept across `reset`).
struct Flash(Vec<u8>);

/// The settings' pages; the log's follow.
const SETTINGS_PAGES: usize = 2;
const LOG_PAGES: usize = 4;

/// As on the chip (and the firmware's QEMU stand-in), an erase would stall the board: `save`
/// and `faults clear` wait for rest at 0 V and the log erases at boot only, so a script that
/// passes here passes on silicon.
const ERASE_STALLS: bool = true;

impl Flash {
    fn new() -> Self {
        Flash(vec![0xFF; (SETTINGS_PAGES + LOG_PAGES) * RAM_PAGE_BYTES])
    }

    fn keeper(&mut self) -> FlashKeeper<RamFlash<'_>> {
        let settings = (SETTINGS_PAGES * RAM_PAGE_BYTES) as u32;
        let len = self.0.len() as u32;
        FlashKeeper {
            flash: RamFlash::new(&mut self.0),
            range: 0..settings,
            log: Some(settings..len),
            erase_stalls: ERASE_STALLS,
        }
    }
}

/// A client's connection: its bytes both ways, and whether a program opened it again since
/// the last look (a pseudo-terminal that a terminal program closed and opened anew).
trait Conn: Read + Write {
    fn reopened(&mut self) -> bool {
        false
    }
}
impl Conn for std::net::TcpStream {}
impl Conn for std::os::unix::net::UnixStream {}

/// A connected client: its bytes into lines, its replies queued (nothing waits on a client
/// that does not read).
struct Client {
    stream: Box<dyn Conn>,
    /// Who it is, as another connection is told (`tcp 127.0.0.1:50412`, `the pseudo-terminal`).
    name: String,
    lines: Lines,
    out: Vec<u8>,
    gone: bool,
    /// The one connection whose requests may change the board (the oldest); the others
    /// read (`read_only`), and may `stop` it.
    controls: bool,
}

/// What a connection that does not control the board may ask: what changes nothing, and
/// `stop`, an emergency stop any connection may give (the controlling one is told): each
/// command's entry says (`Command::reads_only`).
fn read_only(line: &Line) -> bool {
    match line {
        Line::Text(bytes) => match commands::parse(bytes) {
            Ok(command) => command.reads_only(),
            // Not a request: the board's own `err 1` says why.
            Err(_) => true,
        },
        Line::TooLong | Line::Garbled => true,
    }
}

/// Whether `line` is a `stop`.
fn is_stop(line: &Line) -> bool {
    matches!(line, Line::Text(bytes) if commands::parse(bytes) == Ok(Command::Stop))
}

/// The controlling connection gone (found by its read): the oldest left takes over, and is
/// told.
fn promote(clients: &mut [Client]) {
    if clients.iter().any(|c| c.controls && !c.gone) {
        return;
    }
    if let Some(next) = clients.iter_mut().find(|c| !c.gone) {
        next.controls = true;
        next.say(control::NOW_CONTROLS);
        next.flush();
    }
}

/// Who controls the board now, by name.
fn controller(clients: &[Client]) -> String {
    clients
        .iter()
        .find(|c| c.controls && !c.gone)
        .map_or_else(|| "none".to_string(), |c| c.name.clone())
}

/// Bytes read from one client at one poll, at most: a client that never stops sending
/// cannot hold the board's ticks.
const READ_BYTES: usize = 4096;
/// Replies queued for a client that does not read, at most; beyond, it is dropped.
const QUEUED_BYTES: usize = 1 << 16;

impl Client {
    fn new(stream: Box<dyn Conn>, name: String) -> Self {
        Self {
            stream,
            name,
            lines: Lines::default(),
            out: Vec::new(),
            gone: false,
            controls: false,
        }
    }

    /// Queue a line for the client, ended as its connection ends lines (a prompt after it
    /// for a person at a terminal).
    fn say(&mut self, line: &str) {
        if self.out.len() > QUEUED_BYTES {
            self.gone = true;
            return;
        }
        self.out.extend_from_slice(line.as_bytes());
        self.out
            .extend_from_slice(self.lines.reply_end().as_bytes());
    }

    /// Queue a stream frame; dropped (a gap the receiver counts) while the client is more
    /// than `QUEUED_BYTES` behind.
    fn send(&mut self, frame: &[u8]) {
        if self.out.len() <= QUEUED_BYTES {
            self.out.extend_from_slice(frame);
        }
    }

    /// Write what is queued, as far as the socket takes it now.
    fn flush(&mut self) {
        while !self.out.is_empty() && !self.gone {
            match self.stream.write(&self.out) {
                Ok(0) => self.gone = true,
                Ok(n) => {
                    self.out.drain(..n);
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(_) => self.gone = true,
            }
        }
    }

    /// The request lines the client sent since the last poll (at most `READ_BYTES`).
    fn read_lines(&mut self, lines: &mut Vec<Line>) {
        let mut buf = [0u8; 512];
        let mut left = READ_BYTES;
        while left > 0 && !self.gone {
            match self.stream.read(&mut buf[..left.min(512)]) {
                Ok(0) => self.gone = true,
                Ok(n) => {
                    left -= n;
                    for &b in &buf[..n] {
                        let pushed = self.lines.push(b);
                        pushed.echo.bytes(|e| self.out.push(e));
                        lines.extend(pushed.line);
                    }
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(_) => self.gone = true,
            }
        }
    }
}

enum Listener {
    Tcp(TcpListener),
    Unix(UnixListener, PathBuf),
    /// A pseudo-terminal's master: one client, for good (taken at the first accept).
    Pty(std::cell::RefCell<Option<Pty>>),
}

/// A pseudo-terminal's master side, non-blocking: while no program has the terminal open,
/// reads find nothing (not an end), and writes are kept by the terminal as far as it can.
struct Pty {
    master: nix::pty::PtyMaster,
    /// No program had the terminal open at the last read (EIO).
    closed: bool,
    /// A program opened it since (found by a read that was not EIO), not yet told.
    reopened: bool,
}

impl Pty {
    /// A new pseudo-terminal in raw mode (no echo or line editing of its own: the board
    /// does those), and its path.
    fn open() -> Result<(Self, String), String> {
        use nix::fcntl::OFlag;
        use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};
        use std::os::fd::AsRawFd;
        let failed = |e: nix::Error| format!("cannot open a pseudo-terminal: {e}");
        let master = nix::pty::posix_openpt(OFlag::O_RDWR | OFlag::O_NOCTTY | OFlag::O_NONBLOCK)
            .map_err(failed)?;
        nix::pty::grantpt(&master).map_err(failed)?;
        nix::pty::unlockpt(&master).map_err(failed)?;
        let path = nix::pty::ptsname_r(&master).map_err(failed)?;
        let mut raw = tcgetattr(master.as_raw_fd()).map_err(failed)?;
        cfmakeraw(&mut raw);
        tcsetattr(master.as_raw_fd(), SetArg::TCSANOW, &raw).map_err(failed)?;
        let pty = Pty {
            master,
            closed: false,
            reopened: false,
        };
        Ok((pty, path))
    }
}

impl Read for Pty {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        match self.master.read(buf) {
            // EIO: no program has the terminal open now; one may later.
            Err(e) if e.raw_os_error() == Some(libc::EIO) => {
                self.closed = true;
                Err(ErrorKind::WouldBlock.into())
            }
            other => {
                if std::mem::take(&mut self.closed) {
                    self.reopened = true;
                }
                other
            }
        }
    }
}

impl Conn for Pty {
    fn reopened(&mut self) -> bool {
        std::mem::take(&mut self.reopened)
    }
}

impl Write for Pty {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self.master.write(buf) {
            Err(e) if e.raw_os_error() == Some(libc::EIO) => Err(ErrorKind::WouldBlock.into()),
            other => other,
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.master.flush()
    }
}

impl Listener {
    /// A listener on the TCP address or the Unix path given (one of them).
    fn bind(tcp: Option<&str>, unix: Option<&PathBuf>) -> Result<(Self, String), String> {
        if let Some(address) = tcp {
            let l = TcpListener::bind(address)
                .map_err(|e| format!("cannot listen on {address}: {e}"))?;
            l.set_nonblocking(true).map_err(|e| e.to_string())?;
            let at = l.local_addr().map_err(|e| e.to_string())?;
            return Ok((Listener::Tcp(l), format!("tcp {at}")));
        }
        let path = unix.cloned().ok_or("give --tcp or --unix")?;
        if let Ok(meta) = std::fs::symlink_metadata(&path) {
            if !meta.file_type().is_socket() {
                return Err(format!("{} exists and is not a socket", path.display()));
            }
            if std::os::unix::net::UnixStream::connect(&path).is_ok() {
                return Err(format!(
                    "{}: another server is listening there",
                    path.display()
                ));
            }
            let _ = std::fs::remove_file(&path);
        }
        let l = UnixListener::bind(&path)
            .map_err(|e| format!("cannot listen on {}: {e}", path.display()))?;
        l.set_nonblocking(true).map_err(|e| e.to_string())?;
        let at = format!("unix {}", path.display());
        Ok((Listener::Unix(l, path), at))
    }

    /// A client waiting to connect, if any, as a [`Client`] named for the others.
    fn accept(&self, count: usize) -> Option<Client> {
        match self {
            Listener::Tcp(l) => {
                let (s, peer) = l.accept().ok()?;
                s.set_nonblocking(true).ok()?;
                let _ = s.set_nodelay(true);
                Some(Client::new(Box::new(s), format!("tcp {peer}")))
            }
            Listener::Unix(l, _) => {
                let (s, _) = l.accept().ok()?;
                s.set_nonblocking(true).ok()?;
                Some(Client::new(
                    Box::new(s),
                    format!("unix socket client {count}"),
                ))
            }
            Listener::Pty(pty) => pty
                .borrow_mut()
                .take()
                .map(|p| Client::new(Box::new(p), "the pseudo-terminal".into())),
        }
    }
}

impl Drop for Listener {
    fn drop(&mut self) {
        if let Listener::Unix(_, path) = self {
            let _ = std::fs::remove_file(path);
        }
    }
}

/// How often the sockets are polled at `--speed max`, wall time.
const POLL: Duration = Duration::from_millis(1);

pub fn serve(args: &ServeArgs) -> Result<ServeReport, String> {
    let scene = match &args.scene {
        Some(path) => scene::load(path)?,
        None => {
            scene::parse(scene::REFERENCE).map_err(|e| format!("built-in reference scene: {e}"))?
        }
    };
    let lp = &scene.run;
    let tick_seconds = 1.0 / f64::from(lp.settings.tick_hz);
    let ticks_limit = match args.seconds {
        None => None,
        Some(s) if s > 0.0 && s.is_finite() && s * f64::from(lp.settings.tick_hz) < 4e9 => {
            Some((s / tick_seconds).round() as u64)
        }
        Some(s) => {
            return Err(format!(
                "--seconds {s}: a positive number of simulated seconds"
            ))
        }
    };
    // The image the scene's board boots from (`run`'s and the firmware's in the loop).
    let bytes = lp.image(args.power_up.into())?;
    let mut flash = Flash::new();
    let (listener, at) = if args.pty {
        let (pty, path) = Pty::open()?;
        // The path alone on stdout, for a script; how to use it on stderr.
        println!("{path}");
        eprintln!("the command port on {path}: `picocom {path}` (any terminal program)");
        let at = format!("pty {path}");
        (Listener::Pty(std::cell::RefCell::new(Some(pty))), at)
    } else {
        Listener::bind(args.tcp.as_deref(), args.unix.as_ref())?
    };
    let streams = match (&args.stream_tcp, &args.stream_unix) {
        (None, None) => None,
        (tcp, unix) => {
            let (l, at) = Listener::bind(tcp.as_deref(), unix.as_ref())?;
            eprintln!("the telemetry stream on {at} (`stream <hz>` starts it)");
            Some(l)
        }
    };
    let mut stream_clients: Vec<Client> = Vec::new();
    let mut telemetry = Telemetry::default();
    let mut ticker = Ticker::new();
    let mut frame = [0u8; stream::FRAME_BYTES];
    eprintln!(
        "serving scene {} on {at} at {}; the command port's protocol (`help`)",
        scene.name,
        match args.speed {
            Speed::Max => "full speed".to_string(),
            Speed::Times(x) => format!("{}× real time", sig(x)),
        }
    );

    let wires = lp.wires();
    let mut stage = OutputStage::new(Dac8551::new(&wires.bus), &wires.enable);
    let _ = stage.safe();
    let mut slot: Option<Controller> = None;
    let boot = |slot: &mut Option<Controller>, keeper, cause| {
        let (board, started) = Board::boot(slot, Image::parse(&bytes), keeper, cause);
        let mut banner = String::new();
        if let Some(cause) = cause {
            let _ = runner::write_reset(cause, &mut banner, "\n");
        }
        let _ = started.write_banner(&mut banner, "\n");
        let said: Vec<String> = banner.lines().map(str::to_string).collect();
        (board, said)
    };
    let (mut logic, mut banner) = boot(&mut slot, Some(flash.keeper()), None);
    // A request served since the last boot: the start-up line no longer says the state.
    let mut asked_since_boot = false;
    for line in &banner {
        eprintln!("{line}");
    }
    let mut bench = lp.bench(false);
    let mut clients: Vec<Client> = Vec::new();
    let mut report = ServeReport {
        scene: scene.name.clone(),
        ticks: 0,
        simulated_seconds: 0.0,
        wall_seconds: 0.0,
        clients: 0,
        requests: 0,
        events: Vec::new(),
        plant_crossing: None,
        leaving: String::new(),
    };
    // Ctrl-C (or a SIGTERM) ends the session between two ticks, saying what the board did;
    // a second one ends the process at once.
    let interrupted = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        let _ = signal_hook::flag::register_conditional_shutdown(signal, 1, interrupted.clone());
        let _ = signal_hook::flag::register(signal, interrupted.clone());
    }
    let started = Instant::now();
    let mut next_poll = started;
    let mut k: u64 = 0;
    while ticks_limit.is_none_or(|n| k < n)
        && !interrupted.load(std::sync::atomic::Ordering::Relaxed)
    {
        let now = Instant::now();
        let due = match args.speed {
            Speed::Max => None,
            Speed::Times(x) => Duration::try_from_secs_f64(k as f64 * tick_seconds / x)
                .ok()
                .and_then(|d| started.checked_add(d)),
        };
        if now >= next_poll || due.is_some_and(|d| d > now) {
            next_poll = now + POLL;
            if let Some(streams) = &streams {
                while let Some(client) = streams.accept(stream_clients.len() + 1) {
                    stream_clients.push(client);
                }
            }
            // The clock the firmware's status reports (u32s of ticks and µs, wrapping).
            let extras = Extras {
                clock: Some(TickClock {
                    tick: k as u32,
                    micros: (k as f64 * tick_seconds * 1e6) as u64 as u32,
                }),
                stream_port: streams.is_some(),
                ..Extras::default()
            };
            let mut queue = Vec::new();
            for (i, client) in clients.iter_mut().enumerate() {
                let mut lines = Vec::new();
                client.read_lines(&mut lines);
                queue.extend(lines.into_iter().map(|line| (i, line)));
            }
            promote(&mut clients);
            // A new client, or a terminal opened again on the pseudo-terminal, hears the
            // board's state now: the last boot's start-up line while it still says it
            // (nothing asked since, no fault), else the status now.
            let reopened: Vec<usize> = (0..clients.len())
                .filter(|&i| clients[i].stream.reopened())
                .collect();
            let mut joined = Vec::new();
            while let Some(client) = listener.accept(report.clients + joined.len() + 1) {
                joined.push(client);
            }
            if !reopened.is_empty() || !joined.is_empty() {
                let faulted = slot.as_ref().is_some_and(|c| c.latched_fault().is_some());
                let said = if asked_since_boot || faulted {
                    let mut now = ReplyLine::new();
                    let status = crate::engine::core_board::command_line("status")?;
                    logic.serve(&status, &mut &mut slot, &extras, &mut now);
                    vec![format!("{NOTICE}now {}", now.trim_start_matches("ok "))]
                } else {
                    banner.clone()
                };
                for i in reopened {
                    said.iter().for_each(|line| clients[i].say(line));
                }
                for mut client in joined {
                    said.iter().for_each(|line| client.say(line));
                    // (A client that left since the last poll was found gone by its read.)
                    client.controls = !clients.iter().any(|c| c.controls && !c.gone);
                    if !client.controls {
                        client.say(&control::reads_only(&controller(&clients)));
                    }
                    clients.push(client);
                    report.clients += 1;
                }
            }
            // In the order received; after a `reset`, the rest go to the board booted anew.
            for (i, line) in queue {
                report.requests += 1;
                let mut reply = ReplyLine::new();
                if !clients[i].controls && !read_only(&line) {
                    let refused = control::not_in_control(&controller(&clients));
                    clients[i].say(&refused);
                    continue;
                }
                asked_since_boot = true;
                let then = logic.serve(&line, &mut &mut slot, &extras, &mut reply);
                clients[i].say(&reply);
                // An emergency stop from a connection that reads: the controlling one told.
                if !clients[i].controls && is_stop(&line) {
                    let told = control::stopped_by(&clients[i].name, &reply);
                    clients
                        .iter_mut()
                        .filter(|c| c.controls)
                        .for_each(|c| c.say(&told));
                }
                // A restart stops the stream (its count starts again, as on a board).
                if runner::follow(then, &mut telemetry) == Follow::Reset {
                    // The slot is empty: the output off at once (as the firmware's next tick
                    // does), then the boot, the settings' flash kept; the board's ticks count
                    // from its boot, as the firmware's do.
                    let _ = board::tick::drive(&mut slot, &mut stage, Ok(Inputs::NONE));
                    ticker = Ticker::new();
                    let keeper = logic.into_keeper();
                    (logic, banner) = boot(&mut slot, keeper, Some(ResetCause::Asked));
                    asked_since_boot = false;
                    for line in &banner {
                        eprintln!("{line}");
                        clients.iter_mut().for_each(|c| c.say(line));
                    }
                }
            }
            clients.iter_mut().for_each(Client::flush);
            clients.retain(|c| !c.gone);
            promote(&mut clients);
            stream_clients.iter_mut().for_each(Client::flush);
            stream_clients.retain(|c| !c.gone);
            if let Some(due) = due.filter(|&d| d > Instant::now()) {
                std::thread::sleep((due - Instant::now().min(due)).min(POLL));
                continue;
            }
        }
        let t = k as f64 * tick_seconds;
        let done = lp
            .step(k, &mut bench, &mut ticker, &mut slot, &mut stage, &wires)?
            .done;
        if let Some(record) =
            telemetry.record(done.tick, !stage.is_safe(), slot.as_ref(), &done.readings)
        {
            let n = record.frame(&mut frame);
            for client in &mut stream_clients {
                client.send(&frame[..n]);
            }
        }
        if let Some(event) = done.event() {
            let line = format!("{} s: {event}", sig(t));
            eprintln!("{line}");
            report.events.push(line);
        }
        // A fault into the log, as the firmware's command task writes it after the tick, at
        // the tick rate the board runs at.
        if let Some(logged) = done.logged() {
            if let Some(Err(e)) = logic.log(&logged, logic.tick_hz(&slot)) {
                eprintln!("{} s: the fault log: {e}", sig(t));
            }
        }
        if report.plant_crossing.is_none() {
            if let Some((mode, at)) = bench.crossing {
                eprintln!("{} s: the plant crossed {}", sig(at), mode.name());
                report.plant_crossing =
                    super::Crossing::with_state(Some((mode, at)), bench.crossing_state);
            }
        }
        k += 1;
    }
    let mut now = ReplyLine::new();
    let status = crate::engine::core_board::command_line("status")?;
    logic.serve(&status, &mut &mut slot, &Extras::default(), &mut now);
    let how = if interrupted.load(std::sync::atomic::Ordering::Relaxed) {
        "interrupted"
    } else {
        "its time over"
    };
    report.leaving = format!(
        "{how} at {} s simulated; the board's last status: {}",
        sig(k as f64 * tick_seconds),
        now.trim_start_matches("ok ")
    );
    eprintln!(
        "{}; the virtual board ends with this session (a real board goes on as it was told)",
        report.leaving
    );
    report.ticks = k;
    report.simulated_seconds = k as f64 * tick_seconds;
    report.wall_seconds = started.elapsed().as_secs_f64();
    Ok(report)
}
