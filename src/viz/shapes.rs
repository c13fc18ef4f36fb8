//! The shapes a recording draws, computed without the recorder (so that they are tested in
//! every build): a fitted arc's points, one box per link segment, the four-bar's closed loop,
//! and the error vectors between two point lists.

use crate::calibration::ArcFit;
use crate::robot::FourBarGeometry;
use nalgebra::{Isometry3, Point3, Rotation3, Unit, UnitQuaternion, Vector3};

/// `samples` points of the fitted arc of `fit` over the swept range of `commands_rad`, in the
/// fit's unit: `p(D) = c + r (cos(phi0 + D) u + sin(phi0 + D) v)` for `D` from the smallest to
/// the largest `D_j = f^-1(theta_c^j) - f^-1(theta_c^0)` (the arc model of
/// [`crate::calibration::arc_model`], paper eqs. 6-8). Commands that the fitted transmission
/// cannot invert are skipped; `None` if none is left.
pub fn arc_points(fit: &ArcFit, commands_rad: &[f64], samples: usize) -> Option<Vec<Point3<f64>>> {
    let d: Vec<f64> = commands_rad
        .iter()
        .filter_map(|&c| fit.transmission.actual_from_command(c))
        .map(|a| a - fit.actual_start_rad)
        .collect();
    let lo = d.iter().copied().reduce(f64::min)?;
    let hi = d.iter().copied().reduce(f64::max)?;
    let p = &fit.params;
    let (u, v) = (p.u().into_inner(), p.v().into_inner());
    let samples = samples.max(2);
    Some(
        (0..samples)
            .map(|i| {
                let dj = lo + (hi - lo) * i as f64 / (samples - 1) as f64;
                let (s, c) = (p.phase_rad + dj).sin_cos();
                p.centre + p.radius * (c * u + s * v)
            })
            .collect(),
    )
}

/// One box per segment `points[i] -> points[i+1]` of a polyline: `(centre, half sizes,
/// rotation)`, the box's local x along the segment, `half_width` across. Zero-length segments
/// are skipped.
pub fn segment_boxes(
    points_m: &[Point3<f64>],
    half_width_m: f64,
) -> Vec<(Point3<f64>, Vector3<f64>, UnitQuaternion<f64>)> {
    points_m
        .windows(2)
        .filter_map(|w| {
            let d = w[1] - w[0];
            let length = d.norm();
            if length <= f64::EPSILON {
                return None;
            }
            let rotation = UnitQuaternion::rotation_between(&Vector3::x(), &d)
                // x and d antiparallel: half a turn about z.
                .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI));
            Some((
                nalgebra::center(&w[0], &w[1]),
                Vector3::new(length / 2.0, half_width_m, half_width_m),
                rotation,
            ))
        })
        .collect()
}

/// The closed loop `O2 -> C -> P -> O3 -> O2` of the 2->3 four-bar (the planar construction
/// documented with [`FourBarGeometry`]: arm, crank, rod, lever) in the world \[m\]: the linkage's plane is the one
/// through `O2` (origin of `world_from_frame2`, the fixed frame of axis 2) normal to axis 2;
/// its planar x axis is the arm direction `O2 -> O3` (projected in the plane) turned back by
/// `theta_2_rad`, the active displacement of joint 2; `passive_rad` is `g(theta_2)`.
pub fn four_bar_loop_m(
    geometry: &FourBarGeometry,
    world_from_frame2: &Isometry3<f64>,
    axis3_point_m: &Point3<f64>,
    theta_2_rad: f64,
    passive_rad: f64,
) -> [Point3<f64>; 5] {
    let o2 = world_from_frame2 * Point3::origin();
    let n = world_from_frame2 * Vector3::z_axis();
    let to_o3 = axis3_point_m - o2;
    let in_plane = to_o3 - n.into_inner() * n.dot(&to_o3);
    let arm = Unit::try_new(in_plane, 1e-9).unwrap_or(world_from_frame2 * Vector3::x_axis());
    let ex = Rotation3::from_axis_angle(&n, -theta_2_rad) * arm.into_inner();
    let ey = n.cross(&ex);
    let at = |radius: f64, angle: f64| radius * (angle.cos() * ex + angle.sin() * ey);
    let g = geometry;
    let o3 = o2 + at(g.arm_m, theta_2_rad);
    let c = o2 + at(g.crank_m, g.crank_angle_rad);
    let p = o3 + at(g.lever_m, theta_2_rad + g.lever_angle_rad + passive_rad);
    [o2, c, p, o3, o2]
}

/// Two point lists that must match in length do not.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{what}: expected {expected} items, found {found}")]
pub struct LengthMismatch {
    /// What was drawn.
    pub what: &'static str,
    /// Expected count.
    pub expected: usize,
    /// Found count.
    pub found: usize,
}

/// The vectors `to_m[i] - from_m[i]` \[m\] (error vectors: measured minus commanded or
/// predicted point); an error if the lists differ in length.
pub fn vectors_between(from_m: &[Point3<f64>], to_m: &[Point3<f64>]) -> Result<Vec<Vector3<f64>>, LengthMismatch> {
    if from_m.len() != to_m.len() {
        return Err(LengthMismatch {
            what: "error vector end points",
            expected: from_m.len(),
            found: to_m.len(),
        });
    }
    Ok(from_m.iter().zip(to_m).map(|(a, b)| b - a).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::{ArcFitOptions, MeasurementNoise, fit_arc};
    use crate::robot::TransmissionFitForm;
    use approx::assert_relative_eq;

    #[test]
    fn arc_points_lie_on_the_fitted_circle_over_the_swept_range() {
        // An exact arc of radius 0.5 about z through (1, 2, 3), swept over 1 rad.
        let commands: Vec<f64> = (0..8).map(|j| 0.2 + j as f64 / 7.0).collect();
        let centre = Point3::new(1.0, 2.0, 3.0);
        let pts: Vec<Point3<f64>> = commands
            .iter()
            .map(|c| centre + 0.5 * Vector3::new(c.cos(), c.sin(), 0.0))
            .collect();
        let options = ArcFitOptions {
            form: TransmissionFitForm::Harmonic { order: 1 },
            noise: MeasurementNoise::Isotropic { sigma_per_axis: 1e-4 },
            reference_point: centre,
            max_iterations: 50,
        };
        let fit = fit_arc(&pts, &commands, &options).expect("fit");
        let arc = arc_points(&fit, &commands, 16).expect("arc");
        assert_eq!(arc.len(), 16);
        for p in &arc {
            assert_relative_eq!((p - centre).xy().norm(), 0.5, epsilon = 1e-6);
        }
        let ends = [arc[0], arc[15]];
        let firsts = [pts[0], pts[7]];
        let matched = ends.iter().all(|e| firsts.iter().any(|f| (e - f).norm() < 1e-6));
        assert!(matched, "arc ends at the first and last measured points");
    }

    #[test]
    fn boxes_span_their_segments() {
        let pts = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.0, 2.0, 0.0),
            Point3::new(0.0, 2.0, 0.0),
            Point3::new(-1.0, 2.0, 0.0),
        ];
        let boxes = segment_boxes(&pts, 0.1);
        assert_eq!(boxes.len(), 2, "the zero-length segment is skipped");
        let (c, h, r) = &boxes[0];
        assert_relative_eq!(*c, Point3::new(0.0, 1.0, 0.0), epsilon = 1e-12);
        assert_relative_eq!(h.x, 1.0, epsilon = 1e-12);
        assert_relative_eq!(r * Vector3::x(), Vector3::y(), epsilon = 1e-12);
        let (_, _, r) = &boxes[1];
        assert_relative_eq!(r * Vector3::x(), -Vector3::x(), epsilon = 1e-12);
    }

    #[test]
    fn parallelogram_loop_closes_with_its_nominal_passive_angle() {
        let g = FourBarGeometry::parallelogram(0.7, 0.2, 2.0);
        let frame2 = Isometry3::translation(1.0, 2.0, 3.0);
        let theta_2: f64 = 0.3;
        let axis3 = Point3::new(1.0 + 0.7 * theta_2.cos(), 2.0 + 0.7 * theta_2.sin(), 3.5);
        let passive = g.passive(theta_2).expect("assembles");
        let [o2, c, p, o3, end] = four_bar_loop_m(&g, &frame2, &axis3, theta_2, passive);
        assert_eq!(o2, end);
        assert_relative_eq!((o3 - o2).norm(), g.arm_m, epsilon = 1e-12);
        assert_relative_eq!((c - o2).norm(), g.crank_m, epsilon = 1e-12);
        assert_relative_eq!((p - c).norm(), g.rod_m, epsilon = 1e-9);
        assert_relative_eq!((p - o3).norm(), g.lever_m, epsilon = 1e-12);
        assert_relative_eq!(o3, Point3::new(axis3.x, axis3.y, 3.0), epsilon = 1e-12);
    }

    #[test]
    fn mismatched_error_vectors_are_an_error() {
        let err = vectors_between(&[Point3::origin()], &[]);
        assert_eq!(
            err,
            Err(LengthMismatch {
                what: "error vector end points",
                expected: 1,
                found: 0,
            })
        );
        let v = vectors_between(&[Point3::origin()], &[Point3::new(0.001, 0.0, 0.0)]).expect("same lengths");
        assert_relative_eq!(v[0].norm(), 0.001);
    }
}
