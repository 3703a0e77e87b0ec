//! Long work: independent jobs over the machine's cores, with a progress bar on stderr (shown
//! only on a terminal, so pipes and JSON consumers see nothing of it), and a way to stop it
//! (a caller's flag, read by the long loops: the Python package's Ctrl-C).

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

/// What a long loop stopped by its caller's flag says.
pub const INTERRUPTED: &str = "interrupted";

thread_local! {
    /// The flag that stops this thread's long work, while `stoppable` runs it.
    static STOP: RefCell<Option<Arc<AtomicBool>>> = const { RefCell::new(None) };
}

/// Run `job` on this thread with `stop` as the flag its long loops read ([`stopped`]).
pub fn stoppable<R>(stop: Arc<AtomicBool>, job: impl FnOnce() -> R) -> R {
    let before = STOP.with(|s| s.replace(Some(stop)));
    let out = job();
    STOP.with(|s| *s.borrow_mut() = before);
    out
}

/// Whether this thread's caller asked its long work to stop (never, outside `stoppable`).
pub fn stopped() -> bool {
    STOP.with(|s| {
        s.borrow()
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    })
}

/// A progress bar of `len` jobs titled `what`, on stderr (hidden when it is not a terminal).
pub fn bar(what: &str, len: usize) -> ProgressBar {
    let bar = ProgressBar::new(len as u64).with_message(what.to_string());
    if let Ok(style) = ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} {eta}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// `job` applied to every item, in order, on this thread; stopped between items when the
/// caller's flag is raised ([`stopped`]: `INTERRUPTED`).
pub fn each<I, O>(items: &[I], mut job: impl FnMut(&I) -> O) -> Result<Vec<O>, String> {
    let mut out = Vec::with_capacity(items.len());
    for item in items {
        if stopped() {
            return Err(INTERRUPTED.to_string());
        }
        out.push(job(item));
    }
    Ok(out)
}

/// `job` applied to every item, in order, on all cores (rayon), with a progress bar titled
/// `what`; the jobs see the caller's stop flag ([`stopped`]).
pub fn map<I: Sync, O: Send>(what: &str, items: &[I], job: impl Fn(&I) -> O + Sync) -> Vec<O> {
    let bar = bar(what, items.len());
    // The caller's stop flag, read by the jobs on rayon's threads too.
    let stop = STOP.with(|s| s.borrow().clone());
    let out = items
        .par_iter()
        .map(|item| {
            let out = match &stop {
                Some(flag) => stoppable(flag.clone(), || job(item)),
                None => job(item),
            };
            bar.inc(1);
            out
        })
        .collect();
    bar.finish_and_clear();
    out
}

/// `INTERRUPTED` as an error if any of the runs says it stopped for it: a study stopped by
/// Ctrl-C reports nothing half done.
pub fn interrupted<'a>(stopped: impl IntoIterator<Item = Option<&'a str>>) -> Result<(), String> {
    match stopped.into_iter().any(|why| why == Some(INTERRUPTED)) {
        true => Err(INTERRUPTED.into()),
        false => Ok(()),
    }
}

/// `map` for few long jobs made of many units: one bar of `units` that the jobs advance
/// themselves (`tick` once a unit).
pub fn map_units<I: Sync, O: Send>(
    what: &str,
    items: &[I],
    units: usize,
    job: impl Fn(&I, &(dyn Fn() + Sync)) -> O + Sync,
) -> Vec<O> {
    let bar = bar(what, units);
    let stop = STOP.with(|s| s.borrow().clone());
    let tick = || bar.inc(1);
    let out = items
        .par_iter()
        .map(|item| match &stop {
            Some(flag) => stoppable(flag.clone(), || job(item, &tick)),
            None => job(item, &tick),
        })
        .collect();
    bar.finish_and_clear();
    out
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    #[test]
    fn stopped_reads_the_callers_flag_only_inside_stoppable() {
        let flag = Arc::new(AtomicBool::new(false));
        assert!(!super::stopped());
        super::stoppable(flag.clone(), || {
            assert!(!super::stopped());
            flag.store(true, Ordering::Relaxed);
            assert!(super::stopped());
        });
        assert!(!super::stopped());
    }

    #[test]
    fn each_stops_between_items_once_the_flag_is_raised() {
        let flag = Arc::new(AtomicBool::new(false));
        let items: Vec<u32> = (0..10).collect();
        let done = super::stoppable(flag.clone(), || {
            super::each(&items, |&k| {
                if k == 3 {
                    flag.store(true, Ordering::Relaxed);
                }
                k
            })
        });
        assert_eq!(done, Err(super::INTERRUPTED.to_string()));
        assert_eq!(super::each(&items, |&k| 2 * k).unwrap()[9], 18);
    }

    #[test]
    fn keeps_order_and_runs_every_job() {
        let items: Vec<u64> = (0..1000).collect();
        let out = super::map("squares", &items, |k| k * k);
        assert_eq!(out, items.iter().map(|k| k * k).collect::<Vec<_>>());
    }
}
