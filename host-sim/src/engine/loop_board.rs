//! The board a loop runs against the plant ([`LoopBoard`]): the core's on the host
//! ([`crate::engine::core_board`]) or the firmware's under QEMU ([`crate::engine::firmware`]),
//! and what it is given each tick ([`Samples`]).

use de_resonator::acquire::{InputError, Stall};
use de_resonator::wire::link::{Booted, Observed};
use de_resonator::wire::stream::{Receiver, Record};
use de_resonator::{Fault, Inputs};

/// A tick's measurements: read directly (a scene with no front end), or the ADC's codes
/// (`Bench::codes`) that the board's acquisition reads.
#[derive(Clone, Copy, Debug)]
pub enum Samples {
    Direct(Inputs),
    /// The codes in `Bench::codes`; a stall re-armed before this tick (its codes lost).
    Codes {
        stall: Option<Stall>,
    },
}

/// The board a loop runs against the plant: the core's, on the host ([`CoreBoard`](crate::engine::core_board::CoreBoard)), or the
/// firmware's link build under QEMU (`engine::firmware`). Both give the same record of a tick
/// (`wire::link`'s `Observed`), from which the run is kept.
pub trait LoopBoard {
    /// What the boot found, and the refusal's words.
    fn booted(&mut self) -> (Booted, Option<String>);
    /// Tick `k`: its samples (read directly; or the ADC's `codes`, which the core's board
    /// reads as `inputs`) in, then the background job; the board after it, and the words of
    /// what it said. The plant then sees the board's wires.
    fn tick(
        &mut self,
        k: u64,
        inputs: Result<Inputs, InputError>,
        samples: Samples,
        codes: &[u16],
    ) -> Result<(Observed, String), String>;
    /// The fault the last tick raised, where the board gives it as a value (the core's).
    fn fault(&self) -> Option<Fault> {
        None
    }
    /// A line on the command port, between ticks: the board's reply.
    fn command(&mut self, line: &str) -> Result<String, String>;
    /// The telemetry stream's records received so far and the receiver's counts.
    fn records(&mut self) -> Result<(Vec<Record>, Receiver), String>;
}
