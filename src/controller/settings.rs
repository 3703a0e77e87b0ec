//! What the controller is asked to do (`Settings`), and the checks every setting passes
//! before anything is driven.

use super::fault::Fault;
use crate::estimate::ring::MAX_WINDOW;
use crate::tuning::TuneError;

/// What the controller is asked to do, and how.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settings {
    /// The natural frequency to tune to, Hz.
    pub target_hz: f32,
    /// Voltage margin: every commanded voltage stays at most (1 − margin)·Φlimit.
    pub margin: f32,
    /// Bias ramp rate, V/s.
    pub slew_volts_per_second: f32,
    /// The controller's fixed rate, Hz.
    pub tick_hz: f32,
    /// Hold at the bias before the AC drive starts, s.
    pub settle_seconds: f32,
    /// AC drive amplitude, V (0: none).
    pub ac_volts: f32,
    /// AC drive frequency, Hz.
    pub ac_hz: f32,
    /// How long the model follows the AC drive after it starts, s.
    pub check_seconds: f32,
    /// Largest relative difference allowed between the natural frequency at the table's bias
    /// and at the direct solve's (the two biases differ by the table's interpolation).
    pub agreement: f32,
    /// Largest difference between the amplifier's monitored output and the last command,
    /// V, for more than `AMPLIFIER_TICKS` ticks in a row (a saturated or failed amplifier).
    pub amplifier_tolerance_volts: f32,
    /// Bit-identical sensor samples in a row that mean a stuck sensor (`None`: no such
    /// check; a real sensor's noise never repeats that long).
    pub stuck_samples: Option<u32>,
    /// Closed-loop trim: the relative frequency error to reach (`None`: no trim). Needs the
    /// stretch sensor or the amplifier's current monitor (`Inputs`), and the `cross_check`
    /// stage (the model is re-solved on the chip).
    pub trim_tolerance: Option<f32>,
    /// The ring measured after each pulse, s: at least `MIN_WINDOW_PERIODS` target periods, and
    /// averaged into at most `MAX_WINDOW` samples, at least `MIN_SAMPLES_PER_PERIOD` a period.
    pub trim_window_seconds: f32,
    /// The pulse's drop below the bias, V, for half a period of the target.
    pub trim_pulse_volts: f32,
    /// The first bias the trim measures at, as a fraction of the nominal cap at most: a
    /// plant softer than the model by a factor r has its limit √r lower, so a fraction p
    /// covers plants down to r = p².
    pub trim_probe_fraction: f32,
    /// Trim again after this long of AC drive, s (`None`: once): for a plant that drifts,
    /// as a viscoelastic membrane creeps. The AC pauses while the ring is measured.
    pub trim_every_seconds: Option<f32>,
    /// The leakage watch (model.md §8): the membrane's leakage resistance, from the DC part
    /// of the amplifier's current against the voltage over each `LEAKAGE_WINDOW_SECONDS` at
    /// a steady bias, must stay above this, Ω (`None`: no watch). A falling leakage
    /// resistance is a precursor of breakdown. Needs the current monitor.
    pub leakage_floor_ohms: Option<f32>,
    /// The leakage watch's second test: from one window to the next, the leakage resistance
    /// may fall by at most this fraction a second, where the fall stands out of the current's
    /// scatter (`None`: no such test). A fast fall comes before breakdown, far above a floor.
    pub leakage_fall_per_second: Option<f32>,
    /// Resonance tracking while driving (feature `track`, `crate::estimate::lockin`): the drive follows
    /// the resonance measured in the stretch with this time constant, s, and the bias is
    /// retuned to the target within `trim_tolerance` without pausing the drive (`None`: off).
    /// Needs the stretch sensor and a trim; not with `trim_every_seconds`.
    pub track_seconds: Option<f32>,
    /// The stretch from the capacitance (feature `probe`, `crate::estimate::capacitance`): a square probe of
    /// this amplitude, V, rides on the bias (`None`: off). The current monitor's lock-in on
    /// it gives λ with its uncertainty, checked against model.md §6 widened by it. Off while
    /// the trim measures a ring.
    pub probe_volts: Option<f32>,
    /// The probe's frequency, Hz: half the tick rate over a whole number (its sign flips
    /// every so many ticks).
    pub probe_hz: f32,
}

/// The f32 solve's allowance: the cap is (1 − margin)·(1 − F32_GUARD)·Φlimit in f32, so it
/// stays below (1 − margin)·Φlimit in f64. The f32 limit was within 6.7e-7 of the f64 limit
/// of the same parameters on 28,726 random devices (`tests/safety.rs` holds it to 1e-6).
pub const F32_GUARD: f32 = 1e-5;

/// The margin the f32 solve runs with: (1 − margin)·(1 − F32_GUARD) = 1 − that.
pub(super) fn guarded(margin: f32) -> f32 {
    1.0 - (1.0 - margin) * (1.0 - F32_GUARD)
}

/// The self-sensing probe's frequency over the target's, at least.
pub const PROBE_ABOVE_TARGET: f32 = 4.0;

/// Most trims (measure, estimate, retune) before the controller gives up.
pub const MAX_TRIMS: u8 = 8;

/// Largest change of the bias a secant step may make, as a fraction of the bias.
pub const TRIM_SECANT_STEP: f32 = 0.1;

impl Settings {
    /// The probe's half period in ticks: `tick_hz`/(2·`probe_hz`), which must be a whole
    /// number (within 1e-4) of at least 1; else a `Setting` fault naming `probe_hz`.
    pub(super) fn probe_half_ticks(&self) -> Result<u32, Fault> {
        let hz = self.probe_hz;
        let half = self.tick_hz / (2.0 * hz);
        let whole = libm::roundf(half);
        if !(hz > 0.0 && whole >= 1.0 && (half - whole).abs() <= 1e-4 * whole && whole < 1e6) {
            return Err(Fault::Setting {
                setting: Setting::ProbeHz,
                value: hz,
            });
        }
        Ok(whole as u32)
    }

    /// The most the voltage swings about the bias: the AC and the probe, V.
    pub fn swing_volts(&self) -> f32 {
        self.ac_volts + self.probe_volts.unwrap_or(0.0)
    }

    /// The trim's window as recorded: the ticks each sample averages (the stride: 1 while
    /// the window fits `MAX_WINDOW` ticks, more at a faster tick) and the samples it holds.
    pub fn trim_window(&self) -> (u32, usize) {
        let ticks = self.trim_window_seconds * self.tick_hz;
        let stride = libm::ceilf(ticks / MAX_WINDOW as f32).max(1.0);
        let samples = (ticks / stride) as usize;
        (stride as u32, samples.min(MAX_WINDOW))
    }

    /// Defaults for a target: 5% margin, 10 kV/s, 1 kHz, 0.25 s hold, no AC, 0.5 s of
    /// model after the AC starts, table and solve within 1e-4 in frequency, the amplifier
    /// within 200 V of its command, 100 equal sensor samples in a row a stuck sensor; no
    /// probe (its frequency, once on, 500 Hz).
    pub const fn for_target(target_hz: f32) -> Self {
        Self {
            target_hz,
            margin: 0.05,
            slew_volts_per_second: 10_000.0,
            tick_hz: 1_000.0,
            settle_seconds: 0.25,
            ac_volts: 0.0,
            ac_hz: 0.0,
            check_seconds: 0.5,
            agreement: 1e-4,
            amplifier_tolerance_volts: 200.0,
            stuck_samples: Some(100),
            trim_tolerance: None,
            trim_window_seconds: 0.5,
            trim_pulse_volts: 200.0,
            trim_probe_fraction: 0.5,
            trim_every_seconds: None,
            leakage_floor_ohms: None,
            leakage_fall_per_second: None,
            track_seconds: None,
            probe_volts: None,
            probe_hz: 500.0,
        }
    }

    /// One setting's value; a setting that is off (`None`) reads 0, as settings files
    /// write it.
    pub fn get(&self, setting: Setting) -> f32 {
        match setting {
            Setting::StuckSamples => self.stuck_samples.map_or(0.0, |n| n as f32),
            Setting::TrimTolerance => self.trim_tolerance.unwrap_or(0.0),
            Setting::TrimEverySeconds => self.trim_every_seconds.unwrap_or(0.0),
            Setting::LeakageFloorOhms => self.leakage_floor_ohms.unwrap_or(0.0),
            Setting::LeakageFallPerSecond => self.leakage_fall_per_second.unwrap_or(0.0),
            Setting::TrackSeconds => self.track_seconds.unwrap_or(0.0),
            Setting::ProbeVolts => self.probe_volts.unwrap_or(0.0),
            other => {
                let mut copy = *self;
                copy.slot_mut(other).map_or(f32::NAN, |value| *value)
            }
        }
    }

    /// Set one setting; 0 turns off one that can be off (`stuck_samples` is rounded
    /// down, saturating).
    pub fn set(&mut self, setting: Setting, value: f32) {
        let on = (value != 0.0).then_some(value);
        match setting {
            Setting::StuckSamples => self.stuck_samples = on.map(|n| n as u32),
            Setting::TrimTolerance => self.trim_tolerance = on,
            Setting::TrimEverySeconds => self.trim_every_seconds = on,
            Setting::LeakageFloorOhms => self.leakage_floor_ohms = on,
            Setting::LeakageFallPerSecond => self.leakage_fall_per_second = on,
            Setting::TrackSeconds => self.track_seconds = on,
            Setting::ProbeVolts => self.probe_volts = on,
            other => {
                if let Some(slot) = self.slot_mut(other) {
                    *slot = value;
                }
            }
        }
    }

    fn slot_mut(&mut self, setting: Setting) -> Option<&mut f32> {
        Some(match setting {
            Setting::TargetHz => &mut self.target_hz,
            Setting::Margin => &mut self.margin,
            Setting::SlewVoltsPerSecond => &mut self.slew_volts_per_second,
            Setting::TickHz => &mut self.tick_hz,
            Setting::SettleSeconds => &mut self.settle_seconds,
            Setting::AcVolts => &mut self.ac_volts,
            Setting::AcHz => &mut self.ac_hz,
            Setting::CheckSeconds => &mut self.check_seconds,
            Setting::Agreement => &mut self.agreement,
            Setting::AmplifierToleranceVolts => &mut self.amplifier_tolerance_volts,

            Setting::TrimWindowSeconds => &mut self.trim_window_seconds,
            Setting::TrimPulseVolts => &mut self.trim_pulse_volts,
            Setting::TrimProbeFraction => &mut self.trim_probe_fraction,
            Setting::ProbeHz => &mut self.probe_hz,
            Setting::StuckSamples
            | Setting::TrimTolerance
            | Setting::TrimEverySeconds
            | Setting::LeakageFloorOhms
            | Setting::LeakageFallPerSecond
            | Setting::TrackSeconds
            | Setting::ProbeVolts => return None,
        })
    }

    /// Every setting in its range (the trim's only with the `trim` feature): a `Setting`
    /// fault naming the first that is not, or `Tune` for the margin.
    pub(super) fn check(&self) -> Result<(), Fault> {
        let tick_hz = positive(Setting::TickHz, self.tick_hz)?;
        positive(Setting::SlewVoltsPerSecond, self.slew_volts_per_second)?;
        non_negative(Setting::SettleSeconds, self.settle_seconds)?;
        non_negative(Setting::AcVolts, self.ac_volts)?;
        let ac_hz = non_negative(Setting::AcHz, self.ac_hz)?;
        non_negative(Setting::CheckSeconds, self.check_seconds)?;
        positive(Setting::Agreement, self.agreement)?;
        positive(
            Setting::AmplifierToleranceVolts,
            self.amplifier_tolerance_volts,
        )?;
        if let Some(trim) = self.trim_tolerance {
            positive(Setting::TrimTolerance, trim)?;
            if !cfg!(feature = "trim") {
                // Built without the trim: asking for it is an error, not a silent no.
                return Err(Fault::Setting {
                    setting: Setting::TrimTolerance,
                    value: trim,
                });
            }
        }
        if self.stuck_samples == Some(0) {
            return Err(Fault::Setting {
                setting: Setting::StuckSamples,
                value: 0.0,
            });
        }
        non_negative(Setting::TrimPulseVolts, self.trim_pulse_volts)?;
        positive(Setting::TrimWindowSeconds, self.trim_window_seconds)?;
        let (stride, _) = self.trim_window();
        let per_period = tick_hz / (stride as f32 * self.target_hz);
        let periods = self.trim_window_seconds * self.target_hz;
        // (A target out of range is the tuner's to refuse, by name.)
        let target_ok = self.target_hz > 0.0 && self.target_hz.is_finite();
        if self.trim_tolerance.is_some()
            && target_ok
            && !(per_period >= crate::estimate::ring::MIN_SAMPLES_PER_PERIOD
                && periods >= crate::estimate::ring::MIN_WINDOW_PERIODS)
        {
            let window = self.trim_window_seconds;
            return Err(Fault::Setting {
                setting: Setting::TrimWindowSeconds,
                value: window,
            });
        }
        if let Some(every) = self.trim_every_seconds {
            positive(Setting::TrimEverySeconds, every)?;
        }
        if let Some(ohms) = self.leakage_floor_ohms {
            positive(Setting::LeakageFloorOhms, ohms)?;
        }
        if let Some(rate) = self.leakage_fall_per_second {
            positive(Setting::LeakageFallPerSecond, rate)?;
        }
        if let Some(seconds) = self.track_seconds {
            positive(Setting::TrackSeconds, seconds)?;
            // Built without tracking, or without the trim it retunes with, or with the
            // periodic trim that pauses the drive it would track: an error, not a silent no.
            if !cfg!(feature = "track")
                || self.trim_tolerance.is_none()
                || self.trim_every_seconds.is_some()
                || !(self.ac_volts > 0.0)
            {
                return Err(Fault::Setting {
                    setting: Setting::TrackSeconds,
                    value: seconds,
                });
            }
        }
        if let Some(volts) = self.probe_volts {
            positive(Setting::ProbeVolts, volts)?;
            if !cfg!(feature = "probe") {
                return Err(Fault::Setting {
                    setting: Setting::ProbeVolts,
                    value: volts,
                });
            }
            self.probe_half_ticks()?;
            // Well above the resonance: the motion the probe drives stays small against the
            // AC's (it is not in the edges' charge, `crate::estimate::capacitance`, but moves λ).
            if !(self.probe_hz >= PROBE_ABOVE_TARGET * self.target_hz) {
                return Err(Fault::Setting {
                    setting: Setting::ProbeHz,
                    value: self.probe_hz,
                });
            }
        }
        let probe = positive(Setting::TrimProbeFraction, self.trim_probe_fraction)?;
        if !(probe <= 1.0) {
            return Err(Fault::Setting {
                setting: Setting::TrimProbeFraction,
                value: probe,
            });
        }
        // Below Nyquist; and AC volts without a frequency would drive nothing, silently.
        if !(ac_hz < 0.5 * tick_hz) || (self.ac_volts > 0.0 && ac_hz == 0.0) {
            return Err(Fault::Setting {
                setting: Setting::AcHz,
                value: ac_hz,
            });
        }
        if !(self.margin >= 0.0 && self.margin < 1.0) {
            return Err(Fault::Tune(TuneError::InvalidMargin {
                margin: self.margin,
            }));
        }
        Ok(())
    }
}

/// A setting: the one list that settings files, messages and a command port take theirs from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Setting {
    TargetHz,
    Margin,
    SlewVoltsPerSecond,
    TickHz,
    SettleSeconds,
    AcVolts,
    AcHz,
    CheckSeconds,
    Agreement,
    AmplifierToleranceVolts,
    TrimTolerance,
    TrimWindowSeconds,
    TrimPulseVolts,
    TrimProbeFraction,
    TrimEverySeconds,
    StuckSamples,
    LeakageFloorOhms,
    LeakageFallPerSecond,
    TrackSeconds,
    ProbeVolts,
    ProbeHz,
}

impl Setting {
    /// Every setting, in `Settings` order.
    pub const ALL: [Setting; 21] = [
        Setting::TargetHz,
        Setting::Margin,
        Setting::SlewVoltsPerSecond,
        Setting::TickHz,
        Setting::SettleSeconds,
        Setting::AcVolts,
        Setting::AcHz,
        Setting::CheckSeconds,
        Setting::Agreement,
        Setting::AmplifierToleranceVolts,
        Setting::StuckSamples,
        Setting::TrimTolerance,
        Setting::TrimWindowSeconds,
        Setting::TrimPulseVolts,
        Setting::TrimProbeFraction,
        Setting::TrimEverySeconds,
        Setting::LeakageFloorOhms,
        Setting::LeakageFallPerSecond,
        Setting::TrackSeconds,
        Setting::ProbeVolts,
        Setting::ProbeHz,
    ];

    /// The setting with this key.
    pub fn from_key(key: &str) -> Option<Setting> {
        Setting::ALL.into_iter().find(|s| s.key() == key)
    }

    /// The setting's key, as in `Settings` and a scene's `[controller]` table.
    pub fn key(self) -> &'static str {
        match self {
            Setting::TargetHz => "target_hz",
            Setting::Margin => "margin",
            Setting::StuckSamples => "stuck_samples",
            Setting::SlewVoltsPerSecond => "slew_volts_per_second",
            Setting::TickHz => "tick_hz",
            Setting::SettleSeconds => "settle_seconds",
            Setting::AcVolts => "ac_volts",
            Setting::AcHz => "ac_hz",
            Setting::CheckSeconds => "check_seconds",
            Setting::Agreement => "agreement",
            Setting::AmplifierToleranceVolts => "amplifier_tolerance_volts",
            Setting::TrimTolerance => "trim_tolerance",
            Setting::TrimWindowSeconds => "trim_window_seconds",
            Setting::TrimPulseVolts => "trim_pulse_volts",
            Setting::TrimProbeFraction => "trim_probe_fraction",
            Setting::TrimEverySeconds => "trim_every_seconds",
            Setting::LeakageFloorOhms => "leakage_floor_ohms",
            Setting::LeakageFallPerSecond => "leakage_fall_per_second",
            Setting::TrackSeconds => "track_seconds",
            Setting::ProbeVolts => "probe_volts",
            Setting::ProbeHz => "probe_hz",
        }
    }
}

impl Setting {
    /// The unit its value is in (the key's suffix says it too).
    pub fn unit(self) -> &'static str {
        match self {
            Setting::TargetHz | Setting::AcHz | Setting::TickHz | Setting::ProbeHz => "Hz",
            Setting::AcVolts
            | Setting::ProbeVolts
            | Setting::TrimPulseVolts
            | Setting::AmplifierToleranceVolts => "V",
            Setting::SlewVoltsPerSecond => "V/s",
            Setting::SettleSeconds
            | Setting::CheckSeconds
            | Setting::TrimWindowSeconds
            | Setting::TrimEverySeconds
            | Setting::TrackSeconds => "s",
            Setting::LeakageFloorOhms => "ohm",
            Setting::LeakageFallPerSecond => "1/s",
            Setting::StuckSamples => "samples",
            Setting::Margin
            | Setting::Agreement
            | Setting::TrimTolerance
            | Setting::TrimProbeFraction => "fraction",
        }
    }

    /// Whether it counts something: a fraction is refused, never rounded.
    pub fn whole(self) -> bool {
        matches!(self, Setting::StuckSamples)
    }

    /// What the checks ask of it, said when they refuse it.
    pub fn rule(self) -> &'static str {
        match self {
            Setting::TargetHz => "a frequency in the device's tunable range",
            Setting::Margin => "in [0, 1)",
            Setting::SlewVoltsPerSecond => "> 0",
            Setting::TickHz => {
                "> 0, and fast enough for the model to step the device stably in substeps"
            }
            Setting::SettleSeconds | Setting::CheckSeconds => ">= 0",
            Setting::AcVolts => {
                ">= 0, the AC (and the probe) about the bias within [0 V, the cap in force]"
            }
            Setting::AcHz => "below half the tick rate, and > 0 where ac_volts is",
            Setting::Agreement | Setting::AmplifierToleranceVolts => "> 0",
            Setting::TrimTolerance => "> 0 or off, in a build with the trim",
            Setting::TrimWindowSeconds => {
                "at least 4 target periods long, and once its ticks are averaged into 512 \
                 samples, at least 8 samples per target period (at most 64 periods)"
            }
            Setting::TrimPulseVolts => ">= 0",
            Setting::TrimProbeFraction => "in (0, 1]",
            Setting::TrimEverySeconds => "> 0 or off",
            Setting::StuckSamples => ">= 1 or off",
            Setting::LeakageFloorOhms | Setting::LeakageFallPerSecond => "> 0 or off",
            Setting::TrackSeconds => {
                "> 0 or off; with the track build, a trim, ac_volts > 0 and no trim_every_seconds"
            }
            Setting::ProbeVolts => {
                "> 0 or off, in a build with the probe; the probe and the AC about the bias \
                 within [0 V, the cap in force]"
            }
            Setting::ProbeHz => "at least 4x target_hz, a whole number of ticks per half period",
        }
    }
}

fn positive(setting: Setting, value: f32) -> Result<f32, Fault> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Fault::Setting { setting, value })
    }
}

fn non_negative(setting: Setting, value: f32) -> Result<f32, Fault> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(Fault::Setting { setting, value })
    }
}
