//! Instruction counts on the target: run under QEMU with `-icount shift=0`
//! (`QEMU_ICOUNT=1 cargo run --release --bin count`), where virtual time advances one
//! nanosecond per instruction, so SysTick at the 168 MHz core clock counts one tick per
//! 168/1000 instructions... i.e. instructions = ticks × 1000/168. Each figure is an average
//! over repeated calls, loop overhead included.
#![no_std]
#![no_main]

use core::hint::black_box;

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use de_resonator::acquire::{Block, Channel, ChannelSpec, FrontEnd, Reader};
use de_resonator::board::runner::Ticker;
use de_resonator::board::tick;
use de_resonator::wire::stream::{Telemetry, FRAME_BYTES};
use de_resonator::{
    Controller, Dac8551, Device, Drive, Inputs, Integrator, Method, OutputStage, State, Table,
    Tuner, REFERENCE_DEVICE,
};
use de_resonator_firmware::reference::{amplifier, device, settings, BATCH_TABLE, TABLE};
use de_resonator_firmware::stand_in::{EnableLine, RecordingBus};
use de_resonator_firmware::{exit, stack};

/// Instructions per call of `f`, averaged over `n` calls.
fn count(n: u32, mut f: impl FnMut()) -> u32 {
    let start = SYST::get_current();
    for _ in 0..n {
        f();
    }
    let end = SYST::get_current();
    let ticks = start.wrapping_sub(end) & 0x00FF_FFFF;
    (ticks as f32 * (1000.0 / 168.0) / n as f32) as u32
}

fn integrator(method: Method) -> Option<Integrator<f32>> {
    let dev = Device::new(REFERENCE_DEVICE.cast::<f32>()).ok()?;
    let drive = Drive::from_volts(&dev, 7450.0, 100.0, 40.0);
    let start = State {
        stretch: dev.stretch_for_bias(7450.0, dev.scan_end_stretch())?,
        velocity: 0.0,
    };
    // One step of the method itself: 0.9 of the guard's largest stable step (no substeps).
    let range = dev.model_range();
    let step = de_resonator::model::motion::max_stable_step_seconds(&dev, &drive, method, range)
        .map_or(1e-3, |h| 0.9 * h);
    Integrator::new(dev, drive, method, step, range, start, false).ok()
}

#[cortex_m_rt::entry]
fn main() -> ! {
    stack::paint();
    let Some(peripherals) = cortex_m::Peripherals::take() else {
        exit(1)
    };
    let mut syst = peripherals.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(0x00FF_FFFF);
    syst.clear_current();
    syst.enable_counter();

    let n = count(1000, cortex_m::asm::nop);
    defmt::info!(
        "calibration, an empty loop with one nop: {=u32} instructions",
        n
    );
    for method in [Method::Rk4, Method::Verlet, Method::ImplicitMidpoint] {
        let Some(mut it) = integrator(method) else {
            exit(1)
        };
        let n = count(1000, || {
            let _ = black_box(it.step());
        });
        defmt::info!("{=str} step: {=u32} instructions", method.name(), n);
    }
    let Ok(dev) = Device::new(REFERENCE_DEVICE.cast::<f32>()) else {
        exit(1)
    };
    let drive = Drive::from_volts(&dev, 7450.0, 100.0, 40.0);
    let state = State {
        stretch: 2.19,
        velocity: 0.01,
    };
    let n = count(1000, || {
        let _ = black_box(dev.acceleration(black_box(state), black_box(0.05)));
    });
    defmt::info!("equation of motion, one evaluation: {=u32} instructions", n);
    let n = count(1000, || {
        let _ = black_box(drive.bias_dimless_squared_at(black_box(12.5)));
    });
    defmt::info!("drive, one evaluation (sine): {=u32} instructions", n);
    math_kernels();
    let n = count(4, || {
        let tuner = Tuner::new(black_box(dev));
        let _ = black_box(tuner.tune(black_box(44.0), 0.05));
    });
    defmt::info!(
        "tuning solve (limit + bias for 44 Hz): {=u32} instructions",
        n
    );
    let tuner = Tuner::new(dev);
    let n = count(16, || {
        let _ = black_box(tuner.tune(black_box(44.0), 0.05));
    });
    defmt::info!("bias solve with the limit known: {=u32} instructions", n);
    let Ok(table) = Table::parse(TABLE) else {
        exit(1)
    };
    let n = count(1000, || {
        let _ = black_box(table.bias_volts(black_box(44.0)));
    });
    defmt::info!("table lookup: {=u32} instructions", n);
    let n = count(8, || {
        let _ = black_box(Table::parse(black_box(TABLE)));
    });
    defmt::info!("table check (CRC, order): {=u32} instructions", n);
    let Ok(amp) = amplifier() else { exit(1) };
    let Ok((mut c, _)) = Controller::start(device(), TABLE, amp, settings()) else {
        exit(1)
    };
    let n = count(500, || {
        let _ = black_box(c.tick(Inputs::NONE));
    });
    defmt::info!("controller tick on the ramp: {=u32} instructions", n);
    // On to the AC drive (tick 995 with the reference settings), where each tick takes a sine.
    while c.phase() != de_resonator::Phase::Driving {
        c.tick(Inputs::NONE);
    }
    let n = count(1000, || {
        let _ = black_box(c.tick(Inputs::NONE));
    });
    defmt::info!("controller tick with the AC drive: {=u32} instructions", n);
    let mut sample = 2.19f32;
    let n = count(1000, || {
        // Samples that differ, as a real sensor's do (equal ones in a row mean stuck).
        sample += 1e-6;
        let _ = black_box(c.tick(Inputs::stretch(black_box(sample))));
    });
    defmt::info!(
        "controller tick with the AC drive and a sensor sample: {=u32} instructions",
        n
    );
    for sensing in [Sensing::Current, Sensing::Stretch] {
        let fe = front_end(sensing);
        let block = block_of(&fe, [1e-6, 7450.0, 2.19], 10, 0);
        let mut reader = Reader::new(fe, 10);
        let n = count(1000, || {
            let _ = black_box(reader.inputs(black_box(&block)));
        });
        defmt::info!(
            "the block of a tick through the front end ({=usize} channels): {=u32} instructions",
            fe.fitted().count(),
            n
        );
        // A block short of a buffer (an interrupt late by one, the tick after a stall).
        let short = block_of(&fe, [1e-6, 7450.0, 2.19], 5, 0);
        let n = count(1000, || {
            let _ = black_box(reader.inputs(black_box(&short)));
        });
        defmt::info!(
            "the block of a tick short of a buffer, through the front end (by its mean; {=usize} channels): {=u32} instructions",
            fe.fitted().count(),
            n
        );
        // A stall re-armed before the tick (its first: recovered, its tick reads nothing).
        let mut stalled = short;
        stalled.stalled(de_resonator::acquire::Stall::Overrun);
        let mut fresh = Reader::new(fe, 10);
        let n = count(1, || {
            let _ = black_box(fresh.inputs(black_box(&stalled)));
        });
        defmt::info!(
            "the block of a stalled tick, recovered from, through the front end ({=usize} channels): {=u32} instructions",
            fe.fitted().count(),
            n
        );
        let mut b = Block::EMPTY;
        let codes = [2047u16; 15];
        let n = count(100, || {
            b.add_scans(black_box(&fe), black_box(&codes[..5 * fe.fitted().count()]));
        });
        defmt::info!(
            "a DMA buffer of 5 scans into the block (the DMA's task, not the tick): {=u32} instructions",
            n
        );
    }
    {
        let mut bus = RecordingBus::new(None);
        let mut enable = EnableLine::default();
        let mut stage = OutputStage::new(Dac8551::new(&mut bus), &mut enable);
        let mut slot = Some(c.clone());
        let n = count(1000, || {
            let _ = black_box(tick::drive(&mut slot, &mut stage, Ok(Inputs::NONE)));
        });
        defmt::info!(
            "the board's tick with the AC drive (the controller's and the DAC frame): {=u32} instructions",
            n
        );
    }
    let n = count(1, || {
        let _ = black_box(Controller::start(device(), TABLE, amp, settings()));
    });
    defmt::info!(
        "controller boot (all checks, plan in the model): {=u32} instructions",
        n
    );

    trim_cycle(Sensing::Stretch, None, 0);
    trim_cycle(Sensing::Current, None, 0);
    trim_cycle(Sensing::Stretch, Some(0.2), 3000);

    defmt::info!(
        "stack, deepest over all of the above, from the top of RAM: {=u32} bytes",
        stack::used_below(stack::top())
    );
    // Stack high-water of each boot stage and of a tick with its DAC frame, from here.
    let mut slot = None;
    let Ok(_) = deepest("the whole boot, in place as the firmware boots", || {
        let inputs = front_end(Sensing::Stretch).input_noise(10);
        Controller::start_in(&mut slot, device(), TABLE, (amp, inputs), settings())
    }) else {
        exit(1)
    };
    let Ok((mut c, boot)) = deepest("boot from the table", || {
        Controller::from_table(device(), TABLE, amp, settings())
    }) else {
        exit(1)
    };
    let Ok(boot) = deepest("cross-check by the direct solve", || {
        c.cross_check(boot, TABLE)
    }) else {
        exit(1)
    };
    let Ok(_) = deepest("plan run through the model", || c.check_plan(boot)) else {
        exit(1)
    };
    let mut dac = Dac8551::new(RecordingBus::new(None));
    let _ = deepest("controller tick and its DAC frame", || {
        let out = c.tick(Inputs::stretch(2.19));
        black_box(dac.write(out.code))
    });
    exit(0)
}

/// Run `f` on a freshly painted stack and log the most stack it used below this frame.
fn deepest<R>(what: &str, f: impl FnOnce() -> R) -> R {
    let mark = stack::pointer();
    stack::paint();
    let result = black_box(f());
    defmt::info!(
        "stack for {=str}: {=u32} bytes",
        what,
        stack::used_below(mark)
    );
    result
}

/// The f32 functions the firmware would use, one call each (argument varied so nothing is
/// folded): the core's kernels and libm against micromath (errors: tests/math_kernels.rs).
fn math_kernels() {
    use de_resonator::Real;
    use micromath::F32Ext;
    type Kernel = (&'static str, fn(f32) -> f32);
    let kernels: [Kernel; 13] = [
        ("sin, the core's kernel", |x| Real::sin(x)),
        ("sin, libm sinf", libm::sinf),
        ("sin, micromath", |x| F32Ext::sin(x)),
        ("cos, libm cosf", libm::cosf),
        ("cos, micromath", |x| F32Ext::cos(x)),
        ("sqrt, libm sqrtf", libm::sqrtf),
        ("sqrt, micromath", |x| F32Ext::sqrt(x)),
        ("1/sqrt, 1 / libm sqrtf", |x| 1.0 / libm::sqrtf(x)),
        ("1/sqrt, micromath invsqrt", |x| F32Ext::invsqrt(x)),
        ("ln, libm logf", libm::logf),
        ("ln, micromath", |x| F32Ext::ln(x)),
        ("exp, libm expf", libm::expf),
        ("exp, micromath", |x| F32Ext::exp(x)),
    ];
    for (name, f) in kernels {
        let mut x = 0.3f32;
        let n = count(1000, || {
            x = black_box(x) + 0.001;
            let _ = black_box(f(black_box(x)));
        });
        defmt::info!("math: {=str}: {=u32} instructions", name, n);
    }
}

/// How the controller senses the plant in a counted cycle.
#[derive(Clone, Copy, PartialEq)]
enum Sensing {
    /// The displacement sensor's stretch.
    Stretch,
    /// The amplifier's current only (self-sensing): the change of the membrane's charge
    /// C(λ)·Φ over the tick (model.md §8).
    Current,
}

/// The counted board's analog front end (the e2e test's, a wider current monitor): the
/// current monitor (±490 µA about mid-scale: a 200 V pulse's step in a tick is 106 µA, with
/// the AC's more) and the HV monitor (0-10 kV from code 100) always, a displacement sensor
/// (λ1 1.0-3.0 over codes 200-3900) where it senses the stretch; ten scans a tick.
fn front_end(sensing: Sensing) -> FrontEnd {
    let spec = |input, zero_code, per_count, low, high| {
        Some(ChannelSpec {
            input,
            zero_code,
            per_count,
            low,
            high,
            noise_codes: 1.0,
        })
    };
    FrontEnd {
        scan_hz: 10_000.0,
        channels: [
            spec(10, 2047.5, 2.5e-7, -4.9e-4, 4.9e-4),
            spec(11, 100.0, 10_000.0 / 3800.0, -100.0, 10_000.0),
            match sensing {
                Sensing::Stretch => spec(12, -1650.0, 5.405_405_4e-4, 1.0, 3.0),
                Sensing::Current => None,
            },
        ],
    }
}

/// The block the DMA would give for one tick: `scans` scans of each fitted channel's reading
/// as its (rounded, in-range) code, a count of noise alternating so no sample repeats for long.
fn block_of(fe: &FrontEnd, readings: [f32; 3], scans: u32, k: u32) -> Block {
    let mut block = Block::EMPTY;
    for s in 0..scans {
        for (channel, spec) in fe.fitted() {
            let reading = match channel {
                Channel::Current => readings[0],
                Channel::Amplifier => readings[1],
                Channel::Stretch => readings[2],
            };
            let dither = if (k + s).is_multiple_of(2) { 0.5 } else { -0.5 };
            block.add(channel, spec.adc_code(reading + dither * spec.per_count));
        }
    }
    block
}

/// The membrane's charge C(λ)·Φ, C(λ) = ε·L1A·L2·λ²·λ2p²/H (model.md §8), C.
fn charge_coulombs(p: &de_resonator::DeviceParams<f32>, stretch: f32, volts: f32) -> f32 {
    p.capacitance_farads(stretch) * volts
}

/// The same tick had its block been short of a buffer (an interrupt late by one, the tick
/// after a stall), or stalled and re-armed (its first stall: its tick reads nothing), on
/// copies of the reader: the dearer (apart from the cycle's loop, so as not to change how it
/// is compiled).
#[inline(never)]
fn other_blocks(reader: &Reader, fe: &FrontEnd, readings: [f32; 3], k: u32) -> u32 {
    let scans = 10;
    let mut short = block_of(fe, readings, scans / 2, k);
    let (mut copy, mut result) = (*reader, Ok(Inputs::NONE));
    let n_short = count(1, || result = copy.inputs(black_box(&short)));
    short.stalled(de_resonator::acquire::Stall::Overrun);
    let mut copy = *reader;
    let n_stalled = count(1, || result = copy.inputs(black_box(&short)));
    if result.is_err() {
        defmt::error!("the counted board's stalled block: {}", result);
        exit(1)
    }
    n_short.max(n_stalled)
}

/// A whole trim cycle (ramp to the probe bias, hold, pulse, ring, solve, retune, ... to the AC
/// drive), the reference device itself the plant (f32 RK4 between ticks, not counted) read
/// through the board's front end (its block of ADC codes made between ticks, as the DMA's
/// task does): the worst of the board's tick (the budget's figure: the call the firmware's
/// tick task makes, `Ticker::tick_block`), the stream's record, and the solve (outside the
/// tick) apart. With `track_seconds`, on for `track_ticks` of tracked drive
/// (the plant damped to Q = 30, as a driven resonance needs), counting the tracked ticks'
/// worst too.
fn trim_cycle(sensing: Sensing, track_seconds: Option<f32>, track_ticks: u32) {
    use de_resonator::{Phase, Settings};
    let Ok(amp) = amplifier() else { exit(1) };
    let s = Settings {
        trim_tolerance: Some(1e-3),
        ac_volts: 100.0,
        ac_hz: if track_seconds.is_some() { 44.0 } else { 40.0 },
        track_seconds,
        // Self-sensing: λ from C as well, under a ±20 V probe, checked at the holds against
        // the capacitance of a batch's table (model.md §10; 45 Hz: under the batch's cap).
        probe_volts: matches!(sensing, Sensing::Current).then_some(20.0),
        probe_hz: 500.0,
        target_hz: if sensing == Sensing::Current {
            45.0
        } else {
            settings().target_hz
        },
        ..settings()
    };
    let table = if sensing == Sensing::Current {
        BATCH_TABLE
    } else {
        TABLE
    };
    // A drive at the resonance is checked with the damping the device is told (model.md
    // §7): Q 60 at 44 Hz, half the plant's below.
    let mut told = device();
    if track_seconds.is_some() {
        told.damping = told.effective_mass() * core::f32::consts::TAU * 44.0 / 60.0;
    }
    let Ok((c, _)) = Controller::start(told, table, amp, s) else {
        exit(1)
    };
    let mut slot = Some(c);
    let mut ticker = Ticker::new();
    let mut bus = RecordingBus::new(None);
    let mut enable = EnableLine::default();
    let mut stage = OutputStage::new(Dac8551::new(&mut bus), &mut enable);
    if stage.enable().is_err() {
        exit(1)
    }
    let fe = front_end(sensing);
    let scans = fe.check(s.tick_hz).unwrap_or_else(|_| exit(1));
    let mut reader = Reader::new(fe, scans);
    let mut params = device();
    if track_seconds.is_some() {
        // c = M·ω/Q at 44 Hz, Q = 30.
        params.damping = params.effective_mass() * core::f32::consts::TAU * 44.0 / 30.0;
    }
    let Ok(dev) = Device::new(params) else {
        exit(1)
    };
    let rest = State {
        stretch: dev.prestretch_1(),
        velocity: 0.0,
    };
    let range = dev.model_range();
    let drive = Drive::constant(&dev, 0.0);
    let Ok(mut plant) = Integrator::new(dev, drive, Method::Rk4, 1e-3, range, rest, true) else {
        exit(1)
    };
    let (mut worst, mut worst_phase, mut solves, mut solve_most) = (0, Phase::Ramping, 0, 0);
    let mut worst_front_end = 0;
    let (mut worst_record, mut worst_framing) = (0, 0);
    let mut telemetry = Telemetry::default();
    telemetry.set(Some(1));
    let mut frame = [0u8; FRAME_BYTES];
    let (mut tracked, mut worst_tracked) = (0u32, 0);
    let (mut charge, mut amps, mut volts) = (0.0f32, 0.0f32, 0.0f32);
    for k in 0..40_000 {
        let Some(phase) = slot.as_ref().map(Controller::phase) else {
            exit(1)
        };
        let stretch = plant.state().stretch;
        let block = block_of(&fe, [amps, volts, stretch], scans, k);
        // The front end on this block (a copy of the reader), and on the same tick's block
        // short of a buffer or stalled: what those would add to the board's tick.
        let (mut copy, mut read) = (reader, Ok(Inputs::NONE));
        let n_whole = count(1, || read = copy.inputs(black_box(&block)));
        if let Err(e) = read {
            defmt::error!("the counted board's block: {}", e);
            exit(1)
        }
        let n_other = other_blocks(&reader, &fe, [amps, volts, stretch], k);
        // The board's tick as the firmware's tick task calls it.
        let n_tick = count(1, || {
            black_box(ticker.tick_block(&mut reader, black_box(&block), &mut slot, &mut stage));
        });
        let done = *ticker.last();
        let Some(sent) = done.ticked else { exit(1) };
        let n = n_tick + n_other.saturating_sub(n_whole);
        worst_front_end = worst_front_end.max(n_whole.max(n_other));
        // The telemetry stream at the tick rate, as the idle loop takes it after the tick:
        // the record under the locks (a latency for a tick that comes meanwhile, not the
        // tick's work), then its frame outside them.
        let mut record = None;
        let n_record = count(1, || {
            record = telemetry.record(done.tick, true, slot.as_ref(), &done.readings);
        });
        if let Some(record) = record {
            let n_framing = count(1, || {
                black_box(record.frame(&mut frame));
            });
            worst_record = worst_record.max(n_record);
            worst_framing = worst_framing.max(n_framing);
        }
        if n > worst {
            (worst, worst_phase) = (n, phase);
        }
        if phase == Phase::Driving && track_seconds.is_some() {
            tracked += 1;
            worst_tracked = worst_tracked.max(n);
        }
        let Some(c) = slot.as_mut() else { exit(1) };
        if let Some(job) = c.trim_job() {
            if solves == 0 && sensing == Sensing::Stretch && track_seconds.is_none() {
                let _ = deepest("the trim's solve (the work task)", || job.solve());
            }
            let mut result = None;
            let n = count(1, || result = Some(job.solve()));
            solves += 1;
            solve_most = solve_most.max(n);
            if let Some(result) = result {
                c.trim_done(result);
            }
        }
        volts = sent.output.volts;
        if plant.set_drive(Drive::constant(&dev, volts)).is_err() || plant.step().is_err() {
            exit(1)
        }
        let now = charge_coulombs(&params, plant.state().stretch, volts);
        (amps, charge) = ((now - charge) * 1000.0, now);
        let done = match track_seconds {
            Some(_) => tracked >= track_ticks,
            None => c.phase() == Phase::Driving,
        };
        if done || c.phase() == Phase::Faulted {
            break;
        }
    }
    let Some(c) = slot.as_ref() else { exit(1) };
    if c.phase() != Phase::Driving {
        if let Some(fault) = c.latched_fault() {
            defmt::error!("fault: {}", fault);
        }
        defmt::error!("the trim cycle did not reach the AC drive: {}", c.phase());
        exit(1)
    }
    let what = match (sensing, track_seconds) {
        (Sensing::Stretch, None) => "trim",
        (Sensing::Stretch, Some(_)) => "trim then tracking",
        (Sensing::Current, _) => "sensorless trim (the current only, and λ from C under the probe, checked against a batch's table)",
    };
    defmt::info!(
        "board tick with {=str}, worst over the cycle: {=u32} instructions ({}; the call the firmware's tick task makes, `Ticker::tick_block`, over the stand-in bus and pin: the block through the front end, the controller, the DAC frame, a fault's entry; each tick's worst over its block whole, short of a buffer or stalled, the front end at most {=u32})",
        what,
        worst,
        worst_phase,
        worst_front_end
    );
    defmt::info!(
        "the telemetry stream at every tick with {=str}, in the idle loop: the record under the locks at most {=u32} instructions, its frame (CRC-32, COBS) at most {=u32}",
        what,
        worst_record,
        worst_framing
    );
    defmt::info!(
        "{=str} solve outside the tick ({=u32} solves): at most {=u32} instructions",
        what,
        solves,
        solve_most
    );
    if let Some(sensed) = c.sensed() {
        let (_, high) = dev.plausible_stretch();
        let rest = dev.stretch_for_bias(c.plan().bias_volts, high);
        defmt::info!(
            "λ from C, the last window's mean: {=f32} ± {=f32} (the plant's equilibrium at the bias, the AC drive's centre: {=f32})",
            sensed.stretch,
            sensed.sigma,
            rest.unwrap_or(f32::NAN)
        );
    }
    if track_seconds.is_some() {
        let hz = c.tracked().map_or(f32::NAN, |l| l.natural_hz);
        let q = c.tracked().map_or(f32::NAN, |l| l.quality_factor);
        defmt::info!(
            "board tick with tracking, worst over {=u32} tracked ticks: {=u32} instructions (f {=f32} Hz, Q {=f32})",
            tracked,
            worst_tracked,
            hz,
            q
        );
    }
}
