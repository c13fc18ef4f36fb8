//! The refit model: the calibrated robot with a geometric refit (row lengths and angles, joint
//! zero offsets, the identified function shapes, the tool targets, base and tool frames) plus
//! any number of candidate effects ([`Candidate`], each a member of a family), each a small
//! extension of the phi-model (paper appendix, eqs. A1-A4) and of the fig. 3 joint semantics.
//! `calibrate --refine` refines a calibration through it ([`crate::calibration::refine`]); the
//! diagnosis fits its candidates with it.

mod candidate;
mod compliance;
mod effect_set;
mod layout;
mod poses;
pub mod refine;
#[cfg(test)]
mod tests;

pub use candidate::{
    Candidate, DEFAULT_MAX_HARMONIC_ORDER, LoadPath, MIN_THERMAL_ROW_M, MassModel, ModelShape, SpringSite,
    ThermalLinks, TiltShape, drives_mechanism, is_geared, unmodelled_harmonic_order,
};
pub use poses::{
    Pose, free_poses_only, reference_temperature, split, target_count, training_mask, validation_poses,
    validation_poses_at_most,
};

use crate::kinematics::FixedFrames;
use crate::physics::{
    ApproachSource, ComplianceEffect, GearHarmonic, LinkMass, add_joint_period_errors, apply_axis_tilts,
    first_order_deflection, with_gear_harmonics,
};
use crate::robot::{Controller, CouplingFunction, RobotDescription, RobotModel};
use effect_set::EffectSet;
use nalgebra::{DMatrix, Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Gravity in the instrument frame \[m/s^2\] assumed by the compliance candidates.
pub const GRAVITY_M_S2: [f64; 3] = [0.0, 0.0, -9.81];

/// Number of refit coefficients of a coupling: a gear's ratio and harmonics, the fractional
/// form's numerator and denominator; none for a geometric four-bar (never calibrated).
fn coupling_parameters(g: Option<&CouplingFunction>) -> usize {
    match g {
        Some(CouplingFunction::Gear { sin, cos, .. }) => 1 + sin.len() + cos.len(),
        Some(CouplingFunction::Fractional { .. }) => 5,
        Some(CouplingFunction::FourBar(_)) | None => 0,
    }
}

/// Adds `d` to the coefficients of `g` (in [`coupling_parameters`] order); returns how many
/// it used.
fn perturb_coupling(g: Option<&mut CouplingFunction>, d: &[f64]) -> usize {
    match g {
        Some(CouplingFunction::Gear { ratio, sin, cos }) => {
            *ratio += d[0];
            let mut i = 1;
            for c in sin.iter_mut().chain(cos.iter_mut()) {
                *c += d[i];
                i += 1;
            }
            i
        }
        Some(CouplingFunction::Fractional { num, den }) => {
            for (c, x) in num.iter_mut().chain(den.iter_mut()).zip(d) {
                *c += x;
            }
            5
        }
        Some(CouplingFunction::FourBar(_)) | None => 0,
    }
}

/// A pose's payload as the description-mass candidates assume it: `payload_kg` on the tool
/// frame's origin (the measurement CSV gives only the mass), in the last link's frame; `None`
/// without one.
fn payload_at_tool(model: &crate::kinematics::PhiModel, payload_kg: f64) -> Option<(f64, Point3<f64>)> {
    (payload_kg > 0.0).then(|| (payload_kg, Point3::from(model.last_link_from_tool.translation.vector)))
}

/// A frame correction from a refit's translation \[m\] and rotation vector \[rad\] `p`.
fn frame_correction(p: &[f64]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(p[0], p[1], p[2]),
        UnitQuaternion::from_scaled_axis(Vector3::new(p[3], p[4], p[5])),
    )
}

/// The calibrated robot with the refit parameters and any candidates: predicts the measured
/// tool targets of a pose.
#[derive(Clone, Debug)]
pub struct Predictor {
    base: RobotModel,
    controller: Controller,
    masses: Vec<LinkMass>,
    tool_targets_m: Vec<Point3<f64>>,
    reference_c: f64,
    /// Per joint, the transmission harmonic orders the calibrator fits.
    harmonic_orders: Vec<usize>,
    shape: ModelShape,
    /// The candidate effects, their parameters after the refit's in this order.
    pub candidates: Vec<Candidate>,
    /// What the baseline refits besides the geometry.
    pub scope: RefitScope,
}

/// The work of an evaluation that the evaluations near it can reuse: per pose the actuator
/// commands (fig. 3 decoupling) and the active displacements (the transmissions' inversions,
/// eq. 8), with the transducer offset and transmission of every joint they were computed
/// with, and the model's constant frames (eq. A1).
struct JointMemo {
    transmissions: Vec<(f64, crate::robot::Transmission)>,
    poses: Vec<(Vec<f64>, Vec<f64>)>,
    frames: FixedFrames,
    /// Per pose, its joint values and links (`frames.world_from_links`) at the memo's
    /// parameters, where its frames are `frames` (`None` under a thermal candidate's rows or
    /// a tilt).
    links: Vec<Option<PoseLinks>>,
}

/// A pose's joint values and the links' frames at them (`FixedFrames::world_from_links`).
type PoseLinks = (Vec<f64>, Vec<Isometry3<f64>>);

/// Workspace features of a validation pose ([`Predictor::pose_features`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PoseFeatures {
    /// Joint values on the calibrated robot \[rad or m\].
    pub q: Vec<f64>,
    /// Horizontal distance of the tool point from the base's vertical axis \[m\].
    pub reach_m: f64,
    /// Gravity torque about every joint, payload included \[N m\].
    pub gravity_torque_nm: Vec<f64>,
}

/// What the baseline refit adjusts besides the geometry (rows `a`, `b`, `alpha`, `beta`, joint
/// zero offsets, tool targets, base and tool frames).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum RefitScope {
    /// The geometry only: the calibrated transmission and coupling shapes stay as the axis
    /// experiments fitted them.
    Geometry,
    /// Also every parameter the calibrator identifies from the shapes of its functions: the
    /// fitted transmission harmonics (eq. 8, the orders of each joint's `transmission_fit`)
    /// and every coefficient of each passive coupling (eq. 15: a gear's ratio and harmonics,
    /// the fractional form's five), whose noise-driven errors (fitted over the axis spans
    /// only) would otherwise dominate the validation residual.
    #[default]
    Identified,
}

impl Predictor {
    /// The predictor of the calibrated robot `base` for `desc`'s controller, link masses and
    /// tool targets (see [`Predictor::with_tool_targets`]); `reference_c` is the temperature
    /// the calibration holds at. No candidate.
    pub fn new(base: &RobotModel, desc: &RobotDescription, reference_c: f64, scope: RefitScope) -> Self {
        let harmonic_orders = (1..=desc.dof())
            .map(|j| unmodelled_harmonic_order(desc, j).saturating_sub(1))
            .collect();
        Predictor {
            base: base.clone(),
            controller: Controller::from_description(desc),
            masses: LinkMass::from_description(desc),
            tool_targets_m: desc.tool_targets_m(),
            reference_c,
            harmonic_orders,
            shape: ModelShape::of(desc),
            candidates: Vec::new(),
            scope,
        }
    }

    /// The same predictor with `candidates`.
    pub fn with_candidates(&self, candidates: &[Candidate]) -> Self {
        Predictor {
            candidates: candidates.to_vec(),
            ..self.clone()
        }
    }

    /// The same predictor with the tool targets (tool frame \[m\]) at `targets_m`.
    pub fn with_tool_targets(&self, targets_m: Vec<Point3<f64>>) -> Self {
        Predictor {
            tool_targets_m: targets_m,
            ..self.clone()
        }
    }

    /// The tool targets in the tool frame \[m\].
    pub fn tool_targets_m(&self) -> &[Point3<f64>] {
        &self.tool_targets_m
    }

    /// The tool targets at the refit's parameters `params`, in the calibrated tool frame
    /// (the refit's tool-frame correction applied to its corrected targets) \[m\].
    pub fn refit_tool_targets_m(&self, params: &[f64]) -> Vec<Point3<f64>> {
        let g = self.geometric_count();
        let tool = frame_correction(&params[g - 6..g]);
        self.targets(params).iter().map(|t| tool * t).collect()
    }

    /// The parameter layout's dependence on the robot.
    pub fn shape(&self) -> &ModelShape {
        &self.shape
    }

    /// Number of baseline refit parameters: per row `a`, `b` \[m\], `alpha`, `beta` \[rad\]; per
    /// joint a zero offset \[rad\]; with [`RefitScope::Identified`] per joint its fitted
    /// transmission harmonics (sin, cos per order \[rad\]) and the coefficients of the
    /// coupling into it; per tool target its position in the tool frame \[m\]; the base
    /// placement and the tool frame, each a translation \[m\] and a rotation vector \[rad\]
    /// (last). Redundant directions, e.g. joint 1's offset against the base yaw or the tool
    /// frame against three tool targets, are dropped by the fit's SVD.
    pub fn geometric_count(&self) -> usize {
        self.targets_start() + 3 * self.tool_targets_m.len() + 12
    }

    /// Transmission-harmonic and coupling-slope parameters of the refit.
    fn shape_count(&self) -> usize {
        match self.scope {
            RefitScope::Geometry => 0,
            RefitScope::Identified => {
                2 * self.harmonic_orders.iter().sum::<usize>()
                    + self
                        .base
                        .joints
                        .iter()
                        .map(|j| coupling_parameters(j.coupling_in.as_ref()))
                        .sum::<usize>()
            }
        }
    }

    /// Index of the first shape parameter.
    fn shape_start(&self) -> usize {
        4 * self.base.rows.len() + self.base.dof()
    }

    /// Index of the first tool-target parameter.
    fn targets_start(&self) -> usize {
        self.shape_start() + self.shape_count()
    }

    /// Number of parameters of the candidates.
    pub fn effect_count(&self) -> usize {
        self.candidates
            .iter()
            .map(|c| c.parameter_names(&self.shape).len())
            .sum()
    }

    /// Finite-difference step of every parameter.
    pub fn steps(&self) -> Vec<f64> {
        let mut s = vec![1e-6; self.geometric_count()];
        for c in &self.candidates {
            s.extend(c.steps(&self.shape));
        }
        s
    }

    /// The refit robot (geometry and identified shapes of `params`; transmission-period
    /// harmonics of the candidates in its transmissions) and the candidates' other effects.
    fn robot_and_effects(&self, params: &[f64]) -> (RobotModel, EffectSet) {
        let mut robot = self.base.clone();
        let rows = robot.rows.len();
        for (r, row) in robot.rows.iter_mut().enumerate() {
            row.a_m += params[4 * r];
            row.b_m += params[4 * r + 1];
            row.alpha_deg += params[4 * r + 2].to_degrees();
            row.beta_deg += params[4 * r + 3].to_degrees();
        }
        for (k, j) in robot.joints.iter_mut().enumerate() {
            j.transducer_offset += params[4 * rows + k];
        }
        let mut harmonics = Vec::new();
        if self.scope == RefitScope::Identified {
            let mut i = self.shape_start();
            for j in robot.joints.iter_mut() {
                i += perturb_coupling(j.coupling_in.as_mut(), &params[i..]);
            }
            for (k, &orders) in self.harmonic_orders.iter().enumerate() {
                for order in 1..=orders {
                    harmonics.push(GearHarmonic {
                        joint: k + 1,
                        order,
                        sin_rad: params[i],
                        cos_rad: params[i + 1],
                        period: Default::default(),
                    });
                    i += 2;
                }
            }
        }
        let mut effects = EffectSet::new(self.reference_c);
        let mut at = self.geometric_count();
        for c in &self.candidates {
            let n = c.parameter_names(&self.shape).len();
            effects.add(*c, &params[at..at + n], &self.shape);
            at += n;
        }
        let robot = with_gear_harmonics(&robot, &harmonics);
        (with_gear_harmonics(&robot, &effects.harmonics), effects)
    }

    /// The refit phi-model: `robot`'s with the base and tool corrections of `params`.
    fn model(&self, robot: &RobotModel, params: &[f64]) -> crate::kinematics::PhiModel {
        let g = self.geometric_count();
        let mut model = robot.phi_model();
        model.world_from_base = frame_correction(&params[g - 12..g - 6]) * model.world_from_base;
        model.last_link_from_tool *= frame_correction(&params[g - 6..g]);
        model
    }

    /// The tool targets corrected by `params` (tool frame \[m\]).
    fn targets(&self, params: &[f64]) -> Vec<Point3<f64>> {
        let start = self.targets_start();
        self.tool_targets_m
            .iter()
            .enumerate()
            .map(|(i, t)| t + Vector3::from_column_slice(&params[start + 3 * i..start + 3 * i + 3]))
            .collect()
    }

    /// Joint values `(q, active displacements)` of `pose` on `robot` (fig. 3 controller,
    /// transmissions, the candidates' joint-period harmonics and backlash lags, passive
    /// couplings); `None` when the command cannot be executed.
    fn joint_values(&self, robot: &RobotModel, effects: &EffectSet, pose: &Pose) -> Option<(Vec<f64>, Vec<f64>)> {
        let u = self.controller.decouple(&pose.cmd).ok()?;
        let active = robot.active_displacements(&u).ok()?;
        self.joint_values_from(robot, effects, pose, active)
    }

    /// [`Predictor::joint_values`] from the transmissions' active displacements `active`.
    fn joint_values_from(
        &self,
        robot: &RobotModel,
        effects: &EffectSet,
        pose: &Pose,
        mut active: Vec<f64>,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        add_joint_period_errors(&effects.harmonics, &mut active);
        for &(k, source, half_band_rad) in &effects.backlash {
            let approach = match source {
                ApproachSource::Command => pose.approach[k],
                ApproachSource::Actuator => pose.actuator_approach[k],
            };
            active[k] -= approach * half_band_rad;
        }
        let mut q = active.clone();
        for k in 1..q.len() {
            if let Some(g) = &robot.joints[k].coupling_in {
                q[k] += g.try_passive(active[k - 1]).ok()?;
            }
        }
        Some((q, active))
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.base.dof()
    }

    /// The workspace features of `pose` on the calibrated robot (no refit, no candidate):
    /// joint values, the tool point's horizontal distance from the base's vertical axis, and
    /// the gravity torque about every joint with the pose's payload (the actuator load before
    /// any coupling, `first_order_deflection` at unit stiffness, the description's masses).
    /// `None` when the command cannot be executed.
    pub fn pose_features(&self, pose: &Pose) -> Option<PoseFeatures> {
        let n = self.base.dof();
        let (q, _) = self.joint_values(&self.base, &EffectSet::new(self.reference_c), pose)?;
        let model = self.base.phi_model();
        let tool = model.poses(&q).world_from_link[n - 1] * model.last_link_from_tool;
        let base = model.world_from_base;
        let tool_in_base = base.inverse() * Point3::from(tool.translation.vector);
        let payload = payload_at_tool(&model, pose.payload_kg);
        let unit = ComplianceEffect::new(vec![1.0; n], GRAVITY_M_S2);
        let gravity_torque_nm = first_order_deflection(&model, &q, &self.masses, payload, &unit);
        Some(PoseFeatures {
            q,
            reach_m: tool_in_base.x.hypot(tool_in_base.y),
            gravity_torque_nm,
        })
    }

    /// Residuals `measured - predicted` \[m\] (3 per target) of `poses` for `params`; `None`
    /// when a command cannot be executed by the model (a transmission that does not invert,
    /// a compliance under which the arm buckles).
    pub fn residuals(&self, params: &[f64], poses: &[&Pose]) -> Option<Vec<f64>> {
        self.residuals_offset(params, poses, &[], None)
    }

    /// The transmissions' work for `poses` at `params`, for the evaluations near `params`
    /// ([`JointMemo`]); `None` when a command cannot be executed.
    fn joint_memo(&self, params: &[f64], poses: &[&Pose]) -> Option<JointMemo> {
        let (robot, effects) = self.robot_and_effects(params);
        let memo_poses: Vec<(Vec<f64>, Vec<f64>)> = poses
            .iter()
            .map(|pose| {
                let u = self.controller.decouple(&pose.cmd).ok()?;
                let active = robot.active_displacements(&u).ok()?;
                Some((u, active))
            })
            .collect::<Option<_>>()?;
        let frames = FixedFrames::new(self.model(&robot, params));
        // The links of every pose whose frames are the model's (no thermal candidate's rows of
        // its temperature, no tilt): what the columns that leave the chain below alone reuse.
        let links = poses
            .iter()
            .zip(&memo_poses)
            .map(|(pose, (_, active))| {
                if !effects.tilts.is_empty() {
                    return None;
                }
                let (q, expanded) = self.pose_joints(&robot, &effects, &frames, pose, Some(active.clone()), &[])?;
                expanded.is_none().then(|| {
                    let links = frames.world_from_links(&q);
                    (q, links)
                })
            })
            .collect();
        Some(JointMemo {
            frames,
            links,
            transmissions: robot
                .joints
                .iter()
                .map(|j| (j.transducer_offset, j.transmission.clone()))
                .collect(),
            poses: memo_poses,
        })
    }

    /// The active displacements of pose `i` of `memo` on `robot`: the memo's, with those of
    /// the joints whose transducer offset or transmission differs from the memo's
    /// (`changed`) inverted again as [`RobotModel::active_displacements`] does.
    fn active_from_memo(&self, robot: &RobotModel, memo: &JointMemo, changed: &[usize], i: usize) -> Option<Vec<f64>> {
        let (u, active) = &memo.poses[i];
        let mut active = active.clone();
        for &k in changed {
            let j = &robot.joints[k];
            active[k] = j.transmission.actual_from_command(u[k] - j.transducer_offset)?;
        }
        Some(active)
    }

    /// The sensitivity `X = d prediction / d p` of the residual rows of `poses` to the
    /// parameters `columns` at `params`: the central differences of [`Predictor::residuals`]
    /// by the project's one tool ([`crate::calibration::refine::sensitivity`]) with the steps
    /// `steps[columns]`, bit for bit, but with the transmission inversions (most of an
    /// evaluation) done once at `params` (kept in a private memo): a column redoes only the joint its
    /// parameter moves (a zero offset, a transmission harmonic), none for the rest (rows,
    /// couplings, tool targets, frames, the backlash, tilt, thermal, scale and compliance
    /// candidates'); likewise the model's constant frames, of which a row's column redoes
    /// one. `None` when a command cannot be executed.
    pub fn sensitivity(
        &self,
        params: &[f64],
        columns: std::ops::Range<usize>,
        poses: &[&Pose],
        steps: &[f64],
    ) -> Option<DMatrix<f64>> {
        let memo = self.joint_memo(params, poses);
        crate::calibration::refine::sensitivity(
            |e| {
                let mut p = params.to_vec();
                p[columns.clone()].copy_from_slice(e);
                self.residuals_offset(&p, poses, &[], memo.as_ref())
            },
            &params[columns.clone()],
            &steps[columns.clone()],
        )
    }

    /// [`Predictor::residuals`] with the joint values of every pose offset by `offset_rad`
    /// (after the sag; empty: none): the function [`Predictor::joint_sensitivity`]
    /// differences. With a `memo` of the same poses, the active displacements of the joints
    /// whose transmission is the memo's and the frames of the rows that are its come from it
    /// (the same values bit for bit).
    fn residuals_offset(
        &self,
        params: &[f64],
        poses: &[&Pose],
        offset_rad: &[f64],
        memo: Option<&JointMemo>,
    ) -> Option<Vec<f64>> {
        let (robot, effects) = self.robot_and_effects(params);
        let memo = memo.filter(|m| m.poses.len() == poses.len());
        let frames = match memo {
            Some(m) => FixedFrames::new_near(self.model(&robot, params), &m.frames),
            None => FixedFrames::new(self.model(&robot, params)),
        };
        let targets = self.targets(params);
        let changed: Vec<usize> = memo.map_or_else(Vec::new, |m| {
            (robot.joints.iter().zip(&m.transmissions).enumerate())
                .filter(|(_, (j, (offset, t)))| {
                    j.transducer_offset.to_bits() != offset.to_bits() || j.transmission != *t
                })
                .map(|(k, _)| k)
                .collect()
        });
        let mut out = Vec::with_capacity(poses.len() * 9);
        for (i, pose) in poses.iter().enumerate() {
            let active = match memo {
                Some(m) => Some(self.active_from_memo(&robot, m, &changed, i)?),
                None => None,
            };
            let (q, expanded) = self.pose_joints(&robot, &effects, &frames, pose, active, offset_rad)?;
            let frames_t = expanded.as_ref().unwrap_or(&frames);
            let model_t = frames_t.model();
            // Without a tilt only the last link's frame is needed (the same numbers), from the
            // memo's links where the chain below is the memo's.
            let near = memo.and_then(|m| Some((m, m.links.get(i)?.as_ref()?)));
            let last_link = if let (true, Some((m, (near_q, links)))) = (effects.tilts.is_empty(), near) {
                frames_t.world_from_last_link_near(&q, &m.frames, near_q, links)
            } else if effects.tilts.is_empty() {
                frames_t.world_from_last_link(&q)
            } else {
                let mut links = frames_t.poses(&q).world_from_link;
                apply_axis_tilts(&effects.tilts, model_t, &q, &mut links);
                links[links.len() - 1]
            };
            let tool = last_link * model_t.last_link_from_tool;
            for (id, measured) in &pose.targets {
                let t = targets.get(*id)?;
                let p = (tool * t).coords * effects.scale;
                out.extend((measured.coords - p).iter());
            }
        }
        Some(out)
    }

    /// The joint values of `pose` on `robot` with `effects` (from the active displacements
    /// `active` when given), the sag and `offset_rad` added, and the pose's frames when a
    /// thermal candidate changes the rows with its temperature (else `frames` serve every
    /// pose); `None` when the command cannot be executed.
    fn pose_joints(
        &self,
        robot: &RobotModel,
        effects: &EffectSet,
        frames: &FixedFrames,
        pose: &Pose,
        active: Option<Vec<f64>>,
        offset_rad: &[f64],
    ) -> Option<(Vec<f64>, Option<FixedFrames>)> {
        let (mut q, active) = match active {
            Some(active) => self.joint_values_from(robot, effects, pose, active)?,
            None => self.joint_values(robot, effects, pose)?,
        };
        let expanded = effects
            .expanded_at(frames.model(), pose.temperature_c)
            .map(FixedFrames::new);
        let model_t = expanded.as_ref().unwrap_or(frames).model();
        let sag = self.sag(robot, model_t, effects, &q, &active, pose.payload_kg)?;
        for (qk, d) in q.iter_mut().zip(sag) {
            *qk += d;
        }
        for (qk, d) in q.iter_mut().zip(offset_rad) {
            *qk += d;
        }
        Some((q, expanded))
    }

    /// The largest sag of a compliance candidate's own joint over `poses` \[rad\], at effect
    /// parameters `effect_params` (the refit at zero): what its fitted parameters mean
    /// physically, for the plausibility check. `None` for another candidate or when a command
    /// cannot be executed.
    pub fn largest_sag_rad(&self, candidate: Candidate, effect_params: &[f64], poses: &[&Pose]) -> Option<f64> {
        let Candidate::JointCompliance { joint, .. } = candidate else {
            return None;
        };
        let p = self.with_candidates(&[candidate]);
        let mut params = vec![0.0; p.geometric_count()];
        params.extend_from_slice(effect_params);
        let (robot, effects) = p.robot_and_effects(&params);
        let model = p.model(&robot, &params);
        let mut largest: f64 = 0.0;
        for pose in poses {
            let (q, active) = p.joint_values(&robot, &effects, pose)?;
            let model_t = effects.model_at(&model, pose.temperature_c);
            let sag = p.sag(&robot, &model_t, &effects, &q, &active, pose.payload_kg)?;
            largest = largest.max(sag[joint - 1].abs());
        }
        Some(largest)
    }
}
