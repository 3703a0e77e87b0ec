//! What holds for every device of a batch (model.md §10): the guaranteed limit, certified by
//! interval arithmetic over the box (no device in it fails below it), and the band of
//! natural frequencies the batch has at one bias.
//!
//! A branch and bound: the box is cut into leaves; on each, the loading branch is walked in
//! cells of the offset δ = λ − λ1p, each cell's bias and checks enclosed in intervals
//! ([`crate::numerics::interval`]) with the material's own formulas. A leaf's bound is
//! certified; the search refines the leaf with the lowest bound until it lies within a
//! tolerance of the lowest value sampled (the f64 model at leaves' centres), so the bound is
//! also tight. The caller lends the leaves' storage (no allocation here).

use heapless::Vec;

use crate::model::device::{Device, DeviceParams, Field, ParamError, VACUUM_PERMITTIVITY};
use crate::model::material::Gent;
use crate::model::safety::{FailureMode, Limit};
use crate::model::tolerance::DeviceBox;
use crate::numerics::gradient::Gradient;
use crate::numerics::interval::Interval;
use crate::numerics::real::Real;

type I = Interval;

/// Cells the branch is first cut into (each then halved where a check is uncertain).
const CELLS: usize = 8;
/// Halvings of one cell at most.
const MAX_DEPTH: u8 = 24;
/// A cell not certain to pass is halved down to this width relative to its offset.
const OFFSET_RESOLUTION: f64 = 1e-3;
/// A cell is halved while its bias spans more than this fraction of its value.
const CELL_TOLERANCE: f64 = 2e-4;
/// The limit's search stops when its certified bound is within this fraction of the lowest
/// limit sampled (so within it of the true lowest).
pub const LIMIT_TOLERANCE: f64 = 0.01;
/// The band's searches stop when each end is within this fraction of the sampled spread of
/// frequencies (its width) of the sampled end.
pub const BAND_TOLERANCE: f64 = 0.02;
/// The search samples every corner of at most this many of its parameters.
const CORNER_DIMS: usize = 10;
/// The branch is walked this far past the leaf centre's scan end (model.md §6: any end is
/// valid; a longer walk only costs time).
const WALK_PAST_SCAN_END: f64 = 1.5;

/// The loading branch and its checks (model.md §§2–6) over any [`Real`]: run on
/// [`Interval`] at a box's centre and on [`Gradient`] over the box (the mean-value form).
struct Branch<T> {
    l1p: T,
    l2p: T,
    material: Gent<T>,
    ratio: T,
}

/// Each check's margins in model.md §6's order, positive exactly when it holds; the
/// Hessian's (§6.2) and the lock-up's (§6.6) in two parts each.
const PARTS: [FailureMode; 9] = [
    FailureMode::DeviceInstability,
    FailureMode::Emi,
    FailureMode::Emi,
    FailureMode::LossOfTension1,
    FailureMode::LossOfTension2a,
    FailureMode::LossOfTension2b,
    FailureMode::Breakdown,
    FailureMode::StretchLimit,
    FailureMode::StretchLimit,
];

impl<T: Real> Branch<T> {
    /// λ and λB at the offset `d` (model.md §2).
    fn stretches(&self, d: T) -> (T, T) {
        (self.l1p + d, self.l1p - self.ratio * d)
    }

    /// Φ̄² on the loading branch at the offset `d` (model.md §5): the material's factored
    /// stress difference, as the f64 model takes it.
    fn bias_squared(&self, d: T) -> T {
        let (l, lb) = self.stretches(d);
        let apart = (T::one() + self.ratio) * d;
        let difference = self.material.stress_1_difference(l, lb, apart, self.l2p);
        difference / (l * self.l2p.squared())
    }

    /// The elastic stiffness s̄1'(λ) + (L1A/L1B)·s̄1'(λB) of model.md §5 at the offset `d`.
    fn elastic_stiffness(&self, d: T) -> T {
        let (l, lb) = self.stretches(d);
        let m = &self.material;
        m.stiffness_1(l, self.l2p) + self.ratio * m.stiffness_1(lb, self.l2p)
    }

    /// The margins of [`PARTS`] at the offset `d` under Φ̄² = `p2`, the breakdown field
    /// over √(μ/ε) being `breakdown`.
    fn margins(&self, d: T, p2: T, breakdown: T) -> [T; 9] {
        let (l, lb) = self.stretches(d);
        let (m, l2p) = (&self.material, self.l2p);
        let hessian = m.hessian(l, l2p).under_bias(l, l2p, p2);
        [
            self.elastic_stiffness(d) - p2 * l2p.squared(),
            hessian.d11,
            hessian.d11 * hessian.d22 - hessian.d12.squared(),
            m.stress_1(lb, l2p),
            l2p * m.stress_2(l, l2p) - p2 * (l * l2p).squared(),
            l2p * m.stress_2(lb, l2p),
            breakdown - p2.sqrt() * l * l2p,
            m.lock_up_margin(l, l2p),
            m.lock_up_margin(lb, l2p),
        ]
    }
}

/// The variables of the mean-value form: δ, λ1p, λ2p, Jlim, L1A/L1B.
const VARIABLES: usize = 5;
type G = Gradient<VARIABLES>;

/// One cell of the branch over a box: the margins, enclosed.
struct Cell {
    margins: [I; 9],
}

impl Cell {
    /// The first check (in model.md §6's order) not certain to hold on the cell.
    fn first_uncertain(&self) -> Option<FailureMode> {
        PARTS
            .into_iter()
            .zip(self.margins)
            .find(|(_, margin)| !(margin.lo > 0.0))
            .map(|(mode, _)| mode)
    }
}

/// The mean-value form's pieces at one cell (`BoxModel::at_offsets`).
struct Offsets {
    over: Branch<G>,
    at: Branch<I>,
    /// δ over the cell and at its centre.
    d: (G, I),
    ranges: [I; VARIABLES],
    centres: [f64; VARIABLES],
}

impl Offsets {
    /// The enclosure of a quantity from its gradient over the box and its value at the
    /// centre.
    fn mean_value(&self, over: G, at: I) -> I {
        over.mean_value(at, &self.ranges, &self.centres)
    }
}

/// The model over a sub-box of devices: the branch in the mean-value form, and the scales
/// back to volts and hertz in intervals.
struct BoxModel {
    /// The ranges of [`VARIABLES`] but δ (its slot a placeholder) and their centres.
    ranges: [I; VARIABLES],
    centres: [f64; VARIABLES],
    neo_hookean: bool,
    volts_per_unit: I,
    breakdown_dimless: I,
    /// (1/T0)² = μ·L2·H/M, rad²/s².
    rad_per_s_squared: I,
    /// C1 = ε·L1A·L2·λ2p²/H, F (model.md §8).
    farads_per_stretch_squared: I,
}

impl BoxModel {
    fn of(low: &DeviceParams<f64>, high: &DeviceParams<f64>) -> Self {
        let r = |f: Field| I::new(low.get(f), high.get(f));
        let mu = r(Field::ShearModulus);
        let eps = r(Field::RelativePermittivity) * I::point(VACUUM_PERMITTIVITY);
        let h = r(Field::Thickness);
        let (sqrt_mu, sqrt_eps) = (mu.sqrt(), eps.sqrt());
        // μ·L2·H/M rises with μ, L2 and H (H/(a + b·H) with a = m·L1A ≥ 0, likewise L2) and
        // falls with m, ρ, L1A and L1B (M rises with each): its range is its value at two
        // corners, each worked out in intervals for the rounding.
        let scale = |up: &DeviceParams<f64>, down: &DeviceParams<f64>| {
            let p = |f: Field, from: &DeviceParams<f64>| I::point(from.get(f));
            let (la, lb) = (p(Field::LengthActive, down), p(Field::LengthPassive, down));
            let (w, thick) = (p(Field::Width, up), p(Field::Thickness, up));
            let mass = p(Field::BarMass, down) * la
                + p(Field::Density, down) * w * thick * la * (la + lb) / I::point(3.0);
            p(Field::ShearModulus, up) * w * thick / mass
        };
        let ranges = [
            I::point(0.0),
            r(Field::Prestretch1),
            r(Field::Prestretch2),
            r(Field::Jlim),
            r(Field::LengthActive) / r(Field::LengthPassive),
        ];
        Self {
            ranges,
            centres: ranges.map(|x| x.mid()),
            neo_hookean: low.jlim.is_none(),
            volts_per_unit: h * sqrt_mu / sqrt_eps,
            breakdown_dimless: r(Field::BreakdownField) * sqrt_eps / sqrt_mu,
            rad_per_s_squared: scale(low, high).hull(scale(high, low)),
            farads_per_stretch_squared: eps
                * r(Field::LengthActive)
                * r(Field::Width)
                * r(Field::Prestretch2).square()
                / h,
        }
    }

    /// The branch with each variable `of` its range (or centre).
    fn branch<T: Real>(&self, of: [T; VARIABLES]) -> Branch<T> {
        let [_, l1p, l2p, jlim, ratio] = of;
        Branch {
            l1p,
            l2p,
            material: if self.neo_hookean {
                Gent::neo_hookean()
            } else {
                Gent::with_jlim(jlim)
            },
            ratio,
        }
    }

    /// The mean-value form's pieces at the offsets `d`: the ranges and centres with δ's,
    /// the branch over the box in gradients, and at its centre in intervals.
    fn at_offsets(&self, d: I) -> Offsets {
        let mut ranges = self.ranges;
        let mut centres = self.centres;
        if let (Some(r), Some(c)) = (ranges.first_mut(), centres.first_mut()) {
            *r = d;
            *c = d.mid();
        }
        let mut index = 0;
        let over = self.branch(ranges.map(|x| {
            index += 1;
            G::variable(x, index - 1)
        }));
        let at = self.branch(centres.map(I::point));
        Offsets {
            over,
            at,
            d: (G::variable(d, 0), I::point(d.mid())),
            ranges,
            centres,
        }
    }

    /// Φ̄² on the branch at the offsets `d`, enclosed (its non-negative part).
    fn bias_squared(&self, d: I) -> I {
        let o = self.at_offsets(d);
        let (dg, dc) = o.d;
        o.mean_value(o.over.bias_squared(dg), o.at.bias_squared(dc))
            .non_negative()
    }

    /// The branch's cell at the offsets `d`: its margins.
    fn cell(&self, d: I) -> Cell {
        // The plain enclosure first: where it is certain (most cells), the gradients'
        // sixfold cost is saved.
        let mut ranges = self.ranges;
        if let Some(r) = ranges.first_mut() {
            *r = d;
        }
        let plain = self.branch(ranges);
        let p2 = plain.bias_squared(d);
        let margins = plain.margins(d, p2, self.breakdown_dimless);
        if margins.iter().all(|m| m.lo > 0.0) {
            return Cell { margins };
        }
        let o = self.at_offsets(d);
        let (dg, dc) = o.d;
        let (p2g, p2c) = (o.over.bias_squared(dg), o.at.bias_squared(dc));
        let mg = o.over.margins(dg, p2g, G::constant(self.breakdown_dimless));
        let mc = o.at.margins(dc, p2c, self.breakdown_dimless);
        let mut margins = mc;
        for ((out, g), c) in margins.iter_mut().zip(mg).zip(mc) {
            *out = o.mean_value(g, c);
        }
        Cell { margins }
    }

    /// The elastic stiffness at the offsets `d`, enclosed.
    fn elastic_stiffness(&self, d: I) -> I {
        let o = self.at_offsets(d);
        let (dg, dc) = o.d;
        o.mean_value(o.over.elastic_stiffness(dg), o.at.elastic_stiffness(dc))
    }

    /// λ2p's range.
    fn l2p(&self) -> I {
        self.ranges.get(2).copied().unwrap_or(I::ENTIRE)
    }

    /// Walk the branch's cells over [`start`, `end`] in order: each cell's offsets `look`ed at
    /// once, halved while `split` asks; `visit` sees each cell kept and says whether to go on.
    fn walk<E>(
        &self,
        (start, end): (f64, f64),
        look: impl Fn(I) -> E,
        split: impl Fn(I, &E) -> bool,
        mut visit: impl FnMut(&E) -> bool,
    ) -> bool {
        for i in 0..CELLS {
            let at = |k: usize| start + (end - start) * k as f64 / CELLS as f64;
            let mut stack: Vec<(f64, f64, u8), { MAX_DEPTH as usize + 2 }> = Vec::new();
            let _ = stack.push((at(i), at(i + 1), 0));
            while let Some((a, b, depth)) = stack.pop() {
                let d = I::new(a, b);
                let seen = look(d);
                if depth < MAX_DEPTH && split(d, &seen) {
                    let mid = 0.5 * (a + b);
                    // Right then left: the left half is taken first. The stack holds one
                    // entry per level, so both fit.
                    if stack.push((mid, b, depth + 1)).is_ok()
                        && stack.push((a, mid, depth + 1)).is_ok()
                    {
                        continue;
                    }
                }
                if !visit(&seen) {
                    return false;
                }
            }
        }
        true
    }

    /// A bound (V) no device of the box has its limit below, and the check uncertain at it:
    /// for every device, every equilibrium of the branch below the bound passes all checks.
    /// Cells below `start` are known to pass for every device (a larger box's walk); the
    /// offset up to which every cell passed is returned with the bound, for smaller boxes.
    fn limit_bound(&self, (start, end): (f64, f64)) -> (f64, f64) {
        let mut bound = f64::INFINITY;
        let bound_seen = core::cell::Cell::new(bound);
        let mut passed_to = start;
        let mut last = f64::INFINITY;
        let volts = |p2: I| self.volts_per_unit * p2.sqrt();
        // Each cell's bias and, where it could set the bound, its first uncertain check.
        let look = |d: I| {
            let v = volts(self.bias_squared(d));
            let uncertain = if v.lo < bound_seen.get() {
                self.cell(d).first_uncertain()
            } else {
                None
            };
            (d, v, uncertain)
        };
        // A cell not certain to pass is halved (to `MAX_DEPTH`): its checks may hold on
        // the halves, and the bias at the first that does not is the bound.
        let split = |d: I, (_, v, uncertain): &(I, I, Option<FailureMode>)| {
            uncertain.is_some()
                && v.width() > CELL_TOLERANCE * v.hi
                && d.width() > OFFSET_RESOLUTION * d.hi
        };
        let walked_to_end = self.walk((start, end), look, split, |&(d, v, uncertain)| {
            last = v.lo;
            if uncertain.is_none() && bound == f64::INFINITY {
                passed_to = d.hi;
            }
            // Every device's branch passes the bound in this cell: each one's equilibria
            // below it lie in cells already seen.
            if v.lo >= bound {
                return false;
            }
            if uncertain.is_some() {
                bound = v.lo;
                bound_seen.set(bound);
            }
            true
        });
        if walked_to_end {
            // Devices whose branch rises past the walk's end: below the last cell's bias
            // each one's equilibria were all seen.
            bound = bound.min(last);
        }
        (bound.max(0.0), passed_to)
    }

    /// A quantity of the equilibria the box's devices hold at the bias `volts`, enclosed
    /// (`quantity` of a cell's offsets and its Φ̄² where it meets the bias); `None` when some
    /// device may hold no equilibrium at that bias before `end`. Cells below `start` are
    /// known to lie below the bias for every device; returned with the offset up to which
    /// every cell did.
    fn at_bias(
        &self,
        volts: f64,
        (start, end): (f64, f64),
        quantity: impl Fn(&Self, I, I) -> I,
    ) -> (Option<I>, f64) {
        let target = (I::point(volts.abs()) / self.volts_per_unit).square();
        let floor = target.width().max(CELL_TOLERANCE * target.hi).max(1e-12);
        let mut band: Option<I> = None;
        let look = |d: I| (d, self.bias_squared(d));
        let split = |d: I, &(_, p2): &(I, I)| {
            p2.intersect(target).is_some() && p2.width() > floor && {
                let at_mid = self.bias_squared(I::point(d.mid()));
                p2.width() > 2.0 * at_mid.width() + floor
            }
        };
        let mut below_to = start;
        let walked_to_end = self.walk((start, end), look, split, |&(d, p2)| {
            if p2.hi < target.lo && band.is_none() {
                below_to = d.hi;
            }
            if p2.lo > target.hi {
                return false;
            }
            if let Some(common) = p2.intersect(target) {
                let q = quantity(self, d, common);
                band = Some(band.map_or(q, |b| b.hull(q)));
            }
            true
        });
        if walked_to_end {
            (None, below_to)
        } else {
            (band, below_to)
        }
    }

    /// The natural frequency (Hz) on the cell at the offsets `d` under Φ̄² = `p2` (model.md
    /// §5).
    fn frequency_hz(&self, d: I, p2: I) -> I {
        let w2 = (self.elastic_stiffness(d) - p2 * self.l2p().square()).non_negative();
        (self.rad_per_s_squared * w2).sqrt() / I::point(core::f64::consts::TAU)
    }

    /// Membrane A's capacitance (F) on the cell at the offsets `d` (model.md §8: C1·λ²).
    fn capacitance_farads(&self, d: I, _p2: I) -> I {
        let l1p = self.ranges.get(1).copied().unwrap_or(I::ENTIRE);
        self.farads_per_stretch_squared * (l1p + d).square()
    }
}

/// A piece of a box the search holds: its ranges and its certified bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Leaf {
    low: DeviceParams<f64>,
    high: DeviceParams<f64>,
    bound: f64,
    /// The offset below which the branch's cells are settled for every device of the leaf
    /// (by its own walk or a larger leaf's): its parts' walks start there.
    start: f64,
}

impl Default for Leaf {
    fn default() -> Self {
        let nominal = crate::model::device::REFERENCE_DEVICE;
        Self {
            low: nominal,
            high: nominal,
            bound: 0.0,
            start: 0.0,
        }
    }
}

/// What a search found: a certified bound, the extreme sampled and where.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Found {
    /// No device in the box lies beyond it (certified).
    pub bound: f64,
    /// The most extreme value of the devices sampled.
    pub sampled: f64,
    /// The device sampled there.
    pub at: DeviceParams<f64>,
}

/// The centre of a leaf (each field the middle of its range).
fn centre(low: &DeviceParams<f64>, high: &DeviceParams<f64>) -> DeviceParams<f64> {
    let mut out = *low;
    for f in Field::ALL {
        out.set(f, low.get(f).mid_with(high.get(f)));
    }
    out
}

trait Mid {
    fn mid_with(self, other: f64) -> f64;
}

impl Mid for f64 {
    fn mid_with(self, other: f64) -> f64 {
        if self == other {
            self
        } else {
            0.5 * self + 0.5 * other
        }
    }
}

/// Branch and bound for the lowest value over `root`'s `dims`: `bound` a certified lower
/// bound on a leaf (its ranges and the offset its walk may start at; it gives back the
/// offset its parts' walks may start at), `sample` the value at one device (the leaves'
/// centres and the root's corners). Stops when the lowest leaf bound is
/// within `tolerance(lowest, spread)` of the lowest sample (`spread` the samples' range),
/// or when `leaves` is full.
fn minimise(
    root: &DeviceBox,
    dims: &[Field],
    leaves: &mut [Leaf],
    tolerance: impl Fn(f64, f64) -> f64,
    bound: impl Fn(&DeviceParams<f64>, &DeviceParams<f64>, f64) -> (f64, f64),
    sample: impl Fn(&DeviceParams<f64>) -> Option<f64>,
) -> Found {
    let width = |leaf: &Leaf, f: Field| leaf.high.get(f) - leaf.low.get(f);
    let mut best = (f64::INFINITY, root.nominal);
    let highest = core::cell::Cell::new(f64::NEG_INFINITY);
    let consider = |best: &mut (f64, DeviceParams<f64>), params: DeviceParams<f64>| {
        if let Some(v) = sample(&params) {
            if v < best.0 {
                *best = (v, params);
            }
            highest.set(highest.get().max(v));
        }
    };
    consider(&mut best, root.nominal);
    consider(&mut best, centre(&root.low, &root.high));
    // Every corner of the root's split parameters (at most 2¹⁰): where a monotone
    // dependence puts the extreme.
    let spread: Vec<Field, 16> = dims
        .iter()
        .copied()
        .filter(|&f| root.high.get(f) > root.low.get(f))
        .take(CORNER_DIMS)
        .collect();
    for corner in 0..(1u32 << spread.len()) {
        let mut params = centre(&root.low, &root.high);
        for (bit, &f) in spread.iter().enumerate() {
            let end = if corner & (1 << bit) == 0 {
                &root.low
            } else {
                &root.high
            };
            params.set(f, end.get(f));
        }
        consider(&mut best, params);
    }
    let (first_bound, first_start) = bound(&root.low, &root.high, 0.0);
    let first = Leaf {
        low: root.low,
        high: root.high,
        bound: first_bound,
        start: first_start,
    };
    let mut used = 0;
    if let Some(slot) = leaves.first_mut() {
        *slot = first;
        used = 1;
    }
    loop {
        let lowest = leaves
            .get(..used)
            .unwrap_or_default()
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.bound.total_cmp(&b.1.bound))
            .map(|(i, leaf)| (i, *leaf));
        let Some((index, leaf)) = lowest else {
            return Found {
                bound: first.bound,
                sampled: best.0,
                at: best.1,
            };
        };
        let done = best.0 - leaf.bound <= tolerance(best.0, highest.get() - best.0);
        if done || used >= leaves.len() {
            return Found {
                bound: leaf.bound.min(best.0),
                sampled: best.0,
                at: best.1,
            };
        }
        // Halve along the parameter widest against its width in the root.
        let field = dims
            .iter()
            .copied()
            .filter(|&f| width(&leaf, f) > 0.0)
            .max_by(|&x, &y| {
                let rel = |f| width(&leaf, f) / width(&first, f);
                rel(x).total_cmp(&rel(y))
            });
        let Some(field) = field else {
            return Found {
                bound: leaf.bound.min(best.0),
                sampled: best.0,
                at: best.1,
            };
        };
        let mid = leaf.low.get(field).mid_with(leaf.high.get(field));
        let (mut a, mut b) = (leaf, leaf);
        a.high.set(field, mid);
        b.low.set(field, mid);
        for half in [&mut a, &mut b] {
            // A part's bound is at least its whole's (the whole's holds on it too).
            let (bound, start) = bound(&half.low, &half.high, leaf.start);
            half.bound = bound.max(leaf.bound);
            half.start = start;
        }
        for half in [&a, &b] {
            consider(&mut best, centre(&half.low, &half.high));
        }
        if let Some(slot) = leaves.get_mut(index) {
            *slot = a;
        }
        if let Some(slot) = leaves.get_mut(used) {
            *slot = b;
        }
        used += 1;
    }
}

/// How far along the branch to walk for the devices of a box: past the scan end of its
/// centre (model.md §6); the walk's end only costs time, never validity.
fn walk_end(low: &DeviceParams<f64>, high: &DeviceParams<f64>) -> f64 {
    let c = centre(low, high);
    match Device::new(c) {
        Ok(d) => (d.scan_end_stretch() - d.prestretch_1()) * WALK_PAST_SCAN_END,
        Err(_) => high.prestretch_1,
    }
}

/// The lowest limit of the box's devices, certified (model.md §10).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuaranteedLimit {
    /// No device in the box fails below this bias, V.
    pub volts: f64,
    /// The lowest limit found among the devices sampled, V (≥ `volts`).
    pub lowest_found_volts: f64,
    /// That device's failure mode.
    pub mode: FailureMode,
    /// That device.
    pub at: DeviceParams<f64>,
}

/// The parameters whose worst end is known (model.md §10): the limit falls as μ, H and E_B
/// fall and as εr rises.
pub const MONOTONE_LIMIT: [(Field, bool); 4] = [
    (Field::ShearModulus, false),
    (Field::RelativePermittivity, true),
    (Field::Thickness, false),
    (Field::BreakdownField, false),
];

/// The parameters the limit depends on otherwise (split by the search): the lengths only
/// through L1A/L1B, which the search holds as L1A over the nominal L1B.
const LIMIT_DIMS: [Field; 4] = [
    Field::Prestretch1,
    Field::Prestretch2,
    Field::Jlim,
    Field::LengthActive,
];

/// The limit of one device (f64), `None` if it is not a valid device.
fn limit_of(params: &DeviceParams<f64>) -> Option<Limit<f64>> {
    Device::new(*params).ok().map(|d| Limit::of(&d))
}

impl DeviceBox {
    /// The box with each parameter of [`MONOTONE_LIMIT`] at its worst end, and the lengths
    /// as their ratio: L1B at its nominal value, L1A spanning every L1A/L1B of the box times
    /// it (the limit depends on the lengths through the ratio alone, model.md §10).
    pub fn worst_for_limit(&self) -> DeviceBox {
        let pinned = MONOTONE_LIMIT
            .into_iter()
            .fold(*self, |b, (field, high_is_worse)| {
                let end = if high_is_worse { &b.high } else { &b.low };
                b.pinned(field, end.get(field))
            });
        let lb = self.nominal.length_passive;
        let ratio = I::new(self.low.length_active, self.high.length_active)
            / I::new(self.low.length_passive, self.high.length_passive);
        let span = ratio * I::point(lb);
        let mut out = pinned.pinned(Field::LengthPassive, lb);
        if self.high.length_active > self.low.length_active
            || self.high.length_passive > self.low.length_passive
        {
            out.low.length_active = span.lo.min(self.nominal.length_active);
            out.high.length_active = span.hi.max(self.nominal.length_active);
        }
        out
    }

    /// A device of this box with the limit of `found` (a device of `worst_for_limit`): its
    /// ratio L1A/L1B split back into lengths inside the box.
    fn with_lengths_of(&self, found: &DeviceParams<f64>) -> DeviceParams<f64> {
        let ratio = found.length_active / found.length_passive;
        let mut out = *found;
        let la = (ratio * self.nominal.length_passive)
            .clamp(self.low.length_active, self.high.length_active);
        out.length_active = la;
        out.length_passive = (la / ratio).clamp(self.low.length_passive, self.high.length_passive);
        out
    }

    /// Whether every device of the box is a device the model takes, safe at zero bias:
    /// the first check not certain to hold there over the whole box.
    pub fn check(&self) -> Result<(), BoxError> {
        if let Err(error) = Device::new(self.nominal) {
            return Err(BoxError::Nominal(error));
        }
        if self.is_exact() {
            return Ok(());
        }
        match BoxModel::of(&self.low, &self.high)
            .cell(I::point(0.0))
            .first_uncertain()
        {
            Some(mode) => Err(BoxError::ZeroBias(mode)),
            None => Ok(()),
        }
    }

    /// The guaranteed limit: the exact box's is the nominal device's `Limit` itself.
    /// `leaves` is the search's storage (more: tighter on wide boxes).
    pub fn guaranteed_limit(&self, leaves: &mut [Leaf]) -> Result<GuaranteedLimit, BoxError> {
        self.check()?;
        let nominal =
            limit_of(&self.nominal).ok_or(BoxError::ZeroBias(FailureMode::LossOfTension1))?;
        if self.is_exact() {
            return Ok(GuaranteedLimit {
                volts: nominal.at.volts,
                lowest_found_volts: nominal.at.volts,
                mode: nominal.mode,
                at: self.nominal,
            });
        }
        let worst = self.worst_for_limit();
        let end = walk_end(&worst.low, &worst.high);
        let found = minimise(
            &worst,
            &LIMIT_DIMS,
            leaves,
            |lowest, _| LIMIT_TOLERANCE * lowest.abs(),
            |low, high, start| BoxModel::of(low, high).limit_bound((start, end)),
            |p| limit_of(p).map(|l| l.at.volts),
        );
        let at = self.with_lengths_of(&found.at);
        let mode = limit_of(&at).map_or(nominal.mode, |l| l.mode);
        Ok(GuaranteedLimit {
            volts: found.bound,
            lowest_found_volts: found.sampled,
            mode,
            at,
        })
    }

    /// The natural frequencies (Hz) the box's devices have at the bias `volts`: a certified
    /// enclosure [low, high] and the devices sampled at each end.
    pub fn band_hz(&self, volts: f64, leaves: &mut [Leaf]) -> Result<Band, BoxError> {
        // f² = (μ·L2·H/M)·ω̄² with ω̄² free of m, ρ and L2: f falls with m and ρ, rises
        // with L2 (see `BoxModel::of`); each end of the band takes their worst.
        let pin = |b: DeviceBox, toward_high: bool| {
            let (up, down) = if toward_high {
                (&b.high, &b.low)
            } else {
                (&b.low, &b.high)
            };
            b.pinned(Field::BarMass, down.get(Field::BarMass))
                .pinned(Field::Density, down.get(Field::Density))
                .pinned(Field::Width, up.get(Field::Width))
        };
        let (low, high) =
            self.ends_at_bias(volts, leaves, pin, BoxModel::frequency_hz, |d, s| {
                d.natural_frequency_hz(s)
            })?;
        Ok(Band {
            low_hz: low.bound.max(0.0),
            high_hz: -high.bound,
            sampled_low_hz: low.sampled,
            sampled_high_hz: -high.sampled,
        })
    }

    /// Membrane A's capacitance (F, model.md §8) every device of the box has at the bias
    /// `volts`, certified: (low, high). What the board's self-sensing measures at a known
    /// bias (`crate::estimate::capacitance`).
    pub fn capacitance_farads(
        &self,
        volts: f64,
        leaves: &mut [Leaf],
    ) -> Result<(f64, f64), BoxError> {
        // C = C1·λ² with C1 = ε·L1A·L2·λ2p²/H: L2 enters C1 alone (not the branch), so each
        // end takes its end; m and ρ enter neither.
        let pin = |b: DeviceBox, toward_high: bool| {
            let width = if toward_high { &b.high } else { &b.low }.get(Field::Width);
            let nominal = b.nominal;
            b.pinned(Field::BarMass, nominal.bar_mass)
                .pinned(Field::Density, nominal.density)
                .pinned(Field::Width, width)
        };
        let (low, high) =
            self.ends_at_bias(volts, leaves, pin, BoxModel::capacitance_farads, |d, s| {
                d.params().capacitance_farads(s)
            })?;
        Ok((low.bound.max(0.0), -high.bound))
    }

    /// The lowest and (negated) highest of a quantity of the box's devices at the bias
    /// `volts`: `enclose` on a leaf's cells, `of` at one device's stretch there; `pin` sets
    /// the parameters the quantity is monotone in to the end that makes it low (false) or
    /// high (true).
    fn ends_at_bias(
        &self,
        volts: f64,
        leaves: &mut [Leaf],
        pin: impl Fn(DeviceBox, bool) -> DeviceBox,
        enclose: fn(&BoxModel, I, I) -> I,
        of: fn(&Device<f64>, f64) -> f64,
    ) -> Result<(Found, Found), BoxError> {
        self.check()?;
        let at = |p: &DeviceParams<f64>| {
            let d = Device::new(*p).ok()?;
            let stretch = Limit::of(&d).stretch_for_bias(&d, volts)?;
            Some(of(&d, stretch))
        };
        if self.is_exact() {
            let x = at(&self.nominal).ok_or(BoxError::NoEquilibrium { volts })?;
            let found = |v: f64| Found {
                bound: v,
                sampled: v,
                at: self.nominal,
            };
            return Ok((found(x), found(-x)));
        }
        let dims = [
            Field::ShearModulus,
            Field::RelativePermittivity,
            Field::Thickness,
            Field::Prestretch1,
            Field::Prestretch2,
            Field::Jlim,
            Field::LengthActive,
            Field::LengthPassive,
        ];
        let end = walk_end(&self.low, &self.high);
        let enclosed = |low: &DeviceParams<f64>, high: &DeviceParams<f64>, start: f64| {
            BoxModel::of(low, high).at_bias(volts, (start, end), enclose)
        };
        let low = minimise(
            &pin(*self, false),
            &dims,
            leaves,
            |_, spread| BAND_TOLERANCE * spread,
            |l, h, start| {
                let (b, start) = enclosed(l, h, start);
                (b.map_or(f64::NEG_INFINITY, |b| b.lo), start)
            },
            at,
        );
        let high = minimise(
            &pin(*self, true),
            &dims,
            leaves,
            |_, spread| BAND_TOLERANCE * spread,
            |l, h, start| {
                let (b, start) = enclosed(l, h, start);
                (b.map_or(f64::NEG_INFINITY, |b| -b.hi), start)
            },
            |p| at(p).map(|x| -x),
        );
        if !(low.bound.is_finite() && high.bound.is_finite()) {
            return Err(BoxError::NoEquilibrium { volts });
        }
        Ok((low, high))
    }

    /// The targets every device of the box reaches at some bias in [0, `cap_volts`]: between
    /// the band at zero bias and the band at the cap (each device's frequency moves
    /// continuously from one to the other), `None` when the two bands overlap.
    pub fn tunable_range_hz(
        &self,
        cap_volts: f64,
        leaves: &mut [Leaf],
    ) -> Result<Option<(f64, f64)>, BoxError> {
        let rest = self.band_hz(0.0, leaves)?;
        let cap = self.band_hz(cap_volts, leaves)?;
        Ok(if cap.high_hz < rest.low_hz {
            Some((cap.high_hz, rest.low_hz))
        } else if rest.high_hz < cap.low_hz {
            Some((rest.high_hz, cap.low_hz))
        } else {
            None
        })
    }
}

/// Why a box has no guaranteed answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoxError {
    /// The nominal device itself is refused.
    Nominal(ParamError),
    /// Some device of the box may fail this check at zero bias already.
    ZeroBias(FailureMode),
    /// Some device of the box may hold no equilibrium at this bias (past its fold).
    NoEquilibrium { volts: f64 },
}

impl core::fmt::Display for BoxError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            BoxError::Nominal(error) => write!(f, "{error}"),
            BoxError::ZeroBias(mode) => write!(
                f,
                "the tolerances reach devices that may fail at zero bias by {} \
                 (narrow the tolerances of the pre-stretches or jlim)",
                mode.description()
            ),
            BoxError::NoEquilibrium { volts } => write!(
                f,
                "some devices within the tolerances hold no equilibrium at {volts} V \
                 (past their fold): no frequency band there"
            ),
        }
    }
}

impl core::error::Error for BoxError {}

/// The natural frequencies of a box's devices at one bias.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    /// No device lies below (certified), Hz.
    pub low_hz: f64,
    /// No device lies above (certified), Hz.
    pub high_hz: f64,
    /// The lowest and highest frequencies of the devices sampled, Hz.
    pub sampled_low_hz: f64,
    pub sampled_high_hz: f64,
}
