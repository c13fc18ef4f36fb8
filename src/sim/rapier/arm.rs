//! Building the arm as a rapier multibody (reduced coordinates) and its kinematic mode.
//!
//! Frames: the body frame of link `k` (0-based, moved by joint `k + 1`) is the phi-model's
//! moving frame `link_k` of [`PhiModel::poses`]; the base body's frame is frame 1
//! (`world_from_base`). rapier's revolute (prismatic) joints turn (slide) about the *X* axis of
//! their joint frames, the phi-model's about *Z*; so both joint frames carry the fixed
//! rotation `R = Rot(y, -90 deg)` (which maps X onto Z):
//! `local_frame1 = parent_from_frame_k * R`, `local_frame2 = R`, and rapier's
//! `body_to_parent = local_frame1 * Rot(x, q) * local_frame2^-1 = parent_from_frame_k * Rot(z, q)`,
//! which is eq. (A1)'s `frame_k * joint_motion(q)`.

use super::SimError;
use super::convert::{
    point_from_glam, point_to_glam, pose_from_glam, pose_to_glam, rotation_to_glam, vector_from_glam,
};
use crate::kinematics::{JointKind, PhiModel};
use crate::robot::{LinkTarget, RobotDescription};
use nalgebra::{Isometry3, Point3, Quaternion, UnitQuaternion, Vector3};
use parry3d_f64::shape::{Ball, Capsule, SharedShape};
use rapier3d_f64::math::Vector;
use rapier3d_f64::prelude::{
    GenericJointBuilder, JointAxesMask, MassProperties, MultibodyJointHandle, PhysicsWorld, RigidBodyBuilder,
    RigidBodyHandle,
};

/// Mass properties of one link, in its moving frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkInertia {
    /// Mass \[kg\].
    pub mass_kg: f64,
    /// Centre of mass in the link's moving frame \[m\].
    pub com_in_link_m: Point3<f64>,
}

/// A point fixed on a link (a target), in that link's moving frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkPoint {
    /// The link, 0-based (link `k` is moved by joint `k + 1`, as in [`PhiModel::poses`]).
    pub link: usize,
    /// Position in the link's moving frame \[m\].
    pub position_in_link_m: Point3<f64>,
}

impl LinkPoint {
    /// A description-file target (1-based link, mm) as a link point.
    pub fn from_target(target: &LinkTarget) -> Self {
        Self {
            link: target.link - 1,
            position_in_link_m: target.position_m(),
        }
    }
}

/// The body a collision shape rides on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArmBody {
    /// The fixed base (frame 1).
    Base,
    /// Link `k`, 0-based.
    Link(usize),
}

/// A collision shape attached to a body, given in that body's frame.
#[derive(Clone)]
pub struct LinkShape {
    /// The carrying body.
    pub body: ArmBody,
    /// The shape in the body frame.
    pub body_from_shape: Isometry3<f64>,
    /// The shape (parry).
    pub shape: SharedShape,
}

/// How to build the simulated arm beyond its kinematics and masses.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmOptions {
    /// Radius of each link's capsule \[m\] (one per link); also the radius of the solid
    /// cylinder used for the link's inertia estimate. Targets must lie outside the capsule
    /// of their own link, or line of sight will find them hidden (the shipped IRB/L6 joint-2
    /// target sits 60 mm off the upper arm's axis, so radii up to about 55 mm).
    pub link_radius_m: Vec<f64>,
    /// Payload point mass \[kg\] (0 for none).
    pub payload_kg: f64,
    /// Where the payload sits in the last link's moving frame \[m\]; `None`: the tool-frame
    /// origin.
    pub payload_in_last_link_m: Option<Point3<f64>>,
    /// Gravity in the world frame \[m/s^2\].
    pub gravity_m_s2: Vector3<f64>,
}

impl ArmOptions {
    /// Capsules of 50 mm radius on every link, no payload, gravity `(0, 0, -9.81)`.
    pub fn new(dof: usize) -> Self {
        Self {
            link_radius_m: vec![0.05; dof],
            payload_kg: 0.0,
            payload_in_last_link_m: None,
            gravity_m_s2: Vector3::new(0.0, 0.0, -9.81),
        }
    }
}

/// The arm as a rapier multibody.
pub struct SimArm {
    pub(super) model: PhiModel,
    pub(super) world: PhysicsWorld,
    base: RigidBodyHandle,
    links: Vec<RigidBodyHandle>,
    pub(super) joints: Vec<MultibodyJointHandle>,
    shapes: Vec<LinkShape>,
    inertias: Vec<LinkInertia>,
}

/// `R = Rot(y, -90 deg)`: maps rapier's joint axis X onto the phi-model's Z (exact quaternion).
fn x_onto_z() -> UnitQuaternion<f64> {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    UnitQuaternion::new_unchecked(Quaternion::new(h, 0.0, -h, 0.0))
}

/// The segment of link `k` in its own frame: from its origin to the next frame's origin (to
/// the tool-frame origin for the last link).
fn link_segment(model: &PhiModel, k: usize) -> (Point3<f64>, Point3<f64>) {
    let end = if k + 1 < model.dof() {
        model.link_from_next_frame(k) * Point3::origin()
    } else {
        model.last_link_from_tool * Point3::origin()
    };
    (Point3::origin(), end)
}

/// Mass properties of one link: mass `m` at the given centre of mass with the inertia of a
/// solid cylinder of radius `r` along the link segment of length `L`:
/// `I_axial = m r^2 / 2`, `I_transverse = m (3 r^2 + L^2) / 12` (a crude but documented
/// estimate: static sag does not depend on it, only the dynamics of settling do).
fn link_mass_properties(inertia: &LinkInertia, segment: (Point3<f64>, Point3<f64>), radius_m: f64) -> MassProperties {
    let m = inertia.mass_kg;
    let axis = segment.1 - segment.0;
    let length_m = axis.norm();
    let frame = UnitQuaternion::rotation_between(&Vector3::z(), &axis)
        .filter(|_| length_m > 1e-9)
        .unwrap_or_else(UnitQuaternion::identity);
    let i_axial = m * radius_m * radius_m / 2.0;
    let i_trans = m * (3.0 * radius_m * radius_m + length_m * length_m) / 12.0;
    MassProperties::with_principal_inertia_frame(
        point_to_glam(&inertia.com_in_link_m),
        m,
        Vector::new(i_trans, i_trans, i_axial),
        rotation_to_glam(&frame),
    )
}

impl SimArm {
    /// Builds the arm for `model` with the masses and centres of mass of `description`'s joints.
    pub fn from_description(
        model: &PhiModel,
        description: &RobotDescription,
        options: &ArmOptions,
    ) -> Result<Self, SimError> {
        let inertias: Vec<LinkInertia> = description
            .joints
            .iter()
            .map(|j| LinkInertia {
                mass_kg: j.mass_kg,
                com_in_link_m: Point3::from(j.com_mm) * 1e-3,
            })
            .collect();
        Self::new(model, &inertias, options)
    }

    /// Builds the arm: a fixed base body at `world_from_base`, one dynamic body per link (its
    /// frame the phi-model's moving link frame), one multibody joint per phi-model joint
    /// (frames in the module doc), a capsule per link from its origin to the next frame origin.
    ///
    /// Masses must be positive: the multibody's mass matrix must be invertible.
    pub fn new(model: &PhiModel, inertias: &[LinkInertia], options: &ArmOptions) -> Result<Self, SimError> {
        let n = model.dof();
        if !model.is_consistent() {
            return Err(SimError::InconsistentModel {
                joints: n,
                rows: model.rows.len(),
            });
        }
        check_len("link inertias", n, inertias.len())?;
        check_len("link radii", n, options.link_radius_m.len())?;
        for (k, li) in inertias.iter().enumerate() {
            check_positive(
                "mass_kg (the rapier arm needs every link's mass_kg and com_mm in the description; without them simulate with --sim analytic)",
                k,
                li.mass_kg,
            )?;
            check_positive("link radius", k, options.link_radius_m[k])?;
        }
        let mut world = PhysicsWorld::new();
        world.gravity = super::convert::vector_to_glam(&options.gravity_m_s2);
        let base = world.insert_body(RigidBodyBuilder::fixed().pose(pose_to_glam(&model.world_from_base)));
        let r = x_onto_z();
        let mut links = Vec::with_capacity(n);
        let mut joints = Vec::with_capacity(n);
        let mut shapes = Vec::with_capacity(n);
        let mut parent = base;
        let mut parent_from_frame = Isometry3::identity();
        let poses = model.poses(&vec![0.0; n]);
        for (k, inertia) in inertias.iter().enumerate() {
            let segment = link_segment(model, k);
            let mut mprops = link_mass_properties(inertia, segment, options.link_radius_m[k]);
            if k + 1 == n && options.payload_kg > 0.0 {
                let tool = options
                    .payload_in_last_link_m
                    .unwrap_or_else(|| model.last_link_from_tool * Point3::origin());
                mprops += MassProperties::new(point_to_glam(&tool), options.payload_kg, Vector::ZERO);
            }
            let body = world.insert_body(
                RigidBodyBuilder::dynamic()
                    .pose(pose_to_glam(&poses.world_from_link[k]))
                    .additional_mass_properties(mprops)
                    .can_sleep(false),
            );
            let locked = match model.joints[k].kind {
                JointKind::Revolute => JointAxesMask::LOCKED_REVOLUTE_AXES,
                JointKind::Prismatic => JointAxesMask::LOCKED_PRISMATIC_AXES,
            };
            let frame1 = parent_from_frame * Isometry3::from_parts(Default::default(), r);
            let frame2 = Isometry3::from_parts(Default::default(), r);
            let joint = GenericJointBuilder::new(locked)
                .local_frame1(pose_to_glam(&frame1))
                .local_frame2(pose_to_glam(&frame2))
                .contacts_enabled(false)
                .build();
            let handle = world
                .multibody_joints
                .insert(parent, body, joint, true)
                .ok_or(SimError::JointRejected { joint: k })?;
            shapes.push(LinkShape {
                body: ArmBody::Link(k),
                body_from_shape: Isometry3::identity(),
                shape: capsule_or_ball(segment, options.link_radius_m[k]),
            });
            links.push(body);
            joints.push(handle);
            parent = body;
            if k + 1 < n {
                parent_from_frame = model.link_from_next_frame(k);
            }
        }
        let mut arm = Self {
            model: model.clone(),
            world,
            base,
            links,
            joints,
            shapes,
            inertias: inertias.to_vec(),
        };
        arm.set_joint_positions(&vec![0.0; n])?;
        Ok(arm)
    }

    /// The phi-model the arm was built from.
    pub fn model(&self) -> &PhiModel {
        &self.model
    }

    /// The masses the arm was built with (without the payload).
    pub fn inertias(&self) -> &[LinkInertia] {
        &self.inertias
    }

    /// The rapier world, for adding bodies (e.g. a four-bar closed by an impulse joint).
    pub fn world(&self) -> &PhysicsWorld {
        &self.world
    }

    /// The rapier world, mutable, for adding bodies and joints.
    pub fn world_mut(&mut self) -> &mut PhysicsWorld {
        &mut self.world
    }

    /// The base body.
    pub fn base_body(&self) -> RigidBodyHandle {
        self.base
    }

    /// The body of link `k` (0-based).
    pub fn link_body(&self, k: usize) -> RigidBodyHandle {
        self.links[k]
    }

    /// The multibody joint of joint `k` (0-based).
    pub fn joint_handle(&self, k: usize) -> MultibodyJointHandle {
        self.joints[k]
    }

    /// The collision shapes (one capsule per link plus any added).
    pub fn shapes(&self) -> &[LinkShape] {
        &self.shapes
    }

    /// Adds a collision shape (used for line of sight), e.g. a wrist housing or a tool.
    pub fn add_shape(&mut self, shape: LinkShape) {
        self.shapes.push(shape);
    }

    /// Kinematic mode: writes the joint values `q` (rad or m) straight into the multibody's
    /// generalised coordinates, zeroes its velocities, and places every body by rapier's
    /// forward kinematics.
    pub fn set_joint_positions(&mut self, q: &[f64]) -> Result<(), SimError> {
        check_len("joint positions", self.model.dof(), q.len())?;
        let current = self.joint_positions();
        let link_ids = self.link_ids()?;
        let Some((mb, _)) = self.world.multibody_joints.get_mut(self.joints[0]) else {
            return Err(SimError::JointRejected { joint: 0 });
        };
        // A multibody created under a dynamic root has a free root joint until its first
        // forward kinematics notices the fixed base; settle that before indexing DOFs.
        mb.forward_kinematics(&self.world.bodies, true);
        let mut disp = vec![0.0; mb.ndofs()];
        for (k, &id) in link_ids.iter().enumerate() {
            let Some(link) = mb.link(id) else {
                return Err(SimError::JointRejected { joint: k });
            };
            disp[link.assembly_id()] = q[k] - current[k];
        }
        mb.apply_displacements(&disp);
        mb.generalized_velocity_mut().fill(0.0);
        mb.forward_kinematics(&self.world.bodies, false);
        mb.update_rigid_bodies(&mut self.world.bodies, false);
        Ok(())
    }

    /// The joint values (rad or m) currently held by the multibody.
    pub fn joint_positions(&self) -> Vec<f64> {
        (0..self.model.dof()).map(|k| self.joint_position(k)).collect()
    }

    /// The multibody link id of each joint.
    fn link_ids(&self) -> Result<Vec<usize>, SimError> {
        self.joints
            .iter()
            .enumerate()
            .map(|(k, &h)| {
                self.world
                    .multibody_joints
                    .get(h)
                    .map(|(_, id)| id)
                    .ok_or(SimError::JointRejected { joint: k })
            })
            .collect()
    }

    /// Joint `k`'s (0-based) value (rad or m) held by the multibody.
    pub fn joint_position(&self, k: usize) -> f64 {
        let axis = match self.model.joints[k].kind {
            JointKind::Revolute => 3,
            JointKind::Prismatic => 0,
        };
        self.world
            .multibody_joints
            .get(self.joints[k])
            .and_then(|(mb, id)| mb.link(id))
            .map_or(f64::NAN, |link| link.joint().coords()[axis])
    }

    /// The pose of a body in the world frame.
    pub fn world_from_body(&self, body: ArmBody) -> Isometry3<f64> {
        let handle = match body {
            ArmBody::Base => self.base,
            ArmBody::Link(k) => self.links[k],
        };
        pose_from_glam(self.world.bodies[handle].position())
    }

    /// The moving frame of link `k` (0-based) in the world frame.
    pub fn world_from_link(&self, k: usize) -> Isometry3<f64> {
        self.world_from_body(ArmBody::Link(k))
    }

    /// The tool frame in the world frame.
    pub fn world_from_tool(&self) -> Isometry3<f64> {
        self.world_from_link(self.model.dof() - 1) * self.model.last_link_from_tool
    }

    /// A point fixed on a link, in the world frame \[m\].
    pub fn point_in_world(&self, point: &LinkPoint) -> Point3<f64> {
        let pose = self.world.bodies[self.links[point.link]].position();
        point_from_glam(pose.transform_point(point_to_glam(&point.position_in_link_m)))
    }

    /// The velocity of a point fixed on a link, in the world frame, as of the last step \[m/s\].
    pub(super) fn point_velocity(&self, point: &LinkPoint) -> Vector3<f64> {
        let body = &self.world.bodies[self.links[point.link]];
        let at = body
            .position()
            .transform_point(point_to_glam(&point.position_in_link_m));
        vector_from_glam(body.velocity_at_point(at))
    }

    /// Moves every degree of freedom of the multibody (the joints and any four-bar's crank
    /// and rod) by its generalised velocity times `duration_s`, then scales the velocity by
    /// `keep`: a straight-line move along the current motion, which keeps a closed loop closed
    /// to first order (the velocities satisfy its constraint).
    pub(super) fn coast(&mut self, duration_s: f64, keep: f64) -> Result<(), SimError> {
        let Some((mb, _)) = self.world.multibody_joints.get_mut(self.joints[0]) else {
            return Err(SimError::JointRejected { joint: 0 });
        };
        let disp: Vec<f64> = mb.generalized_velocity().iter().map(|v| v * duration_s).collect();
        mb.apply_displacements(&disp);
        mb.generalized_velocity_mut().scale_mut(keep);
        mb.forward_kinematics(&self.world.bodies, false);
        mb.update_rigid_bodies(&mut self.world.bodies, false);
        Ok(())
    }

    /// Every shape with its pose in the world frame at the current configuration.
    pub fn placed_shapes(&self) -> Vec<(Isometry3<f64>, SharedShape)> {
        self.shapes
            .iter()
            .map(|s| (self.world_from_body(s.body) * s.body_from_shape, s.shape.clone()))
            .collect()
    }
}

/// A capsule on the segment, or a ball where the segment is (nearly) a point.
fn capsule_or_ball(segment: (Point3<f64>, Point3<f64>), radius_m: f64) -> SharedShape {
    if (segment.1 - segment.0).norm() < 1e-6 {
        SharedShape::new(Ball::new(radius_m))
    } else {
        SharedShape::new(Capsule::new(
            point_to_glam(&segment.0),
            point_to_glam(&segment.1),
            radius_m,
        ))
    }
}

pub(super) fn check_len(what: &'static str, expected: usize, found: usize) -> Result<(), SimError> {
    if expected == found {
        Ok(())
    } else {
        Err(SimError::WrongLength { what, expected, found })
    }
}

pub(super) fn check_positive(what: &'static str, joint: usize, value: f64) -> Result<(), SimError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SimError::NotPositive { what, joint, value })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::ChaCha12Rng;
    use rand::{RngExt, SeedableRng};

    /// The nominal IRB/L6 with every row, phi angle, the base and the tool moved by a few mm
    /// and tenths of a degree by hand (Table 2-like errors).
    fn perturbed() -> (PhiModel, RobotDescription) {
        let d = RobotDescription::asea_irb6l();
        let mut m = d.nominal_model();
        let mm = 1e-3;
        let tenth_deg = 0.1_f64.to_radians();
        let deltas = [
            [
                1.2 * mm,
                -0.8 * mm,
                0.3 * tenth_deg,
                -0.5 * tenth_deg,
                0.2 * tenth_deg,
                0.7 * mm,
            ],
            [-2.1 * mm, 1.5 * mm, -0.4 * tenth_deg, 0.6 * tenth_deg, 0.0, 0.0],
            [
                0.9 * mm,
                2.4 * mm,
                0.8 * tenth_deg,
                -0.2 * tenth_deg,
                -0.3 * tenth_deg,
                -1.1 * mm,
            ],
            [-0.6 * mm, -1.3 * mm, -0.7 * tenth_deg, 0.9 * tenth_deg, 0.0, 0.0],
            [
                1.7 * mm,
                0.4 * mm,
                0.5 * tenth_deg,
                -0.6 * tenth_deg,
                0.4 * tenth_deg,
                0.5 * mm,
            ],
        ];
        for (row, delta) in m.rows.iter_mut().zip(&deltas) {
            let p = row.to_array();
            *row = crate::kinematics::PhiRow::from_array(std::array::from_fn(|i| p[i] + delta[i]));
        }
        for (k, j) in m.joints.iter_mut().enumerate() {
            j.phi_rad += (k as f64 - 2.5) * 0.3 * tenth_deg;
        }
        m.world_from_base *= Isometry3::new(Vector3::new(0.002, -0.001, 0.003), Vector3::new(0.01, -0.02, 0.015));
        m.last_link_from_tool = Isometry3::new(Vector3::new(0.01, 0.02, 0.15), Vector3::new(0.1, 0.2, -0.3));
        (m, d)
    }

    fn random_q(d: &RobotDescription, rng: &mut ChaCha12Rng) -> Vec<f64> {
        (0..d.dof())
            .map(|k| {
                let [lo, hi] = d.limits_internal(k);
                rng.random_range(lo..hi)
            })
            .collect()
    }

    /// rapier's multibody forward kinematics reproduces eq. (A1) for every link frame and a
    /// target on every link. The bound is a few hundred ulps of the 5 m lever (round-off of
    /// two differently ordered products of six quaternions), far below the 1 micrometre the
    /// simulation needs.
    #[test]
    fn kinematic_mode_matches_phi_model_on_a_perturbed_arm() {
        let (model, d) = perturbed();
        let mut arm = SimArm::from_description(&model, &d, &ArmOptions::new(6)).expect("valid arm");
        let mut rng = ChaCha12Rng::seed_from_u64(7);
        let target = Point3::new(0.08, -0.03, 0.15);
        let mut worst_m = 0.0_f64;
        for _ in 0..1000 {
            let q = random_q(&d, &mut rng);
            arm.set_joint_positions(&q).expect("six values");
            let poses = model.poses(&q);
            for k in 0..6 {
                let sim = arm.world_from_link(k);
                let phi = poses.world_from_link[k];
                worst_m = worst_m.max((sim.translation.vector - phi.translation.vector).norm());
                worst_m = worst_m.max(sim.rotation.angle_to(&phi.rotation));
                let on_link = LinkPoint {
                    link: k,
                    position_in_link_m: target,
                };
                let p_sim = arm.point_in_world(&on_link);
                worst_m = worst_m.max((p_sim - model.point_on_link(&q, k, &target)).norm());
            }
            let tool = arm.world_from_tool().translation.vector - poses.world_from_tool.translation.vector;
            worst_m = worst_m.max(tool.norm());
            for (a, b) in arm.joint_positions().iter().zip(&q) {
                worst_m = worst_m.max((a - b).abs());
            }
        }
        assert!(worst_m < 1e-12, "worst disagreement {worst_m:e} (m or rad)");
    }

    #[test]
    fn wrong_lengths_and_masses_are_errors() {
        let d = RobotDescription::asea_irb6l();
        let model = d.nominal_model();
        let mut arm = SimArm::from_description(&model, &d, &ArmOptions::new(6)).expect("valid arm");
        assert!(matches!(
            arm.set_joint_positions(&[0.0; 5]),
            Err(SimError::WrongLength {
                expected: 6,
                found: 5,
                ..
            })
        ));
        let mut light = d.clone();
        light.joints[3].mass_kg = 0.0;
        assert!(matches!(
            SimArm::from_description(&model, &light, &ArmOptions::new(6)),
            Err(SimError::NotPositive { joint: 3, .. })
        ));
    }
}
