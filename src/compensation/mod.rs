//! Compensation (paper fig. 5): the commands that make the real robot reach a required tool
//! pose, computed from the CALIBRATED model and fed to the UNCHANGED controller.
//!
//! For a required pose `world_from_tool`:
//! 1. inverse kinematics on the calibrated phi-model (appendix eqs. A1-A4), seeded by the
//!    nominal closed-form branches ([`solve_seeded_by_nominal`]) or by a given configuration:
//!    the joint values `q` the robot must reach;
//! 2. the calibrated couplings undone from joint 1 up (eq. 15 inverted):
//!    `theta_act_1 = q_1`, `theta_act_k = q_k - g_{k-1,k}(theta_act_{k-1})`;
//! 3. the calibrated transmissions and transducer offsets applied (eq. 8):
//!    `u_k = f_k(theta_act_k) + offset_k`, the actuator commands;
//! 4. the controller's NOMINAL couplings re-applied, so that its own decoupling (fig. 3)
//!    gives back `u`: `cmd_1 = u_1`, `cmd_{k+1} = u_{k+1} + nominal_slope_{k,k+1} u_k`;
//! 5. for a controller that takes poses, the nominal direct kinematics of `cmd`: that pose is
//!    what is sent ([`CompensatedPose::nominal_pose_to_send`]); the controller's nominal
//!    inverse kinematics returns `cmd` on the same branch.
//!
//! Steps 2-4 are the exact inverse of the truth-model semantics
//! ([`crate::robot::RobotModel::joint_values`]), so a robot equal to the calibrated model
//! reaches `q` exactly.
//!
//! A calibrated model with effects ([`crate::robot::ModelEffects`]) adds two steps:
//! - before step 2, the sag undone: the joint values before the sag `q0` solve
//!   `q0 + sag(q0) = q`, by the fixed point `q0 <- q - sag(q0)` (a contraction: the sag's
//!   change over the sag itself is 1e-3 of it);
//! - after step 3, for poses visited in sequence ([`Compensator::compensate_sequence`]), each
//!   actuator command moved by the backlash the robot will show: `u_k + s_k h_k`, `s_k` the
//!   direction from the previous pose's sent command (the model's backlash lags `u_k` by
//!   `s_k h_k`).

use crate::kinematics::{IkError, IkOptions, IkReport, PhiModel, solve_ik, solve_seeded_by_nominal};
use crate::robot::{Controller, FourBarError, RobotDescription, RobotModel};
use nalgebra::Isometry3;

/// Why a pose cannot be compensated.
#[derive(Debug, thiserror::Error)]
pub enum CompensationError {
    /// The calibrated model is not a consistent robot (a damaged or hand-edited file).
    #[error("the calibrated robot: {0}")]
    Model(crate::robot::ModelError),
    /// The calibrated model and the robot description disagree in their number of joints.
    #[error("the calibrated robot has {calibrated} joints, the description {nominal}")]
    JointCount {
        /// Joints of the calibrated robot.
        calibrated: usize,
        /// Joints of the description.
        nominal: usize,
    },
    /// Inverse kinematics on the calibrated model failed (out of reach, singular).
    #[error("inverse kinematics on the calibrated model: {0}")]
    Ik(IkError),
    /// A calibrated coupling cannot be evaluated at the required active displacement.
    #[error("coupling into joint {joint}: {cause}")]
    Coupling {
        /// 1-based driven joint.
        joint: usize,
        /// The linkage problem.
        cause: FourBarError,
    },
    /// A command is not finite (a coefficient blew up).
    #[error("joint {joint}: the command is not finite")]
    NonFinite {
        /// 1-based joint.
        joint: usize,
    },
}

/// Everything fig. 5 produces for one pose.
#[derive(Clone, Debug, PartialEq)]
pub struct CompensatedPose {
    /// Joint values of the calibrated model that reach the pose \[rad or m\].
    pub q: Vec<f64>,
    /// Actual active displacements `theta_act` \[rad or m\].
    pub theta_act: Vec<f64>,
    /// Actuator commands `u` (after the controller's decoupling) \[rad or m\].
    pub actuator: Vec<f64>,
    /// Joint commands for the unchanged controller \[rad or m\].
    pub cmd: Vec<f64>,
    /// Nominal direct kinematics of `cmd`: the pose to send to a controller that takes poses.
    pub nominal_pose_to_send: Isometry3<f64>,
    /// How the IK iteration ended.
    pub ik: IkReport,
}

/// Fig. 5 for one calibrated robot and its (unchanged) controller.
#[derive(Clone, Debug)]
pub struct Compensator {
    calibrated: RobotModel,
    calibrated_model: PhiModel,
    nominal_model: PhiModel,
    controller: Controller,
    ik: IkOptions,
    payload_kg: f64,
}

/// Fixed-point steps of the sag's inversion at most; each shrinks the error by the sag's
/// relative change (about 1e-3), so three reach rounding.
const SAG_STEPS: usize = 20;

impl Compensator {
    /// The compensator of `calibrated` (the [`crate::calibration::procedure::Calibration`]'s
    /// robot) behind the controller of `desc`. IK uses the default tolerances (1e-12 m and
    /// rad) and reports joints outside the description's limits (seeds inside them first).
    pub fn new(calibrated: &RobotModel, desc: &RobotDescription) -> Result<Self, CompensationError> {
        calibrated.validate()?;
        if calibrated.dof() != desc.dof() {
            return Err(CompensationError::JointCount {
                calibrated: calibrated.dof(),
                nominal: desc.dof(),
            });
        }
        let ik = IkOptions {
            limits: Some((0..desc.dof()).map(|k| desc.limits_internal(k)).collect()),
            ..IkOptions::default()
        };
        Ok(Compensator {
            calibrated: calibrated.clone(),
            calibrated_model: calibrated.phi_model(),
            nominal_model: desc.nominal_model(),
            controller: Controller::from_description(desc),
            ik,
            payload_kg: 0.0,
        })
    }

    /// The payload the robot carries \[kg\] (the sag's payload terms; default 0).
    pub fn with_payload_kg(mut self, payload_kg: f64) -> Self {
        self.payload_kg = payload_kg;
        self
    }

    /// Fig. 5 for the poses `world_from_tool` visited in this order: each as
    /// [`Compensator::compensate`], with the backlash of the calibrated model added to its
    /// actuator commands in the direction the robot arrives from (module docs). A pose that
    /// fails leaves the previous sent command as the reference.
    pub fn compensate_sequence(
        &self,
        world_from_tool: &[Isometry3<f64>],
    ) -> Vec<Result<CompensatedPose, CompensationError>> {
        let mut approach = vec![0.0; self.calibrated.dof()];
        let mut last_sent: Option<Vec<f64>> = None;
        world_from_tool
            .iter()
            .map(|pose| {
                let mut c = self.compensate(pose)?;
                if self.calibrated.effects.backlash.is_empty() {
                    return Ok(c);
                }
                // The direction from the previous sent command to this one before its shift
                // (a move larger than the band, as between measured poses, keeps its sign
                // through the shift); no move keeps the previous direction.
                let mut u = c.actuator.clone();
                if let Some(last) = &last_sent {
                    for ((s, now), before) in approach.iter_mut().zip(&u).zip(last) {
                        if (now - before).abs() > crate::physics::UNMOVED_ACTUATOR_RAD {
                            *s = (now - before).signum();
                        }
                    }
                }
                for b in &self.calibrated.effects.backlash {
                    u[b.joint - 1] += approach[b.joint - 1] * b.half_band;
                }
                c.cmd = self.commands_from_actuators(&u)?;
                c.nominal_pose_to_send = self.nominal_model.world_from_tool(&c.cmd);
                c.actuator = u.clone();
                last_sent = Some(u);
                Ok(c)
            })
            .collect()
    }

    /// Replaces the IK settings.
    pub fn with_ik_options(mut self, ik: IkOptions) -> Self {
        self.ik = ik;
        self
    }

    /// The nominal model (what the controller believes).
    pub fn nominal_model(&self) -> &PhiModel {
        &self.nominal_model
    }

    /// The calibrated model.
    pub fn calibrated_model(&self) -> &PhiModel {
        &self.calibrated_model
    }

    /// The calibrated model's joint values for controller commands `cmd` \[rad or m\].
    pub fn calibrated_joint_values(&self, cmd: &[f64]) -> Result<Vec<f64>, crate::robot::ModelError> {
        self.calibrated.joint_values(&self.controller, cmd)
    }

    /// Fig. 5 for `world_from_tool` (instrument frame, metres), the IK seeded by the nominal
    /// closed-form branches (inside the limits first, nearest the zero pose first).
    pub fn compensate(&self, world_from_tool: &Isometry3<f64>) -> Result<CompensatedPose, CompensationError> {
        let s = solve_seeded_by_nominal(&self.calibrated_model, &self.nominal_model, world_from_tool, &self.ik)?;
        self.commands_for(s.q, s.report)
    }

    /// Fig. 5 with the IK seeded by `seed` (e.g. the nominal controller's own IK answer, so
    /// the compensated commands stay on its branch); falls back to [`Compensator::compensate`]
    /// if the iteration from `seed` does not converge.
    pub fn compensate_from(
        &self,
        world_from_tool: &Isometry3<f64>,
        seed: &[f64],
    ) -> Result<CompensatedPose, CompensationError> {
        match solve_ik(&self.calibrated_model, world_from_tool, seed, &self.ik) {
            Ok(s) => self.commands_for(s.q, s.report),
            // Near a wrist singularity the iteration can stall from one seed: try the
            // nominal closed-form branches before giving up.
            Err(IkError::NotConverged { .. }) => self.compensate(world_from_tool),
            Err(e) => Err(e.into()),
        }
    }

    /// Steps 2-5 (module docs) for joint values `q` of the calibrated model.
    fn commands_for(&self, q: Vec<f64>, ik: IkReport) -> Result<CompensatedPose, CompensationError> {
        let (theta_act, actuator, cmd) = self.joint_commands(&q)?;
        let nominal_pose_to_send = self.nominal_model.world_from_tool(&cmd);
        Ok(CompensatedPose {
            q,
            theta_act,
            actuator,
            cmd,
            nominal_pose_to_send,
            ik,
        })
    }

    /// Steps 2-4: `(theta_act, u, cmd)` for joint values `q` of the calibrated model.
    #[allow(clippy::type_complexity)]
    pub fn joint_commands(&self, q: &[f64]) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>), CompensationError> {
        let n = self.calibrated.dof();
        if q.len() != n {
            return Err(IkError::WrongLength {
                what: "joint values",
                expected: n,
                found: q.len(),
            }
            .into());
        }
        let q = self.without_sag(q)?;
        let theta = self.calibrated.active_from_joint_values(&q).map_err(|e| match e {
            crate::robot::ModelError::Coupling { joint, cause } => CompensationError::Coupling { joint, cause },
            other => other.into(),
        })?;
        let u: Vec<f64> = self
            .calibrated
            .joints
            .iter()
            .zip(&theta)
            .map(|(j, &t)| j.transmission.command_from_actual(t) + j.transducer_offset)
            .collect();
        let cmd = self.commands_from_actuators(&u)?;
        Ok((theta, u, cmd))
    }

    /// Step 4: the joint commands whose decoupling gives the actuator commands `u`.
    fn commands_from_actuators(&self, u: &[f64]) -> Result<Vec<f64>, CompensationError> {
        let mut cmd = Vec::with_capacity(u.len());
        for k in 0..u.len() {
            let c = match k {
                0 => u[0],
                _ => u[k] + self.controller.nominal_passive_into(k + 1, u[k - 1]),
            };
            if !c.is_finite() {
                return Err(CompensationError::NonFinite { joint: k + 1 });
            }
            cmd.push(c);
        }
        Ok(cmd)
    }

    /// The joint values before the calibrated model's sag that sag to `q` (module docs);
    /// `q` itself without a sag.
    fn without_sag(&self, q: &[f64]) -> Result<Vec<f64>, CompensationError> {
        let mut q0 = q.to_vec();
        if !self.calibrated.effects.sags() {
            return Ok(q0);
        }
        let load = crate::robot::PoseLoad {
            approach: &[],
            payload_kg: self.payload_kg,
        };
        for _ in 0..SAG_STEPS {
            let active = match self.calibrated.effects.compliance.is_empty() {
                true => Vec::new(),
                false => self.calibrated.active_from_joint_values(&q0)?,
            };
            let sagged = self.calibrated.sagged(&self.calibrated_model, &q0, &active, &load)?;
            let next: Vec<f64> = q
                .iter()
                .zip(sagged.iter().zip(&q0))
                .map(|(t, (s, z))| t - (s - z))
                .collect();
            let settled = next.iter().zip(&q0).all(|(a, b)| (a - b).abs() <= 1e-15);
            q0 = next;
            if settled {
                break;
            }
        }
        Ok(q0)
    }
}

impl From<crate::robot::ModelError> for CompensationError {
    fn from(e: crate::robot::ModelError) -> Self {
        Self::Model(e)
    }
}

impl From<IkError> for CompensationError {
    fn from(e: IkError) -> Self {
        Self::Ik(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn commands_invert_the_truth_semantics() {
        let desc = RobotDescription::asea_irb6l();
        let robot = crate::sim::paper_robot();
        let comp = Compensator::new(&robot, &desc).unwrap();
        let controller = Controller::from_description(&desc);
        let q = [0.2, -0.1, 0.3, -0.5, 0.7, 1.1];
        let (_, _, cmd) = comp.joint_commands(&q).unwrap();
        let back = robot.joint_values(&controller, &cmd).unwrap();
        for (a, b) in back.iter().zip(q) {
            // The transmission inverse is a Newton iteration to machine precision.
            assert_relative_eq!(*a, b, epsilon = 1e-12);
        }
    }

    #[test]
    fn an_ideal_robot_needs_no_compensation() {
        let desc = RobotDescription::asea_irb6l();
        let comp = Compensator::new(&RobotModel::ideal(&desc), &desc).unwrap();
        let q = [0.1, 0.2, -0.3, 0.4, -0.5, 0.6];
        let target = desc.nominal_model().world_from_tool(&q);
        let c = comp.compensate(&target).unwrap();
        for (a, b) in c.cmd.iter().zip(q) {
            assert_relative_eq!(*a, b, epsilon = 1e-9);
        }
        assert_relative_eq!(
            c.nominal_pose_to_send.to_homogeneous(),
            target.to_homogeneous(),
            epsilon = 1e-9
        );
    }

    /// A calibrated model with a sag (joints 2 and 3 under their links' loads and a payload)
    /// and backlash (joints 1-3): the commands of a sequence of poses, executed in order by a
    /// robot equal to the model (its backlash signed by the actuator commands' own history,
    /// [`crate::physics::ApproachTracker`]), reach every pose to the IK's tolerance; without
    /// the effects' steps they miss by the sag and the backlash.
    #[test]
    fn a_model_with_sag_compliance_and_backlash_is_compensated_in_sequence() {
        use crate::robot::{BacklashTerm, ComplianceTerm, LoadProduct, LoadTerm, PoseLoad, SagTerm, SpringLoad};
        let desc = RobotDescription::asea_irb6l();
        let mut robot = crate::sim::paper_robot();
        for (joint, link, load, coefficient) in [
            (2, 2, LoadTerm::Mass, 2e-4),
            (2, 3, LoadTerm::MomentX, -3e-4),
            (3, 3, LoadTerm::MomentY, 4e-4),
            (3, 6, LoadTerm::PayloadMass, 1e-5),
        ] {
            robot.effects.sag.push(SagTerm {
                joint,
                link,
                load,
                coefficient,
            });
        }
        robot.effects.backlash = (1..=3)
            .map(|joint| BacklashTerm {
                joint,
                half_band: 2e-4 * joint as f64,
            })
            .collect();
        // Joint 2's actuator compliance along the four-bar's load path (a diagnosis's member).
        let c = 2e-5;
        let scaled = |m: &crate::physics::LinkMass| crate::physics::LinkMass {
            mass_kg: m.mass_kg * c,
            first_moment_kg_m: m.first_moment_kg_m * c,
        };
        robot.effects.compliance.push(ComplianceTerm {
            joint: 2,
            spring: crate::robot::SpringSite::Actuator,
            reflects_load: true,
            carried: SpringLoad {
                links: crate::physics::LinkMass::from_description(&desc)
                    .iter()
                    .map(|m| LoadProduct::of(&scaled(m)))
                    .collect(),
                payload: LoadProduct {
                    mass_kg_rad_per_nm: c,
                    first_moment_kg_m_rad_per_nm: (robot.tool_frame.to_isometry().translation.vector * c).into(),
                },
            },
            reflected: None,
        });
        let payload_kg = 5.0;
        let comp = Compensator::new(&robot, &desc).unwrap().with_payload_kg(payload_kg);
        let geometric = Compensator::new(
            &RobotModel {
                effects: Default::default(),
                ..robot.clone()
            },
            &desc,
        )
        .unwrap();
        let nominal = desc.nominal_model();
        let q_path = [
            [0.1, 0.2, -0.3, 0.4, -0.5, 0.6],
            [0.3, 0.1, -0.2, 0.5, -0.4, 0.2],
            [0.2, 0.3, -0.4, 0.1, -0.6, 0.5],
            [0.2, 0.05, -0.1, 0.3, -0.2, 0.1],
        ];
        let required: Vec<Isometry3<f64>> = q_path.iter().map(|q| nominal.world_from_tool(q)).collect();
        let controller = Controller::from_description(&desc);
        let phi = robot.phi_model();
        let mut tracker = crate::physics::ApproachTracker::new(desc.dof(), crate::physics::UNMOVED_ACTUATOR_RAD);
        for (target, c) in required.iter().zip(comp.compensate_sequence(&required)) {
            let c = c.unwrap();
            let u = controller.decouple(&c.cmd).unwrap();
            let approach = tracker.step(&u).to_vec();
            let load = PoseLoad {
                approach: &approach,
                payload_kg,
            };
            let q = robot.loaded_joint_values(&controller, &phi, &c.cmd, &load).unwrap();
            let reached = phi.world_from_tool(&q);
            let miss = (reached.translation.vector - target.translation.vector).norm();
            assert!(miss < 1e-9, "missed by {miss:.3e} m");
            let plain = geometric.compensate(target).unwrap();
            let q_plain = robot.loaded_joint_values(&controller, &phi, &plain.cmd, &load).unwrap();
            let miss_plain = (phi.world_from_tool(&q_plain).translation.vector - target.translation.vector).norm();
            assert!(miss_plain > 1e-5, "the effects matter: {miss_plain:.3e} m");
        }
    }
}
