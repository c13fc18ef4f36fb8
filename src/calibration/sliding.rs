//! Sliding-axis fit, eqs. (9)-(13): only the direction of a prismatic axis matters
//! (`a = b = 0`, eq. 9); `(alpha, beta)` place `Z_i` from the `phi_0` frame and Gauss-Newton
//! (eq. 11, `J` of size `2(n-1) x 2`, analytic) zeroes the X and Y motion of the points in the
//! axis frame (eq. 10). Displacements are the Z differences (eq. 12) and a polynomial
//! `S_c - S_c^0 = sum_k c_k S^k` is fitted to the commands (eq. 13).

use nalgebra::{DMatrix, DVector, Isometry3, Point3, Rotation3, Unit, Vector3};

use super::CalibrationError;
use super::axis_paper::phi0_for;
use crate::kinematics::{PhiRow, frame_from_phi};
use crate::numerics::lsq;

const FIT: &str = "sliding axis fit (eqs. 9-13)";

/// The result of [`fit_sliding_axis`].
#[derive(Clone, Debug, PartialEq)]
pub struct SlidingAxisFit {
    /// Angle of `Z_phi0` from the base X axis \[rad\].
    pub phi0_rad: f64,
    /// Fitted `alpha` \[rad\].
    pub alpha_rad: f64,
    /// Fitted `beta` \[rad\].
    pub beta_rad: f64,
    /// The axis frame (origin at the base origin, eq. 9) in the base frame.
    pub base_from_axis: Isometry3<f64>,
    /// Unit axis direction, oriented along the motion.
    pub direction: Unit<Vector3<f64>>,
    /// Displacement from step 0 along the axis (eq. 12 accumulated; points' unit).
    pub displacements: Vec<f64>,
    /// Gauss-Newton iterations used.
    pub iterations: usize,
}

fn residuals(phi0: f64, x: &[f64], points: &[Point3<f64>]) -> (DVector<f64>, DMatrix<f64>, Vec<Vector3<f64>>) {
    let phi_from_base = frame_from_phi(phi0, 0.0, 0.0).inverse();
    let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), -x[0]);
    let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), -x[1]);
    let pts: Vec<(Vector3<f64>, [Vector3<f64>; 2])> = points
        .iter()
        .map(|p0| {
            let w2 = rz * (phi_from_base * p0).coords;
            let p = rx * w2;
            (p, [-Vector3::x().cross(&p), rx * (-Vector3::z().cross(&w2))])
        })
        .collect();
    let n = points.len();
    let mut r = DVector::zeros(2 * (n - 1));
    let mut j = DMatrix::zeros(2 * (n - 1), 2);
    let (p0, d0) = pts[0];
    for (k, (p, d)) in pts.iter().enumerate().skip(1) {
        r[2 * (k - 1)] = p.x - p0.x;
        r[2 * k - 1] = p.y - p0.y;
        for c in 0..2 {
            j[(2 * (k - 1), c)] = d[c].x - d0[c].x;
            j[(2 * k - 1, c)] = d[c].y - d0[c].y;
        }
    }
    (r, j, pts.into_iter().map(|p| p.0).collect())
}

/// Fit the direction of a sliding axis from points observed along its motion (base frame).
pub fn fit_sliding_axis(points: &[Point3<f64>], max_iterations: usize) -> Result<SlidingAxisFit, CalibrationError> {
    let n = points.len();
    if n < 2 {
        return Err(CalibrationError::TooFewPoints {
            fit: FIT,
            got: n,
            needed: 2,
        });
    }
    let motion = points[n - 1] - points[0];
    if motion.norm() == 0.0 {
        return Err(CalibrationError::ZeroSpan { fit: FIT });
    }
    let d = motion.normalize();
    let phi0 = phi0_for(&d);
    let dp = frame_from_phi(phi0, 0.0, 0.0).inverse() * d;
    // Z_i = (sin b sin a, -cos b sin a, cos a) in the phi frame.
    let x0 = DVector::from_vec(vec![dp.z.clamp(-1.0, 1.0).acos(), dp.x.atan2(-dp.y)]);
    let small = |step: &DVector<f64>| step.amax() < 1e-13;
    let options = lsq::LmOptions {
        damping: lsq::Damping::GaussNewton {
            truncate_below: None,
            monotone: false,
        },
        small_step: Some(&small),
        ..lsq::LmOptions::marquardt(FIT, max_iterations)
    };
    let outcome = lsq::levenberg_marquardt(
        x0,
        &options,
        |x: &DVector<f64>| {
            let (r, j, _) = residuals(phi0, x.as_slice(), points);
            Ok::<_, CalibrationError>((r, j))
        },
        |x, step| Ok(x + step),
    )?
    .converged(FIT, None)?;
    let (x, iterations) = (outcome.state, outcome.iterations);
    let (_, _, local) = residuals(phi0, x.as_slice(), points);
    let base_from_axis = frame_from_phi(phi0, 0.0, 0.0) * PhiRow::new(0.0, 0.0, x[0], x[1]).phi_from_next();
    let mut direction = base_from_axis * Vector3::z();
    let mut sign = 1.0;
    if direction.dot(&motion) < 0.0 {
        direction = -direction;
        sign = -1.0;
    }
    Ok(SlidingAxisFit {
        phi0_rad: phi0,
        alpha_rad: x[0],
        beta_rad: x[1],
        base_from_axis,
        direction: Unit::new_normalize(direction),
        displacements: local.iter().map(|p| sign * (p.z - local[0].z)).collect(),
        iterations,
    })
}

/// The result of [`fit_sliding_function`].
#[derive(Clone, Debug, PartialEq)]
pub struct SlidingFunctionFit {
    /// `c_1..c_d` of `S_c - S_c^0 = sum_k c_k S^k`.
    pub coefficients: Vec<f64>,
    /// 1-sigma of each coefficient, a-posteriori.
    pub sigma: Vec<f64>,
    /// RMS of the residuals (command unit).
    pub residual_rms: f64,
}

/// Eq. (13): polynomial of `degree` from observed displacements (from step 0) to commands.
pub fn fit_sliding_function(
    displacements: &[f64],
    commands: &[f64],
    degree: usize,
) -> Result<SlidingFunctionFit, CalibrationError> {
    let n = displacements.len();
    if commands.len() != n {
        return Err(CalibrationError::LengthMismatch {
            fit: FIT,
            what: "commands",
            got: commands.len(),
            expected: n,
        });
    }
    if n < degree + 2 {
        return Err(CalibrationError::TooFewPoints {
            fit: FIT,
            got: n,
            needed: degree + 2,
        });
    }
    let a = DMatrix::from_fn(n - 1, degree, |r, k| displacements[r + 1].powi(k as i32 + 1));
    let y = DVector::from_fn(n - 1, |r, _| commands[r + 1] - commands[0]);
    let (c, inv, res) = lsq::linear_lsq(&a, &y, FIT)?;
    let s2 = res.norm_squared() / (n - 1 - degree).max(1) as f64;
    Ok(SlidingFunctionFit {
        coefficients: c.iter().copied().collect(),
        sigma: (0..degree).map(|k| (s2 * inv[(k, k)]).sqrt()).collect(),
        residual_rms: (res.norm_squared() / (n - 1) as f64).sqrt(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn recovers_direction_displacements_and_function() {
        let d = Vector3::new(0.2, -0.5, 0.84).normalize();
        let start = Point3::new(0.4, 1.0, -0.2);
        let s: Vec<f64> = (0..10).map(|j| 0.03 * j as f64).collect();
        let pts: Vec<Point3<f64>> = s.iter().map(|v| start + d * *v).collect();
        let fit = fit_sliding_axis(&pts, 50).unwrap();
        assert_relative_eq!(fit.direction.into_inner(), d, epsilon = 1e-12);
        for (a, b) in fit.displacements.iter().zip(&s) {
            assert_relative_eq!(a, b, epsilon = 1e-12);
        }
        let commands: Vec<f64> = s.iter().map(|v| 1.0 + 1.01 * v - 0.2 * v * v).collect();
        let f = fit_sliding_function(&fit.displacements, &commands, 2).unwrap();
        assert_relative_eq!(f.coefficients[0], 1.01, epsilon = 1e-9);
        assert_relative_eq!(f.coefficients[1], -0.2, epsilon = 1e-8);
    }

    #[test]
    fn jacobian_matches_central_differences() {
        let pts: Vec<Point3<f64>> = (0..5)
            .map(|j| Point3::new(0.1 * j as f64, 0.3, -0.02 * j as f64))
            .collect();
        let x = [1.3, -0.4];
        let (_, j, _) = residuals(0.5, &x, &pts);
        let h = 1e-6;
        for c in 0..2 {
            let (mut xp, mut xm) = (x, x);
            xp[c] += h;
            xm[c] -= h;
            let fd = (residuals(0.5, &xp, &pts).0 - residuals(0.5, &xm, &pts).0) / (2.0 * h);
            for r in 0..fd.len() {
                assert_relative_eq!(j[(r, c)], fd[r], epsilon = 1e-8);
            }
        }
    }
}
