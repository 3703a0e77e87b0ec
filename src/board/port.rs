//! The command port's board side: bytes into request lines ([`Lines`]), what a reply is
//! written into ([`ReplyLine`]) and sets off ([`Then`]), and the controller as a request
//! reaches it ([`Shared`]). Each request is answered by [`super::commands`]; the line
//! protocol's words, replies and status are [`crate::wire::protocol`].

use core::fmt::Write as _;

use heapless::{String, Vec};

use crate::controller::Controller;
use crate::wire::protocol::{ErrorCode, MAX_LINE};

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

pub use crate::wire::protocol::{Extras, TickClock};

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

/// Whether the output is at rest at 0 V: no controller, or one at rest (`Controller::at_rest`).
#[inline]
pub(super) fn at_zero(controller: &mut impl Shared) -> bool {
    controller.with(|c| c.as_ref().is_none_or(Controller::at_rest))
}

/// `err <code> <message>` into `out`.
pub(super) fn err(out: &mut ReplyLine, code: ErrorCode, message: impl core::fmt::Display) {
    out.clear();
    let _ = write!(out, "err {code} {message}");
}
