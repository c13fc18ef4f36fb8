//! Building the four-bar's bodies and joints in the arm's world ([`FourBarBodies::attach`](super::FourBarBodies::attach)):
//! the planar layout, the crank on the driving axis and the rod on the crank tip.

use super::{BAR_RADIUS_M, CRANK_MASS_KG, ROD_MASS_KG};
use crate::kinematics::PhiModel;
use crate::robot::FourBarGeometry;
use crate::sim::rapier::arm::SimArm;
use crate::sim::rapier::convert::{point_to_glam, pose_to_glam, rotation_to_glam};
use crate::sim::rapier::{ArmBody, SimError};
use nalgebra::{Isometry3, Point3, Quaternion, UnitQuaternion, Vector3};
use rapier3d_f64::math::Vector;
use rapier3d_f64::prelude::{
    GenericJointBuilder, JointAxesMask, MassProperties, MultibodyJointHandle, PhysicsWorld, RigidBodyBuilder,
    RigidBodyHandle,
};

/// The rotation taking the X axis onto the Z axis (a quarter turn about -Y).
fn x_onto_z() -> UnitQuaternion<f64> {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    UnitQuaternion::new_unchecked(Quaternion::new(h, 0.0, -h, 0.0))
}

/// Mass properties of a solid bar of `mass_kg`, `length_m` and radius [`BAR_RADIUS_M`] from
/// `from` in the direction of `along` (any length; only its direction is used): centre of mass
/// at the bar's midpoint, `from + (length_m / 2) along / |along|`, the bar's axis along `along`.
fn bar_mass(mass_kg: f64, length_m: f64, along: Vector3<f64>, from: Point3<f64>) -> MassProperties {
    let r = BAR_RADIUS_M;
    let i_axial = mass_kg * r * r / 2.0;
    let i_trans = mass_kg * (3.0 * r * r + length_m * length_m) / 12.0;
    let frame = UnitQuaternion::rotation_between(&Vector3::z(), &along).unwrap_or_else(UnitQuaternion::identity);
    let direction = along.try_normalize(0.0).unwrap_or_else(Vector3::z);
    MassProperties::with_principal_inertia_frame(
        point_to_glam(&(from + direction * (length_m / 2.0))),
        mass_kg,
        Vector::new(i_trans, i_trans, i_axial),
        rotation_to_glam(&frame),
    )
}

/// The planar layout of the mechanism in link `a`'s (= the crank's) frame (module docs).
pub(super) struct PlanarLayout {
    /// `O2`: the foot of frame `b`'s origin on axis `a` \[m\].
    pub(super) o2: Point3<f64>,
    /// `e_x = (O3 - O2)/|O3 - O2|`.
    pub(super) ex: Vector3<f64>,
    /// `e_y = z x e_x`.
    pub(super) ey: Vector3<f64>,
    /// The crank tip, `O2 + r_c e(psi_c)`, in the crank's frame \[m\].
    pub(super) crank_tip_m: Point3<f64>,
    /// The lever point, `O3 + r_l e(psi_l)`, in link `b`'s frame \[m\].
    pub(super) lever_in_link_b_m: Point3<f64>,
}

/// The layout of geometry `g` with frame `b` at `t_ab` in link `a`'s frame.
pub(super) fn planar_layout(t_ab: Isometry3<f64>, g: &FourBarGeometry) -> PlanarLayout {
    let o3 = t_ab * Point3::origin();
    let o2 = Point3::new(0.0, 0.0, o3.z);
    let ex = (o3 - o2).normalize();
    let ey = Vector3::z().cross(&ex);
    let e = |angle: f64| ex * angle.cos() + ey * angle.sin();
    let crank_tip = o2 + e(g.crank_angle_rad) * g.crank_m;
    let lever_in_link_b_m = t_ab.inverse() * (o3 + e(g.lever_angle_rad) * g.lever_m);
    PlanarLayout {
        o2,
        ex,
        ey,
        crank_tip_m: crank_tip,
        lever_in_link_b_m,
    }
}

/// Where the crank hangs.
#[derive(Clone, Copy)]
pub(super) struct CrankMount {
    /// The body carrying the driving axis (joint `a`'s parent).
    pub(super) parent: RigidBodyHandle,
    /// Joint `a`'s frame in that body.
    pub(super) parent_from_frame: Isometry3<f64>,
    /// Joint `a`'s frame in the world.
    pub(super) world_from_frame: Isometry3<f64>,
}

/// Where the crank of driving joint `a` (0-based) hangs in `arm` (geometry `model`).
pub(super) fn crank_mount(arm: &SimArm, model: &PhiModel, a: usize) -> CrankMount {
    let (parent, parent_from_frame) = if a == 0 {
        (arm.base_body(), Isometry3::identity())
    } else {
        (arm.link_body(a - 1), model.link_from_next_frame(a - 1))
    };
    let world_from_frame =
        arm.world_from_body(if a == 0 { ArmBody::Base } else { ArmBody::Link(a - 1) }) * parent_from_frame;
    CrankMount {
        parent,
        parent_from_frame,
        world_from_frame,
    }
}

/// Inserts the crank body (at joint `a`'s frame) and its revolute joint to the mount's parent
/// into `world`.
pub(super) fn insert_crank(
    world: &mut PhysicsWorld,
    mount: CrankMount,
    layout: &PlanarLayout,
    crank_m: f64,
    a: usize,
) -> Result<(RigidBodyHandle, MultibodyJointHandle), SimError> {
    let (crank_tip, o2) = (layout.crank_tip_m, layout.o2);
    let (parent, parent_from_frame, world_from_frame) = (mount.parent, mount.parent_from_frame, mount.world_from_frame);
    let r = x_onto_z();
    let crank_body = world.insert_body(
        RigidBodyBuilder::dynamic()
            .pose(pose_to_glam(&world_from_frame))
            .additional_mass_properties(bar_mass(CRANK_MASS_KG, crank_m, crank_tip - o2, o2))
            .can_sleep(false),
    );
    let crank = GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
        .local_frame1(pose_to_glam(
            &(parent_from_frame * Isometry3::from_parts(Default::default(), r)),
        ))
        .local_frame2(pose_to_glam(&Isometry3::from_parts(Default::default(), r)))
        .contacts_enabled(false)
        .build();
    let crank_joint = world
        .multibody_joints
        .insert(parent, crank_body, crank, true)
        .ok_or(SimError::JointRejected { joint: a })?;
    Ok((crank_body, crank_joint))
}

/// Inserts the rod body (hanging on the crank tip `crank_tip` of `crank_body`, whose frame is
/// `world_from_frame` in the world) and its spherical joint into `world`.
pub(super) fn insert_rod(
    world: &mut PhysicsWorld,
    crank_body: RigidBodyHandle,
    world_from_frame: Isometry3<f64>,
    crank_tip: Point3<f64>,
    rod_m: f64,
    a: usize,
) -> Result<(RigidBodyHandle, MultibodyJointHandle), SimError> {
    let rod_body = world.insert_body(
        RigidBodyBuilder::dynamic()
            .pose(pose_to_glam(
                &(world_from_frame * Isometry3::translation(crank_tip.x, crank_tip.y, crank_tip.z)),
            ))
            .additional_mass_properties(bar_mass(ROD_MASS_KG, rod_m, Vector3::x(), Point3::origin()))
            .can_sleep(false),
    );
    let rod = GenericJointBuilder::new(JointAxesMask::LOCKED_SPHERICAL_AXES)
        .local_frame1(pose_to_glam(&Isometry3::translation(
            crank_tip.x,
            crank_tip.y,
            crank_tip.z,
        )))
        .contacts_enabled(false)
        .build();
    let rod_joint = world
        .multibody_joints
        .insert(crank_body, rod_body, rod, true)
        .ok_or(SimError::JointRejected { joint: a + 1 })?;
    Ok((rod_body, rod_joint))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::rapier::convert::point_from_glam;
    use approx::assert_relative_eq;

    /// The crank is built with `along` the full crank vector (tip minus foot, length
    /// `crank_m`), the rod with a unit vector: either way the centre of mass is at the bar's
    /// midpoint, and the mass and the inertia about the bar's own axis are those of the
    /// solid cylinder.
    #[test]
    fn a_bar_has_its_centre_of_mass_at_its_midpoint_whatever_the_length_of_along() {
        let from = Point3::new(0.1, -0.3, 0.7);
        let direction = Vector3::new(1.0, 2.0, -0.5).normalize();
        for length_m in [0.2, 1.0, 2.5] {
            for along in [direction, direction * length_m] {
                let m = bar_mass(CRANK_MASS_KG, length_m, along, from);
                assert_relative_eq!(
                    point_from_glam(m.local_com),
                    from + direction * (length_m / 2.0),
                    epsilon = 1e-15
                );
                assert_relative_eq!(m.mass(), CRANK_MASS_KG, max_relative = 1e-15);
            }
        }
    }
}
