//! A running controller operated from the command port (the core's side of it): new targets
//! and AC drives checked outside the tick and ramped to from the present bias, `stop`, the
//! refusals that leave the drive as it was; and the configuration image the firmware boots
//! from, read back and refused when it is wrong.

mod common;

use common::{amplifier, reference_table, reseal};

use de_resonator::acquire::{FrontEnd, FrontEndError};
use de_resonator::board::commands::{self, Command};
use de_resonator::image::{self, AmplifierSpec, Image, ImageError, PowerUp, DAC_BITS};
use de_resonator::table::TableError;
use de_resonator::wire::reply::Reply;
use de_resonator::{
    Controller, Device, Fault, Inputs, Phase, Refusal, Settings, TuneError, Tuner, REFERENCE_DEVICE,
};

fn started(settings: Settings) -> Controller {
    let (c, _) = Controller::start(
        REFERENCE_DEVICE.cast(),
        &reference_table(),
        amplifier(),
        settings,
    )
    .unwrap();
    c
}

/// Tick until the phase is one of `phases` (at most `limit` ticks); the volts of each tick.
fn run_until(c: &mut Controller, phases: &[Phase], limit: u32) -> Vec<f32> {
    let mut volts = Vec::new();
    for _ in 0..limit {
        let out = c.tick(Inputs::NONE);
        volts.push(out.volts);
        if phases.contains(&c.phase()) {
            return volts;
        }
    }
    panic!("never reached {phases:?}: {:?}", c.phase());
}

/// The f64 model's bias for a target (the yardstick, independent of the f32 controller).
fn f64_bias(target_hz: f64) -> f64 {
    Tuner::new(Device::new(REFERENCE_DEVICE).unwrap())
        .tune(target_hz, 0.05)
        .unwrap()
        .volts
}

/// One DAC step of the test amplifier, V.
const STEP_VOLTS: f32 = 10_000.0 / 65536.0;

#[test]
fn a_new_target_ramps_from_the_present_bias_to_the_f64_models_bias() {
    let mut c = started(Settings::for_target(44.0));
    run_until(&mut c, &[Phase::Holding], 5_000);
    let before = c.plan().bias_volts;
    let settings = Settings {
        target_hz: 43.5,
        ..*c.settings()
    };
    let replanned = c
        .replan(settings)
        .unwrap()
        .solve(&reference_table())
        .unwrap();
    let boot = c.adopt(replanned).unwrap();
    let expected = f64_bias(43.5);
    assert!(
        (f64::from(boot.bias_volts) - expected).abs() <= 1e-4 * expected,
        "{} V against {expected} V",
        boot.bias_volts
    );
    assert_eq!(c.plan().start_volts, before);
    let volts = run_until(&mut c, &[Phase::Holding], 5_000);
    // Up at the slew rate (10 kV/s at 1 kHz: 10 V a tick), never past the new bias.
    for pair in volts.windows(2) {
        assert!(pair[1] - pair[0] <= 10.0 + STEP_VOLTS, "{pair:?}");
        assert!(pair[1] <= boot.bias_volts, "{pair:?}");
    }
    let ramp_ticks = volts.len() as f32;
    let expected_ticks = (boot.bias_volts - before) / 10.0;
    assert!(
        (ramp_ticks - expected_ticks).abs() <= 2.0,
        "{ramp_ticks} ticks"
    );
    assert!((c.last_volts() - boot.bias_volts).abs() <= STEP_VOLTS);
}

#[test]
fn a_refused_request_leaves_the_drive_as_it_was() {
    let mut c = started(Settings::for_target(44.0));
    // While the boot's ramp runs: busy.
    c.tick(Inputs::NONE);
    let busy = c.replan(Settings::for_target(43.5));
    assert!(
        matches!(
            busy,
            Err(Refusal::Busy {
                phase: Phase::Ramping
            })
        ),
        "{busy:?}"
    );
    run_until(&mut c, &[Phase::Holding], 5_000);
    let plan = *c.plan();
    // Outside the range (the table's lookup refuses first): the range in the refusal.
    let range = Tuner::new(Device::new(REFERENCE_DEVICE.cast::<f32>()).unwrap())
        .tunable_range(0.05)
        .unwrap();
    let refused = c
        .replan(Settings::for_target(47.0))
        .unwrap()
        .solve(&reference_table());
    match refused {
        Err(Refusal::Checks(Fault::Table(TableError::OutOfRange { high_hz, .. }))) => {
            assert!((high_hz - range.high_hz).abs() <= 1e-5 * range.high_hz)
        }
        other => panic!("{other:?}"),
    }
    // A margin past 1: the direct solve's refusal.
    let bad = Settings {
        margin: 1.5,
        ..*c.settings()
    };
    let refused = c.replan(bad).unwrap().solve(&reference_table());
    assert!(
        matches!(
            refused,
            Err(Refusal::Checks(Fault::Tune(
                TuneError::InvalidMargin { .. }
            ))) | Err(Refusal::Checks(Fault::Setting { .. }))
        ),
        "{refused:?}"
    );
    assert_eq!(*c.plan(), plan);
    assert_eq!(c.phase(), Phase::Holding);
}

#[test]
fn an_ac_too_large_for_the_cap_is_refused_and_a_good_one_drives() {
    let mut c = started(Settings::for_target(44.0));
    run_until(&mut c, &[Phase::Holding], 5_000);
    let cap = c.max_volts();
    let bias = c.plan().bias_volts;
    let too_much = Settings {
        ac_volts: cap - bias + 1.0,
        ac_hz: 40.0,
        ..*c.settings()
    };
    let refused = c.replan(too_much).unwrap().solve(&reference_table());
    assert!(
        matches!(
            refused,
            Err(Refusal::Checks(Fault::Swing {
                setting: de_resonator::Setting::AcVolts,
                ..
            }))
        ),
        "{refused:?}"
    );
    let ac = Settings {
        ac_volts: 100.0,
        ac_hz: 40.0,
        ..*c.settings()
    };
    let replanned = c.replan(ac).unwrap().solve(&reference_table()).unwrap();
    c.adopt(replanned).unwrap();
    let volts = run_until(&mut c, &[Phase::Driving], 5_000);
    assert!(volts.iter().all(|&v| v <= cap));
    // 40 Hz at 1 kHz: the next 25 ticks are one period of 100 V about the bias.
    let period: Vec<f32> = (0..25).map(|_| c.tick(Inputs::NONE).volts).collect();
    let high = period.iter().cloned().fold(f32::MIN, f32::max);
    let low = period.iter().cloned().fold(f32::MAX, f32::min);
    assert!((high - bias - 100.0).abs() <= 1.0 && (bias - low - 100.0).abs() <= 1.0);
}

#[test]
fn a_plan_changed_since_its_job_is_not_adopted() {
    let mut c = started(Settings::for_target(44.0));
    run_until(&mut c, &[Phase::Holding], 5_000);
    let job = c.replan(Settings::for_target(43.5)).unwrap();
    c.stop();
    run_until(&mut c, &[Phase::Holding], 5_000);
    let replanned = job.solve(&reference_table()).unwrap();
    assert!(matches!(c.adopt(replanned), Err(Refusal::Busy { .. })));
    assert_eq!(c.plan().bias_volts, 0.0);
}

/// A plan's job made in the hold before its AC came on does not count that drive's swing:
/// once the drive is on, the job's plan is not adopted (the membrane may carry the swing
/// into the new plan); one made while driving is.
#[test]
fn a_job_made_before_a_drive_came_on_is_not_adopted() {
    let settings = Settings {
        ac_volts: 100.0,
        ac_hz: 40.0,
        ..Settings::for_target(44.0)
    };
    let mut c = started(settings);
    run_until(&mut c, &[Phase::Holding], 5_000);
    let smaller = Settings {
        ac_volts: 50.0,
        ..settings
    };
    let job = c.replan(smaller).unwrap();
    run_until(&mut c, &[Phase::Driving], 5_000);
    let replanned = job.solve(&reference_table()).unwrap();
    assert!(matches!(c.adopt(replanned), Err(Refusal::Busy { .. })));
    assert_eq!(c.settings().ac_volts, 100.0);
    let job = c.replan(smaller).unwrap();
    c.adopt(job.solve(&reference_table()).unwrap()).unwrap();
    assert_eq!(c.settings().ac_volts, 50.0);
}

#[test]
fn stop_ramps_down_at_the_slew_rate_and_stays_at_zero() {
    let settings = Settings {
        ac_volts: 100.0,
        ac_hz: 40.0,
        ..Settings::for_target(44.0)
    };
    let mut c = started(settings);
    run_until(&mut c, &[Phase::Driving], 5_000);
    for _ in 0..13 {
        c.tick(Inputs::NONE);
    }
    let from = c.last_volts();
    c.stop();
    let volts = run_until(&mut c, &[Phase::Holding], 5_000);
    assert!(volts[0] <= from && from - volts[0] <= 10.0 + STEP_VOLTS);
    for pair in volts.windows(2) {
        assert!(
            pair[0] - pair[1] <= 10.0 + STEP_VOLTS && pair[1] <= pair[0],
            "{pair:?}"
        );
    }
    assert_eq!(*volts.last().unwrap(), 0.0);
    assert!((volts.len() as f32 - from / 10.0).abs() <= 2.0);
    for _ in 0..2_000 {
        assert_eq!(c.tick(Inputs::NONE).volts, 0.0);
    }
    // From rest a new target starts again from 0 V.
    let replanned = c
        .replan(Settings::for_target(44.0))
        .unwrap()
        .solve(&reference_table())
        .unwrap();
    c.adopt(replanned).unwrap();
    assert_eq!(c.plan().start_volts, 0.0);
}

#[test]
fn a_replan_never_lifts_the_cap_fixed_at_boot() {
    let mut c = started(Settings {
        margin: 0.2,
        ..Settings::for_target(44.5)
    });
    run_until(&mut c, &[Phase::Holding], 5_000);
    let ceiling = c.ceiling_volts();
    let looser = Settings {
        margin: 0.05,
        target_hz: 44.0,
        ..*c.settings()
    };
    let replanned = c.replan(looser).unwrap().solve(&reference_table()).unwrap();
    c.adopt(replanned).unwrap();
    assert!(c.max_volts() <= ceiling);
    assert_eq!(c.ceiling_volts(), ceiling);
}

#[test]
fn a_new_plan_keeps_the_tick_rate_booted_with_and_reports_the_cap_in_force() {
    let mut c = started(Settings {
        margin: 0.2,
        ..Settings::for_target(44.5)
    });
    run_until(&mut c, &[Phase::Holding], 5_000);
    let cap = c.max_volts();
    let other_rate = Settings {
        tick_hz: 2_000.0,
        margin: 0.05,
        target_hz: 44.0,
        ..*c.settings()
    };
    let replanned = c
        .replan(other_rate)
        .unwrap()
        .solve(&reference_table())
        .unwrap();
    let boot = c.adopt(replanned).unwrap();
    assert_eq!(c.settings().tick_hz, 1_000.0);
    assert_eq!(boot.max_volts, c.max_volts());
    assert!(boot.max_volts <= cap);
    // 10 kV/s at the booted 1 kHz: 10 V a tick on the way up.
    let volts = run_until(&mut c, &[Phase::Holding], 5_000);
    let step = volts[1] - volts[0];
    assert!((step - 10.0).abs() <= STEP_VOLTS, "{step}");
}

#[test]
fn a_trim_is_refused_without_a_trim_tolerance() {
    let mut c = started(Settings::for_target(44.0));
    run_until(&mut c, &[Phase::Holding], 5_000);
    assert_eq!(c.trim_now(), Err(Refusal::NoTrim));
    assert_eq!(c.phase(), Phase::Holding);
}

/// Issue 25: a trim asked for once `stop` has brought the output down is refused as
/// `Stopped` (it would hold a bias of 0 V and measure nothing), where the same request on a
/// running drive pauses the AC and measures. (The reference device as its own plant.)
#[cfg(feature = "trim")]
#[test]
fn a_trim_after_stop_is_refused_and_one_while_driving_is_taken() {
    let settings = Settings {
        ac_volts: 30.0,
        ac_hz: 40.0,
        trim_tolerance: Some(1e-3),
        ..Settings::for_target(44.0)
    };
    let plant = common::with_quality_factor(REFERENCE_DEVICE, 50.0);
    let drive = |c: &mut Controller, p: &mut common::Plant, ticks: u32| {
        let mut last = 0.0;
        for _ in 0..ticks {
            let out = c.tick(Inputs::stretch(p.stretch() as f32));
            if let Some(job) = c.trim_job() {
                c.trim_done(job.solve());
            }
            p.step(out.volts);
            last = out.volts;
        }
        last
    };
    let mut running = started(settings);
    let mut p = common::Plant::new(plant, 1000.0);
    drive(&mut running, &mut p, 10_000);
    assert_eq!(running.phase(), Phase::Driving);
    assert_eq!(running.trim_now(), Ok(()));
    assert_ne!(running.phase(), Phase::Driving);
    let mut stopped = started(settings);
    let mut p = common::Plant::new(plant, 1000.0);
    drive(&mut stopped, &mut p, 10_000);
    stopped.stop();
    assert_eq!(drive(&mut stopped, &mut p, 3_000), 0.0);
    let phase = stopped.phase();
    assert_eq!(stopped.trim_now(), Err(Refusal::Stopped));
    assert_eq!(stopped.phase(), phase);
    assert_eq!(drive(&mut stopped, &mut p, 100), 0.0);
}

/// `stop` during a trim's pulse: the ramp down never dips below itself (the pulse is
/// dropped) and no AC is left in the plan.
#[cfg(feature = "trim")]
#[test]
fn stop_drops_a_pending_pulse_and_the_ac() {
    let settings = Settings {
        trim_tolerance: Some(1e-3),
        ac_volts: 100.0,
        ac_hz: 40.0,
        // The stand-in plant below is static: its samples repeat while the bias holds.
        stuck_samples: None,
        ..Settings::for_target(44.0)
    };
    let (mut c, _) = Controller::start(
        REFERENCE_DEVICE.cast(),
        &reference_table(),
        amplifier(),
        settings,
    )
    .unwrap();
    // The plant: the device's equilibrium at the voltage commanded, its stretch the sensor.
    let device = Device::new(REFERENCE_DEVICE.cast::<f32>()).unwrap();
    let stretch_at = |volts: f32| {
        device
            .offset_for_bias(volts, Tuner::new(device).limit().at.offset)
            .map(|o| device.stretch_at(o))
            .unwrap_or(device.prestretch_1())
    };
    let mut volts = 0.0;
    for _ in 0..20_000 {
        let out = c.tick(Inputs::stretch(stretch_at(volts)));
        volts = out.volts;
        if c.phase() == Phase::Measuring {
            break;
        }
    }
    assert_eq!(c.phase(), Phase::Measuring);
    c.stop();
    assert_eq!(c.plan().ac_volts, 0.0);
    let mut last = c.last_volts();
    for _ in 0..2_000 {
        let v = c.tick(Inputs::stretch(stretch_at(last))).volts;
        assert!(v <= last && last - v <= 10.0 + STEP_VOLTS, "{last} -> {v}");
        last = v;
    }
    assert_eq!(last, 0.0);
}

#[test]
fn a_faulted_controller_refuses_every_request_but_stop() {
    let mut c = started(Settings::for_target(44.0));
    c.fault(Fault::Bus);
    assert!(matches!(
        c.replan(Settings::for_target(44.0)),
        Err(Refusal::Faulted { fault: Fault::Bus })
    ));
    assert!(matches!(c.trim_now(), Err(Refusal::Faulted { .. })));
    c.stop();
    assert_eq!(c.phase(), Phase::Faulted);
    assert_eq!(c.tick(Inputs::NONE).volts, 0.0);
}

fn spec() -> AmplifierSpec {
    AmplifierSpec {
        dac_reference_volts: 2.5,
        gain: 4000.0,
        rail_volts: 9_000.0,
        dac_bits: DAC_BITS,
    }
}

fn made_image(settings: &Settings) -> Vec<u8> {
    let t = reference_table();
    let mut out = vec![0xAA; image::image_bytes(t.len()) + 100];
    let n = Image::write(
        &mut out,
        &REFERENCE_DEVICE.cast(),
        &spec(),
        &FrontEnd::NONE,
        settings,
        PowerUp::Drive,
        &t,
    )
    .unwrap();
    out.truncate(n);
    out
}

#[test]
fn an_image_reads_back_what_was_written() {
    let settings = Settings {
        ac_volts: 100.0,
        ac_hz: 40.0,
        stuck_samples: None,
        ..Settings::for_target(44.0)
    };
    let bytes = made_image(&settings);
    assert_eq!(
        bytes.len(),
        image::HEADER_BYTES + reference_table().len() + 4
    );
    // In a sector larger than the image (erased flash after it).
    let mut sector = bytes.clone();
    sector.resize(128 * 1024, 0xFF);
    let read = Image::parse(&sector).unwrap();
    assert_eq!(read.params, REFERENCE_DEVICE.cast());
    assert_eq!(read.amplifier, spec());
    assert_eq!(read.settings, settings);
    assert_eq!(read.table, &reference_table()[..]);
    // The rail caps the amplifier below its full scale.
    let a = read.amplifier.amplifier().unwrap();
    assert_eq!(a.max_volts(), 9_000.0);
    assert!(a.code(9_000.5).is_err());
}

#[test]
fn every_wrong_image_is_refused_with_its_reason() {
    let good = made_image(&Settings::for_target(44.0));
    for byte in [0x00, 0xFF] {
        assert_eq!(
            Image::parse(&vec![byte; 128 * 1024]).unwrap_err(),
            ImageError::Empty { byte }
        );
    }
    assert!(matches!(
        Image::parse(&good[..50]),
        Err(ImageError::TooShort { .. })
    ));
    // Every single flipped bit is caught (by the CRC, or before it by the frame).
    for at in 0..good.len() {
        let mut bad = good.clone();
        bad[at] ^= 0x10;
        assert!(Image::parse(&bad).is_err(), "bit flip at {at} accepted");
    }
    // Cut short: the stated length runs past the room (the settings' count or more left),
    // or not even the header before the settings and a CRC (160 bytes).
    for cut in [good.len() - 1, 300, image::HEADER_BYTES + 3, 160] {
        assert!(
            matches!(
                Image::parse(&good[..cut]),
                Err(ImageError::WrongLength { .. })
            ),
            "{cut}"
        );
    }
    assert_eq!(
        Image::parse(&good[..159]).unwrap_err(),
        ImageError::TooShort { bytes: 159 }
    );
    // Erased flash is empty only when all of the header is: anything else is not an image.
    let mut stranger = vec![0xFFu8; 4096];
    stranger[40] = 0x12;
    assert_eq!(Image::parse(&stranger).unwrap_err(), ImageError::BadMagic);
    assert_eq!(
        Image::parse(&[0x5A; 4096]).unwrap_err(),
        ImageError::BadMagic
    );
    let mut version = good.clone();
    version[4] = 1;
    reseal(&mut version);
    assert_eq!(
        Image::parse(&version).unwrap_err(),
        ImageError::UnsupportedVersion { version: 1 }
    );
    // A front end the board cannot read: the current monitor on the command port's RX pin
    // (IN3), or with no scale.
    let mut front = good.clone();
    front[84] = 3;
    reseal(&mut front);
    assert!(matches!(
        Image::parse(&front),
        Err(ImageError::FrontEnd(FrontEndError::Input { input: 3, .. }))
    ));
    front[84] = 10;
    reseal(&mut front);
    assert!(matches!(
        Image::parse(&front),
        Err(ImageError::FrontEnd(FrontEndError::Scale { .. }))
    ));
    let mut bits = good.clone();
    bits[76] = 12;
    reseal(&mut bits);
    assert_eq!(
        Image::parse(&bits).unwrap_err(),
        ImageError::DacBits { bits: 12 }
    );
    let mut rail = good.clone();
    rail[72..76].copy_from_slice(&f32::NAN.to_le_bytes());
    reseal(&mut rail);
    assert!(matches!(Image::parse(&rail), Err(ImageError::Amplifier(_))));
    // A setting out of range passes the frame and is the boot's to refuse, by name.
    // (The margin, id 1, is the second entry: its id at 164, its value at 168.)
    let mut margin = good.clone();
    assert_eq!(margin[164..166], 1u16.to_le_bytes());
    margin[168..172].copy_from_slice(&1.5f32.to_le_bytes());
    reseal(&mut margin);
    let read = Image::parse(&margin).unwrap();
    let a = read.amplifier.amplifier().unwrap();
    let refused = Controller::start(read.params, read.table, a, read.settings).map(|_| ());
    assert!(
        matches!(
            refused,
            Err(Fault::Tune(TuneError::InvalidMargin { .. }))
                | Err(Fault::Setting {
                    setting: de_resonator::Setting::Margin,
                    ..
                })
        ),
        "{refused:?}"
    );
}

/// Settings by id in an image: one made before a setting was added (here, one lacking
/// `settle_seconds`) parses with every value it holds and that one at its default, and says
/// which; one holding a setting this firmware does not know (made for a newer one) is
/// refused by name, saying what to do.
#[test]
fn an_older_image_defaults_the_new_setting_and_a_newer_one_is_refused() {
    let settings = Settings {
        settle_seconds: 0.4,
        ac_volts: 30.0,
        ac_hz: 44.0,
        ..Settings::for_target(44.5)
    };
    let mut good = made_image(&settings);
    let length = u32::from_le_bytes(good[8..12].try_into().unwrap()) as usize;
    good.truncate(length);
    let lacking = de_resonator::Setting::from_key("settle_seconds").unwrap();
    // The entry of `settle_seconds` (8 bytes from 156, by id) taken out.
    let at = 156 + 8 * usize::from(lacking.id());
    assert_eq!(good[at..at + 2], u16::from(lacking.id()).to_le_bytes());
    let mut older = good.clone();
    older.drain(at..at + 8);
    let held = de_resonator::Setting::ALL.len() as u16 - 1;
    older[6..8].copy_from_slice(&held.to_le_bytes());
    older[8..12].copy_from_slice(&((length - 8) as u32).to_le_bytes());
    reseal(&mut older);
    let read = Image::parse(&older).unwrap();
    assert_eq!(
        read.settings,
        Settings {
            settle_seconds: Settings::DEFAULTS.settle_seconds,
            ..settings
        }
    );
    assert_eq!(read.defaulted.iter().collect::<Vec<_>>(), [lacking]);
    // An entry of an id no setting has, in the place of `settle_seconds`'s.
    let mut newer = good.clone();
    newer[at..at + 2].copy_from_slice(&77u16.to_le_bytes());
    reseal(&mut newer);
    let refused = Image::parse(&newer).unwrap_err();
    assert_eq!(refused, ImageError::UnknownSetting { id: 77 });
    assert!(refused.to_string().contains("host-sim image"), "{refused}");
}

/// Image errors and refusals read as sentences that name their cause.
#[test]
fn image_errors_and_refusals_say_why() {
    let cases: [(String, &str); 8] = [
        (
            ImageError::Empty { byte: 0xFF }.to_string(),
            "no configuration image",
        ),
        (ImageError::BadMagic.to_string(), "DERI"),
        (
            ImageError::UnsupportedVersion { version: 2 }.to_string(),
            "version 2",
        ),
        (ImageError::DacBits { bits: 12 }.to_string(), "12-bit DAC"),
        (
            ImageError::BadCrc {
                stored: 1,
                computed: 2,
            }
            .to_string(),
            "corrupted",
        ),
        (
            Refusal::Busy {
                phase: Phase::Ramping,
            }
            .to_string(),
            "busy (ramping)",
        ),
        (
            Refusal::Faulted { fault: Fault::Bus }.to_string(),
            "DAC bus error",
        ),
        (Refusal::NoTrim.to_string(), "trim_tolerance"),
    ];
    for (text, word) in cases {
        assert!(text.contains(word), "{text:?} lacks {word:?}");
    }
}

/// Every request the help line names parses, and its reply forms read back.
#[test]
fn the_protocol_covers_what_help_says() {
    for name in [
        "help", "status", "info", "stop", "trim", "clear", "save", "reset",
    ] {
        assert!(commands::parse(name.as_bytes()).is_ok(), "{name}");
    }
    assert_eq!(
        commands::parse(b"target 44"),
        Ok(Command::Target { hz: 44.0 })
    );
    assert!(commands::HELP.contains("target <Hz>"));
    assert_eq!(
        commands::parse(b"stream 100"),
        Ok(Command::Stream(Some(100.0)))
    );
    assert_eq!(commands::parse(b"stream off"), Ok(Command::Stream(None)));
    assert!(commands::parse(b"stream").is_err() && commands::parse(b"stream fast").is_err());
    assert!(commands::HELP.contains("stream <Hz>"));
    assert!(commands::HELP.contains("faults [<n> | clear]"));
    assert!(!commands::HELP.contains('\n'), "one reply line");
    use de_resonator::board::commands::FaultsAsk;
    for (line, ask) in [
        (&b"faults"[..], FaultsAsk::List),
        (b"faults clear", FaultsAsk::Clear),
        (b"faults 7", FaultsAsk::One(7)),
    ] {
        assert_eq!(commands::parse(line), Ok(Command::Faults(ask)));
    }
    for bad in [
        &b"faults 0"[..],
        b"faults 1.5",
        b"faults -2",
        b"faults 1e9",
        b"faults x",
    ] {
        assert!(
            commands::parse(bad).is_err(),
            "{}",
            String::from_utf8_lossy(bad)
        );
    }
    assert_eq!(
        Reply::parse("ok target_hz=44 bias_volts=7449.878").and_then(|r| r.field("bias_volts")),
        Some("7449.878")
    );
}

/// `help <command>` knows every command `parse` knows, and only those; `help` of a typo
/// suggests the nearest command or setting.
#[test]
fn help_knows_every_command_and_suggests_for_a_typo() {
    use de_resonator::board::commands::{Topic, COMMANDS};
    use de_resonator::wire::protocol::ParseError;
    for (k, command) in COMMANDS.iter().enumerate() {
        let name = command.name();
        let said = format!("{}: {}", command.form, command.does);
        let asked = format!("help {name}");
        assert_eq!(
            commands::parse(asked.as_bytes()),
            Ok(Command::Help(Some(Topic::Command(k as u8)))),
            "{name}"
        );
        assert!(said.starts_with(name), "{name}: {said}");
        assert!(commands::HELP.contains(name), "{name}");
        // The command itself parses: bare, or with what its form asks.
        let form = said.split(':').next().unwrap_or_default();
        let example = form
            .replace("<Hz>", "44")
            .replace("<volts>", "10")
            .replace("<setting>", "margin")
            .replace("<value>", "0.05")
            .replace("<n>", "1");
        let first = example.split(" | ").next().unwrap_or_default();
        let first = first.replace(['[', ']'], "");
        let words: Vec<&str> = first
            .split_whitespace()
            .take_while(|w| !w.contains('|'))
            .collect();
        let bare = if words.len() > 1 && ["command", "setting"].contains(&words[1]) {
            words[0].to_string()
        } else {
            words.join(" ")
        };
        assert!(commands::parse(bare.as_bytes()).is_ok(), "{name}: `{bare}`");
    }
    // Every word `parse` takes as a command is in the list (and so in `help`).
    for word in ["sto", "stat", "targe", "tirm", "faultz"] {
        assert!(commands::parse(word.as_bytes()).is_err(), "{word}");
    }
    assert_eq!(
        commands::parse(b"help stpo"),
        Err(ParseError::UnknownTopic {
            nearest: Some("stop")
        })
    );
    assert_eq!(
        commands::parse(b"help marign"),
        Err(ParseError::UnknownTopic {
            nearest: Some(de_resonator::controller::Setting::Margin.key())
        })
    );
    assert_eq!(
        commands::parse(b"help foo"),
        Err(ParseError::UnknownTopic { nearest: None })
    );
    let said = ParseError::UnknownTopic {
        nearest: Some(COMMANDS[0].name()),
    }
    .to_string();
    assert!(said.contains("did you mean `help`?"), "{said}");
}

/// A unit after a number is its own unit or named in the error; a count refuses a fraction.
#[test]
fn units_after_numbers_are_taken_or_named_and_counts_are_whole() {
    use de_resonator::controller::Setting;
    use de_resonator::wire::protocol::ParseError;
    let target = Ok(Command::Target { hz: 33.5 });
    for line in [
        "target 33.5",
        "target 33.5 Hz",
        "target 33.5Hz",
        "target 33.5 hz",
    ] {
        assert_eq!(commands::parse(line.as_bytes()), target, "{line}");
    }
    let ac = Ok(Command::Ac {
        volts: 80.0,
        hz: 33.0,
    });
    for line in ["ac 80 33", "ac 80 V 33 Hz", "ac 80V 33Hz", "ac 80 v 33"] {
        assert_eq!(commands::parse(line.as_bytes()), ac, "{line}");
    }
    for (line, index, unit) in [
        ("target 33.5 kHz", 1, "Hz"),
        ("target 33.5kHz", 1, "Hz"),
        ("ac 80 mV 33", 1, "V"),
        ("ac 80 33 V", 2, "Hz"),
        ("set slew_volts_per_second 1e4 V", 2, "V/s"),
    ] {
        let got = commands::parse(line.as_bytes());
        assert_eq!(got, Err(ParseError::WrongUnit { index, unit }), "{line}");
        let said = got.unwrap_err().to_string();
        assert!(
            said.contains(&format!("argument {index} is in {unit}")),
            "{said}"
        );
    }
    assert_eq!(
        commands::parse(b"set slew_volts_per_second 1e4 V/s"),
        Ok(Command::Set(Setting::SlewVoltsPerSecond, 1e4))
    );
    assert_eq!(
        commands::parse(b"stream 100Hz"),
        Ok(Command::Stream(Some(100.0)))
    );
    assert_eq!(commands::parse(b"target 33.5 Hz 2"), Err(ParseError::Extra));
    assert_eq!(commands::parse(b"target 44 extra"), Err(ParseError::Extra));
    assert_eq!(
        commands::parse(b"target Hz"),
        Err(ParseError::BadNumber { index: 1 })
    );
    // A count: a fraction is refused, not rounded (1.5 would have been 1).
    assert_eq!(
        commands::parse(b"set stuck_samples 1.5"),
        Err(ParseError::NotWhole { index: 2 })
    );
    assert_eq!(
        commands::parse(b"set stuck_samples 100"),
        Ok(Command::Set(Setting::StuckSamples, 100.0))
    );
    assert!(Setting::ALL
        .iter()
        .filter(|s| s.whole())
        .all(|s| s.unit() == "samples"));
}

/// A fitted channel on an input the layout cannot hold (0xFF means "not fitted") is refused
/// when the image is written, not read back as no channel.
#[test]
fn an_image_refuses_a_channel_it_could_not_read_back() {
    use de_resonator::acquire::{Channel, ChannelSpec};
    let t = reference_table();
    let mut out = vec![0; image::image_bytes(t.len())];
    let channel = ChannelSpec {
        input: 0xFF,
        zero_code: 2047.5,
        per_count: 1e-7,
        low: -1e-4,
        high: 1e-4,
        noise_codes: 0.0,
    };
    let front_end = FrontEnd {
        scan_hz: 10_000.0,
        channels: [Some(channel), None, None],
    };
    assert_eq!(
        Image::write(
            &mut out,
            &REFERENCE_DEVICE.cast(),
            &spec(),
            &front_end,
            &Settings::for_target(44.0),
            PowerUp::Drive,
            &t,
        ),
        Err(ImageError::FrontEnd(FrontEndError::Input {
            channel: Channel::Current,
            input: 0xFF
        }))
    );
}

/// Issue 46: a target out of the table's range is refused for its range, first: not for a
/// setting only the out-of-range target makes wrong (the trim's window counts target
/// periods: 200 Hz at a 1 kHz tick has too few samples a period). Where the target is in
/// range, the setting is refused by its own rule.
#[test]
fn a_target_out_of_range_is_refused_for_its_range_before_a_setting_it_implies() {
    let t = reference_table();
    let trimmed = |target_hz: f32, window: f32| Settings {
        trim_tolerance: Some(0.01),
        trim_window_seconds: window,
        ..Settings::for_target(target_hz)
    };
    let start = |settings| Controller::start(REFERENCE_DEVICE.cast(), &t, amplifier(), settings);
    match start(trimmed(200.0, 0.5)) {
        Err(Fault::Table(e)) => assert!(e.to_string().contains("200"), "{e}"),
        other => panic!("{:?}", other.map(|(_, boot)| boot)),
    }
    // (Without the trim the window is not checked: a trim asked for is refused itself.)
    #[cfg(feature = "trim")]
    match start(trimmed(44.0, 0.001)) {
        Err(Fault::Setting { setting, .. }) => {
            assert_eq!(
                setting,
                de_resonator::controller::Setting::TrimWindowSeconds
            )
        }
        other => panic!("{:?}", other.map(|(_, boot)| boot)),
    }
}

/// docs/commands.md, the requests' reference, is what their declarations say (each one's
/// form, rule and docs): written from them with `UPDATE_DOCS=1 cargo test --test operation
/// requests_reference`, and compared with them in every other run.
#[test]
fn the_requests_reference_is_the_declarations() {
    use de_resonator::board::commands::{Rule, COMMANDS, COMMAND_DOCS, COMMAND_RULES};
    use std::fmt::Write;
    let mut doc = String::from(
        "# The command port's requests\n\n\
         One request a line, one reply line each (`ok …` or `err <code> <message>`; \
         docs/firmware.md, **The command port**). `help` lists them, `help <command>` says \
         what one does.\n\n\
         This file is written from the declarations in `src/board/commands/mod.rs` \
         (`tests/operation.rs` checks it).\n\n\
         | request | answered | what it does |\n|---|---|---|\n",
    );
    for ((command, docs), rule) in COMMANDS.iter().zip(COMMAND_DOCS).zip(COMMAND_RULES) {
        let when = match rule {
            Rule::Always => "always",
            Rule::Imaged => "with an image",
            Rule::Booted => "once booted",
        };
        let what: Vec<&str> = docs.iter().map(|line| line.trim()).collect();
        let _ = writeln!(
            doc,
            "| `{}` | {when} | {} |",
            command.form.replace('|', "\\|"),
            what.join(" ").replace('|', "\\|")
        );
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/commands.md");
    if std::env::var_os("UPDATE_DOCS").is_some() {
        std::fs::write(&path, &doc).unwrap();
    }
    let kept = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        kept == doc,
        "docs/commands.md is not what the declarations say: UPDATE_DOCS=1 cargo test --test \
         operation requests_reference writes it"
    );
}
