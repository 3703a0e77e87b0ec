//! A client of the board's command port (the core's `protocol`): where it is (a serial port,
//! a TCP or a Unix socket), a reader thread taking every line the board sends, and one
//! request at a time answered by its reply. `console` and `dash` talk to the board through it.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::PathBuf;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::time::Duration;

use clap::Args;
use de_resonator::wire::protocol::NOTICE;
use de_resonator::wire::reply::Reply;
use serde_json::{Map, Value};

use crate::telemetry::Source;

/// Where the board's command port is: exactly one of a serial port, a TCP or a Unix socket.
#[derive(Args, Debug, Clone)]
#[command(group(clap::ArgGroup::new("connection").required(true).args(["port", "tcp", "unix"])))]
pub struct PortArgs {
    /// A serial port (a board's USART2 through a USB adapter), e.g.
    ///
    /// /dev/ttyUSB0.
    #[arg(long, value_name = "DEVICE")]
    pub port: Option<String>,
    /// A TCP socket, HOST:PORT (QEMU's `-chardev socket,host=…,port=…,server=on`, `serve
    /// --tcp`).
    #[arg(long, value_name = "HOST:PORT")]
    pub tcp: Option<String>,
    /// A Unix socket (QEMU's `-chardev socket,path=…,server=on`, `serve --unix`).
    #[arg(long, value_name = "PATH")]
    pub unix: Option<PathBuf>,
    /// The serial port's baud rate.
    #[arg(long, value_name = "BAUD", default_value_t = 115_200)]
    pub baud: u32,
    /// How long to wait for a reply, s.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 10.0,
        allow_negative_numbers = true
    )]
    pub timeout: f64,
}

impl PortArgs {
    /// Where the port is, as said to the user.
    pub fn describe(&self) -> String {
        match (&self.tcp, &self.unix, &self.port) {
            (Some(address), _, _) => format!("tcp:{address}"),
            (_, Some(path), _) => format!("unix:{}", path.display()),
            (_, _, Some(port)) => format!("{port} at {} baud", self.baud),
            _ => "nothing".into(),
        }
    }
}

/// Where the board's telemetry stream is: at most one of a serial port, a TCP or a Unix
/// socket.
#[derive(Args, Debug, Clone)]
#[command(group(clap::ArgGroup::new("stream_source").multiple(false)))]
pub struct StreamArgs {
    /// The stream's serial port (the board's stream UART), e.g. /dev/ttyUSB1.
    #[arg(long, value_name = "DEVICE", group = "stream_source")]
    pub stream_port: Option<String>,
    /// The stream on a TCP socket (`serve --stream-tcp`, QEMU's chardev), HOST:PORT.
    #[arg(long, value_name = "HOST:PORT", group = "stream_source")]
    pub stream_tcp: Option<String>,
    /// The stream on a Unix socket (`serve --stream-unix`, `scripts/qemu.sh`'s
    /// target/qemu/fw-stream.sock).
    #[arg(long, value_name = "PATH", group = "stream_source")]
    pub stream_unix: Option<PathBuf>,
    /// The stream's serial port's baud rate.
    #[arg(long, value_name = "BAUD", default_value_t = 2_000_000)]
    pub stream_baud: u32,
}

impl StreamArgs {
    /// The stream's source, if one was given.
    pub fn source(&self) -> Option<Source> {
        match (&self.stream_port, &self.stream_tcp, &self.stream_unix) {
            (Some(device), _, _) => Some(Source::Port {
                device: device.clone(),
                baud: self.stream_baud,
            }),
            (_, Some(address), _) => Some(Source::Tcp(address.clone())),
            (_, _, Some(path)) => Some(Source::Unix(path.clone())),
            _ => None,
        }
    }
}

/// The fields of a reply line: `ok`'s pairs (numbers as numbers), `err`'s code and message.
pub fn fields(line: &str) -> Map<String, Value> {
    let mut map = Map::new();
    match Reply::parse(line) {
        Some(reply @ Reply::Ok(_)) => {
            for (key, value) in reply.pairs() {
                let value = match value.parse::<f64>() {
                    Ok(n) if n.is_finite() => Value::from(n),
                    _ => Value::from(value),
                };
                map.insert(key.into(), value);
            }
        }
        Some(Reply::Err { code, message }) => {
            map.insert("code".into(), Value::from(code as u8));
            map.insert("message".into(), Value::from(message));
        }
        None => {}
    }
    map
}

/// A connection's writing half.
pub trait Port: Read + Write + Send {}
impl<T: Read + Write + Send> Port for T {}

/// A connection: its reading half and its writing half.
pub type Halves = (Box<dyn Read + Send>, Box<dyn Port>);

/// Open the connection asked for: a reader (reads time out after `timeout`, a quiet line)
/// and a writer on it.
pub fn connect(args: &PortArgs, timeout: Duration) -> Result<Halves, String> {
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

/// What the reader thread hands the requests: a reply line, or the end of the connection.
pub enum Heard {
    Reply(String),
    NotAReply(String),
    Closed(String),
}

/// Read every line the board sends on a thread: what it says on its own (`# …`: the start-up
/// line, a reset, a fault) to `notice` as it arrives, the rest handed on.
pub fn listen(
    reader: Box<dyn Read + Send>,
    notice: impl Fn(String) + Send + 'static,
) -> Receiver<Heard> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut reader = BufReader::new(reader);
        // Kept across read timeouts: a line that arrives in pieces is read whole.
        let mut line = String::new();
        loop {
            let heard = match reader.read_line(&mut line) {
                Ok(0) => Heard::Closed("the board closed the connection".into()),
                Ok(_) if !line.ends_with('\n') => continue,
                Ok(_) => {
                    let whole = std::mem::take(&mut line);
                    let line = whole.trim_end().to_string();
                    if line.starts_with(NOTICE) {
                        notice(line);
                        continue;
                    }
                    if Reply::parse(&line).is_some() {
                        Heard::Reply(line)
                    } else {
                        Heard::NotAReply(line)
                    }
                }
                // A read timeout is only a quiet line: keep listening.
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    continue
                }
                Err(e) => Heard::Closed(format!("the connection failed: {e}")),
            };
            let closed = matches!(heard, Heard::Closed(_));
            if tx.send(heard).is_err() || closed {
                return;
            }
        }
    });
    rx
}

/// A connected client: the writer, the reader thread's lines, the replies' timeout.
pub struct Session {
    pub writer: Box<dyn Port>,
    pub heard: Receiver<Heard>,
    pub timeout: Duration,
    /// A request went unanswered in time: its reply may still come, and must not be taken
    /// for the next one's.
    late: bool,
}

/// How long a port must stay quiet, after a reply came late, before the next request.
const QUIET: Duration = Duration::from_millis(300);

impl Session {
    /// Connect to the port and listen on it, notices to `notice`.
    pub fn open(args: &PortArgs, notice: impl Fn(String) + Send + 'static) -> Result<Self, String> {
        if !(args.timeout > 0.0 && args.timeout.is_finite()) {
            return Err(format!(
                "--timeout {} must be a positive number of seconds",
                args.timeout
            ));
        }
        let (reader, writer) = connect(args, Duration::from_millis(200))?;
        Ok(Session {
            writer,
            heard: listen(reader, notice),
            timeout: Duration::from_secs_f64(args.timeout),
            late: false,
        })
    }

    /// Send one request and wait for its reply; `Err` when the board went away or is silent.
    pub fn ask(&mut self, request: &str) -> Result<String, String> {
        // A connection the board closed is said as such, not as the write's error; a reply
        // that came after its request's time ran out is dropped, not taken for this one's.
        while let Ok(heard) = self.heard.try_recv() {
            if let Heard::Closed(why) = heard {
                return Err(why);
            }
        }
        // After a reply came late: wait for the port to be quiet (the late reply dropped).
        if self.late {
            loop {
                match self.heard.recv_timeout(QUIET) {
                    Ok(Heard::Closed(why)) => return Err(why),
                    Ok(_) => continue,
                    Err(RecvTimeoutError::Timeout) => break,
                    Err(RecvTimeoutError::Disconnected) => {
                        return Err("the board closed the connection".into())
                    }
                }
            }
            self.late = false;
        }
        self.writer
            .write_all(format!("{request}\n").as_bytes())
            .and_then(|()| self.writer.flush())
            .map_err(|e| match e.kind() {
                std::io::ErrorKind::BrokenPipe | std::io::ErrorKind::ConnectionReset => {
                    "the board closed the connection".to_string()
                }
                _ => format!("cannot send `{request}`: {e}"),
            })?;
        match self.heard.recv_timeout(self.timeout) {
            Ok(Heard::Reply(line)) => Ok(line),
            Ok(Heard::NotAReply(line)) => {
                self.late = true;
                Err(format!("not a reply: {line:?}"))
            }
            Ok(Heard::Closed(why)) => Err(why),
            Err(RecvTimeoutError::Timeout) => {
                self.late = true;
                Err(format!(
                    "no reply to `{}` in {} s",
                    request.escape_debug(),
                    self.timeout.as_secs_f64()
                ))
            }
            Err(RecvTimeoutError::Disconnected) => Err("the board closed the connection".into()),
        }
    }
}

/// What a client sends first for a clean line: a byte no request may hold, then a line end.
/// Whatever an earlier connection left half sent is refused with it (`err 1 … not printable`),
/// never run: a half `start` must not switch the output on.
const CLEAN_LINE: &str = "\u{0}";

impl Session {
    /// Start from a clean line. A board's port is one line buffer whoever writes to it (a
    /// UART, QEMU's socket): a line half sent by an earlier connection would be glued to this
    /// one's first request. A byte no request holds and a line end refuse whatever is there
    /// (the board's reply read and dropped). `Err` when the board says nothing: under QEMU the
    /// port serves one connection at a time, and another is connected.
    pub fn clean_line(&mut self) -> Result<(), String> {
        match self.ask(CLEAN_LINE) {
            // The line refused, as it must be (a NUL is in no request).
            Ok(reply) if matches!(Reply::parse(&reply), Some(Reply::Err { code, .. }) if code as u8 == 1) => {
                Ok(())
            }
            // Never expected: the NUL was lost on the way and a half line ran.
            Ok(reply) => Err(format!(
                "the board ran a line left half sent on its port before this connection: \
                 `{reply}` (check the board: `status`)"
            )),
            Err(why) if why.starts_with("no reply") => Err(format!(
                "no reply in {} s: the board's port says nothing. Under QEMU it serves one \
                 connection at a time (is another console or dash connected?); on a board, \
                 check the port and its baud rate",
                self.timeout.as_secs_f64()
            )),
            Err(why) => Err(why),
        }
    }
}

/// Whether an error means the board went away (the session ends, said as such).
pub fn gone(why: &str) -> bool {
    why.starts_with("the board closed") || why.starts_with("the connection failed")
}

/// Who may change the board when `serve` has several connections, said once for both
/// sides: `serve` says these lines, a client (`dash`) reads them back. The oldest
/// connection controls; the others read, and any of them may `stop` the board (an
/// emergency stop, told to the one that controls). A board's one port has no such lines.
pub mod control {
    use de_resonator::wire::protocol::{ErrorCode, NOTICE};

    /// What the connection that now controls the board is told.
    pub const NOW_CONTROLS: &str = "# this connection now controls the board";
    /// How the line to a connection that only reads begins.
    const READS: &str = "# another connection controls the board (";
    /// What a connection that reads may ask.
    const MAY: &str = "this one reads (status, info, get, help, faults) and may `stop` the \
                       board; it takes over when that one leaves";

    /// The line a connection that reads hears as it connects.
    pub fn reads_only(controller: &str) -> String {
        format!("{READS}{controller}): {MAY}")
    }

    /// The reply to a request that would change the board, from a connection that reads.
    pub fn not_in_control(controller: &str) -> String {
        format!(
            "err {} another connection controls the board ({controller}): {MAY}",
            ErrorCode::NotInControl
        )
    }

    /// What the controlling connection is told of a `stop` another connection gave.
    pub fn stopped_by(who: &str, reply: &str) -> String {
        format!(
            "{NOTICE}stop from another connection ({who}): {}",
            reply.trim_start_matches("ok stop: ")
        )
    }

    /// Who controls the board, as a line of `serve`'s says it: `Some(None)` this connection,
    /// `Some(Some(who))` another; `None`: the line says nothing of control.
    pub fn of_line(line: &str) -> Option<Option<String>> {
        if line == NOW_CONTROLS {
            return Some(None);
        }
        let not_ours = format!(
            "err {} another connection controls the board (",
            ErrorCode::NotInControl
        );
        let rest = line
            .strip_prefix(READS)
            .or_else(|| line.strip_prefix(not_ours.as_str()))?;
        let who = rest.split_once("): ").map_or(rest, |(who, _)| who);
        Some(Some(who.to_string()))
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn each_line_names_who_controls() {
            let who = "tcp 127.0.0.1:50412";
            assert_eq!(of_line(&reads_only(who)), Some(Some(who.to_string())));
            assert_eq!(of_line(&not_in_control(who)), Some(Some(who.to_string())));
            assert_eq!(of_line(NOW_CONTROLS), Some(None));
            assert_eq!(of_line("# ready phase=holding"), None);
            assert_eq!(of_line("ok stop: at 0 V, the output off"), None);
        }
    }
}
