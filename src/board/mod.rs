//! The board: everything the firmware decides, without its hardware, so the host tests it and
//! host-sim's virtual board (`host-sim serve`) runs it. It boots from an image and the saved
//! settings (the fallback, the watchdog's refusal: [`Board::boot`]), answers the command port
//! ([`port`], in the line [`crate::wire::protocol`] the host shares), turns a tick's output into what the
//! output stage ([`stage`]) does ([`tick`]: the one enable policy), runs the tick's background
//! job ([`tick::run_job`]), does the work around a tick and a request that every caller shares
//! ([`runner`]: the tick's count, a fault's entry, what a reply sets off,
//! the start-up lines) and feeds the watchdog only while the low-priority tasks check in
//! ([`watchdog`]). What only hardware
//! has comes in behind [`Keeper`] (where `save` keeps the settings and the fault log is
//! kept: [`keeper`]) and as arguments (the reset's cause, the clock).
//!
//! The controller's slot is not in [`Board`]: the tick owns it under a lock the command task
//! takes only briefly ([`port::Shared`]), so the long work of a request (a new plan's checks,
//! a boot) runs outside the lock while the tick preempts it.

pub mod commands;
pub mod faults;
#[cfg(feature = "storage")]
mod flash_keeper;
pub mod keeper;
pub mod port;
pub mod runner;
pub mod stage;
pub mod tick;
pub mod watchdog;

use core::fmt::{self, Write as _};

use heapless::String;

use crate::controller::{Boot, Controller, SettingSet, Settings};
use crate::drive::Amplifier;
use crate::image::{Image, ImageError, PowerUp};
use crate::model::safety::FailureMode;
use crate::numerics::decimal::Decimal;

#[cfg(feature = "storage")]
pub use flash_keeper::{FlashKeeper, FlashLog};
pub use keeper::{FaultKeeper, Keeper, NoKeeper, NoLog, SettingsKeeper};
pub use port::{Echo, Line, Lines, Pushed, ReplyLine, Shared, Then, REPLY_END, TERMINAL_REPLY_END};

/// Why the firmware restarted, as it recorded it before the reset.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ResetCause {
    /// The command port asked (`reset`).
    Asked,
    /// The watchdog was not fed in time.
    Watchdog,
    /// The supply fell below the brown-out level (the chip's reset flags; never under QEMU).
    BrownOut,
}

impl ResetCause {
    pub fn name(self) -> &'static str {
        match self {
            ResetCause::Asked => "asked",
            ResetCause::Watchdog => "watchdog",
            ResetCause::BrownOut => "brown_out",
        }
    }
}

/// Why saved settings were not booted (the image's then are).
enum SavedRefused {
    Fault(crate::controller::Fault),
    FrontEnd(crate::acquire::FrontEndError),
}

impl fmt::Display for SavedRefused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SavedRefused::Fault(fault) => write!(f, "{fault}"),
            SavedRefused::FrontEnd(e) => write!(f, "{e}"),
        }
    }
}

/// A clause of the boot's warning line, after a `; `.
fn clause(line: &mut ReplyLine, what: fmt::Arguments) {
    if !line.is_empty() {
        let _ = write!(line, "; ");
    }
    let _ = line.write_fmt(what);
}

/// A clause naming `settings` after `what` (none: not said).
fn clause_naming(line: &mut ReplyLine, what: &str, settings: SettingSet) {
    if settings.is_empty() {
        return;
    }
    clause(line, format_args!("{what}"));
    for setting in settings.iter() {
        let _ = write!(line, " {}", setting.key());
    }
}

/// Why the board drives nothing, one line (room for the longest refusal with its figures:
/// a ring too weak to time, about 330 bytes).
pub type Reason = String<384>;

/// The board's state besides the controller: the image, the settings `clear` boots with
/// while nothing runs (a running controller holds the settings in force: one copy), why it
/// refuses, if it does, and where the settings are saved.
pub struct Board<'a, K> {
    image: Option<(Image<'a>, Amplifier)>,
    /// The settings asked for while no controller runs (refused at boot, or by the image).
    idle_settings: Settings,
    refusal: Option<Reason>,
    /// The limit the last boot or plan found on the chip (its mode).
    limit: Option<FailureMode>,
    /// What the boot's checks found, while the controller it started drives.
    booted: Option<Boot>,
    keeper: Option<K>,
}

/// What the boot says on the command port before any request: the start-up line (after
/// [`crate::wire::protocol::NOTICE`]: `ready …` or `refused …`), and a warning, if any.
#[derive(Clone, Debug, Default)]
pub struct Started {
    pub notice: ReplyLine,
    pub warning: Option<ReplyLine>,
}

impl<'a, K: Keeper> Board<'a, K> {
    /// Boot: check the image, then start the controller in `slot` with the saved settings if
    /// the boot checks pass them, else with the image's (said in the warning). After a
    /// watchdog reset nothing is driven until `clear`: someone has to look first.
    pub fn boot(
        slot: &mut Option<Controller>,
        image: Result<Image<'a>, ImageError>,
        keeper: Option<K>,
        cause: Option<ResetCause>,
    ) -> (Self, Started) {
        *slot = None;
        let mut board = Board {
            image: None,
            idle_settings: Settings::for_target(0.0),
            refusal: None,
            limit: None,
            booted: None,
            keeper,
        };
        // The fault log ready for the run (a stall here harms nothing); a reset the board did
        // not ask for is its first entry.
        if let Some(mut log) = board.fault_log() {
            let _ = log.prepare();
        }
        if let Some(cause @ (ResetCause::Watchdog | ResetCause::BrownOut)) = cause {
            let _ = board.log_reset(cause);
        }
        let mut started = Started::default();
        let image = match image.and_then(|i| Ok((i, i.amplifier.amplifier()?))) {
            Ok(pair) => pair,
            Err(e) => {
                board.refuse_boot(slot, &e, &mut started.notice);
                return (board, started);
            }
        };
        board.image = Some(image);
        board.idle_settings = image.0.settings;
        let mut source = "image";
        // Written where it is returned: a second 1 KB line would sit under the boot's checks.
        let warning = started.warning.insert(ReplyLine::new());
        let saved = match board.keeper.as_mut().map(SettingsKeeper::load) {
            Some(Ok(saved)) => saved,
            Some(Err(e)) => {
                clause(warning, format_args!("{e}: the image's settings used"));
                None
            }
            None => None,
        };
        let mut booted = None;
        // The settings the image lacks (made before they were added), at their defaults
        // unless saved settings give them.
        let mut defaulted = image.0.defaulted;
        if let Some(saved) = saved {
            // Settings added since they were saved (by an older firmware) take the image's.
            let (settings, new) = saved.onto(image.0.settings);
            // Checked as at any boot, and the image's front end at their tick rate (the image
            // checked it at its own).
            let started = board
                .start(slot, image, settings)
                .map_err(SavedRefused::Fault)
                .and_then(|bias| match image.0.front_end.check(settings.tick_hz) {
                    Ok(_) => Ok(bias),
                    Err(e) => {
                        *slot = None;
                        Err(SavedRefused::FrontEnd(e))
                    }
                });
            match started {
                Ok(bias) => {
                    source = "saved";
                    booted = Some(bias);
                    defaulted = defaulted.and(new);
                    clause_naming(
                        warning,
                        "saved settings from an earlier firmware; new since, at the image's values:",
                        new,
                    );
                }
                Err(why) => clause(
                    warning,
                    format_args!("saved settings refused ({why}): the image's used"),
                ),
            }
        }
        clause_naming(
            warning,
            "image from an earlier host-sim; new since, at their defaults:",
            defaulted,
        );
        if warning.is_empty() {
            started.warning = None;
        }
        let booted = match booted {
            Some(bias) => Ok(bias),
            None => board.start(slot, image, image.0.settings),
        };
        // The image's front end at the tick rate booted with (saved settings at a rate it
        // cannot run fell back above; the image checked its own): one the board cannot run
        // refuses, for good.
        if booted.is_ok() {
            if let Err(e) = image.0.front_end.check(board.tick_hz(slot)) {
                board.refuse(slot, &e, &mut started.notice);
                return (board, started);
            }
        }
        match booted {
            Err(fault) => board.refuse_boot(slot, &fault, &mut started.notice),
            Ok(_) if cause == Some(ResetCause::Watchdog) => board.refuse_boot(
                slot,
                &"reset by the watchdog (a task missed its deadline): `clear` to re-arm, `start` to drive",
                &mut started.notice,
            ),
            Ok(bias_volts) => {
                // An image drives at power-up only: after a `reset` the output stays off
                // (it was asked to be off at 0 V; no command named `reset` switches it on).
                let waits = image.0.power_up == PowerUp::Wait || cause.is_some();
                if waits {
                    // Checked, not switched on: at 0 V with the stage off until `start`
                    // (as `clear` leaves it).
                    if let Some(c) = slot.as_mut() {
                        c.stop();
                    }
                }
                let (target_hz, max_volts) = slot.as_ref().map_or((0.0, 0.0), |c| {
                    (c.settings().target_hz, board.max_volts(c))
                });
                let _ = write!(
                    started.notice,
                    "ready target_hz={} bias_volts={} max_volts={} settings={source} power_up={}",
                    Decimal(target_hz),
                    Decimal(bias_volts),
                    Decimal(max_volts),
                    image.0.power_up.name()
                );
                // A batch's table (model.md §10): which bound set the cap, and the batch's.
                if let Some(boot) = board.booted {
                    if let Some(limit) = boot.batch_limit_volts {
                        let _ = write!(
                            started.notice,
                            " cap_by={} batch_limit_volts={}",
                            boot.cap_by.name(),
                            Decimal(limit)
                        );
                    }
                }
                let _ = write!(
                    started.notice,
                    " output={}",
                    if waits { "off" } else { "on" }
                );
                match (waits, image.0.power_up) {
                    (true, PowerUp::Drive) => {
                        let _ = write!(
                            started.notice,
                            " (after a reset the output stays off at 0 V: `start` to drive)"
                        );
                    }
                    (true, _) => {
                        let _ = write!(
                            started.notice,
                            " (the output off at 0 V: `start` to drive)"
                        );
                    }
                    (false, _) => {}
                }
            }
        }
        (board, started)
    }

    /// Start a controller in `slot` with `settings` (every boot check): its bias, V. The
    /// settings are kept for `clear` either way; the slot is `None` on a refusal.
    fn start(
        &mut self,
        slot: &mut Option<Controller>,
        (image, amplifier): (Image<'a>, Amplifier),
        settings: Settings,
    ) -> Result<f32, crate::controller::Fault> {
        self.idle_settings = settings;
        let board = image.board(amplifier, settings.tick_hz);
        let boot = Controller::start_in(slot, image.params, image.table, board, settings)?;
        self.limit = boot.limit.map(|l| l.mode);
        self.refusal = None;
        self.booted = Some(boot);
        Ok(boot.bias_volts)
    }

    /// Drive nothing, and say why (in `notice`, and to every request that needs a controller);
    /// `clear` may boot again (a watchdog's reset, settings the checks refused).
    fn refuse_boot(
        &mut self,
        slot: &mut Option<Controller>,
        why: &dyn fmt::Display,
        notice: &mut ReplyLine,
    ) {
        *slot = None;
        self.booted = None;
        let mut reason = Reason::new();
        let _ = write!(reason, "{why}");
        notice.clear();
        let _ = write!(notice, "refused {reason}");
        self.refusal = Some(reason);
    }

    /// Drive nothing with this image, for good (until a new image and a power-up): what only
    /// the firmware finds, such as a tick rate beyond its timer's reach. Every request but
    /// `help` answers why; `clear` cannot lift it.
    pub fn refuse(
        &mut self,
        slot: &mut Option<Controller>,
        why: &dyn fmt::Display,
        notice: &mut ReplyLine,
    ) {
        self.refuse_boot(slot, why, notice);
        self.image = None;
    }

    /// Where the settings are kept, back for the next boot (a reset).
    pub fn into_keeper(self) -> Option<K> {
        self.keeper
    }

    /// Why nothing is driven, if it is not.
    pub fn refusal(&self) -> Option<&str> {
        self.refusal.as_deref()
    }

    /// What the boot's checks found, while the controller the last boot started may drive
    /// (`None`: refused).
    pub fn booted(&self) -> Option<&Boot> {
        self.booted.as_ref()
    }

    /// The highest voltage the board can command under `c`: the cap in force, or the
    /// amplifier's top (its rail, or the DAC's top code) where that is lower, V.
    pub fn max_volts(&self, c: &Controller) -> f32 {
        let top = self.image.map_or(f32::INFINITY, |(_, a)| a.max_volts());
        c.max_volts().min(top)
    }

    /// The image booted from (`None`: none that reads).
    pub fn image(&self) -> Option<Image<'a>> {
        self.image.map(|(image, _)| image)
    }

    /// The tick rate the board runs at: the settings in force, or those `clear` would boot
    /// with (the timer is set once, at power-up).
    pub fn tick_hz(&self, slot: &Option<Controller>) -> f32 {
        slot.as_ref()
            .map_or(self.idle_settings.tick_hz, |c| c.settings().tick_hz)
    }
}
