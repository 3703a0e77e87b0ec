//! One controller tick of the plant: its equations with the amplifier's input held
//! ([`Motion`], on as many states as the plant has), solved over the tick ([`Tick`]) to its
//! end state and the turns of the stretch within it ([`Solved`]).

use differential_equations::prelude::*;

use crate::engine::erk::Start;
use crate::engine::events::{self, Hermite, Jet};
use crate::engine::lift::Lift;
use crate::engine::solver::{Solver, Span, Tolerance};

use super::{flow, AmplifierPath, Dynamics, Plant, Vector, STATE};

/// The plant's equations over one controller tick, with the amplifier's input held (the
/// DAC holds its code between ticks), on `N` states: λ, λ' and four a branch (the plant's
/// state less the amplifier's output, which is in closed form), so that a plant with fewer
/// branches than `MAX_BRANCHES` does not integrate zeros. With a `lift` (from `start`), the
/// states are λ̂ = λ − η and λ̂' = λ' − η' ([`Lift`]).
#[derive(Clone, Copy)]
pub struct Motion<'a, const N: usize> {
    pub plant: &'a Plant,
    /// The amplifier's input, V (DAC output × nothing: the gain is applied here).
    pub input_volts: f64,
    /// The amplifier's output over the tick, where it has a lag or a slew limit: in closed
    /// form, not integrated (its fast exponential would bind the solver's step).
    amplifier: Option<AmplifierPath>,
    /// The fast part of the stretch taken out, from its start time.
    lift: Option<(f64, Lift)>,
    dynamics: Dynamics,
}

/// The solved states of the plant's state `y` ([`Motion`]): all but the amplifier's output.
fn solved_of<const N: usize>(y: &Vector) -> [f64; N] {
    std::array::from_fn(|i| if i < 2 { y[i] } else { y[i + 1] })
}

/// The solved states put back into the plant's state `y` (the inverse of [`solved_of`]).
fn place<const N: usize>(y: &mut Vector, solved: &[f64; N]) {
    y[..2].copy_from_slice(&solved[..2]);
    y[3..N + 1].copy_from_slice(&solved[2..]);
}

impl<const N: usize> Motion<'_, N> {
    /// The plant's state at `t` from the solved one: λ = λ̂ + η, λ' = λ̂' + η', the
    /// amplifier's output in closed form; and η''.
    #[inline]
    fn unlift(&self, t: f64, short: &[f64; N], base: &Vector) -> (Vector, f64) {
        let mut y = *base;
        place(&mut y, short);
        let mut fast = 0.0;
        if let Some((start, lift)) = &self.lift {
            let ((e0, e1, e2), volts) = lift.at(t - start);
            y[0] += e0;
            y[1] += e1;
            y[2] = volts;
            fast = e2;
        } else if let Some(path) = &self.amplifier {
            y[2] = path.volts_at(t);
        }
        (y, fast)
    }

    /// The turn in a step from `a` to `b` (time, solved state, the plant's state), if the
    /// ends' velocities differ in sign: located on a quintic through the solved ends (value,
    /// slope, and the curvature from the equations: with a lift, λ̂, which has nothing fast)
    /// plus η in closed form, the slow states between them linear; (time, the plant's state).
    fn turn(
        &self,
        (a, ya, whole_a): (f64, &[f64; N], Vector),
        (b, yb, whole_b): (f64, &[f64; N], Vector),
    ) -> Option<(f64, Vector)> {
        if !events::turns(whole_a[1], whole_b[1]) {
            return None;
        }
        // The quintic through the solved (lifted: smooth) states, η added in closed form.
        let jet = |t: f64, y: &[f64; N]| {
            let mut rate = [0.0; N];
            self.diff(t, y, &mut rate);
            Jet {
                t,
                stretch: y[0],
                velocity: y[1],
                acceleration: rate[1],
            }
        };
        let path = Hermite::new(jet(a, ya), jet(b, yb));
        let at = events::turn(a, b, |t| path.at(t).1 + self.eta(t).1);
        let w = (at - a) / (b - a);
        let mut y: Vector = std::array::from_fn(|i| whole_a[i] + w * (whole_b[i] - whole_a[i]));
        let ((stretch, velocity), (e0, e1, _)) = (path.at(at), self.eta(at));
        (y[0], y[1]) = (stretch + e0, velocity + e1);
        if let Some(amplifier) = &self.amplifier {
            y[2] = amplifier.volts_at(at);
        }
        Some((at, y))
    }

    /// The plant's state at `t` from the solved one.
    fn whole(&self, t: f64, short: &[f64; N], base: &Vector) -> Vector {
        self.unlift(t, short, base).0
    }

    /// η, η' and η'' at `t` (zero without a lift).
    fn eta(&self, t: f64) -> (f64, f64, f64) {
        self.lift
            .as_ref()
            .map_or((0.0, 0.0, 0.0), |(start, lift)| lift.at(t - start).0)
    }

    /// The solved states' derivative at `t` from the plant's (`rate`, [`Solved::rate`]).
    fn solved_rate(&self, t: f64, rate: &Vector) -> [f64; N] {
        let mut solved = solved_of(rate);
        let (_, e1, e2) = self.eta(t);
        solved[0] -= e1;
        solved[1] -= e2;
        solved
    }

    /// The plant's state's derivative at `t` from the solved states' (the amplifier's
    /// output's left 0: it is in closed form).
    fn plant_rate(&self, t: f64, solved: &[f64; N]) -> Vector {
        let mut rate = [0.0; STATE];
        place(&mut rate, solved);
        let (_, e1, e2) = self.eta(t);
        rate[0] += e1;
        rate[1] += e2;
        rate
    }
}

impl<const N: usize> ODE<f64, [f64; N]> for Motion<'_, N> {
    fn diff(&self, t: f64, short: &[f64; N], rate: &mut [f64; N]) {
        let plant = self.plant;
        let (y, e2) = self.unlift(t, short, &[0.0; STATE]);
        let volts = plant.volts(&y, self.input_volts);
        let mut dydt = [0.0; STATE];
        dydt[0] = short[1];
        dydt[1] = self.dynamics.acceleration(&plant.branches, &y, volts) - e2;
        let l2 = plant.params.prestretch_2;
        let lb = self.dynamics.passive_stretch(y[0]);
        for (k, b) in plant.branches.iter().enumerate() {
            let at = 3 + 4 * k;
            let (a1, a2) = flow(b, y[0], l2, y[at], y[at + 1]);
            let (b1, b2) = flow(b, lb, l2, y[at + 2], y[at + 3]);
            dydt[at] = a1;
            dydt[at + 1] = a2;
            dydt[at + 2] = b1;
            dydt[at + 3] = b2;
        }
        *rate = solved_of(&dydt);
    }
}

/// A tick solved: the state at its end, the first step the solve took after the drive's
/// jump, and where the stretch turned highest and lowest within it (time, state: the
/// extremes a check between tick ends must see; with BDF, a turn between the tick's ends).
#[derive(Clone, Copy, Debug)]
pub struct Solved {
    pub y: Vector,
    pub first_step: f64,
    /// dy/dt at the end where the tick's own steps worked it out (the amplifier's output's
    /// left 0): the next tick's [`Tick::rate`].
    pub rate: Option<Vector>,
    pub turns: [Option<(f64, Vector)>; 2],
}

/// One tick of the plant: `y` over `[t0, t1]` with the amplifier's input held at
/// `input_volts`.
pub struct Tick<'a> {
    pub plant: &'a Plant,
    pub solver: Solver,
    pub tolerance: Tolerance,
    pub y: Vector,
    pub t0: f64,
    pub t1: f64,
    pub input_volts: f64,
    /// The last tick's first step after the drive's jump, so that a tick neither estimates
    /// its first step again nor starts too long and has it rejected (`None` at the start).
    pub first_step: Option<f64>,
    /// dy/dt at `t0`, if known (the last tick's [`Solved::rate`]): the solve's first stage,
    /// saved. Used only where the plant's right-hand side is continuous across the tick's
    /// start, as it is when the amplifier's output is a state (the DAC's jump moves its
    /// target, not its output).
    pub rate: Option<Vector>,
}

impl Tick<'_> {
    /// The state at `t1`, the first step the solve took after the drive's jump, its turns.
    pub fn solve(self) -> Result<Solved, String> {
        let t0 = self.t0;
        match self.plant.branches.len() {
            0 => self.advance::<2>(),
            1 => self.advance::<6>(),
            2 => self.advance::<10>(),
            _ => self.advance::<{ STATE - 1 }>(),
        }
        .map_err(|e| {
            format!(
                "the plant's integration at t = {} s: {e}",
                crate::text::sig(t0)
            )
        })
    }
}

impl Tick<'_> {
    fn advance<const N: usize>(self) -> Result<Solved, String> {
        let amplifier = self.plant.amplifier_has_state().then(|| {
            self.plant
                .amplifier_path(self.t0, self.y[2], self.input_volts)
        });
        let plain = Motion::<N> {
            plant: self.plant,
            input_volts: self.input_volts,
            amplifier,
            lift: None,
            dynamics: self.plant.dynamics(),
        };
        // Split at the amplifier's knee, where its output's second derivative jumps.
        let knee = amplifier
            .and_then(|path| path.knee_time())
            .filter(|&at| at > self.t0 && at < self.t1);
        // The exponential toward the target (a finite bandwidth): from its start, its fast
        // part is taken out of the solve.
        let exponential = amplifier
            .filter(|path| path.rate_per_second.is_finite())
            .map(|path| (path, path.exponential()));
        // The highest turn and the lowest (however many a long tick holds): where an
        // excursion peaks.
        let mut turns: [Option<(f64, Vector)>; 2] = [None; 2];
        // The ramp at the slew rate (if any) in one step; then the rest from the last tick's
        // first step there.
        let (mut from, mut end, mut h) = (self.t0, self.y, f64::NAN);
        // dy/dt at `from`: continuous at the knee, and at the tick's start with an amplifier.
        let mut rate = self.rate.filter(|_| amplifier.is_some());
        for to in knee.into_iter().chain([self.t1]) {
            let first = if to == self.t1 {
                self.first_step
            } else {
                Some(to - from)
            };
            let lift = exponential
                .filter(|(_, (start, _))| from >= *start)
                .and_then(|(path, (start, gap))| {
                    let known = rate.map(|rate| rate[1]);
                    let lift = self.plant.lift(&plain.dynamics, &end, &path, gap, known)?;
                    Some((start, lift))
                });
            let motion = Motion { lift, ..plain };
            // λ̂ = λ − η at the start.
            let mut short = solved_of::<N>(&end);
            let (e0, e1, _) = motion.eta(from);
            short[0] -= e0;
            short[1] -= e1;
            // The plant's state at the last step's end: the next step's start.
            let mut last = (from, end);
            let mut on_step = |(a, ya): (f64, [f64; N]), (b, yb): (f64, [f64; N])| {
                let start = if last.0 == a {
                    last.1
                } else {
                    motion.whole(a, &ya, &self.y)
                };
                last = (b, motion.whole(b, &yb, &self.y));
                let Some(turn) = motion.turn((a, &ya, start), (b, &yb, last.1)) else {
                    return;
                };
                let [high, low] = &mut turns;
                if high.is_none_or(|(_, h)| turn.1[0] > h[0]) {
                    *high = Some(turn);
                }
                if low.is_none_or(|(_, l)| turn.1[0] < l[0]) {
                    *low = Some(turn);
                }
            };
            let span = Span {
                from,
                to,
                short: to < self.t1,
            };
            let start = Start {
                y: short,
                rate: rate.map(|rate| motion.solved_rate(from, &rate)),
            };
            let solved = self.solver.advance_watched(
                &motion,
                span,
                start,
                self.tolerance,
                first,
                &mut on_step,
            )?;
            h = solved.first_step;
            rate = solved.rate.map(|r| motion.plant_rate(to, &r));
            end = if last.0 == to {
                last.1
            } else {
                motion.whole(to, &solved.y, &self.y)
            };
            from = to;
        }
        Ok(Solved {
            y: end,
            first_step: h,
            rate,
            turns,
        })
    }
}
