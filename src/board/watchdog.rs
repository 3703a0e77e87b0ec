//! A watchdog only a healthy control loop can feed: the tick feeds it, and only while the
//! low-priority tasks (the command port, the background job) have checked in within
//! [`CHECK_IN_SECONDS`], through a heartbeat the tick asks for at their priority. A task that
//! hangs, or runs past the deadline, starves the dog; a stuck tick starves it too. The dog
//! starts with the first controller; a latched fault keeps it fed (the output is already at
//! 0 V, and a reset would only lose the fault's reason).

/// The dog's timeout, ms.
pub const TIMEOUT_MS: u32 = 1_000;
/// How long the low-priority tasks may go without checking in, s: longer than their longest
/// work (a boot's checks, about 12 ms on the chip).
pub const CHECK_IN_SECONDS: f32 = 0.5;

/// What the tick does with the dog.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Feed {
    /// Start the dog (once, with the first controller), `TIMEOUT_MS`.
    pub start: bool,
    /// Feed it.
    pub feed: bool,
    /// Ask the low-priority tasks to check in (four times a deadline while they are late).
    pub heartbeat: bool,
}

/// The ticks since the low-priority tasks last checked in.
#[derive(Clone, Copy, Debug)]
pub struct CheckIn {
    started: bool,
    since_ticks: u32,
    deadline_ticks: u32,
}

impl CheckIn {
    /// At a tick rate of `tick_hz`.
    pub fn new(tick_hz: f32) -> Self {
        Self {
            started: false,
            since_ticks: 0,
            deadline_ticks: (CHECK_IN_SECONDS * tick_hz) as u32,
        }
    }

    /// A tick: whether the tasks checked in since the last, and whether a controller runs.
    pub fn tick(&mut self, checked_in: bool, running: bool) -> Feed {
        let start = running && !self.started;
        self.started |= start;
        self.since_ticks = if checked_in {
            0
        } else {
            self.since_ticks.saturating_add(1)
        };
        let every = (self.deadline_ticks / 4).max(1);
        Feed {
            start,
            feed: self.since_ticks <= self.deadline_ticks,
            heartbeat: self.since_ticks > 0 && self.since_ticks.is_multiple_of(every),
        }
    }
}
