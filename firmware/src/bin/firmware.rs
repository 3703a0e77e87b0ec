//! The firmware: check everything, tune the reference device to its target, ramp, drive,
//! and (under QEMU) stop after two seconds with status 0; status 1 if it refused to drive.
#![no_std]
#![no_main]

use de_resonator::{Controller, Dac8551, DacCode, Event, Fault};
use de_resonator_firmware::{amplifier, device, exit, settings, RecordingBus, TABLE};

/// Ticks run under QEMU (2 s at 1 kHz).
const RUN_TICKS: u32 = 2000;

#[cortex_m_rt::entry]
fn main() -> ! {
    let mut dac = Dac8551::new(RecordingBus::new(None));
    let settings = settings();
    defmt::info!(
        "de-resonator: target {=f32} Hz, margin {=f32}, table {=usize} bytes",
        settings.target_hz,
        settings.margin,
        TABLE.len()
    );
    let started = amplifier()
        .map_err(Fault::Amplifier)
        .and_then(|amp| Controller::start(device(), TABLE, amp, settings));
    let (mut controller, boot) = match started {
        Ok(ok) => ok,
        Err(fault) => {
            defmt::error!("refusing to drive: {}", fault);
            let _ = dac.power_down();
            exit(1)
        }
    };
    defmt::info!(
        "limit {} at {=f32} V; commands stay at or below {=f32} V",
        boot.limit_mode,
        boot.limit_volts,
        boot.max_volts
    );
    defmt::info!(
        "bias {=f32} V by direct solve, {=f32} V from the table",
        boot.bias_volts,
        boot.table_volts
    );
    defmt::info!(
        "plan checked in the model: {=u32} ticks, stretch {=f32} .. {=f32}",
        boot.plan_ticks,
        boot.plan_stretch.0,
        boot.plan_stretch.1
    );
    let mut highest = DacCode(0);
    for _ in 0..RUN_TICKS {
        let out = controller.tick(None);
        highest = highest.max(out.code);
        if dac.write(out.code).is_err() {
            controller.fault(Fault::Bus);
            defmt::error!("DAC bus error: 0 V");
            let _ = dac.power_down();
            exit(3)
        }
        match out.event {
            Some(Event::AtBias { volts }) => {
                defmt::info!("tick {=u32}: at bias, {=f32} V", controller.ticks(), volts)
            }
            Some(Event::DriveOn) => defmt::info!("tick {=u32}: AC drive on", controller.ticks()),
            Some(Event::Fault(fault)) => {
                defmt::error!("tick {=u32}: {}", controller.ticks(), fault);
                let _ = dac.power_down();
                exit(2)
            }
            None => {}
        }
    }
    let _ = dac.power_down();
    let bus = dac.release();
    defmt::info!(
        "done: {=u32} ticks, {=u32} frames, highest code {=u16}, last frame {=[u8]:#04x}",
        controller.ticks(),
        bus.frames,
        highest.0,
        bus.last
    );
    exit(0)
}
