//! host-sim: workstation tools for de-resonator, on the same `no_std` core the firmware runs.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use de_resonator::{Device, DeviceParams, Tuner, DEFAULT_MARGIN, REFERENCE_DEVICE};
use host_sim::simulate::{self, Choice, Scene, Start};
use host_sim::{device_file, lut, report, stress, sweep};

/// Safe region, bias tuning and dynamics of a dielectric elastomer resonator.
///
/// A static bias voltage sets the resonator's natural frequency; too much voltage and the
/// membrane fails. `run` runs a scene: the firmware's controller tunes and drives a full
/// simulation of the plant. `safe` shows where the loading branch fails first and the
/// frequencies reachable before it; `tune` finds the bias for a target frequency; `simulate`
/// integrates the motion under a drive and reports any dynamic crossing of a limit. Without
/// a command, `run` runs the built-in reference scene (scenes/reference.toml).
///
/// Exit status: 0 on success; 1 when a run failed (a scene's plant left its safe region, a
/// stress run failed silently); 2 when the target cannot be reached, the device, a scene or
/// a setting is invalid, or a step is unstable (one line on stderr says why, nothing on
/// stdout).
#[derive(Parser, Debug)]
#[command(name = "host-sim", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a scene: the firmware's controller (the core's, unchanged) tunes and drives the
    /// full plant simulator through its DAC driver, reading the simulated sensor; host-sim
    /// checks the true plant against MODEL.md §6 at every tick. Prints a short report and
    /// writes what the scene asks for (a plot, the time history) into --out/<scene name>.
    /// Without a scene: the built-in reference scene (scenes/reference.toml).
    Run {
        /// Scene file (TOML; see scenes/ and the README).
        scene: Option<PathBuf>,
        /// Folder for the scene's files (a subfolder per scene).
        #[arg(long, value_name = "DIR", default_value = "out/run")]
        out: PathBuf,
        /// Print one JSON object on stdout instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Show the safe region: f at zero bias, the first failure on the loading branch
    /// (mode, volts, stretch, f there) and the tunable range within the margin.
    Safe {
        #[command(flatten)]
        common: Common,
    },
    /// Find the smallest bias (volts) that sets the natural frequency to a target,
    /// at most (1 − margin) times the limit voltage.
    Tune {
        /// Target natural frequency, Hz.
        #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
        target_hz: f64,
        #[command(flatten)]
        common: Common,
    },
    /// Integrate the motion from rest under Φ(t) = bias + ac·sin(2π·f·t), watched by the
    /// dynamic safety monitor (the six checks of MODEL.md §6 at every step).
    Simulate {
        /// Static bias, V.
        #[arg(long, value_name = "V", allow_negative_numbers = true)]
        bias_volts: f64,
        /// AC amplitude, V.
        #[arg(
            long,
            value_name = "A",
            default_value_t = 0.0,
            allow_negative_numbers = true
        )]
        ac_volts: f64,
        /// AC drive frequency, Hz.
        #[arg(long, value_name = "F", default_value_t = 0.0)]
        drive_hz: f64,
        /// Viscous damping c, N·s (overrides the device's).
        #[arg(long, value_name = "C")]
        damping: Option<f64>,
        /// Simulated time, s.
        #[arg(long, value_name = "S", allow_negative_numbers = true)]
        duration: f64,
        /// Start at rest at the bias's equilibrium, or at the pre-stretch with the voltage
        /// switched on at t = 0.
        #[arg(long, value_enum, default_value_t = Start::Equilibrium)]
        start: Start,
        /// `reference` (adaptive DOP853, rtol = atol = 1e-12, f64) or a core fixed-step
        /// method: rk4, verlet, implicit-midpoint, each with -f32 (as on the target) or -f64.
        #[arg(long, value_name = "M", default_value = "reference")]
        method: String,
        /// Step, s (the reference's output spacing). Default: 1/64 of the small-oscillation
        /// period at zero bias.
        #[arg(long, value_name = "H", allow_negative_numbers = true)]
        step: Option<f64>,
        #[arg(long, value_name = "FILE")]
        /// Device file (as for `safe`).
        device: Option<PathBuf>,
        /// Print one JSON object on stdout instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Run the stiff and extreme cases (near the EMI limit, passive membrane near slack,
    /// Gent lock-up, a very light bar, a large AC amplitude, a fast voltage step) with every
    /// core method in f32 and f64 at several steps, against the reference. Each run is
    /// `stable`, `refused` (by the guard), `stopped` (a typed error), or `failed_silently`,
    /// which must never happen: exit status 1 if any run did.
    Stress {
        /// Device the cases are built on (as for `safe`). Default: the reference device.
        #[arg(long, value_name = "FILE")]
        device: Option<PathBuf>,
        /// Print one JSON object on stdout instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Write the tuning table the firmware flashes: bias against natural frequency from zero
    /// bias to (1 − margin)·limit, evenly spaced in bias², with the device parameters, the
    /// margin, the measured interpolation error and a CRC-32 (layout: the core's `table`
    /// module, README). Prints the interpolation error against the direct solve.
    Lut {
        /// Output file.
        #[arg(long, value_name = "FILE")]
        out: PathBuf,
        /// Number of points (2 to 1024). Default: the fewest of 64, 128, … 1024 that
        /// interpolate within 1e-5 in frequency.
        #[arg(long, value_name = "N")]
        points: Option<usize>,
        /// `bin` (for flashing) or `csv` (for people).
        #[arg(long, value_enum, default_value_t = LutFormat::Bin)]
        format: LutFormat,
        #[command(flatten)]
        common: Common,
    },
    /// Error against run time (a work-precision study): every core method in f32 and f64 at
    /// 8 to 512 steps a period against the reference (DOP853, 1e-12), on three scenes (a small
    /// oscillation about a tuned bias, a large parametric drive, a bias near the limit).
    /// Writes work-precision.csv and work-precision.svg (log-log) into --out; prints a table.
    Report {
        /// Folder for the CSV and the plot (created if needed).
        #[arg(long, value_name = "DIR", default_value = "out/report")]
        out: PathBuf,
        /// Device file (as for `safe`).
        #[arg(long, value_name = "FILE")]
        device: Option<PathBuf>,
        /// Print one JSON object on stdout instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Frequency response under parametric drive Φ = bias + ac·sin(2π·f·t) (MODEL.md §7):
    /// one run from rest per drive frequency, the amplitude once settled, and the peaks
    /// (expected near f0/2, f0 and 2·f0, f0 the small-oscillation frequency at the bias).
    /// Writes sweep.csv and sweep.svg into --out.
    Sweep {
        /// Static bias, V.
        #[arg(
            long,
            value_name = "V",
            default_value_t = 6000.0,
            allow_negative_numbers = true
        )]
        bias_volts: f64,
        /// AC amplitude, V.
        #[arg(
            long,
            value_name = "A",
            default_value_t = 2000.0,
            allow_negative_numbers = true
        )]
        ac_volts: f64,
        /// Quality factor Q of the small oscillation at the bias: sets the damping
        /// c = M·ω0/Q (M the effective mass of MODEL.md §4). 0 keeps the device's damping.
        #[arg(
            long,
            value_name = "Q",
            default_value_t = 200.0,
            allow_negative_numbers = true
        )]
        quality: f64,
        /// Lowest drive frequency, as a multiple of f0.
        #[arg(
            long,
            value_name = "R",
            default_value_t = 0.3,
            allow_negative_numbers = true
        )]
        from_ratio: f64,
        /// Highest drive frequency, as a multiple of f0.
        #[arg(
            long,
            value_name = "R",
            default_value_t = 2.4,
            allow_negative_numbers = true
        )]
        to_ratio: f64,
        /// Drive frequencies, evenly spaced.
        #[arg(long, value_name = "N", default_value_t = 211)]
        points: usize,
        /// Run length per drive frequency, in periods of f0 (the last quarter is measured).
        #[arg(
            long,
            value_name = "N",
            default_value_t = 400.0,
            allow_negative_numbers = true
        )]
        periods: f64,
        /// RK4 steps (f64) per period of the faster of the drive and f0.
        #[arg(
            long,
            value_name = "N",
            default_value_t = 48.0,
            allow_negative_numbers = true
        )]
        steps_per_period: f64,
        /// Folder for sweep.csv and sweep.svg (created if needed).
        #[arg(long, value_name = "DIR", default_value = "out/sweep")]
        out: PathBuf,
        /// Device file (as for `safe`).
        #[arg(long, value_name = "FILE")]
        device: Option<PathBuf>,
        /// Print one JSON object on stdout instead of text.
        #[arg(long)]
        json: bool,
    },
}

/// How `lut` writes the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum LutFormat {
    Bin,
    Csv,
}

#[derive(Args, Debug)]
struct Common {
    /// Device file (TOML, SI units, flat keys; absent keys take the reference device's
    /// values, an absent `jlim` means neo-Hookean). Default: the built-in reference device.
    #[arg(long, value_name = "FILE")]
    device: Option<PathBuf>,
    /// Voltage margin: the bias may not exceed (1 − margin) × the limit voltage.
    #[arg(long, value_name = "M", default_value_t = DEFAULT_MARGIN, allow_negative_numbers = true)]
    margin: f64,
    /// Print one JSON object on stdout instead of text.
    #[arg(long)]
    json: bool,
}

impl Default for Common {
    fn default() -> Self {
        Self {
            device: None,
            margin: DEFAULT_MARGIN,
            json: false,
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let command = cli.command.unwrap_or(Command::Run {
        scene: None,
        out: PathBuf::from("out/run"),
        json: false,
    });
    match run(command) {
        Ok((out, failure)) => {
            println!("{out}");
            match failure {
                None => ExitCode::SUCCESS,
                Some(message) => {
                    eprintln!("error: {message}");
                    ExitCode::from(1)
                }
            }
        }
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
    }
}

/// Run a command: what to print, and a failure to report with exit status 1 (a stress run
/// that failed silently). `Err` is the one-line reason for exit status 2.
fn run(command: Command) -> Result<(String, Option<String>), String> {
    match command {
        Command::Run { scene, out, json } => {
            let scene = match scene {
                Some(path) => host_sim::scene::load(&path)?,
                None => host_sim::scene::parse(host_sim::scene::REFERENCE)
                    .map_err(|e| format!("built-in reference scene: {e}"))?,
            };
            if !json {
                eprintln!(
                    "running scene {} ({} s)...",
                    scene.name, scene.run.duration_seconds
                );
            }
            let run = scene.run.run()?;
            let files = report::run_files(&host_sim::scene::out_dir(&out, &scene), &scene, &run)?;
            let text = report::run(&scene, &run, &files, json);
            // A plant that left its true safe region fails the run.
            let failure = run
                .plant_crossing
                .map(|(mode, t)| format!("the plant crossed {} at {t} s", mode.name()));
            Ok((text, failure))
        }
        Command::Safe { common } => {
            let (tuner, name) = tuner(&common)?;
            let range = tuner
                .tunable_range(common.margin)
                .map_err(|e| e.to_string())?;
            let text = report::safe(&name, &tuner, &range, common.margin, common.json);
            Ok((text, None))
        }
        Command::Tune { target_hz, common } => {
            let (tuner, name) = tuner(&common)?;
            let range = tuner
                .tunable_range(common.margin)
                .map_err(|e| e.to_string())?;
            let bias = tuner
                .tune(target_hz, common.margin)
                .map_err(|e| format!("{e} (margin {})", common.margin))?;
            let text = report::tune(
                &name,
                &tuner,
                &range,
                common.margin,
                target_hz,
                &bias,
                common.json,
            );
            Ok((text, None))
        }
        Command::Simulate {
            bias_volts,
            ac_volts,
            drive_hz,
            damping,
            duration,
            start,
            method,
            step,
            device,
            json,
        } => {
            let (mut params, name) = params(&device)?;
            if let Some(c) = damping {
                params.damping = c;
            }
            let choice = Choice::parse(&method)?;
            let checked = Device::new(params).map_err(|e| format!("{name}: {e}"))?;
            let step =
                step.unwrap_or(1.0 / (64.0 * checked.natural_frequency_hz(checked.prestretch_1())));
            let scene = Scene {
                params,
                bias_volts,
                ac_volts,
                drive_hz,
                duration_seconds: duration,
                start,
            };
            let outcome = simulate::simulate(&scene, choice, step).map_err(|e| e.to_string())?;
            let text = report::simulation(&name, &choice.name(), step, &outcome, json);
            Ok((text, None))
        }
        Command::Stress { device, json } => {
            let (params, name) = params(&device)?;
            let (report, silent) = stress::run(params).map_err(|e| format!("{name}: {e}"))?;
            let text = if json {
                report.to_string()
            } else {
                stress::table(&report)
            };
            Ok((
                text,
                silent.then(|| "a stress run failed silently".to_string()),
            ))
        }
        Command::Lut {
            out,
            points,
            format,
            common,
        } => {
            let (params, name) = params(&common.device)?;
            let made =
                lut::make(params, common.margin, points).map_err(|e| format!("{name}: {e}"))?;
            let written: &[u8] = match format {
                LutFormat::Bin => &made.bytes,
                LutFormat::Csv => &lut::csv(&made).into_bytes(),
            };
            std::fs::write(&out, written)
                .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
            let text = report::lut(&name, &made, common.margin, &out, common.json);
            Ok((text, None))
        }
        Command::Report { out, device, json } => {
            let (params, name) = params(&device)?;
            let text = report::work_precision(&name, params, &out, json)
                .map_err(|e| format!("{name}: {e}"))?;
            Ok((text, None))
        }
        Command::Sweep {
            bias_volts,
            ac_volts,
            quality,
            from_ratio,
            to_ratio,
            points,
            periods,
            steps_per_period,
            out,
            device,
            json,
        } => {
            let (mut params, name) = params(&device)?;
            if !(quality.is_finite() && quality >= 0.0) {
                return Err(format!(
                    "quality {quality}: need Q > 0 (or 0 for the device's damping)"
                ));
            }
            let mut sweep = sweep::Sweep {
                params,
                bias_volts,
                ac_volts,
                ratios: (from_ratio, to_ratio),
                points,
                periods,
                steps_per_period,
            };
            let (_, _, natural_hz) =
                sweep::operating_point(&sweep).map_err(|e| format!("{name}: {e}"))?;
            if quality > 0.0 {
                params.damping =
                    params.effective_mass() * std::f64::consts::TAU * natural_hz / quality;
                sweep.params = params;
            }
            let text = report::sweep(&name, &sweep, quality, &out, json)?;
            Ok((text, None))
        }
    }
}

/// The device parameters named on the command line, or the reference device, and a name.
fn params(device: &Option<PathBuf>) -> Result<(DeviceParams<f64>, String), String> {
    Ok(match device {
        Some(path) => (device_file::load(path)?, path.display().to_string()),
        None => (REFERENCE_DEVICE, "reference device (built in)".into()),
    })
}

/// The device named on the command line (or the reference), validated, with its limit found.
fn tuner(common: &Common) -> Result<(Tuner<f64>, String), String> {
    let (params, name) = params(&common.device)?;
    let device = Device::new(params).map_err(|e| format!("{name}: {e}"))?;
    Ok((Tuner::new(device), name))
}
