//! `stress`: the stiff and extreme cases with every core method in f32 and f64 at several
//! steps, against the reference; a run that fails silently fails the command (exit 1).

use std::fmt;

use clap::Args;
use serde::Serialize;

use super::{DeviceArgs, DeviceInfo, Report};
use crate::study::stiff_cases::{self, CaseReport, Summary, Verdict, PERIODS, STEPS_PER_PERIOD};

#[derive(Args, Debug)]
pub struct StressArgs {
    /// Device the cases are built on. Default: the reference device.
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// What `stress` reports.
#[derive(Serialize, Debug)]
pub struct StressReport {
    pub device: DeviceInfo,
    pub periods: f64,
    pub summary: Summary,
    pub cases: Vec<CaseReport>,
}

impl fmt::Display for StressReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "device          {}", self.device)?;
        write!(f, "case                 method                    ")?;
        for n in STEPS_PER_PERIOD {
            write!(f, "{:>24}", format!("{n}/period"))?;
        }
        writeln!(f)?;
        for case in &self.cases {
            if let Some(problem) = &case.problem {
                writeln!(f, "{:<21}no runs: {problem}", case.case)?;
            }
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
             {} failed silently; {} cases without a reference",
            s.runs,
            s.stable,
            s.refused,
            s.stopped,
            s.missed_crossing,
            s.failed_silently,
            s.cases_without_reference
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
        let broken: Vec<String> = self
            .cases
            .iter()
            .filter_map(|c| Some(format!("{}: {}", c.case, c.problem.as_ref()?)))
            .collect();
        match (silent, broken.is_empty()) {
            (true, _) => Some("a stress run failed silently".into()),
            (false, false) => Some(format!("cases without a reference: {}", broken.join("; "))),
            (false, true) => None,
        }
    }
}

pub fn stress(args: &StressArgs) -> Result<StressReport, String> {
    let (params, device) = args.device.source().params()?;
    de_resonator::Device::new(params).map_err(|e| format!("{device}: {e}"))?;
    let (cases, summary) = stiff_cases::run(params);
    Ok(StressReport {
        device,
        periods: PERIODS,
        summary,
        cases,
    })
}
