//! The boot stages, in order: `from_table` (device, settings, table), `cross_check` (the
//! direct solve on the chip, model.md §6–§7) and `check_plan` (the plan through the model,
//! model.md §6). A firmware may take the first alone, or the first two.

use super::envelope::Predicted;
use super::fault::Fault;
use super::plan::Plan;
use super::settings::{guarded, Settings};
use super::{Controller, State};
use crate::acquire::InputNoise;
use crate::drive::Amplifier;
use crate::model::device::{Device, DeviceParams, Field};
use crate::model::safety::Limit;
use crate::model::swing::{AcDrive, Ramp, Swing};
#[cfg(feature = "probe")]
use crate::table::CapacitanceBands;
use crate::table::Table;
use crate::tuning::Tuner;

/// What the boot stages found.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Boot {
    /// The bias the controller drives (the direct solve's once cross-checked), V.
    pub bias_volts: f32,
    /// The table's interpolated bias for the target, V.
    pub table_volts: f32,
    /// The table's highest bias, V.
    pub table_top_volts: f32,
    /// The cap: no command goes above it, V.
    pub max_volts: f32,
    /// The first failure on the loading branch, found on the chip (`cross_check`).
    pub limit: Option<Limit<f32>>,
    /// The ticks of the plan up to the end of its model check.
    pub plan_ticks: u32,
    /// The stretch range the model run of the plan swept (`check_plan`).
    pub plan_stretch: Option<(f32, f32)>,
    /// The guaranteed limit of the batch the table was made for (model.md §10), V; `None`
    /// for a table of one device.
    pub batch_limit_volts: Option<f32>,
    /// Which bound set the cap after `cross_check`: the device's own limit, or the batch's.
    pub cap_by: CapBy,
}

/// The bound behind the cap: (1 − margin) times the flashed device's limit (found on the
/// chip), or times the guaranteed limit of the batch its table declares (model.md §10).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CapBy {
    Limit,
    Batch,
}

impl CapBy {
    /// As the boot's notice says it.
    pub fn name(self) -> &'static str {
        match self {
            CapBy::Limit => "limit",
            CapBy::Batch => "batch",
        }
    }
}

/// What `from_table` checks before a controller exists (small: the boot builds the controller
/// once, in its slot, and never moves it through the stages).
struct Checked {
    device: Device<f32>,
    /// The table's top, its bias for the target and the cap it gives, V.
    top_volts: f32,
    table_volts: f32,
    max_volts: f32,
    /// The table's batch's guaranteed limit, V, and its shear modulus range, Pa.
    batch_limit_volts: Option<f32>,
    batch_modulus: Option<(f32, f32)>,
    /// The batch's capacitance bands, for the probe's check (model.md §10).
    #[cfg(feature = "probe")]
    batch_capacitance: Option<CapacitanceBands>,
}

impl Checked {
    /// Check the device, the settings and the table; the cap from the table's top scaled to
    /// the settings' margin, top·min(1, (1 − margin)/(1 − table margin)), at most
    /// (1 − margin)·limit.
    fn new(params: DeviceParams<f32>, table: &[u8], settings: &Settings) -> Result<Self, Fault> {
        let device = Device::new(params).map_err(Fault::Device)?;
        let table = Table::parse(table).map_err(Fault::Table)?;
        table.check_device(&params).map_err(Fault::Table)?;
        // A target the table does not reach is the operator's reason: said before a setting
        // it would make wrong (the trim's window counts target periods).
        let in_range = settings.target_hz.is_finite() && settings.target_hz > 0.0;
        let table_volts = if in_range {
            Some(table.bias_volts(settings.target_hz).map_err(Fault::Table)?)
        } else {
            None
        };
        settings.check()?;
        let top_volts = table.max_volts();
        let batch = table.batch();
        Ok(Self {
            device,
            top_volts,
            table_volts: match table_volts {
                Some(volts) => volts,
                None => table.bias_volts(settings.target_hz).map_err(Fault::Table)?,
            },
            max_volts: top_volts * ((1.0 - settings.margin) / (1.0 - table.margin())).min(1.0),
            batch_limit_volts: batch.as_ref().map(|b| b.limit_volts),
            batch_modulus: batch
                .as_ref()
                .map(|b| (b.low.shear_modulus, b.high.shear_modulus)),
            #[cfg(feature = "probe")]
            batch_capacitance: batch.map(|b| b.capacitance),
        })
    }

    /// A controller with its first plan from the table, ramping from `from_volts`.
    fn controller(
        &self,
        board: (Amplifier, InputNoise),
        settings: Settings,
        from_volts: f32,
    ) -> Controller {
        let mut controller = Controller::new(self.device, board, settings, self.max_volts);
        controller.plan.start_volts = from_volts;
        controller.batch_modulus = self.batch_modulus;
        #[cfg(feature = "probe")]
        {
            controller.sensing.batch = self.batch_capacitance;
        }
        controller
    }

    /// `controller` built in `slot`. Not inlined: parts of the controller are built on this
    /// frame before they move to the slot (2,856 B on the firmware, its trim state), and this
    /// frame is gone before the checks that follow go deep (else it would sit under them, on
    /// the firmware's boot, `clear` and a replan).
    #[inline(never)]
    fn build_in<'s>(
        &self,
        slot: &'s mut Option<Controller>,
        board: (Amplifier, InputNoise),
        settings: Settings,
        from_volts: f32,
    ) -> &'s mut Controller {
        slot.insert(self.controller(board, settings, from_volts))
    }

    /// The first plan set, the boot so far.
    fn plan(&self, controller: &mut Controller) -> Result<Boot, Fault> {
        Ok(Boot {
            bias_volts: self.table_volts,
            table_volts: self.table_volts,
            table_top_volts: self.top_volts,
            max_volts: self.max_volts,
            limit: None,
            plan_ticks: controller.set_plan(self.table_volts)?,
            plan_stretch: None,
            batch_limit_volts: self.batch_limit_volts,
            cap_by: if self.batch_limit_volts.is_some() {
                CapBy::Batch
            } else {
                CapBy::Limit
            },
        })
    }
}

impl Controller {
    /// Every check: `from_table`, then `cross_check`, then `check_plan`.
    pub fn start(
        params: DeviceParams<f32>,
        table: &[u8],
        amplifier: Amplifier,
        settings: Settings,
    ) -> Result<(Self, Boot), Fault> {
        let (mut controller, boot) = Self::from_table(params, table, amplifier, settings)?;
        let boot = controller.cross_check(boot, table)?;
        let boot = controller.check_plan(boot)?;
        Ok((controller, boot))
    }

    /// `start` with the controller built in `slot`, where it stays through every stage (its
    /// one copy on the stack is in `Checked::build_in`'s frame, gone before the checks), on a
    /// board whose front end declares `inputs` (the trim's ring is weighed against them
    /// before any voltage). On a refusal the slot is left empty.
    pub fn start_in(
        slot: &mut Option<Self>,
        params: DeviceParams<f32>,
        table: &[u8],
        board: (Amplifier, InputNoise),
        settings: Settings,
    ) -> Result<Boot, Fault> {
        let result =
            Self::checks_in(slot, params, table, board, settings, (0.0, 0.0)).map(|(_, boot)| boot);
        if result.is_err() {
            *slot = None;
        }
        result
    }

    /// Every boot stage on the controller built in `slot`, the plan ramping from `from_volts`.
    pub(super) fn checks_in<'s>(
        slot: &'s mut Option<Self>,
        params: DeviceParams<f32>,
        table: &[u8],
        board: (Amplifier, InputNoise),
        settings: Settings,
        (from_volts, carried_ring_stretch): (f32, f32),
    ) -> Result<(&'s mut Self, Boot), Fault> {
        let checked = Checked::new(params, table, &settings)?;
        let controller = checked.build_in(slot, board, settings, from_volts);
        controller.carried_ring_stretch = carried_ring_stretch;
        let boot = checked.plan(controller)?;
        let boot = controller.cross_check(boot, table)?;
        let boot = controller.check_plan(boot)?;
        Ok((controller, boot))
    }

    /// Check the device, the settings and the table, and plan from the table alone: the bias
    /// by interpolation, commands capped at the table's top scaled to the settings' margin.
    pub fn from_table(
        params: DeviceParams<f32>,
        table: &[u8],
        amplifier: Amplifier,
        settings: Settings,
    ) -> Result<(Self, Boot), Fault> {
        let checked = Checked::new(params, table, &settings)?;
        let board = (amplifier, InputNoise::UNDECLARED);
        let mut controller = checked.controller(board, settings, 0.0);
        let boot = checked.plan(&mut controller)?;
        Ok((controller, boot))
    }

    /// Find the limit and the bias on the chip by the direct solve: the table's cap (its top,
    /// scaled down to a larger margin than the table's) must lie below (1 − margin)·limit,
    /// and the natural frequencies at the two biases must agree. The controller then drives
    /// the solve's bias, capped at (1 − margin)·(1 − F32_GUARD)·limit. The drive's swing is
    /// checked there (on the device flashed, and at the corners of the batch `table`
    /// declares, if any: `table` is the one `from_table` took), and its prediction set for
    /// the swing's watch. On a refusal the controller is left faulted at 0 V: a stage's
    /// caller that carried on with it would drive nothing.
    pub fn cross_check(&mut self, boot: Boot, table: &[u8]) -> Result<Boot, Fault> {
        let checked = self.cross_checked(boot, table);
        if let Err(fault) = checked {
            self.fault(fault);
        }
        checked
    }

    fn cross_checked(&mut self, boot: Boot, table: &[u8]) -> Result<Boot, Fault> {
        let settings = self.settings;
        let tuner = Tuner::new(self.flashed);
        let limit = tuner.limit();
        let margin = guarded(settings.margin);
        let own_volts = tuner.max_bias(margin).map_err(Fault::Tune)?.volts;
        // A batch's table: never above (1 − margin) times its guaranteed limit, which no
        // device of the batch fails below (the flashed device is one of them).
        let (max_volts, cap_by) = match boot.batch_limit_volts {
            Some(limit) if (1.0 - margin) * limit < own_volts => {
                ((1.0 - margin) * limit, CapBy::Batch)
            }
            _ => (own_volts, CapBy::Limit),
        };
        if !(boot.max_volts <= max_volts) {
            return Err(Fault::AboveSafe {
                volts: boot.max_volts,
                max_volts,
            });
        }
        let solved = tuner
            .tune(settings.target_hz, margin)
            .map_err(Fault::Tune)?;
        let table_hz = self
            .flashed
            .offset_for_bias(boot.table_volts, limit.at.offset)
            .map(|offset| self.flashed.natural_frequency_hz_at(offset))
            .unwrap_or(f32::NAN);
        let solved_hz = solved.natural_frequency_hz;
        if !((table_hz - solved_hz).abs() <= settings.agreement * solved_hz) {
            return Err(Fault::Disagree {
                table_volts: boot.table_volts,
                table_hz,
                solved_volts: solved.volts,
                solved_hz,
            });
        }
        // The ceiling, and the boot's plan's cap with it: the solve's, not the table's.
        self.ceiling_volts = max_volts;
        self.set_caps(max_volts, self.estimate_volts);
        let plan_ticks = self.set_plan(solved.volts)?;
        // The monitor's band for the checks no voltage enters, about the tuned bias.
        let stretch = self
            .flashed
            .offset_for_bias(solved.volts, limit.at.offset)
            .map_or(f32::NAN, |offset| self.flashed.stretch_at(offset));
        self.watch.band = self.flashed.stretch_band(stretch, settings.margin);
        // The swing about the tuned bias, with the device's damping (model.md §7): the
        // ramp's ring (and a way down's before it: a boot follows `clear` at 0 V, however
        // the membrane still rings) and the drive's, if any, inside the margin of every
        // check, or refused before anything is driven. A tracked drive follows the
        // resonance: checked there.
        let drive = AcDrive {
            bias_volts: solved.volts,
            ac_volts: if settings.ac_hz > 0.0 {
                settings.ac_volts
            } else {
                0.0
            },
            ac_hz: match settings.track_seconds {
                Some(_) => solved.natural_frequency_hz,
                None => settings.ac_hz,
            },
            amplifier_bandwidth_hz: settings.amplifier_bandwidth_hz.unwrap_or(f32::INFINITY),
            ring_stretch: self.pulse_ring(solved.volts, limit.at.offset)
                + self.carried_ring_stretch,
            ramp: Some(Ramp {
                from_volts: self.plan.start_volts,
                slew_volts_per_second: settings.slew_volts_per_second,
                settle_seconds: settings.settle_seconds,
                after_descent: true,
            }),
        };
        let batch = boot.batch_limit_volts.map(|_| table);
        let checked = self.checked_swing(drive, limit.at.offset, settings.margin, batch);
        let swing = match checked {
            // No damping told, and a trim whose ring measures the plant's Q before the AC
            // starts (the AC waits for it): where some Q would let the drive fit (it does at
            // Q = 1: the swing only grows with Q), the ramp's and the pulse's rings are
            // checked now, the drive's swing with the measured Q when the trim converges
            // (`TrimJob::restart_swing`), a fault there if it does not fit. Not for a
            // batch's table: its corners are checked here only.
            Err(Fault::DriveSwing(_))
                if self.quality_to_measure()
                    && batch.is_none()
                    && self
                        .flashed
                        .check_swing(drive, limit.at.offset, Some(1.0), settings.margin)
                        .is_ok() =>
            {
                let quiet = AcDrive {
                    ac_volts: 0.0,
                    ..drive
                };
                self.checked_swing(quiet, limit.at.offset, settings.margin, batch)?;
                None
            }
            checked => Some(checked?),
        };
        // A dead DAC bus drops the output from the plan's top to 0 V at once: its rebound
        // from rest there (the swing it may have then is not counted: docs/safety.md).
        let top_volts = solved.volts + settings.swing_volts();
        self.flashed
            .check_drop(top_volts, 0.0, limit.at.offset, settings.margin)
            .map_err(|e| Fault::of_drop(top_volts, e))?;
        // What the board then watches the measured swing against (`envelope`).
        self.watch
            .predict(swing.filter(|_| drive.ac_volts > 0.0).map(|swing| {
                let noise = self.inputs.stretch;
                Predicted::of(&swing, drive.ac_hz, settings.margin, noise)
            }));
        // The ring the first pulse will leave at the bias it measures at, as the device's
        // damping leaves it over the window, against the noise the front end declares: now,
        // before any voltage, and by the tick before it pulses against the noise it hears.
        #[cfg(feature = "trim")]
        if self.trim_wanted() {
            let (bias, offset) = (self.plan.bias_volts, limit.at.offset);
            let plan = (&self.flashed, offset, bias, &settings);
            if let Some(error) = self.trim.plan_ring(plan, self.inputs) {
                return Err(Fault::Trim(error));
            }
        }
        Ok(Boot {
            bias_volts: solved.volts,
            max_volts,
            limit: Some(*limit),
            plan_ticks,
            cap_by,
            ..boot
        })
    }

    /// The swing of `drive` on the device flashed (its limit at `limit_offset`) and, for a
    /// batch's `table`, on the device at every corner of the batch's box (`corners_swing`):
    /// the first that does not fit refuses the drive, and the largest swing is the one the
    /// board watches. Out of line, as `corners_swing` (the stack's budget).
    #[inline(never)]
    fn checked_swing(
        &self,
        drive: AcDrive<f32>,
        limit_offset: f32,
        margin: f32,
        batch: Option<&[u8]>,
    ) -> Result<Swing<f32>, Fault> {
        let swing = self
            .flashed
            .check_swing(drive, limit_offset, None, margin)
            .map_err(Fault::DriveSwing)?;
        match batch {
            Some(table) => self.corners_swing(table, &drive, margin, swing),
            None => Ok(swing),
        }
    }

    /// The swing of `drive` at every corner of the box of the batch `table` declares (each
    /// device at its own equilibrium, below its own limit; the damping the flashed
    /// device's), the widest of them and `widest`. A box spread in n parameters has 2ⁿ
    /// corners: a boot's work, not a tick's. The box is read from the table here, not kept
    /// (the stack's budget: the boot's frames hold a controller).
    #[inline(never)]
    fn corners_swing(
        &self,
        table: &[u8],
        drive: &AcDrive<f32>,
        margin: f32,
        mut widest: Swing<f32>,
    ) -> Result<Swing<f32>, Fault> {
        let Some(batch) = Table::parse(table).map_err(Fault::Table)?.batch() else {
            return Ok(widest);
        };
        let (low, high) = (batch.low, batch.high);
        let spread = |f: &Field| *f != Field::Damping && low.get(*f) != high.get(*f);
        let n = Field::ALL.iter().filter(|f| spread(f)).count();
        for corner in 0..1u32 << n {
            let mut params = low;
            for (bit, &field) in Field::ALL.iter().filter(|f| spread(f)).enumerate() {
                if corner & (1 << bit) != 0 {
                    params.set(field, high.get(field));
                }
            }
            params.damping = self.flashed.params().damping;
            // A corner that is no valid device is no membrane of the batch (as for its
            // guaranteed limit, `model::guaranteed`).
            let Ok(device) = Device::new(params) else {
                continue;
            };
            let offset = Limit::of(&device).at.offset;
            let swing = device
                .check_swing(*drive, offset, None, margin)
                .map_err(Fault::DriveSwing)?;
            if swing.high_stretch - swing.low_stretch > widest.high_stretch - widest.low_stretch {
                widest = swing;
            }
        }
        Ok(widest)
    }

    /// Run the whole plan through the model (f32 RK4 under the monitor, from rest at the
    /// equilibrium of its first voltage: the pre-stretch from 0 V) and refuse it if a limit
    /// is crossed on the way; refused, the controller is left faulted at 0 V.
    pub fn check_plan(&mut self, boot: Boot) -> Result<Boot, Fault> {
        let checked = self.plan_checked(boot);
        if let Err(fault) = checked {
            self.fault(fault);
        }
        checked
    }

    fn plan_checked(&self, boot: Boot) -> Result<Boot, Fault> {
        let from_volts = self.plan.start_volts;
        let device = &self.flashed;
        let start = if from_volts > 0.0 {
            // Below the cap, so below the limit found by `cross_check` (a replan's boot).
            boot.limit
                .and_then(|limit| device.offset_for_bias(from_volts, limit.at.offset))
                .map(|offset| device.stretch_at(offset))
                .ok_or(Fault::AboveSafe {
                    volts: from_volts,
                    max_volts: boot.max_volts,
                })?
        } else {
            device.prestretch_1()
        };
        let stretch =
            self.plan
                .run_in_model(device, self.settings.tick_hz, boot.plan_ticks, start)?;
        Ok(Boot {
            plan_stretch: Some(stretch),
            ..boot
        })
    }

    /// Plan a ramp from where the present plan starts (0 V at boot) to the bias for
    /// `tuned_volts` (with a trim, first to a probe bias low enough for a softer plant), the
    /// hold and the AC drive, its whole range under the cap; the ticks up to the end of its
    /// model check.
    fn set_plan(&mut self, tuned_volts: f32) -> Result<u32, Fault> {
        let s = self.settings;
        let trimming = self.trim_wanted();
        let bias_volts = if trimming {
            tuned_volts.min(s.trim_probe_fraction * self.max_volts)
        } else {
            tuned_volts
        };
        let from_volts = self.plan.start_volts;
        let (plan, ticks) = Plan::ramp(&s, from_volts, bias_volts, !trimming)?;
        plan.check_range(tuned_volts, self.max_volts)?;
        // The amplifier must give the highest voltage: the AC's and the probe's peak on the
        // tuned bias (the ramp starts at 0 V and ends at a bias no higher, the trim's first
        // bias included).
        let peak_volts = tuned_volts + plan.swing_volts();
        self.amplifier.code(peak_volts).map_err(Fault::Amplifier)?;
        self.plan = plan;
        self.state = State::Ramping {
            then_measure: trimming,
        };
        self.set_tuned(bias_volts == tuned_volts);
        Ok(ticks)
    }
}
