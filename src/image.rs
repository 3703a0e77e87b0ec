//! The configuration image a firmware is flashed with, apart from its code (flash sector 11
//! on the STM32F405): the device, the amplifier, the default settings and the tuning table,
//! one layout for the firmware that reads it and `host-sim image` that writes it.
//!
//! Layout (every number little-endian, f32 unless said):
//!
//! | offset | size | what |
//! |---|---|---|
//! | 0 | 4 | magic `DERI` |
//! | 4 | 2 | version, u16 = 4 |
//! | 6 | 2 | S, the number of settings it holds, u16 (22 now) |
//! | 8 | 4 | L, the image's length in bytes with its CRC, u32 |
//! | 12 | 52 | the 13 device parameters in `DeviceParams` order (`jlim` 0 = neo-Hookean) |
//! | 64 | 14 | the amplifier: DAC reference V, gain V/V, rail V, DAC bits u16 (16) |
//! | 78 | 2 | at power-up, u16: 0 = wait for `start` with the output off, 1 = drive ([`PowerUp`]) |
//! | 80 | 4 | the front end's scans a second (`acquire::FrontEnd`) |
//! | 84 | 3 · 24 | per channel in `Channel::ALL` order: ADC input u8 (0xFF = not fitted), 3 zero bytes, zero code, per count, plausible low, plausible high, RMS noise a conversion in codes (0: not declared) |
//! | 156 | 8·S | the default settings, each by its stable id (`Setting::id`): id u16, two zero bytes, value (0 = off for those that can be) |
//! | 156 + 8·S | L − 160 − 8·S | the tuning table (`table`'s layout, with its own CRC) |
//! | L − 4 | 4 | CRC-32 (IEEE 802.3) of every byte before it, u32 |
//!
//! `Image::parse` checks the frame (magic, version, length, CRC), the amplifier and the front
//! end (at the settings' tick rate); the device, the settings and the table are the
//! controller's boot checks, as for any input. A setting the image does not hold (made
//! before it was added) takes its default (`Image::defaulted` says which); one this code does
//! not know (made for a newer firmware) refuses the image by name. Layout 3 (until
//! 2026-12-05) kept 4·S bytes of settings by place, which was their id: read as such.

use core::fmt;

use crate::acquire::{ChannelSpec, FrontEnd, FrontEndError, InputNoise, MAX_INPUT};
use crate::bytes::{crc32, f32_at, u16_at, u32_at};
use crate::controller::{Held, Setting, SettingSet, Settings};
use crate::drive::{Amplifier, CodeError};
use crate::model::device::DeviceParams;
use crate::table::{Table, TableError};

/// The first four bytes of an image.
pub const MAGIC: [u8; 4] = *b"DERI";
/// The layout version this code writes (it reads 3 too).
pub const VERSION: u16 = 4;
/// The previous layout, still read: settings by place.
const VERSION_BY_PLACE: u16 = 3;
/// Bytes a setting takes (layout 4): id, two zero bytes, value.
const SETTING_BYTES: usize = 8;
/// The most settings an image this code reads may hold.
const MAX_SETTINGS: usize = 64;
/// The DAC this code drives (the DAC8551): its resolution.
pub const DAC_BITS: u16 = 16;
/// Where the front end starts, and its bytes a channel.
const FRONT_END_AT: usize = 80;
const CHANNEL_BYTES: usize = 24;
/// The input byte of a channel not fitted.
const NOT_FITTED: u8 = 0xFF;
/// Bytes before the settings.
const SETTINGS_AT: usize = FRONT_END_AT + 4 + 3 * CHANNEL_BYTES;
const SETTINGS: usize = Setting::ALL.len();
/// Bytes before the table, in an image this code writes.
pub const HEADER_BYTES: usize = SETTINGS_AT + SETTING_BYTES * SETTINGS;

/// The length in bytes of an image holding a table of `table_bytes` bytes.
pub const fn image_bytes(table_bytes: usize) -> usize {
    HEADER_BYTES + table_bytes + 4
}

/// The amplifier the image was made for: the DAC's reference and resolution, the gain, and
/// the rail its output stops at.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AmplifierSpec {
    pub dac_reference_volts: f32,
    pub gain: f32,
    pub rail_volts: f32,
    pub dac_bits: u16,
}

impl AmplifierSpec {
    /// The transfer from codes to membrane volts (the DAC must be this code's, `DAC_BITS`).
    pub fn amplifier(&self) -> Result<Amplifier, ImageError> {
        if self.dac_bits != DAC_BITS {
            return Err(ImageError::DacBits {
                bits: self.dac_bits,
            });
        }
        Amplifier::new(self.dac_reference_volts, self.gain)
            .and_then(|a| a.with_rail(self.rail_volts))
            .map_err(ImageError::Amplifier)
    }
}

/// What the board does at power-up once the boot checks pass (offset 78).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PowerUp {
    /// The output off at 0 V until `start` (or `target`, `ac`): a board's default, as an HV
    /// supply comes up with its output off.
    #[default]
    Wait = 0,
    /// Ramp to the bias at once (a bench run, a scene).
    Drive = 1,
}

impl PowerUp {
    pub fn name(self) -> &'static str {
        match self {
            PowerUp::Wait => "wait",
            PowerUp::Drive => "drive",
        }
    }

    fn from_number(value: u16) -> Option<Self> {
        [PowerUp::Wait, PowerUp::Drive]
            .into_iter()
            .find(|p| *p as u16 == value)
    }
}

/// Why an image cannot be used.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ImageError {
    /// Nothing was flashed: the sector reads all `byte` where the header should be (0xFF
    /// on erased silicon, 0x00 under QEMU).
    Empty { byte: u8 },
    /// Shorter than a header and a CRC.
    TooShort { bytes: usize },
    /// Does not start with `DERI`.
    BadMagic,
    /// A layout version this code does not read.
    UnsupportedVersion { version: u16 },
    /// Holds more settings than any layout has room for.
    SettingsCount { count: u16 },
    /// Holds a setting this firmware does not know (made for a newer one).
    UnknownSetting { id: u16 },
    /// Its length is shorter than its parts or longer than the room it is in.
    WrongLength { stated: u32, room: usize },
    /// The stored CRC does not match the bytes: corrupted or cut short.
    BadCrc { stored: u32, computed: u32 },
    /// Made for a DAC of another resolution than this firmware drives.
    DacBits { bits: u16 },
    /// The amplifier's numbers give no transfer.
    Amplifier(CodeError),
    /// The table inside is not a valid table.
    Table(TableError),
    /// The analog front end cannot be used.
    FrontEnd(FrontEndError),
    /// The power-up field holds no [`PowerUp`].
    PowerUp { value: u16 },
    /// The output buffer is too small (writing).
    BufferTooSmall { needed: usize },
}

impl fmt::Display for ImageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ImageError::Empty { byte } => write!(
                f,
                "no configuration image: the sector reads {byte:#04x} (flash one with \
                 `host-sim image`)"
            ),
            ImageError::TooShort { bytes } => write!(f, "image of {bytes} bytes is too short"),
            ImageError::BadMagic => write!(f, "not a configuration image (no DERI magic)"),
            ImageError::UnsupportedVersion { version } => write!(
                f,
                "image layout version {version}, this firmware reads {VERSION_BY_PLACE} and \
                 {VERSION} (make the image again with this firmware's `host-sim image`)"
            ),
            ImageError::SettingsCount { count } => {
                write!(
                    f,
                    "image holds {count} settings, at most {MAX_SETTINGS} read"
                )
            }
            ImageError::UnknownSetting { id } => write!(
                f,
                "image holds setting id {id}, which this firmware does not know (made for a \
                 newer one): make the image again with this firmware's `host-sim image`"
            ),
            ImageError::WrongLength { stated, room } => write!(
                f,
                "image length {stated} bytes is impossible (room for {room})"
            ),
            ImageError::BadCrc { stored, computed } => write!(
                f,
                "image CRC {stored:#010x} does not match its bytes ({computed:#010x}): corrupted"
            ),
            ImageError::DacBits { bits } => write!(
                f,
                "image made for a {bits}-bit DAC, this firmware drives a {DAC_BITS}-bit DAC8551"
            ),
            ImageError::Amplifier(e) => write!(f, "image amplifier: {e}"),
            ImageError::Table(e) => write!(f, "image {e}"),
            ImageError::FrontEnd(e) => write!(f, "image {e}"),
            ImageError::PowerUp { value } => write!(
                f,
                "image power-up field {value}: 0 (wait for `start`) or 1 (drive) expected"
            ),
            ImageError::BufferTooSmall { needed } => {
                write!(f, "image needs a buffer of {needed} bytes")
            }
        }
    }
}

impl core::error::Error for ImageError {}

/// A configuration image read from flash (borrowing its table, no copy).
#[derive(Clone, Copy, Debug)]
pub struct Image<'a> {
    pub params: DeviceParams<f32>,
    pub amplifier: AmplifierSpec,
    /// The board's analog inputs (checked at the settings' tick rate).
    pub front_end: FrontEnd,
    pub settings: Settings,
    /// The settings it does not hold (made before they were added), at their defaults.
    pub defaulted: SettingSet,
    /// Whether the board drives once its boot checks pass, or waits for `start`.
    pub power_up: PowerUp,
    /// The table's bytes, for `Controller::start` (which parses and checks them).
    pub table: &'a [u8],
    /// The image's own CRC-32 (its last four bytes): which image a board runs, in a word.
    pub crc: u32,
}

impl<'a> Image<'a> {
    /// Read an image from the start of `room` (a flash sector: the image may be shorter).
    pub fn parse(room: &'a [u8]) -> Result<Self, ImageError> {
        let Some(head) = room.get(..SETTINGS_AT + 4) else {
            return Err(ImageError::TooShort { bytes: room.len() });
        };
        if let Some(&byte) = head.first() {
            if head.iter().all(|&b| b == byte) && (byte == 0x00 || byte == 0xFF) {
                return Err(ImageError::Empty { byte });
            }
        }
        if head.get(..4) != Some(&MAGIC[..]) {
            return Err(ImageError::BadMagic);
        }
        let version = u16_at(room, 4);
        let each = match version {
            VERSION => SETTING_BYTES,
            VERSION_BY_PLACE => 4,
            _ => return Err(ImageError::UnsupportedVersion { version }),
        };
        let count = u16_at(room, 6);
        if usize::from(count) > MAX_SETTINGS {
            return Err(ImageError::SettingsCount { count });
        }
        let table_at = SETTINGS_AT + each * usize::from(count);
        let stated = u32_at(room, 8);
        let length = stated as usize;
        let body = length.wrapping_sub(4);
        let (Some(bytes), true) = (room.get(..length), length >= table_at + 4) else {
            return Err(ImageError::WrongLength {
                stated,
                room: room.len(),
            });
        };
        let stored = u32_at(bytes, body);
        let computed = crc32(bytes.get(..body).unwrap_or(&[]));
        if stored != computed {
            return Err(ImageError::BadCrc { stored, computed });
        }
        let mut values = [0.0; 13];
        for (k, value) in values.iter_mut().enumerate() {
            *value = f32_at(bytes, 12 + 4 * k);
        }
        let amplifier = AmplifierSpec {
            dac_reference_volts: f32_at(bytes, 64),
            gain: f32_at(bytes, 68),
            rail_volts: f32_at(bytes, 72),
            dac_bits: u16_at(bytes, 76),
        };
        amplifier.amplifier()?;
        let power_up = u16_at(bytes, 78);
        let power_up =
            PowerUp::from_number(power_up).ok_or(ImageError::PowerUp { value: power_up })?;
        let mut held = Held::NONE;
        for k in 0..usize::from(count) {
            let at = SETTINGS_AT + each * k;
            let (id, value) = match version {
                VERSION_BY_PLACE => (k as u16, f32_at(bytes, at)),
                _ => (u16_at(bytes, at), f32_at(bytes, at + 4)),
            };
            let setting = u8::try_from(id)
                .ok()
                .and_then(Setting::from_id)
                .ok_or(ImageError::UnknownSetting { id })?;
            held = held.with(setting, value);
        }
        let (settings, defaulted) = held.onto(Settings::for_target(0.0));
        let mut front_end = FrontEnd {
            scan_hz: f32_at(bytes, FRONT_END_AT),
            channels: [None; 3],
        };
        for (k, channel) in front_end.channels.iter_mut().enumerate() {
            let at = FRONT_END_AT + 4 + CHANNEL_BYTES * k;
            let input = bytes.get(at).copied().unwrap_or(NOT_FITTED);
            *channel = (input != NOT_FITTED).then(|| ChannelSpec {
                input,
                zero_code: f32_at(bytes, at + 4),
                per_count: f32_at(bytes, at + 8),
                low: f32_at(bytes, at + 12),
                high: f32_at(bytes, at + 16),
                noise_codes: f32_at(bytes, at + 20),
            });
        }
        // A tick rate that is no rate is the controller's to refuse, by name.
        let tick_hz = settings.tick_hz;
        if tick_hz > 0.0 && tick_hz.is_finite() {
            front_end.check(tick_hz).map_err(ImageError::FrontEnd)?;
        }
        let table = bytes.get(table_at..body).unwrap_or(&[]);
        Table::parse(table).map_err(ImageError::Table)?;
        Ok(Self {
            params: DeviceParams::from_values(values),
            amplifier,
            front_end,
            settings,
            defaulted,
            power_up,
            table,
            crc: stored,
        })
    }

    /// What a controller needs of the board at `tick_hz`: the amplifier's transfer and the
    /// noise the front end declares for a tick's readings (a front end the rate does not
    /// suit is refused elsewhere; its noise is taken at one scan a tick, the most).
    pub fn board(&self, amplifier: Amplifier, tick_hz: f32) -> (Amplifier, InputNoise) {
        let scans = self.front_end.check(tick_hz).unwrap_or(1);
        (amplifier, self.front_end.input_noise(scans))
    }

    /// Write an image into `out`; the bytes written. What is written parses back.
    pub fn write(
        out: &mut [u8],
        params: &DeviceParams<f32>,
        amplifier: &AmplifierSpec,
        front_end: &FrontEnd,
        settings: &Settings,
        power_up: PowerUp,
        table: &[u8],
    ) -> Result<usize, ImageError> {
        Table::parse(table).map_err(ImageError::Table)?;
        // An input the layout cannot hold (0xFF is "not fitted") would read back as none.
        if let Some((channel, spec)) = front_end.fitted().find(|(_, s)| s.input > MAX_INPUT) {
            return Err(ImageError::FrontEnd(FrontEndError::Input {
                channel,
                input: spec.input,
            }));
        }
        let needed = image_bytes(table.len());
        let Some(out) = out.get_mut(..needed) else {
            return Err(ImageError::BufferTooSmall { needed });
        };
        let numbers = params
            .values()
            .into_iter()
            .chain([
                amplifier.dac_reference_volts,
                amplifier.gain,
                amplifier.rail_volts,
            ])
            .flat_map(f32::to_le_bytes)
            .chain(amplifier.dac_bits.to_le_bytes())
            .chain((power_up as u16).to_le_bytes())
            .chain(front_end.scan_hz.to_le_bytes())
            .chain(front_end.channels.iter().flat_map(|spec| {
                let (input, numbers) = match spec {
                    Some(c) => (
                        c.input,
                        [c.zero_code, c.per_count, c.low, c.high, c.noise_codes],
                    ),
                    None => (NOT_FITTED, [0.0; 5]),
                };
                [input, 0, 0, 0]
                    .into_iter()
                    .chain(numbers.into_iter().flat_map(f32::to_le_bytes))
            }))
            .chain(Setting::ALL.into_iter().flat_map(|s| {
                let id = u16::from(s.id()).to_le_bytes();
                let value = settings.get(s).to_le_bytes();
                [id[0], id[1], 0, 0, value[0], value[1], value[2], value[3]]
            }));
        let head = MAGIC
            .into_iter()
            .chain(VERSION.to_le_bytes())
            .chain((SETTINGS as u16).to_le_bytes())
            .chain((needed as u32).to_le_bytes())
            .chain(numbers)
            .chain(table.iter().copied());
        let (body, crc_bytes) = out.split_at_mut(needed - 4);
        for (slot, byte) in body.iter_mut().zip(head) {
            *slot = byte;
        }
        crc_bytes.copy_from_slice(&crc32(body).to_le_bytes());
        Image::parse(out)?;
        Ok(needed)
    }
}
