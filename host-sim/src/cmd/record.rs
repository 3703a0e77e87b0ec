//! The board's telemetry stream (`de_resonator::wire::stream`) written to CSV with a header
//! that names what ran (`console --record`, `run --record`); records lost on the way counted
//! from the sequence's gaps and said, never filled in; and drawn (`--plot`).

use std::path::Path;

use de_resonator::wire::stream::{Receiver, Record, VERSION};
use de_resonator::Fault;
use serde::Serialize;

use crate::plot::{self, Panel, Series};

/// What a recording holds, as reported.
#[derive(Serialize, Debug, Clone)]
pub struct Recorded {
    pub file: String,
    pub plot: Option<String>,
    pub records: u64,
    /// Records missing from the sequence between the first and the last read.
    pub lost: u64,
    /// Frames that failed their checks (bytes lost or changed on the way).
    pub bad_frames: u64,
    pub first_tick: Option<u32>,
    pub last_tick: Option<u32>,
}

/// One record as a CSV row: units in the names, empty where nothing was measured.
#[derive(Serialize)]
struct Row {
    sequence: u32,
    tick: u32,
    time_seconds: f64,
    volts: f32,
    dac_code: u16,
    enable: u8,
    phase: &'static str,
    fault: &'static str,
    max_volts: Option<f32>,
    stretch: Option<f32>,
    current_amps: Option<f32>,
    amplifier_volts: Option<f32>,
    sensed_stretch: Option<f32>,
    sensed_sigma: Option<f32>,
    natural_hz: Option<f32>,
    quality_factor: Option<f32>,
    leakage_ohms: Option<f32>,
    bias_volts: Option<f32>,
}

fn finite(x: f32) -> Option<f32> {
    x.is_finite().then_some(x)
}

impl Row {
    fn of(r: &Record, tick_hz: f64) -> Self {
        Row {
            sequence: r.sequence,
            tick: r.tick,
            time_seconds: f64::from(r.tick) / tick_hz,
            volts: r.volts,
            dac_code: r.dac_code,
            enable: u8::from(r.enabled),
            phase: r.phase.map_or("none", |p| p.name()),
            fault: r.fault.and_then(Fault::key_of).unwrap_or(""),
            max_volts: finite(r.max_volts),
            stretch: r.inputs.stretch,
            current_amps: r.inputs.current_amps,
            amplifier_volts: r.inputs.amplifier_volts,
            sensed_stretch: r.sensed.map(|s| s.0),
            sensed_sigma: r.sensed.map(|s| s.1),
            natural_hz: r.resonance.map(|t| t.0),
            quality_factor: r.resonance.map(|t| t.1),
            leakage_ohms: r.leakage_ohms,
            bias_volts: finite(r.bias_volts),
        }
    }
}

/// What a stream's receiver counted over a recording.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    pub records: u64,
    pub lost: u64,
    pub bad_frames: u64,
}

impl Counts {
    pub fn of(receiver: &Receiver) -> Self {
        Counts {
            records: receiver.records,
            lost: receiver.lost,
            bad_frames: receiver.bad_frames,
        }
    }

    /// These counts after `before`'s (a stream read again over a new connection).
    pub fn after(self, before: Counts) -> Self {
        Counts {
            records: before.records + self.records,
            lost: before.lost + self.lost,
            bad_frames: before.bad_frames + self.bad_frames,
        }
    }
}

/// The recording as CSV: `#` header lines (`header`, then the counts), then the rows.
pub fn csv(
    header: &[String],
    records: &[Record],
    counts: Counts,
    tick_hz: f64,
) -> Result<Vec<u8>, String> {
    let mut text = format!("# de-resonator telemetry, record layout {VERSION}\n");
    for line in header {
        text.push_str(&format!("# {line}\n"));
    }
    text.push_str(&format!(
        "# records={} lost={} bad_frames={} (lost records are missing rows, not filled in)\n",
        counts.records, counts.lost, counts.bad_frames
    ));
    let rows: Vec<Row> = records.iter().map(|r| Row::of(r, tick_hz)).collect();
    let mut bytes = text.into_bytes();
    bytes.extend(super::csv(&rows)?);
    if rows.is_empty() {
        // The column names even with no record.
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(COLUMNS).map_err(|e| e.to_string())?;
        bytes.extend(w.into_inner().map_err(|e| e.to_string())?);
    }
    Ok(bytes)
}

/// Write the records to `path` ([`csv`]).
pub fn write(
    path: &Path,
    header: &[String],
    records: &[Record],
    receiver: &Receiver,
    tick_hz: f64,
) -> Result<Recorded, String> {
    let bytes = csv(header, records, Counts::of(receiver), tick_hz)?;
    std::fs::write(path, bytes).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(Recorded {
        file: path.display().to_string(),
        plot: None,
        records: receiver.records,
        lost: receiver.lost,
        bad_frames: receiver.bad_frames,
        first_tick: records.first().map(|r| r.tick),
        last_tick: records.last().map(|r| r.tick),
    })
}

/// The CSV's columns, as `Row` writes them.
const COLUMNS: [&str; 18] = [
    "sequence",
    "tick",
    "time_seconds",
    "volts",
    "dac_code",
    "enable",
    "phase",
    "fault",
    "max_volts",
    "stretch",
    "current_amps",
    "amplifier_volts",
    "sensed_stretch",
    "sensed_sigma",
    "natural_hz",
    "quality_factor",
    "leakage_ohms",
    "bias_volts",
];

/// The recording drawn: the voltage commanded under the cap in force, and the stretch (the
/// sensor's and the probe's λ from C), against time; the records lost said in a note.
pub fn plot(records: &[Record], receiver: &Receiver, tick_hz: f64, title: &str) -> Vec<Panel> {
    let t = |r: &Record| f64::from(r.tick) / tick_hz;
    let series = |name: &str, pick: &dyn Fn(&Record) -> Option<f32>| Series {
        name: name.into(),
        points: records
            .iter()
            .filter_map(|r| pick(r).map(|y| (t(r), f64::from(y))))
            .collect(),
        ..Series::default()
    };
    let cap = series("cap in force", &|r| finite(r.max_volts));
    let cap = Series {
        style: plot::Style {
            colour: Some(plot::RED),
            dashed: true,
            ..plot::Style::default()
        },
        ..cap
    };
    let mut volts = Panel {
        title: format!("{title}: voltage commanded"),
        x_label: "time, s".into(),
        y_label: "V".into(),
        series: vec![series("commanded", &|r| Some(r.volts)), cap],
        notes: vec![
            format!(
                "{} records, {} lost, {} bad frames",
                receiver.records, receiver.lost, receiver.bad_frames
            ),
            aliasing(records, tick_hz),
        ],
        ..Panel::default()
    };
    let mut stretch = Panel {
        title: "stretch".into(),
        x_label: "time, s".into(),
        y_label: "stretch λ".into(),
        series: vec![
            series("sensor", &|r| r.inputs.stretch),
            series("from C", &|r| r.sensed.map(|s| s.0)),
        ],
        ..Panel::default()
    };
    for panel in [&mut volts, &mut stretch] {
        panel.series.retain(|s| !s.points.is_empty());
    }
    let mut panels = vec![volts];
    if !stretch.series.is_empty() {
        panels.push(stretch);
    }
    panels
}

/// The note a record rate needs: motion faster than half of it (a drive, a ring) is drawn
/// aliased, as a slower wave or none.
fn aliasing(records: &[Record], tick_hz: f64) -> String {
    let mut gaps: Vec<u32> = records
        .windows(2)
        .map(|w| w[1].tick.wrapping_sub(w[0].tick))
        .filter(|&g| g > 0)
        .collect();
    gaps.sort_unstable();
    match gaps.get(gaps.len() / 2) {
        Some(&ticks) => {
            let hz = tick_hz / f64::from(ticks);
            format!(
                "a record every {ticks} ticks ({} Hz): motion above {} Hz is drawn aliased",
                crate::cmd::sig(hz),
                crate::cmd::sig(hz / 2.0)
            )
        }
        None => "too few records for their rate".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use de_resonator::Inputs;

    /// The column names written for an empty recording are the rows' own.
    #[test]
    fn the_columns_are_the_rows_header() {
        let record = Record {
            sequence: 0,
            tick: 0,
            volts: 0.0,
            dac_code: 0,
            enabled: false,
            phase: None,
            fault: None,
            max_volts: f32::NAN,
            inputs: Inputs::NONE,
            sensed: None,
            resonance: None,
            leakage_ohms: None,
            bias_volts: f32::NAN,
        };
        let bytes = super::super::csv(&[Row::of(&record, 1000.0)]).unwrap();
        let header = String::from_utf8(bytes).unwrap();
        assert_eq!(header.lines().next(), Some(COLUMNS.join(",").as_str()));
    }
}
