//! Gross errors among the second targets (target 1) of the sweeps that measure a coupling
//! (eqs. 14-15), after [`super::screen_sweeps`]'s test of target 0: each point's passive angle
//! against the curve of its neighbours in the active angle (`docs/method.md`, "Outliers").
//! A reading swapped with another step's, or off, would shift the coupling by tens of its
//! sigmas, or fail its fit (the fractional form does not converge through it).

use super::super::outlier_point::{OutlierPoint, OutlierTest, row_of};
use super::super::{CalibrationOptions, Detail, ProcedureError, SecondTargetData, calibrate_model};
use super::rounds::{OUTLIER_ROUNDS_MAX, OUTLIER_SHARE_MAX, too_many_which, without_poses};
use crate::measurement::MeasurementSet;
use crate::numerics::lsq::linear_lsq;
use crate::numerics::stats::chi_square_quantile;
use crate::numerics::stats::median;
use crate::robot::RobotDescription;
use nalgebra::{DMatrix, DVector};

/// The second targets' gross errors: the points of the sweeps that measure a
/// coupling (target 1, eqs. 14-15) whose passive angle lies beyond the `fence` from the curve
/// of its neighbours ([`SecondTargetData::flagged`]), the passive angles as the procedure on
/// `set` (its lean path, weighted with the noise of `options`) gives them. When a coupling
/// fit fails on them, its points are tested all the same, the points flagged set aside and the
/// procedure rerun; `keep` flags without dropping. `original` is the file's set (the points'
/// lines). A procedure that fails otherwise is left to the calibration, which says why.
pub(super) fn outliers(
    set: &MeasurementSet,
    original: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
    (fence, keep): (f64, bool),
) -> Result<Vec<OutlierPoint>, ProcedureError> {
    let lean = CalibrationOptions {
        estimate_noise: false,
        ..options.clone()
    };
    let floor_mm = options.noise_rms_3d_mm / 3f64.sqrt();
    let mut working = set.clone();
    let mut out: Vec<OutlierPoint> = Vec::new();
    // At most one rerun per coupling whose fit failed on its data.
    for _ in 0..=desc.couplings.len() {
        let (tested, failed): (Vec<(String, usize, SecondTargetData)>, bool) =
            match calibrate_model(&working, desc, &lean, Detail::Model) {
                Ok(model) => (
                    model
                        .couplings
                        .into_iter()
                        .map(|c| (c.experiment, c.from, c.second_target))
                        .collect(),
                    false,
                ),
                Err(ProcedureError::CouplingFit {
                    experiment,
                    joint,
                    data,
                    ..
                }) => (vec![(experiment, joint, *data)], true),
                Err(_) => (vec![], false),
            };
        let before = out.len();
        for (experiment, joint, data) in tested {
            let points: Vec<OutlierPoint> = data
                .flagged(floor_mm, fence)
                .into_iter()
                .map(|w| {
                    let mut o = OutlierPoint {
                        experiment: experiment.clone(),
                        joint,
                        step: w.step,
                        target: 1,
                        line: None,
                        residual_mm: w.residual_mm,
                        normalised_residual: w.ratio,
                        fence,
                        dropped: !keep,
                        approach: None,
                        test: OutlierTest::Screen,
                    };
                    o.line = row_of(original, &o).and_then(|row| original.line_of(row));
                    o
                })
                .collect();
            if points.len() as f64 > OUTLIER_SHARE_MAX * data.steps.len() as f64 {
                let mut off: Vec<(usize, usize, Option<u64>)> = points
                    .iter()
                    .map(|o| {
                        (
                            data.steps.iter().position(|&s| s == o.step).unwrap_or(usize::MAX),
                            o.step,
                            o.line,
                        )
                    })
                    .collect();
                off.sort_unstable();
                return Err(ProcedureError::TooManyOutliers {
                    experiment,
                    flagged: points.len(),
                    points: data.steps.len(),
                    fence,
                    which: too_many_which(&off),
                });
            }
            out.extend(points);
        }
        let dropping: Vec<OutlierPoint> = out[before..]
            .iter()
            .map(|o| OutlierPoint {
                dropped: true,
                approach: None,
                ..o.clone()
            })
            .collect();
        match without_poses(&working, &dropping) {
            Some(next) if failed => working = next,
            _ => break,
        }
    }
    Ok(out)
}

/// A second target's reading far from the curve of its neighbours ([`SecondTargetData`]).
#[derive(Clone, Debug, PartialEq)]
pub struct WorstSecondTarget {
    /// Its step.
    pub step: usize,
    /// Its distance from the curve \[mm\] (the passive angle's residual over the prediction's
    /// standard error in units of a point's, times its lever arm).
    pub residual_mm: f64,
    /// That over the residuals' scale.
    pub ratio: f64,
}

impl std::fmt::Display for WorstSecondTarget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "; its second target (target 1) lies farthest from the curve of its neighbours at step {}: {:.3} mm, {:.1} times their scatter (check that row: a reading swapped with another step's or off)",
            self.step, self.residual_mm, self.ratio
        )
    }
}

/// The other points a second-target point is predicted from ([`SecondTargetData::residuals`]):
/// its nearest in the active angle.
const SECOND_TARGET_NEIGHBOURS: usize = 6;

/// Each prediction is that of the quadratic through the subset of this many of the neighbours
/// (one more than a quadratic's coefficients: a degree of freedom each) it fits best: two gross
/// errors among six neighbours leave a subset clean, and it fits far better than any other.
const SECOND_TARGET_SUBSET: usize = 4;

/// The subsets of `SECOND_TARGET_SUBSET` indices of `0..SECOND_TARGET_NEIGHBOURS`.
fn neighbour_subsets() -> Vec<Vec<usize>> {
    (0u32..1 << SECOND_TARGET_NEIGHBOURS)
        .filter(|m| m.count_ones() as usize == SECOND_TARGET_SUBSET)
        .map(|m| (0..SECOND_TARGET_NEIGHBOURS).filter(|&k| m & (1 << k) != 0).collect())
        .collect()
}

impl SecondTargetData {
    /// The same data without point `i`.
    fn without(&self, i: usize) -> SecondTargetData {
        let drop = |v: &[f64]| -> Vec<f64> { v.iter().enumerate().filter(|(j, _)| *j != i).map(|(_, x)| *x).collect() };
        SecondTargetData {
            steps: self
                .steps
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, s)| *s)
                .collect(),
            active_rad: drop(&self.active_rad),
            passive_rad: drop(&self.passive_rad),
            lever_arms_m: drop(&self.lever_arms_m),
        }
    }

    /// The indices of point `i`'s [`SECOND_TARGET_NEIGHBOURS`] nearest others in the active
    /// angle, from `order` (the points sorted by it) and `at` (each point's place in `order`).
    fn neighbours(&self, i: usize, order: &[usize], at: &[usize]) -> Vec<usize> {
        let t = &self.active_rad;
        let (lo, hi) = (
            at[i].saturating_sub(SECOND_TARGET_NEIGHBOURS),
            (at[i] + SECOND_TARGET_NEIGHBOURS + 1).min(order.len()),
        );
        let mut near: Vec<usize> = order[lo..hi].iter().copied().filter(|&j| j != i).collect();
        near.sort_by(|&a, &b| (t[a] - t[i]).abs().total_cmp(&(t[b] - t[i]).abs()));
        near.truncate(SECOND_TARGET_NEIGHBOURS);
        near
    }

    /// Each point's passive angle's residual from its [`SECOND_TARGET_NEIGHBOURS`] nearest
    /// others' curve (the quadratic through the [`SECOND_TARGET_SUBSET`] of them it fits best),
    /// over the prediction's standard error in units of a point's (it extrapolates at a
    /// sweep's end), times its lever arm
    /// \[mm\] (`None` where no fit succeeds). A coupling over a few steps is a quadratic to well
    /// within the noise; a reading swapped or off lies far from its neighbours' curve, which it
    /// cannot pull (a fit of every point, the coupling's own form included, bends towards it,
    /// and two such readings lift every residual). Empty with fewer points than a prediction
    /// needs.
    fn residuals(&self) -> Vec<Option<f64>> {
        let (t, n) = (&self.active_rad, self.steps.len());
        if n <= SECOND_TARGET_NEIGHBOURS {
            return vec![];
        }
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| t[a].total_cmp(&t[b]));
        let mut at = vec![0; n];
        order.iter().enumerate().for_each(|(place, &i)| at[i] = place);
        let subsets = neighbour_subsets();
        (0..n)
            .map(|i| {
                let near = self.neighbours(i, &order, &at);
                // Centred on the point and scaled to the neighbours' reach: a prediction is the
                // constant coefficient, its variance factor the first diagonal entry.
                let reach = near.iter().map(|&j| (t[j] - t[i]).abs()).fold(0.0, f64::max);
                let x = |j: usize| (t[j] - t[i]) / reach;
                let (predicted, variance, _) = subsets
                    .iter()
                    .filter_map(|subset| {
                        let a = DMatrix::from_fn(subset.len(), 3, |r, c| x(near[subset[r]]).powi(c as i32));
                        let y = DVector::from_iterator(subset.len(), subset.iter().map(|&k| self.passive_rad[near[k]]));
                        let (c, inv, r) = linear_lsq(&a, &y, "second-target outlier test").ok()?;
                        Some((c[0], inv[(0, 0)], r.norm_squared()))
                    })
                    .min_by(|a, b| a.2.total_cmp(&b.2))?;
                let standard = (self.passive_rad[i] - predicted) / (1.0 + variance).sqrt();
                Some(standard * self.lever_arms_m[i] * 1e3)
            })
            .collect()
    }

    /// Each point's residual ([`Self::residuals`]) over their scale: their median absolute value
    /// over that of a standard normal variable, at least `floor_mm`. `(point, residual, ratio)`.
    fn normalised(&self, floor_mm: f64) -> Vec<(usize, f64, f64)> {
        let residuals: Vec<(usize, f64)> = self
            .residuals()
            .into_iter()
            .enumerate()
            .filter_map(|(i, r)| Some((i, r?.abs())))
            .collect();
        let sizes: Vec<f64> = residuals.iter().map(|r| r.1).collect();
        let scale = (median(&sizes) / chi_square_quantile(0.5, 1.0).sqrt()).max(floor_mm);
        residuals.into_iter().map(|(i, r)| (i, r, r / scale)).collect()
    }

    /// The point farthest from its neighbours' curve, its ratio to the residuals' scale.
    pub fn worst(&self) -> Option<WorstSecondTarget> {
        let (i, residual_mm, ratio) = self.normalised(0.0).into_iter().max_by(|a, b| a.2.total_cmp(&b.2))?;
        Some(WorstSecondTarget {
            step: self.steps[i],
            residual_mm,
            ratio,
        })
    }

    /// The points beyond `fence` (ratios to the scale of [`Self::normalised`], at least
    /// `floor_mm`), the worst set aside one at a time until none is left; at most one more
    /// than [`OUTLIER_SHARE_MAX`] of the points (or [`OUTLIER_ROUNDS_MAX`]).
    fn flagged(&self, floor_mm: f64, fence: f64) -> Vec<WorstSecondTarget> {
        let most = ((OUTLIER_SHARE_MAX * self.steps.len() as f64).floor() as usize + 1).min(OUTLIER_ROUNDS_MAX);
        let mut data = self.clone();
        let mut out = Vec::new();
        while out.len() < most {
            let worst = data.normalised(floor_mm).into_iter().max_by(|a, b| a.2.total_cmp(&b.2));
            let Some((i, residual_mm, ratio)) = worst.filter(|w| w.2 > fence) else {
                break;
            };
            out.push(WorstSecondTarget {
                step: data.steps[i],
                residual_mm,
                ratio,
            });
            data = data.without(i);
        }
        out
    }
}
