//! `axiscal plan --optimize`: the spans and the points per sweep that minimise the predicted
//! tool error over a workspace ([`PlanObjective`]) at a fixed total of axis-experiment points,
//! within the joint limits and the lines of sight (`docs/method.md#plans-that-buy-accuracy`).
//!
//! The search is deterministic coordinate descent seeded by the given plan (paper Table 1 by
//! default) with its intervals scaled to the point budget ([`with_point_budget`]). Each round:
//! 1. **Spans**, sweep by sweep: the largest span that keeps every command within the limits
//!    (bisection, no calibration, 0.1 deg/mm resolution), the current span x 0.8 and x 1.25, and the middle between the current and
//!    the largest; the best feasible one is taken when it lowers the predicted position RMS.
//!    Sweeps stay centred on the reference (as the workspace is).
//! 2. **Points**, for each ordered pair of sweeps (a, b): move `m` poses' worth of points from
//!    a to b (`m` = 4, 2, 1, the first that helps; a sweep with a second target costs two
//!    points a pose, so a move keeps the total exactly), never below
//!    [`OptimizeOptions::min_intervals`].
//!
//! A point the nominal arm hides from a station is planned (it counts against the budget) but
//! not measured, so the prediction, not a constraint, keeps the sight lines. Rounds repeat until one changes nothing (or [`OptimizeOptions::max_rounds`]). Which joints
//! are swept, in what order, and which carry a second target stay as in the seed: a second
//! target is what measures a coupling, and without it the coupling would be taken as nominal
//! and drop out of the predicted covariance (an apparent gain that is a blind spot). Cost: one
//! calibration of a noise-free campaign per candidate (~10 ms in a release build), about 25 +
//! 30 x (1..3) candidates a round, a few hundred for the paper robot.

use super::predict::{PlanObjective, PlanPrediction, PredictError};
use super::CalibrationPlan;
use crate::kinematics::JointKind;
use crate::robot::RobotDescription;

/// Settings of the search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OptimizeOptions {
    /// Fewest intervals a sweep keeps (its transmission and coupling fits need points).
    pub min_intervals: usize,
    /// Most rounds of coordinate descent.
    pub max_rounds: usize,
}

impl Default for OptimizeOptions {
    /// At least 8 intervals a sweep (9 poses: a harmonic transmission of order 2 with the
    /// axis has 9 unknowns along the sweep), at most 20 rounds.
    fn default() -> Self {
        OptimizeOptions {
            min_intervals: 8,
            max_rounds: 20,
        }
    }
}

/// The result of [`optimize`].
#[derive(Clone, Debug, PartialEq)]
pub struct Optimized {
    /// The optimised plan.
    pub plan: CalibrationPlan,
    /// Its prediction.
    pub prediction: PlanPrediction,
    /// The seed plan's prediction (the same number of points).
    pub seed: PlanPrediction,
    /// Candidate plans calibrated.
    pub candidates: usize,
    /// Rounds run.
    pub rounds: usize,
}

/// Points a sweep measures per pose (one target, or two with the second target).
fn targets(sweep: &super::AxisSweep) -> usize {
    1 + usize::from(sweep.second_target)
}

/// Axis-experiment points of `plan`.
pub fn axis_points(plan: &CalibrationPlan) -> usize {
    plan.sweeps.iter().map(|s| s.poses() * targets(s)).sum()
}

/// `plan` with its intervals scaled so that its axis experiments measure `points` points (each
/// sweep's share as in `plan`, at least 2 intervals); the remainder from rounding is given to,
/// or taken from, the one-target sweeps in turn. `None` when `points` cannot be met exactly.
pub fn with_point_budget(plan: &CalibrationPlan, points: usize) -> Option<CalibrationPlan> {
    let mut out = plan.clone();
    let total = axis_points(plan) as f64;
    for s in &mut out.sweeps {
        let share = (s.poses() * targets(s)) as f64 * points as f64 / total;
        s.intervals = ((share / targets(s) as f64).round() as usize).saturating_sub(1).max(2);
    }
    let singles: Vec<usize> = (0..out.sweeps.len()).filter(|&i| !out.sweeps[i].second_target).collect();
    let mut turn = 0;
    while axis_points(&out) != points {
        let pairs_only = singles.is_empty();
        let i = if pairs_only { turn % out.sweeps.len() } else { singles[turn % singles.len()] };
        let have = axis_points(&out);
        let t = targets(&out.sweeps[i]);
        if have < points && points - have >= t {
            out.sweeps[i].intervals += 1;
        } else if have > points && out.sweeps[i].intervals > 2 {
            out.sweeps[i].intervals -= 1;
        } else if pairs_only || turn > 4 * out.sweeps.len() * points.max(1) {
            return None;
        }
        turn += 1;
    }
    Some(out)
}

/// The search state: the objective, the best plan so far and the count of calibrations.
struct Search<'a> {
    objective: &'a PlanObjective,
    desc: &'a RobotDescription,
    best: CalibrationPlan,
    best_prediction: PlanPrediction,
    candidates: usize,
}

impl Search<'_> {
    /// Calibrates `plan`; takes it when it lowers the predicted position RMS by more than
    /// 0.1 % (the tie threshold keeps the descent from cycling on rounding).
    fn try_plan(&mut self, plan: CalibrationPlan) -> bool {
        self.candidates += 1;
        match self.objective.predict(&plan) {
            Ok(p) if p.position_rms_mm < self.best_prediction.position_rms_mm * (1.0 - 1e-3) => {
                self.best = plan;
                self.best_prediction = p;
                true
            }
            _ => false,
        }
    }

    /// Whether `plan` stays within the joint limits (no calibration; a point out of sight is
    /// not measured, which the prediction counts).
    fn feasible(&self, plan: &CalibrationPlan) -> bool {
        plan.validate(self.desc).is_ok()
    }

    /// The largest span of sweep `i` (centred) that is feasible, by bisection to 0.1 deg/mm.
    fn largest_span(&self, i: usize) -> f64 {
        let joint = &self.desc.joints[self.best.sweeps[i].joint - 1];
        let range = joint.limits[1] - joint.limits[0];
        let cap = match joint.kind {
            // A full turn would measure the first pose twice.
            JointKind::Revolute => range.min(350.0),
            JointKind::Prismatic => range,
        };
        let with_span = |span: f64| {
            let mut p = self.best.clone();
            p.sweeps[i].span = span;
            p
        };
        let (mut lo, mut hi) = (self.best.sweeps[i].span, cap);
        if self.feasible(&with_span(hi)) {
            return hi;
        }
        while hi - lo > 0.1 {
            let mid = 0.5 * (lo + hi);
            if self.feasible(&with_span(mid)) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (lo * 10.0).floor() / 10.0
    }

    /// Step 1 of a round for sweep `i`; whether it changed the plan.
    fn improve_span(&mut self, i: usize) -> bool {
        let current = self.best.sweeps[i].span;
        let largest = self.largest_span(i).max(current);
        let round = |x: f64| (x * 10.0).round() / 10.0;
        let mut spans = vec![largest, round(0.5 * (current + largest)), round(current * 1.25), round(current * 0.8)];
        spans.dedup();
        let base = self.best.clone();
        let mut changed = false;
        for span in spans.into_iter().filter(|&s| s > 0.0 && s <= largest && s != current) {
            let mut plan = base.clone();
            plan.sweeps[i].span = span;
            if self.feasible(&plan) {
                changed |= self.try_plan(plan);
            }
        }
        changed
    }

    /// Step 2 of a round for the pair (a, b); whether it changed the plan.
    fn improve_points(&mut self, a: usize, b: usize, min_intervals: usize) -> bool {
        let (ta, tb) = (targets(&self.best.sweeps[a]), targets(&self.best.sweeps[b]));
        // Poses moved: a loses `m * tb / g`, b gains `m * ta / g` (g = gcd), the same points.
        let g = if ta == tb { ta } else { 1 };
        for m in [4, 2, 1] {
            let (lose, gain) = (m * tb / g, m * ta / g);
            if self.best.sweeps[a].intervals < min_intervals + lose {
                continue;
            }
            let mut plan = self.best.clone();
            plan.sweeps[a].intervals -= lose;
            plan.sweeps[b].intervals += gain;
            if self.try_plan(plan) {
                return true;
            }
        }
        false
    }
}

/// Optimises `seed` (already at the point budget) for `objective`; see the module docs.
pub fn optimize(
    objective: &PlanObjective,
    desc: &RobotDescription,
    seed: &CalibrationPlan,
    options: OptimizeOptions,
) -> Result<Optimized, PredictError> {
    let seed_prediction = objective.predict(seed)?;
    let mut search = Search {
        objective,
        desc,
        best: seed.clone(),
        best_prediction: seed_prediction.clone(),
        candidates: 1,
    };
    let n = seed.sweeps.len();
    let mut rounds = 0;
    while rounds < options.max_rounds {
        rounds += 1;
        let mut changed = false;
        for i in 0..n {
            changed |= search.improve_span(i);
        }
        for a in 0..n {
            for b in (0..n).filter(|&b| b != a) {
                changed |= search.improve_points(a, b, options.min_intervals);
            }
        }
        if !changed {
            break;
        }
    }
    Ok(Optimized {
        plan: search.best,
        prediction: search.best_prediction,
        seed: seed_prediction,
        candidates: search.candidates,
        rounds,
    })
}
