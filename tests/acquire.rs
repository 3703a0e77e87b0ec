//! The acquisition's processing (`acquire`) on samples made from the plant's signals: the
//! reference device ring_stretch at a bias, its stretch, its current (the membrane's charge, model.md
//! §8) and the amplifier's voltage, through a front end (noise, quantisation, the ADC's
//! rails). Each tick's reading is right within its stated error (half a count and five
//! standard errors of the noise), or a named fault: a rail-stuck input, an open input, a
//! wrong gain in the image, a stopped DMA.

mod common;

use common::Rng;
use de_resonator::acquire::{
    Block, Channel, ChannelSpec, FrontEnd, FrontEndError, InputError, FULL_SCALE_CODE,
};
use de_resonator::board::stage::OutputStage;
use de_resonator::board::tick;
use de_resonator::{
    Dac8551, Device, Drive, Fault, Inputs, Integrator, Method, Phase, Settings, State,
    REFERENCE_DEVICE,
};

const TICK_HZ: f64 = 1_000.0;
const SCANS_PER_TICK: usize = 10;
/// One code of the reference amplifier (2.5 V reference, gain 4000, 16 bits), V.
const DAC_VOLTS: f32 = 2.5 * 4000.0 / 65536.0;

/// A standard normal draw (Box–Muller).
fn normal(rng: &mut Rng) -> f64 {
    let u = rng.unit().max(1e-300);
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * rng.unit()).cos()
}

/// The ADC's code for a reading through `spec` with `sigma_counts` of noise: rounded, held
/// within the rails as the converter is.
fn code(spec: &ChannelSpec, reading: f64, sigma_counts: f64, rng: &mut Rng) -> u16 {
    let c = f64::from(spec.zero_code) + reading / f64::from(spec.per_count);
    (c + sigma_counts * normal(rng))
        .round()
        .clamp(0.0, f64::from(FULL_SCALE_CODE)) as u16
}

/// The plant's signals at one scan: stretch, the current over the scan's interval (the
/// charge's change over it, A), the amplifier's voltage.
#[derive(Clone, Copy)]
struct Scan {
    stretch: f64,
    amps: f64,
    volts: f64,
}

/// The reference device from rest at its pre-stretch, the bias applied at once (it rings),
/// sampled `scans` times at the scan rate.
fn plant_scans(bias_volts: f64, scans: usize) -> Vec<Scan> {
    let device = Device::new(REFERENCE_DEVICE).unwrap();
    let h = 1.0 / (TICK_HZ * SCANS_PER_TICK as f64);
    let rest = State {
        stretch: device.prestretch_1(),
        velocity: 0.0,
    };
    let mut model = Integrator::new(
        device,
        Drive::constant(&device, bias_volts),
        Method::Rk4,
        h,
        device.model_range(),
        rest,
        true,
    )
    .unwrap();
    let mut out = Vec::with_capacity(scans);
    let mut before = model.state().stretch;
    for _ in 0..scans {
        let after = model.step().unwrap().stretch;
        let charge = |l: f64| bias_volts * REFERENCE_DEVICE.capacitance_farads(l);
        out.push(Scan {
            stretch: after,
            amps: (charge(after) - charge(before)) / h,
            volts: bias_volts,
        });
        before = after;
    }
    out
}

/// A board's front end for the reference device: the current monitor bipolar about
/// mid-scale over ±`amps_full` A, the HV monitor 0..10 kV with a live zero at code 100, a
/// displacement sensor over λ1 ± 30% from code 200 to 3900.
fn front_end(amps_full: f32) -> FrontEnd {
    let l = REFERENCE_DEVICE.prestretch_1 as f32;
    let (low, high) = (0.7 * l, 1.3 * l);
    let per_count = (high - low) / 3700.0;
    FrontEnd {
        scan_hz: (TICK_HZ * SCANS_PER_TICK as f64) as f32,
        channels: [
            Some(ChannelSpec {
                input: 10,
                zero_code: 2047.5,
                per_count: amps_full / 2000.0,
                low: -amps_full,
                high: amps_full,
                noise_codes: 0.0,
            }),
            Some(ChannelSpec {
                input: 11,
                zero_code: 100.0,
                per_count: 10_000.0 / 3800.0,
                low: -100.0,
                high: 10_000.0,
                noise_codes: 0.0,
            }),
            Some(ChannelSpec {
                input: 12,
                zero_code: 200.0 - low / per_count,
                per_count,
                low,
                high,
                noise_codes: 0.0,
            }),
        ],
    }
}

/// The block of one tick's scans as the DMA writes them (interleaved in scan order), through
/// the board's true front end `board`.
fn block(board: &FrontEnd, scans: &[Scan], sigma_counts: f64, rng: &mut Rng) -> Block {
    let mut dma = Vec::new();
    for s in scans {
        for (channel, spec) in board.fitted() {
            let reading = match channel {
                Channel::Current => s.amps,
                Channel::Amplifier => s.volts,
                Channel::Stretch => s.stretch,
            };
            dma.push(code(spec, reading, sigma_counts, rng));
        }
    }
    let mut b = Block::EMPTY;
    // The DMA's two halves, added as their interrupts come.
    let (first, second) = dma.split_at(dma.len() / 2 / 3 * 3);
    b.add_scans(board, first);
    b.add_scans(board, second);
    b
}

/// The peak of the ring's current at `bias_volts`, A.
fn peak_amps(scans: &[Scan]) -> f64 {
    scans.iter().map(|s| s.amps.abs()).fold(0.0, f64::max)
}

/// With noise of 0, 1 and 3 counts, every tick's three readings are the plant's means over
/// the tick within half a count and five standard errors of the noise's mean; the current's
/// mean is the charge's change over the tick (a conservation law, not a mean of samples).
#[test]
fn readings_are_the_plants_means_within_the_stated_error() {
    let bias = 6000.0;
    let ticks = 300;
    let scans = plant_scans(bias, ticks * SCANS_PER_TICK);
    let amps_full = (1.5 * peak_amps(&scans)) as f32;
    let fe = front_end(amps_full);
    assert_eq!(fe.check(TICK_HZ as f32), Ok(SCANS_PER_TICK as u32));
    let device = Device::new(REFERENCE_DEVICE).unwrap();
    for sigma in [0.0, 1.0, 3.0] {
        let mut rng = Rng(0x5eed + sigma as u64);
        let mut worst = [0.0f64; 3];
        for k in 0..ticks {
            let tick = &scans[k * SCANS_PER_TICK..(k + 1) * SCANS_PER_TICK];
            let b = block(&fe, tick, sigma, &mut rng);
            assert_eq!(b.samples(Channel::Stretch), SCANS_PER_TICK as u32);
            let got = fe.inputs(&b).unwrap_or_else(|e| panic!("tick {k}: {e}"));
            let n = SCANS_PER_TICK as f64;
            let before = if k == 0 {
                device.prestretch_1()
            } else {
                scans[k * SCANS_PER_TICK - 1].stretch
            };
            let after = tick[SCANS_PER_TICK - 1].stretch;
            let charge_amps = bias
                * (REFERENCE_DEVICE.capacitance_farads(after)
                    - REFERENCE_DEVICE.capacitance_farads(before))
                * TICK_HZ;
            let truth = [
                charge_amps,
                bias,
                tick.iter().map(|s| s.stretch).sum::<f64>() / n,
            ];
            let read = [
                got.current_amps.unwrap(),
                got.amplifier_volts.unwrap(),
                got.stretch.unwrap(),
            ];
            for (i, (spec, (t, r))) in fe
                .channels
                .iter()
                .flatten()
                .zip(truth.iter().zip(read))
                .enumerate()
            {
                let counts = (f64::from(r) - t).abs() / f64::from(spec.per_count).abs();
                let bound = 0.5 + 5.0 * sigma / n.sqrt() + 1e-3;
                assert!(
                    counts <= bound,
                    "σ {sigma}, tick {k}, channel {i}: {counts} counts off"
                );
                worst[i] = worst[i].max(counts);
            }
        }
        eprintln!(
            "σ {sigma} counts: worst error in counts (current, amplifier, stretch) {worst:?}"
        );
    }
}

/// An input stuck at either rail, and an open input pulled to ground by its bias resistor
/// (a few counts of noise above 0), are faults that name the channel and the rail.
#[test]
fn rail_stuck_and_open_inputs_are_named_faults() {
    let scans = plant_scans(6000.0, SCANS_PER_TICK);
    let fe = front_end((1.5 * peak_amps(&plant_scans(6000.0, 200))) as f32);
    let mut rng = Rng(7);
    for channel in Channel::ALL {
        for (what, make) in [
            (
                "stuck high",
                (|_: &mut Rng| FULL_SCALE_CODE) as fn(&mut Rng) -> u16,
            ),
            ("stuck low", |_| 0),
            ("open", |rng| (rng.unit() * 4.0) as u16),
        ] {
            let mut b = block(&fe, &scans, 1.0, &mut rng);
            // The channel's samples replaced: a block made again with this channel's codes.
            let mut dma = Vec::new();
            for _ in 0..SCANS_PER_TICK {
                for (c, spec) in fe.fitted() {
                    let good = code(spec, 0.5 * f64::from(spec.low + spec.high), 1.0, &mut rng);
                    dma.push(if c == channel { make(&mut rng) } else { good });
                }
            }
            b = {
                let _ = b.take();
                let mut fresh = Block::EMPTY;
                fresh.add_scans(&fe, &dma);
                fresh
            };
            let err = fe.inputs(&b).unwrap_err();
            match err {
                InputError::AtRail { channel: c, .. } => assert_eq!(c, channel, "{what}"),
                other => panic!("{what} {channel:?}: {other:?}"),
            }
            let said = Fault::Input(err).to_string();
            assert!(
                said.contains(channel.name()) && said.contains("rail"),
                "{said}"
            );
        }
    }
}

/// A wrong gain in the image: the stretch's gain about mid-span three times the board's,
/// the ring's swing reads outside its plausible range at its extremes (named), and in
/// between the reading is the wrong gain's exactly (the image's mapping, not noise); the
/// amplifier monitor's at 1.5 times the board's is inside its range, and the controller's
/// cross-check against its command names it (the amplifier disagrees) while the ramp
/// climbs, and the output comes down at the slew rate.
#[test]
fn a_wrong_gain_in_the_image_is_a_named_fault() {
    let ticks = 300;
    let scans = plant_scans(6000.0, ticks * SCANS_PER_TICK);
    let board = front_end((1.5 * peak_amps(&scans)) as f32);
    let mut rng = Rng(11);
    let mut image = board;
    let stretch = image.channels[2].as_mut().unwrap();
    let mid_code = 2047.5;
    let mid = stretch.reading(mid_code);
    stretch.per_count *= 3.0;
    stretch.zero_code = mid_code - mid / stretch.per_count;
    assert_eq!(image.check(TICK_HZ as f32).map(|_| ()), Ok(()));
    let (mut named, mut read) = (0, 0);
    for tick in scans.chunks(SCANS_PER_TICK) {
        let b = block(&board, tick, 1.0, &mut rng);
        let truth = tick.iter().map(|s| s.stretch).sum::<f64>() / SCANS_PER_TICK as f64;
        match image.inputs(&b) {
            Err(InputError::Implausible { channel, .. }) => {
                assert_eq!(channel, Channel::Stretch);
                named += 1;
            }
            Ok(i) => {
                let wrong = f64::from(mid) + 3.0 * (truth - f64::from(mid));
                let counts = (f64::from(i.stretch.unwrap()) - wrong).abs()
                    / f64::from(image.channels[2].unwrap().per_count);
                assert!(
                    counts < 0.5 + 5.0 / (SCANS_PER_TICK as f64).sqrt(),
                    "{counts}"
                );
                read += 1;
            }
            Err(other) => panic!("{other:?}"),
        }
    }
    assert!(named > 0 && read > 0, "{named} named, {read} read");

    // The amplifier's monitor read at 1.5 times its gain, the board driving the reference.
    let mut image = board;
    image.channels[0] = None;
    image.channels[2] = None;
    image.channels[1].as_mut().unwrap().per_count *= 1.5;
    let settings = Settings::for_target(44.0);
    let mut slot = Some(common::start_reference(settings).unwrap());
    let (bus, pin) = (common::Bus::default(), common::Pin::default());
    let mut stage = OutputStage::new(Dac8551::new(&bus), &pin);
    let mut sent = 0.0f64;
    let mut volts_seen = Vec::new();
    for _ in 0..20_000 {
        let mut dma = Vec::new();
        for _ in 0..SCANS_PER_TICK {
            dma.push(code(
                board.channels[1].as_ref().unwrap(),
                sent,
                1.0,
                &mut rng,
            ));
        }
        let mut b = Block::EMPTY;
        b.add_scans(&image, &dma);
        let t = tick::drive(&mut slot, &mut stage, image.inputs(&b)).unwrap();
        sent = f64::from(t.output.volts);
        volts_seen.push(t.output.volts);
        if slot.as_ref().unwrap().latched_fault().is_some() && sent == 0.0 {
            break;
        }
    }
    let fault = slot.as_ref().unwrap().latched_fault();
    assert!(
        matches!(fault, Some(Fault::AmplifierDisagrees { .. })),
        "{fault:?}"
    );
    // A step at the slew rate, and the DAC's code below it (the gate rounds down).
    let step = settings.slew_volts_per_second / settings.tick_hz + DAC_VOLTS;
    let top = volts_seen.iter().cloned().fold(0.0, f32::max);
    let peak = volts_seen.iter().position(|&v| v == top).unwrap();
    for w in volts_seen[peak..].windows(2) {
        assert!(w[1] <= w[0] && w[0] - w[1] <= step, "{w:?}");
    }
    assert_eq!(*volts_seen.last().unwrap(), 0.0);
}

/// An input error at the tick trips the controller (`Fault::Input`), latched: from the bias
/// the output comes down at the slew rate, never up, to 0 V, however long the input stays
/// bad; the fault says the channel.
#[test]
fn an_input_fault_descends_at_the_slew_rate() {
    let settings = Settings::for_target(44.0);
    let mut slot = Some(common::start_reference(settings).unwrap());
    let (bus, pin) = (common::Bus::default(), common::Pin::default());
    let mut stage = OutputStage::new(Dac8551::new(&bus), &pin);
    let mut volts = 0.0;
    while slot.as_ref().unwrap().phase() != Phase::Holding || volts == 0.0 {
        volts = tick::drive(&mut slot, &mut stage, Ok(Inputs::NONE))
            .unwrap()
            .output
            .volts;
    }
    let bias = volts;
    let bad = InputError::NoSamples {
        channel: Channel::Current,
    };
    let step = settings.slew_volts_per_second / settings.tick_hz + DAC_VOLTS;
    let ticks = (bias / step).ceil() as usize + 50;
    let mut last = bias;
    for k in 0..ticks {
        let t = tick::drive(&mut slot, &mut stage, Err(bad)).unwrap();
        let v = t.output.volts;
        assert!(v <= last && last - v <= step, "tick {k}: {last} -> {v}");
        last = v;
    }
    assert_eq!(last, 0.0);
    let fault = slot.as_ref().unwrap().latched_fault().unwrap();
    assert_eq!(fault, Fault::Input(bad));
    assert!(fault.to_string().contains("current input"), "{fault}");
}

/// A DMA buffer holds a whole part of a tick's scans, at most half of them, within its room:
/// every tick takes the same number of buffers.
#[test]
fn buffers_divide_a_ticks_scans() {
    use de_resonator::acquire::BUFFER_CODES;
    let three = front_end(1e-3);
    let mut one = three;
    one.channels[1] = None;
    one.channels[2] = None;
    for fe in [one, three] {
        let channels = fe.fitted().count() as u32;
        for scans_per_tick in 1..=300u32 {
            let b = fe.scans_per_buffer(scans_per_tick);
            assert!(b >= 1 && scans_per_tick % b == 0, "{scans_per_tick}: {b}");
            assert!((b * channels) as usize <= BUFFER_CODES);
            assert!(
                scans_per_tick == 1 || b <= scans_per_tick / 2,
                "{scans_per_tick}: {b}"
            );
        }
    }
    assert_eq!(three.scans_per_buffer(10), 5);
    assert_eq!(three.scans_per_buffer(100), 25);
    assert_eq!(one.scans_per_buffer(1), 1);
}

/// What the tick cannot read is named: a channel with no sample (the DMA stopped) and a
/// code above the ADC's full scale. Integers in the block: no code makes a NaN reading.
#[test]
fn no_samples_and_impossible_codes_are_named() {
    let fe = front_end(1e-3);
    assert_eq!(
        fe.inputs(&Block::EMPTY),
        Err(InputError::NoSamples {
            channel: Channel::Current
        })
    );
    let mut b = Block::EMPTY;
    b.add_scans(&fe, &[2047, 2000, 1000, 2047, 4096, 1000]);
    assert_eq!(
        fe.inputs(&b),
        Err(InputError::NotACode {
            channel: Channel::Amplifier,
            code: 4096
        })
    );
    // A trailing part scan is not taken for whole ones.
    let mut b = Block::EMPTY;
    b.add_scans(&fe, &[2047, 2000, 1000, 2047]);
    assert_eq!(b.samples(Channel::Current), 1);
    assert_eq!(b.samples(Channel::Stretch), 1);
    // Any codes: a reading is a number or an error, never NaN.
    let mut rng = Rng(3);
    for _ in 0..2_000 {
        let mut b = Block::EMPTY;
        let n = rng.below(40);
        let codes: Vec<u16> = (0..n).map(|_| (rng.unit() * 65536.0) as u16).collect();
        b.add_scans(&fe, &codes);
        if let Ok(i) = fe.inputs(&b) {
            for r in [i.current_amps, i.amplifier_volts, i.stretch] {
                assert!(r.unwrap().is_finite());
            }
        }
    }
}

/// The image's front end is checked: a plausible range that reaches a rail (no live zero),
/// two channels on one input, an input that does not exist, a scale of zero or NaN, and a
/// scan rate that is not a whole number a tick or beyond the ADC.
#[test]
fn a_front_end_the_board_cannot_use_is_refused() {
    let good = front_end(1e-3);
    let tick = TICK_HZ as f32;
    let with = |f: &dyn Fn(&mut FrontEnd)| {
        let mut fe = good;
        f(&mut fe);
        fe.check(tick)
    };
    assert!(matches!(
        with(&|fe| fe.channels[1].as_mut().unwrap().zero_code = 0.0),
        Err(FrontEndError::Range {
            channel: Channel::Amplifier,
            ..
        })
    ));
    assert_eq!(
        with(&|fe| fe.channels[2].as_mut().unwrap().input = 10),
        Err(FrontEndError::SameInput { input: 10 })
    );
    // No such input; the command port's RX pin (PA3, IN3); the enable line's (PB0, IN8).
    for input in [16, 3, 8] {
        assert!(matches!(
            with(&|fe| fe.channels[0].as_mut().unwrap().input = input),
            Err(FrontEndError::Input { input: i, .. }) if i == input
        ));
    }
    for bad in [0.0, f32::NAN, f32::INFINITY] {
        assert!(matches!(
            with(&|fe| fe.channels[0].as_mut().unwrap().per_count = bad),
            Err(FrontEndError::Scale { .. })
        ));
    }
    for scan_hz in [10_500.0, 500.0, 0.0, f32::NAN, 100_000.0] {
        assert!(
            matches!(
                with(&|fe| fe.scan_hz = scan_hz),
                Err(FrontEndError::ScanRate { .. })
            ),
            "{scan_hz}"
        );
    }
    // None fitted: nothing to scan, at any rate.
    assert_eq!(FrontEnd::NONE.check(tick), Ok(0));
    assert_eq!(FrontEnd::NONE.scans_per_buffer(10), 0);
    let said = with(&|fe| fe.channels[1].as_mut().unwrap().zero_code = 0.0)
        .unwrap_err()
        .to_string();
    assert!(
        said.contains("amplifier") && said.contains("live zero"),
        "{said}"
    );
}

/// The tick's reader (`Reader`: whole sums against precomputed bounds) gives what the checked
/// path (`FrontEnd::inputs`) gives, on blocks of every kind: full blocks of plausible codes
/// (to f32 rounding), and the same named error on every other (short blocks, rails, codes
/// out of range or beyond the ADC).
#[test]
fn the_ticks_reader_agrees_with_the_checked_path() {
    use de_resonator::acquire::Reader;
    let fe = front_end(1e-3);
    let scans = fe.check(TICK_HZ as f32).unwrap();
    let mut reader = Reader::new(fe, scans);
    let mut rng = Rng(17);
    // Past the power-up's wait for a first sample (tested below).
    let mut first = Block::EMPTY;
    first.add(Channel::Current, 2047);
    let _ = reader.inputs(&first);
    let (mut fast, mut slow) = (0, 0);
    for trial in 0..20_000 {
        let mut b = Block::EMPTY;
        let n = match trial % 4 {
            0 => rng.below(2 * scans as usize + 1),
            _ => scans as usize,
        };
        for _ in 0..n {
            for (_, spec) in fe.fitted() {
                // Mostly near the plausible range's edges, now and then anywhere.
                let (lo, hi) = (spec.code_of(spec.low), spec.code_of(spec.high));
                let code = match rng.below(8) {
                    0 => rng.unit() * 4200.0,
                    1 => f64::from(lo.min(hi)) + rng.range(-2.0, 2.0),
                    2 => f64::from(lo.max(hi)) + rng.range(-2.0, 2.0),
                    _ => f64::from(lo) + (f64::from(hi) - f64::from(lo)) * rng.unit(),
                };
                b.add(
                    channel_of(&fe, spec),
                    code.round().clamp(0.0, 65535.0) as u16,
                );
            }
        }
        let (want, got) = (fe.inputs(&b), reader.inputs(&b));
        match (want, got) {
            (Ok(w), Ok(g)) => {
                for (x, y) in [
                    (w.current_amps, g.current_amps),
                    (w.amplifier_volts, g.amplifier_volts),
                    (w.stretch, g.stretch),
                ] {
                    let (x, y) = (x.unwrap(), y.unwrap());
                    assert!((x - y).abs() <= 1e-5 * x.abs().max(1e-3), "{x} against {y}");
                }
                fast += 1;
            }
            (w, g) => {
                assert_eq!(w, g);
                slow += 1;
            }
        }
    }
    assert!(fast > 1000 && slow > 1000, "{fast} read, {slow} refused");
}

/// The channel a spec of `fe` belongs to.
fn channel_of(fe: &FrontEnd, spec: &ChannelSpec) -> Channel {
    fe.fitted().find(|(_, s)| *s == spec).unwrap().0
}

/// At power-up the timer, the ADC and the tick are not in phase: for the first
/// `FIRST_BUFFER_TICKS` ticks an empty block is no reading (not a fault); after them, or once a
/// sample has come, an empty block is `NoSamples` by name.
#[test]
fn an_empty_block_is_a_fault_once_the_first_samples_are_due() {
    use de_resonator::acquire::{Reader, FIRST_BUFFER_TICKS};
    let fe = front_end(1e-3);
    let scans = fe.check(TICK_HZ as f32).unwrap();
    let no_samples = Err(InputError::NoSamples {
        channel: Channel::Current,
    });
    let mut reader = Reader::new(fe, scans);
    for _ in 0..FIRST_BUFFER_TICKS {
        assert_eq!(reader.inputs(&Block::EMPTY), Ok(Inputs::NONE));
    }
    assert_eq!(reader.inputs(&Block::EMPTY), no_samples);
    // A sample in time: from then on an empty block is a fault at once.
    let mut reader = Reader::new(fe, scans);
    assert_eq!(reader.inputs(&Block::EMPTY), Ok(Inputs::NONE));
    let scans = plant_scans(6000.0, SCANS_PER_TICK);
    let mut rng = Rng(5);
    assert!(reader.inputs(&block(&fe, &scans, 1.0, &mut rng)).is_ok());
    assert_eq!(reader.inputs(&Block::EMPTY), no_samples);
}

/// The scan rate: at least two scans a tick (the DMA's buffers are not in phase with the
/// tick: one buffer a tick would leave some ticks none), and not so many buffers a tick that
/// the DMA's interrupt comes a scan (a prime number of scans larger than a buffer holds).
#[test]
fn the_scan_rate_leaves_every_tick_a_buffer_at_a_bounded_interrupt_rate() {
    let mut fe = front_end(1e-3);
    for (scan_hz, ok) in [
        (1_000.0, false),
        (2_000.0, true),
        (10_000.0, true),
        (40_000.0, true),
        // 53 scans a tick, prime and more than a buffer of three channels holds (42):
        // a buffer a scan, 53 interrupts a tick.
        (53_000.0, false),
        // Beyond the ADC: 270,000 conversions a second.
        (90_000.0, false),
    ] {
        fe.scan_hz = scan_hz;
        assert_eq!(fe.check(TICK_HZ as f32).is_ok(), ok, "{scan_hz}");
    }
}

/// A whole number of scans a tick, to 1e-4 of it (a crystal's ppm, not a different rate):
/// 10.0005 scans a tick (5e-5 off) is 10; 10.002 (2e-4 off) is refused.
#[test]
fn the_scans_a_tick_are_whole_to_a_ten_thousandth() {
    let mut fe = front_end(1e-3);
    for (per_tick, scans) in [
        (10.0, Ok(10)),
        (10.0005, Ok(10)),
        (9.9995, Ok(10)),
        (10.002, Err(())),
        (9.998, Err(())),
    ] {
        fe.scan_hz = per_tick * TICK_HZ as f32;
        assert_eq!(
            fe.check(TICK_HZ as f32).map_err(|_| ()),
            scans,
            "{per_tick}"
        );
    }
}

/// The trim's input noise is each fitted channel's tick noise at the scans a tick: the
/// stretch's and the current's (the HV monitor's is not the trim's), none where a channel is
/// not fitted. Against the noise of a mean of `n` dithered conversions, q·√((σ² + 1/12)/n).
#[test]
fn the_trims_input_noise_is_the_stretch_and_current_channels() {
    let mut fe = front_end(1e-3);
    fe.channels[0] = fe.channels[0].map(|c| ChannelSpec {
        noise_codes: 2.0,
        ..c
    });
    fe.channels[2] = fe.channels[2].map(|c| ChannelSpec {
        noise_codes: 1.0,
        ..c
    });
    let (amps_per_count, stretch_per_count) = (
        fe.channels[0].unwrap().per_count,
        fe.channels[2].unwrap().per_count,
    );
    let n = 10.0f64;
    let expect = |q: f32, sigma: f64| f64::from(q) * ((sigma * sigma + 1.0 / 12.0) / n).sqrt();
    let noise = fe.input_noise(n as u32);
    let (amps, stretch) = (noise.amps.unwrap(), noise.stretch.unwrap());
    assert!((f64::from(amps) / expect(amps_per_count, 2.0) - 1.0).abs() < 1e-5);
    assert!((f64::from(stretch) / expect(stretch_per_count, 1.0) - 1.0).abs() < 1e-5);
    fe.channels[0] = None;
    fe.channels[2] = None;
    let none = fe.input_noise(10);
    assert_eq!((none.amps, none.stretch), (None, None));
}

/// The code a reading gives (for stand-ins and studies): rounded, held within the ADC's
/// range as the converter holds its input.
#[test]
fn a_readings_code_is_rounded_and_held_in_range() {
    let spec = ChannelSpec {
        input: 10,
        zero_code: 100.0,
        per_count: 2.0,
        low: -100.0,
        high: 7_000.0,
        noise_codes: 0.0,
    };
    assert_eq!(spec.adc_code(0.0), 100);
    assert_eq!(spec.adc_code(1.2), 101);
    assert_eq!(spec.adc_code(-1_000.0), 0);
    assert_eq!(spec.adc_code(1e6), FULL_SCALE_CODE);
    assert_eq!(spec.adc_code(f32::NAN), 0);
}

/// A stall of the acquisition (silicon's ADC overrun or DMA transfer error, re-armed by the
/// firmware) is recovered from and counted: its tick reads nothing, and the next
/// `STALL_GRACE_TICKS - 1` may lack samples (the buffers the re-arm lost) and read nothing,
/// not a fault; a full block then reads as before. A second stall within `STALL_REPEAT_SECONDS` of the last recovered one is
/// the fault, named; one a second or more later is recovered from again. A block the grace
/// has run out on is `NoSamples` again.
#[test]
fn a_stall_is_recovered_once_and_a_repeat_within_a_second_is_a_fault() {
    use de_resonator::acquire::{Reader, Stall, STALL_GRACE_TICKS, STALL_REPEAT_SECONDS};
    let fe = front_end(1e-3);
    let scans_per_tick = fe.check(TICK_HZ as f32).unwrap();
    let scans = plant_scans(6000.0, SCANS_PER_TICK);
    let mut rng = Rng(11);
    let full = |rng: &mut Rng| block(&fe, &scans, 1.0, rng);
    let stalled = |why| {
        let mut b = Block::EMPTY;
        b.stalled(why);
        b
    };
    let mut reader = Reader::new(fe, scans_per_tick);
    assert!(reader.inputs(&full(&mut rng)).is_ok());
    assert_eq!(reader.recovered(), 0);
    // The stall's tick, empty: nothing read, no fault; the grace's other ticks likewise.
    assert_eq!(reader.inputs(&stalled(Stall::Overrun)), Ok(Inputs::NONE));
    for _ in 1..STALL_GRACE_TICKS {
        assert_eq!(reader.inputs(&Block::EMPTY), Ok(Inputs::NONE));
    }
    assert_eq!(reader.recovered(), 1);
    // Full blocks read again; the grace over, an empty block is the fault it always was.
    assert!(reader.inputs(&full(&mut rng)).is_ok());
    assert_eq!(
        reader.inputs(&Block::EMPTY),
        Err(InputError::NoSamples {
            channel: Channel::Current
        })
    );
    // A second stall within the window (half of it later): the fault, naming the cause.
    let mut reader = Reader::new(fe, scans_per_tick);
    assert!(reader.inputs(&full(&mut rng)).is_ok());
    assert!(reader.inputs(&stalled(Stall::TransferError)).is_ok());
    let half = (0.5 * f64::from(STALL_REPEAT_SECONDS) * TICK_HZ) as usize;
    for _ in 0..half {
        assert!(reader.inputs(&full(&mut rng)).is_ok());
    }
    assert_eq!(
        reader.inputs(&stalled(Stall::Overrun)),
        Err(InputError::Stalled {
            stall: Stall::Overrun,
            recovered: 1
        })
    );
    // A second stall past the window: recovered from again, counted.
    let mut reader = Reader::new(fe, scans_per_tick);
    assert!(reader.inputs(&stalled(Stall::Overrun)).is_ok());
    let past = (1.01 * f64::from(STALL_REPEAT_SECONDS) * TICK_HZ) as usize;
    for _ in 0..past {
        assert!(reader.inputs(&full(&mut rng)).is_ok());
    }
    assert!(reader.inputs(&stalled(Stall::TransferError)).is_ok());
    assert_eq!(reader.recovered(), 2);
    // The stall's own tick reads nothing, whatever its block holds (the re-arm cut it); the
    // next reads a block short of scans.
    let mut partial = full(&mut rng);
    partial.stalled(Stall::Overrun);
    let mut reader = Reader::new(fe, scans_per_tick);
    assert_eq!(reader.inputs(&partial), Ok(Inputs::NONE));
    let short = block(&fe, &scans[..3], 1.0, &mut rng);
    let read = reader.inputs(&short).unwrap();
    assert!(read.stretch.is_some() && read.current_amps.is_some());
}

/// The ADC's clock in use bounds the conversions: the reference front end (3 channels at
/// 10 kHz: 30,000 conversions/s) passes at 21 MHz and at the 16 MHz HSI fallback's 4 MHz
/// (the limit scales: 250,000 · 4/21 ≈ 47,600); at 20 kHz scans (60,000) the fallback refuses
/// it, naming the clock.
#[test]
fn the_adc_clock_in_use_bounds_the_conversions() {
    use de_resonator::acquire::{max_conversions_hz, MAX_CONVERSIONS_HZ};
    assert_eq!(max_conversions_hz(21.0e6), MAX_CONVERSIONS_HZ);
    let hsi_adc_hz = 16.0e6 / 4.0;
    let fe = front_end(1e-3);
    assert_eq!(fe.check_adc_clock(21.0e6), Ok(()));
    assert_eq!(fe.check_adc_clock(hsi_adc_hz), Ok(()));
    let fast = FrontEnd {
        scan_hz: 20_000.0,
        ..fe
    };
    assert_eq!(fast.check_adc_clock(21.0e6), Ok(()));
    let refused = fast.check_adc_clock(hsi_adc_hz).unwrap_err();
    assert!(matches!(refused, FrontEndError::AdcClock { .. }));
    let words = refused.to_string();
    assert!(
        words.contains("60000 conversions/s") && words.contains("4 MHz"),
        "{words}"
    );
}

/// Random runs of blocks (full, short of a buffer, empty, stalled with or without samples,
/// stalls bunched so that some repeat within the window) against the rule written out on its
/// own: a stall within `STALL_REPEAT_SECONDS` of the last one recovered from is
/// `Stalled`; any other stall is recovered from, its tick reads nothing and the next whatever
/// samples it holds; outside that grace an empty block is `NoSamples`; a block with samples
/// reads every fitted channel, finite.
#[test]
fn random_runs_of_stalls_follow_the_rule() {
    use de_resonator::acquire::{Reader, Stall, STALL_GRACE_TICKS, STALL_REPEAT_SECONDS};
    let fe = front_end(1e-3);
    let scans_per_tick = fe.check(TICK_HZ as f32).unwrap();
    let repeat_ticks = (f64::from(STALL_REPEAT_SECONDS) * TICK_HZ) as i64;
    let scans = plant_scans(6000.0, SCANS_PER_TICK);
    let mut rng = Rng(0x5EED_57A1);
    let full = block(&fe, &scans, 1.0, &mut rng);
    let short = block(&fe, &scans[..5], 1.0, &mut rng);
    let (mut stalls, mut faults) = (0, 0);
    for _ in 0..20 {
        let mut reader = Reader::new(fe, scans_per_tick);
        assert!(reader.inputs(&full).is_ok());
        let mut last_recovered: Option<i64> = None;
        let mut grace_until = -1i64;
        let mut run_recovered = 0u32;
        // Stalls about every 2 s to 20 s: some repeat within the window, some do not.
        let every = rng.range(2_000.0, 20_000.0);
        for t in 1..40_000i64 {
            let mut b = match rng.below(20) {
                0 => short,
                1 => Block::EMPTY,
                _ => full,
            };
            let stall = (rng.unit() < 1.0 / every).then(|| {
                if rng.below(2) == 0 {
                    Stall::Overrun
                } else {
                    Stall::TransferError
                }
            });
            if let Some(why) = stall {
                if rng.below(2) == 0 {
                    b = Block::EMPTY;
                }
                b.stalled(why);
            }
            let got = reader.inputs(&b);
            let empty = b.samples(Channel::Stretch) == 0;
            match stall {
                Some(why) if last_recovered.is_some_and(|at| t - at < repeat_ticks) => {
                    faults += 1;
                    assert!(
                        matches!(got, Err(InputError::Stalled { stall, .. }) if stall == why),
                        "tick {t}: {got:?}"
                    );
                    continue;
                }
                Some(_) => {
                    stalls += 1;
                    run_recovered += 1;
                    last_recovered = Some(t);
                    grace_until = t + i64::from(STALL_GRACE_TICKS) - 1;
                }
                None => {}
            }
            if stall.is_some() {
                assert_eq!(
                    got,
                    Ok(Inputs::NONE),
                    "tick {t}: a stall's tick reads nothing"
                );
            } else if empty && t > grace_until {
                assert_eq!(
                    got,
                    Err(InputError::NoSamples {
                        channel: Channel::Current
                    }),
                    "tick {t}"
                );
            } else if empty {
                assert_eq!(got, Ok(Inputs::NONE), "tick {t}");
            } else {
                let read = got.unwrap_or_else(|e| panic!("tick {t}: {e}"));
                for r in [read.current_amps, read.amplifier_volts, read.stretch] {
                    assert!(r.is_some_and(f32::is_finite), "tick {t}: {read:?}");
                }
            }
        }
        // The reader's count is the rule's.
        assert_eq!(reader.recovered(), run_recovered);
    }
    assert!(
        stalls > 40 && faults > 10,
        "{stalls} recovered, {faults} faults"
    );
}

/// The repeat window's edge: a second stall `repeat_ticks − 1` ticks after the first is the
/// fault, one `repeat_ticks` after is recovered from; two stalls in one block are the fault.
#[test]
fn the_repeat_windows_edge_and_two_stalls_in_a_block() {
    use de_resonator::acquire::{Reader, Stall, STALL_REPEAT_SECONDS};
    let fe = front_end(1e-3);
    let scans_per_tick = fe.check(TICK_HZ as f32).unwrap();
    let repeat_ticks = (f64::from(STALL_REPEAT_SECONDS) * TICK_HZ) as usize;
    let scans = plant_scans(6000.0, SCANS_PER_TICK);
    let mut rng = Rng(23);
    let full = block(&fe, &scans, 1.0, &mut rng);
    let mut stalled = Block::EMPTY;
    stalled.stalled(Stall::Overrun);
    for (gap, faults) in [(repeat_ticks - 1, true), (repeat_ticks, false)] {
        let mut reader = Reader::new(fe, scans_per_tick);
        assert!(reader.inputs(&full).is_ok());
        assert_eq!(reader.inputs(&stalled), Ok(Inputs::NONE));
        // The stall's tick, then gap − 1 ticks: the next stall `gap` ticks after the first.
        for _ in 1..gap {
            assert!(reader.inputs(&full).is_ok());
        }
        let got = reader.inputs(&stalled);
        assert_eq!(
            got.is_err(),
            faults,
            "a second stall {gap} ticks on: {got:?}"
        );
    }
    let mut twice = Block::EMPTY;
    twice.stalled(Stall::Overrun);
    twice.stalled(Stall::TransferError);
    let mut reader = Reader::new(fe, scans_per_tick);
    assert!(reader.inputs(&full).is_ok());
    assert_eq!(
        reader.inputs(&twice),
        Err(InputError::Stalled {
            stall: Stall::TransferError,
            recovered: 0
        })
    );
}

/// The input errors read as sentences naming what failed: the stall's cause, the channel and
/// its reading's unit (what an operator sees in `status` and the fault log).
#[test]
fn input_errors_name_the_stall_the_channel_and_its_unit() {
    use de_resonator::acquire::{Channel, InputError, Stall};
    let stalled = InputError::Stalled {
        stall: Stall::Overrun,
        recovered: 2,
    }
    .to_string();
    assert!(stalled.contains("(an ADC overrun)"), "{stalled}");
    let dma = InputError::Stalled {
        stall: Stall::TransferError,
        recovered: 1,
    }
    .to_string();
    assert!(dma.contains("(a DMA transfer error)"), "{dma}");
    for (channel, reading) in [
        (Channel::Current, "reads 0.5 A,"),
        (Channel::Amplifier, "reads 0.5 V,"),
        (Channel::Stretch, "reads 0.5 (stretch),"),
    ] {
        let said = InputError::Implausible {
            channel,
            reading: 0.5,
            low: 1.0,
            high: 2.0,
        }
        .to_string();
        assert!(said.contains(reading), "{said}");
        assert!(said.starts_with(channel.name()), "{said}");
    }
}

/// A tick's noise as the trim weighs it (`ChannelSpec::tick_noise`) is what the mean of
/// `scans` conversions scatters by: measured here on simulated conversions (Gaussian noise of
/// `noise_codes`, then the ADC's rounding, at a true value anywhere between two codes), in
/// the reading's unit. Where the noise dithers the rounding (half a code or more) both
/// average over the scans; with no noise the rounding is the same at every scan.
#[test]
fn a_ticks_noise_is_what_the_mean_of_its_scans_scatters_by() {
    let mut rng = Rng(23);
    for noise_codes in [0.0f32, 1.0, 3.0] {
        for scans in [1u32, 4, 10] {
            let spec = ChannelSpec {
                input: 11,
                zero_code: 100.0,
                per_count: 2.6,
                low: -100.0,
                high: 10_000.0,
                noise_codes,
            };
            let ticks = 40_000;
            let mut squares = 0.0;
            for _ in 0..ticks {
                let truth = 1000.0 + rng.unit();
                let mut sum = 0.0;
                for _ in 0..scans {
                    sum += (truth + f64::from(noise_codes) * normal(&mut rng)).round();
                }
                let error = sum / f64::from(scans) - truth;
                squares += error * error;
            }
            let measured = 2.6 * (squares / f64::from(ticks)).sqrt();
            let said = f64::from(spec.tick_noise(scans));
            assert!(
                (said / measured - 1.0).abs() < 0.03,
                "noise {noise_codes} codes, {scans} scans: said {said}, measured {measured}"
            );
        }
    }
}

/// In a stall's grace (the tick after the stall's own) a channel with no sample reads
/// nothing, and a reading the fast path refused is named as the checked path names it.
#[test]
fn in_a_stalls_grace_a_channel_with_no_sample_reads_nothing() {
    use de_resonator::acquire::{Reader, Stall};
    let fe = front_end(1e-3);
    let scans = fe.check(TICK_HZ as f32).unwrap();
    let whole = |current: Option<u16>, amplifier: u16, stretch: u16| {
        let mut b = Block::EMPTY;
        for _ in 0..scans {
            if let Some(code) = current {
                b.add(Channel::Current, code);
            }
            b.add(Channel::Amplifier, amplifier);
            b.add(Channel::Stretch, stretch);
        }
        b
    };
    let mut reader = Reader::new(fe, scans);
    assert!(reader.inputs(&whole(Some(2047), 1000, 2000)).is_ok());
    let mut stalled = Block::EMPTY;
    stalled.stalled(Stall::Overrun);
    assert_eq!(reader.inputs(&stalled), Ok(Inputs::NONE));
    // The grace tick: no current sample, the rest read.
    let read = reader.inputs(&whole(None, 1000, 2000)).unwrap();
    assert_eq!(read.current_amps, None);
    assert!(read.amplifier_volts.is_some() && read.stretch.is_some());
    // The same, the amplifier's monitor beyond its plausible range: that one named.
    let mut reader = Reader::new(fe, scans);
    assert!(reader.inputs(&whole(Some(2047), 1000, 2000)).is_ok());
    assert_eq!(reader.inputs(&stalled), Ok(Inputs::NONE));
    let refused = reader.inputs(&whole(None, 4000, 2000));
    assert!(
        matches!(
            refused,
            Err(InputError::Implausible {
                channel: Channel::Amplifier,
                ..
            })
        ),
        "{refused:?}"
    );
    // After the grace an empty channel is a fault again.
    assert_eq!(
        reader.inputs(&whole(None, 1000, 2000)),
        Err(InputError::NoSamples {
            channel: Channel::Current
        })
    );
}

/// A channel's spec at its edges: infinite noise refused, input 15 (the board has it)
/// accepted, a range reaching within the rail margin of full scale refused, an empty range
/// (low = high) refused.
#[test]
fn a_channels_spec_is_checked_at_its_edges() {
    let good = front_end(1e-3);
    let with = |change: &dyn Fn(&mut ChannelSpec)| {
        let mut fe = good;
        if let Some(spec) = fe.channels[1].as_mut() {
            change(spec);
        }
        fe.check(TICK_HZ as f32)
    };
    assert!(with(&|_| {}).is_ok());
    assert!(matches!(
        with(&|s| s.noise_codes = f32::INFINITY),
        Err(FrontEndError::Noise { .. })
    ));
    assert!(with(&|s| s.input = 15).is_ok(), "input 15 is on the board");
    // The top of the range 10 codes below full scale: inside the rail's margin of 16.
    let top = |s: &ChannelSpec| (f32::from(FULL_SCALE_CODE) - 10.0 - s.zero_code) * s.per_count;
    assert!(matches!(
        with(&|s| s.high = top(s)),
        Err(FrontEndError::Range { .. })
    ));
    assert!(matches!(
        with(&|s| s.low = s.high),
        Err(FrontEndError::Range { .. })
    ));
}

/// The tick takes the block the DMA's task filled and leaves an empty one for the next tick.
#[test]
fn the_tick_takes_the_block_and_leaves_an_empty_one() {
    let mut b = Block::EMPTY;
    b.add(Channel::Current, 2047);
    b.add(Channel::Stretch, 1000);
    let taken = b.take();
    assert_eq!(taken.samples(Channel::Current), 1);
    assert_eq!(taken.samples(Channel::Stretch), 1);
    assert_eq!(b, Block::EMPTY);
}
