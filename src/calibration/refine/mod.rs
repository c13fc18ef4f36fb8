//! Refinement of the calibrated independent-axis model on free poses (validation poses measured
//! anywhere in the workspace): the one implementation shared by `calibrate --refine`
//! ([`refine_free_poses`]) and the diagnosis's baseline refit
//! ([`crate::diagnosis`]).
//!
//! The model is a residual function of small corrections `p` to the calibrated parameters
//! (rows, zero offsets, transmission harmonics, coupling coefficients, base and tool frames;
//! its layout is the caller's, [`RefitParameter`] names each). Both users:
//! 1. linearise it at the calibrated model by central differences ([`sensitivity`]);
//! 2. solve the linearised problem rank-revealingly ([`LinearFit`], a truncated SVD);
//! 3. refine from that solution by Gauss-Newton steps re-linearised at the current parameters
//!    ([`refine_from_linear`]; the program's one least-squares loop,
//!    [`levenberg_marquardt_from`], monotone, the same truncation).
//!
//! Pure maths: no files, no CLI, no simulator.

mod free_poses;
mod linear;
mod prior;
mod report;

pub use free_poses::{
    DroppedDirection, FoldCheck, ParameterChange, ParameterUnit, RefineError, RefineOptions, Refinement,
    RefinementResult, RefitParameter, refine_free_poses,
};
pub use linear::{Block, LinearFit, NULL_DIRECTION_TOLERANCE, sensitivity};
pub use prior::unrefined_sigma;
pub use report::markdown;

use crate::numerics::lsq::{Damping, LmOptions, LsqError, Stop, VectorTest, levenberg_marquardt_from};
use nalgebra::{DMatrix, DVector};

/// A fit refined beyond its linearisation ([`refine_from_linear`]).
#[derive(Clone, Debug)]
pub struct Refined {
    /// Fitted parameters.
    pub params: DVector<f64>,
    /// The fit linearised at the parameters (training rows, then the held-out ones): its
    /// `normal_inverse` times the per-coordinate noise variance is their covariance.
    pub fit: LinearFit,
    /// Residuals `measured - predicted` at the parameters \[m\] (every row, training first).
    pub residual: DVector<f64>,
    /// Gauss-Newton steps taken after the linearised solution.
    pub iterations: usize,
    /// Why the loop stopped.
    pub stop: Stop,
}

/// How [`refine_from_linear`] iterates.
#[derive(Clone, Copy)]
pub struct GaussNewtonSteps<'a> {
    /// Names the fit in errors.
    pub fit: &'static str,
    /// Gauss-Newton steps at most after the linearised solution.
    pub max_steps: usize,
    /// Relative singular-value threshold of each step's rank-revealing solve.
    pub truncate_below: f64,
    /// A step for which this holds is negligible: not taken, the refinement has converged.
    pub small_step: Option<&'a VectorTest<'a>>,
}

/// The model could not execute a command at some parameters.
#[derive(Debug)]
struct Unexecutable;

impl From<LsqError> for Unexecutable {
    fn from(_: LsqError) -> Self {
        Unexecutable
    }
}

/// Refines the linearised solution of `residuals` (`measured - predicted` \[m\] of every row at
/// parameters `p`, the first `train_rows` fitted, the rest carried along unfitted): starts at
/// `linear.params(r0_train)` (the Gauss-Newton step from `p = 0`, Nocedal & Wright,
/// *Numerical Optimization*, 2nd ed., eq. 10.24, on the kept directions of `linear`) and takes
/// monotone Gauss-Newton steps re-linearised by central differences of step `steps` at the
/// current parameters. `None` when the model cannot execute a command at some parameters.
pub fn refine_from_linear<F>(
    residuals: F,
    steps: &[f64],
    linear: &LinearFit,
    r0_train: &DVector<f64>,
    train_rows: usize,
    how: GaussNewtonSteps<'_>,
) -> Option<Refined>
where
    F: Fn(&[f64]) -> Option<Vec<f64>> + Sync,
{
    refine_from_linear_with(
        &residuals,
        |p| sensitivity(&residuals, p, steps),
        linear,
        r0_train,
        train_rows,
        how,
    )
}

/// [`refine_from_linear`] with the re-linearisation `linearise` (the sensitivity
/// `X = -d residual / d p` at `p`, `None` when the model cannot execute a command there) given
/// by the caller: the central differences of [`sensitivity`] computed by a caller that knows
/// which of its work a column can reuse (the diagnosis's predictor keeps the joint values).
pub fn refine_from_linear_with<F, G>(
    residuals: F,
    linearise: G,
    linear: &LinearFit,
    r0_train: &DVector<f64>,
    train_rows: usize,
    how: GaussNewtonSteps<'_>,
) -> Option<Refined>
where
    F: Fn(&[f64]) -> Option<Vec<f64>>,
    G: Fn(&[f64]) -> Option<DMatrix<f64>>,
{
    // The residual is `measured - predicted`: its Jacobian is minus the sensitivity.
    let eval = |p: &DVector<f64>| -> Result<(DVector<f64>, DMatrix<f64>), Unexecutable> {
        let r = residuals(p.as_slice()).ok_or(Unexecutable)?;
        let x = linearise(p.as_slice()).ok_or(Unexecutable)?;
        Ok((DVector::from_vec(r), -x))
    };
    let p1 = linear.params(r0_train);
    let at_p1 = eval(&p1).ok()?;
    let options = LmOptions {
        damping: Damping::GaussNewton {
            truncate_below: Some(how.truncate_below),
            monotone: true,
        },
        fitted_rows: Some(train_rows),
        small_step: how.small_step,
        ..LmOptions::marquardt(how.fit, how.max_steps)
    };
    let outcome = levenberg_marquardt_from(p1, at_p1, &options, eval, |p, d| Ok(p + d)).ok()?;
    let n = outcome.jacobian.nrows();
    let x = -outcome.jacobian;
    let (t, h) = (
        x.rows(0, train_rows).into_owned(),
        x.rows(train_rows, n - train_rows).into_owned(),
    );
    Some(Refined {
        params: outcome.state,
        fit: LinearFit::new(&t, &h),
        residual: outcome.residual,
        iterations: outcome.iterations,
        stop: outcome.stop,
    })
}
