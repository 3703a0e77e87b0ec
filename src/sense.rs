//! The stretch from the membrane's capacitance (MODEL.md §8, self-sensing): a square probe
//! of ±p volts rides on the bias, its sign flipping every few ticks; the charge the
//! amplifier delivers over each half period is C·ΔΦ (ΔΦ ≈ ±2p) plus the leakage, the bias's
//! drift and the motion's Φ·ΔC. Over a block of four halves, each half's charge and voltage
//! change are summed times its probe sign and the weights 1, 3, 3, 1: the probe's part adds
//! up (8 times a half's), while whatever is smooth across the block cancels to its third
//! difference (the weights annihilate a quadratic), the AC drive's motion included. The sums'
//! ratio is C; C(λ) = C1·λ² gives λ; the blocks' scatter gives its uncertainty.
//!
//! The leakage Φ/R moves with the probe's sign too: it is taken out given the leakage
//! watch's conductance (`set_conductance`; n·T/(2RC) of C otherwise, 6e-7 for a 1 TΩ
//! membrane at 1 kHz). The motion the probe drives itself is not seen: the charge is read at
//! the probe's edges, where an undamped oscillator's antiperiodic response to a square
//! force passes through its mean (x(0) = e − e = 0 in the periodic solution
//! x = e + A·cos ω0t + B·sin ω0t, e = F/ω0²), whatever ω0; an amplifier's lag shifts the
//! force against the edges and lets some through (−3e-4 of λ with host-sim's 2 kHz
//! amplifier at a 1 kHz tick: README). What it cannot see: an error in
//! the flashed ε, L1A, L2, λ2p or H (λ scales as C1^−½). The estimate is the window's mean
//! stretch; an AC drive's swing within the window widens it through the blocks' scatter.

use crate::device::Device;

/// How long a window of blocks lasts at least, s: the estimate's rate.
pub const PROBE_WINDOW_SECONDS: f32 = 0.1;

/// Fewest blocks in a window (the scatter needs some).
pub const MIN_BLOCKS: u32 = 8;

/// A block's weights, by half: the binomial (1 + z)³, zero at the probe's frequency to
/// third order after the probe's sign is taken out.
const WEIGHTS: [f32; 4] = [1.0, 3.0, 3.0, 1.0];

/// How many standard errors widen the estimate before the monitor's check: 4, as the window
/// after a ramp stops (the ring and a fast creep in it) was 3.3 off (`sensorless-vhb`).
pub const PROBE_SIGMAS: f32 = 4.0;

/// One window's estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SensedStretch {
    /// λ from C, the window's mean.
    pub stretch: f32,
    /// Its standard error, from the blocks' scatter.
    pub sigma: f32,
    /// The capacitance measured, F.
    pub farads: f32,
    /// The mean voltage at the blocks' ends, V.
    pub volts: f32,
}

impl SensedStretch {
    /// The estimate widened by `PROBE_SIGMAS` standard errors: (low, high).
    pub fn widened(&self) -> (f32, f32) {
        let w = PROBE_SIGMAS * self.sigma;
        (self.stretch - w, self.stretch + w)
    }
}

/// A block's weighted sums of charge and voltage change so far, C and V, and its halves.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Block {
    coulombs: f32,
    volts: f32,
    /// Σ Φ·dt, the leakage's part per siemens, V·s.
    volt_seconds: f32,
    halves: usize,
}

/// The window's sums over blocks: d = y − c0·x about a reference c0 (y and x a block's
/// weighted charge and voltage), so that f32 keeps the scatter's digits.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Sums {
    blocks: u32,
    d: f32,
    dd: f32,
    x: f32,
    z: f32,
    volts: f32,
}

/// The lock-in between ticks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeLockIn {
    /// C1 = C/λ² of the device flashed, F.
    farads_per_stretch_squared: f32,
    blocks_per_window: u32,
    tick_seconds: f32,
    /// The leakage conductance taken out, S.
    siemens: f32,
    /// The half being summed: its charge and Σ Φ·dt so far, and the voltage at its start
    /// (`None`: the first half's start is not yet seen).
    charge: f32,
    volt_seconds: f32,
    start_volts: Option<f32>,
    block: Block,
    /// The reference c0, F: the last window's C (the first block's ratio before any).
    reference: Option<f32>,
    sums: Sums,
    last: Option<SensedStretch>,
}

impl ProbeLockIn {
    /// A lock-in for `device`, its probe at `probe_hz`, ticking at `tick_hz`.
    pub fn new(device: &Device<f32>, probe_hz: f32, tick_hz: f32) -> Self {
        let blocks = libm::ceilf(0.5 * PROBE_WINDOW_SECONDS * probe_hz) as u32;
        Self {
            farads_per_stretch_squared: device.params().farads_per_stretch_squared(),
            blocks_per_window: blocks.max(MIN_BLOCKS),
            tick_seconds: 1.0 / tick_hz,
            siemens: 0.0,
            charge: 0.0,
            volt_seconds: 0.0,
            start_volts: None,
            block: Block::default(),
            reference: None,
            sums: Sums::default(),
            last: None,
        }
    }

    /// The last window's estimate.
    pub fn last(&self) -> Option<SensedStretch> {
        self.last
    }

    /// Start again (the probe was off): the halves are summed from the next edge.
    pub fn restart(&mut self) {
        *self = Self {
            charge: 0.0,
            volt_seconds: 0.0,
            start_volts: None,
            block: Block::default(),
            sums: Sums::default(),
            ..*self
        };
    }

    /// The leakage conductance to take out (the leakage watch's), S.
    pub fn set_conductance(&mut self, siemens: f32) {
        self.siemens = siemens;
    }

    /// One tick's current (over the tick before, A) and the voltage at the tick's end (the
    /// command held over it, V); `edge`: a half ends here, and whether it was the + one. At
    /// a window's end, its estimate.
    pub fn observe(&mut self, amps: f32, volts: f32, edge: Option<bool>) -> Option<SensedStretch> {
        self.charge += amps * self.tick_seconds;
        self.volt_seconds += volts * self.tick_seconds;
        let positive = edge?;
        let start = self.start_volts.replace(volts);
        let coulombs = core::mem::take(&mut self.charge);
        let volt_seconds = core::mem::take(&mut self.volt_seconds);
        let start = start?;
        let b = &mut self.block;
        let weight = WEIGHTS.get(b.halves).copied().unwrap_or(0.0);
        let weight = if positive { weight } else { -weight };
        b.coulombs += weight * coulombs;
        b.volts += weight * (volts - start);
        b.volt_seconds += weight * volt_seconds;
        b.halves += 1;
        if b.halves < WEIGHTS.len() {
            return None;
        }
        let block = core::mem::take(&mut self.block);
        self.add(block, volts)
    }

    /// A block summed; at the window's end, its estimate.
    fn add(&mut self, block: Block, volts: f32) -> Option<SensedStretch> {
        let (y, x) = (block.coulombs, block.volts);
        let c0 = *self.reference.get_or_insert(y / x);
        let d = y - c0 * x;
        let s = &mut self.sums;
        s.blocks += 1;
        s.d += d;
        s.dd += d * d;
        s.x += x;
        s.z += block.volt_seconds;
        s.volts += volts;
        if s.blocks < self.blocks_per_window {
            return None;
        }
        let n = s.blocks as f32;
        let farads = c0 + (s.d - self.siemens * s.z) / s.x;
        let variance = ((s.dd - s.d * s.d / n) / (n - 1.0)).max(0.0);
        let sigma_farads = libm::sqrtf(variance * n) / s.x.abs();
        let stretch = libm::sqrtf(farads / self.farads_per_stretch_squared);
        let estimate = SensedStretch {
            stretch,
            // dλ/λ = dC/(2C).
            sigma: 0.5 * stretch * sigma_farads / farads,
            farads,
            volts: s.volts / n,
        };
        self.sums = Sums::default();
        if farads.is_finite() && farads > 0.0 {
            self.reference = Some(farads);
        }
        self.last = Some(estimate);
        Some(estimate)
    }
}
