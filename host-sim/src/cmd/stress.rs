//! `stress`: the stiff and extreme cases with every core method in f32 and f64 at several
//! steps, against the reference; a run that fails silently fails the command (exit 1).

use std::fmt;

use clap::Args;
use serde::Serialize;

use super::{DeviceArgs, Report};
use crate::stress::{self, CaseReport, Summary, Verdict, PERIODS, STEPS_PER_PERIOD};

#[derive(Args, Debug)]
pub struct StressArgs {
    /// Device the cases are built on. Default: the reference device.
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// What `stress` reports.
#[derive(Serialize, Debug)]
pub struct StressReport {
    pub periods: f64,
    pub summary: Summary,
    pub cases: Vec<CaseReport>,
}

impl fmt::Display for StressReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "case                 method                    ")?;
        for n in STEPS_PER_PERIOD {
            write!(f, "{:>24}", format!("{n}/period"))?;
        }
        writeln!(f)?;
        for case in &self.cases {
            for chunk in case.runs.chunks(STEPS_PER_PERIOD.len()) {
                let method = chunk.first().map_or("", |r| r.method);
                write!(f, "{:<21}{:<26}", case.case, method)?;
                for run in chunk {
                    let cell = match run.final_error_over_swing {
                        Some(e) => format!("{} {e:.1e}", run.verdict.name()),
                        None => run.verdict.name().to_string(),
                    };
                    write!(f, "{cell:>24}")?;
                }
                writeln!(f)?;
            }
        }
        let s = &self.summary;
        write!(
            f,
            "\nsummary: {} runs: {} stable, {} refused, {} stopped, {} missed a crossing, \
             {} failed silently",
            s.runs, s.stable, s.refused, s.stopped, s.missed_crossing, s.failed_silently
        )
    }
}

impl Report for StressReport {
    fn failure(&self) -> Option<String> {
        let silent = self
            .cases
            .iter()
            .flat_map(|c| &c.runs)
            .any(|r| r.verdict == Verdict::FailedSilently);
        silent.then(|| "a stress run failed silently".to_string())
    }
}

pub fn stress(args: &StressArgs) -> Result<StressReport, String> {
    let (params, name) = args.device.params()?;
    let (cases, summary) = stress::run(params).map_err(|e| format!("{name}: {e}"))?;
    Ok(StressReport {
        periods: PERIODS,
        summary,
        cases,
    })
}
