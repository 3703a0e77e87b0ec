//! QEMU's test switches in the tick, in one place: what a QEMU run started with the
//! semihosting argument `dac-bus-fails` or `tick-hangs` ([`crate::chip::asked`]) does, and the
//! tick's stamp of virtual time for `status`. On silicon there is none: each step is empty
//! and costs the tick nothing (the tick task calls them either way: no switch inside it).

use de_resonator::board::port::TickClock;

#[cfg(feature = "qemu")]
use crate::chip;

/// The tick's test switches and their counts.
pub struct TickSwitches {
    /// `tick-hangs`: the tick hangs after this many ticks of driving (the watchdog's test).
    #[cfg(feature = "qemu")]
    hang_after_ticks: Option<u32>,
    /// Ticks a controller has driven.
    #[cfg(feature = "qemu")]
    driven_ticks: u32,
    /// `dac-bus-fails`: the DAC's bus fails from this tick since power-up on (as a scene's
    /// `dac_bus_fails_after_seconds` breaks `host-sim serve`'s).
    #[cfg(feature = "qemu")]
    bus_fails_at_tick: Option<u32>,
    /// Ticks since power-up.
    #[cfg(feature = "qemu")]
    power_up_ticks: u32,
}

impl TickSwitches {
    /// The switches QEMU was started with, at `tick_hz` (each acts two seconds in).
    pub fn asked(tick_hz: f32) -> Self {
        #[cfg(feature = "qemu")]
        {
            let after = 2 * tick_hz as u32;
            TickSwitches {
                hang_after_ticks: chip::asked("tick-hangs").then_some(after),
                driven_ticks: 0,
                bus_fails_at_tick: chip::asked("dac-bus-fails").then_some(after),
                power_up_ticks: 0,
            }
        }
        #[cfg(not(feature = "qemu"))]
        {
            let _ = tick_hz;
            TickSwitches {}
        }
    }

    /// At the tick's start, before its frame: the DAC's bus broken when its tick has come,
    /// and the tick's stamp of virtual time (`None` on silicon: no clock but the cycles).
    #[inline(always)]
    pub fn start(&mut self) -> Option<TickClock> {
        #[cfg(feature = "qemu")]
        {
            let clock = TickClock {
                tick: self.power_up_ticks,
                micros: crate::qemu::clock::micros(),
            };
            if self
                .bus_fails_at_tick
                .is_some_and(|n| self.power_up_ticks >= n)
            {
                crate::qemu::bus::break_dac_bus();
            }
            self.power_up_ticks = self.power_up_ticks.wrapping_add(1);
            Some(clock)
        }
        #[cfg(not(feature = "qemu"))]
        None
    }

    /// After the board's tick (`driving`: a controller ticked): a stuck tick when asked.
    #[inline(always)]
    pub fn after(&mut self, driving: bool) {
        #[cfg(feature = "qemu")]
        if driving {
            self.driven_ticks += 1;
            if self.hang_after_ticks.is_some_and(|n| self.driven_ticks > n) {
                // A stuck tick, for the watchdog to catch.
                loop {
                    cortex_m::asm::nop();
                }
            }
        }
        #[cfg(not(feature = "qemu"))]
        let _ = driving;
    }
}
