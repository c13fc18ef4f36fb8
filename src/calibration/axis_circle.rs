//! Initial circle fit of an arc of observed points: an SVD plane fit, then Kasa's algebraic
//! circle fit in that plane (Kasa 1976: `x^2 + y^2 = 2 a x + 2 b y + c`, linear least squares).
//!
//! This is the starting point of the efficient estimator ([`super::arc_ml`]) and of the paper's
//! estimator ([`super::axis_paper`]); it is unit-agnostic (centre and radius come out in the
//! points' unit).

use nalgebra::{DMatrix, DVector, Matrix3, Point3, Unit, Vector3};

use super::CalibrationError;
use crate::numerics::lsq;

const FIT: &str = "circle fit";

/// Smallest ratio of the second to the first singular value of the centred points that is
/// still a plane (below it the points are collinear).
const COLLINEAR_RATIO: f64 = 1e-9;

/// A circle in space fitted to an arc of points.
#[derive(Clone, Debug, PartialEq)]
pub struct CircleFit {
    /// Centre of the circle (points' unit).
    pub centre: Point3<f64>,
    /// Plane normal, oriented so the points advance positively (right-handed) about it in
    /// the order given: the rotation axis direction of the arc.
    pub normal: Unit<Vector3<f64>>,
    /// In-plane unit vector from the centre towards the first point.
    pub u: Unit<Vector3<f64>>,
    /// `normal x u`: `(u, v, normal)` is right-handed.
    pub v: Unit<Vector3<f64>>,
    /// Radius (points' unit).
    pub radius: f64,
    /// RMS distance of the points from the plane.
    pub plane_rms: f64,
    /// RMS of the in-plane radial residuals.
    pub radial_rms: f64,
    /// Angle subtended by the points about the centre, first to last \[rad\].
    pub span_rad: f64,
}

/// The plane of an arc's points: their mean, the two in-plane principal directions and the
/// singular values of the centred points, largest first.
struct PlaneFit {
    /// Mean of the points.
    mean: Vector3<f64>,
    /// First principal direction.
    e1: Vector3<f64>,
    /// Second principal direction.
    e2: Vector3<f64>,
    /// The largest singular value.
    s0: f64,
    /// The second one.
    s1: f64,
    /// The smallest one (the spread out of the plane).
    s2: f64,
}

/// At least 3 points, all finite.
fn check_points(points: &[Point3<f64>]) -> Result<(), CalibrationError> {
    let n = points.len();
    if n < 3 {
        return Err(CalibrationError::TooFewPoints {
            fit: FIT,
            got: n,
            needed: 3,
        });
    }
    if points.iter().any(|p| !p.coords.iter().all(|c| c.is_finite())) {
        return Err(CalibrationError::InvalidInput {
            fit: FIT,
            what: "non-finite coordinate",
        });
    }
    Ok(())
}

/// The SVD plane fit of the points (not all equal, not collinear).
fn fit_plane(points: &[Point3<f64>]) -> Result<PlaneFit, CalibrationError> {
    let n = points.len();
    let mean = points.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / n as f64;
    let scatter: Matrix3<f64> = points
        .iter()
        .map(|p| (p.coords - mean) * (p.coords - mean).transpose())
        .sum();
    let eig = scatter.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let s0 = eig.eigenvalues[order[0]].max(0.0).sqrt();
    let s1 = eig.eigenvalues[order[1]].max(0.0).sqrt();
    let s2 = eig.eigenvalues[order[2]].max(0.0).sqrt();
    if s0 == 0.0 {
        return Err(CalibrationError::ZeroSpan { fit: FIT });
    }
    if s1 / s0 < COLLINEAR_RATIO {
        return Err(CalibrationError::Collinear {
            fit: FIT,
            ratio: s1 / s0,
        });
    }
    let e1: Vector3<f64> = eig.eigenvectors.column(order[0]).into();
    let e2: Vector3<f64> = eig.eigenvectors.column(order[1]).into();
    Ok(PlaneFit {
        mean,
        e1,
        e2,
        s0,
        s1,
        s2,
    })
}

/// Kasa's fit in the plane: `x^2 + y^2 = 2 a x + 2 b y + c` in the plane coordinates `(e1, e2)`;
/// the centre and the radius.
fn kasa_circle(points: &[Point3<f64>], plane: &PlaneFit) -> Result<(Point3<f64>, f64), CalibrationError> {
    let n = points.len();
    let PlaneFit {
        mean, e1, e2, s0, s1, ..
    } = *plane;
    let xy: Vec<(f64, f64)> = points
        .iter()
        .map(|p| ((p.coords - mean).dot(&e1), (p.coords - mean).dot(&e2)))
        .collect();
    let a = DMatrix::from_fn(n, 3, |r, c| match c {
        0 => 2.0 * xy[r].0,
        1 => 2.0 * xy[r].1,
        _ => 1.0,
    });
    let y = DVector::from_fn(n, |r, _| xy[r].0 * xy[r].0 + xy[r].1 * xy[r].1);
    let (sol, _, _) = lsq::linear_lsq(&a, &y, FIT)?;
    let radius_sq = sol[2] + sol[0] * sol[0] + sol[1] * sol[1];
    if radius_sq.is_nan() || radius_sq <= 0.0 {
        return Err(CalibrationError::Collinear {
            fit: FIT,
            ratio: s1 / s0,
        });
    }
    let radius = radius_sq.sqrt();
    let centre = Point3::from(mean + sol[0] * e1 + sol[1] * e2);
    Ok((centre, radius))
}

/// RMS of the in-plane radial residuals of the points about the circle (`centre`, `normal`,
/// `radius`).
fn radial_rms(points: &[Point3<f64>], centre: Point3<f64>, normal: &Unit<Vector3<f64>>, radius: f64) -> f64 {
    let n = points.len();
    (points
        .iter()
        .map(|p| {
            let d = p - centre;
            let inplane = d - d.dot(normal) * normal.into_inner();
            (inplane.norm() - radius).powi(2)
        })
        .sum::<f64>()
        / n as f64)
        .sqrt()
}

/// Fit a circle to `points` (at least 3, not collinear), eqs. none: the paper leaves the
/// initial guess to the user; this is a standard SVD plane + Kasa fit.
pub fn fit_circle(points: &[Point3<f64>]) -> Result<CircleFit, CalibrationError> {
    check_points(points)?;
    let n = points.len();
    let plane = fit_plane(points)?;
    let mut normal: Vector3<f64> = plane.e1.cross(&plane.e2).normalize();
    let (centre, radius) = kasa_circle(points, &plane)?;

    // Orient the normal so the sequence turns positively about it.
    let turn: f64 = points
        .windows(2)
        .map(|w| (w[0] - centre).cross(&(w[1] - centre)).dot(&normal))
        .sum();
    if turn < 0.0 {
        normal = -normal;
    }
    let to_first = points[0] - centre;
    let u = Unit::new_normalize(to_first - to_first.dot(&normal) * normal);
    let normal = Unit::new_unchecked(normal);
    let v = Unit::new_normalize(normal.cross(&u));
    let radial_rms = radial_rms(points, centre, &normal, radius);
    let last = points[n - 1] - centre;
    let span_rad = last.dot(&v).atan2(last.dot(&u)).rem_euclid(std::f64::consts::TAU);
    Ok(CircleFit {
        centre,
        normal,
        u,
        v,
        radius,
        plane_rms: plane.s2 / (n as f64).sqrt(),
        radial_rms,
        span_rad,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn arc(n: usize, span: f64) -> (Vec<Point3<f64>>, Point3<f64>, Vector3<f64>) {
        let c = Point3::new(0.3, -1.2, 0.5);
        let axis = Vector3::new(0.2, -0.3, 0.93).normalize();
        let u = axis.cross(&Vector3::x()).normalize();
        let v = axis.cross(&u);
        let pts = (0..n)
            .map(|j| {
                let t = 0.1 + span * j as f64 / (n - 1) as f64;
                c + 0.7 * (t.cos() * u + t.sin() * v)
            })
            .collect();
        (pts, c, axis)
    }

    #[test]
    fn recovers_an_exact_arc() {
        let (pts, c, axis) = arc(16, 0.785);
        let f = fit_circle(&pts).unwrap();
        assert_relative_eq!(f.centre, c, epsilon = 1e-9);
        assert_relative_eq!(f.normal.into_inner(), axis, epsilon = 1e-9);
        assert_relative_eq!(f.radius, 0.7, epsilon = 1e-9);
        assert_relative_eq!(f.span_rad, 0.785, epsilon = 1e-9);
    }

    #[test]
    fn reversed_order_flips_the_normal() {
        let (mut pts, _, axis) = arc(8, 1.0);
        pts.reverse();
        let f = fit_circle(&pts).unwrap();
        assert_relative_eq!(f.normal.into_inner(), -axis, epsilon = 1e-9);
    }

    #[test]
    fn degenerate_inputs_are_errors() {
        let p = Point3::new(1.0, 2.0, 3.0);
        assert!(matches!(
            fit_circle(&[p, p]),
            Err(CalibrationError::TooFewPoints { got: 2, .. })
        ));
        assert!(matches!(fit_circle(&[p, p, p]), Err(CalibrationError::ZeroSpan { .. })));
        let line: Vec<_> = (0..5).map(|k| p + Vector3::new(1.0, 1.0, 0.0) * k as f64).collect();
        assert!(matches!(fit_circle(&line), Err(CalibrationError::Collinear { .. })));
    }
}
