//! `axiscal plan --optimize`: the spans and the points per sweep that minimise the predicted
//! tool error over a workspace ([`PlanObjective`]) at a fixed total of axis-experiment points,
//! within the joint limits and the lines of sight (`docs/method.md#plans-that-buy-accuracy`).
//!
//! The search is deterministic coordinate descent seeded by the given plan (paper Table 1 by
//! default) with its intervals scaled to the point budget ([`with_point_budget`]). Each round:
//! 1. **Spans and placement**, sweep by sweep: the largest span that keeps every command within
//!    the limits (bisection, no calibration, 0.1 deg/mm resolution), half-way to it from the
//!    current span, the current span x 1.25 and x 0.8; a sweep with a second target is tried
//!    both with its follower joint starting at the reference and centred on it
//!    (`held_at = -slope x span / 2`). The best feasible candidate is taken when it lowers the predicted
//!    position RMS. Sweeps stay centred on the reference (as the workspace is).
//! 2. **Points**, for each ordered pair of sweeps (a, b): move `m` poses' worth of points from
//!    a to b (`m` = 4, 2, 1, the first that helps; a sweep with a second target costs two
//!    points a pose, so a move keeps the total exactly), never below
//!    [`OptimizeOptions::min_intervals`].
//!
//! A point the nominal arm hides from a station is planned (it counts against the budget) but
//! not measured, so the prediction, not a constraint, keeps the sight lines. Rounds repeat
//! until one changes nothing (or [`OptimizeOptions::max_rounds`]). Which joints are swept, in
//! what order, and which carry a second target stay as in the seed: a second target is what
//! measures a coupling, and without it the coupling would be taken as nominal and drop out of
//! the predicted covariance (an apparent gain that is a blind spot). Cost: one calibration of
//! a noise-free campaign per candidate (~30 ms in a release build), about 30 + 30 x (1..3)
//! candidates a round, a few hundred for the paper robot.

use super::CalibrationPlan;
use super::predict::{PlanObjective, PlanPrediction, PredictError};
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

/// Points one pose of every sweep of `plan` measures together (one a sweep, two with its
/// second target): a sweep of `n` intervals measures `n + 1` poses, so every sweep keeps `n`
/// intervals at once within `(n + 1)` times this many axis points.
pub fn points_per_round(plan: &CalibrationPlan) -> usize {
    plan.sweeps.iter().map(targets).sum()
}

/// `plan` with its intervals scaled so that its axis experiments measure `points` points (each
/// sweep's share as in `plan`, at least 2 intervals); the remainder from rounding is given to,
/// or taken from, the one-target sweeps in turn. `None` when `points` cannot be met exactly.
pub fn with_point_budget(plan: &CalibrationPlan, points: usize) -> Option<CalibrationPlan> {
    let total = axis_points(plan) as f64;
    if plan.sweeps.is_empty() || total == 0.0 {
        return None;
    }
    let mut out = plan.clone();
    for s in &mut out.sweeps {
        let share = (s.poses() * targets(s)) as f64 * points as f64 / total;
        s.intervals = ((share / targets(s) as f64).round() as usize).saturating_sub(1).max(2);
    }
    let singles: Vec<usize> = (0..out.sweeps.len())
        .filter(|&i| !out.sweeps[i].second_target)
        .collect();
    let order: Vec<usize> = if singles.is_empty() {
        (0..out.sweeps.len()).collect()
    } else {
        singles
    };
    // Above the budget a sweep gives up one pose; below it takes one only where that does not
    // overshoot, so the count moves monotonically once below: it ends when the budget is met
    // or when a whole round of sweeps can move no further.
    let (mut turn, mut idle) = (0, 0);
    while axis_points(&out) != points {
        if idle >= order.len() {
            return None;
        }
        let i = order[turn % order.len()];
        let have = axis_points(&out);
        let t = targets(&out.sweeps[i]);
        if have < points && points - have >= t {
            out.sweeps[i].intervals += 1;
            idle = 0;
        } else if have > points && out.sweeps[i].intervals > 2 {
            out.sweeps[i].intervals -= 1;
            idle = 0;
        } else {
            idle += 1;
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

    /// The plan with sweep `i` over `span`, centred on the reference; with `centre_follower`
    /// (a sweep with a second target only) the follower joint `k + 1`, which moves one way by
    /// `slope x span` to hold its actuator still, starts at `-slope x span / 2` from the
    /// reference (`held_at`), so that it too is centred and the span can grow to the limits.
    fn placed(&self, i: usize, span: f64, centre_follower: bool) -> CalibrationPlan {
        let mut plan = self.best.clone();
        let sweep = &mut plan.sweeps[i];
        sweep.span = span;
        let slope = self
            .desc
            .nominal_coupling_from(sweep.joint)
            .filter(|_| sweep.second_target);
        if let Some(slope) = slope {
            let follower = sweep.joint; // 0-based index of joint k + 1
            let mut held = sweep.held_at.clone().unwrap_or_else(|| vec![0.0; self.desc.dof()]);
            held[follower] = if centre_follower { -slope * span / 2.0 } else { 0.0 };
            sweep.held_at = held.iter().any(|v| *v != 0.0).then_some(held);
        }
        plan
    }

    /// Whether sweep `i` of the best plan has its follower centred (see [`Search::placed`]).
    fn follower_centred(&self, i: usize) -> bool {
        let sweep = &self.best.sweeps[i];
        sweep
            .held_at
            .as_ref()
            .is_some_and(|h| h.get(sweep.joint).is_some_and(|v| *v != 0.0))
    }

    /// The largest span of sweep `i` (placed as [`Search::placed`]) within the limits, by
    /// bisection to 0.1 deg/mm.
    fn largest_span(&self, i: usize, centre_follower: bool) -> f64 {
        let joint = &self.desc.joints[self.best.sweeps[i].joint - 1];
        let range = joint.limits[1] - joint.limits[0];
        let cap = match joint.kind {
            // A full turn would measure the first pose twice.
            JointKind::Revolute => range.min(350.0),
            JointKind::Prismatic => range,
        };
        let feasible = |span: f64| self.feasible(&self.placed(i, span, centre_follower));
        if feasible(cap) {
            return cap;
        }
        let stop = crate::numerics::roots::Bisection::to_width(0.1);
        let [lo, _] = crate::numerics::roots::bisect_infallible(0.0, cap, stop, feasible);
        (lo * 10.0).floor() / 10.0
    }

    /// Step 1 of a round for sweep `i`; whether it changed the plan.
    fn improve_span(&mut self, i: usize) -> bool {
        let current = (self.best.sweeps[i].span, self.follower_centred(i));
        let placements: &[bool] = if self.best.sweeps[i].second_target {
            &[false, true]
        } else {
            &[false]
        };
        let round = |x: f64| (x * 10.0).round() / 10.0;
        let mut candidates = Vec::new();
        for &centred in placements {
            let largest = self.largest_span(i, centred);
            let s = current.0;
            for span in [largest, round(0.5 * (s + largest)), round(s * 1.25), round(s * 0.8)] {
                if span > 0.0 && span <= largest && (span, centred) != current && !candidates.contains(&(span, centred))
                {
                    candidates.push((span, centred));
                }
            }
        }
        let mut changed = false;
        for (span, centred) in candidates {
            let plan = self.placed(i, span, centred);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Table 1 met exactly at several budgets (including odd ones, which only its one-target
    /// sweeps can absorb); an empty plan and a budget a two-target-only plan cannot meet are
    /// `None`, not a panic or an endless loop.
    #[test]
    fn the_point_budget_is_met_exactly_or_refused() {
        let table1 = CalibrationPlan::table1(6);
        for points in [60, 101, 129, 200, 333] {
            let plan = with_point_budget(&table1, points).expect("reachable");
            assert_eq!(axis_points(&plan), points);
            assert!(plan.sweeps.iter().all(|s| s.intervals >= 2));
        }
        let empty = CalibrationPlan {
            sweeps: vec![],
            ..table1.clone()
        };
        assert!(with_point_budget(&empty, 50).is_none());
        let pairs = CalibrationPlan {
            sweeps: table1.sweeps.iter().filter(|s| s.second_target).cloned().collect(),
            ..table1
        };
        let even = with_point_budget(&pairs, 60).expect("an even budget of pairs");
        assert_eq!(axis_points(&even), 60);
        assert!(with_point_budget(&pairs, 61).is_none());
    }
}
