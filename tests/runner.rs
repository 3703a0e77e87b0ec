//! The board's runner (`board::runner`): the work around a tick and a request that the
//! firmware's tasks, `host-sim serve`, the core in host-sim's loop and `count` all call.

mod common;

use de_resonator::board::runner::{follow, Follow, Ticker};
use de_resonator::board::{ReplyLine, ResetCause, Started, Then};
use de_resonator::wire::protocol::NOTICE;
use de_resonator::wire::stream::Telemetry;
use de_resonator::{Dac8551, Event, Fault, Inputs, OutputStage, Settings};

/// A fault's entry says the voltage sent on the tick before it (the fault's own tick already
/// sends the descent's first step), at the board tick counted from boot, on the readings that
/// tripped it; a fault latched once is entered once.
#[test]
fn a_faults_entry_says_the_voltage_sent_before_it_at_the_tick_since_boot() {
    let mut slot = Some(common::start_reference(Settings::for_target(44.0)).unwrap());
    let (bus, pin) = (common::Bus::default(), common::Pin::default());
    let mut stage = OutputStage::new(Dac8551::new(&bus), &pin);
    let mut ticker = Ticker::new();
    let mut sent = Vec::new();
    for k in 0..50 {
        let done = ticker.tick(Ok(Inputs::NONE), &mut slot, &mut stage);
        assert_eq!(done.tick, k, "the ticks counted from boot");
        assert!(done.logged().is_none() && !matches!(done.event(), Some(Event::Fault(_))));
        sent.push(done.ticked.expect("a controller runs").output.volts);
    }
    let before = *sent.last().unwrap();
    assert!(
        before > 0.0 && before > sent[sent.len() - 2],
        "ramping up: {before} V"
    );
    // A stretch sensor that reads NaN trips at once.
    let done = ticker.tick(Ok(Inputs::stretch(f32::NAN)), &mut slot, &mut stage);
    let logged = done.logged().expect("the fault's entry");
    // The sensor's NaN, named as such.
    assert!(
        matches!(logged.fault, Fault::Sensor { value } if value.is_nan()),
        "{:?}",
        logged.fault
    );
    assert_eq!(logged.tick, 50);
    assert_eq!(logged.volts, before, "the voltage sent before the fault");
    let descent = done.ticked.unwrap().output.volts;
    assert!(
        descent < before,
        "the fault's tick already comes down: {descent} V"
    );
    assert!(logged.readings.stretch.is_some_and(f32::is_nan));
    // Latched: the descent's ticks enter nothing more, a refused block reads as none.
    for _ in 0..100 {
        let done = ticker.tick(
            Err(de_resonator::acquire::InputError::NoSamples {
                channel: de_resonator::acquire::Channel::Stretch,
            }),
            &mut slot,
            &mut stage,
        );
        assert!(done.logged().is_none());
        assert_eq!(done.readings, Inputs::NONE);
    }
    assert_eq!(ticker.ticks(), 151);
}

/// With no controller the tick counts on, sends nothing and enters nothing.
#[test]
fn with_no_controller_a_tick_enters_nothing() {
    let mut slot = None;
    let (bus, pin) = (common::Bus::default(), common::Pin::default());
    let mut stage = OutputStage::new(Dac8551::new(&bus), &pin);
    let mut ticker = Ticker::new();
    let done = ticker.tick(Ok(Inputs::stretch(f32::NAN)), &mut slot, &mut stage);
    assert!(done.ticked.is_none() && done.logged().is_none());
    assert!(stage.is_safe() && !pin.high.get());
    assert_eq!(ticker.ticks(), 1);
}

/// `stream <hz>` starts the records from the next tick, `stream 0` stops them, a `reset`
/// stops them and restarts their sequence (a board just booted streams nothing until asked).
#[test]
fn a_reply_sets_off_the_stream_and_the_reset() {
    let c = common::start_reference(Settings::for_target(44.0)).unwrap();
    let mut t = Telemetry::default();
    let record = |t: &mut Telemetry, tick| t.record(tick, true, Some(&c), &Inputs::NONE);
    assert!(record(&mut t, 0).is_none(), "off at boot");
    assert_eq!(follow(Then::Reply, &mut t), Follow::Nothing);
    assert_eq!(follow(Then::Stream(Some(10)), &mut t), Follow::Nothing);
    // `is_due` (the firmware's look before it takes the tick's locks) says what `record` does.
    let ticks: Vec<u32> = (5..40)
        .filter(|&k| {
            let due = t.is_due(k);
            let taken = record(&mut t, k).is_some();
            assert_eq!(due, taken, "tick {k}");
            taken
        })
        .collect();
    assert_eq!(
        ticks,
        [5, 15, 25, 35],
        "every 10th tick from the first asked"
    );
    assert_eq!(follow(Then::Stream(None), &mut t), Follow::Nothing);
    assert!((40..100).all(|k| record(&mut t, k).is_none()));
    assert_eq!(follow(Then::Stream(Some(1)), &mut t), Follow::Nothing);
    assert_eq!(record(&mut t, 100).unwrap().sequence, 4);
    assert_eq!(follow(Then::Reset, &mut t), Follow::Reset);
    assert_eq!(t, Telemetry::default(), "the stream off, its count from 0");
}

/// The start-up lines, as docs/firmware.md gives them: the reset's cause, the warning, the
/// notice, each a notice line.
#[test]
fn the_start_up_lines_are_the_cause_the_warning_and_the_notice() {
    let started = Started {
        notice: ReplyLine::try_from("ready target_hz=44").unwrap(),
        warning: Some(ReplyLine::try_from("saved settings refused (x)").unwrap()),
    };
    let mut out = String::new();
    de_resonator::board::runner::write_reset(ResetCause::Watchdog, &mut out, "\r\n").unwrap();
    started.write_banner(&mut out, "\r\n").unwrap();
    assert_eq!(
        out,
        format!(
            "{NOTICE}reset: watchdog\r\n{NOTICE}warning: saved settings refused (x)\r\n\
             {NOTICE}ready target_hz=44\r\n"
        )
    );
    let mut out = String::new();
    let plain = Started {
        warning: None,
        ..started
    };
    plain.write_banner(&mut out, "\n").unwrap();
    assert_eq!(out, format!("{NOTICE}ready target_hz=44\n"));
}
