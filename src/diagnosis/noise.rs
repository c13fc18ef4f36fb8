//! Noise-only replicas of a campaign: the same commands on the CALIBRATED robot, each target
//! where the calibrated model puts it, moved by the robot's repeatability jitter and by
//! isotropic Gaussian instrument noise of the stated 3-D RMS (the "Monte-Carlo of the same
//! commands on the calibrated robot" of the diagnosis).
//!
//! The jitter is the one `calibrate` models (`CalibrationOptions::repeatability_sigma_rad`,
//! default the description's `repeatability_sigma`): a Gaussian error of each joint value,
//! drawn anew each time the joint's actuator is re-positioned (its actuator command changes by
//! more than [`UNMOVED_ACTUATOR_RAD`]) and held while it is not, so in an axis experiment only
//! the swept joint jitters from step to step.

use super::DiagnosisError;
use super::Pose;
use crate::calibration::procedure::Calibration;
use crate::kinematics::FixedFrames;
use crate::measurement::{Measurement, MeasurementSet};
use crate::numerics::finite_diff::central_difference;
use crate::physics::UNMOVED_ACTUATOR_RAD;
use crate::plan::TOOL_EXPERIMENT;
use crate::robot::commands_to_internal;
use crate::robot::{Controller, ModelError, RobotDescription, RobotModel};
use nalgebra::{Point3, Vector3};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use std::collections::HashMap;

/// What a noise-only replica draws: the instrument's noise and the robot's repeatability.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseModel {
    /// Instrument noise, 3-D RMS of a point \[m\] (each coordinate `/ sqrt(3)`).
    pub noise_rms_3d_m: f64,
    /// Repeatability of each joint: standard deviation of its value per re-positioning
    /// \[rad or m\].
    pub repeatability_rad: Vec<f64>,
}

/// One row of a campaign on the calibrated robot, noise-free (its joint values and actuator
/// commands are in [`CleanCampaign::joints`]).
#[derive(Clone, Debug)]
struct CleanRow {
    /// The link carrying the target (0-based) and the target in its moving frame \[m\].
    link: usize,
    point_in_link_m: Point3<f64>,
    /// An axis target: its index among the campaign's (experiment, target) pairs; a tool
    /// target: its position in the tool frame \[m\].
    target: RowTarget,
}

/// What a row measures.
#[derive(Clone, Copy, Debug)]
enum RowTarget {
    /// An axis target, by its index among the campaign's (experiment, target) pairs.
    Axis(usize),
    /// A tool target at this position in the tool frame \[m\].
    Tool(Point3<f64>),
}

/// A campaign's rows on the calibrated robot: where every target is without noise, and what
/// the jitter moves. Axis-experiment targets sit at their mean position in their link's frame
/// (target 0's link for a target the description does not place), estimated from the
/// measurements through the calibrated model; tool targets at `tool_targets_m` (tool frame).
#[derive(Clone, Debug)]
pub struct CleanCampaign {
    /// The calibrated model with its constant frames (computed once for every row).
    frames: FixedFrames,
    rows: Vec<CleanRow>,
    /// Every row's calibrated joint values then its actuator commands (fig. 3 decoupling: when
    /// they change, the joints re-position), `2 * width` numbers a row, one after the other:
    /// one allocation for the campaign, not two a row (a million-row file's rows).
    joints: Vec<f64>,
    /// The number of joint values (and of actuator commands) of a row.
    width: usize,
}

fn model_error(message: String) -> DiagnosisError {
    DiagnosisError::Model { message }
}

/// The link (0-based) carrying the target of axis-experiment row `m`: a target the
/// description does not place (e.g. a third reflector) turns rigidly with target 0, since only
/// the experiment's joint moves; without `axis_targets` for the joint, the last link (as the
/// calibrator takes it: the held joints do not move within a sweep).
fn axis_target_link(desc: &RobotDescription, m: &Measurement) -> usize {
    let Some(t) = desc.axis_targets_of(m.moved_joint) else {
        return desc.dof() - 1;
    };
    match (m.target, t.target1) {
        (1, Some(t1)) => t1.link - 1,
        _ => t.target0.link - 1,
    }
}

impl CleanCampaign {
    /// The rows of `set` on the calibrated robot `cal` (module docs).
    pub fn new(
        set: &MeasurementSet,
        cal: &Calibration,
        desc: &RobotDescription,
        tool_targets_m: &[Point3<f64>],
    ) -> Result<Self, DiagnosisError> {
        Self::on_robot(set, &cal.robot, desc, tool_targets_m)
    }

    /// [`Self::new`] on the model `robot` (e.g. the one a calibration converges to).
    pub fn on_robot(
        set: &MeasurementSet,
        robot: &RobotModel,
        desc: &RobotDescription,
        tool_targets_m: &[Point3<f64>],
    ) -> Result<Self, DiagnosisError> {
        let controller = Controller::from_description(desc);
        let model = robot.phi_model();
        let width = desc.dof();
        let mut joints = Vec::with_capacity(2 * width * set.rows().len());
        let approach = crate::physics::actuator_approach_by_pose(set.rows(), desc);
        for m in set.rows() {
            let q = calibrated_joint_values(robot, &controller, &model, desc, m, &approach)?;
            let u = controller
                .decouple(&commands_to_internal(desc, &m.cmd))
                .map_err(|e| model_error(format!("experiment {} step {}: {e}", m.experiment, m.step)))?;
            if q.len() != width || u.len() != width {
                return Err(model_error(format!(
                    "experiment {} step {}: {} joint values and {} actuator commands for {width} joints",
                    m.experiment,
                    m.step,
                    q.len(),
                    u.len()
                )));
            }
            joints.extend_from_slice(&q);
            joints.extend_from_slice(&u);
        }
        drop(approach);
        let q_of = |i: usize| &joints[2 * width * i..2 * width * i + width];
        // Mean link-frame position of each axis target.
        let mut sums: HashMap<(&str, usize), (Vector3<f64>, usize, usize)> = HashMap::new();
        for (i, m) in set.rows().iter().enumerate() {
            if m.moved_joint > 0 {
                let l = axis_target_link(desc, m);
                let p = model.poses(q_of(i)).world_from_link[l].inverse() * m.position_m();
                let group = sums.len();
                let e = sums
                    .entry((m.experiment.as_str(), m.target))
                    .or_insert((Vector3::zeros(), 0, group));
                e.0 += p.coords;
                e.1 += 1;
            }
        }
        let last = desc.dof() - 1;
        let rows = set
            .rows()
            .iter()
            .map(|m| {
                let (link, point_in_link_m, target) = if m.moved_joint > 0 {
                    let l = axis_target_link(desc, m);
                    let (s, n, group) = sums[&(m.experiment.as_str(), m.target)];
                    (l, Point3::from(s / n as f64), RowTarget::Axis(group))
                } else {
                    let t = tool_targets_m.get(m.target).ok_or_else(|| {
                        model_error(format!(
                            "experiment {}: tool target {} is not in the description",
                            m.experiment, m.target
                        ))
                    })?;
                    (last, model.last_link_from_tool * t, RowTarget::Tool(*t))
                };
                Ok(CleanRow {
                    link,
                    point_in_link_m,
                    target,
                })
            })
            .collect::<Result<_, DiagnosisError>>()?;
        Ok(CleanCampaign {
            frames: FixedFrames::new(model),
            rows,
            joints,
            width,
        })
    }

    /// Row `i`'s calibrated joint values.
    fn q(&self, i: usize) -> &[f64] {
        let at = 2 * self.width * i;
        &self.joints[at..at + self.width]
    }

    /// Row `i`'s actuator commands.
    fn u(&self, i: usize) -> &[f64] {
        let at = 2 * self.width * i + self.width;
        &self.joints[at..at + self.width]
    }

    /// The number of axis targets (one per experiment and target): the nuisance positions of
    /// [`Self::positions_on`].
    pub fn axis_target_count(&self) -> usize {
        self.rows
            .iter()
            .filter_map(|r| match r.target {
                RowTarget::Axis(g) => Some(g + 1),
                RowTarget::Tool(_) => None,
            })
            .max()
            .unwrap_or(0)
    }

    /// The campaign predicted by another model of the same structure (e.g. the calibrated one
    /// moved along its parameter vector): every row's actuator commands through `robot`'s
    /// transmissions and couplings (eqs. A1-A4; the joint readings are never used), the axis
    /// targets at their positions in their links' frames moved by `axis_target_shift_m` (per
    /// target, [`Self::axis_target_count`]), the tool targets through `robot`'s tool frame
    /// \[m\]. What the whole-campaign Cramer-Rao bound differentiates.
    pub fn positions_on(
        &self,
        robot: &RobotModel,
        axis_target_shift_m: &[Vector3<f64>],
    ) -> Result<Vec<Point3<f64>>, ModelError> {
        let model = robot.phi_model();
        self.rows
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let q = robot.joint_values_from_actuators(self.u(i))?;
                let point = match r.target {
                    RowTarget::Axis(g) => r.point_in_link_m + axis_target_shift_m[g],
                    RowTarget::Tool(t) => model.last_link_from_tool * t,
                };
                Ok(model.poses(&q).world_from_link[r.link] * point)
            })
            .collect()
    }

    /// The frame of every row's target link at its joint values (world from link): where a
    /// target fixed on the link sits for each row.
    pub fn link_frames(&self) -> Vec<nalgebra::Isometry3<f64>> {
        self.rows
            .iter()
            .enumerate()
            .map(|(i, r)| self.frames.poses(self.q(i)).world_from_link[r.link])
            .collect()
    }

    /// Noise-free positions of every row \[m\].
    pub fn positions(&self) -> Vec<Point3<f64>> {
        (0..self.rows.len()).map(|i| self.position(i, None)).collect()
    }

    /// How row `i`'s target moves with joint `joint`'s (0-based) value \[m per rad or m\]:
    /// central differences of the target's position with a step of 1e-6 (rad or m), far below
    /// the chain's curvature scale.
    pub fn joint_sensitivity(&self, i: usize, joint: usize) -> Vector3<f64> {
        let moved = |t: f64| {
            let mut dq = vec![0.0; self.width];
            dq[joint] = t;
            self.position(i, Some(&dq))
        };
        central_difference(moved, 1e-6)
    }

    /// Where row `i`'s target is with the joint values moved by `dq`.
    fn position(&self, i: usize, dq: Option<&[f64]>) -> Point3<f64> {
        let (r, q) = (&self.rows[i], self.q(i));
        let poses = match dq {
            Some(d) => self
                .frames
                .poses(&q.iter().zip(d).map(|(a, b)| a + b).collect::<Vec<f64>>()),
            None => self.frames.poses(q),
        };
        poses.world_from_link[r.link] * r.point_in_link_m
    }
}

/// The repeatability jitter of a sequence of executions (module docs): each execution draws
/// one standard normal per joint (so the random stream does not depend on which actuators
/// moved) and keeps the previous draw of every joint whose actuator did not move.
struct Jitter<'a> {
    sigma: &'a [f64],
    last: Option<(Vec<f64>, Vec<f64>)>,
}

impl<'a> Jitter<'a> {
    fn new(sigma: &'a [f64]) -> Self {
        Jitter { sigma, last: None }
    }

    /// The joint-value errors of an execution at actuator commands `u`.
    fn draw<R: Rng + ?Sized>(&mut self, u: &[f64], rng: &mut R) -> Vec<f64> {
        let mut z: Vec<f64> = u.iter().map(|_| StandardNormal.sample(rng)).collect();
        if let Some((last_u, last_z)) = &self.last {
            for ((z, (now, before)), held) in z.iter_mut().zip(u.iter().zip(last_u)).zip(last_z) {
                if (now - before).abs() <= UNMOVED_ACTUATOR_RAD {
                    *z = *held;
                }
            }
        }
        let dq = z.iter().zip(self.sigma).map(|(z, s)| z * s).collect();
        self.last = Some((u.to_vec(), z));
        dq
    }
}

/// Noise-free positions of every row of `set` on the calibrated robot \[m\], tool targets at
/// the description's ([`CleanCampaign::positions`]).
pub fn clean_positions(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
) -> Result<Vec<Point3<f64>>, DiagnosisError> {
    Ok(CleanCampaign::new(set, cal, desc, &desc.tool_targets_m())?.positions())
}

/// The joint values of `m`'s commands on `robot` (the controller, then its transmissions
/// and couplings, and the model's effects under the row's payload and `approach`, its pose's
/// actuator approach directions; `phi` is `robot`'s geometry).
pub(super) fn calibrated_joint_values(
    robot: &RobotModel,
    controller: &Controller,
    phi: &crate::kinematics::PhiModel,
    desc: &RobotDescription,
    m: &Measurement,
    approach: &HashMap<(String, usize), Vec<f64>>,
) -> Result<Vec<f64>, DiagnosisError> {
    let load = crate::robot::PoseLoad {
        approach: approach.get(&(m.experiment.clone(), m.step)).map_or(&[], Vec::as_slice),
        payload_kg: m.payload_kg,
    };
    robot
        .loaded_joint_values(controller, phi, &commands_to_internal(desc, &m.cmd), &load)
        .map_err(|e| model_error(format!("experiment {} step {}: {e}", m.experiment, m.step)))
}

/// Whether `m` is a validation measurement (`docs/formats.md#measurement-csv`: `moved_joint = 0`, not the
/// tool experiment).
pub fn is_validation(m: &Measurement) -> bool {
    m.moved_joint == 0 && m.experiment != TOOL_EXPERIMENT
}

/// One noise-only replica: `set`'s rows at `clean`, jittered and with isotropic noise
/// ([`NoiseModel`]); validation rows get neither only when `validation_noise` is false (the
/// diagnoser draws theirs separately, many per replica, [`ValidationRows::validation_draw`]).
pub fn replica<R: Rng + ?Sized>(
    set: &MeasurementSet,
    clean: &CleanCampaign,
    noise: &NoiseModel,
    validation_noise: bool,
    rng: &mut R,
) -> Result<MeasurementSet, DiagnosisError> {
    let sigma = noise.noise_rms_3d_m / 3f64.sqrt();
    let mut jitter = Jitter::new(&noise.repeatability_rad);
    let mut execution: Option<((&str, usize), Vec<f64>)> = None;
    let mut rows = Vec::with_capacity(set.rows().len());
    for (i, m) in set.rows().iter().enumerate().take(clean.rows.len()) {
        let mut out = m.clone();
        let p = if validation_noise || !is_validation(m) {
            let key = (m.experiment.as_str(), m.step);
            if execution.as_ref().is_none_or(|(k, _)| *k != key) {
                execution = Some((key, jitter.draw(clean.u(i), rng)));
            }
            let dq = execution.as_ref().map(|(_, d)| d.as_slice());
            clean.position(i, dq).coords
                + Vector3::from_fn(|_, _| sigma * Distribution::<f64>::sample(&StandardNormal, rng))
        } else {
            clean.position(i, None).coords
        };
        for (c, x) in out.position_mm.iter_mut().zip(p.iter()) {
            *c = x * 1e3;
        }
        rows.push(out);
    }
    MeasurementSet::new(set.joint_count(), rows).map_err(|e| model_error(format!("noise replica: {e}")))
}

/// One validation pose on the calibrated robot: joint values, actuator commands, and per target
/// (first residual row, target in the last link's frame, noise-free position).
type ValidationPose = (Vec<f64>, Vec<f64>, Vec<(usize, Point3<f64>, Point3<f64>)>);

/// The validation poses of a campaign on the calibrated robot, for drawing their noise: per
/// pose (file order) its joint values, actuator commands and the residual rows of its targets.
pub struct ValidationRows {
    /// The calibrated model with its constant frames.
    frames: FixedFrames,
    /// Per pose: joint values, actuator commands, and per target (first residual row, target
    /// in the last link's frame, noise-free position).
    poses: Vec<ValidationPose>,
}

impl ValidationRows {
    /// The validation poses `poses` (file order) on the calibrated robot `cal`, their tool
    /// targets at `tool_targets_m` (tool frame); `row_of(pose, k)` is the first residual row of
    /// the pose's `k`-th target.
    pub fn new(
        cal: &Calibration,
        desc: &RobotDescription,
        tool_targets_m: &[Point3<f64>],
        poses: &[Pose],
        row_of: impl Fn(usize, usize) -> usize,
    ) -> Result<Self, DiagnosisError> {
        let controller = Controller::from_description(desc);
        let model = cal.robot.phi_model();
        let n = desc.dof();
        let mut out = Vec::with_capacity(poses.len());
        for (i, pose) in poses.iter().enumerate() {
            let fail = |e: crate::robot::ModelError| model_error(format!("validation step {}: {e}", pose.step));
            let load = crate::robot::PoseLoad {
                approach: &pose.actuator_approach,
                payload_kg: pose.payload_kg,
            };
            let q = cal
                .robot
                .loaded_joint_values(&controller, &model, &pose.cmd, &load)
                .map_err(fail)?;
            let u = controller.decouple(&pose.cmd).map_err(fail)?;
            let link = model.poses(&q).world_from_link[n - 1];
            let mut targets = Vec::with_capacity(pose.targets.len());
            for (k, (id, _)) in pose.targets.iter().enumerate() {
                let t = tool_targets_m
                    .get(*id)
                    .ok_or_else(|| model_error(format!("tool target {id} is not in the description")))?;
                let in_link = model.last_link_from_tool * t;
                targets.push((row_of(i, k), in_link, link * in_link));
            }
            out.push((q, u, targets));
        }
        Ok(ValidationRows {
            frames: FixedFrames::new(model),
            poses: out,
        })
    }

    /// Adds one draw of the validation noise to `column` (residual rows, `measured -
    /// predicted`): the jitter's displacement of every target and isotropic instrument noise.
    pub fn validation_draw<R: Rng + ?Sized>(&self, noise: &NoiseModel, column: &mut [f64], rng: &mut R) {
        let sigma = noise.noise_rms_3d_m / 3f64.sqrt();
        let mut jitter = Jitter::new(&noise.repeatability_rad);
        let jittered = noise.repeatability_rad.iter().any(|s| *s > 0.0);
        for (q, u, targets) in &self.poses {
            let dq = jitter.draw(u, rng);
            let link = jittered.then(|| {
                let q: Vec<f64> = q.iter().zip(&dq).map(|(a, b)| a + b).collect();
                self.frames.world_from_last_link(&q)
            });
            for (row, in_link, clean) in targets {
                let moved = link.map_or(Vector3::zeros(), |l| l * in_link - clean);
                for c in 0..3 {
                    let z: f64 = StandardNormal.sample(rng);
                    column[row + c] += moved[c] + sigma * z;
                }
            }
        }
    }
}
