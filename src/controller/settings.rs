//! What the controller is asked to do (`Settings`), and the checks every setting passes
//! before anything is driven.

use crate::estimate::ring::MAX_WINDOW;

/// The settings, declared once: each with its stable id, its field (whose name is its key),
/// its type, its default, its unit, the rule its checks hold it to and its doc. From this
/// come `Settings` and its defaults, `Setting` with `ALL`, `key`, `unit`, `rule` and the doc,
/// `get` and `set`, and through them a saved blob's and an image's layout (by id) and the
/// settings reference (docs/settings.md, checked against it). An id is never reused or
/// changed: a new setting takes the next one, at the end.
macro_rules! declare_settings {
    ($(
        $(#[doc = $doc:literal])+
        $id:literal $variant:ident $field:ident: $ty:ty = $default:expr, $unit:literal,
        $rule:literal;
    )+) => {
        /// What the controller is asked to do, and how.
        #[derive(Clone, Copy, Debug, PartialEq)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub struct Settings {
            $($(#[doc = $doc])+ pub $field: $ty,)+
        }

        /// A setting: the one list that settings files, messages, a command port, a saved
        /// blob and an image take theirs from (its number its stable id).
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        #[repr(u8)]
        pub enum Setting {
            $($(#[doc = $doc])+ $variant = $id,)+
        }

        impl Settings {
            /// Every setting at its default; the target 0 (none: `for_target` gives one).
            pub const DEFAULTS: Settings = Settings {
                $($field: $default,)+
            };

            /// One setting's value; a setting that is off (`None`) reads 0, as settings
            /// files write it.
            pub fn get(&self, setting: Setting) -> f32 {
                match setting {
                    $(Setting::$variant => Slot::read(&self.$field),)+
                }
            }

            /// Set one setting; 0 turns off one that can be off (`stuck_samples` is rounded
            /// down, saturating).
            pub fn set(&mut self, setting: Setting, value: f32) {
                match setting {
                    $(Setting::$variant => Slot::write(&mut self.$field, value),)+
                }
            }
        }

        impl Setting {
            /// Every setting, by id (the ids run 0, 1, 2, … in this order).
            pub const ALL: [Setting; [$(Setting::$variant),+].len()] = [$(Setting::$variant),+];

            /// The setting's key, as in `Settings` and a scene's `[controller]` table.
            pub fn key(self) -> &'static str {
                match self {
                    $(Setting::$variant => stringify!($field),)+
                }
            }

            /// The unit its value is in (the key's suffix says it too).
            pub fn unit(self) -> &'static str {
                match self {
                    $(Setting::$variant => $unit,)+
                }
            }

            /// What the checks ask of it, said when they refuse it.
            pub fn rule(self) -> &'static str {
                match self {
                    $(Setting::$variant => $rule,)+
                }
            }

            fn doc_lines(self) -> &'static [&'static str] {
                match self {
                    $(Setting::$variant => &[$($doc),+],)+
                }
            }
        }
    };
}

declare_settings! {
    /// The natural frequency to tune to, Hz.
    0 TargetHz target_hz: f32 = 0.0, "Hz", "a frequency in the device's tunable range";
    /// Voltage margin: every commanded voltage stays at most (1 − margin)·Φlimit.
    1 Margin margin: f32 = 0.05, "fraction", "in [0, 1)";
    /// Bias ramp rate, V/s.
    2 SlewVoltsPerSecond slew_volts_per_second: f32 = 10_000.0, "V/s", "> 0";
    /// The controller's fixed rate, Hz.
    3 TickHz tick_hz: f32 = 1_000.0, "Hz",
        "> 0, and fast enough for the model to step the device stably in substeps";
    /// Hold at the bias before the AC drive starts, s.
    4 SettleSeconds settle_seconds: f32 = 0.25, "s", ">= 0";
    /// AC drive amplitude, V (0: none).
    5 AcVolts ac_volts: f32 = 0.0, "V",
        ">= 0, the AC (and the probe) about the bias within [0 V, the cap in force]";
    /// AC drive frequency, Hz.
    6 AcHz ac_hz: f32 = 0.0, "Hz", "below half the tick rate, and > 0 where ac_volts is";
    /// How long the model follows the AC drive after it starts, s.
    7 CheckSeconds check_seconds: f32 = 0.5, "s", ">= 0";
    /// Largest relative difference allowed between the natural frequency at the table's bias
    /// and at the direct solve's (the two biases differ by the table's interpolation).
    8 Agreement agreement: f32 = 1e-4, "fraction", "> 0";
    /// Largest difference between the amplifier's monitored output and the last command,
    /// V, for more than `AMPLIFIER_TICKS` ticks in a row (a saturated or failed amplifier).
    9 AmplifierToleranceVolts amplifier_tolerance_volts: f32 = 200.0, "V", "> 0";
    /// Bit-identical sensor samples in a row that mean a stuck sensor (`None`: no such
    /// check; a real sensor's noise never repeats that long).
    10 StuckSamples stuck_samples: Option<u32> = Some(100), "samples", ">= 1 or off";
    /// Closed-loop trim: the relative frequency error to reach (`None`: no trim). Needs the
    /// stretch sensor or the amplifier's current monitor (`Inputs`), and the `cross_check`
    /// stage (the model is re-solved on the chip).
    11 TrimTolerance trim_tolerance: Option<f32> = None, "fraction",
        "> 0 or off, in a build with the trim";
    /// The ring measured after each pulse, s: at least `MIN_WINDOW_PERIODS` target periods, and
    /// averaged into at most `MAX_WINDOW` samples, at least `MIN_SAMPLES_PER_PERIOD` a period.
    12 TrimWindowSeconds trim_window_seconds: f32 = 0.5, "s",
        "at least 4 target periods long, and once its ticks are averaged into 512 \
         samples, at least 8 samples per target period (at most 64 periods)";
    /// The pulse's drop below the bias, V, for half a period of the target.
    13 TrimPulseVolts trim_pulse_volts: f32 = 200.0, "V", ">= 0";
    /// The first bias the trim measures at, as a fraction of the nominal cap at most: a
    /// plant softer than the model by a factor r has its limit √r lower, so a fraction p
    /// covers plants down to r = p².
    14 TrimProbeFraction trim_probe_fraction: f32 = 0.5, "fraction", "in (0, 1]";
    /// Trim again after this long of AC drive, s (`None`: once): for a plant that drifts,
    /// as a viscoelastic membrane creeps. The AC pauses while the ring is measured.
    15 TrimEverySeconds trim_every_seconds: Option<f32> = None, "s", "> 0 or off";
    /// The leakage watch (model.md §8): the membrane's leakage resistance, from the DC part
    /// of the amplifier's current against the voltage over each `LEAKAGE_WINDOW_SECONDS` at
    /// a steady bias, must stay above this, Ω (`None`: no watch). A falling leakage
    /// resistance is a precursor of breakdown. Needs the current monitor.
    16 LeakageFloorOhms leakage_floor_ohms: Option<f32> = None, "ohm", "> 0 or off";
    /// The leakage watch's second test: from one window to the next, the leakage resistance
    /// may fall by at most this fraction a second, where the fall stands out of the current's
    /// scatter (`None`: no such test). A fast fall comes before breakdown, far above a floor.
    17 LeakageFallPerSecond leakage_fall_per_second: Option<f32> = None, "1/s", "> 0 or off";
    /// Resonance tracking while driving (feature `track`, `crate::estimate::lockin`): the
    /// drive follows the resonance measured in the stretch with this time constant, s, and
    /// the bias is retuned to the target within `trim_tolerance` without pausing the drive
    /// (`None`: off). Needs the stretch sensor and a trim; not with `trim_every_seconds`.
    18 TrackSeconds track_seconds: Option<f32> = None, "s",
        "> 0 or off; with the track build, a trim, ac_volts > 0 and no trim_every_seconds";
    /// The stretch from the capacitance (feature `probe`, `crate::estimate::capacitance`): a
    /// square probe of this amplitude, V, rides on the bias (`None`: off). The current
    /// monitor's lock-in on it gives λ with its uncertainty, checked against model.md §6
    /// widened by it. Off while the trim measures a ring.
    19 ProbeVolts probe_volts: Option<f32> = None, "V",
        "> 0 or off, in a build with the probe; the probe and the AC about the bias \
         within [0 V, the cap in force]";
    /// The probe's frequency, Hz: half the tick rate over a whole number (its sign flips
    /// every so many ticks).
    20 ProbeHz probe_hz: f32 = 500.0, "Hz",
        "at least 4x target_hz, a whole number of ticks per half period";
    /// The amplifier's slew rate, V/s, as its maker states it (`None`: not declared): a
    /// drive steeper than it is refused before it starts — the AC's steepest slope
    /// 2π·ac_hz·ac_volts (a tracked drive's at the highest frequency it may follow, on the
    /// bias moving at `slew_volts_per_second`), and the bias ramp.
    21 AmplifierSlewVoltsPerSecond amplifier_slew_volts_per_second: Option<f32> = None, "V/s",
        "> 0 or off; at least the AC's slope 2π·ac_hz·ac_volts and slew_volts_per_second";
    /// The amplifier's bandwidth, Hz, as its maker states it (`None`: not declared): a
    /// first-order response, gain 1/√(1 + x²) and lag atan(x) at x = f/bandwidth. The
    /// drive's swing is bounded at the output too (`Device::check_swing`), a tracked drive's
    /// phase read against the output's, and a drive the output would follow further off its
    /// command than `amplifier_tolerance_volts` refused before it starts.
    22 AmplifierBandwidthHz amplifier_bandwidth_hz: Option<f32> = None, "Hz",
        "> 0 or off; the output within amplifier_tolerance_volts of the ramp and the AC";
}

/// Where the amplifier's following error over the AC's amplitude, x/√(1 + x²)·(1 + cos φ·
/// e^(−(π/2 + φ)/x)) (`Settings::ac_following_volts`), is largest: x = f/bandwidth.
const FOLLOWING_PEAK_X: f32 = 4.918;

/// A setting its checks refuse: which, with the value found (the controller's
/// `Fault::Setting`); a margin out of range is the tuner's error (`Fault::Tune`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SettingError {
    Setting {
        setting: Setting,
        value: f32,
    },
    Margin {
        margin: f32,
    },
    /// The drive `setting` asks for (the AC, or the bias ramp) moves the output faster than
    /// the amplifier's declared slew rate: both, V/s.
    Steeper {
        setting: Setting,
        volts_per_second: f32,
        amplifier_volts_per_second: f32,
    },
    /// The amplifier's output, of the declared bandwidth, follows the drive `setting` asks
    /// for (the AC, or the bias ramp) further off its command than the watch allows: both, V.
    Lags {
        setting: Setting,
        following_volts: f32,
        tolerance_volts: f32,
    },
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
    /// number (within 1e-4) of at least 1; else an error naming `probe_hz`.
    pub(super) fn probe_half_ticks(&self) -> Result<u32, SettingError> {
        let hz = self.probe_hz;
        let half = self.tick_hz / (2.0 * hz);
        let whole = libm::roundf(half);
        if !(hz > 0.0 && whole >= 1.0 && (half - whole).abs() <= 1e-4 * whole && whole < 1e6) {
            return Err(SettingError::Setting {
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
    /// probe (its frequency, once on, 500 Hz): `DEFAULTS` but the target.
    pub const fn for_target(target_hz: f32) -> Self {
        Self {
            target_hz,
            ..Self::DEFAULTS
        }
    }

    /// Every setting in its range (the trim's only with the `trim` feature): the first that
    /// is not, with its value, or the margin.
    pub(super) fn check(&self) -> Result<(), SettingError> {
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
                return Err(SettingError::Setting {
                    setting: Setting::TrimTolerance,
                    value: trim,
                });
            }
        }
        if self.stuck_samples == Some(0) {
            return Err(SettingError::Setting {
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
            return Err(SettingError::Setting {
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
                return Err(SettingError::Setting {
                    setting: Setting::TrackSeconds,
                    value: seconds,
                });
            }
        }
        if let Some(volts) = self.probe_volts {
            positive(Setting::ProbeVolts, volts)?;
            if !cfg!(feature = "probe") {
                return Err(SettingError::Setting {
                    setting: Setting::ProbeVolts,
                    value: volts,
                });
            }
            self.probe_half_ticks()?;
            // Well above the resonance: the motion the probe drives stays small against the
            // AC's (it is not in the edges' charge, `crate::estimate::capacitance`, but moves λ).
            if !(self.probe_hz >= PROBE_ABOVE_TARGET * self.target_hz) {
                return Err(SettingError::Setting {
                    setting: Setting::ProbeHz,
                    value: self.probe_hz,
                });
            }
        }
        let probe = positive(Setting::TrimProbeFraction, self.trim_probe_fraction)?;
        if !(probe <= 1.0) {
            return Err(SettingError::Setting {
                setting: Setting::TrimProbeFraction,
                value: probe,
            });
        }
        // Below Nyquist; and AC volts without a frequency would drive nothing, silently.
        if !(ac_hz < 0.5 * tick_hz) || (self.ac_volts > 0.0 && ac_hz == 0.0) {
            return Err(SettingError::Setting {
                setting: Setting::AcHz,
                value: ac_hz,
            });
        }
        if !(self.margin >= 0.0 && self.margin < 1.0) {
            return Err(SettingError::Margin {
                margin: self.margin,
            });
        }
        if let Some(slew) = self.amplifier_slew_volts_per_second {
            let amplifier_volts_per_second = positive(Setting::AmplifierSlewVoltsPerSecond, slew)?;
            let steeper = |setting, volts_per_second: f32| {
                if volts_per_second <= amplifier_volts_per_second {
                    Ok(())
                } else {
                    Err(SettingError::Steeper {
                        setting,
                        volts_per_second,
                        amplifier_volts_per_second,
                    })
                }
            };
            steeper(Setting::SlewVoltsPerSecond, self.slew_volts_per_second)?;
            // (A target that is no frequency is the tuner's to name.)
            if target_ok {
                steeper(Setting::AcVolts, self.ac_slope_volts_per_second())?;
            }
        }
        if let Some(bandwidth) = self.amplifier_bandwidth_hz {
            positive(Setting::AmplifierBandwidthHz, bandwidth)?;
            let tolerance_volts = self.amplifier_tolerance_volts;
            let lags = |setting, following_volts: f32| {
                if following_volts <= tolerance_volts {
                    Ok(())
                } else {
                    Err(SettingError::Lags {
                        setting,
                        following_volts,
                        tolerance_volts,
                    })
                }
            };
            lags(Setting::SlewVoltsPerSecond, self.ramp_following_volts())?;
            if target_ok {
                lags(Setting::AcVolts, self.ac_following_volts())?;
            }
        }
        Ok(())
    }

    /// The amplifier's lag at `hz`, rad (`amplifier_bandwidth_hz`, first order): atan(x),
    /// x = hz/bandwidth; 0 where none is declared.
    pub fn amplifier_lag(&self, hz: f32) -> f32 {
        match self.amplifier_bandwidth_hz {
            Some(bandwidth) if bandwidth > 0.0 => libm::atanf(hz / bandwidth),
            _ => 0.0,
        }
    }

    /// The lowest and highest frequencies the AC may run at, Hz: `ac_hz`; a tracked drive
    /// follows the resonance up to `MAX_DETUNING` off the target either way.
    pub fn ac_hz_span(&self) -> (f32, f32) {
        match self.track_seconds {
            Some(_) => {
                let detuning = crate::estimate::lockin::MAX_DETUNING;
                (
                    self.ac_hz.min(self.target_hz * (1.0 - detuning)),
                    self.ac_hz.max(self.target_hz * (1.0 + detuning)),
                )
            }
            None => (self.ac_hz, self.ac_hz),
        }
    }

    /// The amplifier's gain at `hz` (`amplifier_bandwidth_hz`, first order): 1/√(1 + x²),
    /// x = hz/bandwidth; 1 where none is declared.
    pub fn amplifier_gain(&self, hz: f32) -> f32 {
        match self.amplifier_bandwidth_hz {
            Some(bandwidth) if bandwidth > 0.0 => 1.0 / libm::hypotf(1.0, hz / bandwidth),
            _ => 1.0,
        }
    }

    /// How far the amplifier's output lags a ramp at `slew_volts_per_second`, V: the slew
    /// over 2π·bandwidth (a first order's settled lag; 0 where no bandwidth is declared).
    pub fn ramp_following_volts(&self) -> f32 {
        match self.amplifier_bandwidth_hz {
            Some(bandwidth) => self.slew_volts_per_second / (core::f32::consts::TAU * bandwidth),
            None => 0.0,
        }
    }

    /// The most the amplifier's output is off the AC's command, V, switched on included:
    /// the settled difference A·x/√(1 + x²) (x = f/bandwidth), and on the first lobe against
    /// the switch-on's decaying term, at most cos φ·e^(−(π/2 + φ)/x) of it more (φ = atan x);
    /// the two together rise to 1.0873·A at x = 4.918 and fall after, so taken at the x of
    /// the frequencies the AC may run nearest that; a tracked drive's bias moves meanwhile
    /// (`ramp_following_volts`). 0 where no bandwidth is declared.
    pub fn ac_following_volts(&self) -> f32 {
        let Some(bandwidth) = self.amplifier_bandwidth_hz else {
            return 0.0;
        };
        let (lowest, highest) = self.ac_hz_span();
        // (Not `clamp`: it panics on NaN.)
        let x = FOLLOWING_PEAK_X
            .max(lowest / bandwidth)
            .min(highest / bandwidth);
        if !(x > 0.0) {
            return 0.0;
        }
        let lag = libm::atanf(x);
        let settled = self.ac_volts * x / libm::hypotf(1.0, x);
        let transient = libm::cosf(lag) * libm::expf(-(core::f32::consts::FRAC_PI_2 + lag) / x);
        let ramp = match self.track_seconds {
            Some(_) => self.ramp_following_volts(),
            None => 0.0,
        };
        settled * (1.0 + transient) + ramp
    }

    /// The steepest the AC drive moves the output, V/s: 2π·ac_hz·ac_volts; a tracked drive
    /// at the highest frequency it may follow (`MAX_DETUNING` above the target, where the
    /// tracker lets go), on a bias that may move at the ramp's rate meanwhile. The probe's
    /// square wave and the trim's pulse (a drop) are steps by design, not counted.
    pub fn ac_slope_volts_per_second(&self) -> f32 {
        let slope = core::f32::consts::TAU * self.ac_hz_span().1 * self.ac_volts;
        match self.track_seconds {
            Some(_) => slope + self.slew_volts_per_second,
            None => slope,
        }
    }
}

impl Setting {
    /// Whether it counts something: a fraction is refused, never rounded.
    pub fn whole(self) -> bool {
        matches!(self, Setting::StuckSamples)
    }

    /// The setting with this key.
    pub fn from_key(key: &str) -> Option<Setting> {
        Setting::ALL.into_iter().find(|s| s.key() == key)
    }

    /// The setting with this stable id.
    pub fn from_id(id: u8) -> Option<Setting> {
        Setting::ALL.into_iter().find(|s| s.id() == id)
    }

    /// Its stable id: what a saved blob and an image keep it by, never reused.
    pub const fn id(self) -> u8 {
        self as u8
    }

    /// Its default (`Settings::DEFAULTS`; 0 for one off by default).
    pub fn default_value(self) -> f32 {
        Settings::DEFAULTS.get(self)
    }

    /// Its doc comment, line by line.
    pub fn doc(self) -> impl Iterator<Item = &'static str> {
        self.doc_lines().iter().map(|l| l.trim())
    }
}

/// Some settings (by id): which a saved blob or an image holds, or lacks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SettingSet(u32);

// Room for every id in a set's word.
const _: () = {
    let mut rest: &[Setting] = &Setting::ALL;
    while let [first, more @ ..] = rest {
        assert!((*first as u8) < 32, "a setting's id past its set's word");
        rest = more;
    }
};

impl SettingSet {
    /// None.
    pub const EMPTY: SettingSet = SettingSet(0);

    /// This set with `setting` in it.
    pub fn with(self, setting: Setting) -> Self {
        SettingSet(self.0 | 1 << setting.id())
    }

    pub fn contains(self, setting: Setting) -> bool {
        self.0 & 1 << setting.id() != 0
    }

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The settings in both.
    pub fn and(self, other: Self) -> Self {
        SettingSet(self.0 & other.0)
    }

    /// Every setting not in this set.
    pub fn others(self) -> Self {
        Setting::ALL
            .into_iter()
            .filter(|s| !self.contains(*s))
            .fold(SettingSet::EMPTY, SettingSet::with)
    }

    /// Its settings, by id.
    pub fn iter(self) -> impl Iterator<Item = Setting> {
        Setting::ALL.into_iter().filter(move |s| self.contains(*s))
    }
}

/// Settings as a saved blob or an image held them: the value of each setting it holds (an
/// older one lacks the settings added since).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Held {
    values: [f32; Setting::ALL.len()],
    held: SettingSet,
}

impl Held {
    /// Nothing held yet.
    pub const NONE: Held = Held {
        values: [0.0; Setting::ALL.len()],
        held: SettingSet::EMPTY,
    };

    /// Every setting of `settings`.
    pub fn all(settings: &Settings) -> Self {
        Setting::ALL
            .into_iter()
            .fold(Held::NONE, |h, s| h.with(s, settings.get(s)))
    }

    /// This with `setting` held at `value`.
    pub fn with(mut self, setting: Setting, value: f32) -> Self {
        if let Some(slot) = self.values.get_mut(usize::from(setting.id())) {
            *slot = value;
        }
        self.held = self.held.with(setting);
        self
    }

    /// The settings held, the others `base`'s; and which those others were.
    pub fn onto(&self, base: Settings) -> (Settings, SettingSet) {
        let mut settings = base;
        for setting in self.held.iter() {
            if let Some(&value) = self.values.get(usize::from(setting.id())) {
                settings.set(setting, value);
            }
        }
        (settings, self.held.others())
    }
}

/// How a setting's value is held: a number, or one that can be off (`None`), read and
/// written as 0 (a count rounded down, saturating).
trait Slot {
    fn read(&self) -> f32;
    fn write(&mut self, value: f32);
}

impl Slot for f32 {
    fn read(&self) -> f32 {
        *self
    }
    fn write(&mut self, value: f32) {
        *self = value;
    }
}

impl Slot for Option<f32> {
    fn read(&self) -> f32 {
        self.unwrap_or(0.0)
    }
    fn write(&mut self, value: f32) {
        *self = (value != 0.0).then_some(value);
    }
}

impl Slot for Option<u32> {
    fn read(&self) -> f32 {
        self.map_or(0.0, |n| n as f32)
    }
    fn write(&mut self, value: f32) {
        *self = (value != 0.0).then_some(value as u32);
    }
}

fn positive(setting: Setting, value: f32) -> Result<f32, SettingError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(SettingError::Setting { setting, value })
    }
}

fn non_negative(setting: Setting, value: f32) -> Result<f32, SettingError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(SettingError::Setting { setting, value })
    }
}
