//! The analytic geometric Jacobian of the phi-model chain.
//!
//! For a revolute joint `k` with world axis `z_k` through `o_k`, a point `p` carried by a
//! link at or beyond `k` moves with `dp/dq_k = z_k x (p - o_k)` and the link turns with
//! `omega = z_k`; a prismatic joint gives `dp/dq_k = z_k`, `omega = 0`
//! (Siciliano et al., *Robotics*, eq. 3.30).

use super::chain::{ChainPoses, PhiModel};
use super::phi::JointKind;
use nalgebra::{Matrix3xX, Matrix6xX, Point3, Vector3};

fn column(
    kind: JointKind,
    axis_origin: &Point3<f64>,
    axis: &Vector3<f64>,
    p: &Point3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    match kind {
        JointKind::Revolute => (axis.cross(&(p - axis_origin)), *axis),
        JointKind::Prismatic => (*axis, Vector3::zeros()),
    }
}

/// The 6 x N geometric Jacobian of the tool frame at `q`, in the world frame: rows 0-2 the
/// linear velocity of the tool origin \[m per joint unit\], rows 3-5 the angular velocity
/// \[rad per joint unit\].
pub fn geometric_jacobian(model: &PhiModel, q: &[f64]) -> Matrix6xX<f64> {
    let poses = model.poses(q);
    let p = poses.world_from_tool.translation.vector.into();
    let n = model.dof();
    let mut j = Matrix6xX::zeros(n);
    for k in 0..n {
        let axis = poses.axis(k);
        let (v, w) = column(model.joints[k].kind, &axis.origin_m, &axis.direction, &p);
        j.fixed_view_mut::<3, 1>(0, k).copy_from(&v);
        j.fixed_view_mut::<3, 1>(3, k).copy_from(&w);
    }
    j
}

/// The 3 x N Jacobian of a point fixed on link `link` (0-based), given in that link's moving
/// frame \[m\]: `d(world point)/dq`. Joints beyond `link` do not move it (zero columns).
pub fn point_jacobian(model: &PhiModel, q: &[f64], link: usize, point_in_link_m: &Point3<f64>) -> Matrix3xX<f64> {
    let poses: ChainPoses = model.poses(q);
    let p = poses.world_from_link[link] * point_in_link_m;
    let mut j = Matrix3xX::zeros(model.dof());
    for k in 0..=link {
        let axis = poses.axis(k);
        let (v, _) = column(model.joints[k].kind, &axis.origin_m, &axis.direction, &p);
        j.set_column(k, &v);
    }
    j
}
