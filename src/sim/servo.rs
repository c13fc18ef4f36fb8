//! Dynamic mode: position servos with finite stiffness holding the arm against gravity, and
//! the static-equilibrium solve.
//!
//! Each joint's motor is a rapier position motor with [`MotorModel::ForceBased`], so its
//! generalised force is `tau_k = -K_k (q_k - q_cmd_k) - D_k dq_k/dt` with `K` in N m/rad
//! (N/m for prismatic joints). At rest the soft-constraint impulse of the motor is exactly
//! `K_k (q_cmd_k - q_k) dt` per step, so the equilibrium satisfies `K dq = Q_gravity(q)`, the
//! usual joint-stiffness model of servo compliance.

use super::SimArm;
use super::SimError;
use super::arm::{LinkPoint, check_len, check_positive};
use nalgebra::Point3;
use rapier3d_f64::prelude::{JointAxis, MotorModel};

/// Servo stiffness and damping per joint.
#[derive(Clone, Debug, PartialEq)]
pub struct ServoGains {
    /// Position gain of each joint's servo [N m/rad] (or [N/m]).
    pub stiffness_nm_per_rad: Vec<f64>,
    /// Velocity gain of each joint's servo [N m s/rad] (or [N s/m]).
    pub damping_nms_per_rad: Vec<f64>,
}

impl ServoGains {
    /// Gains with damping `D_k = 2 zeta sqrt(K_k I_k)`, `I_k` the inertia about joint `k` at
    /// `q` estimated from point masses at the centres of mass of the links beyond it (plus
    /// their payload) and the links' own cylinder axial inertia `m r^2 / 2` with `r = 0.05 m`
    /// as a floor. `zeta = 1` gives roughly critical damping of each joint alone.
    pub fn with_damping_ratio(arm: &SimArm, q: &[f64], stiffness_nm_per_rad: &[f64], zeta: f64) -> Self {
        let model = arm.model();
        let poses = model.poses(q);
        let coms: Vec<(f64, Point3<f64>)> = arm
            .inertias()
            .iter()
            .enumerate()
            .map(|(i, li)| (li.mass_kg, poses.world_from_link[i] * li.com_in_link_m))
            .collect();
        let damping = stiffness_nm_per_rad
            .iter()
            .enumerate()
            .map(|(k, &stiff)| {
                let axis = poses.axis(k);
                let inertia: f64 = coms[k..]
                    .iter()
                    .map(|(m, c)| m * (axis.direction.cross(&(c - axis.origin_m)).norm_squared() + 0.05 * 0.05 / 2.0))
                    .sum();
                2.0 * zeta * (stiff * inertia).sqrt()
            })
            .collect();
        Self {
            stiffness_nm_per_rad: stiffness_nm_per_rad.to_vec(),
            damping_nms_per_rad: damping,
        }
    }
}

/// How the joints hold their commanded values.
#[derive(Clone, Debug, PartialEq)]
pub enum Compliance {
    /// Infinitely stiff servos: the arm sits exactly at the command (kinematic mode).
    Rigid,
    /// Finite servo stiffness under gravity: the arm sags to its static equilibrium.
    Servo(ServoGains),
}

/// Time step, solver and stopping rule of the static-equilibrium solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SettleOptions {
    /// Time step [s].
    pub dt_s: f64,
    /// rapier solver iterations per step.
    pub solver_iterations: usize,
    /// Give up after this many steps.
    pub max_steps: usize,
    /// At rest when every watched point moves slower than this [m/s] ...
    pub speed_tolerance_m_s: f64,
    /// ... for this many consecutive steps.
    pub quiet_steps: usize,
}

impl Default for SettleOptions {
    /// 1 ms steps, 16 solver iterations, 1 micrometre per second for 20 steps, at most 20 s.
    fn default() -> Self {
        Self {
            dt_s: 1e-3,
            solver_iterations: 16,
            max_steps: 20_000,
            speed_tolerance_m_s: 1e-6,
            quiet_steps: 20,
        }
    }
}

/// The outcome of a settle.
#[derive(Clone, Debug, PartialEq)]
pub struct SettleReport {
    /// Steps taken.
    pub steps: usize,
    /// Speed of the fastest watched point at the last step [m/s].
    pub max_speed_m_s: f64,
    /// The joint values at rest (rad or m).
    pub joint_positions: Vec<f64>,
}

impl SimArm {
    /// Puts the joint motors in position mode towards `q_cmd` with the given gains
    /// (force-based, so stiffness is in N m/rad).
    pub fn set_servo(&mut self, q_cmd: &[f64], gains: &ServoGains) -> Result<(), SimError> {
        let n = self.model.dof();
        check_len("commanded joint values", n, q_cmd.len())?;
        check_len("servo stiffness", n, gains.stiffness_nm_per_rad.len())?;
        check_len("servo damping", n, gains.damping_nms_per_rad.len())?;
        for k in 0..n {
            check_positive("servo stiffness", k, gains.stiffness_nm_per_rad[k])?;
            let damping = gains.damping_nms_per_rad[k];
            if !(damping.is_finite() && damping >= 0.0) {
                return Err(SimError::NotPositive {
                    what: "servo damping",
                    joint: k,
                    value: damping,
                });
            }
            let axis = match self.model.joints[k].kind {
                crate::kinematics::JointKind::Revolute => JointAxis::AngX,
                crate::kinematics::JointKind::Prismatic => JointAxis::LinX,
            };
            let Some((mb, id)) = self.world.multibody_joints.get_mut(self.joints[k]) else {
                return Err(SimError::JointRejected { joint: k });
            };
            let Some(link) = mb.link_mut(id) else {
                return Err(SimError::JointRejected { joint: k });
            };
            link.joint
                .data
                .set_motor_model(axis, MotorModel::ForceBased)
                .set_motor_position(axis, q_cmd[k], gains.stiffness_nm_per_rad[k], damping);
        }
        Ok(())
    }

    /// Steps the dynamics until every watched point (the tool-frame origin and `watch`) moves
    /// slower than `options.speed_tolerance_m_s` for `options.quiet_steps` steps in a row.
    pub fn settle(&mut self, watch: &[LinkPoint], options: &SettleOptions) -> Result<SettleReport, SimError> {
        self.world.integration_parameters.dt = options.dt_s;
        self.world.integration_parameters.num_solver_iterations = options.solver_iterations;
        let mut points: Vec<LinkPoint> = watch.to_vec();
        let last = self.model.dof() - 1;
        points.push(LinkPoint {
            link: last,
            position_in_link_m: self.model.last_link_from_tool * Point3::origin(),
        });
        let mut previous: Vec<Point3<f64>> = points.iter().map(|p| self.point_in_world(p)).collect();
        let mut quiet = 0;
        let mut max_speed_m_s = f64::INFINITY;
        for step in 1..=options.max_steps {
            self.world.step();
            let now: Vec<Point3<f64>> = points.iter().map(|p| self.point_in_world(p)).collect();
            max_speed_m_s = now
                .iter()
                .zip(&previous)
                .map(|(a, b)| (a - b).norm() / options.dt_s)
                .fold(0.0, f64::max);
            previous = now;
            quiet = if max_speed_m_s < options.speed_tolerance_m_s {
                quiet + 1
            } else {
                0
            };
            if quiet >= options.quiet_steps {
                return Ok(SettleReport {
                    steps: step,
                    max_speed_m_s,
                    joint_positions: self.joint_positions(),
                });
            }
        }
        Err(SimError::NotSettled {
            steps: options.max_steps,
            max_speed_m_s,
        })
    }

    /// The static equilibrium at command `q_cmd`: with [`Compliance::Rigid`] the arm is placed
    /// at `q_cmd` (kinematic mode); with [`Compliance::Servo`] it starts at rest at `q_cmd`, the
    /// servos hold it against gravity, and it is stepped until it settles.
    pub fn static_equilibrium(
        &mut self,
        q_cmd: &[f64],
        compliance: &Compliance,
        watch: &[LinkPoint],
        options: &SettleOptions,
    ) -> Result<SettleReport, SimError> {
        self.set_joint_positions(q_cmd)?;
        match compliance {
            Compliance::Rigid => Ok(SettleReport {
                steps: 0,
                max_speed_m_s: 0.0,
                joint_positions: self.joint_positions(),
            }),
            Compliance::Servo(gains) => {
                self.set_servo(q_cmd, gains)?;
                self.settle(watch, options)
            }
        }
    }
}
