//! The four-bar of paper fig. 6 as real rapier bodies: a crank on the driving joint's axis
//! (turned by the driven joint's actuator), a coupler rod, and a lever point on the driven
//! link, the loop closed by an impulse ball joint.
//!
//! Bodies (all in the arm's multibody, which must stay a tree): the *crank* is a child of
//! the link carrying the driving axis (joint `a`'s parent), with a revolute joint on the same
//! frame as joint `a`: crank body frame = `frame_a Rot(z, c)`, `c` the actuator angle (0 while
//! the actuator holds its reference). The *rod* hangs on the crank tip by a spherical joint
//! (its frame: origin at the crank tip, X along the rod). An impulse spherical joint ties the
//! rod's far end to the lever point on link `b = a + 1`: a spatial RSSR loop, exact also when
//! axes `a` and `b` are not quite parallel (the rod spins freely about itself).
//!
//! Planar layout (as [`FourBarGeometry`]): in link `a`'s frame, `O3` is frame `b`'s origin,
//! `O2` its foot on axis `a`, `e_x = (O3 - O2)/|O3 - O2|`, `e_y = z x e_x`; the crank tip is
//! `O2 + r_c e(psi_c)` in the crank frame and the lever point `O3 + r_l e(psi_l)` in link `b`'s
//! frame at zero relative angle.
//!
//! Two modes: in kinematic mode [`FourBarBodies::place`] solves the crank angle analytically
//! (circle-circle intersection) for the link poses the arm already holds and places crank and
//! rod, so the loop is closed to rounding whatever passive law produced joint `b`; in
//! dynamic mode [`FourBarBodies::drive`] takes joint `b`'s servo off and puts actuator `b`'s
//! servo on the crank: the mechanism then drives joint `b`, and the gravity load of link `b`
//! and beyond reaches the crank's servo through the rod.
//!
//! The closure holds in dynamic mode because the servos are implicit joint springs (see
//! [`SimArm::set_servo`]): measured (test below, dt 1 ms, 8 solver iterations, crank
//! 1e6 N m/rad, the other joints 1e8 N m/rad) the loop gap is 3e-12 to 2.4e-10 m (2e-12 to
//! 1.3e-10 m with 16 iterations) and joint 3's
//! sag is the virtual-work prediction `g'^2 Q_3 / K_c` (about 9e-5 rad) within what the crank
//! and rod's own weight adds (3.2-3.4 % at the three test poses).

mod attach;

use super::SimError;
use super::arm::SimArm;
use super::convert::{point_to_glam, rotation_from_glam};
use crate::robot::FourBarLinkage;
use attach::{PlanarLayout, crank_mount, insert_crank, insert_rod, planar_layout};
use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use parry3d_f64::shape::{Capsule, SharedShape};
use rapier3d_f64::math::Vector;
use rapier3d_f64::prelude::{
    ImpulseJointHandle, JointAxis, MultibodyJointHandle, RigidBodyHandle, SphericalJointBuilder,
};

/// The mechanism's bodies and joints in a [`SimArm`]'s world.
#[derive(Clone, Debug)]
pub struct FourBarBodies {
    linkage: FourBarLinkage,
    /// Driving joint, 0-based.
    a: usize,
    crank_joint: MultibodyJointHandle,
    rod_joint: MultibodyJointHandle,
    crank_body: RigidBodyHandle,
    rod_body: RigidBodyHandle,
    closure: ImpulseJointHandle,
    crank_tip_in_crank_m: Point3<f64>,
    lever_in_link_b_m: Point3<f64>,
    /// `O2`, `e_x`, `e_y` in link `a`'s (= the crank's) frame.
    o2: Point3<f64>,
    ex: Vector3<f64>,
    ey: Vector3<f64>,
    crank_angle_rad: f64,
}

/// Mass of the crank \[kg\] (an estimate: a steel bar of the crank's length).
pub const CRANK_MASS_KG: f64 = 2.0;

/// Mass of the coupler rod \[kg\] (an estimate: a steel tube of the arm's length).
pub const ROD_MASS_KG: f64 = 1.0;

/// Radius of the crank and the rod \[m\]: their collision capsules (line of sight) and the
/// solid cylinders of their inertia estimates.
pub const BAR_RADIUS_M: f64 = 0.015;

impl FourBarBodies {
    /// Adds crank, rod and closure to `arm` for `linkage` (driving joint `linkage.from`,
    /// 1-based); crank and rod get [`CRANK_MASS_KG`] and [`ROD_MASS_KG`]. The arm must sit with the mechanism
    /// assembled before stepping: call [`FourBarBodies::place`].
    pub fn attach(arm: &mut SimArm, linkage: &FourBarLinkage) -> Result<Self, SimError> {
        let n = arm.model().dof();
        let a = linkage.from.wrapping_sub(1);
        if a + 1 >= n {
            return Err(SimError::JointRejected { joint: a });
        }
        let g = linkage.geometry;
        let model = arm.model().clone();
        let layout = planar_layout(model.link_from_next_frame(a), &g);
        let mount = crank_mount(arm, &model, a);
        let world_from_frame = mount.world_from_frame;
        let world = arm.world_mut();
        let (crank_body, crank_joint) = insert_crank(world, mount, &layout, g.crank_m, a)?;
        let (rod_body, rod_joint) = insert_rod(world, crank_body, world_from_frame, layout.crank_tip_m, g.rod_m, a)?;
        let PlanarLayout {
            o2,
            ex,
            ey,
            crank_tip_m: crank_tip,
            lever_in_link_b_m,
        } = layout;
        let link_b = arm.link_body(a + 1);
        let closure = SphericalJointBuilder::new()
            .local_anchor1(Vector::new(g.rod_m, 0.0, 0.0))
            .local_anchor2(point_to_glam(&lever_in_link_b_m))
            .contacts_enabled(false)
            .build();
        let closure = arm.world_mut().impulse_joints.insert(rod_body, link_b, closure, true);
        Ok(Self {
            linkage: *linkage,
            a,
            crank_joint,
            rod_joint,
            crank_body,
            rod_body,
            closure,
            crank_tip_in_crank_m: crank_tip,
            lever_in_link_b_m,
            o2,
            ex,
            ey,
            crank_angle_rad: 0.0,
        })
    }

    /// The joint the mechanism drives (0-based), `b = a + 1`.
    pub fn driven_joint(&self) -> usize {
        self.a + 1
    }

    /// The linkage this mechanism was built from.
    pub fn linkage(&self) -> &FourBarLinkage {
        &self.linkage
    }

    /// The impulse joint closing the loop.
    pub fn closure_joint(&self) -> ImpulseJointHandle {
        self.closure
    }

    /// The crank body and the rod body.
    pub fn bodies(&self) -> (RigidBodyHandle, RigidBodyHandle) {
        (self.crank_body, self.rod_body)
    }

    /// The crank (actuator) angle `c` held by the multibody \[rad\].
    pub fn crank_angle(&self, arm: &SimArm) -> f64 {
        arm.world()
            .multibody_joints
            .get(self.crank_joint)
            .and_then(|(mb, id)| mb.link(id))
            .map_or(f64::NAN, |l| l.joint().coords()[3])
    }

    /// The lever point on link `b` in the world \[m\].
    pub fn lever_point_m(&self, arm: &SimArm) -> Point3<f64> {
        arm.world_from_link(self.a + 1) * self.lever_in_link_b_m
    }

    /// The crank (from `O2` to the crank tip) and the rod (its full length) as capsules of
    /// radius [`BAR_RADIUS_M`], posed in the world at the current configuration.
    pub fn placed_shapes(&self, arm: &SimArm) -> Vec<(Isometry3<f64>, SharedShape)> {
        let pose = |h: RigidBodyHandle| super::convert::pose_from_glam(arm.world().bodies[h].position());
        let capsule = |a: Point3<f64>, b: Point3<f64>| {
            SharedShape::new(Capsule::new(point_to_glam(&a), point_to_glam(&b), BAR_RADIUS_M))
        };
        vec![
            (pose(self.crank_body), capsule(self.o2, self.crank_tip_in_crank_m)),
            (
                pose(self.rod_body),
                capsule(Point3::origin(), Point3::new(self.linkage.geometry.rod_m, 0.0, 0.0)),
            ),
        ]
    }

    /// Loop-closure error: distance between the rod's far end and the lever point \[m\].
    pub fn closure_error_m(&self, arm: &SimArm) -> f64 {
        let rod = super::convert::pose_from_glam(arm.world().bodies[self.rod_body].position());
        (rod * Point3::new(self.linkage.geometry.rod_m, 0.0, 0.0) - self.lever_point_m(arm)).norm()
    }

    /// Kinematic mode: for the link poses the arm holds now, solves the crank angle that
    /// closes the loop (circle-circle intersection in the mechanism plane, the rod shortened
    /// to its in-plane projection; branch nearest the previous crank angle) and writes crank
    /// and rod into the multibody. Returns the crank angle \[rad\].
    pub fn place(&mut self, arm: &mut SimArm) -> Result<f64, SimError> {
        let g = self.linkage.geometry;
        let q_a = arm.joint_positions()[self.a];
        let link_a = arm.world_from_link(self.a);
        let p = link_a.inverse() * self.lever_point_m(arm);
        let rel = p - self.o2;
        let (px, py, dz) = (rel.dot(&self.ex), rel.dot(&self.ey), rel.z);
        let rho2 = g.rod_m * g.rod_m - dz * dz;
        let d = px.hypot(py);
        let k = (g.crank_m * g.crank_m + d * d - rho2) / (2.0 * g.crank_m);
        if !(rho2 > 0.0 && k.abs() < d) {
            return Err(SimError::NotPositive {
                what: "four-bar closure (crank cannot reach the rod)",
                joint: self.a + 1,
                value: k,
            });
        }
        let beta = py.atan2(px);
        let half = (k / d).acos();
        let wrap = |x: f64| (x + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        let candidates = [beta + half, beta - half].map(|phi| q_a + wrap(phi - g.crank_angle_rad));
        let previous = self.crank_angle_rad;
        let c = if (candidates[0] - previous).abs() <= (candidates[1] - previous).abs() {
            candidates[0]
        } else {
            candidates[1]
        };
        // Rod direction in the crank frame (crank frame = link_a Rot(z, c - q_a)).
        let link_a_from_crank = Isometry3::rotation(Vector3::z() * (c - q_a));
        let p_crank = link_a_from_crank.inverse() * p;
        let along = p_crank - self.crank_tip_in_crank_m;
        let desired = UnitQuaternion::rotation_between(&Vector3::x(), &along).unwrap_or_else(UnitQuaternion::identity);
        let rod_link = arm
            .world
            .multibody_joints
            .get(self.rod_joint)
            .map(|(_, id)| id)
            .ok_or(SimError::JointRejected { joint: self.a + 1 })?;
        let bodies = &arm.world.bodies;
        let Some((mb, crank_id)) = arm.world.multibody_joints.get_mut(self.crank_joint) else {
            return Err(SimError::JointRejected { joint: self.a });
        };
        let (crank_dof, crank_now) = {
            let l = mb.link(crank_id).ok_or(SimError::JointRejected { joint: self.a })?;
            (l.assembly_id(), l.joint().coords()[3])
        };
        let (rod_dof, rod_now) = {
            let l = mb.link(rod_link).ok_or(SimError::JointRejected { joint: self.a + 1 })?;
            (l.assembly_id(), rotation_from_glam(l.joint().joint_rot()))
        };
        let mut disp = vec![0.0; mb.ndofs()];
        disp[crank_dof] = c - crank_now;
        let turn = (desired * rod_now.inverse()).scaled_axis();
        disp[rod_dof..rod_dof + 3].copy_from_slice(turn.as_slice());
        mb.apply_displacements(&disp);
        mb.generalized_velocity_mut().fill(0.0);
        mb.forward_kinematics(bodies, false);
        mb.update_rigid_bodies(&mut arm.world.bodies, false);
        self.crank_angle_rad = c;
        Ok(c)
    }

    /// Switches the loop-closing joint on or off. Off is the dynamic-mode fallback where the
    /// loop cannot close at the commanded pose (the truth's passive law reaches poses the
    /// mechanism cannot): joint `b` keeps its own servo, the crank holds still and the rod
    /// hangs from it, its swing damped (2 N m s/rad per axis, about critical for a 1 kg,
    /// 0.7 m pendulum) so that it does not keep the arm from settling; on again, the rod
    /// gets rapier's default damping back.
    pub fn set_loop_closed(&self, arm: &mut SimArm, closed: bool) -> Result<(), SimError> {
        let world = arm.world_mut();
        if let Some(joint) = world.impulse_joints.get_mut(self.closure, true) {
            joint.data.set_enabled(closed);
        }
        let (mb, id) = world
            .multibody_joints
            .get_mut(self.rod_joint)
            .ok_or(SimError::JointRejected { joint: self.a + 1 })?;
        let dof = mb
            .link(id)
            .ok_or(SimError::JointRejected { joint: self.a + 1 })?
            .assembly_id();
        let damping = if closed { 0.1 } else { 2.0 };
        for d in mb.damping_mut().rows_mut(dof, 3).iter_mut() {
            *d = damping;
        }
        Ok(())
    }

    /// Dynamic mode with the loop open: a servo (stiffness `K`, damping `D`) holds the crank
    /// where it is; joint `b`'s own servo is left as it is.
    pub fn hold_crank(
        &self,
        arm: &mut SimArm,
        stiffness_nm_per_rad: f64,
        damping_nms_per_rad: f64,
    ) -> Result<(), SimError> {
        let here = self.crank_angle(arm);
        super::servo::set_joint_spring(
            arm.world_mut(),
            self.crank_joint,
            JointAxis::AngX,
            here,
            stiffness_nm_per_rad,
            damping_nms_per_rad,
        )
        .ok_or(SimError::JointRejected { joint: self.a })
    }

    /// Dynamic mode: joint `b` passive (no servo: the mechanism drives it), and actuator `b`'s
    /// servo (implicit spring of stiffness `K` towards `crank_target_rad`, damping `D`, see
    /// [`SimArm::set_servo`]) on the crank.
    pub fn drive(
        &self,
        arm: &mut SimArm,
        crank_target_rad: f64,
        stiffness_nm_per_rad: f64,
        damping_nms_per_rad: f64,
    ) -> Result<(), SimError> {
        arm.set_joint_servo(self.a + 1, 0.0, 0.0, 0.0)?;
        super::servo::set_joint_spring(
            arm.world_mut(),
            self.crank_joint,
            JointAxis::AngX,
            crank_target_rad,
            stiffness_nm_per_rad,
            damping_nms_per_rad,
        )
        .ok_or(SimError::JointRejected { joint: self.a })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::{FourBarGeometry, RobotDescription};
    use crate::sim::{ArmOptions, ServoGains, SettleOptions};

    /// The paper truth's fitted (non-parallelogram) four-bar on the nominal arm (axes 2 and 3
    /// parallel, 0.69 m apart), so the planar solution is exact.
    fn nominal_arm_with_four_bar() -> (SimArm, FourBarBodies, FourBarGeometry) {
        let d = RobotDescription::asea_irb6l();
        let mut arm = SimArm::from_description(&d.nominal_model(), &d, &ArmOptions::new(6)).expect("valid arm");
        let mut linkage = crate::sim::paper_robot().four_bars[0];
        linkage.geometry.arm_m = 0.69;
        let bodies = FourBarBodies::attach(&mut arm, &linkage).expect("attaches");
        (arm, bodies, linkage.geometry)
    }

    /// Kinematic mode: with joint 3 at the analytic passive angle and actuator 3 at zero,
    /// the crank solved from the link poses is zero and the loop closes to rounding.
    #[test]
    fn kinematic_placement_closes_the_loop_at_the_analytic_crank_angle() {
        let (mut arm, mut bodies, g) = nominal_arm_with_four_bar();
        for deg in [-40.0, -20.0, 0.0, 15.0, 40.0] {
            let t2 = f64::to_radians(deg);
            arm.set_joint_positions(&[0.3, t2, g.passive(t2).unwrap(), 0.1, 0.2, 0.3])
                .unwrap();
            let c = bodies.place(&mut arm).unwrap();
            assert!(c.abs() < 1e-12, "crank {c} at {deg} deg");
            assert!(bodies.closure_error_m(&arm) < 1e-12);
        }
    }

    /// Dynamic mode: actuator 3's servo holds the crank at zero, joint 3 has no servo, joints
    /// 1, 2, 4-6 are held stiffly (1e8 N m/rad) under gravity; the mechanism drives joint 3.
    ///
    /// Expected, by virtual work: with `g` the passive law and `g'` its slope, the crank
    /// carries `tau_c = -g' Q_3` (`Q_3` the gravity torque of links 3-6 about axis 3) plus the
    /// bars' own weight, at most `tau_bars = 9.81 (m_c r_c / 2 + m_r (r_c + |g'| r_l) / 2)`; the
    /// crank (stiffness `K_c`) turns by `c = tau_c / K_c` and joint 3 by `-g' c` (the planar
    /// mechanism gives `theta_23 = g(theta_2 - c)` exactly). So `theta_23 - g(theta_2)` must
    /// equal `g'^2 Q_3 / K_c` within `|g'| tau_bars / K_c`, plus what the loop gap `e` can
    /// turn the lever (`e / (r_l sin mu)`, `mu` the transmission angle between rod and lever)
    /// and the stiff joint 2's own sag (below 1e-8 rad, inside the same margin).
    #[test]
    fn the_mechanism_drives_joint3_along_the_analytic_four_bar() {
        use crate::physics::{ComplianceEffect, LinkMass, first_order_deflection};
        let (mut arm, mut bodies, g) = nominal_arm_with_four_bar();
        let d = RobotDescription::asea_irb6l();
        let crank_k = 1e6;
        for deg in [-17.0, 0.0, 20.0] {
            let t2 = f64::to_radians(deg);
            let target = [0.3, t2, g.passive(t2).unwrap(), 0.0, 0.0, 0.0];
            arm.set_joint_positions(&target).unwrap();
            bodies.place(&mut arm).unwrap();
            let gains = ServoGains::with_damping_ratio(&arm, &target, &[1e8; 6], 1.0);
            arm.set_servo(&target, &gains).unwrap();
            let crank_d = gains.damping_nms_per_rad[2] * (crank_k / 1e8_f64).sqrt();
            bodies.drive(&mut arm, 0.0, crank_k, crank_d).unwrap();
            let report = arm.settle(&[], &SettleOptions::default()).expect("settles");
            let q = &report.joint_positions;
            let c = bodies.crank_angle(&arm);
            let slope = g.solve(q[1] - c).unwrap().slope;
            let unit_stiffness = ComplianceEffect::new(vec![1.0; 6], [0.0, 0.0, -9.81]);
            let q3_torque =
                first_order_deflection(arm.model(), q, &LinkMass::from_description(&d), None, &unit_stiffness)[2];
            let predicted = slope * slope * q3_torque / crank_k;
            let tau_bars = 9.81 * (2.0 * g.crank_m / 2.0 + (g.crank_m + slope.abs() * g.lever_m) / 2.0);
            // Transmission angle in the plane at the mechanism's input theta_2 - c.
            let t = q[1] - c;
            let o3 = Vector3::new(t.cos(), t.sin(), 0.0) * g.arm_m;
            let lever = g.lever_angle_rad + t + (q[2]);
            let p = o3 + Vector3::new(lever.cos(), lever.sin(), 0.0) * g.lever_m;
            let tip = Vector3::new(g.crank_angle_rad.cos(), g.crank_angle_rad.sin(), 0.0) * g.crank_m;
            let sin_mu = (p - tip).normalize().cross(&(p - o3).normalize()).norm();
            let gap = bodies.closure_error_m(&arm);
            let bound = slope.abs() * tau_bars / crank_k + gap / (g.lever_m * sin_mu);
            let sag = q[2] - g.passive(q[1]).unwrap();
            eprintln!(
                "theta_2 {deg} deg: {} steps, sag {sag:.4e} rad, predicted {predicted:.4e}, bound {bound:.2e}, \
                 closure {gap:.2e} m, crank {c:.3e} rad, sin mu {sin_mu:.2}",
                report.steps
            );
            assert!(gap < 1e-6, "loop closure {gap} m");
            assert!((sag - predicted).abs() < bound, "sag {sag} vs {predicted} +- {bound}");
        }
    }
}
