//! The link between host-sim and the firmware's link build (`firmware --features link`, under
//! QEMU): each tick the plant's samples in, as the ADC codes the board's front end would give;
//! the tick's output out, as the DAC frame written and what the controller did. One layout,
//! written and read here by both sides.
//!
//! A frame (every number little-endian):
//!
//! | offset | size | what |
//! |---|---|---|
//! | 0 | 2 | magic `DL` |
//! | 2 | 1 | kind: 1 samples (host → board), 2 a tick's output, 3 the boot (board → host) |
//! | 3 | 1 | flags, on a samples frame (tests of the link build; 0 otherwise): bit 0 the DAC's bus fails from this tick on (`BUS_FAILS`); bit 1 an ADC overrun, bit 2 a DMA transfer error stalled the acquisition, re-armed before this tick (`STALL_OVERRUN`, `STALL_TRANSFER`; the codes it lost are not in the frame) |
//! | 4 | 4 | the tick's number (from 0; 0 for the boot), u32 |
//! | 8 | 2 | P, the payload's bytes, u16 (at most `MAX_PAYLOAD`) |
//! | 10 | P | the payload |
//! | 10 + P | 4 | CRC-32 (IEEE 802.3) of every byte before it, u32 |
//!
//! Payloads: samples are the scans' codes as the DMA writes them (u16 each, the fitted
//! channels interleaved in `Channel::ALL` order: `Block::add_scans`); a tick's output is
//! [`Observed`]; the boot is [`Booted`].

use core::fmt::{self, Write as _};

use embedded_hal::digital::OutputPin;
use embedded_hal::spi::{Operation, SpiDevice};

use crate::bytes::{crc32, f32_at, u16_at, u32_at, Put};
use crate::controller::{phase_byte, phase_of_byte};
use crate::controller::{Boot, Controller, Event, EventKind, Phase, EVENT_VALUES};
use crate::drive::PowerMode;
use crate::model::failure::FailureMode;

/// A frame's first two bytes.
pub const MAGIC: [u8; 2] = *b"DL";
/// A frame's bytes before its payload.
pub const HEADER: usize = 10;
/// The longest payload: 512 ADC codes a tick (a front end scanning faster than that at its
/// tick rate cannot run over the link).
pub const MAX_PAYLOAD: usize = 1024;
/// The longest frame.
pub const MAX_FRAME: usize = HEADER + MAX_PAYLOAD + 4;

/// What a frame carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A tick's ADC codes, host → board.
    Samples = 1,
    /// A tick's output, board → host ([`Observed`]).
    Output = 2,
    /// The boot's outcome, board → host ([`Booted`]).
    Boot = 3,
}

impl Kind {
    fn of(byte: u8) -> Option<Kind> {
        match byte {
            1 => Some(Kind::Samples),
            2 => Some(Kind::Output),
            3 => Some(Kind::Boot),
            _ => None,
        }
    }
}

/// A samples frame's flag: the DAC's bus fails from this tick on (the link build's stand-in
/// for a broken bus: QEMU's SPI never fails).
pub const BUS_FAILS: u8 = 1;
/// A samples frame's flags: the acquisition stalled and was re-armed before this tick (the
/// link build's stand-ins for silicon's ADC overrun and DMA transfer error, which QEMU does
/// not emulate), said to the tick's block as the firmware's recovery says it.
pub const STALL_OVERRUN: u8 = 2;
pub const STALL_TRANSFER: u8 = 4;

/// A stall as a samples frame's flag.
pub const fn stall_flag(stall: crate::acquire::Stall) -> u8 {
    match stall {
        crate::acquire::Stall::Overrun => STALL_OVERRUN,
        crate::acquire::Stall::TransferError => STALL_TRANSFER,
    }
}

/// The stall a samples frame's flags say, if any (a transfer error first: the worse).
pub const fn stall_of_flags(flags: u8) -> Option<crate::acquire::Stall> {
    if flags & STALL_TRANSFER != 0 {
        Some(crate::acquire::Stall::TransferError)
    } else if flags & STALL_OVERRUN != 0 {
        Some(crate::acquire::Stall::Overrun)
    } else {
        None
    }
}

/// A frame's header, once its CRC checked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    pub kind: Kind,
    /// `BUS_FAILS`, `STALL_OVERRUN`, `STALL_TRANSFER` on a samples frame; 0 otherwise.
    pub flags: u8,
    /// The tick the frame is for (0 for the boot).
    pub tick: u32,
    pub payload_bytes: usize,
}

/// Why bytes are not a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkError {
    /// The first two bytes are not `MAGIC`: the stream is out of step.
    NoMagic,
    /// A byte of a record holds no value its field can take.
    BadField { offset: usize, value: u8 },
    /// The kind byte is none of `Kind`'s.
    UnknownKind(u8),
    /// The payload's length is over `MAX_PAYLOAD`.
    TooLong(u16),
    /// The CRC does not match the bytes: corrupted on the way.
    BadCrc { stored: u32, computed: u32 },
    /// The payload does not fit the buffer it is written to, or is too short for its kind.
    Size { bytes: usize, needed: usize },
}

impl fmt::Display for LinkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinkError::NoMagic => write!(f, "link frame without its magic `DL`: out of step"),
            LinkError::BadField { offset, value } => {
                write!(
                    f,
                    "link record byte {offset} holds {value}, no value of its field"
                )
            }
            LinkError::UnknownKind(k) => write!(f, "link frame of unknown kind {k}"),
            LinkError::TooLong(n) => {
                write!(f, "link frame of {n} payload bytes, over {MAX_PAYLOAD}")
            }
            LinkError::BadCrc { stored, computed } => write!(
                f,
                "link frame CRC {stored:#010x} does not match its bytes ({computed:#010x})"
            ),
            LinkError::Size { bytes, needed } => {
                write!(f, "link payload of {bytes} bytes where {needed} are needed")
            }
        }
    }
}

impl core::error::Error for LinkError {}

/// Write a frame of `kind` with `flags` for `tick` into `out`, its payload written by
/// `payload` into the slice it is given (returning its length): the frame's length.
pub fn write_frame(
    out: &mut [u8],
    (kind, flags): (Kind, u8),
    tick: u32,
    payload: impl FnOnce(&mut [u8]) -> Result<usize, LinkError>,
) -> Result<usize, LinkError> {
    let needed = HEADER + 4;
    let room = out.len().saturating_sub(needed).min(MAX_PAYLOAD);
    let bytes = out.len();
    let body = out
        .get_mut(HEADER..HEADER + room)
        .ok_or(LinkError::Size { bytes, needed })?;
    let n = payload(body)?;
    if n > room {
        return Err(LinkError::Size {
            bytes: room,
            needed: n,
        });
    }
    let end = HEADER + n;
    if let Some(head) = out.get_mut(..HEADER) {
        head.copy_from_slice(&header_bytes(kind, flags, tick, n));
    }
    let crc = crc32(out.get(..end).unwrap_or(&[]));
    let tail = out.get_mut(end..end + 4).ok_or(LinkError::Size {
        bytes,
        needed: end + 4,
    })?;
    tail.copy_from_slice(&crc.to_le_bytes());
    Ok(end + 4)
}

fn header_bytes(kind: Kind, flags: u8, tick: u32, payload_bytes: usize) -> [u8; HEADER] {
    let [m0, m1] = MAGIC;
    let [t0, t1, t2, t3] = tick.to_le_bytes();
    let [p0, p1] = (payload_bytes as u16).to_le_bytes();
    [m0, m1, kind as u8, flags, t0, t1, t2, t3, p0, p1]
}

/// A frame's whole length from its first `HEADER` bytes (the rest to read): its magic,
/// kind and payload length checked.
pub fn frame_bytes(header: &[u8]) -> Result<usize, LinkError> {
    let head = header.get(..HEADER).ok_or(LinkError::Size {
        bytes: header.len(),
        needed: HEADER,
    })?;
    if head.get(..2) != Some(&MAGIC[..]) {
        return Err(LinkError::NoMagic);
    }
    let kind = head.get(2).copied().unwrap_or(0);
    if Kind::of(kind).is_none() {
        return Err(LinkError::UnknownKind(kind));
    }
    let n = u16_at(head, 8);
    if usize::from(n) > MAX_PAYLOAD {
        return Err(LinkError::TooLong(n));
    }
    Ok(HEADER + usize::from(n) + 4)
}

/// A whole frame (`frame_bytes` long): its header and payload, once its CRC checked.
pub fn parse(frame: &[u8]) -> Result<(Header, &[u8]), LinkError> {
    let length = frame_bytes(frame)?;
    if frame.len() != length {
        return Err(LinkError::Size {
            bytes: frame.len(),
            needed: length,
        });
    }
    let end = length - 4;
    let body = frame.get(..end).unwrap_or(&[]);
    let (stored, computed) = (u32_at(frame, end), crc32(body));
    if stored != computed {
        return Err(LinkError::BadCrc { stored, computed });
    }
    let byte = |i: usize| frame.get(i).copied().unwrap_or(0);
    let header = Header {
        kind: Kind::of(byte(2)).ok_or(LinkError::UnknownKind(byte(2)))?,
        flags: byte(3),
        tick: u32_at(frame, 4),
        payload_bytes: end - HEADER,
    };
    Ok((header, frame.get(HEADER..end).unwrap_or(&[])))
}

/// A samples payload: `codes` as u16s.
pub fn write_codes(codes: &[u16], out: &mut [u8]) -> Result<usize, LinkError> {
    let needed = 2 * codes.len();
    let bytes = out.len();
    let slots = out
        .get_mut(..needed)
        .ok_or(LinkError::Size { bytes, needed })?;
    for (pair, code) in slots.chunks_exact_mut(2).zip(codes) {
        pair.copy_from_slice(&code.to_le_bytes());
    }
    Ok(needed)
}

/// The codes of a samples payload, in order (a trailing odd byte is ignored).
pub fn codes(payload: &[u8]) -> impl Iterator<Item = u16> + '_ {
    payload.chunks_exact(2).map(|pair| {
        u16::from_le_bytes([
            pair.first().copied().unwrap_or(0),
            pair.get(1).copied().unwrap_or(0),
        ])
    })
}

/// A tick's output as the board saw it: the DAC frame written, the enable line, what the
/// controller said, and what host-sim's report reads of the controller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observed {
    /// The code of the last DAC frame written.
    pub dac_code: u16,
    /// Whether that frame powered the DAC (normal mode) rather than down.
    pub dac_on: bool,
    /// The amplifier's enable line.
    pub enable: bool,
    /// What the controller said, as a kind (its words follow in the payload).
    pub said: Option<EventKind>,
    /// Its numbers (`Event::values`: `EventKind::value_names` says which; NaN past them).
    pub said_values: [f32; EVENT_VALUES],
    /// The controller's phase (`None`: no controller).
    pub phase: Option<Phase>,
    /// The plan's bias, V (NaN: no controller).
    pub bias_volts: f32,
    /// The target in force, Hz (NaN: no controller).
    pub target_hz: f32,
    /// The AC drive's phase step a tick (`None`: no AC).
    pub ac_phase_step: Option<u32>,
    /// Tracking's last cycle's natural frequency, Hz (NaN: none). Tracking's only: a trim's
    /// ring's comes with its `Event::Trimmed` (the stream's pair is either, `resonance`).
    pub tracked_hz: f32,
    /// Tracking's last cycle's quality factor (NaN: none).
    pub quality_factor: f32,
    /// The stretch from the capacitance (NaN: none).
    pub sensed_stretch: f32,
    /// Its standard error (NaN: none).
    pub sensed_sigma: f32,
}

/// The words sent for an event: a fault's own (its kind says which descent), any other
/// event's (`Event`'s wording).
pub struct Words<'a>(pub &'a Event);

impl fmt::Display for Words<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Event::Fault(fault) => write!(f, "{fault}"),
            event => write!(f, "{event}"),
        }
    }
}

/// The fixed part of an output payload; the words of what was said follow. Its layout: DAC
/// code u16; flags u8 (bit 0 the DAC on, bit 1 the enable line); what was said u8
/// (`EventKind` as u8, 0 nothing); phase u8 (its place in `Phase`'s order, 0xFF none); AC on
/// u8; 2 zero bytes; the AC's phase step u32; bias V, tracked Hz, Q, sensed stretch and its
/// σ, target Hz, f32 each; the event's `EVENT_VALUES` numbers, f32 each.
pub const OBSERVED_BYTES: usize = 36 + 4 * EVENT_VALUES;

impl Observed {
    /// The board after a tick: the DAC frame last written (`dac_code`, `dac_on`), the enable
    /// line, the controller (none: nothing driven) and its event.
    pub fn of(
        dac_code: u16,
        dac_on: bool,
        enable: bool,
        controller: Option<&Controller>,
        event: Option<&Event>,
    ) -> Self {
        let plan = controller.map(|c| c.plan());
        let none = (f32::NAN, f32::NAN);
        let (tracked_hz, quality_factor) =
            controller.and_then(Controller::tracking).unwrap_or(none);
        let (sensed_stretch, sensed_sigma) =
            controller.and_then(Controller::sensing).unwrap_or(none);
        Observed {
            dac_code,
            dac_on,
            enable,
            said: event.map(Event::kind),
            said_values: event.map_or([f32::NAN; EVENT_VALUES], Event::values),
            phase: controller.map(|c| c.phase()),
            bias_volts: plan.map_or(f32::NAN, |p| p.bias_volts),
            target_hz: controller.map_or(f32::NAN, |c| c.settings().target_hz),
            ac_phase_step: plan
                .filter(|p| p.ac_tick.is_some())
                .map(|p| p.ac_phase_step),
            tracked_hz,
            quality_factor,
            sensed_stretch,
            sensed_sigma,
        }
    }

    /// The payload: this record, then the words of `event` (cut at the buffer's end).
    pub fn write(&self, event: Option<&Event>, out: &mut [u8]) -> Result<usize, LinkError> {
        let bytes = out.len();
        let fixed = out.get_mut(..OBSERVED_BYTES).ok_or(LinkError::Size {
            bytes,
            needed: OBSERVED_BYTES,
        })?;
        let flags = u8::from(self.dac_on) | u8::from(self.enable) << 1;
        let phase = phase_byte(self.phase);
        let mut put = Put(fixed, 0);
        put.bytes(&self.dac_code.to_le_bytes());
        put.bytes(&[
            flags,
            self.said.map_or(0, |k| k as u8),
            phase,
            u8::from(self.ac_phase_step.is_some()),
            0,
            0,
        ]);
        put.bytes(&self.ac_phase_step.unwrap_or(0).to_le_bytes());
        for x in [
            self.bias_volts,
            self.tracked_hz,
            self.quality_factor,
            self.sensed_stretch,
            self.sensed_sigma,
            self.target_hz,
        ]
        .into_iter()
        .chain(self.said_values)
        {
            put.bytes(&x.to_le_bytes());
        }
        let words = out.get_mut(OBSERVED_BYTES..).unwrap_or(&mut []);
        let mut cursor = Put(words, 0);
        if let Some(event) = event {
            let _ = write!(cursor, "{}", Words(event));
        }
        Ok(OBSERVED_BYTES + cursor.1)
    }

    /// A tick's output payload: the record and the words said (empty when nothing was).
    pub fn read(payload: &[u8]) -> Result<(Observed, &[u8]), LinkError> {
        if payload.len() < OBSERVED_BYTES {
            return Err(LinkError::Size {
                bytes: payload.len(),
                needed: OBSERVED_BYTES,
            });
        }
        let byte = |i: usize| payload.get(i).copied().unwrap_or(0);
        let bad = |offset: usize| LinkError::BadField {
            offset,
            value: byte(offset),
        };
        let flags = byte(2);
        let said = match byte(3) {
            0 => None,
            n => Some(EventKind::of(n).ok_or(bad(3))?),
        };
        let mut said_values = [f32::NAN; EVENT_VALUES];
        for (k, value) in said_values.iter_mut().enumerate() {
            *value = f32_at(payload, 36 + 4 * k);
        }
        let phase = phase_of_byte(byte(4)).ok_or(bad(4))?;
        let observed = Observed {
            dac_code: u16_at(payload, 0),
            dac_on: flags & 1 != 0,
            enable: flags & 2 != 0,
            said,
            said_values,
            phase,
            ac_phase_step: (byte(5) != 0).then(|| u32_at(payload, 8)),
            bias_volts: f32_at(payload, 12),
            tracked_hz: f32_at(payload, 16),
            quality_factor: f32_at(payload, 20),
            sensed_stretch: f32_at(payload, 24),
            sensed_sigma: f32_at(payload, 28),
            target_hz: f32_at(payload, 32),
        };
        Ok((observed, payload.get(OBSERVED_BYTES..).unwrap_or(&[])))
    }
}

/// The boot's outcome, as host-sim's report reads it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Booted {
    /// Whether a controller drives (otherwise the words are the refusal).
    pub driving: bool,
    /// The boot's bias, V (NaN when refused).
    pub bias_volts: f32,
    /// The boot's cap, V (NaN when refused).
    pub max_volts: f32,
    /// The device's limit on its loading branch: its mode and stretch.
    pub limit: Option<(FailureMode, f32)>,
}

/// The fixed part of a boot payload; the refusal's words follow. Its layout: driving u8; the
/// limit's mode u8 (its place in `FailureMode::ALL`, 0xFF none); 2 zero bytes; bias V, cap
/// V, the limit's stretch, f32 each.
pub const BOOTED_BYTES: usize = 16;

impl Booted {
    /// The boot's outcome: what its checks found (`None`: refused).
    pub fn of(boot: Option<&Boot>) -> Self {
        Booted {
            driving: boot.is_some(),
            bias_volts: boot.map_or(f32::NAN, |b| b.bias_volts),
            max_volts: boot.map_or(f32::NAN, |b| b.max_volts),
            limit: boot.and_then(|b| b.limit).map(|l| (l.mode, l.at.stretch)),
        }
    }

    /// The payload: this record, then `refusal`'s words.
    pub fn write(&self, refusal: &str, out: &mut [u8]) -> Result<usize, LinkError> {
        let bytes = out.len();
        let fixed = out.get_mut(..BOOTED_BYTES).ok_or(LinkError::Size {
            bytes,
            needed: BOOTED_BYTES,
        })?;
        let mode = self
            .limit
            .and_then(|(m, _)| FailureMode::ALL.iter().position(|&n| n == m))
            .map_or(0xFF, |i| i as u8);
        let mut put = Put(fixed, 0);
        put.bytes(&[u8::from(self.driving), mode, 0, 0]);
        for x in [
            self.bias_volts,
            self.max_volts,
            self.limit.map_or(f32::NAN, |(_, s)| s),
        ] {
            put.bytes(&x.to_le_bytes());
        }
        let mut cursor = Put(out.get_mut(BOOTED_BYTES..).unwrap_or(&mut []), 0);
        let _ = cursor.write_str(refusal);
        Ok(BOOTED_BYTES + cursor.1)
    }

    /// A boot payload: the record and the refusal's words.
    pub fn read(payload: &[u8]) -> Result<(Booted, &[u8]), LinkError> {
        if payload.len() < BOOTED_BYTES {
            return Err(LinkError::Size {
                bytes: payload.len(),
                needed: BOOTED_BYTES,
            });
        }
        let byte = |i: usize| payload.get(i).copied().unwrap_or(0);
        let limit = match byte(1) {
            0xFF => None,
            i => Some((
                *FailureMode::ALL
                    .get(usize::from(i))
                    .ok_or(LinkError::BadField {
                        offset: 1,
                        value: i,
                    })?,
                f32_at(payload, 12),
            )),
        };
        Ok((
            Booted {
                driving: byte(0) != 0,
                bias_volts: f32_at(payload, 4),
                max_volts: f32_at(payload, 8),
                limit,
            },
            payload.get(BOOTED_BYTES..).unwrap_or(&[]),
        ))
    }
}

/// The output stage's wires as the link reports them: an SPI device or an output pin that
/// passes everything through and keeps what was last written (the firmware's link build
/// wraps its DAC bus and enable pin in it).
pub struct Tap<T> {
    inner: T,
    /// The last DAC frame written whole: its code, and whether it powered the DAC on.
    pub dac: (u16, bool),
    /// The pin's level as last set.
    pub high: bool,
}

impl<T> Tap<T> {
    /// `inner` tapped, nothing written yet (the DAC at code 0 and down, the pin low).
    pub fn new(inner: T) -> Self {
        Tap {
            inner,
            dac: (0, false),
            high: false,
        }
    }
}

/// A DAC8551 frame's code, and whether it powers the DAC on (`drive::frame`'s layout).
pub fn dac_frame(bytes: &[u8]) -> Option<(u16, bool)> {
    match *bytes {
        [mode, high, low] => Some((
            u16::from_be_bytes([high, low]),
            mode & 0b11 == PowerMode::Normal as u8,
        )),
        _ => None,
    }
}

impl<T: embedded_hal::spi::ErrorType> embedded_hal::spi::ErrorType for Tap<T> {
    type Error = T::Error;
}

impl<T: SpiDevice> SpiDevice for Tap<T> {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), T::Error> {
        self.inner.transaction(operations)?;
        for op in operations.iter() {
            if let Operation::Write(bytes) = op {
                if let Some(dac) = dac_frame(bytes) {
                    self.dac = dac;
                }
            }
        }
        Ok(())
    }
}

impl<T: embedded_hal::digital::ErrorType> embedded_hal::digital::ErrorType for Tap<T> {
    type Error = T::Error;
}

impl<T: OutputPin> OutputPin for Tap<T> {
    fn set_low(&mut self) -> Result<(), T::Error> {
        self.inner.set_low()?;
        self.high = false;
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), T::Error> {
        self.inner.set_high()?;
        self.high = true;
        Ok(())
    }
}
