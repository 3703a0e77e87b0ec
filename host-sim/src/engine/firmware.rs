//! The firmware in the loop: the firmware's link build (`firmware --features link`) under
//! QEMU, its image made from the scene, as the board of a loop (`loop_board::LoopBoard`). Each tick
//! the plant's ADC codes go out and the tick's output comes back, in the core's frames
//! (`de_resonator::wire::link`), through two pipes the firmware opens by semihosting
//! (`samples`, `output`), a byte on its USART3 ring_stretch each tick in; its command port
//! (USART2) is connected. QEMU is stopped when the board is dropped.

use std::fs::File;
use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::fs::OpenOptionsExt;
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use de_resonator::acquire::InputError;
use de_resonator::wire::link::{self, Booted, Kind, Observed, HEADER, MAX_FRAME};
use de_resonator::wire::protocol::NOTICE;
use de_resonator::wire::stream::{Receiver, Record};
use de_resonator::Inputs;

use crate::engine::closed_loop::Wires;
use crate::engine::loop_board::{LoopBoard, Samples};
use crate::telemetry::{Recorder, Source};

/// How long QEMU may take to open a port or a pipe, and the firmware to answer a tick or a
/// command line, before the run stops: QEMU stuck or gone.
const REPLY_TIMEOUT: Duration = Duration::from_secs(10);

/// Boards started by this process (each its own folder).
static STARTED: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// The firmware under QEMU, connected.
pub struct Qemu<'w> {
    child: Child,
    dir: PathBuf,
    /// The bell (USART3), and the frames' pipes.
    bell: UnixStream,
    samples: File,
    /// The firmware's frames, read from the output pipe by a thread of their own.
    output: mpsc::Receiver<Result<Vec<u8>, String>>,
    output_path: PathBuf,
    /// The command port (USART2): its writing end, and its lines read by a thread of their
    /// own from the start (QEMU's UART writes a byte at a time, and the socket holds a few
    /// hundred such writes: a start-up line left unread that long would stop QEMU).
    command: UnixStream,
    lines: mpsc::Receiver<Result<String, String>>,
    frame: Vec<u8>,
    booted: (Booted, Option<String>),
    wires: &'w Wires,
    /// The telemetry stream's reader (USART1), until `records` takes it.
    recorder: Option<Recorder>,
}

impl<'w> Qemu<'w> {
    /// Start `elf` under QEMU (`QEMU_BIN`, default `qemu-system-arm`) with `image` flashed,
    /// connect both ports, and read its boot. Its files go in a fresh folder under `work`.
    pub fn start(elf: &Path, image: &[u8], work: &Path, wires: &'w Wires) -> Result<Self, String> {
        if !elf.is_file() {
            return Err(format!(
                "--firmware {}: no such file (build it: cd firmware && cargo build --release \
                 --no-default-features --features qemu,log-semihosting,link)",
                elf.display()
            ));
        }
        let n = STARTED.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = work.join(format!("host-sim-qemu-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        // Removed again if the start fails half way (with QEMU).
        let mut child = Killed(None, dir.clone());
        let image_path = dir.join("image.bin");
        std::fs::write(&image_path, image).map_err(|e| format!("{}: {e}", image_path.display()))?;
        let (command_path, link_path) = (dir.join("cmd.sock"), dir.join("link.sock"));
        let stream_path = dir.join("stream.sock");
        let (samples_path, output_path) = (dir.join("samples"), dir.join("output"));
        for p in [
            &command_path,
            &link_path,
            &stream_path,
            &samples_path,
            &output_path,
        ] {
            let _ = std::fs::remove_file(p);
        }
        for p in [&samples_path, &output_path] {
            mkfifo(p)?;
        }
        let log = std::fs::File::create(dir.join("qemu.log"))
            .map_err(|e| format!("{}: {e}", dir.display()))?;
        let qemu = std::env::var("QEMU_BIN").unwrap_or_else(|_| "qemu-system-arm".into());
        let spawned = Command::new(&qemu)
            .args(["-M", "netduinoplus2", "-nographic", "-monitor", "none"])
            .arg("-chardev")
            .arg(format!(
                "socket,id=stream,path={},server=on,wait=off",
                stream_path.display()
            ))
            .arg("-chardev")
            .arg(format!(
                "socket,id=cmd,path={},server=on,wait=on",
                command_path.display()
            ))
            .arg("-chardev")
            .arg(format!(
                "socket,id=link,path={},server=on,wait=on",
                link_path.display()
            ))
            .args([
                "-serial",
                "chardev:stream",
                "-serial",
                "chardev:cmd",
                "-serial",
                "chardev:link",
            ])
            .args([
                "-semihosting-config",
                "enable=on,target=native,arg=firmware,arg=busy-idle",
            ])
            .arg("-device")
            .arg(format!(
                "loader,file={},addr=0x080E0000",
                image_path.display()
            ))
            .arg("-kernel")
            .arg(
                elf.canonicalize()
                    .map_err(|e| format!("{}: {e}", elf.display()))?,
            )
            // The firmware's semihosting opens its pipes here.
            .current_dir(&dir)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .map_err(|e| format!("cannot start {qemu}: {e} (install qemu-system-arm)"))?;
        child.0 = Some(spawned);
        // QEMU waits on the command socket first, then the link's.
        let command = connect_later(&command_path, &mut child)?;
        let lines = read_lines(
            command
                .try_clone()
                .map_err(|e| format!("the command port: {e}"))?,
        );
        let bell = connect_later(&link_path, &mut child)?;
        // The firmware opens `samples` to read, then `output` to write.
        let samples = open_writer(&samples_path, &mut child)?;
        let output = read_frames(output_path.clone());
        // The telemetry stream (USART1): QEMU listens without waiting; read from now on.
        let recorder = Recorder::start(&Source::Unix(stream_path))?;
        child.1 = PathBuf::new();
        let mut qemu = Qemu {
            child: child.0.take().ok_or("QEMU lost")?,
            output_path,
            dir,
            bell,
            samples,
            output,
            command,
            lines,
            frame: vec![0; MAX_FRAME],
            booted: (Booted::of(None), None),
            wires,
            recorder: Some(recorder),
        };
        let (kind, _, payload) = qemu.frame()?;
        if kind != Kind::Boot {
            return Err(format!(
                "the firmware's first frame is {kind:?}, not its boot"
            ));
        }
        let (booted, words) = Booted::read(&payload).map_err(|e| e.to_string())?;
        let refusal = (!booted.driving).then(|| String::from_utf8_lossy(words).into_owned());
        qemu.booted = (booted, refusal);
        Ok(qemu)
    }

    /// The next whole frame from the firmware: its kind, tick and payload.
    fn frame(&mut self) -> Result<(Kind, u32, Vec<u8>), String> {
        let bytes = match self.output.recv_timeout(REPLY_TIMEOUT) {
            Ok(Ok(bytes)) => bytes,
            Ok(Err(why)) => return Err(self.gone(&why)),
            Err(_) => return Err(self.gone("no output in 10 s")),
        };
        let (header, payload) =
            link::parse(&bytes).map_err(|e| format!("from the firmware: {e}"))?;
        Ok((header.kind, header.tick, payload.to_vec()))
    }

    /// Why the run stopped, with QEMU's own words if it exited.
    fn gone(&mut self, why: &str) -> String {
        let log = std::fs::read_to_string(self.dir.join("qemu.log")).unwrap_or_default();
        let status = self.child.try_wait().ok().flatten();
        format!(
            "the firmware under QEMU: {why}{}{}",
            status.map_or(String::new(), |s| format!(" (QEMU exited: {s})")),
            if log.trim().is_empty() {
                String::new()
            } else {
                format!("; QEMU said: {}", log.trim())
            }
        )
    }
}

/// A named pipe at `path` (coreutils' `mkfifo`).
fn mkfifo(path: &Path) -> Result<(), String> {
    let made = Command::new("mkfifo")
        .args(["-m", "600"])
        .arg(path)
        .status()
        .map_err(|e| format!("cannot run mkfifo: {e}"))?;
    if !made.success() {
        return Err(format!("mkfifo {} failed: {made}", path.display()));
    }
    Ok(())
}

/// Our writing end of a pipe the firmware reads, once the firmware has opened it (tried
/// without waiting until then; QEMU gone, or `REPLY_TIMEOUT`, an error).
fn open_writer(path: &Path, child: &mut Killed) -> Result<File, String> {
    let deadline = Instant::now() + REPLY_TIMEOUT;
    loop {
        let probe = std::fs::OpenOptions::new()
            .write(true)
            .custom_flags(libc::O_NONBLOCK)
            .open(path);
        match probe {
            // The reader is there: opened again to block on writes, as a pipe should.
            Ok(_) => {
                return std::fs::OpenOptions::new()
                    .write(true)
                    .open(path)
                    .map_err(|e| format!("cannot open {}: {e}", path.display()))
            }
            Err(e) if e.raw_os_error() == Some(libc::ENXIO) => {
                if let Some(status) = child.0.as_mut().and_then(|c| c.try_wait().ok().flatten()) {
                    return Err(format!(
                        "QEMU exited before the firmware opened its link: {status}"
                    ));
                }
                if Instant::now() > deadline {
                    return Err(format!(
                        "the firmware did not open {} in 10 s: is it the link build \
                         (--features qemu,log-semihosting,link)?",
                        path.display()
                    ));
                }
                std::thread::sleep(Duration::from_millis(2));
            }
            Err(e) => return Err(format!("cannot open {}: {e}", path.display())),
        }
    }
}

/// The firmware's frames from the pipe at `path`, each whole, read by a thread (a read that
/// waits can then be given up: `Qemu::frame`); the pipe's end or an error ends it.
/// The command port's lines, read as they come by a thread of their own (an error, and the
/// end, once the port closes).
fn read_lines(port: UnixStream) -> mpsc::Receiver<Result<String, String>> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        // Blocking: the lines come when they come; the port closes with QEMU.
        if let Err(e) = port.set_read_timeout(None) {
            let _ = tx.send(Err(format!("the command port: {e}")));
            return;
        }
        let mut port = BufReader::new(port);
        loop {
            let mut line = String::new();
            let read = match port.read_line(&mut line) {
                Ok(0) => Err("the command port closed".to_string()),
                Ok(_) => Ok(line),
                Err(e) => Err(format!("the command port: {e}")),
            };
            let failed = read.is_err();
            if tx.send(read).is_err() || failed {
                return;
            }
        }
    });
    rx
}

fn read_frames(path: PathBuf) -> mpsc::Receiver<Result<Vec<u8>, String>> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut pipe = match File::open(&path) {
            Ok(pipe) => pipe,
            Err(e) => {
                let _ = tx.send(Err(format!("cannot open {}: {e}", path.display())));
                return;
            }
        };
        loop {
            let mut bytes = vec![0u8; HEADER];
            let read = pipe
                .read_exact(&mut bytes)
                .map_err(|e| format!("the output pipe: {e}"))
                .and_then(|()| {
                    let end =
                        link::frame_bytes(&bytes).map_err(|e| format!("from the firmware: {e}"))?;
                    bytes.resize(end, 0);
                    pipe.read_exact(&mut bytes[HEADER..])
                        .map_err(|e| format!("the output pipe: {e}"))
                });
            let sent = match read {
                Ok(()) => tx.send(Ok(bytes)),
                Err(e) => {
                    let _ = tx.send(Err(e));
                    return;
                }
            };
            if sent.is_err() {
                return;
            }
        }
    });
    rx
}

/// QEMU and its folder, killed and removed if the start fails half way (an empty path once
/// the board holds the folder).
struct Killed(Option<Child>, PathBuf);

impl Drop for Killed {
    fn drop(&mut self) {
        if let Some(c) = self.0.as_mut() {
            let _ = c.kill();
            let _ = c.wait();
        }
        if !self.1.as_os_str().is_empty() {
            let _ = std::fs::remove_dir_all(&self.1);
        }
    }
}

/// Connect to QEMU's socket at `path` once it exists (QEMU creates it as it starts); QEMU
/// gone first is an error.
fn connect_later(path: &Path, child: &mut Killed) -> Result<UnixStream, String> {
    let deadline = Instant::now() + REPLY_TIMEOUT;
    loop {
        match UnixStream::connect(path) {
            Ok(s) => {
                s.set_read_timeout(Some(Duration::from_millis(200)))
                    .map_err(|e| e.to_string())?;
                return Ok(s);
            }
            Err(e) => {
                if let Some(status) = child.0.as_mut().and_then(|c| c.try_wait().ok().flatten()) {
                    return Err(format!("QEMU exited before its port opened: {status}"));
                }
                if Instant::now() > deadline {
                    return Err(format!("cannot connect to QEMU at {}: {e}", path.display()));
                }
                std::thread::sleep(Duration::from_millis(5));
            }
        }
    }
}

impl Drop for Qemu<'_> {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        // A reader still waiting for the firmware to open its end is let go.
        let _ = std::fs::OpenOptions::new()
            .write(true)
            .custom_flags(libc::O_NONBLOCK)
            .open(&self.output_path);
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

impl LoopBoard for Qemu<'_> {
    fn command(&mut self, line: &str) -> Result<String, String> {
        let sent = self.command.write_all(format!("{line}\n").as_bytes());
        if let Err(e) = sent {
            return Err(self.gone(&format!("the command port: {e}")));
        }
        // The reply: the first line that is not a notice (the start-up lines come first).
        let deadline = Instant::now() + REPLY_TIMEOUT;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(Ok(reply)) if reply.starts_with(NOTICE) => {}
                Ok(Ok(reply)) => return Ok(reply.trim_end().to_string()),
                Ok(Err(why)) => return Err(self.gone(&why)),
                Err(_) => return Err(self.gone(&format!("`{line}` got no reply in 10 s"))),
            }
        }
    }

    fn booted(&mut self) -> (Booted, Option<String>) {
        self.booted.clone()
    }

    fn records(&mut self) -> Result<(Vec<Record>, Receiver), String> {
        // The last tick's record leaves the firmware's idle loop after its output frame.
        let recorder = self.recorder.take().ok_or("the stream was read already")?;
        recorder.finish(Duration::from_millis(200))
    }

    fn tick(
        &mut self,
        k: u64,
        _: Result<Inputs, InputError>,
        samples: Samples,
        codes: &[u16],
    ) -> Result<(Observed, String), String> {
        let codes = match samples {
            Samples::Codes { .. } => codes,
            Samples::Direct(inputs) if inputs == Inputs::NONE => &[],
            Samples::Direct(_) => {
                return Err("the scene reads its sensors directly ([sensor], \
                            [current_monitor]): give it a [front_end] to run it through the \
                            firmware's ADC"
                    .into())
            }
        };
        let tick = k as u32;
        // The scene's broken bus (the core's board's simulated DAC fails from then on).
        let mut flags = if self.wires.bus.fail_after.get().is_some() {
            link::BUS_FAILS
        } else {
            0
        };
        // The scene's stall, re-armed before this tick (its codes are not in the frame).
        if let Samples::Codes { stall: Some(why) } = samples {
            flags |= link::stall_flag(why);
        }
        let n = link::write_frame(&mut self.frame, (Kind::Samples, flags), tick, |p| {
            link::write_codes(codes, p)
        })
        .map_err(|e| format!("tick {k}: {e}"))?;
        let sent = self
            .samples
            .write_all(&self.frame[..n])
            .and_then(|()| self.bell.write_all(b"!"));
        if let Err(e) = sent {
            return Err(self.gone(&e.to_string()));
        }
        let (kind, at, payload) = self.frame().map_err(|e| format!("tick {k}: {e}"))?;
        if kind != Kind::Output || u64::from(at) != k {
            return Err(format!(
                "tick {k}: the firmware sent {kind:?} for tick {at}, not this tick's output"
            ));
        }
        let (seen, words) = Observed::read(&payload).map_err(|e| format!("tick {k}: {e}"))?;
        self.wires.bus.show(seen.dac_code, seen.dac_on);
        self.wires.enable.high.set(seen.enable);
        Ok((seen, String::from_utf8_lossy(words).into_owned()))
    }
}
