//! The command port's line protocol, one definition for the firmware that serves it and the
//! host that talks to it: a person can type it, a program can parse it.
//!
//! A request is one line of ASCII, at most `MAX_LINE` bytes, ended by `\n`, `\r` (a serial
//! terminal's Enter) or `\r\n`. Every request gets exactly one reply line:
//! - `ok <what was done>`, or `ok <key>=<value> ...` for `status` and `get`;
//! - `err <code> <message>`, `code` an [`ErrorCode`] number.
//!
//! Lines that start with [`NOTICE`] are not replies: the firmware's start-up line (`# ready
//! <status>`, or `# refused <why>` when the image or the boot checks refuse). Numbers are decimals (`44`, `44.5`, `1e-4`),
//! parsed without the core library's float parser (17 KB of flash): [`parse_number`].

use core::fmt;

use crate::controller::{Fault, Inputs, Phase, Setting};
use crate::estimate::ring::RingQuality;
use crate::model::safety::FailureMode;
use crate::numerics::decimal::{scale10, Decimal};

/// What starts a line the firmware says on its own (not a reply).
pub const NOTICE: &str = "# ";

/// The longest request line, in bytes (without its `\n`).
pub const MAX_LINE: usize = 96;

/// Why a request was not done: the number after `err`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ErrorCode {
    /// The line is not a request (unknown command, bad number, too long, not text).
    Syntax = 1,
    /// The checks refused it (out of the tunable range, above the cap, a setting out of range).
    Refused = 2,
    /// Not now: a ramp, a trim or another request is under way; ask again.
    Busy = 3,
    /// A fault brings the output down to 0 V and holds it there: `clear` first.
    Faulted = 4,
    /// No usable configuration image, or its boot checks fail: nothing is driven.
    Config = 5,
    /// This build does not carry what the request needs.
    Unsupported = 6,
    /// Not in this state: the request needs the output at rest at 0 V (`stop` first).
    State = 7,
    /// Another connection controls the board: this one reads (`status`, `info`, `get`,
    /// `help`, `faults`) until that one leaves. Where a board serves several connections
    /// (`host-sim serve`); never on a board's one serial port.
    NotInControl = 8,
}

impl ErrorCode {
    pub const ALL: [ErrorCode; 8] = [
        ErrorCode::Syntax,
        ErrorCode::Refused,
        ErrorCode::Busy,
        ErrorCode::Faulted,
        ErrorCode::Config,
        ErrorCode::Unsupported,
        ErrorCode::State,
        ErrorCode::NotInControl,
    ];

    /// The code with this number.
    pub fn from_number(n: u8) -> Option<Self> {
        Self::ALL.into_iter().find(|c| *c as u8 == n)
    }
}

impl fmt::Display for ErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", *self as u8)
    }
}

/// Why a line is not a request (all `ErrorCode::Syntax`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParseError {
    Empty,
    /// Longer than `MAX_LINE` bytes (the rest of the line was dropped).
    TooLong,
    /// Bytes that are not printable ASCII.
    NotText,
    /// No command has this name; the nearest one's, if one is near.
    UnknownCommand {
        nearest: Option<&'static str>,
    },
    /// No setting has this key; the nearest one, if one is near.
    UnknownSetting {
        nearest: Option<Setting>,
    },
    /// `help` of a word that is no command and no setting; the nearest of either (a
    /// command's name or a setting's key).
    UnknownTopic {
        nearest: Option<&'static str>,
    },
    /// Argument `index` (from 1) is missing.
    Missing {
        index: u8,
    },
    /// More arguments than the command takes.
    Extra,
    /// Argument `index` (from 1) is not a decimal number.
    BadNumber {
        index: u8,
    },
    /// Argument `index` has a unit after it that is not its own (`unit`).
    WrongUnit {
        index: u8,
        unit: &'static str,
    },
    /// Argument `index` counts something: a fraction is refused, not rounded.
    NotWhole {
        index: u8,
    },
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ParseError::Empty => write!(f, "empty line; try `help`"),
            ParseError::TooLong => write!(f, "line longer than {MAX_LINE} bytes, dropped"),
            ParseError::NotText => write!(f, "line holds bytes that are not printable ASCII"),
            ParseError::UnknownCommand { nearest } => {
                write!(f, "unknown command")?;
                if let Some(name) = nearest {
                    write!(f, "; did you mean `{name}`?")?;
                }
                write!(f, " (`help` lists the commands)")
            }
            ParseError::UnknownSetting { nearest } => {
                write!(f, "unknown setting")?;
                if let Some(s) = nearest {
                    write!(f, "; did you mean `{}`?", s.key())?;
                }
                write!(f, " (`get` lists every setting)")
            }
            ParseError::UnknownTopic { nearest } => {
                write!(f, "no command or setting has this name")?;
                if let Some(name) = nearest {
                    write!(f, "; did you mean `{name}`?")?;
                }
                write!(f, " (`help` lists the commands, `get` every setting)")
            }
            ParseError::Missing { index } => write!(f, "argument {index} is missing"),
            ParseError::Extra => write!(f, "too many arguments"),
            ParseError::BadNumber { index } => {
                write!(f, "argument {index} is not a decimal number")
            }
            ParseError::WrongUnit { index, unit } => {
                write!(
                    f,
                    "argument {index} is in {unit} (a unit after it must be {unit})"
                )
            }
            ParseError::NotWhole { index } => {
                write!(f, "argument {index} must be a whole number (it counts)")
            }
        }
    }
}

/// The words of one request line (without its `\n`; a trailing `\r` is dropped): the
/// command's name and its arguments (`Args`), or why the line is not a request.
pub fn words(line: &[u8]) -> Result<(&str, Args<'_>), ParseError> {
    let line = line.strip_suffix(b"\r").unwrap_or(line);
    if line.len() > MAX_LINE {
        return Err(ParseError::TooLong);
    }
    if !line
        .iter()
        .all(|&b| (b' '..=b'~').contains(&b) || b == b'\t')
    {
        return Err(ParseError::NotText);
    }
    let text = core::str::from_utf8(line).map_err(|_| ParseError::NotText)?;
    let mut words = text.split_ascii_whitespace().peekable();
    let name = words.next().ok_or(ParseError::Empty)?;
    Ok((name, Args { words, index: 0 }))
}

/// A request's arguments, read in order; each error names the argument by its place.
pub struct Args<'a> {
    words: core::iter::Peekable<core::str::SplitAsciiWhitespace<'a>>,
    index: u8,
}

impl<'a> Args<'a> {
    /// The next word, if one is left (counted as an argument).
    pub fn optional_word(&mut self) -> Option<&'a str> {
        let word = self.words.next()?;
        self.index += 1;
        Some(word)
    }

    /// Nothing is left: more is `Extra`.
    pub fn end(mut self) -> Result<(), ParseError> {
        match self.words.next() {
            Some(_) => Err(ParseError::Extra),
            None => Ok(()),
        }
    }

    /// A number in `unit`: `33.5`, `33.5Hz` or `33.5 Hz` (the unit's case ignored); another
    /// unit after it is named in the error, never ignored.
    pub fn number_in(&mut self, unit: &'static str) -> Result<f32, ParseError> {
        let word = self.word()?;
        self.with_unit(word, unit)
    }

    /// `word` (argument `self.index`) as a number in `unit`, its unit written on it or the
    /// next word.
    pub fn with_unit(&mut self, word: &'a str, unit: &'static str) -> Result<f32, ParseError> {
        let index = self.index;
        if let Some(x) = parse_number(word) {
            // A unit as the next word: its own is taken, a word of letters that is not
            // (`kHz`, `mV`) is named; anything else is the next argument.
            if let Some(&next) = self.words.peek() {
                if next.eq_ignore_ascii_case(unit) && !unit.is_empty() {
                    self.words.next();
                } else if looks_like_unit(next) && !unit_free(unit) {
                    return Err(ParseError::WrongUnit { index, unit });
                }
            }
            return Ok(x);
        }
        // The unit written on the number: `33.5Hz`.
        let split = word
            .bytes()
            .position(|b| b.is_ascii_alphabetic() && b != b'e' && b != b'E')
            .unwrap_or(word.len());
        let (number, written) = word.split_at(split);
        match parse_number(number) {
            Some(x) if written.eq_ignore_ascii_case(unit) && !unit.is_empty() => Ok(x),
            Some(_) if !written.is_empty() => Err(ParseError::WrongUnit { index, unit }),
            _ => Err(ParseError::BadNumber { index }),
        }
    }

    fn word(&mut self) -> Result<&'a str, ParseError> {
        self.index += 1;
        self.words
            .next()
            .ok_or(ParseError::Missing { index: self.index })
    }

    pub fn setting(&mut self) -> Result<Setting, ParseError> {
        let word = self.word()?;
        Setting::from_key(word).ok_or(ParseError::UnknownSetting {
            nearest: nearest_setting(word),
        })
    }

    /// A setting if a word is left, `None` if none is.
    pub fn optional_setting(&mut self) -> Result<Option<Setting>, ParseError> {
        match self.words.next() {
            None => Ok(None),
            Some(word) => {
                self.index += 1;
                Setting::from_key(word)
                    .map(Some)
                    .ok_or(ParseError::UnknownSetting {
                        nearest: nearest_setting(word),
                    })
            }
        }
    }
}

/// A short word of letters (and `/`): a unit someone typed (`kHz`, `mV`, `V/s`), not a
/// word of more (`extra`: the next argument, too many).
fn looks_like_unit(word: &str) -> bool {
    word.len() <= 4 && word.bytes().all(|b| b.is_ascii_alphabetic() || b == b'/')
}

/// A unit no one writes after the number (a fraction, a count): nothing after it is one.
fn unit_free(unit: &str) -> bool {
    matches!(unit, "fraction" | "samples" | "")
}

/// The item of `items` whose name is nearest `word` (edit distance, case ignored) if it is
/// within a third of the name's length (rounded up): its distance and the name (the first
/// of the nearest).
pub fn nearest_name<T>(
    word: &str,
    items: &[T],
    name: fn(&T) -> &'static str,
) -> Option<(usize, &'static str)> {
    let mut nearest: Option<(usize, &'static str)> = None;
    for item in items {
        let name = name(item);
        let d = edit_distance(word.as_bytes(), name.as_bytes());
        if d <= name.len().div_ceil(3) && nearest.is_none_or(|(best, _)| d < best) {
            nearest = Some((d, name));
        }
    }
    nearest
}

/// The setting whose key is nearest `word` (edit distance, case ignored) if it is within a
/// third of the key's length: a typo's suggestion.
pub fn nearest_setting(word: &str) -> Option<Setting> {
    Setting::ALL
        .into_iter()
        .map(|s| (edit_distance(word.as_bytes(), s.key().as_bytes()), s))
        .filter(|&(d, s)| d <= s.key().len() / 3)
        .min_by_key(|&(d, _)| d)
        .map(|(_, s)| s)
}

/// Levenshtein distance over ASCII (case ignored), for words up to 32 bytes (longer: far).
pub fn edit_distance(a: &[u8], b: &[u8]) -> usize {
    const MAX: usize = 32;
    if a.len() > MAX || b.len() > MAX {
        return usize::MAX;
    }
    let mut row = [0usize; MAX + 1];
    for (j, slot) in row.iter_mut().enumerate() {
        *slot = j;
    }
    for (i, &x) in a.iter().enumerate() {
        let mut diagonal = i;
        let mut left = i + 1;
        for (j, &y) in b.iter().enumerate() {
            let up = row.get(j + 1).copied().unwrap_or(usize::MAX);
            let cost = usize::from(!x.eq_ignore_ascii_case(&y));
            let next = (diagonal + cost).min(up + 1).min(left + 1);
            diagonal = up;
            if let Some(slot) = row.get_mut(j + 1) {
                *slot = next;
            }
            left = next;
        }
        if let Some(slot) = row.get_mut(0) {
            *slot = i + 1;
        }
    }
    row.get(b.len()).copied().unwrap_or(usize::MAX)
}

/// A decimal number (`-12.5`, `.5`, `3e-4`, `1E3`) as the nearest f32, or `None` for anything
/// else (no `inf`, no `nan`, no hex). Up to 19 significant digits are kept, exactly, in a u64;
/// the value is that integer times a power of ten, both exact in f64 for the inputs a person
/// types (|exponent| ≤ 22), so the result is the f64 rounding of the exact value, then f32's:
/// within one f32 ulp of correctly rounded, and equal to it in all but rare double-rounding
/// ties (tests hold it against `str::parse::<f32>`).
pub fn parse_number(word: &str) -> Option<f32> {
    let bytes = word.as_bytes();
    let (negative, rest) = match bytes.first() {
        Some(b'-') => (true, bytes.get(1..)?),
        Some(b'+') => (false, bytes.get(1..)?),
        _ => (false, bytes),
    };
    let mut digits: u64 = 0;
    let mut kept = 0u32;
    let mut exponent: i32 = 0;
    let mut seen_digit = false;
    let mut seen_point = false;
    let mut at = 0;
    while let Some(&b) = rest.get(at) {
        match b {
            b'0'..=b'9' => {
                seen_digit = true;
                if kept < 19 {
                    digits = digits * 10 + u64::from(b - b'0');
                    if digits > 0 {
                        kept += 1;
                    }
                    if seen_point {
                        exponent -= 1;
                    }
                } else if !seen_point {
                    // A digit past the 19 kept: dropped, the magnitude kept.
                    exponent += 1;
                }
            }
            b'.' if !seen_point => seen_point = true,
            b'e' | b'E' => break,
            _ => return None,
        }
        at += 1;
    }
    if !seen_digit {
        return None;
    }
    if let Some(tail) = rest.get(at + 1..).filter(|_| at < rest.len()) {
        let text = core::str::from_utf8(tail).ok()?;
        let (sign, body) = match text.as_bytes().first() {
            Some(b'-') => (-1, text.get(1..)?),
            Some(b'+') => (1, text.get(1..)?),
            _ => (1, text),
        };
        if body.is_empty() || body.len() > 4 || !body.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        let mut e: i32 = 0;
        for b in body.bytes() {
            e = e * 10 + i32::from(b - b'0');
        }
        exponent += sign * e;
    }
    // Exact steps of at most 10²²: the common inputs round once.
    let value = scale10(digits as f64, exponent);
    let value = value as f32;
    if !value.is_finite() {
        return None;
    }
    Some(if negative { -value } else { value })
}

/// What `status` reports, written as key=value pairs, the fault last.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Status {
    pub phase: Phase,
    pub target_hz: f32,
    /// The plan's bias, V.
    pub bias_volts: f32,
    /// The voltage commanded at the last tick, V.
    pub volts: f32,
    /// Whether the output is on: anything but at rest at 0 V (stopped, waiting for `start`,
    /// or faulted with the descent over). A ramp down after `stop` is still on.
    pub output_on: bool,
    /// The highest voltage the board may command: the cap in force, or the amplifier's top
    /// (rail or top code) where lower, V.
    pub max_volts: f32,
    /// Which of the two sets `max_volts`.
    pub max_by: MaxBy,
    /// The first failure above it (the limit's mode), when the chip solved it.
    pub limit: Option<FailureMode>,
    pub ticks: u32,
    pub hardware: Extras,
    /// The last trim window's ring: its frequency, Hz, and Q with the highest its decay
    /// allows (`ring_hz`, `quality_factor`, `quality_high`), if a window measured one.
    pub ring: Option<(f32, RingQuality)>,
    /// The fault that brings the output down to 0 V and holds it there, if any.
    pub fault: Option<Fault>,
}

/// What bounds the voltage a board may command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaxBy {
    /// The cap in force (the model's limit less the margin, an operator's or an estimate's).
    Cap,
    /// The amplifier: its rail, or the DAC's top code.
    Amplifier,
}

impl MaxBy {
    pub fn name(self) -> &'static str {
        match self {
            MaxBy::Cap => "cap",
            MaxBy::Amplifier => "amplifier",
        }
    }
}

/// An independent clock's reading at a tick's start, with that tick's count since power-up,
/// read together in the tick (a status read between two ticks would otherwise pair one tick's
/// count with the next tick's time).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TickClock {
    /// The tick's count since power-up (wrapping).
    pub tick: u32,
    /// The clock at its start, µs (wrapping).
    pub micros: u32,
}

/// What the status line takes from the hardware, read by the command task.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Extras {
    /// The longest tick so far, core cycles (`None` where they are not cycles: under QEMU a
    /// tick after a `wfi` counts QEMU's wake-up; `count` gives its instructions).
    pub tick_cycles_max: Option<u32>,
    /// The deepest stack so far, bytes.
    pub stack_bytes: u32,
    /// An independent clock at the last tick's start (QEMU builds and `serve` only).
    pub clock: Option<TickClock>,
    /// The last tick's readings of the fitted analog inputs, in units (`acquire`).
    pub readings: Inputs,
    /// Whether the board has a port for the telemetry stream (`stream <hz>`).
    pub stream_port: bool,
    /// The acquisition's stalls recovered from since power-up (`acquire::Reader::recovered`;
    /// said when there are any).
    pub stalls_recovered: u32,
}

impl fmt::Display for Extras {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(cycles) = self.tick_cycles_max {
            write!(f, " tick_cycles_max={cycles}")?;
        }
        write!(f, " stack_bytes={}", self.stack_bytes)?;
        if let Some(TickClock { tick, micros }) = self.clock {
            write!(f, " clock_tick={tick} clock_us={micros}")?;
        }
        let r = &self.readings;
        for (key, reading) in [
            ("current_amps", r.current_amps),
            ("amplifier_volts", r.amplifier_volts),
            ("stretch", r.stretch),
        ] {
            if let Some(value) = reading {
                write!(f, " {key}={}", Decimal(value))?;
            }
        }
        if self.stalls_recovered > 0 {
            write!(f, " stalls_recovered={}", self.stalls_recovered)?;
        }
        Ok(())
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "phase={} target_hz={} bias_volts={} volts={} output={} max_volts={} max_by={} \
             limit={} ticks={}{}",
            self.phase.name(),
            Decimal(self.target_hz),
            Decimal(self.bias_volts),
            Decimal(self.volts),
            if self.output_on { "on" } else { "off" },
            Decimal(self.max_volts),
            self.max_by.name(),
            self.limit.map_or("unknown", FailureMode::name),
            self.ticks,
            self.hardware,
        )?;
        if let Some((hz, q)) = self.ring {
            write!(
                f,
                " ring_hz={} quality_factor={} quality_high={}",
                Decimal(hz),
                Decimal(q.quality_factor),
                Decimal(q.high)
            )?;
        }
        match self.fault {
            Some(fault) => write!(f, " fault={fault}"),
            None => write!(f, " fault=none"),
        }
    }
}

/// What `status` answers while no controller runs (no image, or the boot checks refused):
/// the output off at 0 V, and why, last (as a fault is).
#[derive(Clone, Copy, Debug)]
pub struct Refused<'a> {
    pub hardware: Extras,
    pub why: &'a str,
}

impl fmt::Display for Refused<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "phase=refused volts=0 output=off{} fault={}",
            self.hardware, self.why
        )
    }
}

#[cfg(test)]
#[allow(clippy::panic, clippy::indexing_slicing)]
mod tests {
    use super::*;
    use crate::wire::reply::Reply;

    #[test]
    fn numbers_parse_as_the_core_library_does() {
        for word in [
            "44",
            "44.5",
            "-3",
            "+2.25",
            ".5",
            "5.",
            "1e-4",
            "2.5E3",
            "0",
            "0.0001",
            "7449.8784",
            "123456789012345678901234",
            "99999999999999999999999",
            "0.00000000000000000000001234",
            "1e+5",
            "1e0005",
            "1e-30",
            "3.4e38",
            "0.1",
            "-0.0",
        ] {
            let ours = parse_number(word);
            let core: f32 = word.parse().unwrap_or(f32::NAN);
            let Some(ours) = ours else {
                panic!("{word} refused");
            };
            let ulps = (ours.to_bits() as i64 - core.to_bits() as i64).abs();
            assert!(ulps <= 1, "{word}: {ours} against {core}");
        }
        for word in [
            "", "-", ".", "e5", "1e", "1e+", "nan", "inf", "1.2.3", "0x10", "1,5", "4e99",
            "1e00005",
        ] {
            assert_eq!(parse_number(word), None, "{word}");
        }
    }

    #[test]
    fn replies_read_back() {
        let status = Status {
            phase: Phase::Driving,
            target_hz: 44.0,
            bias_volts: 7449.5,
            volts: 7500.25,
            output_on: true,
            max_volts: 9361.9,
            max_by: MaxBy::Cap,
            limit: Some(FailureMode::Emi),
            ticks: 12,
            hardware: Extras {
                tick_cycles_max: None,
                stack_bytes: 1024,
                clock: None,
                readings: Inputs {
                    current_amps: Some(-2.5e-6),
                    ..Inputs::NONE
                },
                stream_port: false,
                stalls_recovered: 0,
            },
            ring: Some((
                44.0,
                RingQuality {
                    quality_factor: 199.5,
                    high: f32::INFINITY,
                },
            )),
            fault: Some(Fault::Bus),
        };
        let mut line = heapless::String::<256>::new();
        let _ = fmt::Write::write_fmt(&mut line, format_args!("ok {status}"));
        let reply = Reply::parse(&line).unwrap_or_else(|| panic!("{line}"));
        assert_eq!(reply.field("phase"), Some("driving"));
        assert_eq!(reply.field("bias_volts"), Some("7449.5"));
        assert_eq!(reply.field("limit"), Some("emi"));
        assert_eq!(reply.field("output"), Some("on"));
        let amps = reply
            .field("current_amps")
            .and_then(|v| v.parse::<f32>().ok());
        assert_eq!(amps, Some(-2.5e-6));
        assert_eq!(reply.field("stretch"), None);
        assert_eq!(reply.field("tick_cycles_max"), None);
        assert_eq!(reply.field("max_by"), Some("cap"));
        assert_eq!(reply.field("quality_factor"), Some("199.5"));
        assert_eq!(reply.field("quality_high"), Some("inf"));
        assert_eq!(reply.field("fault"), Some("DAC bus error"));
        assert_eq!(
            Reply::parse("err 2 target out of range"),
            Some(Reply::Err {
                code: ErrorCode::Refused,
                message: "target out of range"
            })
        );
        assert_eq!(Reply::parse("err 9 what"), None);
        // Codes are written as their numbers, parse errors as sentences.
        let mut text = heapless::String::<64>::new();
        let _ = fmt::Write::write_fmt(&mut text, format_args!("{}", ErrorCode::Busy));
        assert_eq!(text.as_str(), "3");
        text.clear();
        let _ = fmt::Write::write_fmt(
            &mut text,
            format_args!("{}", ParseError::BadNumber { index: 2 }),
        );
        assert_eq!(text.as_str(), "argument 2 is not a decimal number");
        assert_eq!(Reply::parse("hello"), None);
    }
}
