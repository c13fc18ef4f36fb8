//! Cramer-Rao bound of one joint sweep and Monte-Carlo efficiency.
//!
//! For Gaussian noise the Fisher information of the arc model ([`super::arc_model`]) is
//! `F = J^T W J` with the exact (analytic) model Jacobian; any unbiased estimator of a
//! quantity `g(theta)` has covariance `>= G F^-1 G^T` (Kay, *Fundamentals of Statistical
//! Signal Processing I*, eq. 3.30). The quantities judged are those of
//! [`super::arc_model::axis_quantities`]: axis direction (2), axis position (2) and each
//! transmission coefficient. Efficiency = CRB variance / empirical mean squared error.
//!
//! With a robot's repeatability: [`arc_crb_with_angle_noise`] (angle noise on every point of
//! the sweep) and [`held_joint_axis_covariance`] (the constant error of the joints held below
//! it, a bias that adds to the bound).

use nalgebra::{DMatrix, Matrix2, Matrix3, Matrix4, Point3, Unit, Vector3, Vector4};

use crate::kinematics::AxisLine;

use super::CalibrationError;
use super::arc_model::{ArcModel, ArcParams, MeasurementNoise, axis_quantities_gradient};
use crate::numerics::lsq;
use crate::robot::TransmissionFitForm;

mod campaign;
pub use campaign::{
    CampaignBound, ESTIMABLE_TOLERANCE, convention_bound, covariance_range, fisher_bound, fisher_bound_of,
};

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

/// The bound for the true parameters `truth` when each point's joint angle also carries
/// independent Gaussian noise of standard deviation `angle_sigma_rad` (a robot's
/// repeatability) besides the measurement noise `noise`: the same `F = J^T Sigma^-1 J` with the
/// per-point covariance `Sigma_j = Sigma_meas,j + sigma_theta^2 t_j t_j^T`, `t_j = dp_j/dtheta_j`
/// at the truth ([`MeasurementNoise::with_angle_noise`]; exact for the linearised angle noise).
/// Of the Gaussian Fisher information with a parameter-dependent covariance (Kay eq. 3.31)
/// this keeps the mean term; the trace term `1/2 tr(Sigma^-1 dSigma Sigma^-1 dSigma)` is of
/// relative order `(sigma / r)^2`, below 1e-6 for the paper's sweeps. `angle_sigma_rad == 0` is
/// [`arc_crb`] of the measurement noise.
pub fn arc_crb_with_angle_noise(
    form: TransmissionFitForm,
    commands_rad: &[f64],
    noise: &MeasurementNoise,
    angle_sigma_rad: f64,
    truth: &ArcParams,
    reference: &Point3<f64>,
) -> Result<CrbReport, CalibrationError> {
    let measurement = ArcModel::new(form, commands_rad, noise)?;
    if angle_sigma_rad == 0.0 {
        return arc_crb(&measurement, truth, reference);
    }
    let total = noise.with_angle_noise(&measurement.angle_derivatives(truth)?, angle_sigma_rad)?;
    arc_crb(&ArcModel::new(form, commands_rad, &total)?, truth, reference)
}

/// Covariance of the errors `[dir_u, dir_v, pos_u, pos_v]` of an axis (the quantities of
/// [`super::arc_model::axis_quantities`] in the basis `u, v` across it; `axis.origin_m` is the
/// point closest to the reference) caused by the constant errors of the joints held still
/// BELOW it during its sweep: `(line, sigma)` per held joint, its axis line and the standard
/// deviation of its joint-value error \[rad\].
///
/// A held actuator keeps its re-positioning error through the whole sweep, so the error is a
/// bias of that experiment, not noise of its points: it turns everything above that joint,
/// the swept axis included, rigidly about the held joint's axis `(o_i, n_i)` by `e_i`. To first
/// order the axis direction moves by `e_i n_i x n` and its point by `e_i n_i x (q - o_i)` (the
/// move along `n` only slides the point along the line), so with independent `e_i ~ N(0,
/// sigma_i^2)` the covariance is `sum_i sigma_i^2 g_i g_i^T` with
/// `g_i = [(n_i x n).u, (n_i x n).v, (n_i x (q - o_i)).u, (n_i x (q - o_i)).v]` (first-order
/// propagation, as for the rows in `procedure::row_sigmas`). Independent of the sweep's own
/// noise, it adds to the sweep's bound: any estimator unbiased for the displaced arc has at
/// least `F^-1 + this` about the undisplaced one. Joints held ABOVE the swept one only move
/// the target on the swept link (a circle about the same axis) and do not enter. The
/// correlation this error creates between axes swept while the same joint held still is not
/// modelled.
pub fn held_joint_axis_covariance(
    axis: &AxisLine,
    u: &Vector3<f64>,
    v: &Vector3<f64>,
    held: &[(AxisLine, f64)],
) -> Matrix4<f64> {
    let n = axis.direction.into_inner();
    held.iter()
        .map(|(line, sigma)| {
            let ni = line.direction.into_inner();
            let (b, a) = (ni.cross(&n), ni.cross(&(axis.origin_m - line.origin_m)));
            let g = Vector4::new(b.dot(u), b.dot(v), a.dot(u), a.dot(v));
            g * g.transpose() * (sigma * sigma)
        })
        .fold(Matrix4::zeros(), |acc, c| acc + c)
}

/// `n` points evenly spread over `span_rad` of command from `start_command_rad` on an arc with
/// these parameters, under isotropic noise: the hypothetical sweep the span study asks about
/// ("what span would determine a weak axis tilt").
#[derive(Clone, Copy, Debug)]
pub struct UniformArc<'a> {
    /// The arc (centre, frame, radius, phase, transmission coefficients).
    pub params: &'a ArcParams,
    /// The transmission form of the coefficients.
    pub form: TransmissionFitForm,
    /// First command \[rad\].
    pub start_command_rad: f64,
    /// Command span from the first to the last point \[rad\].
    pub span_rad: f64,
    /// Number of points (>= 2).
    pub n: usize,
    /// Noise per coordinate (the points' unit).
    pub sigma_per_axis: f64,
}

impl UniformArc<'_> {
    /// Command of point `j` \[rad\].
    fn command_rad(&self, j: usize) -> f64 {
        self.start_command_rad + self.span_rad * j as f64 / (self.n - 1) as f64
    }

    /// The full bound (reference point: the centre).
    pub fn crb(&self) -> Result<CrbReport, CalibrationError> {
        if self.n < 2 {
            return Err(CalibrationError::TooFewPoints {
                fit: FIT,
                got: self.n,
                needed: 2,
            });
        }
        let commands: Vec<f64> = (0..self.n).map(|j| self.command_rad(j)).collect();
        let model = ArcModel::new(
            self.form,
            &commands,
            &MeasurementNoise::Isotropic {
                sigma_per_axis: self.sigma_per_axis,
            },
        )?;
        arc_crb(&model, self.params, &self.params.centre)
    }

    /// Largest 1-sigma of the axis direction \[rad\] in [`UniformArc::crb`] (same value), from
    /// a 3x3 problem instead of the full one.
    ///
    /// With isotropic noise the Fisher information splits into two blocks. Express the centre
    /// in the frame `(u, v, n)`: the component of point `j` along `n` depends only on
    /// `(c_n, tilt_u, tilt_v)`, with Jacobian row `[1, r sin phi_j, -r cos phi_j]`
    /// (`phi_j = phase + D_j`), while its in-plane components depend on none of them
    /// ([`ArcModel::jacobian`]). So the tilt block of `F^-1` is the tilt block of the inverse
    /// of `F_n = sigma^-2 sum_j [1, r s_j, -r c_j]^T [1, r s_j, -r c_j]`, and the direction
    /// bound (`dir_u = tilt_v`, `dir_v = -tilt_u`) has the same eigenvalues. Cheap enough to
    /// run for every fit's span study.
    pub fn direction_sigma_rad(&self) -> Result<f64, CalibrationError> {
        let &UniformArc {
            params,
            form,
            start_command_rad,
            n,
            sigma_per_axis,
            ..
        } = self;
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
            let command = self.command_rad(j);
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
