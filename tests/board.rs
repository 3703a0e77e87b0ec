//! The core's board on the host, as the firmware runs it: the boot from an image and the
//! saved settings (the fallback, the watchdog's refusal), every request of the command port
//! and its reply, the one enable policy, and the tick's background job. The protocol's
//! grammar is in `src/wire/protocol.rs`'s tests; the controller's decisions in `controller*.rs`.

mod common;

use common::refused_with;
use de_resonator::acquire::FrontEnd;
use de_resonator::board::port::Extras;
use de_resonator::board::{
    tick, Board, FaultKeeper, Keeper, Line, NoKeeper, NoLog, ReplyLine, ResetCause, SettingsKeeper,
    Then,
};
use de_resonator::controller::Held;
use de_resonator::image::{self, AmplifierSpec, Image, PowerUp, DAC_BITS};
use de_resonator::wire::protocol::ErrorCode;
use de_resonator::Setting;
use de_resonator::{Controller, Dac8551, Inputs, OutputStage, Settings, REFERENCE_DEVICE};

/// 0..10 kV: a 2.5 V reference, gain 4000 (as `common::amplifier`).
fn spec() -> AmplifierSpec {
    AmplifierSpec {
        dac_reference_volts: 2.5,
        gain: 4000.0,
        rail_volts: 10_000.0,
        dac_bits: DAC_BITS,
    }
}

/// The reference device's image with `settings`, an amplifier and a power-up choice.
fn image_of(settings: &Settings, amplifier: &AmplifierSpec, power_up: PowerUp) -> Vec<u8> {
    let table = common::reference_table();
    let mut out = vec![0; image::image_bytes(table.len())];
    Image::write(
        &mut out,
        &REFERENCE_DEVICE.cast(),
        amplifier,
        &FrontEnd::NONE,
        settings,
        power_up,
        &table,
    )
    .unwrap();
    out
}

/// The reference device's image with `settings`.
fn image_with(settings: &Settings) -> Vec<u8> {
    let table = common::reference_table();
    let mut out = vec![0; image::image_bytes(table.len())];
    Image::write(
        &mut out,
        &REFERENCE_DEVICE.cast(),
        &spec(),
        &FrontEnd::NONE,
        settings,
        PowerUp::Drive,
        &table,
    )
    .unwrap();
    out
}

fn line(text: &str) -> Line {
    Line::Text(heapless::Vec::from_slice(text.as_bytes()).unwrap())
}

/// Settings kept in memory, as a flash would keep them; `broken` fails every read;
/// `lacking` is a setting the saved ones do not hold (saved before it was added).
#[derive(Default)]
struct Memory {
    saved: Option<Settings>,
    broken: bool,
    lacking: Option<Setting>,
}

impl Keeper for &mut Memory {
    type Log<'a>
        = NoLog
    where
        Self: 'a;
    fn fault_log(&mut self) -> Option<NoLog> {
        None
    }
}

impl SettingsKeeper for &mut Memory {
    type Error = &'static str;
    fn load(&mut self) -> Result<Option<Held>, Self::Error> {
        if self.broken {
            return Err("the settings' flash does not read");
        }
        Ok(self.saved.map(|saved| {
            Setting::ALL
                .into_iter()
                .filter(|s| Some(*s) != self.lacking)
                .fold(Held::NONE, |held, s| held.with(s, saved.get(s)))
        }))
    }
    fn save(&mut self, settings: &Settings) -> Result<(), Self::Error> {
        self.saved = Some(*settings);
        Ok(())
    }
}

/// A board and its controller slot, asked line by line.
struct Bench<'a, K> {
    board: Board<'a, K>,
    slot: Option<Controller>,
    notice: String,
    warning: Option<String>,
}

impl<'a, K: Keeper> Bench<'a, K> {
    fn boot(image: &'a [u8], keeper: Option<K>, cause: Option<ResetCause>) -> Self {
        let mut slot = None;
        let (board, started) = Board::boot(&mut slot, Image::parse(image), keeper, cause);
        Self {
            board,
            slot,
            notice: started.notice.to_string(),
            warning: started.warning.map(|w| w.to_string()),
        }
    }

    fn ask_then(&mut self, request: &Line) -> (String, Then) {
        let mut out = ReplyLine::new();
        let then = self
            .board
            .serve(request, &mut &mut self.slot, &Extras::default(), &mut out);
        (out.to_string(), then)
    }

    fn ask(&mut self, request: &str) -> String {
        let (reply, then) = self.ask_then(&line(request));
        assert_eq!(then, Then::Reply, "{request}: {reply}");
        reply
    }

    /// `ticks` ticks with `inputs` through a stage that works; the last output's volts.
    fn run(&mut self, ticks: u32, inputs: Inputs) -> f32 {
        let (bus, pin) = (common::Bus::default(), common::Pin::default());
        let mut stage = OutputStage::new(Dac8551::new(&bus), &pin);
        let mut volts = 0.0;
        for _ in 0..ticks {
            if let Some(t) = tick::drive(&mut self.slot, &mut stage, Ok(inputs)) {
                volts = t.output.volts;
            }
        }
        volts
    }
}

/// A `key=value` field of a reply or the start-up line, as a number.
fn field(reply: &str, key: &str) -> f32 {
    reply
        .split(' ')
        .find_map(|word| word.strip_prefix(key)?.strip_prefix('='))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no {key} in {reply}"))
}

/// The reply's error code, or `None` for an `ok`.
fn code(reply: &str) -> Option<u8> {
    reply
        .strip_prefix("err ")
        .map(|rest| rest.split(' ').next().unwrap().parse().unwrap())
}

/// An image of 44 Hz boots and says so: the published 7449.88 V (issue 2) and the image's
/// settings; `get` reads the settings in force.
#[test]
fn the_image_boots_and_says_ready() {
    let bytes = image_with(&Settings::for_target(44.0));
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    assert!(b.notice.starts_with("ready "), "{}", b.notice);
    assert!(b.notice.contains(" settings=image "), "{}", b.notice);
    assert!((field(&b.notice, "bias_volts") - 7449.88).abs() < 0.05);
    assert_eq!(b.warning, None);
    assert_eq!(b.ask("get target_hz"), "ok target_hz=44");
    let status = b.ask("status");
    assert!(status.contains("phase=ramping"), "{status}");
    assert!(status.ends_with("fault=none"), "{status}");
    // `save` without storage says so by its code.
    assert_eq!(code(&b.ask("save")), Some(6));
}

/// A corrupt image drives nothing: the start-up line says why, `status` answers it (phase
/// refused, 0 V), every other request but `help` answers it with code 5, and the slot stays
/// empty.
#[test]
fn a_corrupt_image_is_refused_with_its_reason() {
    let mut bytes = image_with(&Settings::for_target(44.0));
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    assert!(b.notice.starts_with("refused "), "{}", b.notice);
    assert!(b.slot.is_none());
    assert!(b.ask("help").starts_with("ok commands:"));
    let status = b.ask("status");
    assert!(status.starts_with("ok phase=refused volts=0 "), "{status}");
    assert!(
        status.ends_with(&format!("fault={}", &b.notice["refused ".len()..])),
        "{status}"
    );
    for request in ["target 44", "clear", "get target_hz", "save", "trim"] {
        let reply = b.ask(request);
        assert_eq!(code(&reply), Some(5), "{request}: {reply}");
        assert!(reply.contains(&b.notice["refused ".len()..]), "{reply}");
    }
    assert_eq!(b.run(10, Inputs::NONE), 0.0);
}

/// Saved settings boot when their checks pass (`settings=saved`); refused or unreadable,
/// the image's are used and a warning says which and why.
#[test]
fn saved_settings_boot_or_fall_back_to_the_image() {
    let bytes = image_with(&Settings::for_target(44.0));
    let mut memory = Memory {
        saved: Some(Settings::for_target(45.0)),
        ..Memory::default()
    };
    let b = Bench::boot(&bytes, Some(&mut memory), None);
    assert!(b.notice.contains(" settings=saved "), "{}", b.notice);
    assert_eq!(field(&b.notice, "target_hz"), 45.0);
    let hz = common::natural_hz_at(&REFERENCE_DEVICE, field(&b.notice, "bias_volts"));
    assert!((hz / 45.0 - 1.0).abs() < 1e-4, "{hz}");
    // 300 Hz is beyond the reference device's range: refused, the image's 44 Hz boots.
    let mut memory = Memory {
        saved: Some(Settings::for_target(300.0)),
        ..Memory::default()
    };
    let b = Bench::boot(&bytes, Some(&mut memory), None);
    assert!(b.notice.contains(" settings=image "), "{}", b.notice);
    assert_eq!(field(&b.notice, "target_hz"), 44.0);
    let warning = b.warning.unwrap();
    assert!(warning.starts_with("saved settings refused"), "{warning}");
    let mut memory = Memory {
        broken: true,
        ..Memory::default()
    };
    let b = Bench::boot(&bytes, Some(&mut memory), None);
    assert!(b.notice.contains(" settings=image "), "{}", b.notice);
    assert!(b.warning.unwrap().contains("does not read"));
}

/// Saved settings from an earlier firmware, which lack a setting added since: they boot with
/// every value they hold, the new setting at the image's value, and the warning names it.
#[test]
fn saved_settings_lacking_a_new_setting_boot_and_say_it() {
    let image = Settings {
        slew_volts_per_second: 5_000.0,
        ..Settings::for_target(44.0)
    };
    let bytes = image_with(&image);
    let mut memory = Memory {
        saved: Some(Settings {
            slew_volts_per_second: 2_000.0,
            settle_seconds: 0.4,
            ..Settings::for_target(45.0)
        }),
        lacking: Setting::from_key("slew_volts_per_second"),
        ..Memory::default()
    };
    let mut b = Bench::boot(&bytes, Some(&mut memory), None);
    assert!(b.notice.contains(" settings=saved "), "{}", b.notice);
    assert_eq!(field(&b.notice, "target_hz"), 45.0);
    let warning = b.warning.clone().unwrap();
    assert!(
        warning.contains("earlier firmware") && warning.ends_with(": slew_volts_per_second"),
        "{warning}"
    );
    assert_eq!(
        b.ask("get slew_volts_per_second"),
        "ok slew_volts_per_second=5000"
    );
    assert_eq!(b.ask("get settle_seconds"), "ok settle_seconds=0.4");
}

/// The image's front end is checked at the tick rate the board boots with, not only the
/// image's own: saved settings at a rate its scans do not divide (10 kHz over 3 kHz) are
/// refused, saying why, and the image's settings boot (the firmware refused for good on its
/// own before, where host-sim's loop took zero scans).
#[test]
fn saved_settings_whose_tick_rate_the_front_end_cannot_run_fall_back_to_the_image() {
    use de_resonator::acquire::ChannelSpec;
    let table = common::reference_table();
    let current = ChannelSpec {
        input: 0,
        zero_code: 2047.5,
        per_count: 1e-7,
        low: -1e-4,
        high: 1e-4,
        noise_codes: 1.0,
    };
    let front_end = FrontEnd {
        scan_hz: 10_000.0,
        channels: [Some(current), None, None],
    };
    let mut bytes = vec![0; image::image_bytes(table.len())];
    Image::write(
        &mut bytes,
        &REFERENCE_DEVICE.cast(),
        &spec(),
        &front_end,
        &Settings::for_target(44.0),
        PowerUp::Drive,
        &table,
    )
    .unwrap();
    let b = Bench::boot(&bytes, None::<NoKeeper>, None);
    assert!(b.notice.starts_with("ready "), "{}", b.notice);
    let mut memory = Memory {
        saved: Some(Settings {
            tick_hz: 3000.0,
            ..Settings::for_target(44.0)
        }),
        ..Memory::default()
    };
    let b = Bench::boot(&bytes, Some(&mut memory), None);
    assert!(
        b.notice.starts_with("ready ") && b.notice.contains(" settings=image "),
        "{}",
        b.notice
    );
    let warning = b.warning.unwrap();
    assert!(
        warning.starts_with("saved settings refused (") && warning.contains("3000"),
        "{warning}"
    );
}

/// After a watchdog reset the board boots refused, whatever the image: nothing is driven
/// until `clear`, which runs every check and re-arms with the output off at 0 V, and then
/// `start`, which ramps to the image's bias (the settings asked for meanwhile).
#[test]
fn a_watchdog_reset_waits_for_clear() {
    let bytes = image_with(&Settings::for_target(44.0));
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, Some(ResetCause::Watchdog));
    assert!(
        b.notice.starts_with("refused reset by the watchdog"),
        "{}",
        b.notice
    );
    assert!(b.slot.is_none());
    let status = b.ask("status");
    assert!(
        status.starts_with("ok phase=refused volts=0 ") && status.contains("watchdog"),
        "{status}"
    );
    assert_eq!(b.run(5, Inputs::NONE), 0.0);
    // A setting asked for now applies at `clear`.
    assert_eq!(
        b.ask("set target_hz 45"),
        "ok target_hz=45 (applies at `clear`)"
    );
    let cleared = b.ask("clear");
    assert!(
        cleared.starts_with("ok clear: boot checks pass; the output off at 0 V until `start`"),
        "{cleared}"
    );
    let bias: f32 = cleared
        .trim_end_matches(" V)")
        .rsplit(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((common::natural_hz_at(&REFERENCE_DEVICE, bias) / 45.0 - 1.0).abs() < 1e-4);
    // Re-armed, not switched on: nothing driven, whatever the ticks; a setting at rest is
    // checked as a plan and leaves the output off.
    assert_eq!(b.run(2_000, Inputs::NONE), 0.0);
    assert!(b.ask("status").contains("phase=holding"));
    assert_eq!(b.ask("get target_hz"), "ok target_hz=45");
    let set = b.ask("set slew_volts_per_second 5000");
    assert!(
        set.ends_with("(the output stays off: `start` to drive)"),
        "{set}"
    );
    assert_eq!(b.run(500, Inputs::NONE), 0.0);
    assert_eq!(
        b.ask("get slew_volts_per_second"),
        "ok slew_volts_per_second=5000"
    );
    let started = b.ask("start");
    assert!(started.starts_with("ok target_hz=45 "), "{started}");
    assert_eq!(field(&started, "bias_volts"), bias);
    assert!(b.run(3, Inputs::NONE) > 0.0);
}

/// Every request to a running board: its reply, and what it did to the controller.
#[test]
fn every_request_gets_its_reply() {
    let bytes = image_with(&Settings::for_target(44.0));
    let mut memory = Memory::default();
    let mut b = Bench::boot(&bytes, Some(&mut memory), None);
    // Not while the bias ramps.
    assert_eq!(code(&b.ask("target 45")), Some(3));
    b.run(30_000, Inputs::NONE);
    assert!(b.ask("status").contains("phase=holding"));
    // In range: the new bias is the model's for 45 Hz, ramped from the old one.
    let moved = b.ask("target 45");
    assert!(moved.starts_with("ok target_hz=45 "), "{moved}");
    let bias = field(&moved, "bias_volts");
    assert!((common::natural_hz_at(&REFERENCE_DEVICE, bias) / 45.0 - 1.0).abs() < 1e-4);
    assert!(
        (field(&moved, "from_volts") - 7449.88).abs() < 0.05,
        "{moved}"
    );
    assert_eq!(b.ask("get target_hz"), "ok target_hz=45");
    b.run(30_000, Inputs::NONE);
    // Out of range: refused by the checks, the plan in force kept.
    let refused = b.ask("target 300");
    assert_eq!(code(&refused), Some(2), "{refused}");
    assert_eq!(b.ask("get target_hz"), "ok target_hz=45");
    assert_eq!(b.slot.as_ref().unwrap().plan().bias_volts, bias);
    // AC at the resonance of a device flashed without damping: no bound in the model, refused
    // with the figures (model.md §7), the plan in force kept.
    let resonant = b.ask("ac 50 45");
    assert_eq!(code(&resonant), Some(2), "{resonant}");
    assert!(
        resonant.contains("harmonic resonance (drive at the natural frequency)"),
        "{resonant}"
    );
    assert_eq!(b.ask("get ac_volts"), "ok ac_volts=0");
    // AC on, off the resonance: the settings in force carry it.
    let ac = b.ask("ac 50 41");
    assert!(ac.contains("ac_volts=50 ac_hz=41"), "{ac}");
    assert_eq!(b.ask("get ac_volts"), "ok ac_volts=50");
    b.run(30_000, Inputs::NONE);
    // A setting by name; the tick rate only in an image.
    assert!(b.ask("set margin 0.1").starts_with("ok target_hz=45 "));
    assert_eq!(b.ask("get margin"), "ok margin=0.1");
    assert_eq!(code(&b.ask("set tick_hz 2000")), Some(2));
    b.run(30_000, Inputs::NONE);
    // No trim set: refused by name.
    assert_eq!(code(&b.ask("trim")), Some(2));
    // Bad lines.
    assert_eq!(code(&b.ask("frobnicate")), Some(1));
    assert_eq!(code(&b.ask_then(&Line::TooLong).0), Some(1));
    assert_eq!(code(&b.ask_then(&Line::Garbled).0), Some(1));
    // Save: the settings in force, as the next boot reads them.
    assert!(b.ask("save").starts_with("ok save"));
    // Stop: down to 0 V; `clear` only there.
    b.run(30_000, Inputs::NONE);
    assert!(b.ask("stop").starts_with("ok stop: ramp from "));
    assert_eq!(code(&b.ask("clear")), Some(7));
    assert_eq!(b.run(60_000, Inputs::NONE), 0.0);
    assert!(b.ask("status").contains("phase=holding"));
    // At rest, a stop has nothing to ramp, and says so (not "from 0 V to 0 V").
    assert_eq!(b.ask("stop"), "ok stop: at 0 V, the output off");
    b.run(10, Inputs::NONE);
    // A typo of a command is named, as `help <typo>` names it.
    let typo = b.ask("stauts");
    assert!(
        code(&typo) == Some(1) && typo.contains("did you mean `status`?"),
        "{typo}"
    );
    assert_eq!(code(&b.ask("trim")), Some(2));
    let (reply, then) = b.ask_then(&line("reset"));
    assert_eq!(
        (reply.as_str(), then),
        ("ok reset: output off, restarting", Then::Reset)
    );
    drop(b);
    let saved = memory.saved.unwrap();
    assert_eq!(
        (saved.target_hz, saved.ac_volts, saved.margin),
        (45.0, 50.0, 0.1)
    );
    // The restart boots the saved settings.
    let b = Bench::boot(&bytes, Some(&mut memory), Some(ResetCause::Asked));
    assert!(b.notice.contains(" settings=saved "), "{}", b.notice);
}

/// A fault latches: the output comes down (never up) to 0 V, requests answer `faulted`,
/// `clear` is refused on the way down and boots again at 0 V.
#[test]
fn a_fault_latches_until_clear_at_zero() {
    let bytes = image_with(&Settings::for_target(44.0));
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    b.run(30_000, Inputs::NONE);
    // A stretch sensor that reads NaN is a fault at once.
    let (bus, pin) = (common::Bus::default(), common::Pin::default());
    let mut stage = OutputStage::new(Dac8551::new(&bus), &pin);
    let first = tick::drive(&mut b.slot, &mut stage, Ok(Inputs::stretch(f32::NAN))).unwrap();
    assert!(matches!(
        first.output.event,
        Some(de_resonator::Event::Fault(_))
    ));
    assert_eq!(code(&b.ask("target 45")), Some(4));
    assert_eq!(code(&b.ask("clear")), Some(7));
    let mut last = first.output.volts;
    for _ in 0..60_000 {
        let t = tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE)).unwrap();
        assert!(t.output.volts <= last);
        last = t.output.volts;
    }
    assert_eq!(last, 0.0);
    assert!(
        stage.is_safe() && !pin.high.get(),
        "the stage off at the descent's end"
    );
    let status = b.ask("status");
    assert!(
        status.contains("phase=faulted") && !status.ends_with("fault=none"),
        "{status}"
    );
    assert!(b.ask("clear").starts_with("ok clear"));
    assert!(b.ask("status").ends_with("fault=none"));
    // Cleared, the output stays off until asked: the enable line never high, from the
    // first tick on.
    for k in 0..2_000 {
        let t = tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE)).unwrap();
        assert_eq!(t.output.volts, 0.0);
        assert!(
            stage.is_safe() && !pin.high.get(),
            "on at tick {k} after clear"
        );
    }
    // `start` switches it on.
    let started = b.ask("start");
    assert!(started.starts_with("ok target_hz=44 "), "{started}");
    let mut volts = 0.0;
    for _ in 0..3 {
        volts = tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE))
            .unwrap()
            .output
            .volts;
    }
    assert!(volts > 0.0 && pin.high.get(), "{volts} V after start");
}

/// The one enable policy: off with no controller, on while a plan drives, off again at
/// rest at 0 V after `stop`, on at the next plan; a dead bus drops the line at once.
#[test]
fn the_amplifier_is_on_only_while_a_plan_drives() {
    let bytes = image_with(&Settings::for_target(44.0));
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    let (bus, pin) = (common::Bus::default(), common::Pin::default());
    let mut stage = OutputStage::new(Dac8551::new(&bus), &pin);
    let _ = stage.safe();
    assert!(tick::drive(&mut None, &mut stage, Ok(Inputs::NONE)).is_none());
    assert!(!pin.high.get());
    tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE));
    assert!(pin.high.get());
    for _ in 0..30_000 {
        tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE));
    }
    b.ask("stop");
    for _ in 0..60_000 {
        tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE));
    }
    assert!(!pin.high.get() && stage.is_safe());
    assert!(b.ask("target 44").starts_with("ok "));
    tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE));
    assert!(pin.high.get());
    bus.fails.set(true);
    let t = tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE)).unwrap();
    assert_eq!(
        t.output.event,
        Some(de_resonator::Event::Fault(de_resonator::Fault::Bus))
    );
    assert!(!pin.high.get());
}

/// Issue 26: tracking's slope solve reaches the background job through the board's tick,
/// as the firmware wires it (its work task once woke only for a trim's solve, so the bias's
/// integral law never got its slope).
#[cfg(feature = "track")]
#[test]
fn tracking_slope_reaches_the_background_job() {
    use de_resonator::Phase;
    let settings = Settings {
        ac_volts: 30.0,
        ac_hz: 45.5,
        trim_tolerance: Some(5e-4),
        track_seconds: Some(0.2),
        ..Settings::for_target(45.5)
    };
    // The device flashed says half the plant's damping: a drive at the resonance has a bound.
    let told = common::with_quality_factor(REFERENCE_DEVICE, 100.0);
    let table = common::made_table(told, 0.05, 64);
    let mut bytes = vec![0; image::image_bytes(table.len())];
    Image::write(
        &mut bytes,
        &told.cast(),
        &spec(),
        &FrontEnd::NONE,
        &settings,
        PowerUp::Drive,
        &table,
    )
    .unwrap();
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    let mut plant = common::Plant::new(common::with_quality_factor(REFERENCE_DEVICE, 50.0), 1e3);
    let (bus, pin) = (common::Bus::default(), common::Pin::default());
    let mut stage = OutputStage::new(Dac8551::new(&bus), &pin);
    let (mut while_driving, mut jobs) = (0, 0);
    for _ in 0..10_000 {
        let t = tick::drive(
            &mut b.slot,
            &mut stage,
            Ok(Inputs::stretch(plant.stretch() as f32)),
        )
        .unwrap();
        plant.step(t.output.volts);
        if t.job_wanted {
            let driving = b.slot.as_ref().unwrap().phase() == Phase::Driving;
            let ran = tick::run_job(|f| f(b.slot.as_mut().unwrap()));
            assert!(ran);
            jobs += 1;
            while_driving += usize::from(driving);
        }
    }
    assert!(
        jobs >= 2 && while_driving >= 1,
        "{jobs} jobs, {while_driving} while driving"
    );
    assert_eq!(b.slot.as_ref().unwrap().latched_fault(), None);
}

/// The watchdog's feeding: at 1 kHz the low-priority tasks may go 0.5 s (500 ticks) without
/// checking in; the dog starts with the first controller, is fed while they check in, asked
/// for a heartbeat four times a deadline while they are late, and starves after 500 ticks.
#[test]
fn the_dog_is_fed_only_while_the_tasks_check_in() {
    use de_resonator::board::watchdog::{CheckIn, Feed, CHECK_IN_SECONDS};
    let deadline = (CHECK_IN_SECONDS * 1000.0) as u32;
    assert_eq!(deadline, 500);
    let mut dog = CheckIn::new(1000.0);
    // Nothing runs: not started (fed or not, it does not bite before its start).
    assert!(!dog.tick(true, false).start);
    let first = dog.tick(true, true);
    assert_eq!(
        first,
        Feed {
            start: true,
            feed: true,
            heartbeat: false
        }
    );
    assert!(!dog.tick(true, true).start, "started once");
    let (mut fed, mut heartbeats) = (0, Vec::new());
    for k in 1..=600u32 {
        let f = dog.tick(false, true);
        fed += u32::from(f.feed);
        if f.heartbeat {
            heartbeats.push(k);
        }
    }
    assert_eq!(fed, deadline, "fed up to the deadline, then starved");
    assert_eq!(heartbeats[..4], [125, 250, 375, 500]);
    // A check-in feeds it again at once.
    assert!(dog.tick(true, true).feed);
}

/// `reset` and `clear` wait for rest at 0 V: refused under the bias; after a dead bus (the
/// command dropped at once, the output following through the amplifier at best at the slew
/// rate) refused for the time the slew rate needs from the bias, then done.
#[test]
fn reset_and_clear_wait_for_rest_at_zero() {
    let bytes = image_with(&Settings::for_target(44.0));
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    b.run(30_000, Inputs::NONE);
    let (reply, then) = b.ask_then(&line("reset"));
    assert_eq!(code(&reply), Some(7), "{reply}");
    assert_eq!(then, Then::Reply);
    assert!(b.slot.is_some(), "the controller stays");
    // The bus dies at the bias.
    let slew = field(&b.ask("get slew_volts_per_second"), "slew_volts_per_second");
    let bias = b.slot.as_ref().unwrap().plan().bias_volts;
    let settle_ticks = (bias / slew * 1000.0) as u32;
    assert!(settle_ticks > 100, "{settle_ticks}");
    let (bus, pin) = (common::Bus::default(), common::Pin::default());
    let mut stage = OutputStage::new(Dac8551::new(&bus), &pin);
    tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE));
    bus.fails.set(true);
    let t = tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE)).unwrap();
    assert_eq!(t.output.volts, 0.0, "0 V commanded at once");
    for _ in 0..settle_ticks * 9 / 10 {
        tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE));
    }
    assert_eq!(code(&b.ask("clear")), Some(7));
    assert_eq!(code(&b.ask_then(&line("reset")).0), Some(7));
    for _ in 0..settle_ticks / 5 {
        tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE));
    }
    let (reply, then) = b.ask_then(&line("reset"));
    assert_eq!(
        (reply.as_str(), then),
        ("ok reset: output off, restarting", Then::Reset)
    );
    assert!(b.slot.is_none(), "taken out with the check");
}

/// A refusal only the firmware finds (a tick rate beyond its timer) holds for good: `clear`
/// cannot lift it. A boot refusal `clear` can lift keeps the settings asked for meanwhile,
/// and `save` saves those.
#[test]
fn refusals_hold_or_lift_as_they_say() {
    let bytes = image_with(&Settings::for_target(44.0));
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    let mut notice = ReplyLine::new();
    b.board.refuse(
        &mut b.slot,
        &"tick_hz = 1e9 is beyond the timer's reach",
        &mut notice,
    );
    assert_eq!(
        notice.as_str(),
        "refused tick_hz = 1e9 is beyond the timer's reach"
    );
    assert!(b.slot.is_none());
    for request in ["clear", "set target_hz 45"] {
        let reply = b.ask(request);
        assert_eq!(code(&reply), Some(5), "{request}: {reply}");
        assert!(reply.contains("beyond the timer's reach"), "{reply}");
    }
    let status = b.ask("status");
    assert!(
        status.starts_with("ok phase=refused") && status.contains("beyond the timer's reach"),
        "{status}"
    );
    let mut memory = Memory::default();
    let mut b = Bench::boot(&bytes, Some(&mut memory), Some(ResetCause::Watchdog));
    assert!(b.ask("set target_hz 45").ends_with("(applies at `clear`)"));
    assert!(b.ask("save").starts_with("ok save"));
    drop(b);
    assert_eq!(memory.saved.unwrap().target_hz, 45.0);
}

/// Each request under its command's rule: on an image whose boot was refused, every request
/// that drives is refused with the reason (`err 5`), not answered by a controller that is not
/// there; `stream` by the board's port, its rate as the tick's whole divisor; `status` says
/// whether the output is on.
#[test]
fn requests_keep_their_rules_and_say_what_is() {
    let bytes = image_with(&Settings::for_target(44.0));
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    // The stream: no port, `err 6`; with one, 100 Hz is every 10th tick of 1 kHz, a frame
    // of 66 bytes each, 6,600 B/s; off.
    assert_eq!(code(&b.ask("stream 100")), Some(6));
    let with_port = Extras {
        stream_port: true,
        ..Extras::default()
    };
    let mut out = ReplyLine::new();
    let then = b
        .board
        .serve(&line("stream 100"), &mut &mut b.slot, &with_port, &mut out);
    assert_eq!(
        (out.as_str(), then),
        (
            "ok stream hz=100 every_ticks=10 frame_bytes=66 bytes_per_second=6600",
            Then::Stream(Some(10))
        )
    );
    let then = b
        .board
        .serve(&line("stream off"), &mut &mut b.slot, &with_port, &mut out);
    assert_eq!((out.as_str(), then), ("ok stream off", Then::Stream(None)));
    // The output: on while the ramp and the hold drive, off once stopped at 0 V.
    assert!(b.ask("status").contains(" output=on "));
    b.run(30_000, Inputs::NONE);
    assert!(b.ask("status").contains(" output=on "));
    b.ask("stop");
    b.run(60_000, Inputs::NONE);
    assert!(b.ask("status").contains(" output=off "));
    // An image whose own settings the boot refuses (a target outside its table): the image
    // is there, no controller runs.
    let bytes = image_with(&Settings::for_target(300.0));
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    assert!(
        b.slot.is_none() && b.board.image().is_some(),
        "{}",
        b.notice
    );
    let why = b.board.refusal().unwrap().to_string();
    for request in ["start", "target 45", "ac 10 40", "stop", "trim", "reset"] {
        let reply = b.ask(request);
        assert_eq!(reply, format!("err 5 {why}"), "{request}");
    }
    // What needs only the image still answers.
    assert_eq!(b.ask("get target_hz"), "ok target_hz=300");
}

/// Issue 29, 1: an image that waits (the default of `host-sim image`) boots its checks and
/// says so, but drives nothing, the stage off, until `start`; then ramps to the bias.
#[test]
fn an_image_that_waits_drives_only_at_start() {
    let bytes = image_of(&Settings::for_target(44.0), &spec(), PowerUp::Wait);
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    assert!(b.notice.starts_with("ready "), "{}", b.notice);
    assert!(
        b.notice
            .ends_with("power_up=wait output=off (the output off at 0 V: `start` to drive)"),
        "{}",
        b.notice
    );
    let bias = field(&b.notice, "bias_volts");
    let (bus, pin) = (common::Bus::default(), common::Pin::default());
    let mut stage = OutputStage::new(Dac8551::new(&bus), &pin);
    for _ in 0..2000 {
        let t = tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE)).unwrap();
        assert_eq!(t.output.volts, 0.0);
        assert!(stage.is_safe(), "the stage stays off");
    }
    assert!(b.ask("status").contains(" volts=0 "));
    assert!(b.ask("start").starts_with("ok target_hz=44 "));
    // 10 kV/s from 0 V: at the bias within a second.
    let mut volts = 0.0;
    for _ in 0..1500 {
        volts = tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE))
            .unwrap()
            .output
            .volts;
    }
    assert!(!stage.is_safe());
    assert!((volts - bias).abs() < 0.5, "{volts} vs {bias}");
    // One that drives at power-up says so and ramps at once.
    let bytes = image_of(&Settings::for_target(44.0), &spec(), PowerUp::Drive);
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    assert!(
        b.notice.ends_with("power_up=drive output=on"),
        "{}",
        b.notice
    );
    assert!(b.run(100, Inputs::NONE) > 0.0);
    // After a `reset` (asked at rest at 0 V) it comes up off: no command named `reset`
    // switches the high voltage on.
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, Some(ResetCause::Asked));
    assert!(
        b.notice
            .ends_with("power_up=drive output=off (after a reset the output stays off at 0 V: `start` to drive)"),
        "{}",
        b.notice
    );
    let (bus, pin) = (common::Bus::default(), common::Pin::default());
    let mut stage = OutputStage::new(Dac8551::new(&bus), &pin);
    for _ in 0..2000 {
        let t = tick::drive(&mut b.slot, &mut stage, Ok(Inputs::NONE)).unwrap();
        assert_eq!(t.output.volts, 0.0);
        assert!(stage.is_safe());
    }
    assert!(b.ask("start").starts_with("ok target_hz=44 "));
}

/// Issue 29, 6: with the amplifier's rail (7600 V) below the cap in force, `status` and the start-up line give the lower as the most the
/// board commands, and say which bounds it.
#[test]
fn status_gives_the_lower_of_the_cap_and_the_rail() {
    let rail = AmplifierSpec {
        rail_volts: 7600.0,
        ..spec()
    };
    let bytes = image_of(&Settings::for_target(44.0), &rail, PowerUp::Drive);
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    assert_eq!(field(&b.notice, "max_volts"), 7600.0, "{}", b.notice);
    let status = b.ask("status");
    assert_eq!(field(&status, "max_volts"), 7600.0, "{status}");
    assert!(status.contains(" max_by=amplifier "), "{status}");
    // With the rail at 10 kV the cap (above 7600 V, or the rail would not have been the
    // lower) is the bound.
    let bytes = image_with(&Settings::for_target(44.0));
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    let status = b.ask("status");
    let cap = field(&status, "max_volts");
    assert!(cap > 7600.0 && cap < 10_000.0, "{status}");
    assert!(status.contains(" max_by=cap "), "{status}");
}

/// Issue 29, 5: replies that say why. `get` lists every setting; `help <setting>` its unit
/// and rule; a typo gets the nearest key; an AC the cap cannot hold says the span it would
/// drive and the cap; `clear` while driving is a wrong state (7), not busy (3).
#[test]
fn replies_say_why() {
    let bytes = image_with(&Settings::for_target(44.0));
    let mut b = Bench::boot(&bytes, None::<NoKeeper>, None);
    let all = b.ask("get");
    for setting in de_resonator::Setting::ALL {
        let one = b.ask(&format!("get {}", setting.key()));
        let pair = one.strip_prefix("ok ").unwrap();
        assert!(
            all.split(' ').any(|word| word == pair),
            "{pair} not in {all}"
        );
    }
    assert_eq!(
        b.ask("help ac_volts"),
        format!("ok ac_volts (V): {}", de_resonator::Setting::AcVolts.rule())
    );
    let typo = b.ask("set ac_volt 100");
    assert!(
        typo.starts_with(&format!(
            "{}unknown setting; did you mean `ac_volts`?",
            refused_with(ErrorCode::Syntax)
        )),
        "{typo}"
    );
    b.run(30_000, Inputs::NONE);
    let status = b.ask("status");
    let (bias, cap) = (field(&status, "bias_volts"), field(&status, "max_volts"));
    let refused = b.ask("ac 5000 28");
    assert_eq!(code(&refused), Some(2), "{refused}");
    let words: Vec<&str> = refused.split(' ').collect();
    let at = words.iter().position(|w| *w == "spans").unwrap();
    let number = |k: usize| words[k].parse::<f32>().unwrap();
    assert!(
        (number(at + 1) - (bias - 5000.0)).abs() < 0.01
            && (number(at + 3) - (bias + 5000.0)).abs() < 0.01,
        "{refused} (bias {bias})"
    );
    assert!(refused.contains(" V: above the cap "), "{refused}");
    // The cap it names: the plan's (at or under the one `status` gives, within 0.5%).
    let named: f32 = refused
        .rsplit(' ')
        .nth(1)
        .and_then(|v| v.parse().ok())
        .unwrap();
    assert!(named <= cap && named > 0.995 * cap, "{named} vs {cap}");
    assert_eq!(code(&b.ask("clear")), Some(7));
}

/// The fault log through the board: a watchdog reset logged at the boot after it; faults
/// logged as the command task writes them; `faults` lists the newest 32 newest first, past
/// the first half's turn; `faults <n>` gives one whole; a board with no log says so.
#[cfg(feature = "storage")]
#[test]
fn the_fault_log_lists_the_newest_first_across_resets() {
    use de_resonator::fault_log::KEPT;
    use de_resonator::flash::RAM_PAGE_BYTES;
    use de_resonator::Fault;

    let image = image_with(&Settings::for_target(44.0));
    let mut bytes = vec![0xFFu8; 6 * RAM_PAGE_BYTES];
    {
        let mut bench = Bench::boot(
            &image,
            Some(flash_keeper(&mut bytes, false)),
            Some(ResetCause::Watchdog),
        );
        assert_eq!(bench.ask("faults"), "ok faults=1 | 1 watchdog t=0");
        for n in 0..40u32 {
            let fault = Fault::Sensor { value: n as f32 };
            let logged =
                bench
                    .board
                    .log_fault(&fault, (100 * n, n as f32 / 10.0), 5.0, &Inputs::NONE);
            assert_eq!(logged, Some(Ok(n + 2)));
        }
    }
    // A reset: a new board on the same flash.
    let mut bench = Bench::boot(
        &image,
        Some(flash_keeper(&mut bytes, false)),
        Some(ResetCause::Asked),
    );
    let list = bench.ask("faults");
    let expected: String = (2..=41u32)
        .rev()
        .take(KEPT)
        .map(|s| format!(" | {s} sensor t={}", 100 * (s - 2)))
        .collect();
    assert_eq!(list, format!("ok faults={KEPT}{expected}"));
    let one = bench.ask("faults 41");
    assert_eq!(
        one,
        "ok sequence=41 cause=sensor tick=3900 seconds=3.9 volts=5 \
         words=sensor sample 39 is not a number"
    );
    // Past the list's 32, the full older half still holds the first entries.
    assert!(
        bench
            .ask("faults 1")
            .starts_with("ok sequence=1 cause=watchdog tick=0 "),
        "the watchdog's entry, in the older half"
    );
    assert_eq!(code(&bench.ask("faults 42")), Some(2), "no such entry");
    // A long sentence kept whole with every figure in it: the reading, the limit, the
    // voltage sent before the fault, the inputs read.
    let trip = Fault::NearLimit {
        mode: de_resonator::FailureMode::LossOfTension2b,
        tick: 51_234,
        stretch: 1.0123,
        volts: 7498.017,
    };
    let stretch = Inputs {
        stretch: Some(1.0123),
        ..Inputs::NONE
    };
    let logged = bench
        .board
        .log_fault(&trip, (51_234, 51.234), 7498.017, &stretch);
    assert_eq!(logged, Some(Ok(42)));
    let sentence = trip.to_string();
    assert!(sentence.len() > 100, "{sentence}");
    assert_eq!(
        bench.ask("faults 42"),
        format!(
            "ok sequence=42 cause=near_limit tick=51234 seconds=51.234 volts=7498.017 \
             stretch=1.0123 words={sentence}"
        )
    );
    // Clearing erases flash (a stall on a chip): at rest at 0 V only. A board that drives at
    // power-up, ramping:
    drop(bench);
    let mut bench = Bench::boot(&image, Some(flash_keeper(&mut bytes, false)), None);
    bench.run(10, Inputs::NONE);
    assert_eq!(code(&bench.ask("faults clear")), Some(7), "while ramping");
    assert!(bench.ask("stop").starts_with("ok stop"));
    bench.run(3000, Inputs::NONE);
    assert_eq!(bench.ask("faults clear"), "ok faults cleared");
    assert_eq!(bench.ask("faults"), "ok faults=0");
    // The longest list the reply line holds: the longest key and tick, 32 of them; what does
    // not fit is said, no entry cut.
    for _ in 0..KEPT {
        let fault = Fault::AmplifierDisagrees {
            commanded_volts: 1.0,
            measured_volts: 2.0,
        };
        let at = (u32::MAX - 1, 1e6);
        assert!(matches!(
            bench.board.log_fault(&fault, at, 0.0, &Inputs::NONE),
            Some(Ok(_))
        ));
    }
    let list = bench.ask("faults");
    let items: Vec<&str> = list.split(" | ").skip(1).collect();
    assert!(items.len() > 16, "{list}");
    let (last, whole) = items.split_last().unwrap();
    assert_eq!(*last, "… (older: `faults <n>`)", "{list}");
    for item in whole {
        assert!(
            item.ends_with(" amplifier_disagrees t=4294967294"),
            "{item}"
        );
    }
    let mut none = Bench::<NoKeeper>::boot(&image, None, None);
    assert_eq!(code(&none.ask("faults")), Some(6));
}

/// Where an erase stalls the chip past its watchdog (`FlashKeeper::erase_stalls`), `save`
/// waits for the output at rest at 0 V; where it does not (RAM: QEMU, the virtual board), it
/// saves while driving.
#[cfg(feature = "storage")]
#[test]
fn a_save_on_a_chip_waits_for_rest() {
    use de_resonator::board::FlashKeeper;
    use de_resonator::flash::{RamFlash, RAM_PAGE_BYTES};

    let image = image_with(&Settings::for_target(44.0));
    for stalls in [true, false] {
        let mut bytes = vec![0xFFu8; 2 * RAM_PAGE_BYTES];
        let keeper = FlashKeeper {
            flash: RamFlash::new(&mut bytes),
            range: 0..(2 * RAM_PAGE_BYTES) as u32,
            log: None,
            erase_stalls: stalls,
        };
        let mut bench = Bench::boot(&image, Some(keeper), None);
        bench.run(10, Inputs::NONE);
        let reply = bench.ask("save");
        if stalls {
            assert_eq!(code(&reply), Some(7), "while ramping: {reply}");
            assert!(bench.ask("stop").starts_with("ok stop"));
            bench.run(3000, Inputs::NONE);
            assert!(bench.ask("save").starts_with("ok save"));
        } else {
            assert!(reply.starts_with("ok save"), "{reply}");
        }
    }
}

/// The bytes a terminal or a program sends, into lines: a line ends at `\n` (a program), `\r`
/// (a serial terminal's Enter: picocom, minicom, PuTTY) or `\r\n` (one end, not two); a
/// program's Enter on nothing is an empty line (answered, not waited on), a terminal's a
/// fresh prompt; an overlong line is one `TooLong` at its end, whatever ends it.
#[test]
fn lines_end_at_a_line_feed_a_carriage_return_or_both() {
    use de_resonator::board::Lines;
    use de_resonator::wire::protocol::MAX_LINE;
    let lines_of = |bytes: &[u8]| {
        let mut lines = Lines::default();
        bytes
            .iter()
            .filter_map(|&b| lines.push(b).line)
            .collect::<Vec<Line>>()
    };
    for ending in ["\n", "\r", "\r\n"] {
        let sent = format!("status{ending}get tick_hz{ending}");
        assert_eq!(
            lines_of(sent.as_bytes()),
            [line("status"), line("get tick_hz")],
            "{ending:?}"
        );
    }
    // The second bare `\r` is a terminal's Enter on nothing: a fresh prompt, no line; a
    // program's empty lines (`\n`, `\r\n`) are lines, answered.
    assert_eq!(
        lines_of(b"a\r\rb\n\nc\r\n\r\n"),
        [line("a"), line("b"), line(""), line("c"), line("")]
    );
    // A request split anywhere, a `\r\n` split between two reads, as bytes arrive.
    let mut lines = Lines::default();
    let got: Vec<Line> = [&b"sta"[..], b"tus\r", b"\nstop\r"]
        .iter()
        .flat_map(|part| {
            part.iter()
                .filter_map(|&b| lines.push(b).line)
                .collect::<Vec<_>>()
        })
        .collect();
    assert_eq!(got, [line("status"), line("stop")]);
    let long = [b'x'; MAX_LINE + 5];
    for ending in [&b"\r"[..], b"\n", b"\r\n"] {
        let sent: Vec<u8> = long
            .iter()
            .chain(ending)
            .chain(b"info\r")
            .copied()
            .collect();
        assert_eq!(lines_of(&sent), [Line::TooLong, line("info")], "{ending:?}");
    }
}

/// What a person at a serial terminal types gets a serial console's echo and editing; a
/// program (LF or CRLF, no edits) sees not one byte more than before.
#[test]
fn a_terminal_gets_echo_and_editing_and_a_program_gets_neither() {
    use de_resonator::board::{Echo, Lines, REPLY_END, TERMINAL_REPLY_END};
    use de_resonator::wire::protocol::MAX_LINE;
    let typed = |lines: &mut Lines, bytes: &[u8]| {
        let mut echoed = Vec::new();
        let mut got = Vec::new();
        for &b in bytes {
            let pushed = lines.push(b);
            pushed.echo.bytes(|e| echoed.push(e));
            got.extend(pushed.line);
        }
        (got, echoed)
    };
    // Programs: LF or CRLF line ends, whatever they send, no echo, `\n` after replies.
    for ending in ["\n", "\r\n"] {
        let mut lines = Lines::default();
        let sent = format!("status{ending}get tick_hz{ending}stop{ending}");
        let (got, echoed) = typed(&mut lines, sent.as_bytes());
        assert_eq!(got, [line("status"), line("get tick_hz"), line("stop")]);
        assert!(echoed.is_empty(), "{ending:?}: {echoed:?}");
        assert_eq!(lines.reply_end(), REPLY_END);
    }
    // A terminal: Enter is a bare CR. The first line is answered as to a program (a CR
    // followed by nothing yet is not known); from the byte after it, echo and editing.
    let mut lines = Lines::default();
    let (got, echoed) = typed(&mut lines, b"status\r");
    assert_eq!((got, echoed), (vec![line("status")], vec![]));
    assert!(!lines.terminal());
    let (got, echoed) = typed(&mut lines, b"stpo\x7f\x7fop\r");
    assert_eq!(got, [line("stop")]);
    // The first byte after the bare CR: back to the line's start, the prompt, the byte.
    assert_eq!(echoed, b"\r> stpo\x08 \x08\x08 \x08op\r\n");
    assert!(lines.terminal());
    assert_eq!(lines.reply_end(), TERMINAL_REPLY_END);
    // Ctrl-U rubs out the line; backspace on an empty line does nothing; a control byte is
    // kept in the line (and refused there) but not echoed.
    let (got, echoed) = typed(&mut lines, b"help\x15\x08inf\x01o\r");
    assert_eq!(
        got,
        [Line::Text(heapless::Vec::from_slice(b"inf\x01o").unwrap())]
    );
    assert_eq!(echoed, b"help\x08 \x08\x08 \x08\x08 \x08\x08 \x08info\r\n");
    // A line ended by `\n` is a program's: the terminal's mode ends with it, and a script
    // that follows on the same port sees its plain replies.
    let (got, echoed) = typed(&mut lines, b"status\nget tick_hz\n");
    assert_eq!(got, [line("status"), line("get tick_hz")]);
    assert_eq!(echoed, b"status");
    assert!(!lines.terminal());
    assert_eq!(lines.reply_end(), REPLY_END);
    // Past the longest line nothing is echoed, and backspace takes those bytes first: the
    // screen and the line agree. A control byte is kept but not shown, and rubbed out
    // without moving the cursor.
    let mut lines = Lines::default();
    let _ = typed(&mut lines, b"\r");
    let mut long = b"x".repeat(MAX_LINE + 4);
    long.extend([0x7f; MAX_LINE + 4]);
    long.extend(b"st\x1bx\x7f\x7fatus\r");
    let (got, echoed) = typed(&mut lines, &long);
    assert_eq!(got, [line("status")]);
    let mut expected = b"\r> ".to_vec();
    expected.extend(b"x".repeat(MAX_LINE));
    expected.extend(b"\x08 \x08".repeat(MAX_LINE));
    expected.extend(b"stx\x08 \x08atus\r\n");
    assert_eq!(echoed, expected);
    // Ctrl-U rubs out what was shown, and a byte lost from the line goes with it.
    lines.lost();
    let (got, echoed) = typed(&mut lines, b"s\x01t\x15info\r");
    assert_eq!(got, [line("info")]);
    assert_eq!(echoed, b"st\x08 \x08\x08 \x08info\r\n");
    // An edit marks a terminal at once.
    let mut lines = Lines::default();
    let (got, echoed) = typed(&mut lines, b"statux\x08s\r");
    assert_eq!(got, [line("status")]);
    assert_eq!(echoed, b"\x08 \x08s\r\n");
    assert_eq!(lines.push(b'x').echo, Echo::Byte(b'x'));
    // Enter on an empty line at a terminal: a fresh prompt, as a shell gives, and no request
    // (no `err`); the terminal's mode holds. A program's empty line is still a request.
    let mut lines = Lines::default();
    let _ = typed(&mut lines, b"status\r");
    let (got, echoed) = typed(&mut lines, b"\r\r");
    assert_eq!((got, echoed), (vec![], b"\r\n> \r\n> ".to_vec()));
    assert!(lines.terminal());
    let (got, _) = typed(&mut lines, b"stop\r");
    assert_eq!(got, [line("stop")]);
    let mut lines = Lines::default();
    let (got, echoed) = typed(&mut lines, b"\n\r\n");
    assert_eq!(got, [line(""), line("")]);
    assert!(echoed.is_empty());
}

/// A keeper with a fault log in memory (its entries as written).
#[derive(Default)]
struct Entries(Vec<de_resonator::fault_log::Entry>);

impl SettingsKeeper for &mut Entries {
    type Error = &'static str;
    fn load(&mut self) -> Result<Option<Held>, Self::Error> {
        Ok(None)
    }
    fn save(&mut self, _: &Settings) -> Result<(), Self::Error> {
        Err("no settings storage")
    }
}

impl Keeper for &mut Entries {
    type Log<'a>
        = EntriesLog<'a>
    where
        Self: 'a;
    fn fault_log(&mut self) -> Option<EntriesLog<'_>> {
        Some(EntriesLog(&mut self.0))
    }
}

/// Its fault log, borrowed.
struct EntriesLog<'a>(&'a mut Vec<de_resonator::fault_log::Entry>);

impl FaultKeeper for EntriesLog<'_> {
    type Error = &'static str;
    /// Numbered from 1, as the flash's log numbers its entries.
    fn log(&mut self, entry: &de_resonator::fault_log::Entry) -> Result<u32, Self::Error> {
        let sequence = self.0.len() as u32 + 1;
        self.0.push(de_resonator::fault_log::Entry {
            sequence,
            ..entry.clone()
        });
        Ok(sequence)
    }
    fn prepare(&mut self) -> Result<bool, Self::Error> {
        Ok(false)
    }
    fn each(
        &mut self,
        each: &mut dyn FnMut(de_resonator::fault_log::Entry),
    ) -> Result<(), Self::Error> {
        self.0.iter().cloned().for_each(each);
        Ok(())
    }
    fn clear(&mut self) -> Result<(), Self::Error> {
        self.0.clear();
        Ok(())
    }
}

/// The board's runner end to end: a fault the tick saw latch goes into the fault log at its
/// board tick, its time since boot at the tick rate in force, the voltage sent before it and
/// the readings that tripped it.
#[test]
fn a_fault_the_tick_saw_is_logged_at_its_tick_and_time() {
    use de_resonator::board::runner::Ticker;
    let settings = Settings {
        tick_hz: 4000.0,
        ..Settings::for_target(44.0)
    };
    let bytes = image_with(&settings);
    let mut entries = Entries::default();
    let mut b = Bench::boot(&bytes, Some(&mut entries), None);
    assert!(b.notice.starts_with("ready "), "{}", b.notice);
    let (bus, pin) = (common::Bus::default(), common::Pin::default());
    let mut stage = OutputStage::new(Dac8551::new(&bus), &pin);
    let mut ticker = Ticker::new();
    let mut before = 0.0;
    for _ in 0..40 {
        before = ticker
            .tick(Ok(Inputs::NONE), &mut b.slot, &mut stage)
            .ticked
            .unwrap()
            .output
            .volts;
    }
    let nan = Inputs::stretch(f32::NAN);
    let logged = ticker
        .tick(Ok(nan), &mut b.slot, &mut stage)
        .logged()
        .expect("a fault");
    let tick_hz = b.board.tick_hz(&b.slot);
    assert_eq!(tick_hz, 4000.0);
    assert_eq!(b.board.log(&logged, tick_hz), Some(Ok(1)));
    drop(b);
    let entry = &entries.0[0];
    assert_eq!(entry.tick, 40);
    assert_eq!(entry.seconds, 0.01, "40 ticks at 4 kHz");
    assert_eq!(entry.volts, before);
    assert!(before > 0.0);
    assert!(entry.stretch.is_some_and(f32::is_nan));
    // The next boot reads it through the command port: listed, whole, then cleared at rest.
    let mut b = Bench::boot(&bytes, Some(&mut entries), None);
    let listed = b.ask("faults");
    assert!(
        listed.starts_with("ok faults=1 | 1 ") && listed.ends_with(" t=40"),
        "{listed}"
    );
    let one = b.ask("faults 1");
    assert!(
        one.starts_with("ok sequence=1 ") && one.contains(" tick=40 seconds=0.01 "),
        "{one}"
    );
    assert!(b.ask("stop").starts_with("ok stop"));
    b.run(100, Inputs::NONE);
    assert_eq!(b.ask("faults clear"), "ok faults cleared");
    assert_eq!(b.ask("faults"), "ok faults=0");
    drop(b);
    assert!(entries.0.is_empty());
}

/// A board that keeps its settings but no fault log: `save` keeps them, `faults` answers
/// that there is no log (unsupported, not an empty one).
#[test]
fn a_board_without_a_fault_log_says_so() {
    let bytes = image_with(&Settings::for_target(44.0));
    let mut memory = Memory::default();
    let mut b = Bench::boot(&bytes, Some(&mut memory), None);
    assert!(b.ask("stop").starts_with("ok stop"));
    b.run(3000, Inputs::NONE);
    assert!(b.ask("save").starts_with("ok save"));
    for request in ["faults", "faults 1", "faults clear"] {
        let reply = b.ask(request);
        assert_eq!(
            reply,
            format!("err {} no fault log on this board", ErrorCode::Unsupported),
            "{request}"
        );
    }
    drop(b);
    assert!(memory.saved.is_some());
}

/// The board's keeper on a flash (`FlashKeeper`, as on the chip: an erase stalls it): `save`
/// at rest boots from then on (`settings=saved`); a fault log whose halves are full takes no
/// entry while running (no erase under the output), and the next boot erases the older half
/// so that the run's faults are kept again.
#[cfg(feature = "storage")]
#[test]
fn the_flash_keeper_saves_and_erases_the_log_only_at_boot() {
    use de_resonator::fault_log::{ENTRY_BYTES, KEPT};
    use de_resonator::flash::RAM_PAGE_BYTES;
    use de_resonator::store::StoreError;
    use de_resonator::Fault;

    let image = image_with(&Settings::for_target(44.0));
    // Two settings pages, then a log of two halves each room for `KEPT` entries.
    let log_pages = 2 * (KEPT * ENTRY_BYTES).div_ceil(RAM_PAGE_BYTES);
    let mut bytes = vec![0xFFu8; (2 + log_pages) * RAM_PAGE_BYTES];
    {
        let mut bench = Bench::boot(&image, Some(flash_keeper(&mut bytes, true)), None);
        assert!(
            bench.notice.contains(" settings=image "),
            "{}",
            bench.notice
        );
        assert!(bench.ask("stop").starts_with("ok stop"));
        bench.run(3000, Inputs::NONE);
        let set = bench.ask("set slew_volts_per_second 5000");
        assert!(set.starts_with("ok "), "{set}");
        assert!(bench.ask("save").starts_with("ok save"), "at rest");
        // Both halves full, then one more: refused while running, nothing erased.
        let fault = Fault::Sensor { value: 1.0 };
        let mut refused = None;
        for n in 0..(2 * KEPT as u32 + 1) {
            match bench.board.log_fault(&fault, (n, 0.0), 0.0, &Inputs::NONE) {
                Some(Ok(_)) => {}
                other => {
                    refused = Some((n, other));
                    break;
                }
            }
        }
        let (n, said) = refused.expect("a full log refuses while running");
        assert_eq!(said, Some(Err(StoreError::LogFull)), "entry {n}");
        assert!(
            n as usize >= KEPT,
            "at least a half's worth kept first: {n}"
        );
    }
    // The next boot: the saved settings, and room in the log again.
    let mut bench = Bench::boot(&image, Some(flash_keeper(&mut bytes, true)), None);
    assert!(
        bench.notice.contains(" settings=saved "),
        "{}",
        bench.notice
    );
    assert_eq!(
        bench.ask("get slew_volts_per_second"),
        "ok slew_volts_per_second=5000"
    );
    let fault = Fault::Sensor { value: 2.0 };
    assert!(matches!(
        bench.board.log_fault(&fault, (1, 0.0), 0.0, &Inputs::NONE),
        Some(Ok(_))
    ));
}

/// The board's keeper on `bytes` of RAM flash: the settings in the first two pages, the fault
/// log in the rest; `erase_stalls` as on the chip (`true`) or host-sim's RAM (`false`).
#[cfg(feature = "storage")]
fn flash_keeper(
    bytes: &mut [u8],
    erase_stalls: bool,
) -> de_resonator::board::FlashKeeper<de_resonator::flash::RamFlash<'_>> {
    use de_resonator::flash::{RamFlash, RAM_PAGE_BYTES};
    let len = bytes.len() as u32;
    de_resonator::board::FlashKeeper {
        flash: RamFlash::new(bytes),
        range: 0..(2 * RAM_PAGE_BYTES) as u32,
        log: Some((2 * RAM_PAGE_BYTES) as u32..len),
        erase_stalls,
    }
}
