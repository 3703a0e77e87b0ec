//! host-sim: workstation tools for de-resonator, on the same `no_std` core the firmware runs.

use std::io::{IsTerminal, Write};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use host_sim::cmd::{self, Report};

/// Safe region, bias tuning and dynamics of a dielectric elastomer resonator.
///
/// A static bias voltage sets the resonator's natural frequency; too much voltage and the
/// membrane fails. `run` runs a scene: the firmware's controller tunes and drives a full
/// simulation of the plant. `safe` shows where the loading branch fails first and the
/// frequencies reachable before it; `tune` finds the bias for a target frequency; `simulate`
/// integrates the motion under a drive and reports any dynamic crossing of a limit. Without
/// a command, `run` runs the built-in reference scene (scenes/reference.toml).
///
/// Exit status, one rule for every command:
///   0  done, and safe;
///   1  done, and the report is on stdout, but a limit was crossed (a scene's plant, a
///      simulated trajectory, a sweep point) or the controller refused or faulted (a scene,
///      `image --check`, a console script's `err`), or a stress case failed silently or lost
///      its reference; the last line on stderr says which;
///   2  nothing done: bad input (the device, a scene, a setting, a flag, an unreachable
///      target, an unstable step, work beyond the bounds); one line on stderr says why,
///      nothing on stdout.
#[derive(Parser, Debug)]
#[command(name = "host-sim", version, about, long_about)]
struct Cli {
    /// Print one JSON object on stdout instead of text.
    #[arg(long, global = true)]
    json: bool,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a scene: the firmware's controller against the full plant simulator.
    ///
    /// Run a scene: the firmware's controller (the core's, unchanged) tunes and drives the full
    /// plant simulator through its DAC driver, reading the simulated sensor; host-sim checks
    /// the true plant against model.md §6 at every tick. Prints a short report and writes what
    /// the scene asks for (a plot, the time history) into --out/<scene name>. Without a scene:
    /// the built-in reference scene (scenes/reference.toml).
    Run(cmd::run::RunArgs),
    /// The tuning curve: f against bias to the limit, or a family over pre-stretches.
    ///
    /// The tuning curve: natural frequency against bias from 0 V to the limit, with the limit,
    /// the margin's highest bias, the tunable range and a target marked; over ranges of
    /// pre-stretch (`--prestretch-1 2:3:5`), a family of curves and the safe region's edge
    /// through their limits. Writes curve.csv and curve.svg into --out.
    Curve(cmd::curve::CurveArgs),
    /// The safe region: the limit of the loading branch and the tunable range.
    ///
    /// Show the safe region: f at zero bias, the first failure on the loading branch (mode,
    /// volts, stretch, f there) and the tunable range within the margin.
    Safe(cmd::safe::SafeArgs),
    /// The smallest bias that sets the natural frequency to a target.
    ///
    /// Find the smallest bias (volts) that sets the natural frequency to a target, at most (1 −
    /// margin) times the limit voltage.
    Tune(cmd::safe::TuneArgs),
    /// Integrate the motion under bias + AC, watched by the safety monitor.
    ///
    /// Integrate the motion from rest under Φ(t) = bias + ac·sin(2π·f·t), watched by the
    /// dynamic safety monitor (the six checks of model.md §6 at every step).
    Simulate(cmd::simulate::SimulateArgs),
    /// Run the stiff and extreme cases with every core method against the reference.
    ///
    /// Run the stiff and extreme cases (near the EMI limit, passive membrane near slack, Gent
    /// lock-up, a very light bar, a large AC amplitude, a fast voltage step) with every core
    /// method in f32 and f64 at several steps, against the reference. Each run is `stable`,
    /// `refused` (by the guard), `stopped` (a typed error), or `failed_silently`, which must
    /// never happen: exit status 1 if any run did.
    Stress(cmd::stress::StressArgs),
    /// Write the tuning table the firmware flashes.
    ///
    /// Write the tuning table the firmware flashes: bias against natural frequency from zero
    /// bias to (1 − margin)·limit, evenly spaced in bias², with the device parameters, the
    /// margin, the measured interpolation error and a CRC-32 (layout: the core's `table`
    /// module, README). Prints the interpolation error against the direct solve.
    Lut(cmd::lut::LutArgs),
    /// Error against run time of every core method (work-precision study).
    ///
    /// Error against run time (a work-precision study): every core method in f32 and f64 at 8
    /// to 512 steps a period against the reference (DOP853, 1e-12), on three scenes (a small
    /// oscillation about a tuned bias, a large parametric drive, a bias near the limit). Writes
    /// work-precision.csv and work-precision.svg (log-log) into --out; prints a table.
    Report(cmd::report::PrecisionArgs),
    /// Frequency response under parametric drive: peaks and crossings.
    ///
    /// Frequency response under parametric drive Φ = bias + ac·sin(2π·f·t) (model.md §7): one
    /// run from rest per drive frequency, the amplitude once settled, and the peaks (expected
    /// near f0/2, f0 and 2·f0, f0 the small-oscillation frequency at the bias). Writes
    /// sweep.csv and sweep.svg into --out.
    Sweep(cmd::sweep::SweepArgs),
    /// Poincaré section at the drive's phase 0, from one or many start states.
    ///
    /// The driven membrane's Poincaré section: the state (stretch, dλ/dt) at t = k/f under
    /// Φ(t) = bias + ac·sin(2π·f·t), from one or many start states (`--y0 "S,V;S,V"`, run on
    /// all cores), the checks of model.md §6 watched along each run. Writes poincare.csv and
    /// poincare.svg into --out.
    Poincare(cmd::poincare::PoincareArgs),
    /// Bifurcation diagram by continuation, walked up and down.
    ///
    /// A bifurcation diagram by continuation: the Poincaré stretches at each value of the AC
    /// amplitude, the drive frequency or the bias (--vary), each value started from the
    /// previous one's end state, walked up and down (each walk from its own start, the two
    /// beside each other) so that hysteresis and jumps show; the first value at which a walk
    /// crossed a limit of model.md §6 marked. Writes bifurcation.csv and bifurcation.svg into
    /// --out.
    Bifurcation(cmd::bifurcation::BifurcationArgs),
    /// Largest Lyapunov exponent, with its convergence.
    ///
    /// The largest Lyapunov exponent (1/s) of the driven membrane, from the variational
    /// equation along the motion, the tangent renormalised once a drive period (without a
    /// drive, once a period of the small oscillation at the start); the running estimate
    /// shows its convergence. Writes lyapunov.csv and lyapunov.svg into --out.
    Lyapunov(cmd::lyapunov::LyapunovArgs),
    /// Safe drive map: AC amplitude × frequency, the full simulation beside the board.
    ///
    /// The safe drive map at the bias the board tunes to: over AC amplitude × drive
    /// frequency, the full simulation's largest swing (from rest, the AC switched on) and
    /// whether it stays inside model.md §6, beside the board's own acceptance of each `ac`
    /// (every boot check of `start`, as the firmware runs them). Exit status 1 if the board
    /// accepts a drive that crosses a limit. Writes drive-map.csv and drive-map.svg into
    /// --out.
    DriveMap(cmd::drive_map::DriveMapArgs),
    /// Write the configuration image the firmware reads, or check one (--check).
    ///
    /// Write the configuration image the firmware reads from its own flash sector (sector 11,
    /// 0x080E0000): the device, the amplifier, the default settings and the tuning table
    /// (layout: the core's `image` module), after running the firmware's own boot checks on it.
    /// `--check FILE` reads an image or a table back: what it holds, and what the firmware's
    /// boot says of it (status 1 if it would refuse).
    Image(cmd::image::ImageArgs),
    /// Talk to the firmware's command port (serial, or QEMU's socket).
    ///
    /// Talk to the firmware's command port (USART2): a serial port, or QEMU's socket. Each
    /// request gets one reply line, `ok …` or `err <code> <message>` (the core's `protocol`
    /// module). With --script, status 1 if any request got an `err`.
    Console(cmd::console::ConsoleArgs),
    /// A virtual board: the firmware's logic and a scene's plant behind a command port.
    ///
    /// A virtual board on a socket: the core's board and controller (what the firmware runs)
    /// at the scene's tick rate against the scene's full plant, in real time (--speed X: X
    /// times it; --speed max: as fast as it computes), serving the firmware's command port
    /// protocol. Talk to it with `host-sim console --tcp/--unix`: the same replies, error
    /// codes and start-up line as the board. Events go to stderr as they happen; with
    /// --seconds it stops there and reports (status 1 if the plant crossed a limit).
    Serve(cmd::serve::ServeArgs),
    /// A live page for the board in the browser: plots, controls, the fault log.
    ///
    /// A live dashboard served on loopback (--listen, default 127.0.0.1:8080): the telemetry
    /// stream's voltage, stretch, current and tracking plotted live, the device's tuning curve
    /// with the operating point, the controls (target, ac, start, stop, trim, clear, settings)
    /// as the protocol's own lines with the board's replies verbatim, the fault log, the
    /// request log, a recording in `console --record`'s CSV. The board is reached as `console`
    /// reaches it: a serial port, `serve`'s socket or QEMU's.
    Dash(host_sim::dash::DashArgs),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return clap_error(e),
    };
    let json = cli.json;
    let command = cli.command.unwrap_or(Command::Run(cmd::run::RunArgs {
        scene: None,
        out: "out/run".into(),
        firmware: None,
        history: false,
        record: false,
        stream_hz: 100.0,
    }));
    let result = match command {
        Command::Run(args) => cmd::run::run(&args, json).map(|r| emit(&r, json)),
        Command::Curve(args) => cmd::curve::curve(&args).map(|r| emit(&r, json)),
        Command::Safe(args) => cmd::safe::safe(&args).map(|r| emit(&r, json)),
        Command::Tune(args) => cmd::safe::tune(&args).map(|r| emit(&r, json)),
        Command::Simulate(args) => cmd::simulate::simulate(&args).map(|r| emit(&r, json)),
        Command::Stress(args) => cmd::stress::stress(&args).map(|r| emit(&r, json)),
        Command::Lut(args) => cmd::lut::lut(&args).map(|r| emit(&r, json)),
        Command::Report(args) => cmd::report::precision(&args).map(|r| emit(&r, json)),
        Command::Sweep(args) => cmd::sweep::sweep(&args).map(|r| emit(&r, json)),
        Command::Poincare(args) => cmd::poincare::poincare(&args).map(|r| emit(&r, json)),
        Command::Bifurcation(args) => cmd::bifurcation::bifurcation(&args).map(|r| emit(&r, json)),
        Command::Lyapunov(args) => cmd::lyapunov::lyapunov(&args).map(|r| emit(&r, json)),
        Command::DriveMap(args) => cmd::drive_map::drive_map(&args).map(|r| emit(&r, json)),
        Command::Image(args) => cmd::image::image(&args).map(|r| emit(&r, json)),
        Command::Console(args) => cmd::console::console(&args, json).map(|r| emit(&r, json)),
        Command::Serve(args) => cmd::serve::serve(&args).map(|r| emit(&r, json)),
        Command::Dash(args) => host_sim::dash::dash(&args, json).map(|r| emit(&r, json)),
    };
    match result {
        Ok((out, failure, to_stderr)) => {
            // A reader that stops early (`host-sim safe | head -1`) is not an error: no panic.
            if to_stderr {
                eprintln!("{out}");
            } else {
                let mut stdout = std::io::stdout().lock();
                let _ = writeln!(stdout, "{out}").and_then(|()| stdout.flush());
            }
            match failure {
                None => ExitCode::SUCCESS,
                Some(message) => {
                    say_error(&message);
                    ExitCode::from(1)
                }
            }
        }
        Err(message) => {
            say_error(&message);
            ExitCode::from(2)
        }
    }
}

/// One line on stderr, `error:` in bold red on a terminal (as clap writes its own).
fn say_error(message: &str) {
    let mut stderr = std::io::stderr().lock();
    let _ = if stderr.is_terminal() {
        writeln!(stderr, "\x1b[1;31merror:\x1b[0m {message}")
    } else {
        writeln!(stderr, "error: {message}")
    };
}

/// A report as text or JSON, and the failure it carries (exit status 1).
/// The report as text or JSON, whether it failed, and whether it goes to stderr (stdout
/// carries the data: `--csv -`).
fn emit<R: Report>(report: &R, json: bool) -> (String, Option<String>, bool) {
    let text = if json {
        serde_json::to_string(report).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    } else {
        report.to_string()
    };
    (text, report.failure(), report.data_on_stdout())
}

/// clap's verdict on the command line: help and version as clap prints them (status 0);
/// anything else on one line of stderr with status 2, as every other refusal.
fn clap_error(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
        let _ = e.print();
        return ExitCode::SUCCESS;
    }
    // Styled on a terminal, as clap would print it; one line either way.
    let text = if std::io::stderr().is_terminal() {
        e.render().ansi().to_string()
    } else {
        e.render().to_string()
    };
    let line: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("For more information"))
        .collect();
    eprintln!("{}", line.join(" "));
    ExitCode::from(2)
}
