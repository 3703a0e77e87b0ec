//! `console`: talk to the firmware's command port (the core's `protocol`) over a serial port,
//! a TCP socket or a Unix socket (QEMU's USART2), typed at a prompt or from a script.
//!
//! A reader thread takes every line the board sends: what it says on its own (`# …`: the
//! start-up line, a reset, a fault) is shown as it arrives, replies go to the request that
//! waits for them. Two requests are the console's own, not sent: `sleep <s>` and
//! `wait <key>=<value>[|<value>…] [<s>]` (asks `status` until the field holds one of the
//! values; a script fails when the time runs out).

use std::fmt;
use std::io::{BufRead, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use clap::Args;
use de_resonator::wire::reply::Reply;
use serde::Serialize;
use serde_json::{Map, Value};

use crate::command_port::{fields, gone, PortArgs, Session, StreamArgs};

use super::record;
use super::Report;
use crate::telemetry::Recorder;

#[derive(Args, Debug)]
pub struct ConsoleArgs {
    #[command(flatten)]
    pub board: PortArgs,
    /// Requests from FILE, one a line (`#` comments and blank lines skipped); status 1 if any gets
    /// an `err` or a `wait` runs out of time.
    ///
    /// Without it: requests from stdin, with a prompt on a terminal. Besides the board's
    /// requests (`help`), the console's own: `sleep <S>` waits S seconds; `wait
    /// <key>=<value>[|<value>…] [<S>]` asks `status` every 0.1 s until the field holds one of
    /// the values (e.g. `wait phase=driving 10`; default 30 s).
    #[arg(long, value_name = "FILE")]
    pub script: Option<PathBuf>,
    /// Record the board's telemetry stream to FILE (CSV, `#` header lines naming the
    /// firmware, the image's CRC, the settings and the records lost): sends `stream <HZ>`
    /// first and `stream off` at the end. Give where the stream comes from with
    /// --stream-port, --stream-tcp or --stream-unix.
    ///
    /// The recording lasts --duration-seconds, or the script's run (stdin is not read).
    #[arg(long, value_name = "FILE.csv", requires = "stream_source")]
    pub record: Option<PathBuf>,
    #[command(flatten)]
    pub stream: StreamArgs,
    /// Records a second asked of the board (`stream <HZ>`).
    #[arg(long, value_name = "HZ", default_value_t = 100.0)]
    pub stream_hz: f64,
    /// How long to record, s (wall time from `stream`). Default: 10 s, or the script's run.
    #[arg(long, value_name = "S")]
    pub duration_seconds: Option<f64>,
    /// Draw the recording to FILE.svg: the voltage commanded under the cap, the stretch.
    #[arg(long, value_name = "FILE.svg", requires = "record")]
    pub plot: Option<PathBuf>,
}

/// One request and its reply.
#[derive(Serialize, Debug)]
pub struct Exchange {
    pub request: String,
    pub reply: String,
    pub ok: bool,
    /// An `ok` reply's `key=value` pairs (numbers as numbers; `fault` takes the rest of the
    /// line), or an `err`'s `code` and `message`.
    pub fields: Map<String, Value>,
}

/// What a console session did.
#[derive(Serialize, Debug)]
pub struct ConsoleReport {
    /// Lines the firmware said on its own (`# …`: its start-up line, a reset, a fault).
    pub notices: Vec<String>,
    pub exchanges: Vec<Exchange>,
    /// Whether the board closed the connection before the requests were done.
    pub closed_by_board: bool,
    /// Why a script stopped before its end (a `wait` that ran out of time, a silent board).
    pub stopped: Option<String>,
    /// The telemetry recorded (`--record`).
    pub recording: Option<record::Recorded>,
    #[serde(skip)]
    script: bool,
}

impl fmt::Display for ConsoleReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let errors = self.exchanges.iter().filter(|e| !e.ok).count();
        write!(
            f,
            "{} requests, {} answered `err`",
            self.exchanges.len(),
            errors
        )?;
        if self.closed_by_board {
            write!(f, "; the board closed the connection")?;
        }
        if let Some(r) = &self.recording {
            write!(
                f,
                "; recorded {} records to {} ({} lost, {} bad frames)",
                r.records, r.file, r.lost, r.bad_frames
            )?;
            if let Some(plot) = &r.plot {
                write!(f, ", drawn to {plot}")?;
            }
        }
        Ok(())
    }
}

impl Report for ConsoleReport {
    fn failure(&self) -> Option<String> {
        if self.closed_by_board {
            return Some("the board closed the connection".into());
        }
        if let Some(why) = &self.stopped {
            return Some(why.clone());
        }
        let first = self.exchanges.iter().find(|e| !e.ok)?;
        self.script
            .then(|| format!("`{}` got `{}`", first.request, first.reply))
    }
}

/// A line on stdout as it happens; a reader gone (a closed pipe) is not an error.
fn say(line: &str) {
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{line}").and_then(|()| out.flush());
}

/// A request of the console's own (not sent to the board).
#[derive(Debug, PartialEq)]
enum Local {
    Sleep(Duration),
    /// Until `status`'s field `key` holds one of `values`, within the time.
    Wait {
        key: String,
        values: Vec<String>,
        within: Duration,
    },
}

/// How long the first request waits for a start-up line (a board already running says none).
const STARTUP_WAIT: Duration = Duration::from_secs(2);

/// The time a `wait` gives the board unless told.
const WAIT_SECONDS: f64 = 30.0;

/// `sleep <s>` or `wait <key>=<v>[|<v>…] [<s>]`; `None` for a board's request.
fn local(request: &str) -> Option<Result<Local, String>> {
    let mut words = request.split_whitespace();
    let seconds = |word: Option<&str>, default: Option<f64>| -> Result<Duration, String> {
        let s = match (word, default) {
            (Some(w), _) => w
                .parse::<f64>()
                .map_err(|_| format!("`{request}`: {w} is not a number of seconds"))?,
            (None, Some(d)) => d,
            (None, None) => return Err(format!("`{request}`: give the seconds")),
        };
        if !(s.is_finite() && (0.0..=86_400.0).contains(&s)) {
            return Err(format!("`{request}`: {s} s is not in 0 .. 86400 s"));
        }
        Ok(Duration::from_secs_f64(s))
    };
    match words.next()? {
        "sleep" => Some(seconds(words.next(), None).map(Local::Sleep)),
        "wait" => Some((|| {
            let condition = words
                .next()
                .ok_or_else(|| format!("`{request}`: wait <key>=<value> [seconds]"))?;
            let (key, values) = condition
                .split_once('=')
                .filter(|(k, v)| !k.is_empty() && !v.is_empty())
                .ok_or_else(|| format!("`{request}`: wait <key>=<value> [seconds]"))?;
            let within = seconds(words.next(), Some(WAIT_SECONDS))?;
            Ok(Local::Wait {
                key: key.into(),
                values: values.split('|').map(String::from).collect(),
                within,
            })
        })()),
        _ => None,
    }
}

pub fn console(args: &ConsoleArgs, json: bool) -> Result<ConsoleReport, String> {
    let script = match &args.script {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| format!("cannot read script {}: {e}", path.display()))?;
            // A line ends at \n, \r or \r\n, as on the board (a script with old Mac line
            // ends is one request a line, not one the board would split).
            let lines: Vec<String> = text
                .split(['\n', '\r'])
                .map(str::trim)
                .filter(|l| !l.is_empty() && !l.starts_with('#'))
                .map(String::from)
                .collect();
            // The console's own requests checked before anything is sent.
            for line in &lines {
                if let Some(Err(why)) = local(line) {
                    return Err(why);
                }
            }
            Some(lines)
        }
        None => None,
    };
    let prompt = script.is_none() && !json && std::io::stdin().is_terminal();
    let echo = !json;
    if echo {
        eprintln!("connected to {}", args.board.describe());
    }
    let notices = Arc::new(Mutex::new(Vec::new()));
    let kept = notices.clone();
    let mut session = Session::open(&args.board, move |line| {
        if echo {
            say(&line);
        }
        if let Ok(mut kept) = kept.lock() {
            kept.push(line);
        }
    })?;
    // A board that starts as the console connects (QEMU's socket, `serve`) says its start-up
    // line first, and may not listen before it: the first request waits for it, a while.
    let end = Instant::now() + STARTUP_WAIT;
    while Instant::now() < end && notices.lock().map_or(true, |n| n.is_empty()) {
        std::thread::sleep(Duration::from_millis(20));
    }
    // A clean line first: a half line an earlier connection left is refused, not glued.
    session.clean_line()?;
    let mut left_by_interrupt = false;
    let mut report = ConsoleReport {
        notices: Vec::new(),
        exchanges: Vec::new(),
        closed_by_board: false,
        stopped: None,
        recording: None,
        script: script.is_some(),
    };
    let recording = match &args.record {
        Some(path) => Some(Recording::start(args, path, &mut session, echo)?),
        None => None,
    };
    // Ctrl-C: a flag, read between requests and in a `wait` (the session then says what the
    // board is still doing as it ends).
    let interrupted = Arc::new(AtomicBool::new(false));
    let _ = signal_hook::flag::register(signal_hook::consts::SIGINT, interrupted.clone());
    let requests: Box<dyn Iterator<Item = String>> = match script {
        Some(lines) => Box::new(lines.into_iter()),
        None if recording.is_some() => Box::new(std::iter::empty()),
        None => Box::new(typed(interrupted.clone())),
    };
    let show_prompt = || {
        if prompt {
            let mut out = std::io::stdout().lock();
            let _ = write!(out, "> ").and_then(|()| out.flush());
        }
    };
    show_prompt();
    for request in requests {
        if interrupted.swap(false, Ordering::Relaxed) {
            left_by_interrupt = true;
            break;
        }
        let request = request.trim().to_string();
        if request.is_empty() || request.starts_with('#') {
            show_prompt();
            continue;
        }
        if echo && report.script {
            say(&format!("> {request}"));
        }
        let done = match local(&request) {
            Some(Ok(Local::Sleep(time))) => {
                std::thread::sleep(time);
                Ok(())
            }
            Some(Ok(Local::Wait {
                key,
                values,
                within,
            })) => wait(&mut session, &key, &values, within, echo, &interrupted),
            Some(Err(why)) => Err(why),
            None => session.ask(&request).map(|line| {
                if echo {
                    say(&line);
                }
                let ok = matches!(Reply::parse(&line), Some(Reply::Ok(_)));
                report.exchanges.push(Exchange {
                    request: request.clone(),
                    fields: fields(&line),
                    reply: line,
                    ok,
                });
            }),
        };
        if let Err(why) = done {
            if gone(&why) {
                if echo {
                    eprintln!("{why}");
                }
                report.closed_by_board = true;
                break;
            }
            if report.script {
                report.stopped = Some(why);
                break;
            }
            eprintln!("error: {why}");
        }
        show_prompt();
    }
    report.notices = notices.lock().map(|n| n.clone()).unwrap_or_default();
    if let Some(recording) = recording {
        report.recording =
            Some(recording.finish(args, &mut session, &report.notices, &interrupted)?);
    }
    left_by_interrupt |= interrupted.load(Ordering::Relaxed);
    if echo && !report.closed_by_board {
        eprintln!("{}", leaving(&mut |r| session.ask(r), left_by_interrupt));
    }
    Ok(report)
}

/// A `--record` under way: the stream's reader, what the header names, when it started.
struct Recording {
    recorder: Recorder,
    path: PathBuf,
    header: Vec<String>,
    tick_hz: f64,
    started: Instant,
}

impl Recording {
    /// Ask what runs (`info`, `get`, `status`) for the header, connect to the stream, and
    /// start it (`stream <hz>`).
    fn start(
        args: &ConsoleArgs,
        path: &Path,
        session: &mut Session,
        echo: bool,
    ) -> Result<Self, String> {
        let hz = args.stream_hz;
        if !(hz > 0.0 && hz.is_finite()) {
            return Err(format!(
                "--stream-hz {hz}: a positive number of records a second"
            ));
        }
        if let Some(s) = args
            .duration_seconds
            .filter(|s| !(*s > 0.0 && s.is_finite()))
        {
            return Err(format!(
                "--duration-seconds {s}: a positive number of seconds"
            ));
        }
        let source = args
            .stream
            .source()
            .ok_or("--record needs --stream-port, --stream-tcp or --stream-unix")?;
        let mut header = Vec::new();
        let mut tick_hz = f64::NAN;
        for request in ["info", "get", "status"] {
            let line = session.ask(request)?;
            if let Some(Value::Number(n)) = fields(&line).get("tick_hz") {
                tick_hz = n.as_f64().unwrap_or(f64::NAN);
            }
            header.push(format!("{request}: {line}"));
        }
        if !(tick_hz > 0.0) {
            return Err("the board's `info` and `get` say no tick rate".into());
        }
        let recorder = Recorder::start(&source)?;
        let request = format!("stream {hz}");
        let line = session.ask(&request)?;
        if !matches!(Reply::parse(&line), Some(Reply::Ok(_))) {
            let _ = recorder.finish(Duration::ZERO);
            return Err(format!("`{request}` got `{line}`"));
        }
        if echo {
            eprintln!("recording the stream to {}: {line}", path.display());
        }
        header.push(format!("{request}: {line}"));
        Ok(Recording {
            recorder,
            path: path.to_path_buf(),
            header,
            tick_hz,
            started: Instant::now(),
        })
    }

    /// Wait out the duration, stop the stream, and write the CSV (and the plot).
    /// Ctrl-C (`interrupted`) ends the recording early, kept as far as it went.
    fn finish(
        self,
        args: &ConsoleArgs,
        session: &mut Session,
        notices: &[String],
        interrupted: &AtomicBool,
    ) -> Result<record::Recorded, String> {
        let duration = match (args.duration_seconds, args.script.is_some()) {
            (Some(s), _) => Duration::from_secs_f64(s),
            (None, true) => Duration::ZERO,
            (None, false) => Duration::from_secs_f64(DEFAULT_RECORD_SECONDS),
        };
        while self.started.elapsed() < duration && !interrupted.load(Ordering::Relaxed) {
            let left = duration.saturating_sub(self.started.elapsed());
            std::thread::sleep(left.min(Duration::from_millis(50)));
        }
        let stopped = session.ask("stream off");
        // The frames in flight when the board stopped.
        let (records, receiver) = self.recorder.finish(Duration::from_millis(200))?;
        stopped?;
        let mut header = self.header;
        header.extend(notices.iter().map(|n| format!("board said: {n}")));
        let mut recording = record::write(&self.path, &header, &records, &receiver, self.tick_hz)?;
        if let Some(plot) = &args.plot {
            let title = self
                .path
                .file_stem()
                .map_or("recording".into(), |s| s.to_string_lossy().into_owned());
            let svg = crate::plot::svg(&record::plot(&records, &receiver, self.tick_hz, &title));
            std::fs::write(plot, svg)
                .map_err(|e| format!("cannot write {}: {e}", plot.display()))?;
            recording.plot = Some(plot.display().to_string());
        }
        Ok(recording)
    }
}

/// How long `--record` records without a script or --duration-seconds, s.
const DEFAULT_RECORD_SECONDS: f64 = 10.0;

/// `status` every 0.1 s until its `key` holds one of `values`, within `within`.
fn wait(
    session: &mut Session,
    key: &str,
    values: &[String],
    within: Duration,
    echo: bool,
    interrupted: &AtomicBool,
) -> Result<(), String> {
    let end = Instant::now() + within;
    loop {
        // Ctrl-C cancels the wait, not the session.
        if interrupted.swap(false, Ordering::Relaxed) {
            if echo {
                eprintln!("wait {key}={}: cancelled (Ctrl-C)", values.join("|"));
            }
            return Ok(());
        }
        let line = session.ask("status")?;
        // The field as the board wrote it (`volts=0`), or as a number equal to the one
        // asked for (`wait volts=0.0`).
        let now = Reply::parse(&line).and_then(|r| r.field(key));
        let holds = |want: &String| match (now, want.parse::<f64>()) {
            (Some(text), Ok(number)) => text == want || text.parse::<f64>() == Ok(number),
            (Some(text), Err(_)) => text == want,
            (None, _) => false,
        };
        if values.iter().any(holds) {
            if echo {
                say(&line);
            }
            return Ok(());
        }
        if Instant::now() >= end {
            return Err(format!(
                "wait {key}={}: not within {} s (last `{line}`)",
                values.join("|"),
                within.as_secs_f64()
            ));
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// The lines typed on stdin, read on a thread of their own: the iterator ends at the end of
/// input, or at Ctrl-C (`interrupted` set) while waiting for a line.
fn typed(interrupted: Arc<AtomicBool>) -> impl Iterator<Item = String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::stdin().lock().lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                return;
            }
        }
    });
    std::iter::from_fn(move || loop {
        match rx.recv_timeout(Duration::from_millis(100)) {
            Ok(line) => return Some(line),
            Err(mpsc::RecvTimeoutError::Timeout) if interrupted.load(Ordering::Relaxed) => {
                return None
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            Err(mpsc::RecvTimeoutError::Disconnected) => return None,
        }
    })
}

/// What the console says as it leaves: what the board is still doing (it keeps its own
/// rules: leaving changes nothing).
pub(crate) fn leaving(
    ask: &mut dyn FnMut(&str) -> Result<String, String>,
    interrupted: bool,
) -> String {
    let how = if interrupted { "Ctrl-C: " } else { "" };
    let Ok(line) = ask("status") else {
        return format!("{how}leaving; the board did not answer `status`");
    };
    let field = |key| {
        Reply::parse(&line)
            .and_then(|r| r.field(key))
            .unwrap_or("?")
    };
    match field("output") {
        "on" => format!(
            "{how}leaving with the output ON: the board is {} at {} V (bias {} V) and goes on \
             as it was told; `stop` brings it to 0 V",
            field("phase"),
            field("volts"),
            field("bias_volts")
        ),
        "off" => format!(
            "{how}leaving; the board is {} with the output off at 0 V",
            field("phase")
        ),
        _ => format!("{how}leaving; the board says `{line}`"),
    }
}
