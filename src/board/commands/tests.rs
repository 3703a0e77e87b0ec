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

/// `HELP`, made at compile time, is the forms joined as `help` says them (joined here by the
/// standard library's `join`), with nothing after its tail.
#[test]
fn help_is_every_form_joined() {
    let forms: std::vec::Vec<&str> = COMMANDS.iter().map(|c| c.form).collect();
    let joined = std::format!("{HELP_HEAD}{}{HELP_TAIL}", forms.join(HELP_SEPARATOR));
    assert_eq!(HELP, joined);
    assert!(!HELP.contains('\0'));
}

/// The table's check that a form starts with its command's name (`names`), on forms right
/// and wrong.
#[test]
fn a_form_names_its_command() {
    for (form, name) in [
        ("target <Hz>", "target"),
        ("stop", "stop"),
        ("get [setting]", "get"),
    ] {
        assert!(names(form, name), "{form} {name}");
    }
    for (form, name) in [
        ("targets <Hz>", "target"),
        ("tar", "target"),
        ("targex <Hz>", "target"),
        ("xtop", "stop"),
        ("sto", "stop"),
        ("", "stop"),
    ] {
        assert!(!names(form, name), "{form} {name}");
    }
    // Each command's name is its form's first word.
    for command in COMMANDS {
        let first = command.form.split(' ').next().unwrap_or_default();
        assert_eq!(command.name(), first);
        assert!(names(command.form, command.name()));
    }
}

/// `help` of a word near a command and a setting both names the nearer (distances worked out
/// by hand: `target_h` is 1 from `target_hz`, 2 from `target`; `marget` 1 from `target`, 2
/// from `margin`), a command on a tie (`target_m`: 2 from each of `target` and `target_hz`).
#[test]
fn help_of_a_typo_names_the_nearer_of_a_command_and_a_setting() {
    for (typo, nearest) in [
        ("target_h", "target_hz"),
        ("marget", "target"),
        ("target_m", "target"),
    ] {
        let line = std::format!("help {typo}");
        assert_eq!(
            parse(line.as_bytes()),
            Err(ParseError::UnknownTopic {
                nearest: Some(nearest)
            }),
            "{typo}"
        );
    }
}
