//! Every conversion between the crate's nalgebra types and rapier/parry's glam types.
//!
//! rapier3d-f64 0.36 and parry3d-f64 0.31 use glam (`DVec3`, `DQuat`, `DPose3`); the rest of
//! axiscal uses nalgebra. Keeping all conversions here means no other module of `sim` has to
//! know both libraries, and a change of either library's math types touches one file.
//! The conversions copy components; they are exact (no rounding).

use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion, Vector3};
use rapier3d_f64::math::{Pose, Rotation, Vector};

/// A nalgebra vector as a glam vector.
pub(crate) fn vector_to_glam(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

/// A nalgebra point as a glam vector (glam has no separate point type).
pub(crate) fn point_to_glam(p: &Point3<f64>) -> Vector {
    Vector::new(p.x, p.y, p.z)
}

/// A glam vector read as a nalgebra point.
pub(crate) fn point_from_glam(v: Vector) -> Point3<f64> {
    Point3::new(v.x, v.y, v.z)
}

/// A glam vector as a nalgebra vector.
pub(crate) fn vector_from_glam(v: Vector) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

/// A nalgebra unit quaternion as a glam quaternion.
pub(crate) fn rotation_to_glam(q: &UnitQuaternion<f64>) -> Rotation {
    Rotation::from_xyzw(q.i, q.j, q.k, q.w)
}

/// A glam quaternion as a nalgebra unit quaternion (assumed normalised, as rapier keeps it).
pub(crate) fn rotation_from_glam(q: Rotation) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(Quaternion::new(q.w, q.x, q.y, q.z))
}

/// A nalgebra isometry as a glam pose.
pub(crate) fn pose_to_glam(iso: &Isometry3<f64>) -> Pose {
    Pose::from_parts(vector_to_glam(&iso.translation.vector), rotation_to_glam(&iso.rotation))
}

/// A glam pose as a nalgebra isometry.
pub(crate) fn pose_from_glam(pose: &Pose) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(vector_from_glam(pose.translation)),
        rotation_from_glam(pose.rotation),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn pose_round_trip_is_exact() {
        let iso = Isometry3::new(Vector3::new(0.1, -2.0, 3.5), Vector3::new(0.3, -1.2, 0.7));
        let back = pose_from_glam(&pose_to_glam(&iso));
        assert_relative_eq!(back.to_homogeneous(), iso.to_homogeneous(), epsilon = 0.0);
    }

    #[test]
    fn points_map_the_same_way() {
        let iso = Isometry3::new(Vector3::new(0.1, -2.0, 3.5), Vector3::new(0.3, -1.2, 0.7));
        let p = Point3::new(0.4, 0.5, -0.6);
        let q = point_from_glam(pose_to_glam(&iso).transform_point(point_to_glam(&p)));
        assert_relative_eq!(q, iso * p, epsilon = 1e-15);
    }
}
