//! The firmware: check what its features carry, tune the reference device to its target,
//! ramp, drive, and (under QEMU) stop after two seconds with status 0; status 1 if it
//! refused to drive, 2 on a fault while driving, 3 on a DAC bus error.
//!
//! Features choose the boot checks (README, Firmware): the table alone; `solver` adds the
//! direct solve on the chip; `dynamics` runs the plan through the model; `defmt` logs.
#![no_std]
#![no_main]

use de_resonator::{Boot, Controller, Dac8551, DacCode, Event, Fault, Inputs, OutputStage};
use de_resonator_firmware::{amplifier, device, exit, settings, EnableLine, RecordingBus, TABLE};

/// Ticks run under QEMU (2 s at 1 kHz).
const RUN_TICKS: u32 = 2000;

/// The boot stages this build carries.
fn boot() -> Result<(Controller, Boot), Fault> {
    let amp = amplifier().map_err(Fault::Amplifier)?;
    let started = Controller::from_table(device(), TABLE, amp, settings());
    #[cfg(feature = "solver")]
    let started = started.and_then(|(c, boot)| c.cross_check(boot));
    #[cfg(feature = "dynamics")]
    let started = started.and_then(|(c, boot)| c.check_plan(boot));
    started
}

#[cortex_m_rt::entry]
fn main() -> ! {
    // The output stage: the DAC and the amplifier-enable line, safe until the boot passes.
    let mut stage = OutputStage::new(Dac8551::new(RecordingBus::new(None)), EnableLine::default());
    let _ = stage.safe();
    #[cfg(feature = "defmt")]
    defmt::info!(
        "de-resonator: target {=f32} Hz, margin {=f32}, table {=usize} bytes",
        settings().target_hz,
        settings().margin,
        TABLE.len()
    );
    let (mut controller, boot) = match boot() {
        Ok(ok) => ok,
        Err(fault) => {
            #[cfg(feature = "defmt")]
            defmt::error!("refusing to drive: {}", fault);
            let _ = fault;
            exit(1)
        }
    };
    let _ = stage.enable();
    #[cfg(feature = "defmt")]
    log_boot(&boot);
    let _ = boot;
    let mut highest = DacCode(0);
    for _ in 0..RUN_TICKS {
        let out = controller.tick(Inputs::NONE);
        highest = highest.max(out.code);
        let out = stage.send(&mut controller, out);
        match out.event {
            #[cfg(feature = "defmt")]
            Some(Event::AtBias { volts }) => {
                defmt::info!("tick {=u32}: at bias, {=f32} V", controller.ticks(), volts)
            }
            #[cfg(feature = "defmt")]
            Some(Event::DriveOn) => defmt::info!("tick {=u32}: AC drive on", controller.ticks()),
            Some(Event::Fault(fault)) => {
                #[cfg(feature = "defmt")]
                defmt::error!("tick {=u32}: {}, 0 V", controller.ticks(), fault);
                let _ = fault;
                exit(2)
            }
            _ => {}
        }
    }
    let _ = stage.safe();
    let (dac, _) = stage.release();
    let bus = dac.release();
    #[cfg(feature = "defmt")]
    {
        defmt::info!(
            "done: {=u32} ticks, {=u32} frames, highest code {=u16}, last frame {=[u8]:#04x}",
            controller.ticks(),
            bus.frames,
            highest.0,
            bus.last
        );
    }
    let _ = (bus, highest);
    exit(0)
}

#[cfg(feature = "defmt")]
fn log_boot(boot: &Boot) {
    if let Some(limit) = boot.limit {
        defmt::info!(
            "limit {} at {=f32} V; commands stay at or below {=f32} V",
            limit.mode,
            limit.at.volts,
            boot.max_volts
        );
        defmt::info!(
            "bias {=f32} V by direct solve, {=f32} V from the table",
            boot.bias_volts,
            boot.table_volts
        );
    } else {
        defmt::info!(
            "bias {=f32} V from the table; commands stay at or below {=f32} V",
            boot.bias_volts,
            boot.max_volts
        );
    }
    if let Some((low, high)) = boot.plan_stretch {
        defmt::info!(
            "plan checked in the model: {=u32} ticks, stretch {=f32} .. {=f32}",
            boot.plan_ticks,
            low,
            high
        );
    }
}
