//! The telemetry stream's receiving end: a thread reading the board's stream port (a serial
//! port, a TCP or a Unix socket) into records (`de_resonator::wire::stream::Receiver`), for
//! `console --record` and a firmware-in-the-loop `run --record`.

use std::io::Read;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use de_resonator::wire::stream::{Receiver, Record};

/// Where the stream comes from: a serial port (the board's stream UART), a TCP or a Unix
/// socket (QEMU's chardev, `serve --stream-tcp/--stream-unix`).
#[derive(Clone, Debug)]
pub enum Source {
    Port { device: String, baud: u32 },
    Tcp(String),
    Unix(PathBuf),
}

impl Source {
    /// Where the stream is, as said to the user.
    pub fn describe(&self) -> String {
        match self {
            Source::Port { device, baud } => format!("{device} at {baud} baud"),
            Source::Tcp(address) => format!("tcp:{address}"),
            Source::Unix(path) => format!("unix:{}", path.display()),
        }
    }

    /// Connect to the stream (reads time out after 50 ms: a quiet stream).
    pub fn open(&self) -> Result<Box<dyn Read + Send>, String> {
        let quiet = Some(READ_TIMEOUT);
        match self {
            Source::Tcp(address) => {
                let s = std::net::TcpStream::connect(address)
                    .map_err(|e| format!("cannot connect to the stream at {address}: {e}"))?;
                s.set_read_timeout(quiet).map_err(|e| e.to_string())?;
                Ok(Box::new(s))
            }
            Source::Unix(path) => {
                let s = std::os::unix::net::UnixStream::connect(path).map_err(|e| {
                    format!("cannot connect to the stream at {}: {e}", path.display())
                })?;
                s.set_read_timeout(quiet).map_err(|e| e.to_string())?;
                Ok(Box::new(s))
            }
            Source::Port { device, baud } => serialport::new(device, *baud)
                .timeout(READ_TIMEOUT)
                .open()
                .map(|p| Box::new(p) as Box<dyn Read + Send>)
                .map_err(|e| format!("cannot open the stream's serial port {device}: {e}")),
        }
    }
}

/// How long a read waits before the reader looks whether it should stop.
const READ_TIMEOUT: Duration = Duration::from_millis(50);

/// A recording under way: a thread reading the stream into records.
pub struct Recorder {
    stop: Arc<AtomicBool>,
    reader: JoinHandle<Result<(Vec<Record>, Receiver), String>>,
}

impl Recorder {
    /// Connect to the stream and read it until `finish`.
    pub fn start(source: &Source) -> Result<Self, String> {
        let port = source.open()?;
        let stop = Arc::new(AtomicBool::new(false));
        let stopping = stop.clone();
        let reader = std::thread::spawn(move || {
            let mut records = Vec::new();
            let receiver = read(port, &stopping, |new, _| records.extend_from_slice(new))?;
            Ok((records, receiver))
        });
        Ok(Recorder { stop, reader })
    }

    /// Stop reading (after what is in flight: `linger`); the records and the receiver's counts.
    pub fn finish(self, linger: Duration) -> Result<(Vec<Record>, Receiver), String> {
        std::thread::sleep(linger);
        self.stop.store(true, Ordering::Relaxed);
        self.reader
            .join()
            .map_err(|_| "the stream's reader stopped unexpectedly".to_string())?
    }
}

/// Read records from `port` until `stop` (or the stream's end): `take` gets each read's new
/// records (none when the stream was quiet for a read's timeout) and the receiver's counts.
pub fn read(
    mut port: Box<dyn Read + Send>,
    stop: &AtomicBool,
    mut take: impl FnMut(&[Record], &Receiver),
) -> Result<Receiver, String> {
    let mut receiver = Receiver::default();
    let mut new = Vec::new();
    let mut buf = [0u8; 4096];
    while !stop.load(Ordering::Relaxed) {
        let n = match port.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::TimedOut
                        | std::io::ErrorKind::Interrupted
                ) =>
            {
                0
            }
            Err(e) => return Err(format!("the stream's connection failed: {e}")),
        };
        new.clear();
        for &b in &buf[..n] {
            if let Some(Ok(record)) = receiver.push(b) {
                new.push(record);
            }
        }
        take(&new, &receiver);
    }
    Ok(receiver)
}
