//! The stretch from the membrane's capacitance (model.md §8, self-sensing): a square probe
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

use crate::model::device::Device;

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

    /// Start again (the probe was off): the halves are summed from the next edge (the half
    /// under way, its start unknown, is dropped there with its charge).
    pub fn restart(&mut self) {
        *self = Self {
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

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::indexing_slicing)] // a test fails by panicking
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::model::device::REFERENCE_DEVICE;

    /// The reference device as the firmware holds it.
    fn device() -> Device<f32> {
        Device::new(REFERENCE_DEVICE.cast()).unwrap_or_else(|_| unreachable!())
    }

    /// A membrane under a ±`probe` square (`half` ticks a half, at 1 kHz) on a bias ramping
    /// `ramp` V a tick from 3 kV, read by `lock`: each tick's current is the charge C·ΔΦ of
    /// its voltage step (C the half's, `farads(n)` for the half ending at edge n) and the
    /// leakage `siemens`·Φ. The estimates, each with the edge it came at, and the voltages at
    /// the edges.
    fn feed(
        lock: &mut ProbeLockIn,
        edges: u32,
        half: u32,
        ramp: f32,
        farads: impl Fn(u32) -> f32,
        siemens: f32,
    ) -> (Vec<(u32, SensedStretch)>, Vec<f32>) {
        let tick = 1e-3f32;
        let volts_at = |i: u32| {
            let sign = if (i / half).is_multiple_of(2) {
                1.0
            } else {
                -1.0
            };
            3000.0 + ramp * i as f32 + 20.0 * sign
        };
        let (mut estimates, mut at_edges) = (Vec::new(), Vec::new());
        let mut edge = 0;
        for i in 1..=edges * half {
            let (before, now) = (volts_at(i - 1), volts_at(i));
            let flipped = (i % half) == 0;
            if flipped {
                edge += 1;
            }
            let amps = farads(edge) * (now - before) / tick + siemens * now;
            // The half that ends here was the + one when the voltage came down.
            let ended = flipped.then_some(now < before);
            if flipped {
                at_edges.push(now);
            }
            if let Some(estimate) = lock.observe(amps, now, ended) {
                estimates.push((edge, estimate));
            }
        }
        (estimates, at_edges)
    }

    /// A still membrane reads C and λ = √(C/C1) to f32's digits, its σ 0, under a ramp; the
    /// voltage reported is the mean at the blocks' ends.
    #[test]
    fn a_still_membrane_reads_c_and_the_mean_voltage() {
        let d = device();
        let c1 = d.params().farads_per_stretch_squared();
        let farads = c1 * 2.1 * 2.1;
        let mut lock = ProbeLockIn::new(&d, 500.0, 1000.0);
        let (estimates, at_edges) = feed(&mut lock, 101, 2, 0.5, |_| farads, 0.0);
        let (edge, e) = estimates[0];
        assert_eq!(edge, 101);
        assert!((e.farads / farads - 1.0).abs() < 1e-5, "{e:?}");
        assert!((e.stretch / 2.1 - 1.0).abs() < 1e-5, "{e:?}");
        assert!(e.sigma.abs() < 1e-5, "{e:?}");
        // The blocks end at edges 5, 9, …, 101.
        let ends: Vec<f32> = (1..=25).map(|b| at_edges[4 * b]).collect();
        let mean = ends.iter().sum::<f32>() / 25.0;
        assert!((e.volts - mean).abs() < 1e-3, "{} against {mean}", e.volts);
    }

    /// A window is max(⌈0.05·probe_hz⌉, 8) blocks of four halves after the first edge: the
    /// estimate comes at exactly that edge, not one block sooner or later.
    #[test]
    fn a_window_is_its_blocks_exactly() {
        let d = device();
        let farads = d.params().farads_per_stretch_squared() * 4.0;
        for (probe_hz, blocks) in [(500.0, 25), (160.0, 8), (100.0, 8), (330.0, 17)] {
            let mut lock = ProbeLockIn::new(&d, probe_hz, 1000.0);
            let (estimates, _) = feed(&mut lock, 4 * blocks + 9, 1, 0.0, |_| farads, 0.0);
            assert_eq!(
                estimates.first().map(|e| e.0),
                Some(4 * blocks + 1),
                "{probe_hz}"
            );
            assert_eq!(estimates.len(), 1, "{probe_hz}");
        }
    }

    /// The standard error is that of the blocks' mean C: blocks alternating C(1 ± e) give
    /// C, and σ(C) = C·e/√(n − 1) over n blocks (the sample variance n/(n − 1)·(Ce)² over n),
    /// halved relative for λ.
    #[test]
    fn the_standard_error_is_the_blocks_scatter() {
        let d = device();
        let c = d.params().farads_per_stretch_squared() * 4.0;
        let e = 1e-3;
        let mut lock = ProbeLockIn::new(&d, 100.0, 1000.0);
        // The first edge starts the first half: the half ending at edge n is block (n − 2)/4.
        let block_of = |edge: u32| (edge.max(2) - 2) / 4;
        let farads = |edge: u32| {
            if block_of(edge).is_multiple_of(2) {
                c * (1.0 + e)
            } else {
                c * (1.0 - e)
            }
        };
        let (estimates, _) = feed(&mut lock, 33, 3, 0.0, farads, 0.0);
        let (_, got) = estimates[0];
        assert!((got.farads / c - 1.0).abs() < 1e-5, "{got:?}");
        let sigma = 0.5 * got.stretch * e / 7.0f32.sqrt();
        assert!(
            (got.sigma / sigma - 1.0).abs() < 1e-2,
            "{got:?} against {sigma}"
        );
    }

    /// The leakage's part (G·Φ over each half) is taken out exactly given the conductance;
    /// without it, C reads high.
    #[test]
    fn the_leakage_given_is_taken_out() {
        let d = device();
        let c = d.params().farads_per_stretch_squared() * 4.0;
        let siemens = 1e-9;
        let mut with = ProbeLockIn::new(&d, 500.0, 1000.0);
        with.set_conductance(siemens);
        let (estimates, _) = feed(&mut with, 101, 4, 0.0, |_| c, siemens);
        assert!(
            (estimates[0].1.farads / c - 1.0).abs() < 1e-5,
            "{estimates:?}"
        );
        let mut without = ProbeLockIn::new(&d, 500.0, 1000.0);
        let (estimates, _) = feed(&mut without, 101, 4, 0.0, |_| c, siemens);
        assert!(
            (estimates[0].1.farads / c - 1.0).abs() > 1e-3,
            "{estimates:?}"
        );
    }

    /// The reference c0 (kept so that f32 holds the scatter's digits) follows the last
    /// window whose C is a positive number: after a window at C, one at 4·C, and one where a
    /// half's charge is infinite (its C too), a window at 4·C(1 ± 1e-4) by block reads its C
    /// and the standard error of its blocks' scatter (4·C·1e-4/√24 in C), which a reference
    /// left at C or taken from the infinite window would lose.
    #[test]
    fn the_reference_follows_the_last_good_window() {
        let d = device();
        let c = d.params().farads_per_stretch_squared();
        let e = 1e-4;
        // The half ending at edge n is in block (n − 2)/4, window block/25.
        let window = |edge: u32| (edge.max(2) - 2) / 4 / 25;
        let farads = |edge: u32| match window(edge) {
            0 => c,
            1 => 4.0 * c,
            2 if edge == 250 => f32::INFINITY,
            2 => 4.0 * c,
            _ if ((edge - 2) / 4).is_multiple_of(2) => 4.0 * c * (1.0 + e),
            _ => 4.0 * c * (1.0 - e),
        };
        let mut lock = ProbeLockIn::new(&d, 500.0, 1000.0);
        let (estimates, _) = feed(&mut lock, 401, 1, 0.0, farads, 0.0);
        let ends: Vec<u32> = estimates.iter().map(|e| e.0).collect();
        assert_eq!(ends, [101, 201, 301, 401]);
        assert!(!(estimates[2].1.farads.is_finite()), "{estimates:?}");
        let last = estimates[3].1;
        assert!((last.stretch / 2.0 - 1.0).abs() < 1e-5, "{last:?}");
        let sigma = 0.5 * last.stretch * e / 24.0f32.sqrt();
        assert!(
            (last.sigma / sigma - 1.0).abs() < 0.05,
            "{last:?} against {sigma}"
        );
    }

    /// `restart` forgets the halves and blocks summed (the probe was off): a window begun at
    /// another capacitance, then a restart, reads the new one exactly.
    #[test]
    fn restart_forgets_what_was_summed() {
        let d = device();
        let c1 = d.params().farads_per_stretch_squared();
        let mut lock = ProbeLockIn::new(&d, 500.0, 1000.0);
        let (none, _) = feed(&mut lock, 51, 1, 0.0, |_| c1 * 9.0, 0.0);
        assert!(none.is_empty());
        lock.restart();
        let (estimates, _) = feed(&mut lock, 101, 1, 0.0, |_| c1 * 4.0, 0.0);
        assert_eq!(estimates.first().map(|e| e.0), Some(101));
        assert!((estimates[0].1.stretch - 2.0).abs() < 1e-5, "{estimates:?}");
    }
}
