//! The link build (under QEMU only): host-sim's plant in, the tick's output out, in the
//! core's frames (`de_resonator::wire::link`). The frames go through two files QEMU's
//! semihosting opens on the host, in its working folder (`samples`, `output`: host-sim's
//! pipes), a frame in two reads (its header, then the rest); a byte on USART3 rings each
//! tick's samples in. QEMU's USART takes a byte a main-loop turn (50 to 130 µs,
//! BENCHMARKS.md): the frames would take milliseconds a tick over it, the bell takes one. A samples frame's codes go into the
//! tick's block, where silicon's DMA puts its buffers, and pend the tick: the link paces the
//! tick, so the plant's clock is the simulation's.

use de_resonator::Event;

#[cfg(feature = "link")]
pub use transport::{LinkIn, LinkOut};

/// What a tick hands the link's reply task: the DAC frame last written (its code, and
/// whether it powered the DAC), the enable line, the controller's event, and whether a job
/// waits.
#[derive(Clone, Copy, Debug)]
pub struct TickDone {
    pub dac: (u16, bool),
    pub enable: bool,
    pub event: Option<Event>,
    pub job: bool,
}

/// QEMU's exit status when the link build cannot open its pipes (not started by host-sim),
/// when host-sim has gone, and when a frame is not one.
pub const LINK_OPEN: i32 = 110;
pub const LINK_GONE: i32 = 111;
pub const LINK_FRAME: i32 = 112;

/// Ticks queued to the reply task (one at a time, host-sim waits for each; two so that the
/// tick never finds the queue full while the task finishes the last).
pub const REPLIES: usize = 2;

/// The link build's ends, none in other builds (the app's resources name their types).
#[cfg(not(feature = "link"))]
pub enum LinkIn {}
#[cfg(not(feature = "link"))]
pub enum LinkOut {}

#[cfg(feature = "link")]
mod transport {
    use super::{LINK_FRAME, LINK_GONE, LINK_OPEN};
    use de_resonator::acquire::{Block, FrontEnd};
    use de_resonator::wire::link::{self, Kind, BUS_FAILS, HEADER, MAX_FRAME, MAX_PAYLOAD};
    use embedded_hal_nb::serial::Read as _;
    use semihosting::fs::File;
    use semihosting::io::{Read as _, Write as _};
    use stm32f4xx_hal::pac::USART3;
    use stm32f4xx_hal::serial::Rx;

    /// The samples side: each ring of the bell, a frame read whole, its codes into the block.
    pub struct LinkIn {
        bell: Rx<USART3>,
        samples: File,
        bytes: [u8; MAX_FRAME],
        codes: [u16; MAX_PAYLOAD / 2],
        front_end: FrontEnd,
    }

    impl LinkIn {
        /// The bell, and the samples file opened (it waits for host-sim to open its end; no
        /// file: the run ends, `LINK_OPEN`).
        pub fn open(bell: Rx<USART3>, front_end: FrontEnd) -> Self {
            let Ok(samples) = File::open(c"samples") else {
                crate::runtime::exit(LINK_OPEN)
            };
            LinkIn {
                bell,
                samples,
                bytes: [0; MAX_FRAME],
                codes: [0; MAX_PAYLOAD / 2],
                front_end,
            }
        }

        /// The rings waiting: each one's samples frame added to the block by `add`. Whether a
        /// tick's samples arrived. host-sim gone (the pipe's end) or a frame that is not a
        /// samples frame ends the run (`LINK_GONE`, `LINK_FRAME`): QEMU's exit status says it.
        pub fn read(&mut self, add: &mut impl FnMut(&mut dyn FnMut(&mut Block))) -> bool {
            let mut arrived = false;
            while self.bell.read().is_ok() {
                let (header, payload) = match read_frame(&mut self.samples, &mut self.bytes) {
                    Ok(frame) => frame,
                    Err(code) => crate::runtime::exit(code),
                };
                if header.flags & BUS_FAILS != 0 {
                    crate::qemu::bus::break_dac_bus();
                }
                let mut count = 0;
                for (slot, code) in self.codes.iter_mut().zip(link::codes(payload)) {
                    *slot = code;
                    count += 1;
                }
                let codes = self.codes.get(..count).unwrap_or(&[]);
                let front_end = &self.front_end;
                // host-sim's injected stall, said to the block as silicon's recovery says it
                // once it has re-armed the ADC and its DMA (`analog`).
                let stall = link::stall_of_flags(header.flags);
                add(&mut |block| {
                    block.add_scans(front_end, codes);
                    if let Some(why) = stall {
                        block.stalled(why);
                    }
                });
                arrived = true;
            }
            arrived
        }
    }

    /// One samples frame from `file` into `bytes`: its header and payload, or the exit code
    /// that says why not.
    fn read_frame<'a>(
        file: &mut File,
        bytes: &'a mut [u8; MAX_FRAME],
    ) -> Result<(link::Header, &'a [u8]), i32> {
        read_exact(file, bytes.get_mut(..HEADER).ok_or(LINK_FRAME)?).ok_or(LINK_GONE)?;
        let end = link::frame_bytes(bytes.as_slice()).map_err(|_| LINK_FRAME)?;
        read_exact(file, bytes.get_mut(HEADER..end).ok_or(LINK_FRAME)?).ok_or(LINK_GONE)?;
        match link::parse(bytes.get(..end).ok_or(LINK_FRAME)?) {
            Ok((header, payload)) if header.kind == Kind::Samples => Ok((header, payload)),
            _ => Err(LINK_FRAME),
        }
    }

    fn read_exact(file: &mut File, mut buf: &mut [u8]) -> Option<()> {
        while !buf.is_empty() {
            match file.read(buf) {
                Ok(0) | Err(_) => return None,
                Ok(n) => buf = buf.get_mut(n..)?,
            }
        }
        Some(())
    }

    /// The output side: a frame at a time, written whole.
    pub struct LinkOut {
        output: File,
        frame: [u8; MAX_FRAME],
    }

    impl LinkOut {
        /// The output file opened (after the samples file: host-sim opens them in that order).
        pub fn open() -> Self {
            let Ok(output) = File::create(c"output") else {
                crate::runtime::exit(LINK_OPEN)
            };
            LinkOut {
                output,
                frame: [0; MAX_FRAME],
            }
        }

        /// A frame of `kind` for `tick`, its payload written by `payload`. A frame that cannot
        /// be made or sent ends the run (`LINK_FRAME`, `LINK_GONE`).
        pub fn send(
            &mut self,
            kind: Kind,
            tick: u32,
            payload: impl FnOnce(&mut [u8]) -> Result<usize, link::LinkError>,
        ) {
            let Ok(n) = link::write_frame(&mut self.frame, (kind, 0), tick, payload) else {
                crate::runtime::exit(LINK_FRAME)
            };
            if self
                .output
                .write_all(self.frame.get(..n).unwrap_or(&[]))
                .is_err()
            {
                crate::runtime::exit(LINK_GONE)
            }
        }
    }
}
