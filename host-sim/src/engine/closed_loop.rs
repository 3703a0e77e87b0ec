//! The closed loop on the host: the core's board (the firmware's, unchanged) at its own rate,
//! or the firmware's binary under QEMU in its place ([`LoopBoard`]), its DAC frames into the
//! simulated bench ([`crate::engine::bench`]), the amplifier and the membrane in the plant
//! simulator, and the sensors sampling the plant back. Every tick host-sim checks the true
//! plant against §6.

use std::time::Instant;

use de_resonator::acquire::{Block, Channel, FrontEnd, InputError, Reader, Stall};
use de_resonator::board::runner::{AfterTick, Ticker};
use de_resonator::image::{AmplifierSpec, PowerUp, DAC_BITS};
use de_resonator::wire::link::{Booted, Observed};
use de_resonator::wire::stream::{Receiver, Record};
use de_resonator::{
    Amplifier, Controller, EventKind, FailureMode, Fault, Inputs, OutputStage, Phase, Settings,
    BUS_FAULT_SAID, FAULT_SAID,
};

use crate::engine::bench::Noise;
pub use crate::engine::bench::{CurrentMonitor, EnableLine, Sensor, SimulatedDac, Wires};
use crate::engine::core_board::{core_tick, CoreBoard};
use crate::engine::events;
use crate::engine::loop_board::{LoopBoard, Samples};
use crate::engine::plant::{self, Plant, Vector};
use crate::engine::solver::{Solver, Tolerance, EVENT_RESOLUTION_SECONDS};
use crate::text::sig;

/// What a tick of `Loop::step` did.
#[derive(Clone, Copy, Debug)]
pub struct Stepped {
    /// The board's tick: its number since boot, what it read and did, a fault's entry.
    pub done: AfterTick,
    /// The plant's stretch at the tick's start.
    pub start_stretch: f64,
    /// The membrane's voltage at the tick's end, V.
    pub volts: f64,
}

/// The plant's side of a loop between ticks: its state, the solver's next step, the
/// sensors' noise and last reading, the amplifier's current. `Loop::sense` reads it before a
/// tick, `Loop::advance` steps it over the tick.
pub struct Bench {
    pub y: Vector,
    next_step: Option<f64>,
    /// dy/dt at `y` where the last tick's solve worked it out (`plant::Tick::rate`).
    rate: Option<Vector>,
    noise: Noise,
    /// The stretch sensor's last reading (a stuck sensor repeats it).
    reading: f64,
    /// The membrane's (stretch, volts) at the tick's start.
    port: (f64, f64),
    /// The mean output current over the last tick, A (none before the first).
    pub last_current: Option<f64>,
    current_wanted: bool,
    /// With a front end: its scans a tick, this tick's codes as the DMA writes them, and
    /// the core's board's acquisition reading them.
    scans: u32,
    pub codes: Vec<u16>,
    reader: Reader,
    /// The stretch input's last code (a stuck sensor repeats it).
    stuck_code: Option<u16>,
    /// The first check of §6 the plant failed, and when (s): located within its tick.
    pub crossing: Option<(FailureMode, f64)>,
    /// The plant's stretch and dλ/dt (1/s) there.
    pub crossing_state: Option<(f64, f64)>,
}

/// The board's analog front end in a scene (`[front_end]`): the image's, and the ADC's noise.
#[derive(Clone, Debug)]
pub struct Analog {
    pub front_end: FrontEnd,
    /// The RMS noise of a conversion, in codes (Gaussian, from the scene's seed).
    pub noise_codes: f64,
    /// From this time on the stretch input's code repeats its last (a stuck sensor), s.
    pub stretch_stuck_after_seconds: Option<f64>,
    /// When the acquisition stalls (silicon's ADC overrun, DMA transfer error), s, in order:
    /// the tick whose samples span that time loses them, its block says the stall.
    pub stalls: Vec<(f64, Stall)>,
}

/// A whole loop: the controller's side (what it is told), the plant's, and the run.
#[derive(Clone, Debug)]
pub struct Loop {
    /// The devices the controller is told about: the scene's device and its tolerances
    /// (model.md §10); its table is made from them.
    pub batch: de_resonator::model::tolerance::DeviceBox,
    pub plant: Plant,
    pub solver: Solver,
    pub tolerance: Tolerance,
    pub dac_reference_volts: f64,
    pub settings: Settings,
    pub sensor: Option<Sensor>,
    /// The amplifier's current monitor, if the controller reads one.
    pub current_monitor: Option<CurrentMonitor>,
    /// The board's analog front end: the sensors read through its ADC (then `sensor` and
    /// `current_monitor` are none).
    pub analog: Option<Analog>,
    /// The DAC bus fails from this time on, s.
    pub bus_fails_after_seconds: Option<f64>,
    pub duration_seconds: f64,
    pub seed: u64,
    /// Command-port lines the scene sends, each before its tick (in order).
    pub commands: Vec<Scripted>,
    /// Keep the time history (`Sample`) at every tick.
    pub history: bool,
    /// Record the board's telemetry stream at this rate, Hz (`stream <hz>` sent before the
    /// first tick; `None`: no stream).
    pub stream_hz: Option<f32>,
}

/// A command-port line a scene sends before tick `tick` (`[[commands]]`).
#[derive(Clone, Debug, PartialEq)]
pub struct Scripted {
    pub tick: u64,
    pub line: String,
}

/// A scripted line and the board's reply, and when.
#[derive(Clone, Debug, PartialEq)]
pub struct Replied {
    pub seconds: f64,
    pub line: String,
    pub reply: String,
}

/// Something the controller said, and when: its kind, its numbers (named by
/// `EventKind::value_names`) and its words.
#[derive(Clone, Debug, PartialEq)]
pub struct Said {
    pub seconds: f64,
    pub kind: EventKind,
    pub values: Vec<(&'static str, f64)>,
    pub what: String,
}

/// What a loop run gives.
#[derive(Clone, Debug)]
pub struct Run {
    /// What the boot found (`driving` false: refused).
    pub boot: Option<Booted>,
    /// Why the board refused to drive.
    pub refused: Option<String>,
    pub events: Vec<Said>,
    /// The scene's command-port lines and the replies.
    pub commands: Vec<Replied>,
    /// The fault that stopped the drive, if any (the core's board only), and its words
    /// (either board).
    pub fault: Option<Fault>,
    pub fault_words: Option<String>,
    /// The first check of §6 the true plant failed, and when (s): must stay `None`.
    pub plant_crossing: Option<(FailureMode, f64)>,
    /// The plant's stretch and dλ/dt (1/s) there.
    pub plant_crossing_state: Option<(f64, f64)>,
    /// The bias the controller holds at the end (0 after a fault or a refusal), V.
    pub bias_volts: f64,
    /// The target in force at the end (the scene's, unless a command changed it), Hz.
    pub target_hz: f64,
    /// The last commanded and applied voltages, V.
    pub final_command_volts: f64,
    /// The highest voltage commanded at any tick, V.
    pub max_command_volts: f64,
    pub final_membrane_volts: f64,
    /// The plant's natural frequency at its static equilibrium under the controller's bias
    /// (networks frozen), Hz; NaN if there is none.
    pub natural_frequency_hz: f64,
    /// The true plant's voltage limit on its loading branch from 0 V (networks frozen as they
    /// are at the end) and its mode.
    pub limit: Option<(FailureMode, f64)>,
    pub history: Vec<Sample>,
    /// The board's telemetry stream as received (`Loop::stream_hz`): the records, and the
    /// receiver's counts.
    pub telemetry: Option<(Vec<Record>, Receiver)>,
    /// With tracking on (`track_seconds`): every `TRACE_SECONDS`, the plant's natural
    /// frequency at the bias held and what the tracker measures.
    pub tracking: Vec<Tracked>,
    /// With the probe on (`probe_volts`): each window's stretch from the capacitance against
    /// the plant's mean stretch over it.
    pub sensed: Vec<Sensed>,
    pub ticks: u64,
    pub run_seconds: f64,
}

/// How often a tracked run records `Tracked`, s.
pub const TRACE_SECONDS: f64 = 0.1;

/// One window of the stretch from the capacitance against the true plant.
#[derive(Clone, Copy, Debug)]
pub struct Sensed {
    /// When the window ended, s.
    pub seconds: f64,
    /// The estimate and its standard error.
    pub stretch: f64,
    pub sigma: f64,
    /// The plant's stretch averaged over the ticks since the last window.
    pub plant_stretch: f64,
}

/// A tracked drive at one time: the true plant against the tracker.
#[derive(Clone, Copy, Debug)]
pub struct Tracked {
    pub seconds: f64,
    /// The plant's natural frequency at its equilibrium under the controller's bias
    /// (networks frozen as they are), Hz; NaN if there is none.
    pub plant_hz: f64,
    /// The drive's frequency, Hz (NaN before the tracker runs).
    pub drive_hz: f64,
    /// The tracker's last cycle: natural frequency, Hz, and Q.
    pub measured_hz: f64,
    pub quality_factor: f64,
    pub bias_volts: f64,
}

impl Run {
    /// Record what the board said at `seconds` (its kind, numbers and words), and the fault
    /// if it is one.
    fn said(&mut self, seconds: f64, seen: &Observed, words: &str) {
        let Some(kind) = seen.said else { return };
        let what = match kind {
            EventKind::Fault | EventKind::BusFault => {
                self.fault_words = Some(words.to_string());
                let what = if kind == EventKind::BusFault {
                    BUS_FAULT_SAID
                } else {
                    FAULT_SAID
                };
                format!("{what}: {words}")
            }
            _ => words.to_string(),
        };
        let values = kind
            .value_names()
            .iter()
            .zip(seen.said_values)
            .filter(|(_, v)| v.is_finite())
            .map(|(name, v)| (*name, f64::from(v)))
            .collect();
        self.events.push(Said {
            seconds,
            kind,
            values,
            what,
        });
    }
}

/// The plant at the end of a tick, as the history keeps it.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    pub tick: u64,
    pub seconds: f64,
    /// The board's last DAC frame (its code, and whether it powered the DAC on) and the
    /// amplifier's enable line after the tick.
    pub dac_code: u16,
    pub dac_on: bool,
    pub enable: bool,
    /// The controller's phase after the tick (`None`: no controller runs).
    pub phase: Option<Phase>,
    pub stretch: f64,
    pub membrane_volts: f64,
    /// The amplifier's mean output current over the tick, A (model.md §8).
    pub current_amps: f64,
}

/// The most ticks a scene may run: 1,000 s at 10 kHz, about a minute of work and 240 MB of
/// history at ~5 µs and 24 bytes a tick.
pub const MAX_TICKS: f64 = 1e7;

impl Loop {
    /// The scene's ticks, refused before any work when not a number or beyond `MAX_TICKS`.
    pub fn ticks(&self) -> Result<u64, String> {
        let tick_hz = f64::from(self.settings.tick_hz);
        let ticks = (self.duration_seconds * tick_hz).round();
        if !(ticks.is_finite() && ticks >= 1.0) {
            return Err(format!(
                "duration_seconds {} at tick_hz {}: not a whole tick",
                sig(self.duration_seconds),
                sig(tick_hz)
            ));
        }
        if ticks > MAX_TICKS {
            return Err(format!(
                "duration_seconds {} at tick_hz {} is {} ticks, more than {}: about {} s of \
                 work; shorten the scene or lower the tick rate",
                sig(self.duration_seconds),
                sig(tick_hz),
                sig(ticks),
                sig(MAX_TICKS),
                sig((ticks * 5e-6).round())
            ));
        }
        Ok(ticks as u64)
    }

    /// The amplifier the controller is told about: the DAC's reference times the gain.
    fn amplifier(&self) -> Result<Amplifier, String> {
        Amplifier::new(
            self.dac_reference_volts as f32,
            self.plant.amplifier.gain as f32,
        )
        .map_err(|e| format!("amplifier: {e}"))
    }

    /// Run the loop for its duration, the core's board on the host.
    pub fn run(&self) -> Result<Run, String> {
        let wires = self.wires();
        let image = self.image(PowerUp::Drive)?;
        let mut board = CoreBoard::boot(&image, &wires);
        self.run_on(&mut board, &wires)
    }

    /// The image `host-sim image` writes for the scene: its device, its amplifier (the
    /// controller told of no rail below the DAC's top code: a saturating amplifier is the
    /// plant's, for the monitor to find), its front end and settings.
    pub fn image(&self, power_up: PowerUp) -> Result<Vec<u8>, String> {
        let amplifier = self.amplifier()?;
        let spec = AmplifierSpec {
            dac_reference_volts: self.dac_reference_volts as f32,
            gain: self.plant.amplifier.gain as f32,
            rail_volts: amplifier.max_volts(),
            dac_bits: DAC_BITS,
        };
        let front_end = self.analog.as_ref().map_or(FrontEnd::NONE, |a| a.front_end);
        crate::lut::image(&self.batch, &spec, &front_end, &self.settings, power_up)
    }

    /// Run the loop for its duration on `board` (the core's, or the firmware's under QEMU),
    /// whose output drives `wires`.
    pub fn run_on(&self, board: &mut dyn LoopBoard, wires: &Wires) -> Result<Run, String> {
        let ticks = self.ticks()?;
        let started = Instant::now();
        let tick_seconds = 1.0 / f64::from(self.settings.tick_hz);
        // On a terminal only, and not tick by tick.
        let progress = crate::progress::bar("run", ticks as usize);
        let every = (ticks / 200).max(1);
        let (booted, refusal) = board.booted();
        let amplifier = self.amplifier()?;
        let mut run = Run {
            boot: Some(booted),
            refused: refusal,
            events: Vec::new(),
            commands: Vec::new(),
            fault: None,
            fault_words: None,
            plant_crossing: None,
            plant_crossing_state: None,
            bias_volts: 0.0,
            target_hz: f64::from(self.settings.target_hz),
            final_command_volts: 0.0,
            max_command_volts: 0.0,
            final_membrane_volts: 0.0,
            natural_frequency_hz: f64::NAN,
            limit: None,
            history: Vec::new(),
            telemetry: None,
            tracking: Vec::new(),
            sensed: Vec::new(),
            ticks: 0,
            run_seconds: 0.0,
        };
        // The amplifier's current, worked out when a monitor, a front end or the history
        // reads it.
        let mut bench = self.bench(self.history);
        let tracked = self.settings.track_seconds.is_some();
        // The plant's stretch summed since the last window of the probe's lock-in.
        let (mut stretch_sum, mut stretch_ticks) = (0.0, 0u32);
        let mut last_sensed = (f32::NAN, f32::NAN);
        let mut bias = f32::NAN;
        let trace_every =
            ((TRACE_SECONDS * f64::from(self.settings.tick_hz)).round() as u64).max(1);
        if let Some(hz) = self.stream_hz {
            let line = format!("stream {hz}");
            let reply = board.command(&line)?;
            if !reply.starts_with("ok ") {
                return Err(format!("`{line}` got `{reply}`"));
            }
            run.commands.push(Replied {
                seconds: 0.0,
                line,
                reply,
            });
        }
        for k in 0..ticks {
            if k % every == 0 {
                progress.set_position(k);
                if crate::progress::stopped() {
                    return Err(crate::progress::INTERRUPTED.into());
                }
            }
            let t = k as f64 * tick_seconds;
            for c in self.commands.iter().filter(|c| c.tick == k) {
                let reply = board.command(&c.line)?;
                run.commands.push(Replied {
                    seconds: t,
                    line: c.line.clone(),
                    reply,
                });
            }
            self.fail_bus(k, wires);
            // The plant is measured every tick, a controller or not (the ADC runs either way):
            // both boards see the same samples whatever the commands do.
            let samples = self.measure(&mut bench, k, self.amplifier_input(wires));
            let inputs = self.acquired(&mut bench, samples);
            let (seen, words) = board.tick(k, inputs, samples, &bench.codes)?;
            if let Some(fault) = board.fault() {
                run.fault = Some(fault);
            }
            let start_stretch = bench.y[0];
            let volts = self.advance(&mut bench, k, self.amplifier_input(wires))?;
            if seen.phase.is_some() {
                stretch_sum += start_stretch;
                stretch_ticks += 1;
                let sensed = (seen.sensed_stretch, seen.sensed_sigma);
                let new = (sensed.0.to_bits(), sensed.1.to_bits())
                    != (last_sensed.0.to_bits(), last_sensed.1.to_bits());
                if !sensed.0.is_nan() && new {
                    run.sensed.push(Sensed {
                        seconds: t,
                        stretch: f64::from(sensed.0),
                        sigma: f64::from(sensed.1),
                        plant_stretch: stretch_sum / f64::from(stretch_ticks.max(1)),
                    });
                    (stretch_sum, stretch_ticks) = (0.0, 0);
                }
                last_sensed = sensed;
                // The lock-in starts again after the trim's ring.
                if seen.phase == Some(Phase::Measuring) {
                    (stretch_sum, stretch_ticks) = (0.0, 0);
                }
                let command = amplifier.volts(de_resonator::DacCode(seen.dac_code));
                let command = if seen.dac_on && seen.enable {
                    f64::from(command)
                } else {
                    0.0
                };
                run.final_command_volts = command;
                run.max_command_volts = run.max_command_volts.max(command);
                run.said(t, &seen, &words);
                bias = seen.bias_volts;
                run.target_hz = f64::from(seen.target_hz);
            }
            let y = bench.y;
            if run.plant_crossing.is_none() {
                (run.plant_crossing, run.plant_crossing_state) =
                    (bench.crossing, bench.crossing_state);
            }
            if self.history {
                run.history.push(Sample {
                    tick: k,
                    seconds: t + tick_seconds,
                    dac_code: seen.dac_code,
                    dac_on: seen.dac_on,
                    enable: seen.enable,
                    phase: seen.phase,
                    stretch: y[0],
                    membrane_volts: volts,
                    current_amps: bench.last_current.unwrap_or(f64::NAN),
                });
            }
            if tracked && (k + 1) % trace_every == 0 {
                run.tracking.push(self.tracked(&seen, &y, t + tick_seconds));
            }
            run.final_membrane_volts = volts;
            run.ticks = k + 1;
        }
        progress.finish_and_clear();
        if self.stream_hz.is_some() {
            run.telemetry = Some(board.records()?);
        }
        let y = bench.y;
        run.run_seconds = started.elapsed().as_secs_f64();
        let bias = if run.fault_words.is_none() && bias.is_finite() {
            f64::from(bias)
        } else {
            0.0
        };
        run.bias_volts = bias;
        if let Some(rest) = self.plant.equilibrium(&y, bias) {
            run.natural_frequency_hz = self.plant.natural_frequency_hz(&rest, bias);
        }
        // The plant's own limit from 0 V up (networks as they are): a bias past it shows as
        // a negative margin, not as a limit just above the bias.
        run.limit = self
            .plant
            .equilibrium(&y, 0.0)
            .and_then(|unbiased| self.plant.limit_volts(&unbiased, 0.0));
        Ok(run)
    }

    /// The scene's DAC bus fails from its time on (the core's board's simulated bus).
    fn fail_bus(&self, k: u64, wires: &Wires) {
        let t = k as f64 * (1.0 / f64::from(self.settings.tick_hz));
        let bus = &wires.bus;
        if self.bus_fails_after_seconds.is_some_and(|at| t >= at) && bus.fail_after.get().is_none()
        {
            bus.fail_after.set(Some(bus.frames.get()));
        }
    }

    /// The board's outputs as the plant sees them, idle: the DAC on its bus, the enable line.
    pub fn wires(&self) -> Wires {
        Wires {
            bus: SimulatedDac {
                reference_volts: self.dac_reference_volts,
                ..SimulatedDac::default()
            },
            enable: EnableLine::default(),
        }
    }

    /// One tick of the board against the plant: the board's tick on the plant's measurements
    /// (the firmware's tick, its enable policy), its background job between ticks (as the
    /// firmware's low-priority task runs it; the next tick applies the result), then the
    /// plant over the tick under the amplifier's input. No controller: no sensor read (its
    /// noise not drawn), the stage kept off.
    pub fn step(
        &self,
        k: u64,
        bench: &mut Bench,
        ticker: &mut Ticker,
        slot: &mut Option<Controller>,
        stage: &mut OutputStage<&SimulatedDac, &EnableLine>,
        wires: &Wires,
    ) -> Result<Stepped, String> {
        self.fail_bus(k, wires);
        let inputs = match slot {
            Some(_) => {
                let samples = self.measure(bench, k, self.amplifier_input(wires));
                self.acquired(bench, samples)
            }
            None => Ok(Inputs::NONE),
        };
        let done = core_tick(ticker, slot, stage, inputs);
        let start_stretch = bench.y[0];
        let volts = self.advance(bench, k, self.amplifier_input(wires))?;
        Ok(Stepped {
            done,
            start_stretch,
            volts,
        })
    }

    /// Tick `k`'s measurements of the plant, the amplifier's input at `input_volts`: read
    /// directly, or (a front end) the ADC's codes into `bench.codes`.
    pub fn measure(&self, bench: &mut Bench, k: u64, input_volts: f64) -> Samples {
        let Some(analog) = &self.analog else {
            return Samples::Direct(self.sense(bench, k, input_volts));
        };
        let membrane_volts = self.plant.volts(&bench.y, input_volts);
        let current = bench.last_current.unwrap_or(0.0);
        let stretch = bench.y[0];
        let t = k as f64 / f64::from(self.settings.tick_hz);
        let stuck = analog.stretch_stuck_after_seconds.is_some_and(|at| t >= at);
        // Each fitted channel's reading, spec and noise scale (its unit a code), once a tick.
        let mut fitted = [None; Channel::ALL.len()];
        for ((channel, spec), slot) in analog.front_end.fitted().zip(&mut fitted) {
            let reading = match channel {
                Channel::Current => current,
                Channel::Amplifier => membrane_volts,
                Channel::Stretch => stretch,
            };
            let noise_scale = analog.noise_codes * f64::from(spec.per_count);
            *slot = Some((channel, reading, noise_scale, spec));
        }
        bench.codes.clear();
        for _ in 0..bench.scans {
            for &(channel, reading, noise_scale, spec) in fitted.iter().flatten() {
                // The ADC's noise in the channel's unit, then the one rounding to a code.
                let noise = noise_scale * bench.noise.gaussian();
                let mut code = spec.adc_code((reading + noise) as f32);
                if channel == Channel::Stretch {
                    match bench.stuck_code {
                        Some(last) if stuck => code = last,
                        _ => bench.stuck_code = Some(code),
                    }
                }
                bench.codes.push(code);
            }
        }
        // A stall within this tick: its codes lost (drawn all the same, so the noise after it
        // is the run's without the stall).
        let dt = 1.0 / f64::from(self.settings.tick_hz);
        let stall = analog
            .stalls
            .iter()
            .find(|&&(at, _)| at >= t && at < t + dt)
            .map(|&(_, why)| why);
        if stall.is_some() {
            bench.codes.clear();
        }
        Samples::Codes { stall }
    }

    /// What the core's board's acquisition reads of a tick's samples.
    pub fn acquired(&self, bench: &mut Bench, samples: Samples) -> Result<Inputs, InputError> {
        match samples {
            Samples::Direct(inputs) => Ok(inputs),
            Samples::Codes { stall } => {
                let mut block = Block::EMPTY;
                if let Some(analog) = &self.analog {
                    block.add_scans(&analog.front_end, &bench.codes);
                }
                if let Some(why) = stall {
                    block.stalled(why);
                }
                bench.reader.inputs(&block)
            }
        }
    }

    /// The amplifier's input: the DAC's output while the enable line is high, V.
    fn amplifier_input(&self, wires: &Wires) -> f64 {
        if wires.enable.high.get() {
            self.plant.amplifier.gain * wires.bus.output_volts.get()
        } else {
            0.0
        }
    }

    /// The first check of §6 the plant fails in a tick from `t0` solved to `solved`: probed
    /// where the stretch turns and at the tick's end (a brief excursion peaks at a turn; the
    /// DAC holds and the amplifier's output is monotone over a tick), then located by solving
    /// the tick again from its start to each bisection's midpoint, to the reference's
    /// `EVENT_RESOLUTION_SECONDS`.
    fn first_crossing(
        &self,
        t0: f64,
        solved: &plant::Solved,
        input_volts: f64,
        solve: &impl Fn(f64) -> Result<plant::Solved, String>,
    ) -> Result<Option<(FailureMode, f64)>, String> {
        let fails = |t: f64, y: &Vector| self.crossing(y, t, self.plant.volts(y, input_volts));
        let end = (t0 + 1.0 / f64::from(self.settings.tick_hz), solved.y);
        // The turns in time order, then the end.
        let mut turns = solved.turns;
        if let [Some((a, _)), Some((b, _))] = turns {
            if b < a {
                turns.swap(0, 1);
            }
        }
        let mut passes = t0;
        for (t, y) in turns.iter().flatten().copied().chain([end]) {
            let Some(mode) = fails(t, &y) else {
                passes = t;
                continue;
            };
            let mut failed = None;
            let located =
                events::first_failing(
                    passes,
                    (t, mode),
                    EVENT_RESOLUTION_SECONDS,
                    |t| match solve(t) {
                        Ok(at) => fails(t, &at.y),
                        Err(e) => {
                            failed.get_or_insert(e);
                            None
                        }
                    },
                );
            return failed.map_or(Ok(Some((located.1, located.0))), Err);
        }
        Ok(None)
    }

    /// The first check of §6 the true plant fails at `seconds` in state `y` at `volts` (the
    /// leakage's breakdown first), if any.
    pub fn crossing(&self, y: &Vector, seconds: f64, volts: f64) -> Option<FailureMode> {
        let broken = self
            .plant
            .leakage
            .breaks_down(seconds, volts)
            .then_some(FailureMode::Breakdown);
        broken.or_else(|| self.plant.first_failure(y, volts))
    }

    /// The plant at rest, ready for the first tick; the amplifier's current worked out at
    /// each tick where a monitor or a front end reads it, or `history` keeps it.
    pub fn bench(&self, history: bool) -> Bench {
        let current_wanted = self.current_monitor.is_some() || self.analog.is_some() || history;
        let y = self.plant.at_rest();
        let front_end = self.analog.as_ref().map_or(FrontEnd::NONE, |a| a.front_end);
        let scans = front_end.check(self.settings.tick_hz).unwrap_or(0);
        Bench {
            port: (y[0], self.plant.volts(&y, 0.0)),
            y,
            next_step: None,
            rate: None,
            noise: Noise(self.seed),
            reading: f64::NAN,
            last_current: None,
            current_wanted,
            scans,
            codes: Vec::new(),
            reader: Reader::new(front_end, scans),
            stuck_code: None,
            crossing: None,
            crossing_state: None,
        }
    }

    /// Tick `k`'s measurements of the plant, the amplifier's input at `input_volts`.
    pub fn sense(&self, bench: &mut Bench, k: u64, input_volts: f64) -> Inputs {
        let t = k as f64 * (1.0 / f64::from(self.settings.tick_hz));
        let membrane_volts = self.plant.volts(&bench.y, input_volts);
        let mut inputs = self.inputs(
            &mut bench.noise,
            &mut bench.reading,
            k,
            t,
            &bench.y,
            membrane_volts,
        );
        inputs.current_amps = self
            .current_monitor
            .zip(bench.last_current)
            .map(|(monitor, amps)| monitor.read(amps, &mut bench.noise) as f32);
        inputs
    }

    /// The plant over tick `k` with the amplifier's input at `input_volts`: the membrane's
    /// voltage at its end.
    pub fn advance(&self, bench: &mut Bench, k: u64, input_volts: f64) -> Result<f64, String> {
        let tick_seconds = 1.0 / f64::from(self.settings.tick_hz);
        let t = k as f64 * tick_seconds;
        let (start, first_step, rate) = (bench.y, bench.next_step, bench.rate);
        // The tick from its start to `t1`.
        let solve = |t1: f64| {
            plant::Tick {
                plant: &self.plant,
                solver: self.solver,
                tolerance: self.tolerance,
                y: start,
                t0: t,
                t1,
                input_volts,
                first_step,
                rate,
            }
            .solve()
        };
        let solved = solve(t + tick_seconds)?;
        (bench.y, bench.next_step, bench.rate) = (solved.y, Some(solved.first_step), solved.rate);
        if bench.crossing.is_none() {
            if let Some((mode, at)) = self.first_crossing(t, &solved, input_volts, &solve)? {
                let there = solve(at)?.y;
                bench.crossing = Some((mode, at));
                bench.crossing_state = Some((there[0], there[1]));
            }
        }
        let volts = self.plant.volts(&bench.y, input_volts);
        if bench.current_wanted {
            // The output current over this tick, from the membrane's charge (§8).
            let end = (bench.y[0], volts);
            bench.last_current =
                Some(
                    self.plant
                        .mean_current_amps(bench.port, end, tick_seconds, t + tick_seconds),
                );
            bench.port = end;
        }
        Ok(volts)
    }

    /// The plant against the tracker at `seconds`, the board as `seen` after its tick.
    fn tracked(&self, seen: &Observed, y: &Vector, seconds: f64) -> Tracked {
        let bias = if seen.bias_volts.is_finite() {
            f64::from(seen.bias_volts)
        } else {
            0.0
        };
        let plant_hz = self.plant.equilibrium(y, bias).map_or(f64::NAN, |rest| {
            self.plant.natural_frequency_hz(&rest, bias)
        });
        let drive_hz = seen.ac_phase_step.map_or(f64::NAN, |step| {
            f64::from(self.settings.tick_hz) * f64::from(step) / 4_294_967_296.0
        });
        Tracked {
            seconds,
            plant_hz,
            drive_hz,
            measured_hz: f64::from(seen.tracked_hz),
            quality_factor: f64::from(seen.quality_factor),
            bias_volts: bias,
        }
    }

    /// This tick's measurements.
    fn inputs(
        &self,
        noise: &mut Noise,
        reading: &mut f64,
        k: u64,
        t: f64,
        y: &Vector,
        membrane_volts: f64,
    ) -> Inputs {
        let Some(sensor) = self.sensor else {
            return Inputs::NONE;
        };
        let due = k.is_multiple_of(u64::from(sensor.every_ticks.max(1)));
        let stuck = sensor.stuck_after_seconds.is_some_and(|at| t >= at) && reading.is_finite();
        let stretch = if !due {
            None
        } else if stuck {
            Some(*reading as f32)
        } else {
            let mut x = y[0] + sensor.noise * noise.gaussian();
            if sensor.resolution > 0.0 {
                x = (x / sensor.resolution).round() * sensor.resolution;
            }
            *reading = x;
            Some(x as f32)
        };
        Inputs {
            stretch,
            amplifier_volts: sensor.amplifier_monitor.then_some(membrane_volts as f32),
            current_amps: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::open_loop::{simulate, Choice, OpenLoop, Start};
    use de_resonator::REFERENCE_DEVICE;

    /// The plant's monitor finds a crossing that comes and goes within one tick, at its
    /// time: a 9360 V step from the pre-stretch (an ideal amplifier, no networks or damping:
    /// the plant is the core's model restated) enters §6.2's region for about a millisecond
    /// inside one 5 ms tick, where no tick's end sees it. Its time agrees with the
    /// reference's event on DOP853's dense output (`simulate`, the core's model) to 1e-9 s.
    #[test]
    fn the_plant_monitor_finds_a_crossing_within_a_tick() {
        let text = "name = \"t\"\ndescription = \"t\"\nduration_seconds = 0.03\n\
                    [controller]\ntarget_hz = 44.0\n";
        let mut run = crate::scene::parse(text).unwrap().run;
        run.plant.params = REFERENCE_DEVICE;
        run.plant.amplifier = plant::AmplifierModel {
            gain: 1.0,
            bandwidth_hz: f64::INFINITY,
            slew_volts_per_second: f64::INFINITY,
            rail_volts: f64::INFINITY,
        };
        run.plant.branches.clear();
        run.plant.leakage = plant::Leakage::NONE;
        run.settings.tick_hz = 200.0;
        let volts = 9360.0;
        let mut bench = run.bench(false);
        for k in 0..6 {
            run.advance(&mut bench, k, volts).unwrap();
            // No tick's end fails: only the search within the tick sees the excursion.
            let end = (k + 1) as f64 / 200.0;
            assert_eq!(run.crossing(&bench.y, end, volts), None, "tick {k}");
        }
        let (mode, at) = bench.crossing.expect("the plant crossed");
        let reference = simulate(
            &OpenLoop {
                params: REFERENCE_DEVICE,
                bias_volts: volts,
                ac_volts: 0.0,
                drive_hz: 0.0,
                duration_seconds: 0.03,
                start: Start::Prestretch,
                y0: None,
                tolerance: None,
            },
            Choice::Reference,
            1e-3,
        )
        .unwrap();
        let (their_mode, their_at) = reference.first_limit.unwrap();
        assert_eq!(mode, their_mode);
        assert!((at - their_at).abs() < 1e-9, "{at} s vs {their_at} s");
        let (stretch, _) = bench.crossing_state.unwrap();
        let (their_stretch, _) = reference.first_limit_state.unwrap();
        assert!(
            (stretch - their_stretch).abs() < 1e-9,
            "{stretch} vs {their_stretch}"
        );
        assert!((0.010..0.015).contains(&at), "{at}");
    }
}
