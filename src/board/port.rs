//! The command port's board side: bytes into request lines ([`Lines`]), and the reply to each
//! request ([`Board::serve`]). The protocol itself (parse, replies, status) is
//! [`crate::wire::protocol`].

use core::fmt::Write as _;

use heapless::{String, Vec};

use super::{Board, Keeper};
use crate::controller::{Controller, Phase, Refusal, Setting, Settings};
use crate::model::device::Field;
use crate::numerics::decimal::Decimal;
use crate::table::Table;
use crate::wire::protocol::{
    self, Command, ErrorCode, MaxBy, ParseError, Refused, Status, Topic, MAX_LINE,
};
use crate::wire::stream;

/// One request as received: its bytes, or why it has none.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Line {
    Text(Vec<u8, MAX_LINE>),
    /// Longer than `MAX_LINE`: the rest was dropped up to its end.
    TooLong,
    /// A byte was lost on the wire (overrun, framing or noise): the line is not trusted.
    Garbled,
}

/// Bytes into lines: at most `MAX_LINE` bytes a line, an overlong or garbled line reported
/// once at its end. A line ends at `\n`, at `\r` (a serial terminal's Enter), or at `\r\n`
/// (one end, not two).
///
/// A person at a serial terminal gets what a serial console gives: what they type echoed,
/// backspace or DEL and Ctrl-U (Ctrl-C too) mending the line, a prompt after each reply. A
/// terminal is known by its Enter, a `\r` that no `\n` follows, or by an edit; from then on
/// (the byte after that `\r`) the connection is a terminal's, until a line ends with `\n`
/// (a program's: the board's one UART may serve a terminal, then a script). A program
/// (`host-sim console`, a script) ends its lines with `\n` or `\r\n` and never edits: it
/// sees not one byte more than before, unless a terminal's line is half typed when it
/// starts. Edit bytes are never part of a line, in either mode.
#[derive(Default)]
pub struct Lines {
    text: Vec<u8, MAX_LINE>,
    /// Bytes past `MAX_LINE`, dropped (and not echoed): the line is too long while any are.
    beyond: usize,
    garbled: bool,
    /// The last byte ended a line with `\r`: a `\n` now is the rest of that end.
    after_cr: bool,
    /// A person at a terminal: echo, and a prompt after each reply.
    terminal: bool,
}

/// What one byte gives: the line it ends, and what to send back to a person typing.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pushed {
    pub line: Option<Line>,
    pub echo: Echo,
}

/// Bytes a terminal shows as the person types (nothing to a program).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Echo {
    Nothing,
    /// The byte typed.
    Byte(u8),
    /// This many characters rubbed out (`\b \b` each).
    Erase(u8),
    /// Enter: to the start of the next line, where the reply goes.
    NewLine,
    /// Enter on an empty line at a terminal: a new line and the prompt, as a shell gives (no
    /// request, no reply).
    Prompt,
    /// The first byte typed once the port knows a terminal: back to the start of the line
    /// the last reply's `\n` left the cursor on, the prompt, then the byte.
    Begin(u8),
}

impl Echo {
    /// Each byte of the echo, in order, to `out`.
    pub fn bytes(self, mut out: impl FnMut(u8)) {
        match self {
            Echo::Nothing => {}
            Echo::Byte(b) => out(b),
            Echo::Erase(n) => {
                for _ in 0..n {
                    b"\x08 \x08".iter().for_each(|&b| out(b));
                }
            }
            Echo::NewLine => b"\r\n".iter().for_each(|&b| out(b)),
            Echo::Prompt => TERMINAL_REPLY_END.bytes().for_each(&mut out),
            Echo::Begin(b) => {
                b"\r> ".iter().for_each(|&b| out(b));
                out(b);
            }
        }
    }
}

/// What ends a reply to a program: a line feed.
pub const REPLY_END: &str = "\n";
/// What ends a reply to a person at a terminal: a whole new line, and the prompt.
pub const TERMINAL_REPLY_END: &str = "\r\n> ";

/// A byte a terminal shows as typed: printable ASCII and tab (what a request may hold).
fn shown(byte: u8) -> bool {
    (b' '..=b'~').contains(&byte) || byte == b'\t'
}

/// Backspace, DEL (what most terminals send for backspace), Ctrl-U and Ctrl-C.
const BACKSPACE: u8 = 0x08;
const DELETE: u8 = 0x7f;
const KILL_LINE: u8 = 0x15;
const INTERRUPT: u8 = 0x03;

impl Lines {
    /// Take one byte: the line it ends, if it ends one, and its echo.
    pub fn push(&mut self, byte: u8) -> Pushed {
        let after_cr = core::mem::take(&mut self.after_cr);
        if byte == b'\n' && after_cr {
            return self.pushed(None, Echo::Nothing);
        }
        // A `\r` that no `\n` followed: a terminal's Enter.
        let known_now = after_cr && !self.terminal;
        self.terminal |= after_cr;
        if byte == b'\n' || byte == b'\r' {
            // A line a program ended (`\n`): the connection is a program's again, whatever
            // came before (the board's one UART serves a terminal, then a script).
            let terminal = self.terminal && byte == b'\r';
            let line = if self.garbled {
                Some(Line::Garbled)
            } else if self.beyond > 0 {
                Some(Line::TooLong)
            } else if self.text.is_empty() && terminal {
                // A person pressed Enter on nothing: a fresh prompt, not an error.
                None
            } else {
                Some(Line::Text(self.text.clone()))
            };
            *self = Self {
                after_cr: byte == b'\r',
                terminal,
                ..Self::default()
            };
            let echo = if line.is_some() {
                Echo::NewLine
            } else {
                Echo::Prompt
            };
            return self.pushed(line, echo);
        }
        match byte {
            BACKSPACE | DELETE => {
                self.terminal = true;
                // A byte dropped past the end goes first (it was never shown); a byte that
                // was not shown (a control byte) is rubbed out without moving the cursor.
                if self.beyond > 0 {
                    self.beyond -= 1;
                    return self.pushed(None, Echo::Nothing);
                }
                let echo = match self.text.pop() {
                    Some(b) if shown(b) => Echo::Erase(1),
                    _ => Echo::Nothing,
                };
                self.pushed(None, echo)
            }
            KILL_LINE | INTERRUPT => {
                self.terminal = true;
                let erased = self.text.iter().filter(|&&b| shown(b)).count() as u8;
                self.text.clear();
                self.beyond = 0;
                // The line is gone, and a byte lost from it with it.
                self.garbled = false;
                self.pushed(None, Echo::Erase(erased))
            }
            _ => {
                if self.text.push(byte).is_err() {
                    self.beyond = self.beyond.saturating_add(1);
                    return self.pushed(None, Echo::Nothing);
                }
                let echo = match (shown(byte), known_now) {
                    (true, true) => Echo::Begin(byte),
                    (true, false) => Echo::Byte(byte),
                    (false, _) => Echo::Nothing,
                };
                self.pushed(None, echo)
            }
        }
    }

    /// The echo only to a terminal.
    fn pushed(&self, line: Option<Line>, echo: Echo) -> Pushed {
        let echo = if self.terminal { echo } else { Echo::Nothing };
        Pushed { line, echo }
    }

    /// A byte was lost: the line it belonged to is dropped at its end.
    pub fn lost(&mut self) {
        self.garbled = true;
    }

    /// Whether a person at a terminal is typing (echo and prompts).
    pub fn terminal(&self) -> bool {
        self.terminal
    }

    /// What ends a reply on this connection: [`REPLY_END`] or [`TERMINAL_REPLY_END`].
    pub fn reply_end(&self) -> &'static str {
        if self.terminal {
            TERMINAL_REPLY_END
        } else {
            REPLY_END
        }
    }
}

/// What the command task does after the reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Then {
    Reply,
    /// Restart: the slot is already empty (the next tick makes the stage safe).
    Reset,
    /// Send the telemetry stream's records every this many ticks (`None`: stop): the tick's
    /// `stream::Telemetry::set`.
    Stream(Option<u32>),
}

/// A reply line (one `ok …` or `err …`, without its `\n`); cut short if it would not fit.
pub type ReplyLine = String<1024>;

pub use protocol::{Extras, TickClock};

/// The controller as the command task reaches it: under a lock shared with the tick.
pub trait Shared {
    fn with<R>(&mut self, f: impl FnOnce(&mut Option<Controller>) -> R) -> R;
}

/// A slot the caller owns outright (no tick to share it with between requests).
impl Shared for &mut Option<Controller> {
    fn with<R>(&mut self, f: impl FnOnce(&mut Option<Controller>) -> R) -> R {
        f(self)
    }
}

/// `err <code> <message>` into `out`.
pub(super) fn err(out: &mut ReplyLine, code: ErrorCode, message: impl core::fmt::Display) {
    out.clear();
    let _ = write!(out, "err {code} {message}");
}

/// The error code for a refusal.
fn code(refusal: &Refusal) -> ErrorCode {
    match refusal {
        Refusal::Busy { .. } => ErrorCode::Busy,
        Refusal::Faulted { .. } => ErrorCode::Faulted,
        // Every build has the trim: no trim means no `trim_tolerance` set, a refusal.
        Refusal::Checks(_) | Refusal::Stopped | Refusal::Held { .. } | Refusal::NoTrim => {
            ErrorCode::Refused
        }
    }
}

impl<K: Keeper> Board<'_, K> {
    /// `stream <hz>` / `stream off`: the rate checked against the tick's, the reply with the
    /// rate it gives and the bytes a second it sends; the tick's side is the caller's.
    fn stream(
        &self,
        hz: Option<f32>,
        controller: &mut impl Shared,
        extras: &Extras,
        out: &mut ReplyLine,
    ) -> Then {
        if !extras.stream_port {
            err(out, ErrorCode::Unsupported, "this board has no stream port");
            return Then::Reply;
        }
        let Some(hz) = hz else {
            let _ = write!(out, "ok stream off");
            return Then::Stream(None);
        };
        let tick_hz = controller.with(|c| self.tick_hz(c));
        match stream::rate(hz, tick_hz) {
            Ok(every) => {
                let hz = tick_hz / every as f32;
                let _ = write!(
                    out,
                    "ok stream hz={} every_ticks={every} frame_bytes={} bytes_per_second={}",
                    Decimal(hz),
                    stream::FRAME_BYTES,
                    Decimal(hz * stream::FRAME_BYTES as f32)
                );
                Then::Stream(Some(every))
            }
            Err(e) => {
                err(out, ErrorCode::Refused, e);
                Then::Reply
            }
        }
    }

    /// Answer one request into `out`. Long work (a new plan's checks, a new boot) runs here,
    /// outside the controller's lock; the tick preempts it.
    pub fn serve(
        &mut self,
        line: &Line,
        controller: &mut impl Shared,
        extras: &Extras,
        out: &mut ReplyLine,
    ) -> Then {
        out.clear();
        let parsed = match line {
            Line::Text(bytes) => protocol::parse(bytes),
            Line::TooLong => Err(ParseError::TooLong),
            Line::Garbled => {
                err(
                    out,
                    ErrorCode::Syntax,
                    "bytes were lost on the line; send it again",
                );
                return Then::Reply;
            }
        };
        let command = match parsed {
            Ok(command) => command,
            Err(e) => {
                err(out, ErrorCode::Syntax, e);
                return Then::Reply;
            }
        };
        match command {
            Command::Help(None) => {
                let _ = write!(out, "ok {}", protocol::HELP);
                return Then::Reply;
            }
            Command::Help(Some(Topic::Command(k))) => {
                let said = protocol::COMMANDS.get(usize::from(k)).map_or("", |c| c.1);
                let _ = write!(out, "ok {said}");
                return Then::Reply;
            }
            Command::Help(Some(Topic::Setting(setting))) => {
                let _ = write!(
                    out,
                    "ok {} ({}): {}",
                    setting.key(),
                    setting.unit(),
                    setting.rule()
                );
                return Then::Reply;
            }
            Command::Stream(hz) => return self.stream(hz, controller, extras, out),
            Command::Faults(ask) => {
                self.faults(ask, controller, out);
                return Then::Reply;
            }
            Command::Info => {
                let _ = write!(
                    out,
                    "ok firmware=de-resonator-{} image_crc=",
                    env!("CARGO_PKG_VERSION")
                );
                let _ = match self.image() {
                    Some(image) => write!(out, "{:#010x}", image.crc),
                    None => write!(out, "none"),
                };
                let _ = write!(
                    out,
                    " tick_hz={} stream_layout={} stream_port={}",
                    Decimal(controller.with(|c| self.tick_hz(c))),
                    stream::VERSION,
                    if extras.stream_port { "yes" } else { "no" }
                );
                // The tunable range: the table's, the targets the board takes (at a margin
                // set above the image's, the plan's check narrows it).
                if let Some(table) = self.image().and_then(|i| Table::parse(i.table).ok()) {
                    let (low, high) = table.range_hz();
                    let _ = write!(
                        out,
                        " tunable_low_hz={} tunable_high_hz={}",
                        Decimal(low),
                        Decimal(high)
                    );
                }
                // The device flashed, by its device-file keys (SI units; `jlim` 0: neo-Hookean).
                if let Some(image) = self.image() {
                    for field in Field::ALL {
                        let value = Decimal(image.params.get(field));
                        let _ = write!(out, " device.{}={value}", field.key());
                    }
                }
                return Then::Reply;
            }
            _ => {}
        }
        // Status always answers: while nothing runs, with why.
        let runs = controller.with(|c| c.is_some());
        if let (Command::Status, false) = (command, runs) {
            let why = self.refusal().unwrap_or("no image");
            let _ = write!(
                out,
                "ok {}",
                Refused {
                    hardware: *extras,
                    why
                }
            );
            return Then::Reply;
        }
        if self.image.is_none() {
            err(out, ErrorCode::Config, self.refusal().unwrap_or("no image"));
            return Then::Reply;
        }
        // The settings in force: the controller's; while none runs, those `clear` boots with.
        let running = controller.with(|c| c.as_ref().map(|c| *c.settings()));
        let settings = running.unwrap_or(self.idle_settings);
        match command {
            Command::Get(Some(setting)) => {
                let _ = write!(
                    out,
                    "ok {}={}",
                    setting.key(),
                    Decimal(settings.get(setting))
                );
            }
            Command::Get(None) => {
                let _ = write!(out, "ok");
                for setting in Setting::ALL {
                    let _ = write!(out, " {}={}", setting.key(), Decimal(settings.get(setting)));
                }
            }
            Command::Set(setting, value) => {
                if setting == Setting::TickHz && value != settings.tick_hz {
                    err(
                        out,
                        ErrorCode::Refused,
                        "tick_hz sets the tick's timer at power-up: make an image with it",
                    );
                    return Then::Reply;
                }
                let mut next = settings;
                next.set(setting, value);
                if running.is_none() {
                    // Refused at boot: kept for `clear` to boot with, and check.
                    self.idle_settings = next;
                    let _ = write!(
                        out,
                        "ok {}={} (applies at `clear`)",
                        setting.key(),
                        Decimal(value)
                    );
                    return Then::Reply;
                }
                // At rest at 0 V (stopped, or re-armed by `clear`): checked as a new plan, the
                // output left off (no command named `set` switches it on).
                let at_rest = controller.with(|c| {
                    c.as_ref()
                        .is_some_and(|c| c.at_rest() && c.phase() != Phase::Faulted)
                });
                self.replan(next, controller, out, at_rest);
            }
            Command::Clear => self.clear(controller, out),
            // A save erases a slot: where that stalls the chip past its watchdog, at rest only.
            Command::Save
                if self.keeper.as_ref().is_some_and(Keeper::erase_stalls)
                    && !controller.with(|c| c.as_ref().is_none_or(Controller::at_rest)) =>
            {
                err(
                    out,
                    ErrorCode::State,
                    "`save` erases flash, which stalls the chip: at rest at 0 V only (`stop` \
                     first)",
                );
            }
            Command::Save => match self.keeper.as_mut().map(|k| k.save(&settings)) {
                Some(Ok(())) => {
                    let _ = write!(out, "ok save: the settings in force boot from now on");
                }
                Some(Err(e)) => err(out, ErrorCode::Refused, e),
                None => err(out, ErrorCode::Unsupported, "no settings storage"),
            },
            _ if running.is_none() => {
                err(
                    out,
                    ErrorCode::Config,
                    self.refusal().unwrap_or("not booted"),
                );
            }
            Command::Status => {
                // Read under the lock, written out after it: formatting the numbers takes
                // thousands of instructions the tick must not wait for.
                let top = self.image.map_or(f32::INFINITY, |(_, a)| a.max_volts());
                let limit = self.limit;
                if let Some(status) =
                    controller.with(|c| c.as_ref().map(|c| status(c, limit, top, extras)))
                {
                    let _ = write!(out, "ok {status}");
                }
            }
            Command::Start => self.replan(settings, controller, out, false),
            Command::Target { hz } => {
                let next = Settings {
                    target_hz: hz,
                    ..settings
                };
                self.replan(next, controller, out, false);
            }
            Command::Ac { volts, hz } => {
                let next = Settings {
                    ac_volts: volts,
                    ac_hz: hz,
                    ..settings
                };
                self.replan(next, controller, out, false);
            }
            Command::Stop => {
                let from = controller.with(|c| {
                    c.as_mut().map(|c| {
                        c.stop();
                        c.last_volts()
                    })
                });
                match from {
                    // Nothing to ramp: said as it is, not as a ramp from 0 V to 0 V.
                    Some(volts) if volts != 0.0 => {
                        let _ = write!(out, "ok stop: ramp from {} V to 0 V", Decimal(volts));
                    }
                    _ => {
                        let _ = write!(out, "ok stop: at 0 V, the output off");
                    }
                }
            }
            Command::Trim => match controller.with(|c| c.as_mut().map(Controller::trim_now)) {
                Some(Ok(())) => {
                    let _ = write!(out, "ok trim: measuring");
                }
                Some(Err(refusal)) => err(out, code(&refusal), refusal),
                None => {}
            },
            Command::Reset => {
                // At rest at 0 V only, as `clear`: switching the output off under a bias
                // would drop the membrane's charge at once, and the next boot would ramp from
                // 0 V while the amplifier still slews down (its monitor's fault, found on
                // `host-sim serve`'s plant). The controller leaves its slot under the same
                // lock as the check: nothing moves between them.
                if !replace_at_rest(controller, &mut None) {
                    err(
                        out,
                        ErrorCode::State,
                        "reset at 0 V only: `stop` first, or wait for a fault's descent",
                    );
                    return Then::Reply;
                }
                let _ = write!(out, "ok reset: output off, restarting");
                return Then::Reset;
            }
            // Answered above.
            Command::Help(_) | Command::Stream(_) | Command::Info | Command::Faults(_) => {}
        }
        Then::Reply
    }

    /// A new plan with `next`: its job made under the lock, solved outside it, adopted under
    /// it; the controller then holds `next`.
    /// `next` checked as a new plan and adopted; `keep_off`: stopped again at once, under the
    /// same lock (the output stays off at 0 V until `start`).
    fn replan(
        &mut self,
        next: Settings,
        controller: &mut impl Shared,
        out: &mut ReplyLine,
        keep_off: bool,
    ) {
        let Some((image, _)) = self.image else { return };
        let job = controller.with(|c| c.as_ref().map(|c| c.replan(next)));
        let result = match job {
            Some(Ok(job)) => job.solve(image.table),
            Some(Err(refusal)) => Err(refusal),
            None => return,
        };
        let adopted = result.and_then(|replanned| {
            controller.with(|c| match c {
                Some(c) => c.adopt(replanned).map(|boot| {
                    let from_volts = c.plan().start_volts;
                    if keep_off {
                        c.stop();
                    }
                    (boot, from_volts)
                }),
                None => Err(Refusal::Busy {
                    phase: Phase::Faulted,
                }),
            })
        });
        match adopted {
            Ok((boot, from_volts)) => {
                let _ = write!(
                    out,
                    "ok target_hz={} bias_volts={} from_volts={} max_volts={} ac_volts={} ac_hz={}",
                    Decimal(next.target_hz),
                    Decimal(boot.bias_volts),
                    Decimal(from_volts),
                    Decimal(boot.max_volts),
                    Decimal(next.ac_volts),
                    Decimal(next.ac_hz)
                );
                if keep_off {
                    let _ = write!(out, " (the output stays off: `start` to drive)");
                }
                self.limit = boot.limit.map(|l| l.mode).or(self.limit);
            }
            Err(refusal) => err(out, code(&refusal), refusal),
        }
    }

    /// Boot again with the settings asked for, once the output is at 0 V (a fault's descent
    /// over, stopped, or never booted); the new controller replaces the old only if every
    /// check passes.
    fn clear(&mut self, controller: &mut impl Shared, out: &mut ReplyLine) {
        let Some((image, amplifier)) = self.image else {
            return;
        };
        if !at_zero(controller) {
            err(
                out,
                ErrorCode::State,
                "clear re-arms at 0 V only: `stop` first, or wait for a fault's descent",
            );
            return;
        }
        // The settings the old controller ran on (a latched one keeps its own), else those
        // asked for while none ran.
        let settings = controller
            .with(|c| c.as_ref().map(|c| *c.settings()))
            .unwrap_or(self.idle_settings);
        let mut fresh = None;
        let board = image.board(amplifier, settings.tick_hz);
        match Controller::start_in(&mut fresh, image.params, image.table, board, settings) {
            Ok(boot) => {
                // Re-armed, not switched on: the new controller stopped at 0 V (the stage
                // off), until `start`, `target` or `ac`.
                if let Some(c) = fresh.as_mut() {
                    c.stop();
                }
                if !replace_at_rest(controller, &mut fresh) {
                    err(
                        out,
                        ErrorCode::Busy,
                        "the output moved during the checks: `stop` first",
                    );
                    return;
                }
                self.refusal = None;
                self.limit = boot.limit.map(|l| l.mode);
                let _ = write!(
                    out,
                    "ok clear: boot checks pass; the output off at 0 V until `start` (ramps to {} V)",
                    Decimal(boot.bias_volts)
                );
            }
            Err(fault) => err(out, ErrorCode::Refused, fault),
        }
    }
}

/// Whether the output is at rest at 0 V: no controller, or one at rest (`Controller::at_rest`).
fn at_zero(controller: &mut impl Shared) -> bool {
    controller.with(|c| c.as_ref().is_none_or(Controller::at_rest))
}

/// Put `next` in the slot if the output is at rest, the check and the swap under one lock
/// (nothing moves between them); whether it did. Swapped in place (the old one left in
/// `next`): a controller (3 KB) moved by value is a copy on the stack.
fn replace_at_rest(controller: &mut impl Shared, next: &mut Option<Controller>) -> bool {
    controller.with(|c| {
        let rest = c.as_ref().is_none_or(Controller::at_rest);
        if rest {
            core::mem::swap(c, next);
        }
        rest
    })
}

/// The status line of a controller, under an amplifier whose top is `top_volts`.
fn status(
    c: &Controller,
    limit: Option<crate::model::safety::FailureMode>,
    top_volts: f32,
    extras: &Extras,
) -> Status {
    let (max_volts, max_by) = if top_volts < c.max_volts() {
        (top_volts, MaxBy::Amplifier)
    } else {
        (c.max_volts(), MaxBy::Cap)
    };
    Status {
        phase: c.phase(),
        target_hz: c.settings().target_hz,
        bias_volts: c.plan().bias_volts,
        volts: c.last_volts(),
        output_on: !c.at_rest(),
        max_volts,
        max_by,
        limit,
        ticks: c.ticks(),
        hardware: *extras,
        ring: c.ring_quality(),
        fault: c.latched_fault(),
    }
}
