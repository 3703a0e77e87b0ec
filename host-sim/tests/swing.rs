//! The drive's swing (issue 44): a drive is accepted only where its swing, settled and on the
//! way there, stays inside the margin of model.md §6, and the monitor takes it off before a
//! limit. Checked on the full plant in f64 (the scenes' simulator: an independent solve of
//! the equation of motion, with the plant's own damping and viscous branches), never on the
//! core's prediction.

use de_resonator::wire::protocol::ErrorCode;
use de_resonator::{AcDrive, Device, DeviceParams, Phase, Ramp, Settings, SwingError, Tuner};

use host_sim::engine::closed_loop::Run;
use host_sim::scene;

/// The VHB-like membrane (μ 60 kPa, 0.5 mm, 3 × 3, no damping given): tuned to
/// 33 Hz, then `ac 80 33` on a plant of Q 1000. Before, `ok`, and the plant's field reached
/// breakdown 1.17 s later; now the drive is refused (no damping known at the resonance) and
/// the plant never crosses.
#[test]
fn an_ac_at_the_resonance_of_an_undamped_device_is_refused_and_the_plant_stays_safe() {
    let run = vhb_like(1000.0, 0.0, 4.0, "ac 80 33");
    assert_eq!(run.plant_crossing, None, "{:?}", run.fault_words);
    let reply = &run.commands[0].reply;
    assert!(
        reply.starts_with(&format!(
            "err {} drive refused: the swing has no bound in the model: harmonic",
            ErrorCode::Refused
        )) && reply.contains("give the device's damping")
            && reply.contains("largest AC that fits is 0 V"),
        "{reply}"
    );
    // The bias still held, nothing faulted: the refusal leaves the board as it was.
    assert!(run.fault.is_none(), "{:?}", run.fault_words);
    assert!(run.bias_volts > 3000.0, "{}", run.bias_volts);
}

/// The same membrane told its damping (Q 300 at 33 Hz), on plants of Q 300 and of 1000
/// (damped less than told): `ac 40 33` is checked on the model with that damping, and
/// either taken, the plant never crossing (the monitor, if it acts, before the limit), or
/// refused with the largest AC that fits (as it is today: 9.0 V fits).
#[test]
fn a_drive_told_its_damping_is_taken_or_refused_and_the_plant_stays_safe() {
    for plant_q in [300.0, 1000.0] {
        let run = vhb_like(plant_q, 300.0, 20.0, "ac 40 33");
        assert_eq!(
            run.plant_crossing, None,
            "plant Q {plant_q}: {:?}; {:?}",
            run.fault_words, run.commands
        );
        let reply = &run.commands[0].reply;
        if let Some(words) = &run.fault_words {
            assert!(words.contains("near a limit"), "plant Q {plant_q}: {words}");
        }
        assert!(
            reply == "ok" || reply.contains("largest AC"),
            "plant Q {plant_q}: {reply}"
        );
    }
}

/// The swing predicted at the amplifier's output (issue 60: its bandwidth declared): behind
/// an amplifier of 33 Hz, the resonant `ac … 33` reaches the membrane at 1/√2 of its
/// command, so the largest AC that fits (the refusal's figure) is up to √2 times the one
/// behind 2 kHz (the harmonic term scales by the gain; the 2Ω term, the pumping and the
/// output's decaying term at the switch-on are kept as commanded: within 3% of √2, never
/// above it). Driven at that largest command
/// on the plant behind that amplifier (Q 300 told and true), five ring times: nothing
/// crosses, nothing faults (the measured swing stays inside the prediction widened by the
/// margin).
#[test]
fn the_swing_is_predicted_at_the_amplifier_s_output() {
    let largest = |bandwidth_hz: f64| {
        let run = vhb_like_behind(300.0, 300.0, bandwidth_hz, 1.5, "ac 40 33");
        let reply = &run.commands[0].reply;
        let figure: f64 = reply
            .split("largest AC that fits is ")
            .nth(1)
            .and_then(|w| w.split(' ').next())
            .and_then(|w| w.parse().ok())
            .unwrap_or_else(|| panic!("{reply}"));
        figure
    };
    let fast = largest(2000.0);
    let slow = largest(33.0);
    let expected = std::f64::consts::SQRT_2 / (1.0 + (33.0f64 / 2000.0).powi(2)).sqrt();
    assert!(
        slow / fast <= 1.001 * expected && slow / fast >= 0.97 * expected,
        "{slow} V behind 33 Hz, {fast} V behind 2 kHz"
    );
    let line = format!("ac {} 33", 0.999 * slow);
    let run = vhb_like_behind(
        300.0,
        300.0,
        33.0,
        1.0 + 5.0 * 300.0 / (std::f64::consts::PI * 33.0),
        &line,
    );
    assert!(
        run.commands[0].reply.starts_with("ok "),
        "{line}: {}",
        run.commands[0].reply
    );
    assert_eq!(run.plant_crossing, None, "{:?}", run.fault_words);
    assert!(run.fault.is_none(), "{:?}", run.fault_words);
}

/// A property over random valid devices: plants of Q from 10 to 10⁴ (a quarter with a
/// viscous branch), the device told the plant's damping, half of it or none; drives at, and
/// 1% and 3% off, f0, 2·f0 and f0/2, with amplitudes across all the cap allows; each run on
/// the full plant for five ring times Q/(π·f) after the drive starts. Zero crossings of any
/// check of §6; each refusal and each early stop says its figures. `SWING_CASES` sets the
/// number of cases (default 48).
#[test]
fn no_accepted_drive_crosses_a_limit_on_random_devices() {
    let cases = cases_from_env("SWING_CASES", 48);
    let mut rng = Rng(0x5eed_0044);
    let (mut refused, mut stopped, mut driven, mut tried) = (0, 0, 0, 0);
    let mut simulated_seconds = 0.0;
    let mut worst: f64 = 0.0;
    let defaults = Settings::for_target(1.0);
    while refused + stopped + driven < cases {
        tried += 1;
        assert!(tried < 50 * cases, "too few valid devices");
        let Some(case) = Case::random(&mut rng) else {
            continue;
        };
        simulated_seconds += case.duration_seconds;
        let run = run(&case.scene(), true);
        assert_eq!(
            run.plant_crossing, None,
            "{case:?}: {:?} {:?}",
            run.refused, run.fault_words
        );
        if let Some(words) = &run.refused {
            // A boot refusal with its figures: the swing's (the largest AC that fits), or
            // the plan's model run, or the AC's range under the cap.
            assert!(
                words.contains("largest AC") || words.contains(" V") || words.contains(" s"),
                "{case:?}: {words}"
            );
            refused += 1;
        } else if let Some(words) = &run.fault_words {
            assert!(
                words.contains("near a limit") || !words.contains("measured motion"),
                "{case:?}: the monitor acted at the limit, not before it: {words}"
            );
            stopped += 1;
        } else {
            driven += 1;
            if case.branch.is_none() {
                // The plant's own swing with the AC on against the prediction (f64, the
                // device told, the bias held): inside the box widened by the margin, and
                // how far out of the unwidened box it went.
                let swing = Device::new(case.params)
                    .unwrap()
                    .check_swing(
                        AcDrive {
                            bias_volts: run.bias_volts,
                            ac_volts: case.ac_volts,
                            ac_hz: case.ac_hz,
                            amplifier_bandwidth_hz: f64::INFINITY,
                            ring_stretch: 0.0,
                            ramp: Some(Ramp {
                                from_volts: 0.0,
                                slew_volts_per_second: defaults.slew_volts_per_second.into(),
                                settle_seconds: defaults.settle_seconds.into(),
                                after_descent: true,
                            }),
                        },
                        Tuner::new(Device::new(case.params).unwrap())
                            .limit()
                            .at
                            .offset,
                        None,
                        0.05,
                    )
                    .unwrap_or_else(|e| panic!("{case:?}: driven, yet {e}"));
                let driving = run
                    .history
                    .iter()
                    .filter(|s| s.phase == Some(Phase::Driving))
                    .map(|s| s.stretch);
                let (low, high) = driving.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
                    (l.min(x), h.max(x))
                });
                let out = ((swing.stretch - low) / (swing.stretch - swing.low_stretch))
                    .max((high - swing.stretch) / (swing.high_stretch - swing.stretch));
                assert!(
                    out <= 1.0 / 0.95,
                    "{case:?}: the plant swung λ {low} .. {high}, predicted {swing:?}"
                );
                if out.is_finite() {
                    worst = worst.max(out);
                }
            }
        }
    }
    println!(
        "swing: {cases} cases ({tried} drawn): {driven} driven to the end, {stopped} stopped \
         early, {refused} refused; {simulated_seconds:.0} s of plant simulated; the plant's \
         swing at most {worst:.3} of the predicted"
    );
    // The property must test drives, not only refusals.
    assert!(driven >= cases / 4, "{driven} of {cases} driven");
}

/// Issue 60's property: random devices on plants of Q 30 to 3,000 whose device file states
/// 0.3 to 10 times the plant's damping, drives at and 1–3% off f0, 2·f0 and f0/2 at the
/// largest AC the board accepts (99% of the f64 check's largest that fits, the cap's room at
/// most). On the full plant with its sensor: zero crossings. Each case the board stopped is
/// run again blind (no sensor: nothing watches the motion): where the blind run crosses,
/// the board's fault came before it, by the margin printed (the least, in seconds and in
/// the plant's periods); one at least would have. A file that states no more damping than
/// the plant has is never stopped. `SWING_EDGE_CASES` sets the number of cases (default
/// 200); `SWING_EDGE_SHOW` prints each case and what the board said.
#[test]
fn the_watch_stops_an_accepted_drive_before_the_limit_whatever_the_file_says() {
    let cases = cases_from_env("SWING_EDGE_CASES", 200);
    let mut rng = Rng(0x5eed_0060);
    let (mut driven, mut stopped, mut refused, mut tried) = (0, 0, 0, 0);
    let (mut would_have_crossed, mut least_seconds, mut least_periods) =
        (0, f64::INFINITY, f64::INFINITY);
    let mut overstated_and_stopped = 0;
    while driven + stopped + refused < cases {
        tried += 1;
        assert!(tried < 50 * cases, "too few valid devices");
        let Some(case) = Case::edge(&mut rng) else {
            continue;
        };
        let run = run_crossing_nothing(&case);
        if std::env::var("SWING_EDGE_SHOW").is_ok() {
            println!(
                "f0 {:.2} Hz, plant Q {:.0}, told {:.2}× its damping, {:.1} V at {:.2} Hz for \
                 {:.2} s: {:?} {:?}",
                case.target_hz,
                case.plant_q,
                case.told,
                case.ac_volts,
                case.ac_hz,
                case.duration_seconds,
                run.refused,
                run.fault_words
            );
        }
        if run.refused.is_some() {
            refused += 1;
            continue;
        }
        let Some(words) = run.fault_words.clone() else {
            driven += 1;
            continue;
        };
        stopped += 1;
        assert!(
            words.contains("outgrew its prediction") || words.contains("near a limit"),
            "{case:?}: {words}"
        );
        // A file that states no more damping than the plant has: its prediction holds, and
        // the board never has to act.
        assert!(
            case.told > 1.0,
            "{case:?}: told {}, yet stopped: {words}",
            case.told
        );
        overstated_and_stopped += 1;
        let fault_seconds = run
            .events
            .iter()
            .find(|e| e.kind == de_resonator::EventKind::Fault)
            .map(|e| e.seconds)
            .unwrap_or_else(|| panic!("{case:?}: no fault event"));
        let blind = run_blind(&case.scene());
        if let Some((mode, crossed_seconds)) = blind.plant_crossing {
            would_have_crossed += 1;
            let margin = crossed_seconds - fault_seconds;
            assert!(
                margin > 0.0,
                "{case:?}: the fault at {fault_seconds} s, the blind plant crossed {mode:?} at \
                 {crossed_seconds} s"
            );
            least_seconds = least_seconds.min(margin);
            least_periods = least_periods.min(margin * case.target_hz);
        }
    }
    println!(
        "swing edge: {cases} cases ({tried} drawn): {driven} driven to the end, {stopped} \
         stopped by the board ({overstated_and_stopped} of them with the damping overstated), \
         {refused} refused; {would_have_crossed} would have crossed blind, the board's fault \
         at least {least_seconds:.3} s ({least_periods:.1} periods) before"
    );
    assert!(
        driven + stopped >= cases / 2,
        "{driven} driven, {stopped} stopped"
    );
    // The property must meet a case the board saved, not only cases that stayed inside.
    assert!(would_have_crossed >= 1, "no case would have crossed blind");
}

/// The swing behind a slow amplifier (issue 60, its bandwidth declared): random devices as
/// in the property above, the file telling the plant's damping as it is, behind a first-order
/// amplifier of 0.5 to 5 times the drive's frequency, the AC the largest the board takes
/// behind it. On the full plant (its amplifier that slow): zero crossings, and the board
/// never has to act (a prediction at the output that fell short would be taken off by the
/// swing's watch). Where the swing, not the cap, bounds the AC, the amplifier lets the board
/// take more than the same drive undeclared: 5% more in 4 of the 40 (asserted: 2 at least).
/// `SWING_SLOW_CASES` sets the number of cases (default 40).
#[test]
fn the_swing_behind_a_slow_amplifier_holds_on_random_devices() {
    let cases = cases_from_env("SWING_SLOW_CASES", 40);
    let mut rng = Rng(0x5eed_0061);
    let (mut driven, mut refused, mut tried, mut gained) = (0, 0, 0, 0);
    while driven + refused < cases {
        tried += 1;
        assert!(tried < 50 * cases, "too few valid devices");
        let Some(case) = Case::edge_behind(&mut rng, true) else {
            continue;
        };
        let run = run_crossing_nothing(&case);
        if run.refused.is_some() {
            refused += 1;
            continue;
        }
        assert!(run.fault_words.is_none(), "{case:?}: {:?}", run.fault_words);
        driven += 1;
        gained += usize::from(case.ac_volts >= 1.05 * case.undeclared_volts);
    }
    println!("swing behind a slow amplifier: {cases} cases ({tried} drawn): {driven} driven, {refused} refused; {gained} took 5% more AC than undeclared");
    assert!(driven >= cases / 2, "{driven} driven");
    assert!(gained >= 2, "{gained} gained");
}

/// A random device tuned inside its range (`Case::tuned`).
struct Tuned {
    params: DeviceParams<f64>,
    tuner: Tuner<f64>,
    target_hz: f64,
    bias: f64,
    room: f64,
}

/// One random case of the property.
#[derive(Debug)]
struct Case {
    params: DeviceParams<f64>,
    target_hz: f64,
    ac_volts: f64,
    ac_hz: f64,
    plant_q: f64,
    branch: Option<(f64, f64)>,
    tick_hz: f64,
    duration_seconds: f64,
    /// The plant's damping the device file states, over the plant's (1: told as it is).
    told: f64,
    /// The amplifier's bandwidth, Hz, declared to the board (∞: none, the scenes' default).
    bandwidth_hz: f64,
    /// The AC the same drive would take with no bandwidth declared (∞: not asked).
    undeclared_volts: f64,
}

impl Case {
    /// A random device (no damping), valid or not.
    fn random_device(rng: &mut Rng) -> DeviceParams<f64> {
        DeviceParams {
            shear_modulus: rng.log_range(20e3, 200e3),
            jlim: (rng.unit() < 0.7).then(|| rng.range(30.0, 200.0)),
            relative_permittivity: rng.range(3.0, 6.0),
            density: rng.range(900.0, 1200.0),
            breakdown_field: rng.log_range(50e6, 200e6),
            thickness: rng.log_range(0.2e-3, 2e-3),
            length_active: rng.range(10e-3, 40e-3),
            length_passive: rng.range(10e-3, 60e-3),
            width: rng.range(20e-3, 80e-3),
            bar_mass: rng.log_range(0.5e-3, 5e-3),
            prestretch_1: rng.range(1.2, 4.0),
            prestretch_2: rng.range(1.0, 4.0),
            damping: 0.0,
        }
    }

    /// A random device tuned inside its range (5–300 Hz) at margin 0.05: its tuner, the
    /// target, the bias and the room for an AC about it under the cap; `None` where any is
    /// wanting.
    fn tuned(rng: &mut Rng) -> Option<Tuned> {
        let params = Self::random_device(rng);
        let tuner = Tuner::new(Device::new(params).ok()?);
        let range = tuner.tunable_range(0.05).ok()?;
        let target_hz = range.low_hz + (range.high_hz - range.low_hz) * rng.range(0.05, 0.95);
        if target_hz.is_nan() || target_hz <= 5.0 || target_hz >= 300.0 {
            return None;
        }
        let bias = tuner.tune(target_hz, 0.05).ok()?.volts;
        let cap = tuner.max_bias(0.05).ok()?.volts;
        let room = bias.min(cap - bias);
        if room.is_nan() || room <= 1.0 {
            return None;
        }
        Some(Tuned {
            params,
            tuner,
            target_hz,
            bias,
            room,
        })
    }

    fn random(rng: &mut Rng) -> Option<Case> {
        let Tuned {
            mut params,
            target_hz,
            bias,
            room,
            ..
        } = Self::tuned(rng)?;
        let ac_volts = room * rng.log_range(0.02, 1.0);
        let near = [1.0, 2.0, 0.5][rng.below(3)];
        let off = [0.0, 0.01, -0.01, 0.03, -0.03][rng.below(5)];
        let ac_hz = target_hz * near * (1.0 + off);
        let plant_q = rng.log_range(10.0, 1e4);
        // The device told the plant's damping, half of it, or none.
        let told = [Some(1.0), Some(2.0), None][rng.below(3)];
        if let Some(factor) = told {
            let omega = std::f64::consts::TAU * target_hz;
            params.damping = params.effective_mass() * omega / (plant_q * factor);
        }
        let branch = (rng.unit() < 0.25).then(|| {
            (
                params.shear_modulus * rng.range(0.05, 0.3),
                rng.log_range(0.05, 5.0),
            )
        });
        let told = told.map_or(0.0, |factor| 1.0 / factor);
        Some(Case::at(
            params,
            (target_hz, bias),
            (ac_volts, ac_hz),
            (plant_q, told),
            branch,
            None,
        ))
    }

    /// A case of issue 60's property (`Case::random`'s devices): plant Q 30–3,000, the file
    /// stating `told` = 0.3–10 times the plant's damping, the AC the largest the board takes.
    fn edge(rng: &mut Rng) -> Option<Case> {
        Self::edge_behind(rng, false)
    }

    /// As `edge`; `slow`: the file told the plant's damping as it is, behind an amplifier of
    /// 0.5 to 5 times the drive's frequency (first order, declared), the AC the largest the
    /// board takes behind it (the watch's tolerance out of the way: 10 kV).
    fn edge_behind(rng: &mut Rng, slow: bool) -> Option<Case> {
        let Tuned {
            mut params,
            tuner,
            target_hz,
            bias,
            room,
        } = Self::tuned(rng)?;
        let near = [1.0, 2.0, 0.5][rng.below(3)];
        let off = [0.0, 0.01, -0.01, 0.03, -0.03][rng.below(5)];
        let ac_hz = target_hz * near * (1.0 + off);
        let plant_q = rng.log_range(30.0, 3000.0);
        let told = if slow {
            rng.log_range(0.3, 10.0);
            1.0
        } else {
            rng.log_range(0.3, 10.0)
        };
        let bandwidth_hz = if slow {
            ac_hz * rng.log_range(0.5, 5.0)
        } else {
            f64::INFINITY
        };
        let omega = std::f64::consts::TAU * target_hz;
        params.damping = told * params.effective_mass() * omega / plant_q;
        let defaults = Settings::for_target(1.0);
        // What the board takes besides the swing: within the cap (its f32 guard: 1% short),
        // the amplifier's top (10 kV) and slew (the scenes' 200 kV/s).
        let slew = 200e3 / (std::f64::consts::TAU * ac_hz);
        let room = 0.99 * room.min(10e3 - bias).min(slew);
        if room.is_nan() || room <= 1.0 {
            return None;
        }
        let drive = AcDrive {
            bias_volts: bias,
            ac_volts: room,
            ac_hz,
            amplifier_bandwidth_hz: bandwidth_hz,
            ring_stretch: 0.0,
            ramp: Some(Ramp {
                from_volts: 0.0,
                slew_volts_per_second: defaults.slew_volts_per_second.into(),
                settle_seconds: defaults.settle_seconds.into(),
                after_descent: true,
            }),
        };
        let device = Device::new(params).ok()?;
        let takes = |drive| match device.check_swing(drive, tuner.limit().at.offset, None, 0.05) {
            Ok(_) => Some(room),
            Err(SwingError::Crosses {
                largest_ac_volts, ..
            })
            | Err(SwingError::Unbounded {
                largest_ac_volts, ..
            }) => Some(0.99 * largest_ac_volts),
            Err(SwingError::NoEquilibrium { .. }) => None,
        };
        let ac_volts = takes(drive)?;
        let undeclared_volts = if slow {
            takes(AcDrive {
                amplifier_bandwidth_hz: f64::INFINITY,
                ..drive
            })?
        } else {
            f64::INFINITY
        };
        if ac_volts.is_nan() || ac_volts <= 1.0 {
            return None;
        }
        let drive = (ac_volts, ac_hz);
        Some(Case {
            bandwidth_hz,
            undeclared_volts,
            ..Case::at(
                params,
                (target_hz, bias),
                drive,
                (plant_q, told),
                None,
                Some(12.0),
            )
        })
    }

    /// The case of `params` tuned to `target_hz` at `bias` V, an AC of `ac_volts` at `ac_hz`,
    /// a plant of Q `plant_q` (the file stating `told` times its damping) and `branch`: ticks
    /// 20 a drive period (1 kHz at least), run five ring times Q/(π·f) after the drive starts
    /// (at most `most_seconds`).
    fn at(
        params: DeviceParams<f64>,
        (target_hz, bias): (f64, f64),
        (ac_volts, ac_hz): (f64, f64),
        (plant_q, told): (f64, f64),
        branch: Option<(f64, f64)>,
        most_seconds: Option<f64>,
    ) -> Case {
        let defaults = Settings::for_target(1.0);
        let drive_starts =
            bias / f64::from(defaults.slew_volts_per_second) + f64::from(defaults.settle_seconds);
        let ring = plant_q / (std::f64::consts::PI * target_hz.min(ac_hz));
        Case {
            params,
            target_hz,
            ac_volts,
            ac_hz,
            plant_q,
            branch,
            tick_hz: (20.0 * ac_hz).max(1000.0).ceil(),
            duration_seconds: drive_starts
                + (5.0 * ring).min(most_seconds.unwrap_or(f64::INFINITY)),
            told,
            bandwidth_hz: f64::INFINITY,
            undeclared_volts: f64::INFINITY,
        }
    }

    fn scene(&self) -> String {
        let branch = self.branch.map_or(String::new(), |(modulus, seconds)| {
            format!("[[plant.branches]]\nmodulus = {modulus:e}\nrelaxation_seconds = {seconds:e}\n")
        });
        let mut controller = format!(
            "target_hz = {:e}\nac_volts = {:e}\nac_hz = {:e}\ntick_hz = {:e}\n",
            self.target_hz, self.ac_volts, self.ac_hz, self.tick_hz
        );
        if self.bandwidth_hz.is_finite() {
            controller += "amplifier_tolerance_volts = 1e4\n";
        }
        let text = scene_text(
            &self.params,
            self.plant_q,
            &branch,
            self.duration_seconds,
            &controller,
        );
        // The plant's amplifier, which the scene declares to the board.
        if self.bandwidth_hz.is_finite() {
            text.replace(
                "[amplifier]\n",
                &format!("[amplifier]\nbandwidth_hz = {:e}\n", self.bandwidth_hz),
            )
        } else {
            text
        }
    }
}

/// A scene of `params` (every device-file key; `jlim` left out for neo-Hookean) on a plant of
/// quality factor `plant_q` (and `branch`, a `[[plant.branches]]` table or nothing),
/// `seconds` long, the stretch read directly, with the `[controller]` table's lines and any
/// tables after it in `controller`.
fn scene_text(
    params: &DeviceParams<f64>,
    plant_q: f64,
    branch: &str,
    seconds: f64,
    controller: &str,
) -> String {
    let device = host_sim::device_file::text(params);
    format!(
        "name = \"swing\"
duration_seconds = {seconds:e}

[device]
{device}
[plant]
quality_factor = {plant_q:e}
{branch}
[amplifier]
gain = 4000.0
dac_reference_volts = 2.5
slew_volts_per_second = 200000.0

[sensor]
noise = 1e-5

[output]
plot = false

[controller]
{controller}"
    )
}

/// The VHB-like membrane, told the damping of `told_q` at 33 Hz (0: none), tuned to
/// 33 Hz on a plant of Q `plant_q`, `seconds` long, the command `line` at 1 s; the run.
fn vhb_like(plant_q: f64, told_q: f64, seconds: f64, line: &str) -> Run {
    vhb_like_behind(plant_q, told_q, f64::INFINITY, seconds, line)
}

/// The same behind an amplifier of `bandwidth_hz` (first order), declared to the board.
fn vhb_like_behind(plant_q: f64, told_q: f64, bandwidth_hz: f64, seconds: f64, line: &str) -> Run {
    let mut params = DeviceParams {
        shear_modulus: 60e3,
        jlim: Some(90.0),
        relative_permittivity: 4.5,
        density: 960.0,
        breakdown_field: 100e6,
        thickness: 0.5e-3,
        length_active: 30e-3,
        length_passive: 25e-3,
        width: 50e-3,
        bar_mass: 3e-3,
        prestretch_1: 3.0,
        prestretch_2: 3.0,
        damping: 0.0,
    };
    if told_q > 0.0 {
        params.damping = params.effective_mass() * std::f64::consts::TAU * 33.0 / told_q;
    }
    let controller =
        format!("target_hz = 33.0\n\n[[commands]]\nat_seconds = 1.0\nline = \"{line}\"\n");
    let text = scene_text(&params, plant_q, "", seconds, &controller);
    let text = if bandwidth_hz.is_finite() {
        text.replace(
            "[amplifier]\n",
            &format!("[amplifier]\nbandwidth_hz = {bandwidth_hz:e}\n"),
        )
    } else {
        text
    };
    run(&text, false)
}

/// `case`'s scene run without the plant's history, the plant crossing nothing.
fn run_crossing_nothing(case: &Case) -> Run {
    let run = run(&case.scene(), false);
    assert_eq!(
        run.plant_crossing, None,
        "{case:?}: {:?} {:?}",
        run.refused, run.fault_words
    );
    run
}

/// The number of cases the environment variable `name` sets, `default` otherwise.
fn cases_from_env(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The scene `text` run, with the plant's history or without.
fn run(text: &str, history: bool) -> Run {
    let mut s = scene::parse(text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    s.run.history = history;
    s.run.run().unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// The scene `text` run blind: its `[sensor]` left out, so that nothing watches the motion.
fn run_blind(text: &str) -> Run {
    let blind = text.replace("[sensor]\nnoise = 1e-5\n", "");
    assert_ne!(blind, text, "a scene with a sensor");
    run(&blind, false)
}

/// SplitMix64: the cases from a seed, the same every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, low: f64, high: f64) -> f64 {
        low + (high - low) * self.unit()
    }
    fn log_range(&mut self, low: f64, high: f64) -> f64 {
        (low.ln() + (high.ln() - low.ln()) * self.unit()).exp()
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}
