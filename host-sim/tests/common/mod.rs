//! A virtual board for the tests: `host-sim serve` started on a scene, stopped when dropped.
#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

pub fn host_sim() -> Command {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
}

/// A scratch directory of this test process.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("host-sim-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `host-sim serve` running; killed when dropped.
pub struct Served {
    child: Child,
    /// `--unix PATH` or `--tcp HOST:PORT`, as `console` takes it.
    pub connection: [String; 2],
    /// The telemetry stream's Unix socket, when it serves one.
    pub stream: Option<String>,
}

impl Served {
    /// Serve `scene` (`None`: the reference scene) at `speed` on a Unix socket named `name`,
    /// or on TCP (`name` = `tcp`, a port the system picks).
    pub fn start(scene: Option<&str>, speed: &str, name: &str) -> Self {
        Self::serve(scene, speed, name, false, &[])
    }

    /// As `start` (on a Unix socket), with the telemetry stream on a second one.
    pub fn streaming(scene: Option<&str>, speed: &str, name: &str) -> Self {
        Self::serve(scene, speed, name, true, &[])
    }

    /// As `start`, with more of serve's arguments.
    pub fn with(scene: Option<&str>, speed: &str, name: &str, args: &[&str]) -> Self {
        Self::serve(scene, speed, name, false, args)
    }

    fn serve(scene: Option<&str>, speed: &str, name: &str, streaming: bool, args: &[&str]) -> Self {
        let mut command = host_sim();
        command.arg("serve");
        if let Some(scene) = scene {
            command.arg(scene);
        }
        command.args(args);
        let socket = scratch("serve").join(format!("{name}.sock"));
        let socket = socket.to_str().unwrap().to_string();
        let tcp = name == "tcp";
        if tcp {
            command.args(["--tcp", "127.0.0.1:0"]);
        } else {
            command.args(["--unix", &socket]);
        }
        let stream = streaming.then(|| {
            let path = scratch("serve").join(format!("{name}-stream.sock"));
            path.to_str().unwrap().to_string()
        });
        if let Some(path) = &stream {
            command.args(["--stream-unix", path]);
        }
        // A bound: a test that dies leaves no board running for long.
        command.args(["--speed", speed, "--seconds", "3000"]);
        let mut child = command
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("host-sim serve starts");
        // Its first line says where it serves (after the stream's, if it has one).
        let mut stderr = BufReader::new(child.stderr.take().unwrap());
        let mut first = String::new();
        stderr.read_line(&mut first).unwrap();
        if stream.is_some() {
            assert!(first.contains("telemetry stream"), "{first:?}");
            first.clear();
            stderr.read_line(&mut first).unwrap();
        }
        let at = first
            .split(" on ")
            .nth(1)
            .and_then(|rest| rest.split(" at ").next())
            .unwrap_or_else(|| panic!("serve's first line: {first:?}"))
            .to_string();
        // The rest of stderr drained, so the board never blocks on it.
        std::thread::spawn(move || for _ in stderr.lines() {});
        let connection = if tcp {
            [
                "--tcp".to_string(),
                at.trim_start_matches("tcp ").to_string(),
            ]
        } else {
            ["--unix".to_string(), socket]
        };
        Self {
            child,
            connection,
            stream,
        }
    }

    /// Stop the board now (a board that goes away under a console).
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// `console --script` (text) with the script `text`, saved as `name`.
    pub fn script(&self, name: &str, text: &str) -> std::process::Output {
        let script = scratch("serve").join(format!("{name}.txt"));
        std::fs::write(&script, text).unwrap();
        host_sim()
            .arg("console")
            .args(&self.connection)
            .args(["--script", script.to_str().unwrap()])
            .output()
            .unwrap()
    }

    /// `console --json --script` with `requests`: its report, and whether it exited 0.
    pub fn console(&self, requests: &[&str]) -> (Value, bool) {
        let script = scratch("serve").join(format!(
            "script-{}.txt",
            SCRIPTS.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
        ));
        std::fs::write(&script, requests.join("\n")).unwrap();
        let out = host_sim()
            .args(["--json", "console"])
            .args(&self.connection)
            .args(["--script", script.to_str().unwrap()])
            .output()
            .unwrap();
        let report: Value = serde_json::from_slice(&out.stdout)
            .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&out.stderr)));
        (report, out.status.success())
    }

    /// The replies to `requests`, in order.
    pub fn replies(&self, requests: &[&str]) -> Vec<String> {
        let (report, _) = self.console(requests);
        report["exchanges"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| e["reply"].as_str().unwrap().to_string())
            .collect()
    }

    /// `status` until `done` holds of its reply (at most 60 s of wall time).
    pub fn wait_for(&self, what: &str, done: impl Fn(&str) -> bool) -> String {
        let end = Instant::now() + Duration::from_secs(60);
        loop {
            let status = self.replies(&["status"]).remove(0);
            if done(&status) {
                return status;
            }
            assert!(Instant::now() < end, "never {what}: {status}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

static SCRIPTS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A `key=value` field of a reply or notice.
pub fn field<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    line.split(' ')
        .find_map(|word| word.strip_prefix(key)?.strip_prefix('='))
}

/// A field as a number.
pub fn number(line: &str, key: &str) -> f64 {
    field(line, key)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no {key} in {line}"))
}

/// The voltage a reply ends with (`… ramp to 7449.878 V`).
pub fn last_volts(reply: &str) -> f64 {
    reply
        .trim_end_matches(')')
        .trim_end_matches(" V")
        .rsplit(' ')
        .next()
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no volts at the end of {reply}"))
}

/// The random scene tests' draws: a 64-bit LCG (Knuth's MMIX constants), uniform in a range.
pub struct Uniform(pub u64);

impl Uniform {
    pub fn draw(&mut self, low: f64, high: f64) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        low + (high - low) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// A random device the scenes' board can trim, with its natural frequencies at no bias and
/// at its top under a 5% margin (Hz), or `None` where it is not one: μ 20–150 kPa, a Gent
/// `jlim` of 40–150 (a share `gent_share` of the time, else neo-Hookean; `None`: always),
/// λ1p from `prestretch_1_low` to 4, the rest of a bench device's sizes; both frequencies a
/// ring the 1 kHz tick and the 0.5 s window can time (20–100 Hz), the top's bias within the
/// scenes' 10 kV amplifier (9 kV).
pub fn tunable_device(
    u: &mut Uniform,
    gent_share: Option<f64>,
    prestretch_1_low: f64,
) -> Option<(de_resonator::DeviceParams<f64>, f64, f64)> {
    use de_resonator::{Device, DeviceParams, Tuner, REFERENCE_DEVICE};
    let params = DeviceParams {
        shear_modulus: u.draw(20e3, 150e3),
        jlim: match gent_share {
            None => Some(u.draw(40.0, 150.0)),
            Some(share) => (u.draw(0.0, 1.0) < share).then(|| u.draw(40.0, 150.0)),
        },
        thickness: u.draw(0.5e-3, 2e-3),
        length_active: u.draw(10e-3, 40e-3),
        length_passive: u.draw(10e-3, 60e-3),
        width: u.draw(20e-3, 60e-3),
        bar_mass: u.draw(0.5e-3, 5e-3),
        prestretch_1: u.draw(prestretch_1_low, 4.0),
        prestretch_2: u.draw(1.0, 3.5),
        ..REFERENCE_DEVICE
    };
    let tuner = Tuner::new(Device::new(params).ok()?);
    let (top, at_zero) = (tuner.max_bias(0.05).ok()?, tuner.zero_bias());
    let (f0, f1) = (at_zero.natural_frequency_hz, top.natural_frequency_hz);
    let timed = (20.0..100.0).contains(&f0) && (20.0..100.0).contains(&f1);
    (timed && top.volts <= 9000.0).then_some((params, f0, f1))
}

/// The start of a reply refused with `code` (`err <n> `): the tests name codes, not numbers.
pub fn refused_with(code: de_resonator::wire::protocol::ErrorCode) -> String {
    format!("err {code} ")
}
