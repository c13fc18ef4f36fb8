//! `calibrate --refine`: the calibrated model refined on the free poses of the same file, the
//! identifiable combination only (module docs of [`super`]; `docs/method.md`, "Refinement on
//! free poses").
//!
//! Parameters are measured in units of their unrefined 1-sigma (`u_i = p_i / sigma_i`, the
//! calibration's propagated sigma; 1 mm, 1 mrad or 1e-3 where it reports none), so that the
//! singular values `s_i` of the design in `u` (metres of prediction over the training rows per
//! unrefined sigma along the direction) compare with the per-coordinate measurement noise
//! `sigma_c`: a direction is **kept** when `s_i >= sigma_c`, i.e. when the free poses carry at
//! least as much information about it (`s_i^2 / sigma_c^2`) as the axis experiments already
//! did (1), and dropped otherwise (with the exact redundancies, below [`NULL_DIRECTION_TOLERANCE`]
//! of the largest). Along a dropped direction the unrefined estimate and its sigma stand.

use super::linear::{LinearFit, NULL_DIRECTION_TOLERANCE, sensitivity};
use super::parameters::{DirectionWeight, ParameterUnit, RefitParameter};
use super::{GaussNewtonSteps, refine_from_linear};
use crate::numerics::lsq::Stop;
use crate::numerics::outlier_rounds::{GroupFlag, TooManyOutliers, fit_without_outliers};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Options of [`refine_free_poses`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineOptions {
    /// Measurement noise, 3-D RMS of a point \[mm\] (the rank rule and the covariance).
    pub noise_rms_3d_mm: f64,
    /// Folds of the held-out check (pose `i` is held out in fold `i mod folds`).
    pub folds: usize,
    /// Gauss-Newton steps at most after the linearised solution.
    pub max_steps: usize,
    /// Free poses refined on at most, evenly spaced through the file (the design's memory
    /// grows with them); the others are left out and [`Refinement::poses_left_out`] counts them.
    pub max_poses: usize,
    /// Keep the poses beyond the outlier fence ([`crate::numerics::outlier_rounds`]) in the
    /// refinement (they are still named).
    pub keep_outliers: bool,
}

impl Default for RefineOptions {
    fn default() -> Self {
        RefineOptions {
            noise_rms_3d_mm: 0.19,
            folds: 5,
            max_steps: 10,
            max_poses: crate::measurement::bounded::FIT_MAX_POSES,
            keep_outliers: false,
        }
    }
}

/// Why a refinement failed.
#[derive(Debug, thiserror::Error)]
pub enum RefineError {
    /// Too few free poses.
    #[error(
        "{found} free poses (experiments named `validation`, moved_joint = 0); --refine needs at least {needed}: one per held-out fold (`--refine-folds`), at least 2"
    )]
    TooFewPoses {
        /// Found.
        found: usize,
        /// Needed.
        needed: usize,
    },
    /// The model could not execute a command.
    #[error(
        "the calibrated model cannot execute the command of free pose {pose} ({what}): a command beyond the range its transmissions were fitted on, or in other units; check that pose's cmd_k"
    )]
    Unexecutable {
        /// At which stage.
        what: &'static str,
        /// The pose (its label).
        pose: String,
    },
    /// No direction of the parameters passes the rank rule.
    #[error(
        "the free poses identify no direction of the model better than the axis experiments did (rank 0): nothing to refine"
    )]
    NothingIdentified,
    /// The noise is not positive.
    #[error("the measurement noise must be positive to refine (got {0} mm)")]
    Noise(f64),
    /// Too many poses fail the outlier test.
    #[error("the free poses: {0}: check their target ids, their units and the robot description")]
    TooManyOutliers(TooManyOutliers),
}

impl From<TooManyOutliers> for RefineError {
    fn from(e: TooManyOutliers) -> Self {
        RefineError::TooManyOutliers(e)
    }
}

/// A direction of the parameters the free poses do not identify.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct DroppedDirection {
    /// Its singular value over the per-coordinate noise: the free poses' information along it
    /// relative to the unrefined estimate's is the square of this (kept at >= 1).
    pub singular_value_over_noise: f64,
    /// The parameters that make it up most (weights of the unit direction in unrefined sigmas,
    /// largest first, at most four).
    pub leading: Vec<DirectionWeight>,
}

/// What the refinement did to one parameter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ParameterChange {
    /// Parameter name (`docs/formats.md#calibration-json`).
    pub name: String,
    /// The unit of `change`, `unrefined_sigma` and `refined_sigma`.
    pub unit: ParameterUnit,
    /// Refined minus unrefined value \[unit\].
    pub change: f64,
    /// The unrefined estimate's 1-sigma \[unit\] (null where the calibration reports none).
    pub unrefined_sigma: Option<f64>,
    /// The refined estimate's 1-sigma \[unit\].
    pub refined_sigma: f64,
    /// `change / unrefined_sigma` (null without an unrefined sigma).
    pub change_sigmas: Option<f64>,
}

/// One fold of the held-out check.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FoldCheck {
    /// Fold (0-based): the held-out poses are those at file positions `i` with `i mod folds = fold`.
    pub fold: usize,
    /// Poses refined on.
    pub training_poses: usize,
    /// Poses held out.
    pub heldout_poses: usize,
    /// Directions kept on the training poses.
    pub rank: usize,
    /// RMS distance of the held-out points from the unrefined model \[mm\].
    pub heldout_rms_before_mm: f64,
    /// The same after the refinement on the training poses \[mm\].
    pub heldout_rms_after_mm: f64,
}

/// The refinement's summary (`calibration.json`'s `refinement`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Refinement {
    /// Free poses refined on.
    pub poses: usize,
    /// Free poses of the file left out (beyond [`RefineOptions::max_poses`], evenly spaced
    /// through the file; absent when every pose is used).
    #[serde(default, skip_serializing_if = "crate::json_file::is_zero_count")]
    pub poses_left_out: usize,
    /// Measured points on them.
    pub points: usize,
    /// The noise the rank rule and the covariance use, 3-D RMS of a point \[mm\].
    pub noise_rms_3d_mm: f64,
    /// Parameters refined (the fixed ones not counted).
    pub parameters: usize,
    /// Parameters kept at their calibrated value.
    pub fixed: Vec<String>,
    /// Identified directions (kept).
    pub rank: usize,
    /// The rank rule in words.
    pub rank_rule: String,
    /// The directions dropped, largest singular value first.
    pub dropped: Vec<DroppedDirection>,
    /// Gauss-Newton steps after the linearised solution.
    pub iterations: usize,
    /// Whether the steps converged (else the step limit ended them).
    pub converged: bool,
    /// RMS distance of the points from the unrefined model \[mm\].
    pub rms_before_mm: f64,
    /// The same from the refined model \[mm\].
    pub rms_after_mm: f64,
    /// What noise alone leaves after fitting `rank` directions: `noise * sqrt(1 - rank / (3 points))` \[mm\].
    pub expected_rms_after_mm: f64,
    /// Per parameter: the change and the sigmas.
    pub changes: Vec<ParameterChange>,
    /// The refined covariance of the parameters, in the order of `changes`, in their units.
    pub covariance: Vec<Vec<f64>>,
    /// The k-fold held-out check (linearised at the unrefined model).
    pub folds: Vec<FoldCheck>,
    /// Held-out RMS over every fold before the refinement \[mm\].
    pub heldout_rms_before_mm: f64,
    /// Held-out RMS over every fold after it \[mm\].
    pub heldout_rms_after_mm: f64,
    /// Free poses beyond the outlier fence (Q3 + 3 IQR of the poses' RMS after the
    /// refinement), left out of it unless `calibrate --keep-outliers`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub outliers: Vec<crate::calibration::free_pose::OutlierPose>,
}

/// A refined RMS beyond this many times what noise alone leaves ([`Refinement::implausible`])
/// is no calibration of these poses. An effect the model lacks leaves a few times it: the
/// IRB/L6 simulated with a backlash of 2-3 mrad on every joint and thermal expansion
/// (`simulate --sim analytic --effects`, seed 11), 5.8 times; target ids swapped in every pose,
/// 240 times (`tests/it/refine.rs`).
pub const IMPLAUSIBLE_RMS_OVER_NOISE: f64 = 10.0;

impl Refinement {
    /// Why the refined model is no calibration of these poses (its RMS beyond
    /// [`IMPLAUSIBLE_RMS_OVER_NOISE`] times what noise alone leaves), if it is not.
    pub fn implausible(&self) -> Option<String> {
        let ratio = self.rms_after_mm / self.expected_rms_after_mm;
        (ratio.is_nan() || ratio > IMPLAUSIBLE_RMS_OVER_NOISE).then(|| {
            format!(
                "the refined model misses the free poses by {:.4} mm RMS, {ratio:.0} times the {:.4} mm noise alone leaves (more than {IMPLAUSIBLE_RMS_OVER_NOISE}): the free poses do not fit the robot's model; check their target ids, their units and that they are this robot's (`axiscal validate` shows each pose's error)",
                self.rms_after_mm, self.expected_rms_after_mm
            )
        })
    }
}

/// A refinement: the refined parameters (the caller's layout) and the summary.
#[derive(Clone, Debug)]
pub struct RefinementResult {
    /// Corrections to the calibrated model, in the caller's layout (fixed ones 0).
    pub params: Vec<f64>,
    /// The poses beyond the outlier fence (indices of the caller's poses; RMS in mm), left out
    /// of the refinement unless [`RefineOptions::keep_outliers`].
    pub outliers: Vec<GroupFlag>,
    /// The summary.
    pub summary: Refinement,
}

/// The kept directions of a design `x` in unrefined-sigma units (module docs).
struct Directions {
    /// Kept unit directions (columns).
    kept: DMatrix<f64>,
    /// Dropped unit directions (columns).
    dropped: DMatrix<f64>,
    /// Singular values of the dropped ones.
    dropped_s: Vec<f64>,
}

impl Directions {
    fn new(x: &DMatrix<f64>, sigma_c: f64) -> Self {
        let n = x.ncols();
        let svd = crate::numerics::svd::thin_svd(x.clone(), false);
        let v_t = svd.v_t.unwrap_or_else(|| DMatrix::identity(n, n));
        let s = &svd.singular_values;
        let s_max = s.iter().cloned().fold(0.0, f64::max);
        let mut order: Vec<usize> = (0..s.len()).collect();
        order.sort_by(|&a, &b| s[b].total_cmp(&s[a]));
        let keep = |i: usize| s[i] >= sigma_c && s[i] > NULL_DIRECTION_TOLERANCE * s_max;
        let (k, d): (Vec<usize>, Vec<usize>) = order.iter().partition(|&&i| keep(i));
        // A wide design (fewer rows than parameters) has directions the SVD does not return:
        // the null space's complement of the returned rows.
        let returned = DMatrix::from_fn(n, s.len(), |r, c| v_t[(c, r)]);
        let null = null_complement(&returned, n);
        let col = |i: usize| returned.column(i).into_owned();
        let mut dropped_cols: Vec<DVector<f64>> = d.iter().map(|&i| col(i)).collect();
        let mut dropped_s: Vec<f64> = d.iter().map(|&i| s[i]).collect();
        for c in null.column_iter() {
            dropped_cols.push(c.into_owned());
            dropped_s.push(0.0);
        }
        Directions {
            kept: if k.is_empty() {
                DMatrix::zeros(n, 0)
            } else {
                DMatrix::from_columns(&k.iter().map(|&i| col(i)).collect::<Vec<_>>())
            },
            dropped: if dropped_cols.is_empty() {
                DMatrix::zeros(n, 0)
            } else {
                DMatrix::from_columns(&dropped_cols)
            },
            dropped_s,
        }
    }
}

/// An orthonormal basis of the complement of the orthonormal columns `v` in `R^n`.
fn null_complement(v: &DMatrix<f64>, n: usize) -> DMatrix<f64> {
    if v.ncols() >= n {
        return DMatrix::zeros(n, 0);
    }
    let projector = DMatrix::identity(n, n) - v * v.transpose();
    let eig = projector.symmetric_eigen();
    let cols: Vec<DVector<f64>> = (0..n)
        .filter(|&i| eig.eigenvalues[i] > 0.5)
        .map(|i| eig.eigenvectors.column(i).into_owned())
        .collect();
    if cols.is_empty() {
        DMatrix::zeros(n, 0)
    } else {
        DMatrix::from_columns(&cols)
    }
}

/// The problem in unrefined-sigma units: the free parameters and their scales.
struct Scaled<'a, F> {
    residuals: F,
    layout: &'a [RefitParameter],
    free: Vec<usize>,
    scale: Vec<f64>,
}

impl<F: Fn(&[f64], &[usize]) -> Option<Vec<f64>> + Sync> Scaled<'_, F> {
    /// The caller's parameters of `u` (unrefined sigmas of the free parameters).
    fn embed(&self, u: &[f64]) -> Vec<f64> {
        let mut p = vec![0.0; self.layout.len()];
        for ((&i, s), x) in self.free.iter().zip(&self.scale).zip(u) {
            p[i] = s * x;
        }
        p
    }

    fn at(&self, u: &[f64], poses: &[usize]) -> Option<Vec<f64>> {
        (self.residuals)(&self.embed(u), poses)
    }

    /// The error of a stage `what` that failed at `u`: the first of `poses` the model cannot
    /// execute there, by its label.
    fn unexecutable(&self, what: &'static str, u: &[f64], poses: &[usize], labels: &[String]) -> RefineError {
        let u = if u.len() == self.free.len() {
            u.to_vec()
        } else {
            vec![0.0; self.free.len()]
        };
        let pose = poses.iter().find(|&&i| self.at(&u, &[i]).is_none()).map_or_else(
            || "(none alone: the poses together)".to_string(),
            |&i| labels[i].clone(),
        );
        RefineError::Unexecutable { what, pose }
    }
}

/// 3-D RMS per point \[mm\] of residual rows `r` \[m\] (three per point).
fn rms_mm(r: &[f64]) -> f64 {
    let points = (r.len() / 3).max(1);
    (r.iter().map(|x| x * x).sum::<f64>() / points as f64).sqrt() * 1e3
}

/// Enough free poses for `folds` held-out folds (at least two): a caller checks it before any
/// work, the refinement again.
pub fn enough_free_poses(poses: usize, folds: usize) -> Result<(), RefineError> {
    let needed = folds.max(2);
    if poses < needed {
        return Err(RefineError::TooFewPoses { found: poses, needed });
    }
    Ok(())
}

/// Enough free poses for the folds (at least two) and a positive noise.
fn check_inputs(poses: usize, options: &RefineOptions) -> Result<(), RefineError> {
    enough_free_poses(poses, options.folds)?;
    if options.noise_rms_3d_mm.is_nan() || options.noise_rms_3d_mm <= 0.0 {
        return Err(RefineError::Noise(options.noise_rms_3d_mm));
    }
    Ok(())
}

/// Refines the calibrated model on free poses (module docs).
///
/// `residuals(p, poses)` gives `measured - predicted` \[m\] (three rows per measured target) of
/// the free poses `poses` (indices, in this order) at corrections `p` (layout `layout`, steps
/// of its central differences `steps`); `targets_per_pose` counts each pose's targets and
/// `labels` names each pose in messages;
/// `unrefined_sigma` is each parameter's 1-sigma before (internal units; `None` where the
/// calibration reports none).
pub fn refine_free_poses<F>(
    residuals: F,
    targets_per_pose: &[usize],
    labels: &[String],
    layout: &[RefitParameter],
    unrefined_sigma: &[Option<f64>],
    steps: &[f64],
    options: &RefineOptions,
) -> Result<RefinementResult, RefineError>
where
    F: Fn(&[f64], &[usize]) -> Option<Vec<f64>> + Sync,
{
    check_inputs(targets_per_pose.len(), options)?;
    let free: Vec<usize> = (0..layout.len()).filter(|&i| !layout[i].fixed()).collect();
    let scale: Vec<f64> = free
        .iter()
        .map(|&i| unrefined_sigma[i].unwrap_or_else(|| layout[i].unit().fallback_scale()))
        .collect();
    let steps_u: Vec<f64> = free.iter().zip(&scale).map(|(&i, s)| steps[i] / s).collect();
    let problem = Scaled {
        residuals,
        layout,
        free,
        scale,
    };
    let sigma_c = options.noise_rms_3d_mm * 1e-3 / 3f64.sqrt();
    let all: Vec<usize> = (0..targets_per_pose.len()).collect();
    let zeros = vec![0.0; problem.free.len()];
    let unexecutable = |what, u: &[f64]| problem.unexecutable(what, u, &all, labels);
    let r0 = DVector::from_vec(
        problem
            .at(&zeros, &all)
            .ok_or_else(|| unexecutable("residuals", &zeros))?,
    );
    let x_u =
        sensitivity(|u| problem.at(u, &all), &zeros, &steps_u).ok_or_else(|| unexecutable("sensitivity", &zeros))?;
    let rows = PoseRows::new(targets_per_pose);
    let linearised = Linearised {
        problem: &problem,
        r0: &r0,
        x_u: &x_u,
        rows: &rows,
        sigma_c,
        max_steps: options.max_steps,
        labels,
    };
    let first = linearised.first_fit(&all, options.keep_outliers)?;
    let peeled = fit_without_outliers(
        &all,
        options.keep_outliers,
        first,
        |_, kept| linearised.refine_on(kept),
        |fit| {
            let r = problem
                .at(&fit.u, &all)
                .ok_or_else(|| unexecutable("outlier test", &fit.u))?;
            Ok(rows.pose_rms_mm(&r))
        },
    )?;
    let summary = summary_of(
        &problem,
        &peeled.fitted,
        targets_per_pose,
        unrefined_sigma,
        sigma_c,
        options,
    );
    Ok(RefinementResult {
        params: problem.embed(&peeled.fitted.u),
        outliers: peeled.flags,
        summary,
    })
}

/// The summary of the refinement `fit` (module docs): its sigmas, its held-out check.
fn summary_of<F: Fn(&[f64], &[usize]) -> Option<Vec<f64>> + Sync>(
    problem: &Scaled<'_, F>,
    fit: &OnPoses,
    targets_per_pose: &[usize],
    unrefined_sigma: &[Option<f64>],
    sigma_c: f64,
    options: &RefineOptions,
) -> Refinement {
    let OnPoses {
        which,
        r0,
        x_u,
        dirs,
        refined,
        u,
    } = fit;
    let targets: Vec<usize> = which.iter().map(|&i| targets_per_pose[i]).collect();
    let rank = dirs.kept.ncols();
    let cov_u = &dirs.dropped * dirs.dropped.transpose()
        + &dirs.kept * (refined.fit.normal_inverse.clone() * sigma_c.powi(2)) * dirs.kept.transpose();
    let folds = k_fold(r0, x_u, &targets, options.folds, sigma_c);
    let summary = summarise(problem, u, &cov_u, unrefined_sigma, dirs, options);
    let points: usize = targets.iter().sum();
    let pooled = |f: &dyn Fn(&FoldCheck) -> f64| {
        let ssr: f64 = folds
            .iter()
            .map(|c| f(&c.check).powi(2) * (c.heldout_points as f64))
            .sum();
        (ssr / points as f64).sqrt()
    };
    Refinement {
        poses: which.len(),
        poses_left_out: 0,
        points,
        noise_rms_3d_mm: options.noise_rms_3d_mm,
        parameters: problem.free.len(),
        fixed: problem
            .layout
            .iter()
            .filter(|p| p.fixed())
            .map(RefitParameter::name)
            .collect(),
        rank,
        rank_rule: RANK_RULE.into(),
        iterations: refined.iterations,
        converged: refined.stop != Stop::MaxIterations,
        rms_before_mm: rms_mm(r0.as_slice()),
        rms_after_mm: rms_mm(refined.residual.as_slice()),
        expected_rms_after_mm: options.noise_rms_3d_mm * (1.0 - rank as f64 / (3 * points) as f64).max(0.0).sqrt(),
        heldout_rms_before_mm: pooled(&|c| c.heldout_rms_before_mm),
        heldout_rms_after_mm: pooled(&|c| c.heldout_rms_after_mm),
        folds: folds.into_iter().map(|c| c.check).collect(),
        ..summary
    }
}

/// Where each pose's residual rows lie (three per target, poses in order).
struct PoseRows {
    /// First row of each pose.
    starts: Vec<usize>,
    /// Rows of each pose.
    counts: Vec<usize>,
}

impl PoseRows {
    fn new(targets_per_pose: &[usize]) -> Self {
        let counts: Vec<usize> = targets_per_pose.iter().map(|t| 3 * t).collect();
        let starts = counts
            .iter()
            .scan(0, |at, c| {
                let start = *at;
                *at += c;
                Some(start)
            })
            .collect();
        PoseRows { starts, counts }
    }

    /// The rows of the poses `which`, in their order.
    fn of(&self, which: &[usize]) -> Vec<usize> {
        which
            .iter()
            .flat_map(|&i| self.starts[i]..self.starts[i] + self.counts[i])
            .collect()
    }

    /// Each pose's 3-D RMS per point \[mm\] of residual rows `r` of every pose \[m\].
    fn pose_rms_mm(&self, r: &[f64]) -> Vec<f64> {
        self.starts
            .iter()
            .zip(&self.counts)
            .map(|(&s, &c)| rms_mm(&r[s..s + c]))
            .collect()
    }
}

/// The problem linearised at the unrefined model on every pose: what a refinement on some of
/// them starts from.
struct Linearised<'a, F> {
    problem: &'a Scaled<'a, F>,
    /// Residuals at the unrefined model, every pose's rows \[m\].
    r0: &'a DVector<f64>,
    /// Their sensitivity to the parameters in unrefined sigmas.
    x_u: &'a DMatrix<f64>,
    rows: &'a PoseRows,
    /// Per-coordinate noise \[m\].
    sigma_c: f64,
    max_steps: usize,
    /// Each pose's label.
    labels: &'a [String],
}

/// The refinement on some poses.
struct OnPoses {
    /// The poses.
    which: Vec<usize>,
    /// Their residual rows at the unrefined model.
    r0: DVector<f64>,
    /// Their sensitivity.
    x_u: DMatrix<f64>,
    /// The directions kept and dropped on them.
    dirs: Directions,
    /// The refined fit.
    refined: super::Refined,
    /// The refined parameters in unrefined sigmas.
    u: Vec<f64>,
}

impl<F: Fn(&[f64], &[usize]) -> Option<Vec<f64>> + Sync> Linearised<'_, F> {
    /// The refinement on every pose of `all`; when the model cannot execute a pose on the
    /// way (a gross error pulls the parameters far: a command in other units), on the poses
    /// within the outlier fence of the unrefined model's residuals (unless `keep_outliers`).
    fn first_fit(&self, all: &[usize], keep_outliers: bool) -> Result<(OnPoses, Vec<usize>), RefineError> {
        match self.refine_on(all) {
            Ok(fit) => Ok((fit, all.to_vec())),
            Err(e @ RefineError::Unexecutable { .. }) if !keep_outliers => {
                let rms = self.rows.pose_rms_mm(self.r0.as_slice());
                let fence = crate::numerics::stats::far_out_fence(&rms);
                let within: Vec<usize> = all.iter().copied().filter(|&i| rms[i] <= fence).collect();
                if within.len() == all.len() {
                    return Err(e);
                }
                Ok((self.refine_on(&within)?, within))
            }
            Err(e) => Err(e),
        }
    }

    /// The rank rule on the poses `which`, the linearised solution and its Gauss-Newton steps.
    fn refine_on(&self, which: &[usize]) -> Result<OnPoses, RefineError> {
        let rows = self.rows.of(which);
        let (r0, x_u) = (self.r0.select_rows(&rows), self.x_u.select_rows(&rows));
        let dirs = Directions::new(&x_u, self.sigma_c);
        let rank = dirs.kept.ncols();
        if rank == 0 {
            return Err(RefineError::NothingIdentified);
        }
        let x_z = &x_u * &dirs.kept;
        let linear = LinearFit::new(&x_z, &DMatrix::zeros(0, rank));
        let kept = &dirs.kept;
        let u_of = |z: &[f64]| (kept * DVector::from_column_slice(z)).as_slice().to_vec();
        // Converged when a step would move the predicted points by less than 1 % of one noise
        // sigma in all (a fraction of the refined parameters' own sigma): not worth a Jacobian.
        let negligible = |delta: &DVector<f64>| (&x_z * delta).norm() < 1e-2 * self.sigma_c;
        let how = GaussNewtonSteps {
            fit: "refinement on free poses",
            max_steps: self.max_steps,
            truncate_below: NULL_DIRECTION_TOLERANCE,
            small_step: Some(&negligible),
            fit_at_end: true,
        };
        // Where the model could not execute a pose (the first such parameters).
        let failed_at = std::sync::Mutex::new(None);
        let at = |z: &[f64]| {
            let u = u_of(z);
            let r = self.problem.at(&u, which);
            if r.is_none()
                && let Ok(mut f) = failed_at.lock()
            {
                f.get_or_insert(u);
            }
            r
        };
        // A z-step of 1e-2 unrefined sigmas: far above rounding, far below curvature.
        let refined = refine_from_linear(at, &vec![1e-2; rank], &linear, &r0, r0.len(), how).ok_or_else(|| {
            let u = failed_at.lock().ok().and_then(|mut f| f.take()).unwrap_or_default();
            self.problem.unexecutable("refinement", &u, which, self.labels)
        })?;
        let u = u_of(refined.params.as_slice());
        Ok(OnPoses {
            which: which.to_vec(),
            r0,
            x_u,
            dirs,
            refined,
            u,
        })
    }
}

/// The rank rule as the summary states it.
const RANK_RULE: &str = "a direction of the parameters in units of their unrefined 1-sigma is kept when its singular value is at least the per-coordinate noise (the free poses know it at least as well as the axis experiments did) and above 1e-7 of the largest";

/// A fold's check and its point count (for pooling).
struct Fold {
    check: FoldCheck,
    heldout_points: usize,
}

/// The k-fold held-out check, linearised at the unrefined model (the refinement's first step):
/// per fold, the directions kept on its training poses, their fit, and the held-out rows'
/// residual before and after. The folds are independent: they run in parallel on the current
/// rayon pool (each the same arithmetic whatever the thread count).
fn k_fold(r0: &DVector<f64>, x_u: &DMatrix<f64>, targets: &[usize], folds: usize, sigma_c: f64) -> Vec<Fold> {
    let mut starts = Vec::with_capacity(targets.len());
    let mut at = 0;
    for t in targets {
        starts.push(at);
        at += 3 * t;
    }
    let rows_of = |held: bool, f: usize| -> Vec<usize> {
        (0..targets.len())
            .filter(|i| (i % folds == f) == held)
            .flat_map(|i| starts[i]..starts[i] + 3 * targets[i])
            .collect()
    };
    (0..folds)
        .into_par_iter()
        .map(|f| {
            let (train, held) = (rows_of(false, f), rows_of(true, f));
            let x_t = x_u.select_rows(&train);
            let dirs = Directions::new(&x_t, sigma_c);
            let fit = LinearFit::new(&(&x_t * &dirs.kept), &(x_u.select_rows(&held) * &dirs.kept));
            let (r_t, r_h) = (r0.select_rows(&train), r0.select_rows(&held));
            let after = fit.heldout(
                &DMatrix::from_column_slice(r_t.len(), 1, r_t.as_slice()),
                &DMatrix::from_column_slice(r_h.len(), 1, r_h.as_slice()),
            );
            let heldout_poses = (0..targets.len()).filter(|i| i % folds == f).count();
            Fold {
                check: FoldCheck {
                    fold: f,
                    training_poses: targets.len() - heldout_poses,
                    heldout_poses,
                    rank: dirs.kept.ncols(),
                    heldout_rms_before_mm: rms_mm(r_h.as_slice()),
                    heldout_rms_after_mm: rms_mm(after.as_slice()),
                },
                heldout_points: held.len() / 3,
            }
        })
        .collect()
}

/// The per-parameter changes, the covariance and the dropped directions (the rest of the
/// summary is filled by the caller).
fn summarise<F>(
    problem: &Scaled<'_, F>,
    u: &[f64],
    cov_u: &DMatrix<f64>,
    unrefined_sigma: &[Option<f64>],
    dirs: &Directions,
    options: &RefineOptions,
) -> Refinement {
    let n = problem.free.len();
    let per_unit: Vec<f64> = problem
        .free
        .iter()
        .zip(&problem.scale)
        .map(|(&i, s)| s * problem.layout[i].unit().per_si())
        .collect();
    let names: Vec<String> = problem.free.iter().map(|&i| problem.layout[i].name()).collect();
    let covariance: Vec<Vec<f64>> = (0..n)
        .map(|a| (0..n).map(|b| cov_u[(a, b)] * per_unit[a] * per_unit[b]).collect())
        .collect();
    let changes = (0..n)
        .map(|a| {
            let i = problem.free[a];
            let unit = problem.layout[i].unit();
            let unrefined = unrefined_sigma[i].map(|s| s * unit.per_si());
            ParameterChange {
                name: names[a].clone(),
                unit,
                change: u[a] * per_unit[a],
                unrefined_sigma: unrefined,
                refined_sigma: covariance[a][a].max(0.0).sqrt(),
                change_sigmas: unrefined.map(|_| u[a]),
            }
        })
        .collect();
    let sigma_c = options.noise_rms_3d_mm * 1e-3 / 3f64.sqrt();
    let dropped = dirs
        .dropped
        .column_iter()
        .zip(&dirs.dropped_s)
        .map(|(v, s)| {
            let mut w: Vec<(usize, f64)> = v.iter().copied().enumerate().collect();
            w.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
            DroppedDirection {
                singular_value_over_noise: s / sigma_c,
                leading: w
                    .iter()
                    .take(4)
                    .map(|&(i, weight)| DirectionWeight {
                        name: names[i].clone(),
                        weight,
                    })
                    .collect(),
            }
        })
        .collect();
    Refinement {
        poses: 0,
        poses_left_out: 0,
        points: 0,
        noise_rms_3d_mm: options.noise_rms_3d_mm,
        parameters: n,
        fixed: Vec::new(),
        rank: 0,
        rank_rule: String::new(),
        dropped,
        iterations: 0,
        converged: true,
        rms_before_mm: 0.0,
        rms_after_mm: 0.0,
        expected_rms_after_mm: 0.0,
        changes,
        covariance,
        folds: Vec::new(),
        heldout_rms_before_mm: 0.0,
        heldout_rms_after_mm: 0.0,
        outliers: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use rand::{SeedableRng, rngs::ChaCha12Rng};
    use rand_distr::{Distribution, StandardNormal};

    const SIGMA_C_M: f64 = 1e-4;

    fn labels(n: usize) -> Vec<String> {
        (0..n).map(|i| format!("pose {i}")).collect()
    }

    /// Three rows per pose at `t`: `s + p2 t`, `p2 t^2 + p2^2 / 2`, `1e-9 p3 t` with `s = p0 +
    /// p1` (p0, p1 redundant; p3 seen far below the noise).
    fn model(p: &[f64], t: f64) -> [f64; 3] {
        [
            p[0] + p[1] + p[2] * t,
            p[2] * t * t + 0.5 * p[2] * p[2],
            1e-9 * p[3] * t,
        ]
    }

    /// Known parameters recovered from noisy data: the redundancy and the unseen parameter
    /// dropped (rank 2), the identified combination within 4 reported sigmas, and the reported
    /// covariance equal to `sigma^2 (J^T J)^-1` of the analytic Jacobian of the identified
    /// combination (a second path: the central differences the refinement uses against the
    /// derivatives by hand).
    #[test]
    fn recovers_the_identifiable_combination_with_its_covariance() {
        let truth = [2e-3, 0.0, 1e-3, 0.0];
        let ts: Vec<f64> = (0..40).map(|i| -1.0 + i as f64 / 20.0).collect();
        let mut rng = ChaCha12Rng::seed_from_u64(7);
        let measured: Vec<[f64; 3]> = ts
            .iter()
            .map(|&t| {
                let f = model(&truth, t);
                f.map(|x| x + SIGMA_C_M * Distribution::<f64>::sample(&StandardNormal, &mut rng))
            })
            .collect();
        let residuals = |p: &[f64], which: &[usize]| -> Option<Vec<f64>> {
            Some(
                which
                    .iter()
                    .flat_map(|&i| {
                        let (f, m) = (model(p, ts[i]), measured[i]);
                        (0..3).map(move |k| m[k] - f[k])
                    })
                    .collect(),
            )
        };
        let layout: Vec<RefitParameter> = (1..=4).map(RefitParameter::RowA).collect();
        let options = RefineOptions {
            noise_rms_3d_mm: SIGMA_C_M * 3f64.sqrt() * 1e3,
            ..RefineOptions::default()
        };
        let out = refine_free_poses(
            residuals,
            &[1; 40],
            &labels(40),
            &layout,
            &[Some(1e-3); 4],
            &[1e-6; 4],
            &options,
        )
        .unwrap();
        let r = &out.summary;
        assert_eq!(r.rank, 2);
        assert_eq!(r.dropped.len(), 2);
        let c = &r.covariance;
        let var_s = c[0][0] + c[1][1] + 2.0 * c[0][1];
        // Analytic Jacobian of (s, p2) at the solution, in mm.
        let p2 = out.params[2];
        let mut jtj = nalgebra::Matrix2::zeros();
        for &t in &ts {
            for row in [[1.0, t], [0.0, t * t + p2]] {
                let v = nalgebra::Vector2::from(row);
                jtj += v * v.transpose();
            }
        }
        let cov = jtj.try_inverse().unwrap() * (SIGMA_C_M * 1e3).powi(2);
        assert_relative_eq!(var_s, cov[(0, 0)], max_relative = 1e-6);
        assert_relative_eq!(c[2][2], cov[(1, 1)], max_relative = 1e-6);
        let s = (out.params[0] + out.params[1]) * 1e3;
        assert!((s - 2.0).abs() < 4.0 * var_s.sqrt(), "{s} +- {}", var_s.sqrt());
        assert!((p2 * 1e3 - 1.0).abs() < 4.0 * c[2][2].sqrt());
        // p3 stays where it was, its sigma the unrefined one.
        assert!(out.params[3].abs() < 1e-12, "{}", out.params[3]);
        assert_relative_eq!(c[3][3].sqrt(), 1.0, max_relative = 1e-9);
        // Changes in sigmas are changes over the unrefined sigma.
        assert_relative_eq!(r.changes[2].change_sigmas.unwrap(), p2 / 1e-3, max_relative = 1e-12);
        // The k-fold check: every pose held out once, the refined model better than none.
        assert_eq!(r.folds.iter().map(|f| f.heldout_poses).sum::<usize>(), 40);
        assert!(r.heldout_rms_after_mm < r.heldout_rms_before_mm);
    }

    /// Central differences of a nonlinear residual against its derivatives by hand.
    #[test]
    fn sensitivity_matches_the_analytic_jacobian() {
        let f = |p: &[f64]| Some(vec![p[0].sin() * p[1], (p[0] * p[1]).exp()]);
        let p = [0.3, -0.7];
        let x = sensitivity(f, &p, &[1e-6, 1e-6]).unwrap();
        let e = (p[0] * p[1]).exp();
        let analytic = DMatrix::from_row_slice(2, 2, &[-p[0].cos() * p[1], -p[0].sin(), -p[1] * e, -p[0] * e]);
        // Central differences: truncation h^2 f''' / 6 ~ 1e-13, rounding eps / h ~ 1e-10.
        assert_relative_eq!(x, analytic, epsilon = 1e-8);
    }

    #[test]
    fn too_few_poses_and_no_noise_are_errors() {
        let layout = [RefitParameter::RowA(1)];
        let f = |_: &[f64], w: &[usize]| Some(vec![0.0; 3 * w.len()]);
        let e = refine_free_poses(
            f,
            &[1; 3],
            &labels(3),
            &layout,
            &[None],
            &[1e-6],
            &RefineOptions::default(),
        );
        assert!(matches!(e, Err(RefineError::TooFewPoses { found: 3, needed: 5 })));
        let zero = RefineOptions {
            noise_rms_3d_mm: 0.0,
            ..RefineOptions::default()
        };
        let e = refine_free_poses(f, &[1; 8], &labels(8), &layout, &[None], &[1e-6], &zero);
        assert!(matches!(e, Err(RefineError::Noise(_))));
    }
}
