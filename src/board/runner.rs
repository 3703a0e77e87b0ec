//! The work around a tick and a request, without I/O: the board tick's count since boot, a
//! fault's entry with the voltage sent before it ([`Ticker`]), what a reply sets off
//! ([`follow`]) and the start-up lines ([`write_reset`], [`Started::write_banner`]). The firmware's tasks,
//! host-sim's virtual board (`serve`), the core in host-sim's loop and `count` all call these
//! and only move bytes, so the four cannot drift.

use core::fmt;

use embedded_hal::digital::OutputPin;
use embedded_hal::spi::SpiDevice;

use super::port::Then;
use super::stage::OutputStage;
use super::tick::{self, Ticked};
use super::{Board, Keeper, ResetCause, Started};
use crate::acquire::{Block, InputError, Inputs, Reader};
use crate::controller::{Controller, Event, Fault};
use crate::wire::protocol::NOTICE;
use crate::wire::stream::Telemetry;

/// A fault as the tick saw it latch: at which board tick, at the voltage sent before it (the
/// tick's own output is already the descent's), on what readings. Written to the fault log
/// outside the tick ([`Board::log`]): flash work stalls.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Logged {
    pub fault: Fault,
    pub tick: u32,
    pub volts: f32,
    pub readings: Inputs,
}

/// What one tick did, for the work after it (kept in the [`Ticker`] and written in place,
/// not copied out through the tick's return).
#[derive(Clone, Copy, Debug)]
pub struct AfterTick {
    /// The board tick it was, counted from boot (the stream's and the fault log's count).
    pub tick: u32,
    /// The inputs as read (a block the front end refused reads as none).
    pub readings: Inputs,
    /// What the controller did (`None`: no controller, the output off).
    pub ticked: Option<Ticked>,
    /// The voltage the tick before sent, V.
    volts_before: f32,
}

impl AfterTick {
    /// The event the tick said, if any.
    pub fn event(&self) -> Option<Event> {
        self.ticked.and_then(|t| t.output.event)
    }

    /// A fault latched on this tick, for the fault log (built only when one is: the tick's
    /// cost stays its own).
    pub fn logged(&self) -> Option<Logged> {
        match self.event()? {
            Event::Fault(fault) => Some(Logged {
                fault,
                tick: self.tick,
                volts: self.volts_before,
                readings: self.readings,
            }),
            _ => None,
        }
    }
}

/// The tick's own state: the board tick's count since boot and what the last tick did (the
/// voltage last sent is the controller's: [`Controller::last_volts`]).
#[derive(Clone, Copy, Debug)]
pub struct Ticker {
    next_tick: u32,
    last: AfterTick,
}

impl Default for Ticker {
    fn default() -> Self {
        Ticker::new()
    }
}

impl Ticker {
    /// At boot: no tick yet, 0 V sent.
    pub const fn new() -> Self {
        Ticker {
            next_tick: 0,
            last: AfterTick {
                tick: 0,
                readings: Inputs::NONE,
                ticked: None,
                volts_before: 0.0,
            },
        }
    }

    /// The board's tick on a block of the ADC's samples: the block through the front end
    /// (`acquire`), then [`Ticker::tick`]: the firmware's tick, as `count` counts it.
    pub fn tick_block<SPI: SpiDevice, EN: OutputPin>(
        &mut self,
        reader: &mut Reader,
        block: &Block,
        slot: &mut Option<Controller>,
        stage: &mut OutputStage<SPI, EN>,
    ) -> &AfterTick {
        let inputs = reader.inputs(block);
        self.tick(inputs, slot, stage)
    }

    /// The board's tick on `inputs`: the controller in `slot` (the caller holds its lock)
    /// through the stage ([`tick::drive`], the one enable policy), the count, and the voltage
    /// sent before it (a fault's entry: [`AfterTick::logged`]).
    pub fn tick<SPI: SpiDevice, EN: OutputPin>(
        &mut self,
        inputs: Result<Inputs, InputError>,
        slot: &mut Option<Controller>,
        stage: &mut OutputStage<SPI, EN>,
    ) -> &AfterTick {
        let last = &mut self.last;
        last.tick = self.next_tick;
        self.next_tick = self.next_tick.wrapping_add(1);
        last.readings = match &inputs {
            Ok(readings) => *readings,
            Err(_) => Inputs::NONE,
        };
        // Read only with a controller's fault (`AfterTick::logged`): its own last voltage.
        last.volts_before = slot.as_ref().map_or(0.0, Controller::last_volts);
        last.ticked = tick::drive(slot, stage, inputs);
        &self.last
    }

    /// What the last tick did (before the first: tick 0, nothing).
    pub fn last(&self) -> &AfterTick {
        &self.last
    }

    /// Ticks done since boot (the next tick's number).
    pub fn ticks(&self) -> u32 {
        self.next_tick
    }
}

/// What the caller does after a reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Follow {
    /// Nothing more.
    Nothing,
    /// Restart the board: the slot is empty, the next tick turns the output off; then boot
    /// again (the firmware resets the chip; the stream and the tick count start again).
    Reset,
}

/// What a reply sets off, on the stream's schedule: `stream <hz>` starts or stops the
/// records, `reset` stops them (a restarted board streams nothing until asked).
pub fn follow(then: Then, telemetry: &mut Telemetry) -> Follow {
    match then {
        Then::Reply => Follow::Nothing,
        Then::Stream(every) => {
            telemetry.set(every);
            Follow::Nothing
        }
        Then::Reset => {
            *telemetry = Telemetry::default();
            Follow::Reset
        }
    }
}

/// The first start-up line after a reset, said before the boot's checks run (a boot that
/// stalls leaves its cause said): `reset: <cause>` after [`NOTICE`], ended by `end`.
pub fn write_reset(cause: ResetCause, out: &mut impl fmt::Write, end: &str) -> fmt::Result {
    write!(out, "{NOTICE}reset: {}{end}", cause.name())
}

impl Started {
    /// The start-up lines the command port hears after the boot, before any request, each
    /// after [`NOTICE`] and ended by `end`: the warning (if one), the notice (`ready …` or
    /// `refused …`). After [`write_reset`]'s line, if a reset came first.
    pub fn write_banner(&self, out: &mut impl fmt::Write, end: &str) -> fmt::Result {
        if let Some(warning) = &self.warning {
            write!(out, "{NOTICE}warning: {warning}{end}")?;
        }
        write!(out, "{NOTICE}{}{end}", self.notice)
    }
}

impl<K: Keeper> Board<'_, K> {
    /// `logged` into the fault log, its time since boot at `tick_hz`; its sequence number,
    /// `None` without a log. Flash work: the caller runs it outside the tick.
    pub fn log(&mut self, logged: &Logged, tick_hz: f32) -> Option<Result<u32, K::Error>> {
        let seconds = logged.tick as f32 / tick_hz;
        self.log_fault(
            &logged.fault,
            (logged.tick, seconds),
            logged.volts,
            &logged.readings,
        )
    }
}
