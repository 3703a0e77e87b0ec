//! The plant's ticks' explicit Runge–Kutta steps: differential-equations' DOP853 and DOPRI5
//! (their tableaux, error estimates and step-size control, as the library's `step`), written
//! for a fixed-size state and a solve a step or two long. A scene solves 1,000 ticks a
//! simulated second, each a solve of its own; the library's general driver (a state by trait,
//! stage loops sized at run time, kilobytes of method built and a `Solution` kept a solve) cost
//! as much as the right-hand sides. Left out, as a tick reads no state between steps: dense
//! output. The reference's solves (`simulate`) keep the library's methods.

use std::sync::LazyLock;

use differential_equations::prelude::ODE;
use differential_equations::tableau::ButcherTableau;

/// An explicit embedded pair of `S` stages.
#[derive(Clone, Debug)]
pub struct Erk<const S: usize> {
    c: [f64; S],
    a: [[f64; S]; S],
    b: [f64; S],
    /// The error estimate's coefficients; DOP853's second, 3rd-order one (b − bh; zeros and
    /// `two_estimates` false where there is none).
    er: [f64; S],
    bh: [f64; S],
    two_estimates: bool,
    /// The order, whose reciprocal is the step-size exponent.
    order: u32,
    /// The last stage is the new point (DOPRI5): its derivative starts the next step.
    fsal: bool,
}

/// DOP853, built once.
pub static DOP853: LazyLock<Erk<12>> = LazyLock::new(|| {
    let t = ButcherTableau::<f64, 12, 16>::dop853();
    Erk::new(
        std::array::from_fn(|i| t.c[i]),
        std::array::from_fn(|i| std::array::from_fn(|j| t.a[i][j])),
        t.b,
        t.er.unwrap_or([0.0; 12]),
        t.bh,
        8,
    )
});

/// DOPRI5, built once.
pub static DOPRI5: LazyLock<Erk<7>> = LazyLock::new(|| {
    let t = ButcherTableau::<f64, 7, 7>::dopri5();
    Erk::new(t.c, t.a, t.b, t.er.unwrap_or([0.0; 7]), t.bh, 5)
});

/// Why a solve stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// The step size fell below 1e-14 of the last (or is not finite).
    StepSize,
    /// Hairer's stiffness test: h·λ above 6.1 in 15 tests before 6 below.
    Stiff,
}

/// A solve's start: the state, and its derivative if known (the last solve's end, where the
/// right-hand side is continuous): the first stage, saved.
#[derive(Clone, Copy, Debug)]
pub struct Start<const N: usize> {
    pub y: [f64; N],
    pub rate: Option<[f64; N]>,
}

/// A solve's end: the state, its derivative (the next solve's first stage, where the
/// right-hand side is continuous), and the step that would come next.
#[derive(Clone, Copy, Debug)]
pub struct End<const N: usize> {
    pub y: [f64; N],
    pub rate: [f64; N],
    pub next_step: f64,
}

/// What sees a step's ends, (time, state) at its start and at its end.
pub type StepEnds<'a, const N: usize> = dyn FnMut((f64, [f64; N]), (f64, [f64; N])) + 'a;

/// Hairer's step-size control, as the library's defaults.
const SAFETY: f64 = 0.9;
const MIN_SCALE: f64 = 0.2;
const MAX_SCALE: f64 = 10.0;

impl<const S: usize> Erk<S> {
    fn new(
        c: [f64; S],
        a: [[f64; S]; S],
        b: [f64; S],
        er: [f64; S],
        bh: Option<[f64; S]>,
        order: u32,
    ) -> Self {
        let last = S - 1;
        let fsal = c[last] == 1.0 && b[last] == 0.0 && (0..last).all(|j| a[last][j] == b[j]);
        Erk {
            c,
            a,
            b,
            er,
            bh: bh.unwrap_or([0.0; S]),
            two_estimates: bh.is_some(),
            order,
            fsal,
        }
    }

    /// `ode` from `start` at `t0` to `t1` starting with step `h0` (> 0), each accepted step's
    /// ends (time, state) to `on_step`: the end at `t1`.
    pub fn solve<const N: usize, F: ODE<f64, [f64; N]>>(
        &self,
        ode: &F,
        (t0, t1): (f64, f64),
        start: Start<N>,
        (rtol, atol): (f64, f64),
        h0: f64,
        on_step: &mut StepEnds<'_, N>,
    ) -> Result<End<N>, Stop> {
        let (mut t, mut y, mut h, mut h_prev) = (t0, start.y, h0, 0.0);
        let mut k = [[0.0; N]; S];
        match start.rate {
            Some(rate) => k[0] = rate,
            None => ode.diff(t, &y, &mut k[0]),
        }
        let (mut rejected, mut steps) = (false, 0usize);
        // Hairer's stiffness test's counts, positive and negative.
        let (mut stiff, mut not_stiff) = (0, 0);
        // The stage's state; after the stages, the last one's (the stiffness test's).
        let mut stage = y;
        while (t1 - t).abs() > 10.0 * f64::EPSILON {
            if t + h > t1 {
                h = t1 - t;
            }
            if !(h >= h_prev * 1e-14 && h > 0.0 && h.is_finite()) {
                return Err(Stop::StepSize);
            }
            steps += 1;
            for i in 1..S {
                stage = y;
                for (kj, aij) in k[..i].iter().zip(&self.a[i][..i]) {
                    let w = aij * h;
                    for (s, d) in stage.iter_mut().zip(kj) {
                        *s += w * d;
                    }
                }
                ode.diff(t + self.c[i] * h, &stage, &mut k[i]);
            }
            // The update and the error estimates, as the library's (Hairer's for DOP853:
            // the 5th- and 3rd-order estimates combined).
            let (mut slope, mut err5, mut err3) = ([0.0; N], [0.0; N], [0.0; N]);
            for (i, ki) in k.iter().enumerate() {
                let (b, er, bh) = (self.b[i], self.er[i], self.bh[i]);
                for n in 0..N {
                    slope[n] += b * ki[n];
                    err5[n] += er * ki[n];
                    err3[n] -= bh * ki[n];
                }
            }
            let mut y_new = y;
            let (mut sum5, mut sum3) = (0.0, 0.0);
            for n in 0..N {
                y_new[n] += h * slope[n];
                let scale = atol + rtol * y[n].abs().max(y_new[n].abs());
                let (e5, e3) = (err5[n] / scale, (err3[n] + slope[n]) / scale);
                sum5 += e5 * e5;
                sum3 += e3 * e3;
            }
            if !self.two_estimates {
                sum3 = 0.0;
            }
            let mut deno = sum5 + 0.01 * sum3;
            if !(deno > 0.0) {
                deno = 1.0;
            }
            let err = h * sum5 * (1.0 / (deno * N as f64)).sqrt();
            // A NaN error (a right-hand side undefined at a trial stage) shrinks the step as
            // far as it may, as the library's, rather than ending the solve.
            // err^(−1/order); for DOP853 by three square roots, a tenth of `powf`'s time.
            let raw = SAFETY
                * if self.order == 8 {
                    1.0 / err.sqrt().sqrt().sqrt()
                } else {
                    err.powf(-1.0 / f64::from(self.order))
                };
            let mut scale = if raw.is_nan() {
                MIN_SCALE
            } else {
                raw.clamp(MIN_SCALE, MAX_SCALE)
            };
            if err <= 1.0 {
                let t_new = t + h;
                let rate = if self.fsal {
                    k[S - 1]
                } else {
                    let mut rate = [0.0; N];
                    ode.diff(t_new, &y_new, &mut rate);
                    rate
                };
                // Hairer's test, as the library's: h·λ from the last stage and the new point,
                // every 100th step and every step once one was positive.
                if steps.is_multiple_of(100) || stiff > 0 {
                    let squared = |a: &[f64; N], b: &[f64; N]| -> f64 {
                        a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
                    };
                    let (num, den) = (squared(&rate, &k[S - 1]), squared(&y_new, &stage));
                    let h_lambda = if den > 0.0 {
                        h * (num / den).sqrt()
                    } else {
                        0.0
                    };
                    if h_lambda > 6.1 {
                        (stiff, not_stiff) = (stiff + 1, 0);
                        if stiff == 15 {
                            return Err(Stop::Stiff);
                        }
                    } else {
                        not_stiff += 1;
                        if not_stiff == 6 {
                            stiff = 0;
                        }
                    }
                }
                on_step((t, y), (t_new, y_new));
                (t, y, h_prev, k[0]) = (t_new, y_new, h, rate);
                if rejected {
                    rejected = false;
                    scale = scale.min(1.0);
                }
            } else {
                rejected = true;
            }
            h *= scale;
        }
        Ok(End {
            y,
            rate: k[0],
            next_step: h,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn start<const N: usize>(y: [f64; N]) -> Start<N> {
        Start { y, rate: None }
    }

    /// A harmonic oscillator with a fast decaying drive, the tick's kind of problem.
    struct Forced;

    impl ODE<f64, [f64; 2]> for Forced {
        fn diff(&self, t: f64, y: &[f64; 2], dydt: &mut [f64; 2]) {
            dydt[0] = y[1];
            dydt[1] = -7.6e4 * y[0] + 50.0 * (-12_566.0 * t).exp();
        }
    }

    /// The same steps and end as the library's DOP853 and DOPRI5 at the same tolerance and
    /// first step: the steps' ends to 1e-7 of their times (a step's error estimate is a
    /// difference of stages 1e5 times larger, so its rounding moves the next step size),
    /// the end to 1e-12.
    #[test]
    fn steps_as_the_library_does() {
        use differential_equations::methods::{DormandPrince, Ordinary};
        use differential_equations::ode::solve_ode;
        use differential_equations::prelude::*;
        use differential_equations::solout::DefaultSolout;
        let (y0, span, tolerance, h0) = ([0.01, 0.5], (0.0, 2e-3), (1e-10, 1e-10), 2.5e-4);
        let ours = |erk: &dyn Fn(&mut StepEnds<'_, 2>) -> _| {
            let mut ends = Vec::new();
            let end: Result<End<2>, Stop> = erk(&mut |_, (t, _)| ends.push(t));
            (end.expect("solves").y, ends)
        };
        fn library<const O: usize, const S: usize, const I: usize>(
            method: ExplicitRungeKutta<Ordinary, DormandPrince, f64, [f64; 2], O, S, I>,
            (y0, span, tolerance, h0): ([f64; 2], (f64, f64), (f64, f64), f64),
        ) -> ([f64; 2], Vec<f64>) {
            let mut method = method.rtol(tolerance.0).atol(tolerance.1).h0(h0);
            let solution = solve_ode(
                &mut method,
                &Forced,
                span.0,
                span.1,
                &y0,
                &mut DefaultSolout::new(),
            )
            .expect("solves");
            (*solution.y.last().expect("an end"), solution.t)
        }
        let setup = (y0, span, tolerance, h0);
        let (end, ends) = ours(&|f| DOP853.solve(&Forced, span, start(y0), tolerance, h0, f));
        let (their_end, their_times) = library(ExplicitRungeKutta::dop853(), setup);
        assert_eq!(
            ends.len() + 1,
            their_times.len(),
            "{ends:?} {their_times:?}"
        );
        for (a, b) in ends.iter().zip(&their_times[1..]) {
            assert!((a - b).abs() < 1e-7 * b, "{a} {b}");
        }
        for (a, b) in end.iter().zip(&their_end) {
            assert!((a - b).abs() < 1e-12 * b.abs().max(1.0), "{a} {b}");
        }
        let (end, ends) = ours(&|f| DOPRI5.solve(&Forced, span, start(y0), tolerance, h0, f));
        let (their_end, their_times) = library(ExplicitRungeKutta::dopri5(), setup);
        assert_eq!(ends.len() + 1, their_times.len());
        for (a, b) in ends.iter().zip(&their_times[1..]) {
            assert!((a - b).abs() < 1e-7 * b, "{a} {b}");
        }
        for (a, b) in end.iter().zip(&their_end) {
            assert!((a - b).abs() < 1e-12 * b.abs().max(1.0), "{a} {b}");
        }
    }

    /// A solve's end derivative is the right-hand side at its end: carried into the next
    /// solve as its first stage, that solve is the one that works it out (DOP853: the same
    /// numbers; DOPRI5, whose last stage stands in for it, to rounding).
    #[test]
    fn a_carried_rate_is_the_first_stage() {
        let (tolerance, h0) = ((1e-10, 1e-10), 2.5e-4);
        for fsal in [false, true] {
            let solve = |span, start| {
                if fsal {
                    DOPRI5.solve(&Forced, span, start, tolerance, h0, &mut |_, _| {})
                } else {
                    DOP853.solve(&Forced, span, start, tolerance, h0, &mut |_, _| {})
                }
                .expect("solves")
            };
            let first = solve((0.0, 1e-3), start([0.01, 0.5]));
            let mut rate = [0.0; 2];
            Forced.diff(1e-3, &first.y, &mut rate);
            for (a, b) in first.rate.iter().zip(&rate) {
                assert!((a - b).abs() <= 1e-12 * b.abs(), "{a} {b}");
            }
            let carried = Start {
                y: first.y,
                rate: Some(first.rate),
            };
            let (with, without) = (
                solve((1e-3, 2e-3), carried),
                solve((1e-3, 2e-3), start(first.y)),
            );
            for (a, b) in with.y.iter().zip(&without.y) {
                assert!((a - b).abs() <= 1e-13 * b.abs(), "{a} {b}");
            }
            if !fsal {
                assert_eq!(with.y, without.y);
            }
        }
    }

    /// A stiff problem, y' = −10⁶·(y − cos t), is refused as stiff (the library refuses it
    /// too), not stepped through at the stability limit.
    #[test]
    fn a_stiff_problem_is_refused() {
        struct Stiff;
        impl ODE<f64, [f64; 1]> for Stiff {
            fn diff(&self, t: f64, y: &[f64; 1], dydt: &mut [f64; 1]) {
                dydt[0] = -1e6 * (y[0] - t.cos());
            }
        }
        let solved = DOP853.solve(
            &Stiff,
            (0.0, 1.0),
            start([1.0]),
            (1e-8, 1e-8),
            1e-6,
            &mut |_, _| {},
        );
        assert_eq!(solved.err(), Some(Stop::Stiff));
    }

    /// A right-hand side undefined past a point (NaN, as Gent's stress past lock-up): a trial
    /// step that reaches it is rejected and shrunk, as the library's, and the solve goes on.
    #[test]
    fn an_undefined_trial_stage_shrinks_the_step() {
        struct Edge;
        impl ODE<f64, [f64; 1]> for Edge {
            fn diff(&self, _: f64, y: &[f64; 1], dydt: &mut [f64; 1]) {
                // Defined for y < 1 only; the solution 1 − (1 − t/2)² stays below it to t = 2.
                dydt[0] = (1.0 - y[0]).sqrt();
            }
        }
        let mut ends = 0;
        let solved = DOP853.solve(
            &Edge,
            (0.0, 1.5),
            start([0.0]),
            (1e-10, 1e-10),
            5.0,
            &mut |_, _| ends += 1,
        );
        let y = solved.expect("solves").y;
        let exact = 1.0 - (1.0f64 - 0.75).powi(2);
        assert!((y[0] - exact).abs() < 1e-8, "{} against {exact}", y[0]);
        assert!(ends > 1);
    }
}
