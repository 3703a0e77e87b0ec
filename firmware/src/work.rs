//! Work the tick hands to the low-priority task: a trim's solve or tracking's slope. The
//! tick only asks for it (`trim_wanted`); the task takes the job from the controller under
//! the lock, solves it outside, and gives the result back, so no 2 KB job is copied through
//! the task queue.

use de_resonator::Controller;

/// Whether the controller waits for a job (a trim's window, or tracking's slope while
/// driving; the task may be asked again: it then finds no job and returns).
pub fn trim_wanted(controller: &Controller) -> bool {
    controller.job_pending()
}

/// Take the job, solve it, give the result back; `with` runs a closure on the controller
/// under its lock.
pub fn trim(mut with: impl FnMut(&mut dyn FnMut(&mut Controller))) {
    let mut job = None;
    with(&mut |c| job = c.trim_job());
    if let Some(job) = job {
        let result = job.solve();
        with(&mut |c| c.trim_done(result));
    }
}
