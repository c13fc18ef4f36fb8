//! The maximum-likelihood sliding-axis fit: the paper's eqs. (9)-(13) folded into one weighted
//! least-squares problem on the observed points, like the arc fit of a rotary axis
//! ([`super::arc_ml`]):
//!
//! ```text
//! p_j = c + n D_j,   D_j = f^-1(S_c^j) - f^-1(S_c^0),   f(S) = S + sum_k c_k S^k  (eq. 13)
//! ```
//!
//! `c` is the target at step 0, `n` the axis direction (only the direction of a sliding axis
//! matters, eq. 9), `f` the transmission (`c_1` the scale error). Parameters (the local vector
//! `delta`): `[c_x, c_y, c_z, tilt_u, tilt_v, coefficients..]`, the tilts turning the frame
//! `(u, v, n)` about its own `u` and `v`. Residuals are taken in that frame, across (`u`, `v`,
//! weight `1/sigma`) and along (`n`, weight `1/sqrt(sigma^2 + s^2)` with `s` the joint's
//! repeatability, a jitter along the axis). Levenberg-Marquardt from the principal direction
//! of the points.

use nalgebra::{DMatrix, DVector, Matrix2, Point3, Rotation3, Unit, Vector3};

use super::CalibrationError;
use super::noise::ResidualMoments;
use crate::numerics::lsq;
use crate::robot::Transmission;
use crate::robot::TransmissionFitForm;

const FIT: &str = "sliding axis maximum-likelihood fit (eqs. 9-13)";

/// Number of geometric parameters before the transmission coefficients.
pub(crate) const N_GEOMETRY: usize = 5;

/// The parameters of the line model.
#[derive(Clone, Debug, PartialEq)]
pub struct LineParams {
    /// The target at step 0 (points' unit).
    pub start: Point3<f64>,
    /// Columns `(u, v, n)`: `n` the axis direction.
    pub frame: Rotation3<f64>,
    /// Transmission coefficients `[c_1..]`.
    pub coefficients: Vec<f64>,
}

impl LineParams {
    /// Column `i` of the frame.
    pub(crate) fn axis(&self, i: usize) -> Vector3<f64> {
        self.frame.matrix().column(i).into()
    }

    /// The parameters moved by a local perturbation `d` (layout in the module doc).
    pub(crate) fn perturbed(&self, d: &[f64]) -> Self {
        let mut p = self.clone();
        p.start += Vector3::new(d[0], d[1], d[2]);
        p.frame = self.frame * Rotation3::new(Vector3::new(d[3], d[4], 0.0));
        p.frame.renormalize();
        for (c, x) in p.coefficients.iter_mut().zip(&d[N_GEOMETRY..]) {
            *c += x;
        }
        p
    }
}

/// The result of [`fit_line`].
#[derive(Clone, Debug, PartialEq)]
pub struct LineFit {
    /// Parameters at the optimum.
    pub params: LineParams,
    /// The axis direction (the sense of increasing commands).
    pub direction: Unit<Vector3<f64>>,
    /// The fitted transmission (its own zero: `c0 = 0`).
    pub transmission: Transmission,
    /// `(J^T W J)^-1` in the local parameters.
    pub covariance: DMatrix<f64>,
    /// Covariance of the direction's components along `u`, `v` \[rad^2\].
    pub direction_covariance: Matrix2<f64>,
    /// 1-sigma of each transmission coefficient.
    pub coefficient_sigma: Vec<f64>,
    /// Residual of each point (points' unit): `[across u, across v, along n]`.
    pub residuals: Vec<Vector3<f64>>,
    /// RMS length of the point residuals.
    pub residual_rms: f64,
    /// Scaled condition number of the whitened Jacobian.
    pub condition_number: f64,
    /// The residual moments of the measurement-noise-only fit (for the noise estimate).
    pub moments: ResidualMoments,
}

/// The displacement from step 0 and its derivative by each coefficient, per point.
fn displacements(
    form: &TransmissionFitForm,
    coefficients: &[f64],
    commands: &[f64],
) -> Result<Vec<(f64, Vec<f64>)>, CalibrationError> {
    let mut basis = vec![0.0; form.n_coefficients()];
    let mut out = Vec::with_capacity(commands.len());
    let mut guess = commands[0];
    for &u in commands {
        let (s, value) = form
            .invert(coefficients, u, guess, &mut basis)
            .ok_or(CalibrationError::NotInvertible {
                fit: FIT,
                command_rad: u,
            })?;
        guess = s;
        // f(g(u)) = u: dg/dc_k = -basis_k(g) / f'(g).
        out.push((s, basis.iter().map(|b| -b / value.slope).collect::<Vec<f64>>()));
    }
    let (s0, d0) = out[0].clone();
    Ok(out
        .into_iter()
        .map(|(s, d)| (s - s0, d.iter().zip(&d0).map(|(a, b)| a - b).collect()))
        .collect())
}

/// The points the line `p` predicts at `commands` (the first command at `p.start`).
pub(crate) fn predict_line(
    form: &TransmissionFitForm,
    p: &LineParams,
    commands: &[f64],
) -> Result<Vec<Point3<f64>>, CalibrationError> {
    let n = p.axis(2);
    Ok(displacements(form, &p.coefficients, commands)?
        .into_iter()
        .map(|(d, _)| p.start + n * d)
        .collect())
}

/// Residuals, their Jacobian and the per-point residual vectors of [`residual_and_jacobian`].
type Linearised = (DVector<f64>, DMatrix<f64>, Vec<Vector3<f64>>);

/// Whitened residuals and Jacobian of the model at `p` (module docs).
fn residual_and_jacobian(
    form: &TransmissionFitForm,
    commands: &[f64],
    points: &[Point3<f64>],
    p: &LineParams,
    weights: [f64; 2],
) -> Result<Linearised, CalibrationError> {
    let (u, v, n) = (p.axis(0), p.axis(1), p.axis(2));
    let m = form.n_coefficients();
    let d = displacements(form, &p.coefficients, commands)?;
    let rows = 3 * points.len();
    let mut r = DVector::zeros(rows);
    let mut j = DMatrix::zeros(rows, N_GEOMETRY + m);
    let mut raw = Vec::with_capacity(points.len());
    let [w_across, w_along] = weights;
    for (i, (pt, (dj, ddj))) in points.iter().zip(&d).enumerate() {
        let e = pt - p.start - n * *dj;
        let (eu, ev, en) = (u.dot(&e), v.dot(&e), n.dot(&e));
        raw.push(Vector3::new(eu, ev, en));
        let k = 3 * i;
        r[k] = eu * w_across;
        r[k + 1] = ev * w_across;
        r[k + 2] = en * w_along;
        for c in 0..3 {
            j[(k, c)] = -u[c] * w_across;
            j[(k + 1, c)] = -v[c] * w_across;
            j[(k + 2, c)] = -n[c] * w_along;
        }
        // Tilts: du = -dv_ n, dv = du_ n, dn = dv_ u - du_ v (module docs).
        j[(k, 4)] = (-en - dj) * w_across;
        j[(k + 1, 3)] = (en + dj) * w_across;
        j[(k + 2, 3)] = -ev * w_along;
        j[(k + 2, 4)] = eu * w_along;
        for (c, dd) in ddj.iter().enumerate() {
            j[(k + 2, N_GEOMETRY + c)] = -dd * w_along;
        }
    }
    Ok((r, j, raw))
}

/// The starting parameters: the principal direction of the points, oriented along
/// increasing commands, from the first point; no transmission error.
fn initial(points: &[Point3<f64>], commands: &[f64], m: usize) -> Result<LineParams, CalibrationError> {
    let centroid = points.iter().map(|p| p.coords).sum::<Vector3<f64>>() / points.len() as f64;
    let a = DMatrix::from_fn(points.len(), 3, |r, c| points[r][c] - centroid[c]);
    let svd = a.svd(false, true);
    let vt = svd.v_t.ok_or(CalibrationError::ZeroSpan { fit: FIT })?;
    let (imax, smax) = svd.singular_values.argmax();
    if smax <= 0.0 {
        return Err(CalibrationError::ZeroSpan { fit: FIT });
    }
    let mut n = Vector3::new(vt[(imax, 0)], vt[(imax, 1)], vt[(imax, 2)]);
    let last = points.len() - 1;
    if (points[last] - points[0]).dot(&n) * (commands[last] - commands[0]) < 0.0 {
        n = -n;
    }
    let rot = Rotation3::rotation_between(&Vector3::z(), &n)
        .unwrap_or_else(|| Rotation3::new(Vector3::x() * std::f64::consts::PI));
    Ok(LineParams {
        start: points[0],
        frame: rot,
        coefficients: vec![0.0; m],
    })
}

/// Maximum-likelihood fit of a sliding axis from `points` observed at absolute commands
/// `commands_m` (the joint's actuator commands \[m\]), with measurement noise `sigma_per_axis`
/// (points' unit) and the joint's repeatability `repeatability` (points' unit, along the axis;
/// 0 = measurement noise only).
pub fn fit_line(
    points: &[Point3<f64>],
    commands_m: &[f64],
    form: &TransmissionFitForm,
    sigma_per_axis: f64,
    repeatability: f64,
    max_iterations: usize,
) -> Result<LineFit, CalibrationError> {
    let n = points.len();
    let m = form.n_coefficients();
    if commands_m.len() != n {
        return Err(CalibrationError::LengthMismatch {
            fit: FIT,
            what: "commands",
            got: commands_m.len(),
            expected: n,
        });
    }
    if n < 2 || 3 * n <= N_GEOMETRY + m {
        return Err(CalibrationError::TooFewPoints {
            fit: FIT,
            got: n,
            needed: ((N_GEOMETRY + m) / 3 + 1).max(2),
        });
    }
    if !(sigma_per_axis > 0.0 && sigma_per_axis.is_finite() && repeatability >= 0.0 && repeatability.is_finite()) {
        return Err(CalibrationError::InvalidInput {
            fit: FIT,
            what: "noise sigma must be positive and the repeatability >= 0",
        });
    }
    let run = |start: LineParams, weights: [f64; 2]| -> Result<_, CalibrationError> {
        Ok(lsq::levenberg_marquardt(
            start,
            &lsq::LmOptions::marquardt(FIT, max_iterations),
            |s| residual_and_jacobian(form, commands_m, points, s, weights).map(|(r, j, _)| (r, j)),
            |s, d| Ok::<_, CalibrationError>(s.perturbed(d.as_slice())),
        )?
        .converged(FIT, None)?)
    };
    let iso = [1.0 / sigma_per_axis; 2];
    let first = run(initial(points, commands_m, m)?, iso)?;
    let (_, j_iso, raw_iso) = residual_and_jacobian(form, commands_m, points, &first.state, iso)?;
    let g_iso = lsq::inverse_normal(&j_iso, FIT)? / (sigma_per_axis * sigma_per_axis);
    let along = vec![Vector3::z(); n];
    let moments = ResidualMoments::of_fit(
        &(&j_iso * sigma_per_axis),
        &g_iso,
        &raw_iso,
        Some((&along, repeatability)),
    );
    let weights = [
        1.0 / sigma_per_axis,
        1.0 / (sigma_per_axis.powi(2) + repeatability.powi(2)).sqrt(),
    ];
    let outcome = if repeatability > 0.0 {
        run(first.state, weights)?
    } else {
        first
    };
    let params = outcome.state;
    let (_, jw, raw) = residual_and_jacobian(form, commands_m, points, &params, weights)?;
    let covariance = lsq::inverse_normal(&jw, FIT)?;
    // Direction components along u, v: dn = tilt_v u - tilt_u v.
    let t = covariance.fixed_view::<2, 2>(3, 3);
    let direction_covariance = Matrix2::new(t[(1, 1)], -t[(0, 1)], -t[(1, 0)], t[(0, 0)]);
    let residual_rms = (raw.iter().map(|r| r.norm_squared()).sum::<f64>() / n as f64).sqrt();
    Ok(LineFit {
        direction: Unit::new_normalize(params.axis(2)),
        transmission: form.build(&params.coefficients),
        coefficient_sigma: (N_GEOMETRY..N_GEOMETRY + m)
            .map(|k| covariance[(k, k)].sqrt())
            .collect(),
        direction_covariance,
        condition_number: lsq::scaled_condition_number(&jw),
        residuals: raw,
        residual_rms,
        covariance,
        moments,
        params,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn sample() -> (Vec<Point3<f64>>, Vec<f64>, Vector3<f64>, Vec<f64>) {
        let dir = Vector3::new(0.3, -0.2, 0.93).normalize();
        let truth = vec![-4e-4, 0.05];
        let f = Transmission::Polynomial {
            c0: 0.0,
            c: truth.clone(),
        };
        let commands: Vec<f64> = (0..12).map(|j| -0.1 + 0.02 * j as f64).collect();
        let s0 = f.actual_from_command(commands[0]).unwrap();
        let start = Point3::new(1.2, -0.4, 0.3);
        let pts = commands
            .iter()
            .map(|&c| start + dir * (f.actual_from_command(c).unwrap() - s0))
            .collect();
        (pts, commands, dir, truth)
    }

    #[test]
    fn recovers_a_noiseless_line_with_scale_and_curvature() {
        let (pts, commands, dir, truth) = sample();
        let form = TransmissionFitForm::Polynomial { order: 2 };
        for rep in [0.0, 2e-5] {
            let fit = fit_line(&pts, &commands, &form, 1e-4, rep, 100).unwrap();
            assert_relative_eq!(fit.direction.into_inner(), dir, epsilon = 1e-10);
            for (a, b) in fit.params.coefficients.iter().zip(&truth) {
                assert_relative_eq!(a, b, epsilon = 1e-9);
            }
            assert!(fit.residual_rms < 1e-10);
        }
    }

    #[test]
    fn jacobian_matches_central_differences() {
        let (pts, commands, _, _) = sample();
        let form = TransmissionFitForm::Polynomial { order: 2 };
        let p = LineParams {
            start: Point3::new(1.1, -0.3, 0.35),
            frame: Rotation3::new(Vector3::new(0.2, 0.4, -0.1)),
            coefficients: vec![1e-3, 0.1],
        };
        let w = [1e4, 0.7e4];
        let (_, j, _) = residual_and_jacobian(&form, &commands, &pts, &p, w).unwrap();
        let h = 1e-7;
        for c in 0..j.ncols() {
            let mut d = vec![0.0; j.ncols()];
            d[c] = h;
            let plus = residual_and_jacobian(&form, &commands, &pts, &p.perturbed(&d), w)
                .unwrap()
                .0;
            d[c] = -h;
            let minus = residual_and_jacobian(&form, &commands, &pts, &p.perturbed(&d), w)
                .unwrap()
                .0;
            let fd = (plus - minus) / (2.0 * h);
            for r in 0..fd.len() {
                assert_relative_eq!(j[(r, c)], fd[r], epsilon = 1e-5, max_relative = 1e-5);
            }
        }
    }
}
