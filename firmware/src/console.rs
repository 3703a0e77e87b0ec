//! The command port's firmware side: bytes from USART2 into request lines (`Lines`, in the
//! receive interrupt), and the reply to each request (`Console::serve`, in the low-priority
//! command task). The protocol itself (parse, replies, status) is the core's `protocol`.

use core::fmt::Write;
use core::ops::Range;

use de_resonator::protocol::{self, Command, ErrorCode, ParseError, Status, MAX_LINE};
use de_resonator::store;
use de_resonator::{
    Amplifier, Controller, Decimal, FailureMode, Image, Refusal, Setting, Settings,
};
use heapless::{String, Vec};

use crate::storage::{block_on, SettingsFlash};

/// One request as received: its bytes, or why it has none.
#[derive(Clone, Debug)]
pub enum Line {
    Text(Vec<u8, MAX_LINE>),
    /// Longer than `MAX_LINE`: the rest was dropped up to its `\n`.
    TooLong,
    /// A byte was lost on the wire (overrun, framing or noise): the line is not trusted.
    Garbled,
}

/// Bytes into lines: at most `MAX_LINE` bytes a line, an overlong or garbled line reported
/// once at its end; a `\r\n` is a `\n`.
#[derive(Default)]
pub struct Lines {
    text: Vec<u8, MAX_LINE>,
    overlong: bool,
    garbled: bool,
}

impl Lines {
    /// Take one byte; a line when it ends one.
    pub fn push(&mut self, byte: u8) -> Option<Line> {
        if byte == b'\n' {
            let line = if self.garbled {
                Line::Garbled
            } else if self.overlong {
                Line::TooLong
            } else {
                Line::Text(self.text.clone())
            };
            *self = Self::default();
            return Some(line);
        }
        if byte == b'\r' {
            return None;
        }
        if self.text.push(byte).is_err() {
            self.overlong = true;
        }
        None
    }

    /// A byte was lost: the line it belonged to is dropped at its end.
    pub fn lost(&mut self) {
        self.garbled = true;
    }
}

/// What the command task does after the reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Then {
    Reply,
    /// Turn the output off and restart the firmware.
    Reset,
}

/// A reply line (one `ok …` or `err …`, without its `\n`); cut short if it would not fit.
pub type ReplyLine = String<256>;

/// What the command task needs besides the controller: the image, the settings asked for
/// (the boot's, then as changed by `target`, `ac`, `set`), and why it refuses, if it does.
pub struct Console {
    pub image: Option<Image<'static>>,
    pub amplifier: Option<Amplifier>,
    pub settings: Settings,
    /// Why nothing is driven: no usable image, or the boot checks refused.
    pub refusal: Option<String<200>>,
    /// The limit the last boot or plan found on the chip (its mode).
    pub limit: Option<FailureMode>,
    /// Where `save` keeps the settings (`None`: nowhere in this build or boot).
    pub store: Option<(SettingsFlash, Range<u32>)>,
}

/// Where the reply's extra status fields come from, read by the command task.
pub struct Extras {
    /// The longest tick so far, core cycles.
    pub tick_cycles_max: u32,
    pub stack_bytes: u32,
    pub clock_us: Option<u32>,
}

/// `err <code> <message>` into `out`.
pub fn err(out: &mut ReplyLine, code: ErrorCode, message: impl core::fmt::Display) {
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

/// The controller as the command task reaches it: under a lock shared with the tick.
pub trait Shared {
    fn with<R>(&mut self, f: impl FnOnce(&mut Option<Controller>) -> R) -> R;
}

impl Console {
    /// The status line of a controller.
    fn status(&self, c: &Controller, extras: &Extras) -> Status {
        Status {
            phase: c.phase(),
            target_hz: c.settings().target_hz,
            bias_volts: c.plan().bias_volts,
            volts: c.last_volts(),
            max_volts: c.max_volts(),
            limit: self.limit,
            ticks: c.ticks(),
            tick_cycles_max: extras.tick_cycles_max,
            stack_bytes: extras.stack_bytes,
            clock_us: extras.clock_us,
            fault: c.latched_fault(),
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
        self.answer(line, controller, extras, out)
    }

    fn answer(
        &mut self,
        line: &Line,
        controller: &mut impl Shared,
        extras: &Extras,
        out: &mut ReplyLine,
    ) -> Then {
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
        if let Command::Help = command {
            let _ = write!(out, "ok {}", protocol::HELP);
            return Then::Reply;
        }
        let (Some(image), Some(amplifier)) = (self.image, self.amplifier) else {
            err(
                out,
                ErrorCode::Config,
                self.refusal.as_deref().unwrap_or("no image"),
            );
            return Then::Reply;
        };
        let running = controller.with(|c| c.is_some());
        match command {
            Command::Get(setting) => {
                let _ = write!(
                    out,
                    "ok {}={}",
                    setting.key(),
                    Decimal(self.settings.get(setting))
                );
            }
            Command::Set(setting, value) => {
                let mut next = self.settings;
                next.set(setting, value);
                if setting == Setting::TickHz && value != self.settings.tick_hz {
                    err(
                        out,
                        ErrorCode::Refused,
                        "tick_hz sets SysTick at power-up: make an image with it",
                    );
                    return Then::Reply;
                }
                if !running {
                    // Refused at boot: kept for `clear` to boot with, and check.
                    self.settings = next;
                    let _ = write!(
                        out,
                        "ok {}={} (applies at `clear`)",
                        setting.key(),
                        Decimal(value)
                    );
                    return Then::Reply;
                }
                self.replan(image, next, controller, out);
            }
            Command::Clear => self.clear(image, amplifier, controller, out),
            Command::Save => {
                let saved = match &mut self.store {
                    // The flash never waits (RAM, or the chip's controller blocking in each
                    // call): run to its end here.
                    Some((flash, range)) => {
                        block_on(store::save(flash, range.clone(), &self.settings))
                            .unwrap_or(Err(store::StoreError::Flash(store::FlashKind::Other)))
                    }
                    None => {
                        err(out, ErrorCode::Unsupported, "no settings storage");
                        return Then::Reply;
                    }
                };
                match saved {
                    Ok(()) => {
                        let _ = write!(out, "ok save: the settings in force boot from now on");
                    }
                    Err(e) => err(out, ErrorCode::Refused, e),
                }
            }
            _ if !running => {
                err(
                    out,
                    ErrorCode::Config,
                    self.refusal.as_deref().unwrap_or("not booted"),
                );
            }
            Command::Status => {
                controller.with(|c| {
                    if let Some(c) = c {
                        let _ = write!(out, "ok {}", self.status(c, extras));
                    }
                });
            }
            Command::Target { hz } => {
                let next = Settings {
                    target_hz: hz,
                    ..self.settings
                };
                self.replan(image, next, controller, out);
            }
            Command::Ac { volts, hz } => {
                let next = Settings {
                    ac_volts: volts,
                    ac_hz: hz,
                    ..self.settings
                };
                self.replan(image, next, controller, out);
            }
            Command::Stop => {
                let from = controller.with(|c| {
                    c.as_mut().map(|c| {
                        c.stop();
                        c.last_volts()
                    })
                });
                let _ = write!(
                    out,
                    "ok stop: ramp from {} V to 0 V",
                    Decimal(from.unwrap_or(0.0))
                );
            }
            Command::Trim => match controller.with(|c| c.as_mut().map(Controller::trim_now)) {
                Some(Ok(())) => {
                    let _ = write!(out, "ok trim: measuring");
                }
                Some(Err(refusal)) => err(out, code(&refusal), refusal),
                None => {}
            },
            Command::Reset => {
                let _ = write!(out, "ok reset: output off, restarting");
                return Then::Reset;
            }
            Command::Help => {}
        }
        Then::Reply
    }

    /// A new plan with `next`: its job made under the lock, solved outside it, adopted under
    /// it; the settings kept only once adopted.
    fn replan(
        &mut self,
        image: Image<'static>,
        next: Settings,
        controller: &mut impl Shared,
        out: &mut ReplyLine,
    ) {
        let job = controller.with(|c| c.as_ref().map(|c| c.replan(next)));
        let result = match job {
            Some(Ok(job)) => job.solve(image.table),
            Some(Err(refusal)) => Err(refusal),
            None => return,
        };
        let adopted = result.and_then(|replanned| {
            controller.with(|c| match c {
                Some(c) => c.adopt(replanned).map(|boot| (boot, c.plan().start_volts)),
                None => Err(Refusal::Busy {
                    phase: de_resonator::Phase::Faulted,
                }),
            })
        });
        match adopted {
            Ok((boot, from_volts)) => {
                self.settings = next;
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
                self.limit = boot.limit.map(|l| l.mode).or(self.limit);
            }
            Err(refusal) => err(out, code(&refusal), refusal),
        }
    }

    /// Boot again with the settings asked for, once the output is at 0 V (a fault's descent
    /// over, stopped, or never booted); the new controller replaces the old only if every check passes.
    fn clear(
        &mut self,
        image: Image<'static>,
        amplifier: Amplifier,
        controller: &mut impl Shared,
        out: &mut ReplyLine,
    ) {
        let at_zero = controller.with(|c| c.as_ref().is_none_or(|c| c.last_volts() == 0.0));
        if !at_zero {
            err(
                out,
                ErrorCode::Busy,
                "clear re-arms at 0 V only: `stop` first, or wait for a fault's descent",
            );
            return;
        }
        let mut fresh = None;
        match Controller::start_in(
            &mut fresh,
            image.params,
            image.table,
            amplifier,
            self.settings,
        ) {
            Ok(boot) => {
                let bias = boot.bias_volts;
                let swapped = controller.with(|c| {
                    let idle = c.as_ref().is_none_or(|c| c.last_volts() == 0.0);
                    if idle {
                        *c = fresh.take();
                    }
                    idle
                });
                if !swapped {
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
                    "ok clear: boot checks pass, ramp to {} V",
                    Decimal(bias)
                );
            }
            Err(fault) => err(out, ErrorCode::Refused, fault),
        }
    }
}
