//! The telemetry stream: a fixed record of what the board does, every `n` ticks, framed so a
//! receiver finds the next record after a lost byte and counts the records it missed. One
//! layout, written by the board (the firmware, host-sim's virtual board) and read by host-sim
//! `console --record`. The command port's `stream <hz>` / `stream off` start and stop it
//! ([`rate`]); the records go out on a port of their own, so the command port stays a line
//! protocol.
//!
//! The tick takes a [`Record`] ([`Record::of`]: a copy of numbers, no encoding); the frame
//! ([`Record::frame`]: CRC-32 and COBS) is made outside the tick.
//!
//! A record ([`RECORD_BYTES`], every number little-endian; NaN: not measured, or nothing):
//!
//! | offset | size | what |
//! |---|---|---|
//! | 0 | 1 | layout version, [`VERSION`] |
//! | 1 | 1 | flags: bit 0 the amplifier's enable line high |
//! | 2 | 1 | the controller's phase (its place in `Phase`'s order; 0xFF: no controller) |
//! | 3 | 1 | the latched fault (`Fault::number`; 0: none) |
//! | 4 | 4 | sequence: records sent since boot, u32 (a gap is records lost) |
//! | 8 | 4 | the board's tick since boot, u32 |
//! | 12 | 4 | the voltage commanded, V, f32 |
//! | 16 | 2 | the DAC code sent, u16 |
//! | 18 | 2 | zero |
//! | 20 | 4 | the cap in force, V |
//! | 24 | 4 | the stretch sample (the displacement sensor) |
//! | 28 | 4 | the amplifier's current, A (the tick's mean) |
//! | 32 | 4 | the amplifier's monitor, V |
//! | 36 | 4 | λ from the capacitance (the probe's last window) |
//! | 40 | 4 | its standard error |
//! | 44 | 4 | the measured natural frequency, Hz: tracking's, else the last trim window's ring |
//! | 48 | 4 | its quality factor (the ring's: from its decay) |
//! | 52 | 4 | the leakage watch's resistance, Ω |
//! | 56 | 4 | the plan's bias, V |
//! | 60 | 4 | CRC-32 (IEEE 802.3) of bytes 0–59 |
//!
//! On the wire each record is COBS-encoded (no zero byte inside) and followed by one zero
//! byte: [`FRAME_BYTES`] at most.

use core::fmt;

use crate::acquire::Inputs;
use crate::bytes::{crc32, f32_at, u16_at, u32_at, Put};
use crate::controller::{phase_byte, phase_of_byte, Controller, Fault, Phase};

/// The record layout's version (byte 0).
pub const VERSION: u8 = 1;
/// A record's bytes, its CRC included.
pub const RECORD_BYTES: usize = 64;
/// A framed record's bytes at most: COBS's overhead and the zero that ends it.
pub const FRAME_BYTES: usize = cobs::max_encoding_length(RECORD_BYTES) + 1;

/// One record: what the board did at a tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// Records sent since boot before this one (wrapping).
    pub sequence: u32,
    /// The board's tick since boot.
    pub tick: u32,
    /// The voltage commanded, V.
    pub volts: f32,
    pub dac_code: u16,
    /// The amplifier's enable line.
    pub enabled: bool,
    /// The controller's phase (`None`: no controller runs).
    pub phase: Option<Phase>,
    /// The latched fault's number (`Fault::number`), if any.
    pub fault: Option<u8>,
    /// The cap in force, V (NaN: no controller).
    pub max_volts: f32,
    /// The tick's readings of the analog inputs, in units.
    pub inputs: Inputs,
    /// λ from the capacitance and its standard error (the probe).
    pub sensed: Option<(f32, f32)>,
    /// The measured natural frequency (Hz) and quality factor (`Controller::resonance`).
    pub resonance: Option<(f32, f32)>,
    /// The leakage watch's resistance, Ω.
    pub leakage_ohms: Option<f32>,
    /// The plan's bias, V (NaN: no controller).
    pub bias_volts: f32,
}

/// Why bytes between two zeros are not a record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StreamError {
    /// Not a COBS frame, or not a record's length: bytes were lost or the stream joined
    /// mid-frame.
    Frame,
    /// A layout this reader does not know.
    Version(u8),
    /// The CRC does not match: bytes were changed on the way.
    Crc,
    /// A byte holds no value of its field.
    Field { offset: u8 },
}

impl fmt::Display for StreamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StreamError::Frame => write!(
                f,
                "a stream frame of the wrong length: bytes were lost on the way"
            ),
            StreamError::Version(v) => write!(
                f,
                "a stream record of layout {v}; this reader knows {VERSION}"
            ),
            StreamError::Crc => write!(f, "a stream record whose CRC does not match"),
            StreamError::Field { offset } => {
                write!(f, "a stream record whose byte {offset} holds no value")
            }
        }
    }
}

impl core::error::Error for StreamError {}

/// `Some` for a number, `None` for NaN (the layout's "nothing").
fn number(x: f32) -> Option<f32> {
    (!x.is_nan()).then_some(x)
}

impl Record {
    /// The board after tick `tick`: the enable line, the controller (none: nothing driven,
    /// 0 V) and the inputs the tick read. A copy of the controller's numbers, read outside
    /// the tick (the firmware's idle loop, under the controller's lock).
    pub fn of(
        (sequence, tick): (u32, u32),
        enabled: bool,
        controller: Option<&Controller>,
        inputs: &Inputs,
    ) -> Self {
        Record {
            sequence,
            tick,
            volts: controller.map_or(0.0, Controller::last_volts),
            dac_code: controller.map_or(0, |c| c.last_code().0),
            enabled,
            phase: controller.map(Controller::phase),
            fault: controller
                .and_then(Controller::latched_fault)
                .as_ref()
                .map(Fault::number),
            max_volts: controller.map_or(f32::NAN, Controller::max_volts),
            inputs: *inputs,
            sensed: controller.and_then(Controller::sensing),
            resonance: controller.and_then(Controller::resonance),
            leakage_ohms: controller.and_then(Controller::leakage_ohms),
            bias_volts: controller.map_or(f32::NAN, |c| c.plan().bias_volts),
        }
    }

    /// The record's bytes, CRC last.
    pub fn to_bytes(&self) -> [u8; RECORD_BYTES] {
        let mut out = [0u8; RECORD_BYTES];
        let mut put = Put(&mut out, 0);
        put.bytes(&[
            VERSION,
            u8::from(self.enabled),
            phase_byte(self.phase),
            self.fault.unwrap_or(0),
        ]);
        put.bytes(&self.sequence.to_le_bytes());
        put.bytes(&self.tick.to_le_bytes());
        put.bytes(&self.volts.to_le_bytes());
        put.bytes(&self.dac_code.to_le_bytes());
        put.bytes(&[0, 0]);
        let pair = |p: Option<(f32, f32)>| p.map_or((f32::NAN, f32::NAN), |(a, b)| (a, b));
        let (sensed, sigma) = pair(self.sensed);
        let (natural_hz, quality) = pair(self.resonance);
        let none = f32::NAN;
        for x in [
            self.max_volts,
            self.inputs.stretch.unwrap_or(none),
            self.inputs.current_amps.unwrap_or(none),
            self.inputs.amplifier_volts.unwrap_or(none),
            sensed,
            sigma,
            natural_hz,
            quality,
            self.leakage_ohms.unwrap_or(none),
            self.bias_volts,
        ] {
            put.bytes(&x.to_le_bytes());
        }
        let crc = crc32(out.get(..RECORD_BYTES - 4).unwrap_or(&[]));
        if let Some(tail) = out.get_mut(RECORD_BYTES - 4..) {
            tail.copy_from_slice(&crc.to_le_bytes());
        }
        out
    }

    /// A record from its bytes, its version, CRC and fields checked.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, StreamError> {
        if bytes.len() != RECORD_BYTES {
            return Err(StreamError::Frame);
        }
        let byte = |i: usize| bytes.get(i).copied().unwrap_or(0);
        if byte(0) != VERSION {
            return Err(StreamError::Version(byte(0)));
        }
        let end = RECORD_BYTES - 4;
        if u32_at(bytes, end) != crc32(bytes.get(..end).unwrap_or(&[])) {
            return Err(StreamError::Crc);
        }
        if byte(1) > 1 {
            return Err(StreamError::Field { offset: 1 });
        }
        let phase = phase_of_byte(byte(2)).ok_or(StreamError::Field { offset: 2 })?;
        let fault = match byte(3) {
            0 => None,
            n if Fault::key_of(n).is_some() => Some(n),
            _ => return Err(StreamError::Field { offset: 3 }),
        };
        let at = |offset: usize| f32_at(bytes, offset);
        let pair = |offset: usize| number(at(offset)).map(|a| (a, at(offset + 4)));
        Ok(Record {
            sequence: u32_at(bytes, 4),
            tick: u32_at(bytes, 8),
            volts: at(12),
            dac_code: u16_at(bytes, 16),
            enabled: byte(1) == 1,
            phase,
            fault,
            max_volts: at(20),
            inputs: Inputs {
                stretch: number(at(24)),
                current_amps: number(at(28)),
                amplifier_volts: number(at(32)),
            },
            sensed: pair(36),
            resonance: pair(44),
            leakage_ohms: number(at(52)),
            bias_volts: at(56),
        })
    }

    /// The record as sent: COBS-encoded, then a zero. Its length (at most `FRAME_BYTES`).
    pub fn frame(&self, out: &mut [u8; FRAME_BYTES]) -> usize {
        let n = cobs::try_encode(&self.to_bytes(), out).unwrap_or(0);
        if let Some(end) = out.get_mut(n) {
            *end = 0;
        }
        n + 1
    }
}

/// Why `stream <hz>` cannot run at that rate.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RateError {
    pub hz: f32,
    pub tick_hz: f32,
}

impl fmt::Display for RateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "stream rate {} Hz: give a rate above 0 and at most the tick rate, {} Hz",
            crate::numerics::decimal::Decimal(self.hz),
            crate::numerics::decimal::Decimal(self.tick_hz)
        )
    }
}

/// Ticks between records for `hz` records a second at `tick_hz` ticks a second (the
/// nearest whole number; the rate is then `tick_hz / ticks`).
pub fn rate(hz: f32, tick_hz: f32) -> Result<u32, RateError> {
    let error = RateError { hz, tick_hz };
    if !(hz > 0.0 && hz <= tick_hz && tick_hz.is_finite()) {
        return Err(error);
    }
    let every = libm::roundf(tick_hz / hz);
    if !(1.0..4e9).contains(&every) {
        return Err(error);
    }
    Ok(every as u32)
}

/// The stream's state: off, or a record every `every_ticks` ticks. The sequence counts the
/// records due since boot, on and off: one due but not sent (the caller was late by more
/// than a period, or its port was busy) is a gap the receiver counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Telemetry {
    /// Ticks between records (`None`: off).
    every_ticks: Option<u32>,
    /// The tick the next record is due at (`None`: the first call's).
    next_tick: Option<u32>,
    sequence: u32,
}

impl Telemetry {
    /// A record every `every_ticks` ticks from the next call on (`None`: off).
    pub fn set(&mut self, every_ticks: Option<u32>) {
        self.every_ticks = every_ticks.filter(|&n| n > 0);
        self.next_tick = None;
    }

    /// At board tick `tick` (asked every tick, or whenever the caller runs): the sequence
    /// number of the record due, if one is. A caller late by whole periods gets one record,
    /// the ones it missed counted in the sequence.
    pub fn due(&mut self, tick: u32) -> Option<u32> {
        let every = self.every_ticks?;
        let late = self.late(tick)?;
        let missed = late / every;
        self.next_tick = Some(tick.wrapping_add(every - late % every));
        self.sequence = self.sequence.wrapping_add(missed);
        let sequence = self.sequence;
        self.sequence = self.sequence.wrapping_add(1);
        Some(sequence)
    }

    /// Ticks past the next record at board tick `tick` (`None`: off, or before it).
    fn late(&self, tick: u32) -> Option<u32> {
        self.every_ticks?;
        match self.next_tick {
            None => Some(0),
            // Before it: a wrapped difference above half the range.
            Some(next) => Some(tick.wrapping_sub(next)).filter(|late| *late < 1 << 31),
        }
    }

    /// Whether a record is due at board tick `tick`, the schedule left as it is: a caller
    /// that must take the tick's locks for the record asks this first, under the stream's
    /// own lock (the firmware's idle loop: the tick never waits for a pass with none due).
    pub fn is_due(&self, tick: u32) -> bool {
        self.late(tick).is_some()
    }

    /// The record of board tick `tick`, if one is due ([`Telemetry::due`]): the state the
    /// tick left (`enabled`: the amplifier on; the controller, if one runs; its readings).
    /// The firmware's idle loop (its link build's `link_reply`), `serve`, the core in the loop
    /// and `count` all take it here.
    pub fn record(
        &mut self,
        tick: u32,
        enabled: bool,
        controller: Option<&Controller>,
        readings: &Inputs,
    ) -> Option<Record> {
        let sequence = self.due(tick)?;
        Some(Record::of((sequence, tick), enabled, controller, readings))
    }
}

/// A receiver's bytes into records: frames split at zeros, decoded and checked; the
/// sequence's gaps counted as records lost, a frame that fails its checks counted and
/// skipped (the next zero starts the next frame: the receiver resyncs by itself).
#[derive(Clone, Debug)]
pub struct Receiver {
    frame: [u8; FRAME_BYTES],
    len: usize,
    /// More bytes than a frame holds since the last zero.
    overlong: bool,
    next_sequence: Option<u32>,
    /// Records decoded.
    pub records: u64,
    /// Records missing from the sequence between those decoded.
    pub lost: u64,
    /// Frames that failed their checks (each one or more records lost).
    pub bad_frames: u64,
}

impl Default for Receiver {
    fn default() -> Self {
        Receiver {
            frame: [0; FRAME_BYTES],
            len: 0,
            overlong: false,
            next_sequence: None,
            records: 0,
            lost: 0,
            bad_frames: 0,
        }
    }
}

impl Receiver {
    /// Take one byte; a record, or why the frame it ends is not one, when it ends a frame.
    pub fn push(&mut self, byte: u8) -> Option<Result<Record, StreamError>> {
        if byte != 0 {
            match self.frame.get_mut(self.len) {
                Some(slot) => {
                    *slot = byte;
                    self.len += 1;
                }
                None => self.overlong = true,
            }
            return None;
        }
        let (len, overlong) = (self.len, self.overlong);
        (self.len, self.overlong) = (0, false);
        if len == 0 {
            return None;
        }
        let decoded = if overlong {
            Err(StreamError::Frame)
        } else {
            self.decode(len)
        };
        match decoded {
            Ok(record) => {
                self.records += 1;
                if let Some(next) = self.next_sequence {
                    let gap = record.sequence.wrapping_sub(next);
                    // A sequence that went back: the board restarted (a new count).
                    if gap < 1 << 31 {
                        self.lost += u64::from(gap);
                    }
                }
                self.next_sequence = Some(record.sequence.wrapping_add(1));
            }
            Err(_) => self.bad_frames += 1,
        }
        Some(decoded)
    }

    fn decode(&self, len: usize) -> Result<Record, StreamError> {
        let mut bytes = [0u8; FRAME_BYTES];
        let encoded = self.frame.get(..len).ok_or(StreamError::Frame)?;
        let report = cobs::decode(encoded, &mut bytes).map_err(|_| StreamError::Frame)?;
        Record::from_bytes(bytes.get(..report.frame_size()).ok_or(StreamError::Frame)?)
    }
}

#[cfg(test)]
#[allow(clippy::indexing_slicing)]
mod tests {
    use super::*;

    fn record(sequence: u32) -> Record {
        Record {
            sequence,
            tick: 10 * sequence + 3,
            volts: 1234.5 + sequence as f32,
            dac_code: 40_000,
            enabled: true,
            phase: Some(Phase::Driving),
            fault: None,
            max_volts: 6500.0,
            inputs: Inputs {
                stretch: Some(2.25),
                current_amps: Some(-1.5e-6),
                amplifier_volts: None,
            },
            sensed: Some((2.3, 1e-4)),
            resonance: None,
            leakage_ohms: Some(2e11),
            bias_volts: 6000.0,
        }
    }

    #[test]
    fn a_record_reads_back_as_written() {
        for r in [
            record(7),
            Record {
                phase: None,
                fault: Some(19),
                ..record(0)
            },
        ] {
            assert_eq!(Record::from_bytes(&r.to_bytes()), Ok(r));
        }
    }

    #[test]
    fn a_changed_byte_fails_the_crc() {
        let mut bytes = record(1).to_bytes();
        bytes[13] ^= 0x10;
        assert_eq!(Record::from_bytes(&bytes), Err(StreamError::Crc));
    }

    #[test]
    fn records_at_the_rate_asked() {
        assert_eq!(rate(100.0, 1000.0), Ok(10));
        assert_eq!(rate(1000.0, 1000.0), Ok(1));
        for bad in [0.0, -1.0, 1001.0, f32::NAN, f32::INFINITY] {
            assert!(rate(bad, 1000.0).is_err(), "{bad}");
        }
        let mut t = Telemetry::default();
        assert_eq!(t.due(5), None);
        t.set(Some(3));
        let due: [Option<u32>; 7] = core::array::from_fn(|k| t.due(10 + k as u32));
        assert_eq!(due, [Some(0), None, None, Some(1), None, None, Some(2)]);
        // Late by a period and one tick (due at 19, asked at 23): one record, the one missed
        // counted, back on the grid (next at 25).
        assert_eq!(t.due(23), Some(4));
        assert_eq!(t.due(24), None);
        assert_eq!(t.due(25), Some(5));
        t.set(None);
        assert_eq!(t.due(26), None);
        t.set(Some(1));
        assert_eq!(t.due(40), Some(6), "the sequence goes on across off and on");
        assert_eq!(t.due(41), Some(7));
    }

    /// Frames with bytes dropped on purpose: every intact frame is read, the damaged ones
    /// counted, and the sequence's gaps equal the records not read.
    #[test]
    fn a_receiver_resyncs_after_lost_bytes_and_counts_the_gaps() {
        let mut wire = [0u8; 100 * FRAME_BYTES];
        let mut len = 0;
        let mut frame = [0u8; FRAME_BYTES];
        for s in 0..100 {
            let n = record(s).frame(&mut frame);
            assert!(frame[..n - 1].iter().all(|&b| b != 0) && frame[n - 1] == 0);
            wire[len..len + n].copy_from_slice(&frame[..n]);
            len += n;
        }
        // Drop one byte in frames 10, 11 (its ending zero: two frames run together), 50.
        let drop = [10 * 66 + 5, 12 * 66 - 1, 50 * 66 + 40];
        assert_eq!(FRAME_BYTES, 66, "the drops above assume 66-byte frames");
        let mut rx = Receiver::default();
        let mut read = 0;
        for (i, &b) in wire[..len].iter().enumerate() {
            if drop.contains(&i) {
                continue;
            }
            if let Some(Ok(r)) = rx.push(b) {
                assert_eq!(r, record(r.sequence));
                read += 1;
            }
        }
        assert_eq!(read, 100 - 4, "frames 10, 11, 12 and 50 damaged");
        assert_eq!(rx.records, 96);
        assert_eq!(rx.lost, 4);
        assert_eq!(rx.bad_frames, 3, "frame 10; 11 and 12 as one; 50");
    }
}
