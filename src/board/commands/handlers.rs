//! The requests' handlers (`super`'s table calls them): each writes its one reply line. Long
//! work (a new plan's checks, a new boot) runs here, outside the controller's lock; the tick
//! preempts it.

use core::fmt::Write as _;

use super::{Request, Topic, COMMANDS, HELP};
use crate::board::port::{at_zero, err, ReplyLine, Shared, Then};
use crate::board::{Board, Keeper};
use crate::controller::{Controller, Phase, Refusal, Setting, Settings};
use crate::model::device::Field;
use crate::model::safety::FailureMode;
use crate::numerics::decimal::Decimal;
use crate::table::Table;
use crate::wire::protocol::{ErrorCode, Extras, MaxBy, Refused, Status};
use crate::wire::stream;

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
    /// `help`, `help <command>`, `help <setting>`.
    pub(super) fn help(&self, topic: Option<Topic>, out: &mut ReplyLine) -> Then {
        let _ = match topic {
            None => write!(out, "ok {HELP}"),
            Some(Topic::Command(k)) => match COMMANDS.get(usize::from(k)) {
                Some(command) => write!(out, "ok {}: {}", command.form, command.does),
                None => write!(out, "ok "),
            },
            Some(Topic::Setting(setting)) => write!(
                out,
                "ok {} ({}): {}",
                setting.key(),
                setting.unit(),
                setting.rule()
            ),
        };
        Then::Reply
    }

    /// `status`: always answered; while nothing runs, with why.
    pub(super) fn status(&self, request: &mut Request<impl Shared>) -> Then {
        if !request.running {
            let why = self.refusal().unwrap_or("no image");
            let _ = write!(
                request.out,
                "ok {}",
                Refused {
                    hardware: *request.extras,
                    why
                }
            );
            return Then::Reply;
        }
        // Read under the lock, written out after it: formatting the numbers takes thousands
        // of instructions the tick must not wait for.
        let top = self.image.map_or(f32::INFINITY, |(_, a)| a.max_volts());
        let limit = self.limit;
        let extras = request.extras;
        if let Some(status) = request
            .controller
            .with(|c| c.as_ref().map(|c| status(c, limit, top, extras)))
        {
            let _ = write!(request.out, "ok {status}");
        }
        Then::Reply
    }

    /// `info`: the firmware, the image, the stream's layout, the tunable range, the device.
    pub(super) fn info(&self, request: &mut Request<impl Shared>) -> Then {
        let out = &mut *request.out;
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
            Decimal(request.controller.with(|c| self.tick_hz(c))),
            stream::VERSION,
            if request.extras.stream_port {
                "yes"
            } else {
                "no"
            }
        );
        // The tunable range: the table's, the targets the board takes (at a margin set above
        // the image's, the plan's check narrows it).
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
        Then::Reply
    }

    /// `get <setting>`, `get`.
    pub(super) fn get(&self, setting: Option<Setting>, request: &mut Request<impl Shared>) -> Then {
        let settings = request.settings;
        let out = &mut *request.out;
        match setting {
            Some(setting) => {
                let _ = write!(
                    out,
                    "ok {}={}",
                    setting.key(),
                    Decimal(settings.get(setting))
                );
            }
            None => {
                let _ = write!(out, "ok");
                for setting in Setting::ALL {
                    let _ = write!(out, " {}={}", setting.key(), Decimal(settings.get(setting)));
                }
            }
        }
        Then::Reply
    }

    /// `set <setting> <value>`: checked as a new plan; at rest the output stays off; while
    /// nothing runs, kept for `clear`.
    pub(super) fn set(
        &mut self,
        setting: Setting,
        value: f32,
        request: &mut Request<impl Shared>,
    ) -> Then {
        let settings = request.settings;
        if setting == Setting::TickHz && value != settings.tick_hz {
            err(
                request.out,
                ErrorCode::Refused,
                "tick_hz sets the tick's timer at power-up: make an image with it",
            );
            return Then::Reply;
        }
        let mut next = settings;
        next.set(setting, value);
        if !request.running {
            // Refused at boot: kept for `clear` to boot with, and check.
            self.idle_settings = next;
            let _ = write!(
                request.out,
                "ok {}={} (applies at `clear`)",
                setting.key(),
                Decimal(value)
            );
            return Then::Reply;
        }
        // At rest at 0 V (stopped, or re-armed by `clear`): checked as a new plan, the output
        // left off (no command named `set` switches it on).
        let at_rest = request.controller.with(|c| {
            c.as_ref()
                .is_some_and(|c| c.at_rest() && c.phase() != Phase::Faulted)
        });
        self.replan(next, request, at_rest)
    }

    /// `save`: the settings in force into flash. A save erases a slot: where that stalls the
    /// chip past its watchdog, at rest only.
    pub(super) fn save(&mut self, request: &mut Request<impl Shared>) -> Then {
        if self.keeper.as_ref().is_some_and(Keeper::erase_stalls) && !at_zero(request.controller) {
            err(
                request.out,
                ErrorCode::State,
                "`save` erases flash, which stalls the chip: at rest at 0 V only (`stop` first)",
            );
            return Then::Reply;
        }
        match self.keeper.as_mut().map(|k| k.save(&request.settings)) {
            Some(Ok(())) => {
                let _ = write!(
                    request.out,
                    "ok save: the settings in force boot from now on"
                );
            }
            Some(Err(e)) => err(request.out, ErrorCode::Refused, e),
            None => err(request.out, ErrorCode::Unsupported, "no settings storage"),
        }
        Then::Reply
    }

    /// `stop`: AC off, down to 0 V at the slew rate.
    pub(super) fn stop(&self, request: &mut Request<impl Shared>) -> Then {
        let from = request.controller.with(|c| {
            c.as_mut().map(|c| {
                c.stop();
                c.last_volts()
            })
        });
        let _ = match from {
            // Nothing to ramp: said as it is, not as a ramp from 0 V to 0 V.
            Some(volts) if volts != 0.0 => write!(
                request.out,
                "ok stop: ramp from {} V to 0 V",
                Decimal(volts)
            ),
            _ => write!(request.out, "ok stop: at 0 V, the output off"),
        };
        Then::Reply
    }

    /// `trim`: measure and trim now.
    pub(super) fn trim(&self, request: &mut Request<impl Shared>) -> Then {
        match request
            .controller
            .with(|c| c.as_mut().map(Controller::trim_now))
        {
            Some(Ok(())) => {
                let _ = write!(request.out, "ok trim: measuring");
            }
            Some(Err(refusal)) => err(request.out, code(&refusal), refusal),
            None => {}
        }
        Then::Reply
    }

    /// `reset`: at rest at 0 V only, as `clear`: switching the output off under a bias would
    /// drop the membrane's charge at once, and the next boot would ramp from 0 V while the
    /// amplifier still slews down (its monitor's fault, found on `host-sim serve`'s plant).
    /// The controller leaves its slot under the same lock as the check: nothing moves
    /// between them.
    // Not inlined: its empty slot (a controller's room, 3 KB) would sit in the command task's
    // frame under every request, the replan's checks too (`cd firmware && cargo build --release`:
    // the task's frame 6,880 B inlined, 5,568 B not).
    #[inline(never)]
    pub(super) fn reset(&self, request: &mut Request<impl Shared>) -> Then {
        if !replace_at_rest(request.controller, &mut None) {
            err(
                request.out,
                ErrorCode::State,
                "reset at 0 V only: `stop` first, or wait for a fault's descent",
            );
            return Then::Reply;
        }
        let _ = write!(request.out, "ok reset: output off, restarting");
        Then::Reset
    }

    /// `stream <hz>` / `stream off`: the rate checked against the tick's, the reply with the
    /// rate it gives and the bytes a second it sends; the tick's side is the caller's.
    pub(super) fn stream(&self, hz: Option<f32>, request: &mut Request<impl Shared>) -> Then {
        let out = &mut *request.out;
        if !request.extras.stream_port {
            err(out, ErrorCode::Unsupported, "this board has no stream port");
            return Then::Reply;
        }
        let Some(hz) = hz else {
            let _ = write!(out, "ok stream off");
            return Then::Stream(None);
        };
        let tick_hz = request.controller.with(|c| self.tick_hz(c));
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

    /// A new plan with `next`: its job made under the lock, solved outside it, adopted under
    /// it; the controller then holds `next`. `keep_off`: stopped again at once, under the
    /// same lock (the output stays off at 0 V until `start`).
    pub(super) fn replan(
        &mut self,
        next: Settings,
        request: &mut Request<impl Shared>,
        keep_off: bool,
    ) -> Then {
        let (controller, out) = (&mut *request.controller, &mut *request.out);
        let Some((image, _)) = self.image else {
            return Then::Reply;
        };
        let job = controller.with(|c| c.as_ref().map(|c| c.replan(next)));
        let result = match job {
            Some(Ok(job)) => job.solve(image.table),
            Some(Err(refusal)) => Err(refusal),
            None => return Then::Reply,
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
        Then::Reply
    }

    /// `clear`: boot again with the settings asked for, once the output is at 0 V (a fault's
    /// descent over, stopped, or never booted); the new controller replaces the old only if
    /// every check passes.
    // Not inlined: its fresh controller (3 KB) would sit in the command task's frame under
    // every request, as `reset`'s slot would.
    #[inline(never)]
    pub(super) fn clear(&mut self, request: &mut Request<impl Shared>) -> Then {
        let (controller, out) = (&mut *request.controller, &mut *request.out);
        let Some((image, amplifier)) = self.image else {
            return Then::Reply;
        };
        if !at_zero(controller) {
            err(
                out,
                ErrorCode::State,
                "clear re-arms at 0 V only: `stop` first, or wait for a fault's descent",
            );
            return Then::Reply;
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
                    return Then::Reply;
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
        Then::Reply
    }
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
#[inline]
fn status(c: &Controller, limit: Option<FailureMode>, top_volts: f32, extras: &Extras) -> Status {
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
