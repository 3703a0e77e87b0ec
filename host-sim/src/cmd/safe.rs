//! `safe` and `tune`: where the loading branch fails first, the frequencies reachable before
//! it, and the smallest bias for a target (model.md §§5–7).

use std::fmt;

use std::collections::BTreeMap;

use clap::Args;
use de_resonator::model::guaranteed::Leaf;
use de_resonator::model::tolerance::DeviceBox;
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

/// The leaves a batch's searches may use (model.md §10): enough for boxes of up to eight
/// parameters at ±15% to come within 1% (BENCHMARKS.md).
pub const SEARCH_LEAVES: usize = 4096;

/// Storage for a batch's searches.
pub fn search_leaves() -> Vec<Leaf> {
    vec![Leaf::default(); SEARCH_LEAVES]
}

/// What holds for every device within the device file's tolerances (model.md §10).
#[derive(Serialize, Debug)]
pub struct Guaranteed {
    pub limit: GuaranteedLimitReport,
    /// (1 − margin) times the guaranteed limit.
    pub max_bias_volts: f64,
    /// The targets every device reaches at a bias of at most the guaranteed cap (less the
    /// table's headroom, as the nominal range); `null` when the devices' ranges do not meet.
    pub tunable_range_hz: Option<[f64; 2]>,
}

/// The guaranteed limit: no device within the tolerances fails below `volts` (certified);
/// the lowest limit the search found, its mode, and the device it found it on.
#[derive(Serialize, Debug)]
pub struct GuaranteedLimitReport {
    pub volts: f64,
    pub mode: &'static str,
    /// The toleranced parameters of the device with the lowest limit found.
    pub at: BTreeMap<&'static str, f64>,
    pub lowest_found_volts: f64,
    #[serde(skip)]
    description: &'static str,
}

impl Guaranteed {
    /// For the batch `b` at the margin `margin`; `None` for the nominal device alone.
    pub fn of(b: &DeviceBox, margin: f64) -> Result<Option<Self>, String> {
        if b.is_exact() {
            return Ok(None);
        }
        let mut leaves = search_leaves();
        let g = b.guaranteed_limit(&mut leaves).map_err(|e| e.to_string())?;
        let top = (1.0 - targets_margin(margin)) * g.volts;
        let range = b
            .tunable_range_hz(top, &mut leaves)
            .map_err(|e| e.to_string())?;
        Ok(Some(Self {
            limit: GuaranteedLimitReport {
                volts: g.volts,
                mode: g.mode.name(),
                at: b.spread_fields().map(|f| (f.key(), g.at.get(f))).collect(),
                lowest_found_volts: g.lowest_found_volts,
                description: g.mode.description(),
            },
            max_bias_volts: (1.0 - margin) * g.volts,
            tunable_range_hz: range.map(|(low, high)| [low, high]),
        }))
    }
}

impl fmt::Display for Guaranteed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let l = &self.limit;
        let at: Vec<String> =
            l.at.iter()
                .map(|(k, v)| format!("{k} {}", sig(*v)))
                .collect();
        let range = match self.tunable_range_hz {
            Some([low, high]) => format!("{} .. {} Hz", sig(low), sig(high)),
            None => "none (the devices' ranges do not meet)".into(),
        };
        write!(
            f,
            "guaranteed      every device within the tolerances is safe below {} V\n\
             \x20               lowest limit found {} V, {}: {}\n\
             \x20               at {}\n\
             \x20               bias at most {} V; targets every device reaches: {}",
            sig(l.volts),
            sig(l.lowest_found_volts),
            l.mode,
            l.description,
            at.join(", "),
            sig(self.max_bias_volts),
            range
        )
    }
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
    /// For a device file with tolerances: what holds for every device of the batch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub guaranteed: Option<Guaranteed>,
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
            guaranteed: None,
        })
    }

    /// The region of the batch `b`'s nominal device, with what holds for every device.
    pub fn of_batch(
        device: DeviceInfo,
        tuner: &Tuner<f64>,
        b: &DeviceBox,
        margin: f64,
    ) -> Result<Self, String> {
        Ok(Self {
            guaranteed: Guaranteed::of(b, margin)?,
            ..Self::new(device, tuner, margin)?
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
        )?;
        if let Some(tolerance) = &self.device.tolerance {
            let said: Vec<String> = tolerance
                .iter()
                .map(|(k, [low, high])| format!("{k} {} .. {}", sig(*low), sig(*high)))
                .collect();
            write!(f, "\ntolerances      {}", said.join(", "))?;
        }
        if let Some(g) = &self.guaranteed {
            write!(f, "\n{g}")?;
        }
        Ok(())
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
    /// With tolerances: the natural frequencies the batch's devices have at this bias.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub band_hz: Option<[f64; 2]>,
    /// With tolerances: whether every device reaches the target at some safe bias (the
    /// target inside the guaranteed tunable range).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub every_device_reaches: Option<bool>,
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
        )?;
        if let Some([low, high]) = self.band_hz {
            write!(
                f,
                "\nband            {} .. {} Hz: the batch's devices at this bias",
                sig(low),
                sig(high)
            )?;
        }
        if self.every_device_reaches == Some(false) {
            write!(
                f,
                "\n                only some devices of the batch reach {} Hz below the \
                 guaranteed cap",
                sig(self.target_hz)
            )?;
        }
        Ok(())
    }
}

impl Report for TuneReport {}

pub fn safe(args: &SafeArgs) -> Result<Region, String> {
    let (b, tuner, name) = args.device.source().batch_tuner()?;
    Region::of_batch(name, &tuner, &b, args.margin.margin)
}

pub fn tune(args: &TuneArgs) -> Result<TuneReport, String> {
    let (b, tuner, name) = args.device.source().batch_tuner()?;
    tune_batch(name, &tuner, &b, args.target_hz, args.margin.margin)
}

/// A target tuned on a batch's nominal device, checked against the batch.
pub struct Tuned {
    pub bias: Equilibrium<f64>,
    /// The batch's natural frequencies at the bias (with tolerances).
    pub band_hz: Option<[f64; 2]>,
    /// Whether the target lies in the guaranteed tunable range (with tolerances).
    pub every_device_reaches: Option<bool>,
}

/// The nominal device's smallest bias for `target_hz`; with tolerances (`guaranteed` given),
/// refused above the guaranteed cap, and the band the batch's devices have at it.
pub fn tune_in_batch(
    tuner: &Tuner<f64>,
    b: &DeviceBox,
    guaranteed: Option<&Guaranteed>,
    target_hz: f64,
    margin: f64,
) -> Result<Tuned, String> {
    let bias: Equilibrium<f64> = tuner
        .tune(target_hz, targets_margin(margin))
        .map_err(|e| format!("{e} (margin {margin})"))?;
    let Some(g) = guaranteed else {
        return Ok(Tuned {
            bias,
            band_hz: None,
            every_device_reaches: None,
        });
    };
    // The bias the batch's nominal device needs, safe for every device or refused.
    let top = (1.0 - targets_margin(margin)) * g.limit.volts;
    if bias.volts > top {
        return Err(format!(
            "target {} Hz needs {} V on the nominal device, above the guaranteed cap {} V \
             (the weakest device within the tolerances fails at {} V, {}); {}",
            sig(target_hz),
            sig(bias.volts),
            sig(top),
            sig(g.limit.volts),
            g.limit.mode,
            match g.tunable_range_hz {
                Some([low, high]) => format!(
                    "every device reaches {} .. {} Hz below it",
                    sig(low),
                    sig(high)
                ),
                None => "no target is reached by every device below it".into(),
            }
        ));
    }
    let band = b
        .band_hz(bias.volts, &mut search_leaves())
        .map_err(|e| e.to_string())?;
    Ok(Tuned {
        bias,
        band_hz: Some([band.low_hz, band.high_hz]),
        every_device_reaches: Some(
            g.tunable_range_hz
                .is_some_and(|[low, high]| (low..=high).contains(&target_hz)),
        ),
    })
}

/// `tune` for the batch `b` whose nominal device `tuner` holds (host-sim and Python): the
/// region with what holds for the batch, and [`tune_in_batch`]'s answer.
pub fn tune_batch(
    name: DeviceInfo,
    tuner: &Tuner<f64>,
    b: &DeviceBox,
    target_hz: f64,
    margin: f64,
) -> Result<TuneReport, String> {
    let region = Region::of_batch(name, tuner, b, margin)?;
    let tuned = tune_in_batch(tuner, b, region.guaranteed.as_ref(), target_hz, margin)?;
    let bias = tuned.bias;
    let (band_hz, every_device_reaches) = (tuned.band_hz, tuned.every_device_reaches);
    Ok(TuneReport {
        region,
        target_hz,
        bias_volts: bias.volts,
        stretch: bias.stretch,
        natural_frequency_hz: bias.natural_frequency_hz,
        band_hz,
        every_device_reaches,
    })
}
