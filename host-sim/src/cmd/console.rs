//! `console`: talk to the firmware's command port (the core's `protocol`) over a serial port,
//! a TCP socket or a Unix socket (QEMU's USART2), typed at a prompt or from a script.

use std::fmt;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::PathBuf;
use std::time::Duration;

use clap::Args;
use de_resonator::board::protocol::{Reply, NOTICE};
use serde::Serialize;

use super::Report;

#[derive(Args, Debug)]
#[command(group(clap::ArgGroup::new("connection").required(true).args(["port", "tcp", "unix"])))]
pub struct ConsoleArgs {
    /// A serial port (a board's USART2 through a USB adapter), e.g.
    ///
    /// /dev/ttyUSB0.
    #[arg(long, value_name = "DEVICE")]
    pub port: Option<String>,
    /// A TCP socket, HOST:PORT (QEMU's `-chardev socket,host=…,port=…,server=on`).
    #[arg(long, value_name = "HOST:PORT")]
    pub tcp: Option<String>,
    /// A Unix socket (QEMU's `-chardev socket,path=…,server=on`).
    #[arg(long, value_name = "PATH")]
    pub unix: Option<PathBuf>,
    /// The serial port's baud rate.
    #[arg(long, value_name = "BAUD", default_value_t = 115_200)]
    pub baud: u32,
    /// Requests from FILE, one a line (`#` comments and blank lines skipped); status 1 if any gets
    /// an `err`.
    ///
    /// Without it: a prompt on stdin.
    #[arg(long, value_name = "FILE")]
    pub script: Option<PathBuf>,
    /// How long to wait for a reply, s.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 10.0,
        allow_negative_numbers = true
    )]
    pub timeout: f64,
}

/// One request and its reply.
#[derive(Serialize, Debug)]
pub struct Exchange {
    pub request: String,
    pub reply: String,
    pub ok: bool,
}

/// What a console session did.
#[derive(Serialize, Debug)]
pub struct ConsoleReport {
    /// Lines the firmware said on its own (`# …`: its start-up banner).
    pub notices: Vec<String>,
    pub exchanges: Vec<Exchange>,
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
        )
    }
}

impl Report for ConsoleReport {
    fn failure(&self) -> Option<String> {
        let first = self.exchanges.iter().find(|e| !e.ok)?;
        self.script
            .then(|| format!("`{}` got `{}`", first.request, first.reply))
    }
}

trait Port: Read + Write {}
impl<T: Read + Write> Port for T {}

/// A connection: its reading half and its writing half.
type Halves = (Box<dyn Read>, Box<dyn Port>);

/// The connection asked for: a reader and a writer on it.
fn connect(args: &ConsoleArgs, timeout: Duration) -> Result<Halves, String> {
    if let Some(address) = &args.tcp {
        let stream = std::net::TcpStream::connect(address)
            .map_err(|e| format!("cannot connect to {address}: {e}"))?;
        stream
            .set_read_timeout(Some(timeout))
            .map_err(|e| e.to_string())?;
        let reader = stream.try_clone().map_err(|e| e.to_string())?;
        return Ok((Box::new(reader), Box::new(stream)));
    }
    if let Some(path) = &args.unix {
        let stream = std::os::unix::net::UnixStream::connect(path)
            .map_err(|e| format!("cannot connect to {}: {e}", path.display()))?;
        stream
            .set_read_timeout(Some(timeout))
            .map_err(|e| e.to_string())?;
        let reader = stream.try_clone().map_err(|e| e.to_string())?;
        return Ok((Box::new(reader), Box::new(stream)));
    }
    let name = args.port.as_deref().ok_or("give --port, --tcp or --unix")?;
    let port = serialport::new(name, args.baud)
        .timeout(timeout)
        .open()
        .map_err(|e| format!("cannot open serial port {name}: {e}"))?;
    let reader = port.try_clone().map_err(|e| e.to_string())?;
    Ok((Box::new(reader), Box::new(port)))
}

/// A line on stdout as it happens; a reader gone (a closed pipe) is not an error.
fn say(line: &str) {
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{line}").and_then(|()| out.flush());
}

/// Read lines until a reply, keeping the notices before it.
fn reply(
    reader: &mut impl BufRead,
    notices: &mut Vec<String>,
    echo: bool,
) -> Result<String, String> {
    loop {
        let mut line = String::new();
        match reader.read_line(&mut line) {
            Ok(0) => return Err("the firmware closed the connection".into()),
            Ok(_) => {}
            Err(e) => return Err(format!("no reply: {e}")),
        }
        let line = line.trim_end().to_string();
        if line.starts_with(NOTICE) {
            if echo {
                say(&line);
            }
            notices.push(line);
            continue;
        }
        if Reply::parse(&line).is_some() {
            return Ok(line);
        }
        return Err(format!("not a reply: {line:?}"));
    }
}

pub fn console(args: &ConsoleArgs, json: bool) -> Result<ConsoleReport, String> {
    if !(args.timeout > 0.0 && args.timeout.is_finite()) {
        return Err(format!(
            "--timeout {} must be a positive number of seconds",
            args.timeout
        ));
    }
    let requests: Box<dyn Iterator<Item = String>> = match &args.script {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| format!("cannot read script {}: {e}", path.display()))?;
            let lines: Vec<String> = text
                .lines()
                .map(str::trim)
                .filter(|l| !l.is_empty() && !l.starts_with('#'))
                .map(String::from)
                .collect();
            Box::new(lines.into_iter())
        }
        None => Box::new(std::io::stdin().lock().lines().map_while(Result::ok)),
    };
    let (reader, mut writer) = connect(args, Duration::from_secs_f64(args.timeout))?;
    let mut reader = BufReader::new(reader);
    let echo = !json;
    let mut report = ConsoleReport {
        notices: Vec::new(),
        exchanges: Vec::new(),
        script: args.script.is_some(),
    };
    for request in requests {
        writer
            .write_all(format!("{request}\n").as_bytes())
            .and_then(|()| writer.flush())
            .map_err(|e| format!("cannot send `{request}`: {e}"))?;
        let line = reply(&mut reader, &mut report.notices, echo)?;
        if echo {
            if report.script {
                say(&format!("> {request}"));
            }
            say(&line);
        }
        let ok = matches!(Reply::parse(&line), Some(Reply::Ok(_)));
        report.exchanges.push(Exchange {
            request,
            reply: line,
            ok,
        });
    }
    Ok(report)
}
