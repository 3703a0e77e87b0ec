//! The board's fault log (the core's [`crate::fault_log`] on its [`Keeper`]): a fault the
//! controller latched, a watchdog reset and a brown-out written as they come; `faults` lists
//! the newest (`| <n> <cause> t=<tick>` each, newest first), `faults <n>` gives entry n whole,
//! `faults clear` empties the log.

use core::fmt::Write as _;

use super::{Board, Keeper, ResetCause};
use crate::acquire::Inputs;
use crate::board::port::ReplyLine;
use crate::board::protocol::{ErrorCode, FaultsAsk};
use crate::controller::Fault;
use crate::fault_log::{Cause, Entry, KEPT};
use crate::numerics::decimal::Decimal;
use crate::table::newer;

impl<K: Keeper> Board<'_, K> {
    /// Log a reset the boot found; `None` without a log.
    pub(super) fn log_reset(&mut self, cause: ResetCause) -> Option<Result<u32, K::Error>> {
        let (cause, words) = match cause {
            ResetCause::Watchdog => (
                Cause::Watchdog,
                "watchdog reset: a task hung or ran too long",
            ),
            ResetCause::BrownOut => (Cause::BrownOut, "brown-out reset: the supply fell"),
            ResetCause::Asked => return None,
        };
        // At boot: nothing driven, an erase may stall the chip.
        self.keeper
            .as_mut()?
            .log(&Entry::of_reset(cause, words), true)
    }

    /// Log `fault`, latched at board tick `tick` (`seconds` since boot) with `volts`
    /// commanded and `inputs` read; its sequence number, `None` without a log. Flash work: the
    /// caller runs it outside the tick, and allows an erase (`may_erase`) only where a stall
    /// is harmless (the output at rest at 0 V, or a flash that never stalls).
    pub fn log_fault(
        &mut self,
        fault: &Fault,
        (tick, seconds): (u32, f32),
        volts: f32,
        inputs: &Inputs,
        may_erase: bool,
    ) -> Option<Result<u32, K::Error>> {
        let entry = Entry {
            current_amps: inputs.current_amps,
            stretch: inputs.stretch,
            ..Entry::of_fault(fault, tick, seconds, volts)
        };
        self.keeper.as_mut()?.log(&entry, may_erase)
    }

    /// `faults`, `faults <n>`, `faults clear`.
    pub(super) fn faults(&mut self, ask: FaultsAsk, out: &mut ReplyLine) {
        let Some(keeper) = self.keeper.as_mut() else {
            return super::port::err(out, ErrorCode::Unsupported, "no fault log on this board");
        };
        let done = match ask {
            FaultsAsk::Clear => keeper.clear_faults().map(|r| {
                r.map(|()| {
                    let _ = write!(out, "ok faults cleared");
                })
            }),
            FaultsAsk::One(n) => {
                let mut found = None;
                let done = keeper.each_fault(&mut |e| {
                    if e.sequence == n {
                        found = Some(e);
                    }
                });
                done.map(|r| {
                    r.map(|()| match found {
                        Some(e) => one(&e, out),
                        None => super::port::err(
                            out,
                            ErrorCode::Refused,
                            format_args!("no fault {n} in the log (`faults` lists them)"),
                        ),
                    })
                })
            }
            FaultsAsk::List => {
                // The newest KEPT, newest first: each entry put in its place, the oldest
                // falling off the end (no sort, no move of the whole list).
                let mut kept: [Option<(u32, Cause, u32)>; KEPT] = [None; KEPT];
                let done = keeper.each_fault(&mut |e| {
                    let item = (e.sequence, e.cause, e.tick);
                    let Some(at) = kept
                        .iter()
                        .position(|k| k.is_none_or(|k| newer(item.0, k.0)))
                    else {
                        return;
                    };
                    let mut carry = Some(item);
                    for slot in kept.iter_mut().skip(at) {
                        carry = core::mem::replace(slot, carry);
                        if carry.is_none() {
                            break;
                        }
                    }
                });
                done.map(|r| {
                    r.map(|()| {
                        let _ = write!(out, "ok faults={}", kept.iter().flatten().count());
                        for (sequence, cause, tick) in kept.iter().flatten() {
                            let _ = write!(out, " | {sequence} {} t={tick}", cause.key());
                        }
                    })
                })
            }
        };
        match done {
            Some(Ok(())) => {}
            Some(Err(e)) => super::port::err(out, ErrorCode::Refused, e),
            None => super::port::err(out, ErrorCode::Unsupported, "no fault log on this board"),
        }
    }
}

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
    let _ = write!(out, " words={}", e.words);
}
