//! The board's analog inputs: the ADC's codes, summed per tick ([`Block`]), to the
//! controller's [`Inputs`] in physical units through the image's [`FrontEnd`]. On silicon a
//! timer triggers the ADC's scan and DMA fills a double buffer; the DMA's task adds each half
//! to the block, the tick takes it. Integer sums, so no sample can make a NaN; a channel whose
//! block sits at the ADC's rail, holds no sample, or reads outside its plausible range is an
//! [`InputError`] said by name, and the tick faults on it.

use core::fmt;

use crate::numerics::decimal::Decimal;

/// The ADC's resolution (the STM32F405's ADC at 12 bits).
pub const ADC_BITS: u32 = 12;
/// The highest code the ADC gives.
pub const FULL_SCALE_CODE: u16 = (1 << ADC_BITS) - 1;
/// A block whose mean is this close to a rail (in codes) sits at the rail: an open input
/// pulled there by its bias resistor, a short, or a saturated amplifier. A front end keeps its
/// plausible range this far inside the rails (a live zero), so no good reading is taken for it.
pub const RAIL_MARGIN_CODES: f32 = 16.0;
/// The highest ADC input (ADC123_IN0..IN15).
pub const MAX_INPUT: u8 = 15;
/// The ADC inputs the board leaves to analog signals, a bit each: IN0, IN1 (PA0, PA1), IN9
/// (PB1), IN10..IN15 (PC0..PC5). The others carry the command port (PA2, PA3), the DAC's SPI
/// (PA4..PA7) and the amplifier's enable line (PB0).
pub const BOARD_INPUTS: u16 = 0b1111_1110_0000_0011;
/// The most codes a DMA buffer holds (each of the three buffers the firmware keeps).
pub const BUFFER_CODES: usize = 128;
/// The most DMA buffers a tick (their interrupt's rate: a tick's scans that no buffer size
/// divides, a prime number of them, would otherwise take an interrupt a scan).
pub const MAX_BUFFERS_PER_TICK: u32 = 16;
/// Ticks at power-up whose block may be empty before the first DMA buffer has come (the
/// timer, the ADC and the tick are not in phase): no reading then, not a fault.
pub const FIRST_BUFFER_TICKS: u32 = 10;
/// The most conversions a second the front end may ask for, all channels together (the
/// ADC at 21 MHz, 15 cycles a 12-bit conversion, a sampling time of 56 cycles: ~296 kHz).
pub const MAX_CONVERSIONS_HZ: f32 = 250_000.0;
/// The ADC's clock `MAX_CONVERSIONS_HZ` is for (84 MHz APB2 / 4), Hz; on another clock (the
/// 16 MHz HSI fallback: 4 MHz) the limit scales with it ([`max_conversions_hz`]).
pub const NOMINAL_ADC_CLOCK_HZ: f32 = 21.0e6;
/// A second stall of the acquisition within this time of the last one it recovered from is a
/// fault (`InputError::Stalled`); one alone is re-armed and counted, s. Ten of the leakage
/// watch's windows (`LEAKAGE_WINDOW_SECONDS`): a stall's tick reads no current, which starts
/// that watch's window again, so stalls it recovers from leave it whole windows between.
pub const STALL_REPEAT_SECONDS: f32 = 10.0;
/// Ticks from a recovered stall's whose block may lack a channel's samples (the buffers the
/// re-arm lost): the stall's own tick reads nothing, the next reads what it holds, a channel
/// with no sample nothing, not a fault.
pub const STALL_GRACE_TICKS: u32 = 2;

/// The most conversions a second at an ADC clock of `adc_clock_hz`, all channels together
/// (`MAX_CONVERSIONS_HZ` scaled: the same sampling time, the same margin).
pub fn max_conversions_hz(adc_clock_hz: f32) -> f32 {
    MAX_CONVERSIONS_HZ * (adc_clock_hz / NOMINAL_ADC_CLOCK_HZ)
}

/// Why the acquisition stopped on silicon and was re-armed (by the firmware's DMA or ADC
/// interrupt; through the link, host-sim's injected fault).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stall {
    /// The ADC converted again before the DMA took its last code (OVR): it stops its DMA
    /// requests until re-armed.
    Overrun,
    /// The DMA stream's transfer error (TEIF): the stream disables itself.
    TransferError,
}

impl Stall {
    /// Every stall, in order (the fault log keeps one by its index).
    pub const ALL: [Stall; 2] = [Stall::Overrun, Stall::TransferError];
}

impl Stall {
    pub const fn name(self) -> &'static str {
        match self {
            Stall::Overrun => "an ADC overrun",
            Stall::TransferError => "a DMA transfer error",
        }
    }
}

/// An analog input of the board.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Channel {
    /// The amplifier's output current monitor (a shunt amplifier), A.
    Current,
    /// The amplifier's output voltage monitor (the high-voltage divider), V.
    Amplifier,
    /// A displacement sensor on the bars, as the stretch λ1 (dimensionless).
    Stretch,
}

impl Channel {
    /// Every channel, in the order of the image's layout and of the ADC's scan.
    pub const ALL: [Channel; 3] = [Channel::Current, Channel::Amplifier, Channel::Stretch];

    /// Its name in the image's report and the settings file's `[front_end]` table.
    pub const fn name(self) -> &'static str {
        match self {
            Channel::Current => "current",
            Channel::Amplifier => "amplifier",
            Channel::Stretch => "stretch",
        }
    }

    /// The unit of its readings.
    pub const fn unit(self) -> &'static str {
        match self {
            Channel::Current => "A",
            Channel::Amplifier => "V",
            Channel::Stretch => "(stretch)",
        }
    }
}

/// One channel's wiring and scaling: `reading = (code − zero_code) · per_count`, plausible
/// within `[low, high]` (in the reading's unit).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelSpec {
    /// The ADC input it is wired to (IN0..IN15).
    pub input: u8,
    /// The code that reads zero (a bipolar current monitor: mid-scale, 2047.5).
    pub zero_code: f32,
    /// The reading's change per code: A, V or stretch per count.
    pub per_count: f32,
    /// The lowest plausible reading.
    pub low: f32,
    /// The highest plausible reading.
    pub high: f32,
    /// The input's RMS noise a conversion, in codes, as the board's maker measured it (0:
    /// not declared, the quantisation alone): what the trim's ring is weighed against before
    /// any voltage (`InputNoise`), checked again against the noise heard in the hold.
    pub noise_codes: f32,
}

impl ChannelSpec {
    /// The reading of a mean code.
    pub fn reading(&self, mean_code: f32) -> f32 {
        (mean_code - self.zero_code) * self.per_count
    }

    /// The (fractional) code a reading gives: the inverse of [`reading`](Self::reading), for
    /// those that make codes from a plant's signals (host-sim, tests).
    pub fn code_of(&self, reading: f32) -> f32 {
        self.zero_code + reading / self.per_count
    }

    /// The ADC's code for a reading: rounded, held within the ADC's range as the converter
    /// holds its input (for those that make codes from a plant's signals).
    pub fn adc_code(&self, reading: f32) -> u16 {
        let code = self.code_of(reading);
        if code >= f32::from(FULL_SCALE_CODE) {
            FULL_SCALE_CODE
        } else if code > 0.0 {
            // The nearest code, halves up, as floor(code + 0.5) in f32 (which, unlike
            // roundf, rounds the one value just below a half up): libm's software roundf cost
            // as much as the rest of a simulated sample.
            (code + 0.5) as u16
        } else {
            0
        }
    }

    /// The RMS noise of a tick's reading, the mean of `scans` conversions (the reading's
    /// unit): the declared noise averaged over the scans, and the quantisation, q/√12 a
    /// conversion, averaged too where the noise dithers it (half a code or more), else not.
    pub fn tick_noise(&self, scans: u32) -> f32 {
        let scans = scans.max(1) as f32;
        let noise = self.noise_codes * self.noise_codes;
        let quantisation = 1.0 / 12.0;
        let codes_squared = if self.noise_codes >= 0.5 {
            (noise + quantisation) / scans
        } else {
            noise / scans + quantisation
        };
        libm::fabsf(self.per_count) * libm::sqrtf(codes_squared)
    }

    fn check(&self, channel: Channel) -> Result<(), FrontEndError> {
        if !(self.noise_codes >= 0.0 && self.noise_codes.is_finite()) {
            return Err(FrontEndError::Noise {
                channel,
                noise_codes: self.noise_codes,
            });
        }
        if self.input > MAX_INPUT || BOARD_INPUTS & (1 << self.input) == 0 {
            return Err(FrontEndError::Input {
                channel,
                input: self.input,
            });
        }
        let per_count_ok = self.per_count.is_finite() && self.per_count != 0.0;
        if !(per_count_ok && self.zero_code.is_finite()) {
            return Err(FrontEndError::Scale {
                channel,
                zero_code: self.zero_code,
                per_count: self.per_count,
            });
        }
        let (a, b) = (self.code_of(self.low), self.code_of(self.high));
        let inside = |code: f32| {
            code >= RAIL_MARGIN_CODES && code <= f32::from(FULL_SCALE_CODE) - RAIL_MARGIN_CODES
        };
        if !(self.low < self.high && inside(a) && inside(b)) {
            return Err(FrontEndError::Range {
                channel,
                low: self.low,
                high: self.high,
                low_code: a,
                high_code: b,
            });
        }
        Ok(())
    }
}

/// The RMS noise of a tick's stretch and current readings as the image's front end declares
/// it (`ChannelSpec::tick_noise`): `None` where the input is not read through it (not
/// fitted; or a host's ideal sensor), and the trim then weighs its ring against the noise it
/// hears alone.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct InputNoise {
    /// The stretch sensor's, a tick.
    pub stretch: Option<f32>,
    /// The current monitor's, A a tick.
    pub amps: Option<f32>,
}

impl InputNoise {
    /// Nothing declared.
    pub const UNDECLARED: InputNoise = InputNoise {
        stretch: None,
        amps: None,
    };
}

/// The board's analog front end, as the image states it: the conversion rate and each
/// channel's wiring (`None`: not fitted; a board without a displacement sensor runs
/// sensorless from the current monitor).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FrontEnd {
    /// Scans a second (each converts every fitted channel once), a whole number per tick.
    pub scan_hz: f32,
    /// By [`Channel::ALL`]'s order.
    pub channels: [Option<ChannelSpec>; 3],
}

impl FrontEnd {
    /// A board with no analog input: open loop (no trim, no monitor of the motion).
    pub const NONE: FrontEnd = FrontEnd {
        scan_hz: 0.0,
        channels: [None; 3],
    };

    /// The fitted channels in the scan's order, with their specs.
    pub fn fitted(&self) -> impl Iterator<Item = (Channel, &ChannelSpec)> {
        Channel::ALL
            .into_iter()
            .zip(self.channels.iter())
            .filter_map(|(c, spec)| spec.as_ref().map(|s| (c, s)))
    }

    /// The noise of a tick's stretch and current readings at `scans_per_tick` (from
    /// [`check`](Self::check)), for the trim's checks.
    pub fn input_noise(&self, scans_per_tick: u32) -> InputNoise {
        let [current, _, stretch] = &self.channels;
        InputNoise {
            stretch: stretch.map(|c| c.tick_noise(scans_per_tick)),
            amps: current.map(|c| c.tick_noise(scans_per_tick)),
        }
    }

    /// Whether no channel is fitted.
    pub fn is_empty(&self) -> bool {
        self.fitted().next().is_none()
    }

    /// The checks of the image's front end at a tick rate: each channel's input, scale and
    /// plausible range (inside the rails), no input twice, and a whole number of scans a
    /// tick within the ADC's rate. The scans a tick (0 with no channel).
    pub fn check(&self, tick_hz: f32) -> Result<u32, FrontEndError> {
        let mut used = 0u16;
        for (channel, spec) in self.fitted() {
            spec.check(channel)?;
            let bit = 1u16 << (spec.input & MAX_INPUT);
            if used & bit != 0 {
                return Err(FrontEndError::SameInput { input: spec.input });
            }
            used |= bit;
        }
        if self.is_empty() {
            return Ok(0);
        }
        let per_tick = self.scan_hz / tick_hz;
        let whole = libm::roundf(per_tick);
        let conversions = self.scan_hz * used.count_ones() as f32;
        // At least two buffers a tick (the DMA's are not locked to the tick: each tick then
        // takes one or more), at most `MAX_BUFFERS_PER_TICK` (the DMA's interrupt rate).
        let ok = whole >= 2.0
            && (per_tick - whole).abs() <= 1e-4 * whole
            && conversions <= MAX_CONVERSIONS_HZ
            && {
                let scans = whole as u32;
                let per_buffer = self.scans_per_buffer(scans).max(1);
                scans / per_buffer <= MAX_BUFFERS_PER_TICK
            };
        if !ok {
            return Err(FrontEndError::ScanRate {
                scan_hz: self.scan_hz,
                tick_hz,
            });
        }
        Ok(whole as u32)
    }

    /// The check of the front end's conversions against the ADC's clock in use (the board
    /// may run on its fallback oscillator, where the ADC converts about 4 times slower).
    pub fn check_adc_clock(&self, adc_clock_hz: f32) -> Result<(), FrontEndError> {
        let conversions_hz = self.scan_hz * self.fitted().count() as f32;
        let max_hz = max_conversions_hz(adc_clock_hz);
        if conversions_hz <= max_hz {
            Ok(())
        } else {
            Err(FrontEndError::AdcClock {
                conversions_hz,
                max_hz,
                adc_clock_hz,
            })
        }
    }

    /// The scans a DMA buffer holds, for `scans_per_tick` (from [`check`](Self::check)):
    /// the largest whole part of a tick's scans that fits [`BUFFER_CODES`], at most half a
    /// tick's (two buffers a tick, so a tick takes whole buffers at a steady phase); 0 with
    /// no channel.
    pub fn scans_per_buffer(&self, scans_per_tick: u32) -> u32 {
        let channels = self.fitted().count() as u32;
        if channels == 0 {
            return 0;
        }
        let room = BUFFER_CODES as u32 / channels;
        let parts = (2..=scans_per_tick.max(2))
            .find(|&k| scans_per_tick.is_multiple_of(k) && scans_per_tick / k <= room);
        parts.map_or(1, |k| scans_per_tick / k)
    }

    /// The block's means in units, checked: a fitted channel with no sample, at a rail, or
    /// outside its plausible range is an error; a channel not fitted is `None`.
    pub fn inputs(&self, block: &Block) -> Result<Inputs, InputError> {
        let [current, amplifier, stretch] = &self.channels;
        let read = |spec: &Option<ChannelSpec>, sums: &Sums, channel| match spec {
            Some(spec) => sums.reading(channel, spec).map(Some),
            None => Ok(None),
        };
        Ok(Inputs {
            current_amps: read(current, &block.current, Channel::Current)?,
            amplifier_volts: read(amplifier, &block.amplifier, Channel::Amplifier)?,
            stretch: read(stretch, &block.stretch, Channel::Stretch)?,
        })
    }
}

/// The front end made ready for the tick at its scans a tick: per channel, the sums of a
/// full block that read plausibly (the plausible range, inside the rails, as whole sums) and
/// the reading per sum. A full block within them is read with a multiply and an add, a block
/// short of scans within the same means with a division more; any other block takes
/// [`FrontEnd::inputs`], which names what is wrong (the tick's budget).
/// At power-up, until the first sample comes, an empty block is no reading (for at most
/// [`FIRST_BUFFER_TICKS`] ticks), not a fault. A block that says a stall (the firmware
/// re-armed the ADC and its DMA) is counted and reads nothing, the next reads what it holds
/// (a channel with no sample nothing); a second stall within [`STALL_REPEAT_SECONDS`], or
/// two in one block, is [`InputError::Stalled`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reader {
    front_end: FrontEnd,
    scans: u32,
    fast: [Option<FastChannel>; 3],
    /// Ticks left that may find no sample yet (0 once one has come).
    waiting: u32,
    /// Ticks since the last stall recovered from (saturating), and the ticks within which
    /// another is a fault (`STALL_REPEAT_SECONDS` at the tick rate).
    since_stall: u32,
    repeat_ticks: u32,
    /// Ticks left whose block may lack a channel's samples after a stall.
    grace: u32,
    /// The stalls recovered from since power-up.
    recovered: u32,
}

/// A channel's fast path: a full block's sums in `[low_sum, high_sum]` read
/// `sum · per_sum − offset`; a block short of scans (a buffer lost, a stall's grace) reads its
/// mean code as the checked path does, `(mean − zero_code) · per_count`, for a mean in
/// `[low_mean, high_mean]`: the means of `low_sum` and `high_sum`, which the checked path
/// reads, so every mean between them reads too (its checks are monotone in the mean).
#[derive(Clone, Copy, Debug, PartialEq)]
struct FastChannel {
    low_sum: u32,
    high_sum: u32,
    per_sum: f32,
    offset: f32,
    low_mean: f32,
    high_mean: f32,
    zero_code: f32,
    per_count: f32,
}

impl Reader {
    /// `front_end` at `scans_per_tick` (from its `check`): no fast path for a channel whose
    /// sums do not fit (it takes `FrontEnd::inputs` every tick, as with 0 scans).
    pub fn new(front_end: FrontEnd, scans_per_tick: u32) -> Self {
        let n = scans_per_tick as f32;
        let fast = front_end.channels.map(|spec| {
            let spec = spec?;
            let (a, b) = (spec.code_of(spec.low), spec.code_of(spec.high));
            let (low, high) = (a.min(b).max(RAIL_MARGIN_CODES), a.max(b));
            let high = high.min(f32::from(FULL_SCALE_CODE) - RAIL_MARGIN_CODES);
            let (low_sum, high_sum) = (libm::ceilf(low * n), libm::floorf(high * n));
            if !(scans_per_tick > 0 && low_sum >= 0.0 && high_sum < 4.0e9) {
                return None;
            }
            // Whole sums the checked path reads, found by it (its reading is monotone in the
            // sum): the fast path never lets one through that it would refuse.
            let checked = |sum: u32| {
                let sums = Sums {
                    sum,
                    count: scans_per_tick,
                    highest: 0,
                };
                sums.reading(Channel::Current, &spec).is_ok()
            };
            let (mut low_sum, mut high_sum) = (low_sum as u32, high_sum as u32);
            for _ in 0..64 {
                if low_sum > high_sum || checked(low_sum) {
                    break;
                }
                low_sum = low_sum.saturating_add(1);
            }
            for _ in 0..64 {
                if low_sum > high_sum || checked(high_sum) {
                    break;
                }
                high_sum = high_sum.saturating_sub(1);
            }
            (low_sum <= high_sum && checked(low_sum) && checked(high_sum)).then(|| FastChannel {
                low_sum,
                high_sum,
                per_sum: spec.per_count / n,
                offset: spec.zero_code * spec.per_count,
                // As `Sums::reading` computes a mean.
                low_mean: low_sum as f32 / scans_per_tick as f32,
                high_mean: high_sum as f32 / scans_per_tick as f32,
                zero_code: spec.zero_code,
                per_count: spec.per_count,
            })
        });
        // The tick rate is the scan rate over the scans a tick.
        let repeat = STALL_REPEAT_SECONDS * front_end.scan_hz / n;
        let repeat_ticks = if repeat.is_finite() && repeat >= 1.0 {
            repeat as u32
        } else {
            1
        };
        Self {
            front_end,
            scans: scans_per_tick,
            fast,
            waiting: FIRST_BUFFER_TICKS,
            since_stall: u32::MAX,
            repeat_ticks,
            grace: 0,
            recovered: 0,
        }
    }

    /// The stalls of the acquisition recovered from since power-up (re-armed, not faults).
    pub fn recovered(&self) -> u32 {
        self.recovered
    }

    /// A stalled block: recovered from (counted; its tick reads nothing, the next
    /// `STALL_GRACE_TICKS - 1` whatever they hold), or, within `STALL_REPEAT_SECONDS` of the
    /// last, the fault.
    #[inline(never)]
    fn on_stall(&mut self, stall: Stall, stalls: u8) -> Result<(), InputError> {
        // Two in one block: two within a tick.
        if stalls > 1 || self.since_stall < self.repeat_ticks {
            return Err(InputError::Stalled {
                stall,
                recovered: self.recovered,
            });
        }
        self.since_stall = 0;
        self.recovered = self.recovered.saturating_add(1);
        self.grace = STALL_GRACE_TICKS - 1;
        Ok(())
    }

    /// A block in a stall's grace that the fast path did not read: a channel with no sample
    /// reads nothing; any other reading is checked as [`FrontEnd::inputs`] checks it.
    #[inline(never)]
    fn in_grace(&self, block: &Block) -> Result<Inputs, InputError> {
        let read = |spec: &Option<ChannelSpec>, sums: &Sums, channel| match spec {
            Some(spec) if sums.count > 0 => sums.reading(channel, spec).map(Some),
            _ => Ok(None),
        };
        let [current, amplifier, stretch] = &self.front_end.channels;
        Ok(Inputs {
            current_amps: read(current, &block.current, Channel::Current)?,
            amplifier_volts: read(amplifier, &block.amplifier, Channel::Amplifier)?,
            stretch: read(stretch, &block.stretch, Channel::Stretch)?,
        })
    }

    /// The block's readings, as [`FrontEnd::inputs`] gives them (to rounding), checked; no
    /// reading while the first sample has not come (at power-up, for a few ticks), nor at a
    /// stall recovered from (see [`Reader`]).
    pub fn inputs(&mut self, block: &Block) -> Result<Inputs, InputError> {
        self.since_stall = self.since_stall.saturating_add(1);
        if let Some(stall) = block.stall {
            // The stall's own tick: its block lost codes to the re-arm; no reading.
            self.on_stall(stall, block.stalls)?;
            return Ok(Inputs::NONE);
        }
        let grace = self.grace > 0;
        if grace {
            self.grace -= 1;
        }
        if self.waiting > 0 {
            let empty =
                block.current.count == 0 && block.amplifier.count == 0 && block.stretch.count == 0;
            if empty {
                self.waiting -= 1;
                return Ok(Inputs::NONE);
            }
            self.waiting = 0;
        }
        let mut good = true;
        let mut read = |fitted: bool, fast: &Option<FastChannel>, sums: &Sums| {
            if !fitted {
                return None;
            }
            match fast {
                Some(f) if sums.count == self.scans => {
                    good &= sums.highest <= FULL_SCALE_CODE
                        && sums.sum >= f.low_sum
                        && sums.sum <= f.high_sum;
                    Some(sums.sum as f32 * f.per_sum - f.offset)
                }
                Some(f) if sums.count > 0 => {
                    let mean = sums.sum as f32 / sums.count as f32;
                    good &= sums.highest <= FULL_SCALE_CODE
                        && mean >= f.low_mean
                        && mean <= f.high_mean;
                    Some((mean - f.zero_code) * f.per_count)
                }
                // A stall's grace: no sample, no reading.
                _ if grace && sums.count == 0 => None,
                _ => {
                    good = false;
                    None
                }
            }
        };
        let [c, a, s] = &self.front_end.channels;
        let [fc, fa, fs] = &self.fast;
        let inputs = Inputs {
            current_amps: read(c.is_some(), fc, &block.current),
            amplifier_volts: read(a.is_some(), fa, &block.amplifier),
            stretch: read(s.is_some(), fs, &block.stretch),
        };
        if good {
            Ok(inputs)
        } else if grace {
            self.in_grace(block)
        } else {
            self.front_end.inputs(block)
        }
    }
}

/// One channel's samples in a block: their sum, number and highest code.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Sums {
    sum: u32,
    count: u32,
    highest: u16,
}

impl Sums {
    fn add(&mut self, code: u16) {
        self.sum = self.sum.saturating_add(u32::from(code));
        self.count = self.count.saturating_add(1);
        self.highest = self.highest.max(code);
    }

    /// The reading through `spec`, or why there is none.
    fn reading(&self, channel: Channel, spec: &ChannelSpec) -> Result<f32, InputError> {
        if self.count == 0 {
            return Err(InputError::NoSamples { channel });
        }
        if self.highest > FULL_SCALE_CODE {
            return Err(InputError::NotACode {
                channel,
                code: self.highest,
            });
        }
        let mean_code = self.sum as f32 / self.count as f32;
        if !(mean_code >= RAIL_MARGIN_CODES
            && mean_code <= f32::from(FULL_SCALE_CODE) - RAIL_MARGIN_CODES)
        {
            return Err(InputError::AtRail { channel, mean_code });
        }
        let reading = (mean_code - spec.zero_code) * spec.per_count;
        if !(reading >= spec.low && reading <= spec.high) {
            return Err(InputError::Implausible {
                channel,
                reading,
                low: spec.low,
                high: spec.high,
            });
        }
        Ok(reading)
    }
}

/// One tick's samples: per channel the sum of its codes, their number, and the highest code
/// (integers: no sample can make a NaN). Filled by the DMA's task, taken by the tick.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Block {
    current: Sums,
    amplifier: Sums,
    stretch: Sums,
    /// The acquisition stalled and was re-armed since the last tick (the latest cause), and
    /// how many times.
    stall: Option<Stall>,
    stalls: u8,
}

impl Block {
    /// No sample yet.
    pub const EMPTY: Block = Block {
        current: Sums {
            sum: 0,
            count: 0,
            highest: 0,
        },
        amplifier: Sums {
            sum: 0,
            count: 0,
            highest: 0,
        },
        stretch: Sums {
            sum: 0,
            count: 0,
            highest: 0,
        },
        stall: None,
        stalls: 0,
    };

    /// The acquisition stopped (`why`) and has been re-armed: the codes it lost are missing
    /// from this block. The firmware's recovery says it here; the tick's reader decides.
    pub fn stalled(&mut self, why: Stall) {
        self.stall = Some(why);
        self.stalls = self.stalls.saturating_add(1);
    }

    fn sums(&mut self, channel: Channel) -> &mut Sums {
        match channel {
            Channel::Current => &mut self.current,
            Channel::Amplifier => &mut self.amplifier,
            Channel::Stretch => &mut self.stretch,
        }
    }

    /// One sample of a channel.
    pub fn add(&mut self, channel: Channel, code: u16) {
        self.sums(channel).add(code);
    }

    /// A buffer of whole scans as the DMA writes them: the fitted channels' codes
    /// interleaved in the scan's order (a trailing part scan is ignored).
    pub fn add_scans(&mut self, front_end: &FrontEnd, codes: &[u16]) {
        let [current, amplifier, stretch] = &front_end.channels;
        match (current.is_some(), amplifier.is_some(), stretch.is_some()) {
            (true, true, true) => {
                for scan in codes.chunks_exact(3) {
                    if let [c, a, s] = *scan {
                        self.current.add(c);
                        self.amplifier.add(a);
                        self.stretch.add(s);
                    }
                }
            }
            (false, false, false) => {}
            _ => {
                let mut order = [Channel::Current; 3];
                let mut n = 0;
                for ((channel, _), slot) in front_end.fitted().zip(order.iter_mut()) {
                    *slot = channel;
                    n += 1;
                }
                let order = order.get(..n).unwrap_or(&[]);
                for scan in codes.chunks_exact(n) {
                    for (&channel, &code) in order.iter().zip(scan) {
                        self.add(channel, code);
                    }
                }
            }
        }
    }

    /// The block so far, leaving an empty one (the tick's take).
    pub fn take(&mut self) -> Block {
        core::mem::take(self)
    }

    /// The samples of a channel so far.
    pub fn samples(&self, channel: Channel) -> u32 {
        match channel {
            Channel::Current => self.current.count,
            Channel::Amplifier => self.amplifier.count,
            Channel::Stretch => self.stretch.count,
        }
    }
}

/// What the IO side measured this tick, if anything: the controller's inputs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Inputs {
    /// The displacement sensor's stretch λ.
    pub stretch: Option<f32>,
    /// The amplifier's monitor output, V.
    pub amplifier_volts: Option<f32>,
    /// The amplifier's output current, A, averaged over the tick (its current monitor).
    /// At a constant bias it is Φ·C'(λ)·dλ/dt plus the leakage (model.md §8, the electrical
    /// port): a ring in it has the stretch's frequency. The trim measures it when there is
    /// no stretch sample (self-sensing).
    pub current_amps: Option<f32>,
}

impl Inputs {
    /// Nothing measured.
    pub const NONE: Inputs = Inputs {
        stretch: None,
        amplifier_volts: None,
        current_amps: None,
    };

    /// A stretch sample only.
    pub const fn stretch(stretch: f32) -> Self {
        Inputs {
            stretch: Some(stretch),
            ..Inputs::NONE
        }
    }

    /// A current sample only (no displacement sensor).
    pub const fn current(amps: f32) -> Self {
        Inputs {
            current_amps: Some(amps),
            ..Inputs::NONE
        }
    }
}

/// Why a front end in an image cannot be used.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrontEndError {
    /// The ADC input does not exist, or the board uses its pin for something else.
    Input { channel: Channel, input: u8 },
    /// Two channels on one input.
    SameInput { input: u8 },
    /// The declared noise is negative, NaN or infinite.
    Noise { channel: Channel, noise_codes: f32 },
    /// The scale is zero, NaN or infinite.
    Scale {
        channel: Channel,
        zero_code: f32,
        per_count: f32,
    },
    /// The plausible range is empty, or reaches the rails (its codes given).
    Range {
        channel: Channel,
        low: f32,
        high: f32,
        low_code: f32,
        high_code: f32,
    },
    /// Not a whole number of scans a tick, or more conversions than the ADC makes.
    ScanRate { scan_hz: f32, tick_hz: f32 },
    /// More conversions than the ADC makes on the clock in use.
    AdcClock {
        conversions_hz: f32,
        max_hz: f32,
        adc_clock_hz: f32,
    },
}

impl fmt::Display for FrontEndError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            FrontEndError::Input { channel, input } => write!(
                f,
                "front end: {} channel on ADC input {input}, not an analog input of the board \
                 (IN0, IN1, IN9, IN10..IN15: PA0, PA1, PB1, PC0..PC5)",
                channel.name()
            ),
            FrontEndError::Noise {
                channel,
                noise_codes,
            } => write!(
                f,
                "front end: {} channel's noise_codes {} is not a number of codes ≥ 0",
                channel.name(),
                Decimal(noise_codes)
            ),
            FrontEndError::SameInput { input } => {
                write!(f, "front end: two channels on ADC input {input}")
            }
            FrontEndError::Scale {
                channel,
                zero_code,
                per_count,
            } => write!(
                f,
                "front end: {} channel's scale ({} per count from code {}) must be finite \
                 and not zero",
                channel.name(),
                Decimal(per_count),
                Decimal(zero_code)
            ),
            FrontEndError::Range {
                channel,
                low,
                high,
                low_code,
                high_code,
            } => write!(
                f,
                "front end: {} channel's plausible range [{}, {}] {} is codes {} .. {}: it must \
                 be a range inside codes {} .. {} (a live zero, so an open input is seen)",
                channel.name(),
                Decimal(low),
                Decimal(high),
                channel.unit(),
                Decimal(low_code),
                Decimal(high_code),
                Decimal(RAIL_MARGIN_CODES),
                Decimal(f32::from(FULL_SCALE_CODE) - RAIL_MARGIN_CODES)
            ),
            FrontEndError::ScanRate { scan_hz, tick_hz } => write!(
                f,
                "front end: {} scans/s at a {} Hz tick must be a whole number of scans a tick, \
                 at least 2, that the DMA's buffers divide into at most {MAX_BUFFERS_PER_TICK} \
                 parts, and at most {} conversions/s for all channels",
                Decimal(scan_hz),
                Decimal(tick_hz),
                Decimal(MAX_CONVERSIONS_HZ)
            ),
            FrontEndError::AdcClock {
                conversions_hz,
                max_hz,
                adc_clock_hz,
            } => write!(
                f,
                "front end: {} conversions/s, more than the {} the ADC makes on its {} MHz \
                 clock (the board runs on its fallback oscillator: fix the crystal, or make an \
                 image with a lower scan_hz)",
                Decimal(conversions_hz),
                Decimal(max_hz),
                Decimal(adc_clock_hz / 1.0e6)
            ),
        }
    }
}

impl core::error::Error for FrontEndError {}

/// Why a tick's block gives no reading of a fitted channel: a sensor fault, by name.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum InputError {
    /// No sample since the last tick: the ADC or its DMA stopped.
    NoSamples { channel: Channel },
    /// The acquisition stalled again within `STALL_REPEAT_SECONDS` of a stall it recovered
    /// from: it cannot keep up (this stall's cause; the stalls recovered from before it).
    Stalled { stall: Stall, recovered: u32 },
    /// A code above the ADC's full scale (not from this ADC).
    NotACode { channel: Channel, code: u16 },
    /// The block's mean sits at a rail: open (pulled there), shorted or saturated.
    AtRail { channel: Channel, mean_code: f32 },
    /// The reading is outside the channel's plausible range: miswired, a wrong gain, or a
    /// failed sensor.
    Implausible {
        channel: Channel,
        reading: f32,
        low: f32,
        high: f32,
    },
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            InputError::NoSamples { channel } => write!(
                f,
                "{} input: no sample this tick (the ADC or its DMA stopped)",
                channel.name()
            ),
            InputError::Stalled { stall, recovered } => write!(
                f,
                "the ADC's acquisition stopped again ({}) within {} s of the last stall it was \
                 re-armed from ({recovered} so far): it cannot keep up",
                stall.name(),
                Decimal(STALL_REPEAT_SECONDS)
            ),
            InputError::NotACode { channel, code } => write!(
                f,
                "{} input: code {code} is above the ADC's {FULL_SCALE_CODE}",
                channel.name()
            ),
            InputError::AtRail { channel, mean_code } => write!(
                f,
                "{} input at the ADC's rail (mean code {}): open, shorted or saturated",
                channel.name(),
                Decimal(mean_code)
            ),
            InputError::Implausible {
                channel,
                reading,
                low,
                high,
            } => write!(
                f,
                "{} input reads {} {}, outside its plausible [{}, {}]: miswired, wrong gain \
                 or failed",
                channel.name(),
                Decimal(reading),
                channel.unit(),
                Decimal(low),
                Decimal(high)
            ),
        }
    }
}

impl core::error::Error for InputError {}
