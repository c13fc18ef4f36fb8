//! The paper's rotary-axis estimator, eqs. (1)-(5).
//!
//! The candidate axis frame `i` is placed from the base (instrument) frame by a `phi_0` frame
//! (eq. A2 about the base Z with zero displacement) and a phi-model row `(a, b, alpha, beta)`
//! (eq. A3): `base_from_axis = 0T_phi * phiT_i`, so eq. (2) is its inverse. Each observed point
//! is expressed in the candidate frame (eq. 1) and Gauss-Newton (eq. 5, `J` of size
//! `2(n-1) x 4`, analytic) drives to zero the axial residuals `p_iz^j - p_iz^0` (eq. 3) and the
//! radial residuals of eq. (4), `(p_ix^j - p_ix^0)(p_ix^j + p_ix^0) + (..y..)`, here divided
//! by `2 r_0` (`r_0` = the initial circle radius) so both kinds are lengths and the answer
//! does not depend on the unit (a constant weight: the minimiser of eq. 4 alone is unchanged).
//! `phi_0` is chosen so `Z_phi0` is perpendicular to the nominal axis (never parallel).
//! Joint readings are not used.

use nalgebra::{DMatrix, DVector, Isometry3, Point3, Unit, Vector3};

use super::CalibrationError;
use super::axis_circle::fit_circle;
use crate::kinematics::{AxisLine, PhiRow, frame_from_phi};
use crate::numerics::lsq;

const FIT: &str = "paper axis fit (eqs. 1-5)";

/// The result of [`fit_axis_paper`].
#[derive(Clone, Debug, PartialEq)]
pub struct PaperAxisFit {
    /// Angle of `Z_phi0` from the base X axis \[rad\].
    pub phi0_rad: f64,
    /// The fitted row `(a, b, alpha, beta)` (lengths in the points' unit).
    pub row: PhiRow,
    /// The axis frame `i` in the base frame (`0T_phi * phiT_i`).
    pub base_from_axis: Isometry3<f64>,
    /// The axis: origin of frame `i` and `+Z_i`, oriented so the points advance positively.
    pub axis: AxisLine,
    /// Gauss-Newton iterations used.
    pub iterations: usize,
    /// RMS of the axial residuals (eq. 3) at the solution (points' unit).
    pub axial_rms: f64,
    /// RMS of the scaled radial residuals (eq. 4 / 2 r_0) at the solution (points' unit).
    pub radial_rms: f64,
    /// Column-scaled condition number of `J` at the solution.
    pub condition_number: f64,
}

impl PaperAxisFit {
    /// The points expressed in the axis frame (eq. 1).
    pub fn points_in_axis_frame(&self, points: &[Point3<f64>]) -> Vec<Point3<f64>> {
        let inv = self.base_from_axis.inverse();
        points.iter().map(|p| inv * p).collect()
    }
}

/// `phi_0` putting `Z_phi0` (in the base XY plane) perpendicular to `direction`.
pub fn phi0_for(direction: &Vector3<f64>) -> f64 {
    direction.y.atan2(direction.x) + std::f64::consts::FRAC_PI_2
}

/// The phi-model row placing a line (point, unit direction, base frame) from the `phi0` frame.
pub fn row_for_line(phi0_rad: f64, point: &Point3<f64>, direction: &Vector3<f64>) -> Result<PhiRow, CalibrationError> {
    let to_phi = frame_from_phi(phi0_rad, 0.0, 0.0).inverse();
    let p = to_phi * point;
    let d = to_phi * direction;
    let z = Vector3::z();
    let x = z.cross(&d);
    let sin_alpha = x.norm();
    if sin_alpha < 1e-9 {
        return Err(CalibrationError::IllConditioned {
            fit: FIT,
            condition_number: 1.0 / sin_alpha.max(f64::MIN_POSITIVE),
        });
    }
    let x = x / sin_alpha;
    let b_ = z.dot(&d);
    let (dz, dd) = (z.dot(&-p.coords), d.dot(&-p.coords));
    let den = 1.0 - b_ * b_;
    let a = (b_ * dd - dz) / den;
    let t = (dd - b_ * dz) / den;
    let foot = p.coords + t * d;
    let b = (foot - a * z).dot(&x);
    Ok(PhiRow::new(a, b, sin_alpha.atan2(b_), x.y.atan2(x.x)))
}

/// `(residuals, J)` of eqs. (3)-(4) at `params = [a, b, alpha, beta]`.
fn residuals(phi0: f64, params: &[f64], points: &[Point3<f64>], scale: f64) -> (DVector<f64>, DMatrix<f64>) {
    let row = PhiRow::new(params[0], params[1], params[2], params[3]);
    let base_from_phi = frame_from_phi(phi0, 0.0, 0.0);
    let phi_from_base = base_from_phi.inverse();
    let rx = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), -params[2]);
    let rz = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), -params[3]);
    let axis_from_base = (base_from_phi * row.phi_from_next()).inverse();
    let rx_ez = rx * Vector3::z();
    let per_point: Vec<(Vector3<f64>, [Vector3<f64>; 4])> = points
        .iter()
        .map(|p0| {
            let p = (axis_from_base * p0).coords;
            let w = (phi_from_base * p0).coords;
            let w2 = rz * (w - params[0] * Vector3::z());
            let d = [
                -rx_ez,
                -Vector3::x(),
                -Vector3::x().cross(&p),
                rx * (-Vector3::z().cross(&w2)),
            ];
            (p, d)
        })
        .collect();
    let n = points.len();
    let mut r = DVector::zeros(2 * (n - 1));
    let mut j = DMatrix::zeros(2 * (n - 1), 4);
    let (p0, d0) = &per_point[0];
    for (k, (p, d)) in per_point.iter().enumerate().skip(1) {
        let row = 2 * (k - 1);
        r[row] = p.z - p0.z;
        r[row + 1] = (p.x * p.x + p.y * p.y - p0.x * p0.x - p0.y * p0.y) / (2.0 * scale);
        for c in 0..4 {
            j[(row, c)] = d[c].z - d0[c].z;
            j[(row + 1, c)] = (p.x * d[c].x + p.y * d[c].y - p0.x * d0[c].x - p0.y * d0[c].y) / scale;
        }
    }
    (r, j)
}

/// Fit the axis of a rotary joint from the observed `points` (base frame), eqs. (1)-(5).
/// `nominal_direction` chooses `phi_0` (the circle fit's normal when `None`).
pub fn fit_axis_paper(
    points: &[Point3<f64>],
    nominal_direction: Option<&Unit<Vector3<f64>>>,
    max_iterations: usize,
) -> Result<PaperAxisFit, CalibrationError> {
    if points.len() < 3 {
        return Err(CalibrationError::TooFewPoints {
            fit: FIT,
            got: points.len(),
            needed: 3,
        });
    }
    let circle = fit_circle(points)?;
    let normal = circle.normal.into_inner();
    let phi0 = phi0_for(&nominal_direction.map_or(normal, |d| d.into_inner()));
    let start = row_for_line(phi0, &circle.centre, &normal)?;
    let scale = circle.radius;
    let x0 = DVector::from_vec(vec![start.a_m, start.b_m, start.alpha_rad, start.beta_rad]);
    let small = |step: &DVector<f64>| (step[0].abs() + step[1].abs()) / scale + step[2].abs() + step[3].abs() < 1e-12;
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
        |x: &DVector<f64>| Ok::<_, CalibrationError>(residuals(phi0, x.as_slice(), points, scale)),
        |x, step| Ok(x + step),
    )?
    .converged(FIT, None)?;
    let (x, r, j, iterations) = (outcome.state, outcome.residual, outcome.jacobian, outcome.iterations);
    let row = PhiRow::new(x[0], x[1], x[2], x[3]);
    let base_from_axis = frame_from_phi(phi0, 0.0, 0.0) * row.phi_from_next();
    let mut direction = base_from_axis * Vector3::z();
    // The fitted row may point Z_i either way: orient it with the motion (right-handed).
    let mut base_from_axis = base_from_axis;
    if direction.dot(&normal) < 0.0 {
        direction = -direction;
        base_from_axis *= Isometry3::rotation(Vector3::x() * std::f64::consts::PI);
    }
    let m = r.len() / 2;
    let sq = |o: usize| ((0..m).map(|k| r[2 * k + o].powi(2)).sum::<f64>() / m as f64).sqrt();
    Ok(PaperAxisFit {
        phi0_rad: phi0,
        row,
        axis: AxisLine {
            origin_m: base_from_axis * Point3::origin(),
            direction: Unit::new_normalize(direction),
        },
        base_from_axis,
        iterations,
        axial_rms: sq(0),
        radial_rms: sq(1),
        condition_number: lsq::scaled_condition_number(&j),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn arc(scale: f64) -> (Vec<Point3<f64>>, Point3<f64>, Vector3<f64>) {
        let c = Point3::new(1.2, -0.4, 0.8) * scale;
        let axis = Vector3::new(0.3, 0.1, 0.95).normalize();
        let u = axis.cross(&Vector3::y()).normalize();
        let v = axis.cross(&u);
        let pts = (0..16)
            .map(|j| {
                let t = 0.785 * j as f64 / 15.0;
                let wobble = 1e-4 * scale * (3.0 * t).sin();
                c + 0.7 * scale * (t.cos() * u + t.sin() * v) + wobble * axis
            })
            .collect();
        (pts, c, axis)
    }

    #[test]
    fn recovers_an_exact_axis() {
        let (pts, c, axis) = arc(1.0);
        let pts: Vec<_> = pts.iter().map(|p| p - axis * (p - c).dot(&axis) + axis * 0.0).collect();
        let fit = fit_axis_paper(&pts, None, 50).unwrap();
        assert_relative_eq!(fit.axis.direction.into_inner(), axis, epsilon = 1e-10);
        let off = fit.axis.origin_m - c;
        assert_relative_eq!((off - axis * off.dot(&axis)).norm(), 0.0, epsilon = 1e-10);
        assert!(fit.axial_rms < 1e-12);
    }

    #[test]
    fn millimetres_and_metres_agree() {
        let (m, _, _) = arc(1.0);
        let (mm, _, _) = arc(1000.0);
        let a = fit_axis_paper(&m, None, 50).unwrap();
        let b = fit_axis_paper(&mm, None, 50).unwrap();
        assert_relative_eq!(a.row.a_m * 1000.0, b.row.a_m, epsilon = 1e-8);
        assert_relative_eq!(a.row.b_m * 1000.0, b.row.b_m, epsilon = 1e-8);
        assert_relative_eq!(a.row.alpha_rad, b.row.alpha_rad, epsilon = 1e-11);
        assert_relative_eq!(a.row.beta_rad, b.row.beta_rad, epsilon = 1e-11);
    }

    #[test]
    fn jacobian_matches_central_differences() {
        let (pts, _, _) = arc(1.0);
        let x = [0.05, -0.3, 1.2, -0.4];
        let (_, j) = residuals(0.7, &x, &pts, 0.7);
        let h = 1e-6;
        for c in 0..4 {
            let mut xp = x;
            xp[c] += h;
            let mut xm = x;
            xm[c] -= h;
            let fd = (residuals(0.7, &xp, &pts, 0.7).0 - residuals(0.7, &xm, &pts, 0.7).0) / (2.0 * h);
            for r in 0..fd.len() {
                assert_relative_eq!(j[(r, c)], fd[r], epsilon = 1e-7);
            }
        }
    }

    #[test]
    fn row_for_line_round_trips() {
        let p = Point3::new(0.3, -0.2, 0.5);
        let d = Vector3::new(0.1, 0.9, 0.2).normalize();
        let phi0 = phi0_for(&d);
        let row = row_for_line(phi0, &p, &d).unwrap();
        let t = frame_from_phi(phi0, 0.0, 0.0) * row.phi_from_next();
        assert_relative_eq!(t * Vector3::z(), d, epsilon = 1e-12);
        let o = t * Point3::origin() - p;
        assert_relative_eq!((o - d * o.dot(&d)).norm(), 0.0, epsilon = 1e-12);
    }
}
