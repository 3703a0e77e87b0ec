//! Requests parse as their entries say, and errors name what is wrong.

extern crate std;

use super::*;
use crate::wire::protocol::MAX_LINE;

#[test]
fn requests_parse() {
    assert_eq!(parse(b"target 44.5"), Ok(Command::Target { hz: 44.5 }));
    assert_eq!(
        parse(b"  ac 100   40\r"),
        Ok(Command::Ac {
            volts: 100.0,
            hz: 40.0
        })
    );
    assert_eq!(
        parse(b"set margin 0.1"),
        Ok(Command::Set(Setting::Margin, 0.1))
    );
    assert_eq!(
        parse(b"get tick_hz"),
        Ok(Command::Get(Some(Setting::TickHz)))
    );
    assert_eq!(parse(b"get"), Ok(Command::Get(None)));
    assert_eq!(parse(b"help"), Ok(Command::Help(None)));
    assert_eq!(
        parse(b"help ac_volts"),
        Ok(Command::Help(Some(Topic::Setting(Setting::AcVolts))))
    );
    assert_eq!(parse(b""), Err(ParseError::Empty));
    assert_eq!(parse(b"target"), Err(ParseError::Missing { index: 1 }));
    assert_eq!(parse(b"ac 100"), Err(ParseError::Missing { index: 2 }));
    assert_eq!(parse(b"stop now"), Err(ParseError::Extra));
    assert_eq!(
        parse(b"target 4x"),
        Err(ParseError::WrongUnit {
            index: 1,
            unit: "Hz"
        })
    );
    assert_eq!(parse(b"target x4"), Err(ParseError::BadNumber { index: 1 }));
    assert_eq!(
        parse(b"get volume"),
        Err(ParseError::UnknownSetting { nearest: None })
    );
    // A typo's suggestion: one letter off, a letter missing, two swapped, case.
    for (typo, meant) in [
        ("ac_volt", Setting::AcVolts),
        ("acvolts", Setting::AcVolts),
        ("tagret_hz", Setting::TargetHz),
        ("MARGIN", Setting::Margin),
        ("slew_volts_per_secnd", Setting::SlewVoltsPerSecond),
    ] {
        let mut line = heapless::Vec::<u8, 64>::new();
        let _ = line.extend_from_slice(b"set ");
        let _ = line.extend_from_slice(typo.as_bytes());
        let _ = line.extend_from_slice(b" 1");
        assert_eq!(
            parse(&line),
            Err(ParseError::UnknownSetting {
                nearest: Some(meant)
            }),
            "{typo}"
        );
    }
    assert_eq!(edit_distance(b"kitten", b"sitting"), 3);
    assert_eq!(edit_distance(b"", b"abc"), 3);
    assert_eq!(edit_distance(b"flaw", b"lawn"), 2);
    assert_eq!(parse(b"start"), Ok(Command::Start));
    assert_eq!(
        parse(b"launch"),
        Err(ParseError::UnknownCommand { nearest: None })
    );
    // A mistyped command is named as `help <typo>` names it.
    for (typo, meant) in [
        ("stauts", "status"),
        ("strat", "start"),
        ("targte", "target"),
    ] {
        assert_eq!(
            parse(typo.as_bytes()),
            Err(ParseError::UnknownCommand {
                nearest: Some(meant)
            }),
            "{typo}"
        );
    }
    assert_eq!(parse(b"target \xff44"), Err(ParseError::NotText));
    assert_eq!(parse(&[b'a'; MAX_LINE + 1]), Err(ParseError::TooLong));
    // Exactly MAX_LINE bytes is a line; tabs separate words as spaces do.
    let mut longest = b"target 44".to_vec();
    longest.resize(MAX_LINE, b' ');
    assert_eq!(parse(&longest), Ok(Command::Target { hz: 44.0 }));
    assert_eq!(
        parse(b"ac\t100\t40"),
        Ok(Command::Ac {
            volts: 100.0,
            hz: 40.0
        })
    );
}
