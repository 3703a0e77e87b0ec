//! Long work: independent jobs over the machine's cores, with a progress bar on stderr (shown
//! only on a terminal, so pipes and JSON consumers see nothing of it).

use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

/// A progress bar of `len` jobs titled `what`, on stderr (hidden when it is not a terminal).
pub fn bar(what: &str, len: usize) -> ProgressBar {
    let bar = ProgressBar::new(len as u64).with_message(what.to_string());
    if let Ok(style) = ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} {eta}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// `job` applied to every item, in order, on all cores (rayon), with a progress bar titled
/// `what`.
pub fn map<I: Sync, O: Send>(what: &str, items: &[I], job: impl Fn(&I) -> O + Sync) -> Vec<O> {
    let bar = bar(what, items.len());
    let out = items
        .par_iter()
        .map(|item| {
            let out = job(item);
            bar.inc(1);
            out
        })
        .collect();
    bar.finish_and_clear();
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn keeps_order_and_runs_every_job() {
        let items: Vec<u64> = (0..1000).collect();
        let out = super::map("squares", &items, |k| k * k);
        assert_eq!(out, items.iter().map(|k| k * k).collect::<Vec<_>>());
    }
}
