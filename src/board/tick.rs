//! A tick of the board: the controller's output through the output stage, with the one
//! policy for when the amplifier is on (the firmware's tick and host-sim's loops both call
//! [`drive`]), and the background job the tick asks for ([`run_job`]).

use embedded_hal::digital::OutputPin;
use embedded_hal::spi::SpiDevice;

use crate::acquire::InputError;
use crate::board::stage::OutputStage;
use crate::controller::{Controller, Inputs, Output, Phase};

/// What a tick did, when a controller runs.
#[derive(Clone, Copy, Debug)]
pub struct Ticked {
    /// The output as sent (a failed send is the controller's bus fault).
    pub output: Output,
    /// The controller's tick count after it.
    pub ticks: u32,
    /// A job waits for the background task ([`run_job`]).
    pub job_wanted: bool,
}

/// One tick: the controller's output to the stage. The amplifier is on while a plan that
/// passed its checks drives; off (the DAC powered down, the enable line low) with no
/// controller, at rest at 0 V after `stop`, and at the end of a fault's descent (the stage's
/// own reaction, in `OutputStage::send`). `inputs` are the acquisition's (`acquire`), taken
/// by `Controller::tick_acquired`. `None`: no controller, the output off.
pub fn drive<SPI: SpiDevice, EN: OutputPin>(
    slot: &mut Option<Controller>,
    stage: &mut OutputStage<SPI, EN>,
    inputs: Result<Inputs, InputError>,
) -> Option<Ticked> {
    let Some(c) = slot.as_mut() else {
        if !stage.is_safe() {
            let _ = stage.safe();
        }
        return None;
    };
    // At rest at 0 V (stopped, re-armed by `clear`, or a fault's descent over), before the
    // tick: the stage stays off on a tick that sends 0 V from there.
    let at_rest = c.at_rest();
    let mut output = c.tick_acquired(inputs);
    let rest = at_rest && output.volts == 0.0;
    if !rest && c.phase() != Phase::Faulted && stage.is_safe() {
        let _ = stage.enable();
    } else if rest && !stage.is_safe() {
        let _ = stage.safe();
    }
    stage.send(c, &mut output);
    Some(Ticked {
        output,
        ticks: c.ticks(),
        job_wanted: job_wanted(c),
    })
}

/// Whether the controller waits for a background job: a trim's solve, or tracking's slope
/// while driving (the task may be woken again: it then finds no job and returns).
#[cfg(feature = "trim")]
fn job_wanted(c: &Controller) -> bool {
    c.job_pending()
}

#[cfg(not(feature = "trim"))]
fn job_wanted(_: &Controller) -> bool {
    false
}

/// The background job, at low priority: take it from the controller under the lock, solve it
/// outside, give the result back (the next tick applies it). `with` runs a closure on the
/// controller under its lock. Whether there was one.
/// Kept out of line: the job (a 2 KB window) then sits in a frame of its own, not in the
/// frame of the task that runs it, where every request would carry it.
#[cfg(feature = "trim")]
#[inline(never)]
pub fn run_job(mut with: impl FnMut(&mut dyn FnMut(&mut Controller))) -> bool {
    let mut job = None;
    with(&mut |c| job = c.trim_job());
    let Some(job) = &job else { return false };
    let result = job.solve();
    with(&mut |c| c.trim_done(result));
    true
}
