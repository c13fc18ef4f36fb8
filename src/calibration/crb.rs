//! Cramer-Rao bound of one joint sweep and Monte-Carlo efficiency.
//!
//! For Gaussian noise the Fisher information of the arc model ([`super::arc_model`]) is
//! `F = J^T W J` with the exact (analytic) model Jacobian; any unbiased estimator of a
//! quantity `g(theta)` has covariance `>= G F^-1 G^T` (Kay, *Fundamentals of Statistical
//! Signal Processing I*, eq. 3.30). The quantities judged are those of
//! [`super::arc_model::axis_quantities`]: axis direction (2), axis position (2) and each
//! transmission coefficient. Efficiency = CRB variance / empirical mean squared error.

use nalgebra::{DMatrix, Matrix2, Matrix3, Point3, Unit, Vector3};

use super::arc_model::{ArcModel, ArcParams, MeasurementNoise, axis_quantities_gradient};
use super::transmission_fit::TransmissionForm;
use super::{CalibrationError, lsq};

const FIT: &str = "Cramer-Rao bound";

/// The Cramer-Rao bound of one sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct CrbReport {
    /// `F^-1` in the local parameters (order of [`ArcModel::param_names`]).
    pub parameter_covariance: DMatrix<f64>,
    /// Bound on the axis direction's components along the truth's `u, v` \[rad^2\].
    pub direction: Matrix2<f64>,
    /// Bound on the axis point's components along `u, v` (points' unit squared).
    pub position: Matrix2<f64>,
    /// Bound on each transmission coefficient's variance \[rad^2\].
    pub coefficient_variance: Vec<f64>,
}

impl CrbReport {
    /// Largest 1-sigma of the axis direction \[rad\].
    pub fn direction_sigma_rad(&self) -> f64 {
        self.direction.symmetric_eigenvalues().max().sqrt()
    }
}

/// The bound for the true parameters `truth` of `model`, with the axis point taken closest to
/// `reference`.
pub fn arc_crb(model: &ArcModel, truth: &ArcParams, reference: &Point3<f64>) -> Result<CrbReport, CalibrationError> {
    let jw = model.whitened_jacobian(truth)?;
    let cov = lsq::inverse_normal(&jw, FIT)?;
    let g = axis_quantities_gradient(truth, reference);
    let q = &g * &cov * g.transpose();
    let m = truth.coefficients.len();
    Ok(CrbReport {
        direction: q.fixed_view::<2, 2>(0, 0).into(),
        position: q.fixed_view::<2, 2>(2, 2).into(),
        coefficient_variance: (0..m).map(|k| q[(4 + k, 4 + k)]).collect(),
        parameter_covariance: cov,
    })
}

/// The bound for `n` points evenly spread over `span_rad` of command from `start_command_rad`
/// with these parameters and isotropic noise (reference point: the centre). Used to say
/// what span would determine a weak axis tilt.
pub fn uniform_arc_crb(
    params: &ArcParams,
    form: TransmissionForm,
    start_command_rad: f64,
    span_rad: f64,
    n: usize,
    sigma_per_axis: f64,
) -> Result<CrbReport, CalibrationError> {
    if n < 2 {
        return Err(CalibrationError::TooFewPoints {
            fit: FIT,
            got: n,
            needed: 2,
        });
    }
    let commands: Vec<f64> = (0..n)
        .map(|j| start_command_rad + span_rad * j as f64 / (n - 1) as f64)
        .collect();
    let model = ArcModel::new(form, &commands, &MeasurementNoise::Isotropic { sigma_per_axis })?;
    arc_crb(&model, params, &params.centre)
}

/// Largest 1-sigma of the axis direction \[rad\] in the bound of [`uniform_arc_crb`] (same
/// arguments, same value), from a 3x3 problem instead of the full one.
///
/// With isotropic noise the Fisher information splits into two blocks. Express the centre in
/// the frame `(u, v, n)`: the component of point `j` along `n` depends only on
/// `(c_n, tilt_u, tilt_v)`, with Jacobian row `[1, r sin phi_j, -r cos phi_j]`
/// (`phi_j = phase + D_j`), while its in-plane components depend on none of them
/// ([`ArcModel::jacobian`]). So the tilt block of `F^-1` is the tilt block of the inverse of
/// `F_n = sigma^-2 sum_j [1, r s_j, -r c_j]^T [1, r s_j, -r c_j]`, and the direction bound
/// (`dir_u = tilt_v`, `dir_v = -tilt_u`) has the same eigenvalues. Cheap enough to run for
/// every fit's span study.
pub fn uniform_arc_direction_sigma(
    params: &ArcParams,
    form: TransmissionForm,
    start_command_rad: f64,
    span_rad: f64,
    n: usize,
    sigma_per_axis: f64,
) -> Result<f64, CalibrationError> {
    let needed = (super::arc_model::N_GEOMETRY + form.n_coefficients()) / 3 + 1;
    if n < needed.max(2) {
        return Err(CalibrationError::TooFewPoints {
            fit: FIT,
            got: n,
            needed: needed.max(2),
        });
    }
    if !(sigma_per_axis > 0.0 && sigma_per_axis.is_finite()) {
        return Err(CalibrationError::InvalidInput {
            fit: FIT,
            what: "sigma must be positive",
        });
    }
    let not_invertible = |command_rad| CalibrationError::NotInvertible { fit: FIT, command_rad };
    let c = &params.coefficients;
    let a0 = form
        .actual_from_command(c, start_command_rad)
        .ok_or(not_invertible(start_command_rad))?;
    let mut fisher = Matrix3::zeros();
    let mut basis = vec![0.0; form.n_coefficients()];
    let (mut previous_command, mut a) = (start_command_rad, a0);
    let mut e = form.evaluate(c, a0, &mut basis);
    for j in 0..n {
        let command = start_command_rad + span_rad * j as f64 / (n - 1) as f64;
        // Second-order Taylor start from the previous point, as the arc model does.
        let step = command - previous_command;
        let guess = a + step / e.slope - 0.5 * e.curvature * step * step / e.slope.powi(3);
        (a, e) = form
            .invert(c, command, guess, &mut basis)
            .ok_or(not_invertible(command))?;
        previous_command = command;
        let (s, co) = (params.phase_rad + a - a0).sin_cos();
        let row = Vector3::new(1.0, params.radius * s, -params.radius * co);
        fisher += row * row.transpose();
    }
    let cov = (fisher / (sigma_per_axis * sigma_per_axis))
        .cholesky()
        .ok_or(CalibrationError::IllConditioned {
            fit: FIT,
            condition_number: f64::INFINITY,
        })?
        .inverse();
    let tilt: Matrix2<f64> = cov.fixed_view::<2, 2>(1, 1).into();
    Ok(tilt.symmetric_eigenvalues().max().sqrt())
}

/// Errors of an estimated axis and coefficients against the truth, in the quantities of the
/// bound: `[dir_u, dir_v, pos_u, pos_v, coefficients..]` along the truth's `u, v`.
pub fn axis_errors(
    direction: &Unit<Vector3<f64>>,
    point_on_axis: &Point3<f64>,
    coefficients: &[f64],
    truth: &ArcParams,
    reference: &Point3<f64>,
) -> Vec<f64> {
    let (u, v) = (truth.u().into_inner(), truth.v().into_inner());
    let d = if direction.dot(&truth.normal()) < 0.0 {
        -direction.into_inner()
    } else {
        direction.into_inner()
    };
    let q = point_on_axis + d * (reference - point_on_axis).dot(&d);
    let qt = truth.axis_point_near(reference);
    [d.dot(&u), d.dot(&v), (q - qt).dot(&u), (q - qt).dot(&v)]
        .into_iter()
        .chain(coefficients.iter().zip(&truth.coefficients).map(|(a, b)| a - b))
        .collect()
}

/// A measured efficiency.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Efficiency {
    /// Trace of the bound over the quantity's components.
    pub crb_variance: f64,
    /// Mean over trials of the squared error length.
    pub mse: f64,
    /// `crb_variance / mse`.
    pub efficiency: f64,
    /// Relative standard error of `mse` (sample standard deviation of the squared error over
    /// `sqrt(trials)`, divided by `mse`); `sqrt(2 / (d trials))` for Gaussian errors.
    pub relative_standard_error: f64,
    /// Number of trials.
    pub trials: usize,
}

/// Efficiency of the components `range` of per-trial error vectors against the bound's trace.
pub fn efficiency(crb_variance: f64, errors: &[Vec<f64>], range: std::ops::Range<usize>) -> Efficiency {
    let sq: Vec<f64> = errors
        .iter()
        .map(|e| e[range.clone()].iter().map(|x| x * x).sum())
        .collect();
    let n = sq.len().max(1) as f64;
    let mse = sq.iter().sum::<f64>() / n;
    let var = sq.iter().map(|s| (s - mse).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    Efficiency {
        crb_variance,
        mse,
        efficiency: crb_variance / mse,
        relative_standard_error: var.sqrt() / n.sqrt() / mse,
        trials: sq.len(),
    }
}

#[cfg(test)]
mod tests;
