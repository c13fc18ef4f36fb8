//! The least-squares fit of the free-pose model and its outlier test.

use super::FreePoseError;
use super::model::FreePoseModel;
use super::poses::FreePoses;
use crate::calibration::refine::RefitParameter;
use crate::numerics::lsq::{LmOptions, LsqError, inverse_normal, levenberg_marquardt};
use crate::robot::Controller;
use nalgebra::{DMatrix, DVector};

/// Levenberg-Marquardt steps at most.
const MAX_ITERATIONS: usize = 200;

/// The run ends where the remaining Gauss-Newton step would lower the cost by at most this
/// fraction of the starting cost per measured coordinate (module docs of
/// [`crate::numerics::lsq::LmOptions::negligible_decrease`]; with the noise at most the start's
/// RMS, a step below 1e-5 of a standard deviation).
const NEGLIGIBLE_DECREASE: f64 = 1e-8;

/// What every fit of one calibration shares.
pub(super) struct Problem<'a> {
    /// The controller (nominal couplings).
    pub controller: &'a Controller,
    /// The measured poses.
    pub poses: &'a FreePoses,
    /// The parameter layout.
    pub layout: &'a [RefitParameter],
    /// The description's tool targets (by id) in the nominal tool frame \[m\].
    pub description_targets_m: Vec<nalgebra::Point3<f64>>,
}

/// A converged fit.
#[derive(Clone, Debug)]
pub(super) struct Fitted {
    /// The fitted model.
    pub model: FreePoseModel,
    /// Residual `measured - predicted` at the fit \[m\], 3 rows a point of the fitted poses.
    pub residual: DVector<f64>,
    /// `d residual / d parameter` of the fitted columns at the fit.
    pub jacobian: DMatrix<f64>,
    /// Levenberg-Marquardt steps taken.
    pub iterations: usize,
}

impl Fitted {
    /// RMS 3-D distance of the points \[m\].
    pub fn rms_m(&self) -> f64 {
        (self.residual.norm_squared() / (self.residual.len() / 3).max(1) as f64).sqrt()
    }

    /// Degrees of freedom `3 points - parameters`.
    pub fn dof(&self) -> usize {
        self.residual.len().saturating_sub(self.jacobian.ncols())
    }

    /// Per-coordinate variance from the residuals, `rss / dof` \[m^2\] (`None` without dof).
    pub fn variance(&self) -> Option<f64> {
        (self.dof() > 0).then(|| self.residual.norm_squared() / self.dof() as f64)
    }

    /// The parameters' covariance `s^2 (J^T J)^-1` with `s^2` the per-coordinate variance.
    pub fn covariance(&self, variance: f64) -> Result<DMatrix<f64>, FreePoseError> {
        Ok(inverse_normal(&self.jacobian, "free-pose calibration")? * variance)
    }
}

/// Fits the parameters `columns` of `start` to the poses `which` by Levenberg-Marquardt
/// (the program's one least-squares loop) with the analytic Jacobian.
pub(super) fn fit(
    problem: &Problem<'_>,
    start: &FreePoseModel,
    which: &[usize],
    columns: &[usize],
) -> Result<Fitted, FreePoseError> {
    let eval = |m: &FreePoseModel| -> Result<(DVector<f64>, DMatrix<f64>), FreePoseError> {
        m.residuals_and_jacobian(problem.controller, problem.poses, which, problem.layout, columns)
            .map_err(|u| u.error(problem.poses))
    };
    let first = eval(start)?;
    let per_coordinate = first.0.norm_squared() / first.0.len().max(1) as f64;
    let options = LmOptions {
        negligible_decrease: Some(NEGLIGIBLE_DECREASE * per_coordinate),
        ..LmOptions::marquardt("free-pose calibration", MAX_ITERATIONS)
    };
    let apply = |m: &FreePoseModel, d: &DVector<f64>| Ok::<_, FreePoseError>(m.moved(problem.layout, columns, d));
    let out = levenberg_marquardt(start.clone(), &options, eval, apply)?.converged("free-pose calibration", None)?;
    Ok(Fitted {
        model: out.state,
        residual: out.residual,
        jacobian: out.jacobian,
        iterations: out.iterations,
    })
}

/// A pose whose points the fit does not explain.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Flag {
    /// The pose.
    pub pose: usize,
    /// RMS 3-D distance of its points \[m\].
    pub rms_m: f64,
    /// The fence it exceeds \[m\].
    pub fence_m: f64,
}

/// The fence of the poses' RMS residuals: Tukey's far-out fence
/// ([`crate::numerics::stats::far_out_fence`]) of the per-pose RMS of the fit's residual
/// `residual` over the poses `which` \[m\]. A gross error (a corrupted cell, swapped target
/// ids, a pose in other units) lies far beyond it.
pub(super) fn outlier_fence(residual: &DVector<f64>, poses: &FreePoses, which: &[usize]) -> f64 {
    crate::numerics::stats::far_out_fence(&pose_rms(residual, poses, which))
}

/// The RMS 3-D distance of each pose's points \[m\].
pub(super) fn pose_rms(residual: &DVector<f64>, poses: &FreePoses, which: &[usize]) -> Vec<f64> {
    let mut row = 0;
    which
        .iter()
        .map(|&i| {
            let coordinates = 3 * poses.poses[i].points_m.len();
            let r = residual.rows(row, coordinates);
            row += coordinates;
            (r.norm_squared() / (coordinates / 3) as f64).sqrt()
        })
        .collect()
}

/// The poses of `which` (whose points' residuals `residual` holds in order) beyond `fence_m`.
pub(super) fn flag_outliers(residual: &DVector<f64>, poses: &FreePoses, which: &[usize], fence_m: f64) -> Vec<Flag> {
    pose_rms(residual, poses, which)
        .into_iter()
        .zip(which)
        .filter(|(rms, _)| *rms > fence_m)
        .map(|(rms_m, &pose)| Flag { pose, rms_m, fence_m })
        .collect()
}

impl From<LsqError> for FreePoseError {
    fn from(e: LsqError) -> Self {
        FreePoseError::Fit(e)
    }
}
