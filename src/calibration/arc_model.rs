//! The measurement model of one joint sweep used by the efficient estimator and the
//! Cramer-Rao bound: `p_j = c + r (cos(phi0 + D_j) u + sin(phi0 + D_j) v)` with
//! `D_j = f^-1(theta_c^j) - f^-1(theta_c^0)` (the paper's eqs. 6-8 folded into one model).
//!
//! The phase `phi0` is the angle of step 0 about the normal, measured from `u`; writing the
//! motion relative to step 0 keeps a constant command offset out of the transmission
//! coefficients (it is confounded with `phi0`). Parameters (the local perturbation vector
//! `delta`): `[c_x, c_y, c_z, tilt_u, tilt_v, radius, phase, coefficients..]`; the tilts rotate
//! the frame `(u, v, n)` about its own `u` and `v`, re-anchored after every step.

use nalgebra::{DMatrix, Matrix3, Point3, Rotation3, Unit, Vector3};

use super::CalibrationError;
use super::transmission_fit::TransmissionValue;
use crate::robot::TransmissionFitForm;

const FIT: &str = "arc model";

/// Transmission coefficients an evaluation of the model keeps on the stack.
const INLINE_COEFFICIENTS: usize = 8;

/// Number of geometric parameters before the transmission coefficients.
pub const N_GEOMETRY: usize = 7;

/// Measurement noise of the observed points.
#[derive(Clone, Debug, PartialEq)]
pub enum MeasurementNoise {
    /// Independent, equal noise on each coordinate (points' unit, 1-sigma per axis).
    Isotropic {
        /// Standard deviation per coordinate axis.
        sigma_per_axis: f64,
    },
    /// A 3x3 covariance per point (points' unit squared).
    PerPoint(Vec<Matrix3<f64>>),
}

impl MeasurementNoise {
    /// Isotropic noise with the given 3-D RMS error length (the paper's "net radial error"):
    /// `sigma_per_axis = rms / sqrt(3)`.
    pub fn from_rms_3d(rms: f64) -> Self {
        MeasurementNoise::Isotropic {
            sigma_per_axis: rms / 3f64.sqrt(),
        }
    }

    /// The 3x3 covariance of point `j` of `n` (points' unit squared).
    fn covariance(&self, j: usize) -> Matrix3<f64> {
        match self {
            MeasurementNoise::Isotropic { sigma_per_axis } => Matrix3::identity() * (sigma_per_axis * sigma_per_axis),
            MeasurementNoise::PerPoint(covs) => covs[j],
        }
    }

    /// This noise plus independent Gaussian noise of standard deviation `angle_sigma_rad` on
    /// the joint angle of each point, propagated to first order (the "effective variance"
    /// method, Orear, Am. J. Phys. 50 (1982) 912, eq. 2, for a 3-vector observation):
    /// `Sigma_j = Sigma_meas,j + sigma_theta^2 t_j t_j^T` with `t_j = dp_j/dtheta_j`
    /// ([`ArcModel::angle_derivatives`]). Per point, one entry of `angle_derivatives` each.
    pub fn with_angle_noise(
        &self,
        angle_derivatives: &[Vector3<f64>],
        angle_sigma_rad: f64,
    ) -> Result<Self, CalibrationError> {
        check_angle_sigma(angle_sigma_rad, FIT)?;
        if let MeasurementNoise::PerPoint(covs) = self
            && covs.len() != angle_derivatives.len()
        {
            return Err(CalibrationError::LengthMismatch {
                fit: FIT,
                what: "covariances",
                got: covs.len(),
                expected: angle_derivatives.len(),
            });
        }
        let s2 = angle_sigma_rad * angle_sigma_rad;
        Ok(MeasurementNoise::PerPoint(
            angle_derivatives
                .iter()
                .enumerate()
                .map(|(j, t)| self.covariance(j) + s2 * t * t.transpose())
                .collect(),
        ))
    }

    /// `L^-1` with `L L^T` the covariance of point `j`: whitens residuals.
    pub(crate) fn whiteners(&self, n: usize) -> Result<Vec<Matrix3<f64>>, CalibrationError> {
        match self {
            MeasurementNoise::Isotropic { sigma_per_axis } => {
                if !(*sigma_per_axis > 0.0 && sigma_per_axis.is_finite()) {
                    return Err(CalibrationError::InvalidInput {
                        fit: FIT,
                        what: "sigma must be positive",
                    });
                }
                Ok(vec![Matrix3::identity() / *sigma_per_axis; n])
            }
            MeasurementNoise::PerPoint(covs) => {
                if covs.len() != n {
                    return Err(CalibrationError::LengthMismatch {
                        fit: FIT,
                        what: "covariances",
                        got: covs.len(),
                        expected: n,
                    });
                }
                covs.iter()
                    .map(|c| {
                        c.cholesky()
                            .and_then(|ch| ch.l().try_inverse())
                            .ok_or(CalibrationError::InvalidInput {
                                fit: FIT,
                                what: "covariance not positive definite",
                            })
                    })
                    .collect()
            }
        }
    }
}

/// An angle noise's standard deviation must be finite and >= 0.
pub(crate) fn check_angle_sigma(angle_sigma_rad: f64, fit: &'static str) -> Result<(), CalibrationError> {
    if angle_sigma_rad >= 0.0 && angle_sigma_rad.is_finite() {
        Ok(())
    } else {
        Err(CalibrationError::InvalidInput {
            fit,
            what: "angle sigma must be finite and >= 0",
        })
    }
}

/// The parameters of the arc model at one point of parameter space.
#[derive(Clone, Debug, PartialEq)]
pub struct ArcParams {
    /// Circle centre (points' unit).
    pub centre: Point3<f64>,
    /// Columns `(u, v, n)`: in-plane basis and the axis direction (right-handed rotation).
    pub frame: Rotation3<f64>,
    /// Radius (points' unit).
    pub radius: f64,
    /// Angle of step 0 about `n`, from `u` \[rad\].
    pub phase_rad: f64,
    /// Transmission coefficients `[sin.., cos..]` \[rad\].
    pub coefficients: Vec<f64>,
}

impl ArcParams {
    /// In-plane unit vector `u`.
    pub fn u(&self) -> Unit<Vector3<f64>> {
        Unit::new_unchecked(self.frame.matrix().column(0).into())
    }
    /// In-plane unit vector `v = n x u`.
    pub fn v(&self) -> Unit<Vector3<f64>> {
        Unit::new_unchecked(self.frame.matrix().column(1).into())
    }
    /// The axis direction `n`.
    pub fn normal(&self) -> Unit<Vector3<f64>> {
        Unit::new_unchecked(self.frame.matrix().column(2).into())
    }

    /// The point of the axis closest to `reference`.
    pub fn axis_point_near(&self, reference: &Point3<f64>) -> Point3<f64> {
        let n = self.normal();
        self.centre + n.into_inner() * (reference - self.centre).dot(&n)
    }

    /// The parameters moved by a local perturbation `delta` (layout in the module doc).
    pub fn perturbed(&self, delta: &[f64]) -> Self {
        let mut p = self.clone();
        p.centre += Vector3::new(delta[0], delta[1], delta[2]);
        p.frame = self.frame * Rotation3::new(Vector3::new(delta[3], delta[4], 0.0));
        p.frame.renormalize();
        p.radius += delta[5];
        p.phase_rad += delta[6];
        for (c, d) in p.coefficients.iter_mut().zip(&delta[N_GEOMETRY..]) {
            *c += d;
        }
        p
    }
}

/// The arc model for a given command sequence and transmission form.
#[derive(Clone, Debug)]
pub struct ArcModel {
    /// The transmission form whose coefficients are fitted.
    pub form: TransmissionFitForm,
    /// Absolute commands `theta_c^j` \[rad\].
    pub commands_rad: Vec<f64>,
    pub(crate) whiteners: Vec<Matrix3<f64>>,
    /// `1 / sigma` when every whitener is that multiple of the identity (the common case):
    /// whitening is then one scaling, with the same result as the 3x3 products.
    isotropic_whitener: Option<f64>,
}

impl ArcModel {
    /// A model for these commands under this noise.
    pub fn new(
        form: TransmissionFitForm,
        commands_rad: &[f64],
        noise: &MeasurementNoise,
    ) -> Result<Self, CalibrationError> {
        let whiteners = noise.whiteners(commands_rad.len())?;
        let isotropic_whitener = match noise {
            MeasurementNoise::Isotropic { .. } => whiteners.first().map(|w| w[(0, 0)]),
            MeasurementNoise::PerPoint(_) => None,
        };
        Ok(Self {
            form,
            commands_rad: commands_rad.to_vec(),
            whiteners,
            isotropic_whitener,
        })
    }

    /// Number of parameters (`7 + coefficients`).
    pub fn n_params(&self) -> usize {
        N_GEOMETRY + self.form.n_coefficients()
    }

    /// Names of the parameters, in `delta` order.
    pub fn param_names(&self) -> Vec<String> {
        [
            "centre_x", "centre_y", "centre_z", "tilt_u", "tilt_v", "radius", "phase",
        ]
        .iter()
        .map(|s| s.to_string())
        .chain(self.form.coefficient_names())
        .collect()
    }

    /// Visits every step `j` in order with the actual motion since step 0, `D_j`, and its
    /// coefficient derivatives `dD_j/dc_k` (a slice of length coefficients), using
    /// `d theta_a / d c_k = -b_k(theta_a) / f'(theta_a)`. No heap buffer (up to
    /// `INLINE_COEFFICIENTS` coefficients) and one `sin_cos` per harmonic per Newton step:
    /// this runs for every point at every iteration of the fit.
    fn for_each_motion(
        &self,
        coefficients: &[f64],
        mut visit: impl FnMut(usize, f64, &[f64]),
    ) -> Result<(), CalibrationError> {
        let m = self.form.n_coefficients();
        let (mut row_inline, mut first_inline) = ([0.0; INLINE_COEFFICIENTS], [0.0; INLINE_COEFFICIENTS]);
        let (mut row_heap, mut first_heap) = (Vec::new(), Vec::new());
        let (row, first) = if m <= INLINE_COEFFICIENTS {
            (&mut row_inline[..m], &mut first_inline[..m])
        } else {
            row_heap.resize(m, 0.0);
            first_heap.resize(m, 0.0);
            (&mut row_heap[..], &mut first_heap[..])
        };
        // Step j's inversion starts from step j-1's solution moved along the second-order
        // Taylor series of f^-1 (error ~ f''' step^3), so Halley's iteration ends after one
        // correction; its last evaluation supplies the basis and slope.
        let mut previous: Option<(f64, f64, TransmissionValue)> = None;
        let mut a0 = 0.0;
        for (j, &c) in self.commands_rad.iter().enumerate() {
            let guess = previous.map_or(c, |(cp, ap, e)| {
                let step = c - cp;
                ap + step / e.slope - 0.5 * e.curvature * step * step / e.slope.powi(3)
            });
            let (a, e) = self
                .form
                .invert(coefficients, c, guess, row)
                .ok_or(CalibrationError::NotInvertible {
                    fit: FIT,
                    command_rad: c,
                })?;
            for b in row.iter_mut() {
                *b = -*b / e.slope;
            }
            if j == 0 {
                a0 = a;
                first.copy_from_slice(row);
                row.iter_mut().for_each(|x| *x = 0.0);
            } else {
                for (x, y) in row.iter_mut().zip(first.iter()) {
                    *x -= y;
                }
            }
            visit(j, a - a0, row);
            previous = Some((c, a, e));
        }
        Ok(())
    }

    /// The actual motions since step 0, `D_j`, of every step.
    fn motion(&self, coefficients: &[f64]) -> Result<Vec<f64>, CalibrationError> {
        let mut d = Vec::with_capacity(self.commands_rad.len());
        self.for_each_motion(coefficients, |_, dj, _| d.push(dj))?;
        Ok(d)
    }

    /// `at(sin, cos, u, v)` of each step's angle `phi0 + D_j`.
    fn per_step<T>(
        &self,
        p: &ArcParams,
        at: impl Fn(f64, f64, &Vector3<f64>, &Vector3<f64>) -> T,
    ) -> Result<Vec<T>, CalibrationError> {
        let d = self.motion(&p.coefficients)?;
        let (u, v) = (p.u().into_inner(), p.v().into_inner());
        Ok(d.iter()
            .map(|dj| {
                let (s, c) = (p.phase_rad + dj).sin_cos();
                at(s, c, &u, &v)
            })
            .collect())
    }

    /// The predicted points.
    pub fn predict(&self, p: &ArcParams) -> Result<Vec<Point3<f64>>, CalibrationError> {
        self.per_step(p, |s, c, u, v| p.centre + p.radius * (c * u + s * v))
    }

    /// Fills the 3 Jacobian rows of step `row` from its motion `dj` and coefficient
    /// derivatives `dg`, each entry times `scale` (1: unweighted; an isotropic whitener: the
    /// product [`Self::whiten_rows`] would form afterwards, bit for bit), and returns its
    /// predicted point; `(u, v, n)` are `p`'s.
    fn fill_row(
        p: &ArcParams,
        (u, v, n): (&Vector3<f64>, &Vector3<f64>, &Vector3<f64>),
        (row, dj, dg): (usize, f64, &[f64]),
        scale: f64,
        jac: &mut DMatrix<f64>,
    ) -> Point3<f64> {
        let (s, c) = (p.phase_rad + dj).sin_cos();
        let radial = c * u + s * v;
        let tangent = p.radius * (-s * u + c * v);
        let r0 = 3 * row;
        for k in 0..3 {
            jac[(r0 + k, k)] = 1.0 * scale;
        }
        jac.fixed_view_mut::<3, 1>(r0, 3).copy_from(&(p.radius * s * n * scale));
        jac.fixed_view_mut::<3, 1>(r0, 4)
            .copy_from(&(-p.radius * c * n * scale));
        jac.fixed_view_mut::<3, 1>(r0, 5).copy_from(&(radial * scale));
        jac.fixed_view_mut::<3, 1>(r0, 6).copy_from(&(tangent * scale));
        for (k, g) in dg.iter().enumerate() {
            jac.fixed_view_mut::<3, 1>(r0, N_GEOMETRY + k)
                .copy_from(&(tangent * *g * scale));
        }
        p.centre + p.radius * radial
    }

    /// `(u, v, n)` of `p`.
    fn basis_of(p: &ArcParams) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        (p.u().into_inner(), p.v().into_inner(), p.normal().into_inner())
    }

    /// `d p_j / d theta_j`: how point `j` moves when its own joint angle (the actual
    /// displacement, `phi0 + D_j` in the model) changes alone, i.e. the arc's tangent
    /// `r (-sin(phi0 + D_j) u + cos(phi0 + D_j) v)` (points' unit per rad). This is what a
    /// re-positioning error of the swept joint moves the point by, to first order.
    pub fn angle_derivatives(&self, p: &ArcParams) -> Result<Vec<Vector3<f64>>, CalibrationError> {
        self.per_step(p, |s, c, u, v| p.radius * (-s * u + c * v))
    }

    /// [`Self::angle_derivatives`] read from the phase column of a whitened Jacobian at `p`
    /// ([`Self::whitened_residual_and_jacobian`]: `d p_j / d phase` is the same tangent),
    /// unwhitened by the one scale factor; `None` unless the whitening is that one scaling
    /// (isotropic noise). Equal to [`Self::angle_derivatives`] to rounding (one product and
    /// one quotient), without inverting the transmission again.
    pub fn angle_derivatives_from(&self, whitened_jacobian: &DMatrix<f64>) -> Option<Vec<Vector3<f64>>> {
        let w = self.isotropic_whitener?;
        (whitened_jacobian.nrows() == 3 * self.commands_rad.len() && whitened_jacobian.ncols() == self.n_params()).then(
            || {
                (0..self.commands_rad.len())
                    .map(|j| whitened_jacobian.fixed_view::<3, 1>(3 * j, 6).into_owned() / w)
                    .collect()
            },
        )
    }

    /// `d p_j / d delta` stacked (3n x n_params), unweighted, analytic.
    pub fn jacobian(&self, p: &ArcParams) -> Result<DMatrix<f64>, CalibrationError> {
        let mut j = DMatrix::zeros(3 * self.commands_rad.len(), self.n_params());
        let (u, v, n) = Self::basis_of(p);
        self.for_each_motion(&p.coefficients, |row, dj, dg| {
            Self::fill_row(p, (&u, &v, &n), (row, dj, dg), 1.0, &mut j);
        })?;
        Ok(j)
    }

    /// Whitened residuals `L^-1 (predicted - observed)` stacked.
    pub fn whitened_residual(
        &self,
        p: &ArcParams,
        observed: &[Point3<f64>],
    ) -> Result<nalgebra::DVector<f64>, CalibrationError> {
        let pred = self.predict(p)?;
        let mut r = nalgebra::DVector::zeros(3 * pred.len());
        for (k, (q, o)) in pred.iter().zip(observed).enumerate() {
            r.fixed_rows_mut::<3>(3 * k).copy_from(&(self.whiteners[k] * (q - o)));
        }
        Ok(r)
    }

    fn whiten_rows(&self, j: &mut DMatrix<f64>) {
        if let Some(w) = self.isotropic_whitener {
            *j *= w;
            return;
        }
        for (k, w) in self.whiteners.iter().enumerate() {
            for c in 0..j.ncols() {
                let col: Vector3<f64> = j.fixed_view::<3, 1>(3 * k, c).into_owned();
                j.fixed_view_mut::<3, 1>(3 * k, c).copy_from(&(w * col));
            }
        }
    }

    /// The whitened Jacobian `L^-1 dp/d delta`.
    pub fn whitened_jacobian(&self, p: &ArcParams) -> Result<DMatrix<f64>, CalibrationError> {
        let mut j = self.jacobian(p)?;
        self.whiten_rows(&mut j);
        Ok(j)
    }

    /// The whitened residual and Jacobian together (one transmission inversion per point):
    /// what one Levenberg-Marquardt evaluation needs.
    pub fn whitened_residual_and_jacobian(
        &self,
        p: &ArcParams,
        observed: &[Point3<f64>],
    ) -> Result<(nalgebra::DVector<f64>, DMatrix<f64>), CalibrationError> {
        let n = self.commands_rad.len();
        if observed.len() != n {
            return Err(CalibrationError::LengthMismatch {
                fit: FIT,
                what: "observed points",
                got: observed.len(),
                expected: n,
            });
        }
        let mut j = DMatrix::zeros(3 * n, self.n_params());
        let mut r = nalgebra::DVector::zeros(3 * n);
        let (u, v, normal) = Self::basis_of(p);
        // An isotropic whitener is applied as the rows are filled; per-point ones after.
        let scale = self.isotropic_whitener.unwrap_or(1.0);
        self.for_each_motion(&p.coefficients, |row, dj, dg| {
            let q = Self::fill_row(p, (&u, &v, &normal), (row, dj, dg), scale, &mut j);
            r.fixed_rows_mut::<3>(3 * row)
                .copy_from(&(self.whiteners[row] * (q - observed[row])));
        })?;
        if self.isotropic_whitener.is_none() {
            self.whiten_rows(&mut j);
        }
        Ok((r, j))
    }

    /// Fisher information `J^T W J` for Gaussian noise.
    pub fn fisher(&self, p: &ArcParams) -> Result<DMatrix<f64>, CalibrationError> {
        let j = self.whitened_jacobian(p)?;
        Ok(j.transpose() * j)
    }
}

/// Rows of the quantities judged by the estimators, in a reference basis `(u_ref, v_ref)`
/// perpendicular to the axis: `[dir_u, dir_v, pos_u, pos_v, coefficients..]` where `dir` are
/// the axis direction's components along `u_ref, v_ref` \[rad\] and `pos` the components of the
/// axis point closest to `reference` (points' unit).
pub fn axis_quantities(p: &ArcParams, reference: &Point3<f64>, u_ref: &Vector3<f64>, v_ref: &Vector3<f64>) -> Vec<f64> {
    let n = p.normal();
    let q = p.axis_point_near(reference);
    [n.dot(u_ref), n.dot(v_ref), q.coords.dot(u_ref), q.coords.dot(v_ref)]
        .into_iter()
        .chain(p.coefficients.iter().copied())
        .collect()
}

/// Gradient of [`axis_quantities`] with respect to `delta`, in the parameters' own basis
/// (`u_ref = u`, `v_ref = v`).
pub fn axis_quantities_gradient(p: &ArcParams, reference: &Point3<f64>) -> DMatrix<f64> {
    let m = p.coefficients.len();
    let mut g = DMatrix::zeros(4 + m, N_GEOMETRY + m);
    let (u, v, n) = (p.u().into_inner(), p.v().into_inner(), p.normal().into_inner());
    let h = (reference - p.centre).dot(&n);
    // dn/dtilt_u = -v, dn/dtilt_v = u.
    g[(0, 4)] = 1.0;
    g[(1, 3)] = -1.0;
    for k in 0..3 {
        g[(2, k)] = u[k];
        g[(3, k)] = v[k];
    }
    g[(2, 4)] = h;
    g[(3, 3)] = -h;
    for k in 0..m {
        g[(4 + k, N_GEOMETRY + k)] = 1.0;
    }
    g
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use approx::assert_relative_eq;

    pub(crate) fn sample_params() -> ArcParams {
        ArcParams {
            centre: Point3::new(0.2, -0.4, 0.9),
            frame: Rotation3::new(Vector3::new(0.3, -0.2, 0.5)),
            radius: 0.7,
            phase_rad: 0.4,
            coefficients: vec![0.0035, -0.0009],
        }
    }

    #[test]
    fn jacobian_matches_central_differences() {
        let model = ArcModel::new(
            TransmissionFitForm::Harmonic { order: 1 },
            &(0..6).map(|j| -0.2 + 0.15 * j as f64).collect::<Vec<_>>(),
            &MeasurementNoise::from_rms_3d(1.0),
        )
        .unwrap();
        let p = sample_params();
        let j = model.jacobian(&p).unwrap();
        let h = 1e-6;
        for k in 0..model.n_params() {
            let mut dp = vec![0.0; model.n_params()];
            dp[k] = h;
            let plus = model.predict(&p.perturbed(&dp)).unwrap();
            dp[k] = -h;
            let minus = model.predict(&p.perturbed(&dp)).unwrap();
            for (r, (a, b)) in plus.iter().zip(&minus).enumerate() {
                let fd = (a - b) / (2.0 * h);
                for c in 0..3 {
                    assert_relative_eq!(j[(3 * r + c, k)], fd[c], epsilon = 1e-8);
                }
            }
        }
    }

    #[test]
    fn angle_derivatives_match_central_differences_of_each_points_angle() {
        // Point j alone turned by h about the axis: the model with step j's motion D_j + h,
        // i.e. the phase moved by h evaluated at step j only.
        let forms = [
            TransmissionFitForm::Harmonic { order: 1 },
            TransmissionFitForm::Gear {
                ratio: 32.0 / 19.0,
                order: 1,
            },
        ];
        for form in forms {
            let commands: Vec<f64> = (0..7).map(|j| -0.6 + 0.2 * j as f64).collect();
            let model = ArcModel::new(form, &commands, &MeasurementNoise::from_rms_3d(1.0)).unwrap();
            let p = sample_params();
            let t = model.angle_derivatives(&p).unwrap();
            let h = 1e-6;
            let mut dp = vec![0.0; model.n_params()];
            dp[6] = h;
            let plus = model.predict(&p.perturbed(&dp)).unwrap();
            dp[6] = -h;
            let minus = model.predict(&p.perturbed(&dp)).unwrap();
            for (j, tj) in t.iter().enumerate() {
                let fd = (plus[j] - minus[j]) / (2.0 * h);
                assert_relative_eq!(*tj, fd, epsilon = 1e-8);
                // Tangential: perpendicular to the radius and the axis, of length r.
                assert_relative_eq!(tj.norm(), p.radius, epsilon = 1e-12);
                assert!(tj.dot(&p.normal()).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn angle_derivatives_from_the_whitened_jacobian_are_the_tangents() {
        let commands: Vec<f64> = (0..7).map(|j| -0.6 + 0.2 * j as f64).collect();
        let form = TransmissionFitForm::Gear { ratio: 1.7, order: 1 };
        let p = sample_params();
        let iso = ArcModel::new(form, &commands, &MeasurementNoise::from_rms_3d(3e-4)).unwrap();
        let observed = iso.predict(&p).unwrap();
        let (_, jw) = iso.whitened_residual_and_jacobian(&p, &observed).unwrap();
        let from = iso.angle_derivatives_from(&jw).unwrap();
        for (a, b) in from.iter().zip(&iso.angle_derivatives(&p).unwrap()) {
            // One product and one quotient by the whitener: a few ulps of |t| = r.
            assert_relative_eq!(*a, *b, epsilon = 4.0 * f64::EPSILON * p.radius);
        }
        assert!(iso.angle_derivatives_from(&jw.rows(0, 3).into_owned()).is_none());
        let per_point = MeasurementNoise::PerPoint(vec![Matrix3::identity() * 1e-8; commands.len()]);
        let aniso = ArcModel::new(form, &commands, &per_point).unwrap();
        assert!(aniso.angle_derivatives_from(&jw).is_none());
    }

    #[test]
    fn angle_noise_adds_a_rank_one_term_per_point() {
        let t = [Vector3::new(0.0, 0.7, 0.0), Vector3::new(-0.3, 0.2, 0.1)];
        let iso = MeasurementNoise::Isotropic { sigma_per_axis: 1e-4 };
        let MeasurementNoise::PerPoint(c) = iso.with_angle_noise(&t, 2e-4).unwrap() else {
            panic!("per-point covariance expected")
        };
        for (cj, tj) in c.iter().zip(&t) {
            let expected = Matrix3::identity() * 1e-8 + tj * tj.transpose() * 4e-8;
            assert_relative_eq!(*cj, expected, epsilon = 1e-20);
        }
        // Along the tangent the variance grows by (sigma_theta |t|)^2; across it, not at all.
        let across = Vector3::new(1.0, 0.0, 0.0);
        assert_relative_eq!((across.transpose() * c[0] * across)[0], 1e-8, epsilon = 1e-20);
        assert!(iso.with_angle_noise(&t, -1.0).is_err());
        let short = MeasurementNoise::PerPoint(vec![Matrix3::identity()]);
        assert!(short.with_angle_noise(&t, 1e-4).is_err());
    }

    #[test]
    fn quantity_gradient_matches_central_differences() {
        let p = sample_params();
        let reference = Point3::new(1.0, 0.5, -0.3);
        let g = axis_quantities_gradient(&p, &reference);
        let (u, v) = (p.u().into_inner(), p.v().into_inner());
        let h = 1e-6;
        for k in 0..p.coefficients.len() + N_GEOMETRY {
            let mut dp = vec![0.0; g.ncols()];
            dp[k] = h;
            let a = axis_quantities(&p.perturbed(&dp), &reference, &u, &v);
            dp[k] = -h;
            let b = axis_quantities(&p.perturbed(&dp), &reference, &u, &v);
            for r in 0..a.len() {
                assert_relative_eq!(g[(r, k)], (a[r] - b[r]) / (2.0 * h), epsilon = 1e-7);
            }
        }
    }
}
