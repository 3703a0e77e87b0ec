//! The output on the host: the DAC8551's frames, the amplifier's transfer and codes, the
//! output stage's reaction to every fault, the drive's errors as sentences.

mod common;

use common::{amplifier, start_reference as start};

use de_resonator::{
    Amplifier, CodeError, Controller, Dac8551, DacCode, DacError, Event, Fault, Inputs, Settings,
};
use embedded_hal_mock::eh1::spi::{Mock, Transaction};

#[test]
fn dac8551_frames_follow_the_datasheet() {
    // 24 bits: 6 don't-care, PD1 PD0, 16 data bits, MSB first.
    let expectations = [
        Transaction::transaction_start(),
        Transaction::write_vec(vec![0x00, 0x12, 0x34]),
        Transaction::transaction_end(),
        Transaction::transaction_start(),
        Transaction::write_vec(vec![0x01, 0x00, 0x00]),
        Transaction::transaction_end(),
    ];
    let mut dac = Dac8551::new(Mock::new(&expectations));
    dac.write(DacCode(0x1234)).unwrap();
    dac.power_down().unwrap();
    dac.release().done();
}

/// A bus that fails every transfer (embedded-hal-mock 0.11 cannot fail an SPI write).
struct BrokenBus;

impl embedded_hal::spi::ErrorType for BrokenBus {
    type Error = embedded_hal::spi::ErrorKind;
}

impl embedded_hal::spi::SpiDevice for BrokenBus {
    fn transaction(
        &mut self,
        _: &mut [embedded_hal::spi::Operation<'_, u8>],
    ) -> Result<(), Self::Error> {
        Err(embedded_hal::spi::ErrorKind::Other)
    }
}

/// The one fault reaction (`OutputStage`, used by the firmware and host-sim's loop): the
/// safe state is the enable line low, then the DAC powered down (DAC8551 frame 01 00 00);
/// nothing is written before `enable`; a tick's code goes out once enabled; a fault event
/// goes safe; and on a dead bus the line still drops and the controller latches `Bus`.
#[test]
fn the_output_stage_reacts_to_every_fault_the_same_way() {
    use de_resonator::{OutputStage, StageError};
    use embedded_hal_mock::eh1::digital::{
        Mock as PinMock, State as PinState, Transaction as PinTransaction,
    };
    let frame = |bytes: [u8; 3]| {
        [
            Transaction::transaction_start(),
            Transaction::write_vec(bytes.to_vec()),
            Transaction::transaction_end(),
        ]
    };
    let spi: Vec<Transaction<u8>> = [
        frame([0x01, 0, 0]),       // safe at power-on
        frame([0x00, 0x12, 0x34]), // a tick's code once enabled
        frame([0x01, 0, 0]),       // the fault
    ]
    .concat();
    let pin = [
        PinTransaction::set(PinState::Low),
        PinTransaction::set(PinState::High),
        PinTransaction::set(PinState::Low),
    ];
    let mut c = start(Settings::for_target(44.0)).unwrap();
    let mut stage = OutputStage::new(Dac8551::new(Mock::new(&spi)), PinMock::new(&pin));
    assert!(stage.is_safe());
    stage.safe().unwrap();
    // Not enabled yet: a tick's output is not written.
    let out = c.tick(Inputs::NONE);
    let mut sent = out;
    stage.send(&mut c, &mut sent);
    assert_eq!(sent, out);
    stage.enable().unwrap();
    assert!(!stage.is_safe());
    let mut code = de_resonator::Output {
        code: DacCode(0x1234),
        volts: 0.0,
        event: None,
    };
    stage.send(&mut c, &mut code);
    let mut out = c.fault(Fault::Bus);
    stage.send(&mut c, &mut out);
    assert!(stage.is_safe());
    let (dac, mut pin) = stage.release();
    dac.release().done();
    pin.done();

    // A dead bus: the enable line drops all the same, the error is the bus's, and a tick
    // sent through it latches the controller at `Bus`.
    let pin = [
        PinTransaction::set(PinState::High),
        PinTransaction::set(PinState::Low),
        PinTransaction::set(PinState::High),
        PinTransaction::set(PinState::Low),
    ];
    let mut stage = OutputStage::new(Dac8551::new(BrokenBus), PinMock::new(&pin));
    stage.enable().unwrap();
    assert_eq!(
        stage.safe(),
        Err(StageError::Bus(embedded_hal::spi::ErrorKind::Other))
    );
    stage.enable().unwrap();
    let mut c = start(Settings::for_target(44.0)).unwrap();
    let mut sent = c.tick(Inputs::NONE);
    stage.send(&mut c, &mut sent);
    assert_eq!(sent.event, Some(Event::Fault(Fault::Bus)));
    assert_eq!(c.latched_fault(), Some(Fault::Bus));
    let (_, mut pin) = stage.release();
    pin.done();
}

#[test]
fn dac_bus_errors_are_typed() {
    let mut dac = Dac8551::new(BrokenBus);
    assert_eq!(
        dac.write(DacCode(0xFFFF)),
        Err(DacError::Bus(embedded_hal::spi::ErrorKind::Other))
    );
    assert!(dac.power_down().is_err());
}

/// The code is the largest whose voltage does not exceed the request (its definition,
/// checked on both sides), and each code's own voltage gives it back, on an amplifier
/// (3.3 V × 3000) whose step is not a binary fraction, where the float product can land a
/// hair above an exact step and rounding down takes a step back.
#[test]
fn codes_are_the_largest_at_or_below_the_voltage() {
    let amp = Amplifier::new(3.3, 3000.0).unwrap();
    let mut stepped_back = 0;
    for k in 0..20_000u32 {
        let volts = amp.max_volts() * k as f32 / 20_000.0;
        let code = amp.code(volts).unwrap();
        assert!(amp.volts(code) <= volts, "{volts}: {code:?}");
        if code.0 < u16::MAX {
            assert!(amp.volts(DacCode(code.0 + 1)) > volts, "{volts}: {code:?}");
        }
        let truncated = (volts * (65536.0 / (3.3 * 3000.0))) as u32;
        stepped_back += usize::from(u32::from(code.0) < truncated);
    }
    // Each code's own voltage gives that code back, from either side of the float product.
    let mut low = 0;
    for c in 0..=u16::MAX {
        let volts = amp.volts(DacCode(c));
        let truncated = (volts * (65536.0 / (3.3 * 3000.0))) as u32;
        low += usize::from(truncated < u32::from(c));
        stepped_back += usize::from(truncated > u32::from(c));
        assert_eq!(amp.code(volts), Ok(DacCode(c)), "{volts}");
    }
    // The step back runs (8 of these 85,536 voltages on x86-64), and no code's own voltage
    // truncates below it.
    assert!(stepped_back > 0 && low == 0, "{stepped_back} {low}");
}

/// The errors say what is wrong, with the numbers.
#[test]
fn drive_errors_read_as_sentences() {
    let out = CodeError::OutOfRange {
        volts: -1.0,
        max_volts: 9999.0,
    };
    assert_eq!(
        out.to_string(),
        "-1 V is outside the amplifier's range [0, 9999] V"
    );
    let bad = CodeError::BadFullScale { volts: f32::NAN };
    assert!(bad.to_string().contains("NaN V is not a positive number"));
    let bus: DacError<embedded_hal::spi::ErrorKind> =
        DacError::Bus(embedded_hal::spi::ErrorKind::Other);
    assert_eq!(bus.to_string(), "DAC bus error: Other");
    let stage: de_resonator::StageError<u8, u8> = de_resonator::StageError::Pin(7);
    assert_eq!(stage.to_string(), "amplifier-enable line error: 7");
    let stage: de_resonator::StageError<u8, u8> = de_resonator::StageError::Bus(3);
    assert_eq!(stage.to_string(), "DAC bus error: 3");
}

/// The amplifier's monitor: a fault on exactly the (AMPLIFIER_TICKS + 1)-th tick in a row it
/// is off its command by more than the tolerance; a tick back on resets the count.
#[test]
fn the_amplifier_faults_after_exactly_its_ticks_off() {
    use de_resonator::controller::AMPLIFIER_TICKS;
    let mut c = start(Settings::for_target(44.0)).unwrap();
    let mut last = 0.0f32;
    let tick = |c: &mut Controller, off: bool, last: &mut f32| {
        let measured = if off { *last - 500.0 } else { *last };
        let out = c.tick(Inputs {
            amplifier_volts: Some(measured),
            ..Inputs::NONE
        });
        *last = out.volts;
        out.event
    };
    // Off for AMPLIFIER_TICKS ticks, then on: no fault, and the count starts again.
    for _ in 0..AMPLIFIER_TICKS {
        assert_eq!(tick(&mut c, true, &mut last), None);
    }
    assert_eq!(tick(&mut c, false, &mut last), None);
    for _ in 0..AMPLIFIER_TICKS {
        assert_eq!(tick(&mut c, true, &mut last), None);
    }
    assert!(matches!(
        tick(&mut c, true, &mut last),
        Some(Event::Fault(Fault::AmplifierDisagrees { .. }))
    ));
}

#[test]
fn codes_round_down_and_refuse_what_the_amplifier_cannot_give() {
    let amp = amplifier();
    assert_eq!(amp.max_volts(), 10_000.0 * 65535.0 / 65536.0);
    for code in [0u16, 1, 1234, 32768, 65535] {
        assert_eq!(amp.code(amp.volts(DacCode(code))), Ok(DacCode(code)));
    }
    // Just below a step: the lower code.
    let v = amp.volts(DacCode(1000));
    assert_eq!(amp.code(v - 0.01), Ok(DacCode(999)));
    for bad in [f32::NAN, -0.1, 10_000.0, f32::INFINITY] {
        assert!(matches!(amp.code(bad), Err(CodeError::OutOfRange { .. })));
    }
    assert!(Amplifier::new(f32::NAN, 1.0).is_err());
    assert!(Amplifier::new(2.5, 0.0).is_err());
}
