//! The command port's requests, each declared once below: its name, form and help, how its
//! arguments parse, the rule it runs under and its handler (`declare_commands!`). `help`, the
//! parser, the suggestion for a typo, `host-sim serve`'s read-only connections and the docs'
//! table of requests (docs/firmware.md, checked against `COMMANDS`) all come from this list.

mod declare;
mod handlers;

use super::port::{err, Line, ReplyLine, Shared, Then};
use super::{Board, Keeper};
use crate::controller::{Setting, Settings};
use crate::wire::protocol::{
    self, edit_distance, nearest_name, nearest_setting, Args, ErrorCode, Extras, ParseError,
};
use declare::declare_commands;

/// A command's form (`target <Hz>`, its name the first word) and what it does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CommandInfo {
    pub form: &'static str,
    pub does: &'static str,
}

impl CommandInfo {
    /// The command's name: its form's first word.
    pub fn name(&self) -> &'static str {
        let words = self.form.as_bytes();
        let mut end = 0;
        while words.get(end).is_some_and(|&b| b != b' ') {
            end += 1;
        }
        self.form.get(..end).unwrap_or(self.form)
    }
}

/// Whether `form` starts with the word `name` (the table's check, when the crate is built).
#[allow(clippy::indexing_slicing)] // an index out of range fails the build
const fn names(form: &str, name: &str) -> bool {
    let (form, name) = (form.as_bytes(), name.as_bytes());
    if form.len() < name.len() || (form.len() > name.len() && form[name.len()] != b' ') {
        return false;
    }
    let mut k = 0;
    while k < name.len() {
        if form[k] != name[k] {
            return false;
        }
        k += 1;
    }
    true
}

/// What must hold before a command's handler runs; else `err 5` (`ErrorCode::Config`) with
/// the boot's refusal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// Answered always, with or without an image or a controller.
    Always,
    /// An image is flashed (its controller may have been refused: the settings asked for
    /// then are those `clear` boots with).
    Imaged,
    /// A controller runs (booted, not refused).
    Booted,
}

/// What `help` is asked about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Topic {
    /// A command, by its index in [`COMMANDS`].
    Command(u8),
    Setting(Setting),
}

/// What `faults` asks of the fault log.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaultsAsk {
    /// `faults`: the newest entries, newest first.
    List,
    /// `faults <n>`: entry number n whole.
    One(u32),
    /// `faults clear`: empty the log.
    Clear,
}

/// A request being answered: the controller's slot, the board's hardware, the reply, and
/// the settings in force (the controller's; while none runs, those `clear` boots with).
pub struct Request<'a, S: Shared> {
    pub controller: &'a mut S,
    pub extras: &'a Extras,
    pub out: &'a mut ReplyLine,
    pub settings: Settings,
    /// Whether a controller runs.
    pub running: bool,
}

declare_commands! {
    /// A request of the command port.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub enum Command {
        /// The list of requests; with a command, what it does; with a setting's key, its unit and
        /// the rule its checks hold it to; a typo gets the nearest command or setting.
        Help(topic: Option<Topic>) = "help" "help [command | setting]"
            "the commands, or what one command does, or one setting's unit and range"
            rule Always
            reads true,
            parse |args| Command::Help(topic(args)?),
            run |board, request| board.help(topic, request.out);

        /// `ok phase=… target_hz=… bias_volts=… volts=… output=on|off max_volts=…
        /// max_by=cap|amplifier limit=… ticks=… [tick_cycles_max=…] stack_bytes=… [clock_tick=…
        /// clock_us=…] [current_amps=… amplifier_volts=… stretch=…] [stalls_recovered=…] [ring_hz=…
        /// quality_factor=… quality_high=…] fault=…` (`output` whether the high voltage is on:
        /// `off` only at rest at 0 V, stopped, waiting for `start` or faulted with its descent
        /// over; a ramp down is `on`; `max_volts` the most the board commands: the cap in force, or
        /// the amplifier's rail or top code where lower, `max_by` says which; `ticks` the
        /// controller's ticks since it started, at the boot or a `clear`; `tick_cycles_max` on
        /// silicon only, under QEMU a tick after a `wfi` counts QEMU's wake-up; `clock_us` an
        /// independent clock (QEMU's TIM2, serve's simulated time) at the start of tick
        /// `clock_tick` since power-up, read together; the readings of the fitted inputs; the last
        /// trim window's ring, its frequency and Q from its decay with the highest Q the window
        /// allows (a drive the trim starts is checked with that, or the device file's Q where
        /// higher); the fault last, `none` or its sentence). Always answered: with no image or a
        /// refused boot, `ok phase=refused volts=0 output=off … fault=<why>`.
        Status = "status" "status"
            "the phase, whether the output is on and its volts, the target, the bias, the cap \
             in force, the limit, the last fault, the ticks"
            rule Always
            reads true,
            run |board, request| board.status(request);

        /// What runs: `ok firmware=… image_crc=0x… tick_hz=… stream_layout=… stream_port=yes|no
        /// tunable_low_hz=… tunable_high_hz=… device.shear_modulus=… …` (the tunable range: the
        /// image's table's ends, the targets `target` takes at the image's margin; the device
        /// flashed, by its device-file keys; a recording's header names them all).
        Info = "info" "info"
            "the firmware's version, the image's CRC, the telemetry record's layout"
            rule Always
            reads true,
            run |board, request| board.info(request);

        /// Switch the high voltage on: the plan of the settings in force, checked as `target` is,
        /// ramped to from the present voltage (after `clear` or `stop`, from 0 V); the reply is
        /// `target`'s.
        Start = "start" "start"
            "switch the high voltage on: ramp at the slew rate to the bias of the settings in \
             force (checked as `target` is)"
            rule Booted
            reads false,
            run |board, request| board.replan(request.settings, request, false);

        /// Solve on the chip, run the new plan through the model from the present bias, ramp there
        /// at the slew rate; `ok target_hz=… bias_volts=… from_volts=… max_volts=…`.
        Target { hz: f32 } = "target" "target <Hz>"
            "tune to this natural frequency: the bias solved within the margin, the plan \
             checked in the model, a ramp there; switches the output on"
            rule Booted
            reads false,
            parse |args| Command::Target { hz: args.number_in("Hz")? },
            run |board, request| {
                let next = Settings {
                    target_hz: hz,
                    ..request.settings
                };
                board.replan(next, request, false)
            };

        /// A new AC drive on the bias (0: none), checked as `target` is.
        Ac { volts: f32, hz: f32 } = "ac" "ac <volts> <Hz>"
            "a new AC drive on the bias (0 V: none), its swing checked against every limit \
             first; switches the output on"
            rule Booted
            reads false,
            parse |args| Command::Ac {
                volts: args.number_in("V")?,
                hz: args.number_in("Hz")?,
            },
            run |board, request| {
                let next = Settings {
                    ac_volts: volts,
                    ac_hz: hz,
                    ..request.settings
                };
                board.replan(next, request, false)
            };

        /// Ramp to 0 V at the slew rate; at rest the DAC is powered down and the amplifier
        /// disabled. An emergency stop any connection may give.
        Stop = "stop" "stop"
            "AC off, then down to 0 V at the slew rate; the output off"
            rule Booted
            reads true,
            run |board, request| board.stop(request);

        /// Measure the natural frequency and Q (from the ring's decay, `status`) and trim now (with
        /// `trim_tolerance` set); refused once stopped at 0 V (it would switch the high voltage on:
        /// `target` does), and while held below the cap (it would measure at the cap: `target` a
        /// reachable frequency, or `stop`).
        Trim = "trim" "trim"
            "measure the natural frequency now and trim the bias to the target"
            rule Booted
            reads false,
            run |board, request| board.trim(request);

        /// At 0 V (a latched fault's descent over, or stopped): the boot checks again with the
        /// settings in force; the output stays off at 0 V (DAC powered down, enable low) until
        /// `start`, `target` or `ac`: no command named `clear` (or `set`) switches the high voltage
        /// on.
        Clear = "clear" "clear"
            "re-arm after a fault, at 0 V: the boot checks again, the output left off (`start` \
             switches it on)"
            rule Imaged
            reads false,
            run |board, request| board.clear(request);

        /// A setting's value by its key (`Setting::ALL`, as in scenes); alone, every setting's
        /// value; a key not known gets the nearest one suggested.
        Get(setting: Option<Setting>) = "get" "get [setting]"
            "one setting's value, or every setting's"
            rule Imaged
            reads true,
            parse |args| Command::Get(args.optional_setting()?),
            run |board, request| board.get(setting, request);

        /// A setting's new value by its key, checked as a new plan (at rest at 0 V the output stays
        /// off: `start` to drive); while no controller runs, kept for `clear`. `tick_hz` sets the
        /// tick's timer, SysTick, at power-up: it comes from the image.
        Set(setting: Setting, value: f32) = "set" "set <setting> <value>"
            "a new value, the plan checked again (err 2 names the rule it breaks); at rest the \
             output stays off"
            rule Imaged
            reads false,
            parse |args| {
                let setting = args.setting()?;
                let value = args.number_in(setting.unit())?;
                if setting.whole() && libm::truncf(value) != value {
                    return Err(ParseError::NotWhole { index: 2 });
                }
                Command::Set(setting, value)
            },
            run |board, request| board.set(setting, value, request);

        /// Store the settings in force in flash: the firmware boots with them from then on (`#
        /// ready … settings=saved`); at rest at 0 V only where an erase stalls the chip (`err 7`: a
        /// slot's erase stalls the core for seconds, the tick with it; the watchdog's window is
        /// lengthened around it, see docs/firmware.md, **Flash erases and the watchdog**); saved
        /// settings the boot checks refuse are ignored with a `# warning:` line, and the image's
        /// are used.
        Save = "save" "save"
            "store the settings in force in flash (at rest at 0 V); the board boots with them"
            rule Imaged
            reads false,
            run |board, request| board.save(request);

        /// At rest at 0 V only (`stop` first, or a fault's descent over, and after a dead bus the
        /// time the output needs to follow at the slew rate; else `err 7`, a wrong state): turn the
        /// output off (the DAC powered down, enable low) and restart; the next start-up line says
        /// `# reset: asked`, and the board comes up with the output off at 0 V whatever the image's
        /// power-up (`start` to drive).
        Reset = "reset" "reset"
            "restart the firmware (at rest at 0 V: `stop` first); it comes up with the output \
             off"
            rule Booted
            reads false,
            run |board, request| board.reset(request);

        /// Start (at the nearest whole number of ticks between records: `ok stream hz=…
        /// every_ticks=… frame_bytes=66 bytes_per_second=…`) or stop (`stream off`) the telemetry
        /// stream (`wire::stream`) on the stream port; `err 6` on a board without one, `err 2` for
        /// a rate above the tick's or not above 0.
        Stream(hz: Option<f32>) = "stream" "stream <Hz> | stream off"
            "send the telemetry records at this rate on the stream port, or stop"
            rule Always
            reads false,
            parse |args| match args.optional_word() {
                Some("off") => Command::Stream(None),
                Some(word) => Command::Stream(Some(args.with_unit(word, "Hz")?)),
                None => return Err(ParseError::Missing { index: 1 }),
            },
            run |board, request| board.stream(hz, request);

        /// The fault log: the newest 32 entries, newest first (`ok faults=N | <n> <cause> t=<tick>
        /// | …`); entry n whole (`ok sequence=n cause=… tick=… seconds=… volts=… [current_amps=…]
        /// [stretch=…] words=<what happened>`); or emptied (`faults clear`, at rest). An entry's
        /// `t`/`tick` counts the board's ticks since it booted (power-up or `reset`; a `clear` does
        /// not restart it, unlike `status`'s `ticks`), `seconds` the same at the tick rate, `volts`
        /// the output sent before the fault.
        Faults(ask: FaultsAsk) = "faults" "faults [<n> | clear]"
            "the fault log, newest first; entry n whole; or empty it (at rest)"
            rule Always
            reads ask != FaultsAsk::Clear,
            parse |args| Command::Faults(match args.optional_word() {
                None => FaultsAsk::List,
                Some("clear") => FaultsAsk::Clear,
                Some(word) => {
                    let n = protocol::parse_number(word)
                        .filter(|n| *n >= 1.0 && *n < 16_777_216.0 && libm::truncf(*n) == *n)
                        .ok_or(ParseError::BadNumber { index: 1 })?;
                    FaultsAsk::One(n as u32)
                }
            }),
            run |board, request| {
                board.faults(ask, request.controller, request.out);
                Then::Reply
            };
    }
}

/// What `help` answers, one line: every command's form, made when the crate is built.
pub const HELP: &str = match core::str::from_utf8(&HELP_BYTES) {
    Ok(text) => text,
    // Never: the bytes are those of `&str`s.
    Err(_) => "",
};

const HELP_HEAD: &str = "commands: ";
const HELP_SEPARATOR: &str = " | ";
const HELP_TAIL: &str = " (`help <command>` says what one does; `get` lists every setting, \
                         `help <setting>` its unit and range)";
const HELP_BYTES: [u8; help_len()] = help_bytes();

/// The length of `HELP`: the head, the forms and their separators, the tail (an index out
/// of range fails the build).
#[allow(clippy::indexing_slicing)]
const fn help_len() -> usize {
    let mut len = HELP_HEAD.len() + HELP_TAIL.len();
    let mut k = 0;
    while k < COMMANDS.len() {
        if k > 0 {
            len += HELP_SEPARATOR.len();
        }
        len += COMMANDS[k].form.len();
        k += 1;
    }
    len
}

/// The bytes of `HELP` (an index out of range fails the build, not the board).
#[allow(clippy::indexing_slicing)]
const fn help_bytes() -> [u8; help_len()] {
    const fn put(bytes: &mut [u8; help_len()], mut at: usize, text: &str) -> usize {
        let text = text.as_bytes();
        let mut k = 0;
        while k < text.len() {
            bytes[at] = text[k];
            at += 1;
            k += 1;
        }
        at
    }
    let mut bytes = [0u8; help_len()];
    let mut at = put(&mut bytes, 0, HELP_HEAD);
    let mut k = 0;
    while k < COMMANDS.len() {
        if k > 0 {
            at = put(&mut bytes, at, HELP_SEPARATOR);
        }
        at = put(&mut bytes, at, COMMANDS[k].form);
        k += 1;
    }
    put(&mut bytes, at, HELP_TAIL);
    bytes
}

/// Parse one request line (without its `\n`; a trailing `\r` is dropped). The commands are
/// `COMMANDS`' (what `help` says): no command without its help.
pub fn parse(line: &[u8]) -> Result<Command, ParseError> {
    let (name, mut args) = protocol::words(line)?;
    let command = command(name, &mut args)?;
    args.end()?;
    Ok(command)
}

/// `help`'s argument: a command or a setting if a word is left, `None` if none is; else the
/// nearer of the two to what was typed (a command on a tie).
fn topic(args: &mut Args) -> Result<Option<Topic>, ParseError> {
    let Some(word) = args.optional_word() else {
        return Ok(None);
    };
    if let Some(k) = COMMANDS.iter().position(|c| c.name() == word) {
        return Ok(Some(Topic::Command(k as u8)));
    }
    if let Some(s) = Setting::from_key(word) {
        return Ok(Some(Topic::Setting(s)));
    }
    let command = nearest_name(word, &COMMANDS, CommandInfo::name);
    let setting = nearest_setting(word)
        .map(|s| (edit_distance(word.as_bytes(), s.key().as_bytes()), s.key()));
    let nearest = match (command, setting) {
        (Some((to_command, command)), Some((to_setting, setting))) => {
            Some(if to_setting < to_command {
                setting
            } else {
                command
            })
        }
        (command, setting) => command.or(setting).map(|(_, name)| name),
    };
    Err(ParseError::UnknownTopic { nearest })
}

impl<K: Keeper> Board<'_, K> {
    /// Answer one request into `out`: parsed, then its command's rule and handler
    /// (below). Long work (a new plan's checks, a new boot) runs here, outside the
    /// controller's lock; the tick preempts it.
    pub fn serve(
        &mut self,
        line: &Line,
        controller: &mut impl Shared,
        extras: &Extras,
        out: &mut ReplyLine,
    ) -> Then {
        out.clear();
        let parsed = match line {
            Line::Text(bytes) => parse(bytes),
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
        match parsed {
            Ok(command) => self.answer(command, controller, extras, out),
            Err(e) => {
                err(out, ErrorCode::Syntax, e);
                Then::Reply
            }
        }
    }

    /// Answer one parsed request into `out`: its rule, then its handler.
    fn answer(
        &mut self,
        command: Command,
        controller: &mut impl Shared,
        extras: &Extras,
        out: &mut ReplyLine,
    ) -> Then {
        // The settings in force: the controller's; while none runs, those `clear` boots with.
        let mut settings = self.idle_settings;
        let running = controller.with(|c| c.as_ref().map(|c| settings = *c.settings()).is_some());
        let mut request = Request {
            controller,
            extras,
            out,
            settings,
            running,
        };
        if !self.admits(command.rule(), &mut request) {
            return Then::Reply;
        }
        self.run(command, &mut request)
    }

    /// Whether `rule` holds for `request`; if not, its `err` written.
    fn admits(&self, rule: Rule, request: &mut Request<impl Shared>) -> bool {
        let refused = match rule {
            Rule::Always => None,
            Rule::Imaged if self.image.is_none() => Some("no image"),
            Rule::Imaged => None,
            Rule::Booted if self.image.is_none() => Some("no image"),
            Rule::Booted if !request.running => Some("not booted"),
            Rule::Booted => None,
        };
        match refused {
            Some(otherwise) => {
                err(
                    request.out,
                    ErrorCode::Config,
                    self.refusal().unwrap_or(otherwise),
                );
                false
            }
            None => true,
        }
    }
}

#[cfg(test)]
#[allow(clippy::indexing_slicing)] // a test fails by panicking
mod tests;
