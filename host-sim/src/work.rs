//! Long work: independent jobs over the machine's cores, with a progress bar on stderr (shown
//! only on a terminal, so pipes and JSON consumers see nothing of it).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar of `len` jobs titled `what`, on stderr (hidden when it is not a terminal).
pub fn bar(what: &str, len: usize) -> ProgressBar {
    let bar = ProgressBar::new(len as u64).with_message(what.to_string());
    if let Ok(style) = ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} {eta}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// `job` applied to every item, in order, on all cores, with a progress bar titled `what`.
pub fn map<I: Sync, O: Send>(what: &str, items: &[I], job: impl Fn(&I) -> O + Sync) -> Vec<O> {
    let bar = bar(what, items.len());
    let next = AtomicUsize::new(0);
    let done: Mutex<Vec<Option<O>>> = Mutex::new(items.iter().map(|_| None).collect());
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get());
    std::thread::scope(|scope| {
        for _ in 0..workers.min(items.len()) {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(item) = items.get(k) else { break };
                let out = job(item);
                if let Ok(mut done) = done.lock() {
                    done[k] = Some(out);
                }
                bar.inc(1);
            });
        }
    });
    bar.finish_and_clear();
    done.into_inner()
        .unwrap_or_default()
        .into_iter()
        .flatten()
        .collect()
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
