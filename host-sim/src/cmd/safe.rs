//! `safe` and `tune`: where the loading branch fails first, the frequencies reachable before
//! it, and the smallest bias for a target (model.md §§5–7).

use std::fmt;

use clap::Args;
use de_resonator::{table, Equilibrium, Tuner};
use serde::Serialize;

use super::{short, sig, DeviceArgs, DeviceInfo, MarginArgs, Report};

#[derive(Args, Debug)]
pub struct SafeArgs {
    #[command(flatten)]
    pub device: DeviceArgs,
    #[command(flatten)]
    pub margin: MarginArgs,
}

#[derive(Args, Debug)]
pub struct TuneArgs {
    /// Target natural frequency, Hz.
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub target_hz: f64,
    #[command(flatten)]
    pub device: DeviceArgs,
    #[command(flatten)]
    pub margin: MarginArgs,
}

/// An equilibrium on the loading branch, for the limit.
#[derive(Serialize, Debug)]
pub struct LimitReport {
    pub mode: &'static str,
    pub volts: f64,
    pub stretch: f64,
    pub natural_frequency_hz: f64,
    #[serde(skip)]
    description: &'static str,
}

/// The margin whose highest bias ends the tunable range, for the margin `margin`: the
/// board's table stops [`table::HEADROOM`] below (1 − margin)·Φlimit (its f32 check of the
/// limit must never refuse it), so the targets the board takes are the natural frequencies
/// of the biases from 0 V to (1 − margin)(1 − HEADROOM)·Φlimit. One rule: `safe`, `tune`,
/// `curve`, the live page, Python and the board's table (`info`'s `tunable_*_hz`) all use it.
pub fn targets_margin(margin: f64) -> f64 {
    table::table_margin(margin)
}

/// The safe region: what `safe` reports, and `tune` before its target.
#[derive(Serialize, Debug)]
pub struct Region {
    pub device: DeviceInfo,
    pub zero_bias_frequency_hz: f64,
    #[serde(skip)]
    zero_bias_stretch: f64,
    pub limit: LimitReport,
    pub margin: f64,
    pub max_bias_volts: f64,
    #[serde(skip)]
    max_bias_stretch: f64,
    pub tunable_range_hz: [f64; 2],
}

impl Region {
    pub fn new(device: DeviceInfo, tuner: &Tuner<f64>, margin: f64) -> Result<Self, String> {
        let max_bias = tuner.max_bias(margin).map_err(|e| e.to_string())?;
        let range = tuner
            .tunable_range(targets_margin(margin))
            .map_err(|e| e.to_string())?;
        let limit = tuner.limit();
        let zero = tuner.zero_bias();
        Ok(Self {
            device,
            zero_bias_frequency_hz: zero.natural_frequency_hz,
            zero_bias_stretch: zero.stretch,
            limit: LimitReport {
                mode: limit.mode.name(),
                volts: limit.at.volts,
                stretch: limit.at.stretch,
                natural_frequency_hz: limit.at.natural_frequency_hz,
                description: limit.mode.description(),
            },
            margin,
            max_bias_volts: max_bias.volts,
            max_bias_stretch: max_bias.stretch,
            tunable_range_hz: [range.low_hz, range.high_hz],
        })
    }
}

impl Region {
    /// Whether the range is empty or of zero width (within 1e-6): the limit is at or near
    /// 0 V, and no bias tunes anything.
    pub fn range_is_empty(&self) -> bool {
        let [low, high] = self.tunable_range_hz;
        !(high - low > 1e-6 * high.abs())
    }

    /// The tunable range as said: `low .. high Hz`, or why there is none.
    fn range_said(&self) -> String {
        let [low, high] = self.tunable_range_hz;
        if self.range_is_empty() {
            format!(
                "none: only {} Hz, the {} limit closes it at {} V",
                sig(low),
                self.limit.mode,
                sig(self.limit.volts)
            )
        } else {
            format!("{} .. {} Hz", sig(low), sig(high))
        }
    }
}

impl fmt::Display for Region {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let l = &self.limit;
        write!(
            f,
            "device          {}\n\
             zero bias       f = {} Hz at stretch {}\n\
             limit           {}: {}\n\
             \x20               at {} V, stretch {}, f = {} Hz\n\
             margin {:<8} bias at most {} V (stretch {})\n\
             tunable range   {}",
            self.device,
            sig(self.zero_bias_frequency_hz),
            sig(self.zero_bias_stretch),
            l.mode,
            l.description,
            sig(l.volts),
            sig(l.stretch),
            sig(l.natural_frequency_hz),
            short(self.margin),
            sig(self.max_bias_volts),
            sig(self.max_bias_stretch),
            self.range_said(),
        )
    }
}

impl Report for Region {}

/// What `tune` reports: the region, the target and its bias.
#[derive(Serialize, Debug)]
pub struct TuneReport {
    #[serde(flatten)]
    pub region: Region,
    pub target_hz: f64,
    pub bias_volts: f64,
    pub stretch: f64,
    pub natural_frequency_hz: f64,
}

impl fmt::Display for TuneReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}\n\ntarget          {} Hz\nbias            {} V (stretch {}, f = {} Hz)",
            self.region,
            sig(self.target_hz),
            sig(self.bias_volts),
            sig(self.stretch),
            sig(self.natural_frequency_hz),
        )
    }
}

impl Report for TuneReport {}

pub fn safe(args: &SafeArgs) -> Result<Region, String> {
    let (tuner, name) = args.device.tuner()?;
    Region::new(name, &tuner, args.margin.margin)
}

pub fn tune(args: &TuneArgs) -> Result<TuneReport, String> {
    let (tuner, name) = args.device.tuner()?;
    let margin = args.margin.margin;
    let region = Region::new(name, &tuner, margin)?;
    let bias: Equilibrium<f64> = tuner
        .tune(args.target_hz, targets_margin(margin))
        .map_err(|e| format!("{e} (margin {margin})"))?;
    Ok(TuneReport {
        region,
        target_hz: args.target_hz,
        bias_volts: bias.volts,
        stretch: bias.stretch,
        natural_frequency_hz: bias.natural_frequency_hz,
    })
}
