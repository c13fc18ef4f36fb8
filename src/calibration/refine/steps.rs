//! Gauss-Newton steps from a linearised fit ([`refine_from_linear`]): the program's one
//! least-squares loop ([`levenberg_marquardt_from`]) re-linearised only where a step is taken,
//! with the linear fit's truncation.

use super::linear::{LinearFit, sensitivity};
use crate::numerics::lsq::{Damping, LmOptions, LsqError, Stop, VectorTest, levenberg_marquardt_from};
use nalgebra::{DMatrix, DVector};

/// A fit refined beyond its linearisation ([`refine_from_linear`]).
#[derive(Clone, Debug)]
pub struct Refined {
    /// Fitted parameters.
    pub params: DVector<f64>,
    /// The fit linearised at the parameters (training rows, then the held-out ones): its
    /// `normal_inverse` times the per-coordinate noise variance is their covariance
    /// ([`GaussNewtonSteps::fit_at_end`]; without it, linearised before the last step).
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
    /// Linearise at the final parameters for [`Refined::fit`]; without, the fit is the last
    /// linearisation made (before the last step), for a caller that needs the residuals only.
    pub fit_at_end: bool,
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
    let p1 = linear.params(r0_train);
    let r1 = DVector::from_vec(residuals(p1.as_slice())?);
    let x1 = linearise(p1.as_slice())?;
    // One Gauss-Newton step of the program's least-squares loop at a time (the loop keeps no
    // state between Gauss-Newton steps: the same steps as one call of `max_steps`), the
    // residual alone at its trial point: the linearisation (2 evaluations a parameter) is made
    // only where a step was taken and another step or the final fit needs it, never at a
    // rejected trial point, nor at the last point without `how.fit_at_end`.
    let one_step = LmOptions {
        damping: Damping::GaussNewton {
            truncate_below: Some(how.truncate_below),
            monotone: true,
        },
        fitted_rows: Some(train_rows),
        small_step: how.small_step,
        ..LmOptions::marquardt(how.fit, 1)
    };
    let trial = |p: &DVector<f64>| -> Result<(DVector<f64>, DMatrix<f64>), Unexecutable> {
        let r = residuals(p.as_slice()).ok_or(Unexecutable)?;
        Ok((DVector::from_vec(r), DMatrix::zeros(0, 0)))
    };
    let (mut p, mut r, mut x) = (p1, r1, x1);
    let (mut iterations, mut stop) = (0, Stop::MaxIterations);
    while iterations < how.max_steps {
        iterations += 1;
        // The residual is `measured - predicted`: its Jacobian is minus the sensitivity.
        let out = levenberg_marquardt_from(p.clone(), (r.clone(), -&x), &one_step, trial, |p, d| Ok(p + d)).ok()?;
        if !matches!(out.stop, Stop::MaxIterations | Stop::CostStalled) {
            stop = out.stop;
            break;
        }
        (p, r) = (out.state, out.residual);
        let last = out.stop == Stop::CostStalled || iterations == how.max_steps;
        if !last || how.fit_at_end {
            x = linearise(p.as_slice())?;
        }
        if out.stop == Stop::CostStalled {
            stop = Stop::CostStalled;
            break;
        }
    }
    let n = x.nrows();
    let (t, h) = (
        x.rows(0, train_rows).into_owned(),
        x.rows(train_rows, n - train_rows).into_owned(),
    );
    Some(Refined {
        params: p,
        fit: LinearFit::new(&t, &h),
        residual: r,
        iterations,
        stop,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::refine::NULL_DIRECTION_TOLERANCE;

    /// The refinement takes the steps of one call of the program's least-squares loop over
    /// every step with a linearisation at every trial point (a second path: the loop as the
    /// refinement called it before it linearised only where a step was taken), bit for bit:
    /// parameters, residuals, iterations, why it stopped and the final fit, for `y = atan(a +
    /// b x)` started near and far (the far starts overshoot: rejected steps), 0 to 4 steps.
    #[test]
    fn the_refinement_takes_the_loops_steps_linearising_only_where_needed() {
        let xs: Vec<f64> = (0..14).map(|i| -1.0 + i as f64 / 6.0).collect();
        let train_rows = 8;
        let mut stops = Vec::new();
        for (a, b, offset) in [(0.3, 0.8, 0.0), (1.2, 2.5, 0.4), (9.0, -3.0, 30.0), (0.1, 14.0, -5.0)] {
            let y: Vec<f64> = xs.iter().map(|x| f64::atan(a + b * x)).collect();
            let residuals = |p: &[f64]| -> Option<Vec<f64>> {
                Some(
                    xs.iter()
                        .zip(&y)
                        .map(|(x, y)| y - f64::atan(offset + p[0] + p[1] * x))
                        .collect(),
                )
            };
            let steps = [1e-6, 1e-6];
            let x0 = sensitivity(residuals, &[0.0, 0.0], &steps).expect("finite");
            let linear = LinearFit::new(
                &x0.rows(0, train_rows).into_owned(),
                &x0.rows(train_rows, xs.len() - train_rows).into_owned(),
            );
            let r0 = DVector::from_vec(residuals(&[0.0, 0.0]).expect("finite"));
            let r0_train = r0.rows(0, train_rows).into_owned();
            for max_steps in 0..5 {
                let how = GaussNewtonSteps {
                    fit: "test",
                    max_steps,
                    truncate_below: NULL_DIRECTION_TOLERANCE,
                    small_step: None,
                    fit_at_end: true,
                };
                let got = refine_from_linear(residuals, &steps, &linear, &r0_train, train_rows, how).expect("refines");
                let eval = |p: &DVector<f64>| -> Result<(DVector<f64>, DMatrix<f64>), LsqError> {
                    let r = residuals(p.as_slice()).expect("finite");
                    Ok((
                        DVector::from_vec(r),
                        -sensitivity(residuals, p.as_slice(), &steps).expect("finite"),
                    ))
                };
                let p1 = linear.params(&r0_train);
                let options = LmOptions {
                    damping: Damping::GaussNewton {
                        truncate_below: Some(NULL_DIRECTION_TOLERANCE),
                        monotone: true,
                    },
                    fitted_rows: Some(train_rows),
                    ..LmOptions::marquardt("test", max_steps)
                };
                let start = eval(&p1).expect("finite");
                let want = levenberg_marquardt_from(p1, start, &options, eval, |p, d| Ok(p + d)).expect("runs");
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                let case = format!("a {a}, b {b}, offset {offset}, {max_steps} steps");
                assert_eq!(bits(got.params.as_slice()), bits(want.state.as_slice()), "{case}");
                assert_eq!(bits(got.residual.as_slice()), bits(want.residual.as_slice()), "{case}");
                assert_eq!((got.iterations, got.stop), (want.iterations, want.stop), "{case}");
                stops.push(want.stop);
                let x = -want.jacobian;
                let fit = LinearFit::new(
                    &x.rows(0, train_rows).into_owned(),
                    &x.rows(train_rows, xs.len() - train_rows).into_owned(),
                );
                assert_eq!(
                    bits(got.fit.normal_inverse.as_slice()),
                    bits(fit.normal_inverse.as_slice()),
                    "{case}"
                );
            }
        }
        assert!(
            stops.contains(&Stop::NoDecrease) && stops.contains(&Stop::MaxIterations),
            "the cases reject a step and take all: {stops:?}"
        );
    }
}
