//! The board's fault log (the core's [`crate::fault_log`] on its [`Keeper`]): a fault the
//! controller latched, a watchdog reset and a brown-out written as they come; `faults` lists
//! the newest (`| <n> <cause> t=<tick>` each, newest first), `faults <n>` gives entry n whole,
//! `faults clear` empties the log.

use core::fmt::Write as _;

use super::commands::FaultsAsk;
use super::{Board, FaultKeeper, Keeper, ResetCause, Shared};
use crate::acquire::Inputs;
use crate::board::port::{at_zero, ReplyLine};
use crate::controller::Fault;
use crate::fault_log::{keep_newest, Cause, Entry, KEPT};
use crate::numerics::decimal::Decimal;
use crate::wire::protocol::ErrorCode;

impl<K: Keeper> Board<'_, K> {
    /// The fault log, if the board keeps one.
    pub(super) fn fault_log(&mut self) -> Option<K::Log<'_>> {
        self.keeper.as_mut()?.fault_log()
    }

    /// Log a reset the boot found; `None` without a log.
    pub(super) fn log_reset(&mut self, cause: ResetCause) -> Option<Result<u32, K::Error>> {
        let cause = match cause {
            ResetCause::Watchdog => Cause::Watchdog,
            ResetCause::BrownOut => Cause::BrownOut,
            ResetCause::Asked => return None,
        };
        Some(self.fault_log()?.log(&Entry::of_reset(cause)))
    }

    /// Log `fault`, latched at board tick `tick` (`seconds` since boot) with `volts` sent
    /// before it and `inputs` read; its sequence number, `None` without a log. Flash work: the
    /// caller runs it outside the tick.
    pub fn log_fault(
        &mut self,
        fault: &Fault,
        (tick, seconds): (u32, f32),
        volts: f32,
        inputs: &Inputs,
    ) -> Option<Result<u32, K::Error>> {
        let entry = Entry {
            current_amps: inputs.current_amps,
            stretch: inputs.stretch,
            ..Entry::of_fault(fault, tick, seconds, volts)
        };
        Some(self.fault_log()?.log(&entry))
    }

    /// `faults`, `faults <n>`, `faults clear` (at rest at 0 V only: it erases flash, which
    /// stalls a chip).
    pub(super) fn faults(
        &mut self,
        ask: FaultsAsk,
        controller: &mut impl Shared,
        out: &mut ReplyLine,
    ) {
        if ask == FaultsAsk::Clear && !at_zero(controller) {
            return super::port::err(
                out,
                ErrorCode::State,
                "`faults clear` erases flash, which stalls the chip: at rest at 0 V only \
                 (`stop` first)",
            );
        }
        let Some(mut log) = self.fault_log() else {
            return super::port::err(out, ErrorCode::Unsupported, "no fault log on this board");
        };
        let done = match ask {
            FaultsAsk::Clear => log.clear().map(|()| {
                let _ = write!(out, "ok faults cleared");
            }),
            FaultsAsk::One(n) => {
                let mut found = None;
                let done = log.each(&mut |e| {
                    if e.sequence == n {
                        found = Some(e);
                    }
                });
                done.map(|()| match found {
                    Some(e) => one(&e, out),
                    None => super::port::err(
                        out,
                        ErrorCode::Refused,
                        format_args!("no fault {n} in the log (`faults` lists them)"),
                    ),
                })
            }
            FaultsAsk::List => {
                // The newest KEPT, newest first (no sort: flash for the firmware).
                let mut kept: [Option<(u32, Cause, u32)>; KEPT] = [None; KEPT];
                let done = log
                    .each(&mut |e| keep_newest(&mut kept, |k| k.0, (e.sequence, e.cause, e.tick)));
                done.map(|()| {
                    let _ = write!(out, "ok faults={}", kept.iter().flatten().count());
                    for (sequence, cause, tick) in kept.iter().flatten() {
                        // The line's room: the rest said as such, never cut mid-entry.
                        if out.capacity() - out.len() < ITEM_BYTES + MORE.len() {
                            let _ = out.push_str(MORE);
                            break;
                        }
                        let _ = write!(out, " | {sequence} {} t={tick}", cause.key());
                    }
                })
            }
        };
        if let Err(e) = done {
            super::port::err(out, ErrorCode::Refused, e);
        }
    }
}

/// The longest item of the list: ` | ` and a u32, a space, the longest key, ` t=` and a u32.
const ITEM_BYTES: usize = 3 + 10 + 1 + 19 + 3 + 10;
/// What ends a list cut for the reply line's room.
const MORE: &str = " | … (older: `faults <n>`)";

/// One entry whole: its fields, its words last (they take the rest of the line).
fn one(e: &Entry, out: &mut ReplyLine) {
    let _ = write!(
        out,
        "ok sequence={} cause={} tick={} seconds={} volts={}",
        e.sequence,
        e.cause.key(),
        e.tick,
        Decimal(e.seconds),
        Decimal(e.volts)
    );
    if let Some(amps) = e.current_amps {
        let _ = write!(out, " current_amps={}", Decimal(amps));
    }
    if let Some(stretch) = e.stretch {
        let _ = write!(out, " stretch={}", Decimal(stretch));
    }
    let _ = write!(out, " words={}", e.words());
}
