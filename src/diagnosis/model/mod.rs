//! The parametric models the diagnoser fits: the calibrated robot with a geometric refit
//! (row lengths and angles, joint zero offsets, base and tool frames) plus at most one
//! candidate effect, each a small extension of the phi-model (paper appendix, eqs. A1-A4) and
//! of the fig. 3 joint semantics.

use super::poses::Pose;
use crate::kinematics::JointKind;
use crate::physics::{
    AxisWobble, ComplianceEffect, CompliantLoad, GearHarmonic, LinkMass, PassiveSlope, ThermalEffect, apply_wobble,
    coupled_static_deflection, with_gear_harmonics,
};
use crate::robot::{Controller, CouplingFunction, RobotDescription, RobotModel, TransmissionFitForm};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Gravity in the instrument frame \[m/s^2\] assumed by the compliance candidate.
pub const GRAVITY_M_S2: [f64; 3] = [0.0, 0.0, -9.81];

/// Order of the wobble candidate: order 0 is a fixed tilt of the axis and order 1 a fixed
/// tilt of the link on its bearing (its points still run on circles about a tilted axis), both
/// absorbed exactly by the calibrated geometry; 2 is the lowest order visible afterwards.
pub const WOBBLE_ORDER: i32 = 2;

/// The lowest transmission harmonic of `joint` (1-based) that the calibrator does NOT fit:
/// one above the order of the joint's declared `transmission_fit` (eq. 8), in the
/// transmission's own angle (the gear angle for a gear form). An extra harmonic of a fitted
/// order would be a calibration error, not an unmodelled effect.
pub fn unmodelled_harmonic_order(desc: &RobotDescription, joint: usize) -> usize {
    match desc.joints.get(joint.wrapping_sub(1)).map(|j| j.transmission_fit) {
        Some(TransmissionFitForm::Harmonic { order } | TransmissionFitForm::Gear { order, .. }) => order + 1,
        None => 1,
    }
}

/// A candidate unmodelled effect (`docs/formats.md#diagnosis-json` names).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "effect", rename_all = "snake_case")]
pub enum Candidate {
    /// Actuator `joint` sags by `c Q_j(q + dq)`, `Q_j` the gravity torque about it (plus the
    /// load a four-bar reflects, and the pose's payload at the tool frame's origin) at the
    /// deflected pose, and the sag drives the passive coupling into the next joint (one
    /// compliance `c` \[rad/(N m)\]; the exact static equilibrium
    /// [`coupled_static_deflection`], the rapier arm's physics). The part of the sag that
    /// follows joint `joint`'s own angle was fitted into its transmission by the calibration;
    /// the refit's transmission harmonics take it back out, so the candidate's trace is what
    /// the posture and the payload add.
    JointCompliance {
        /// 1-based joint.
        joint: usize,
    },
    /// The active displacement of `joint` lags by `h` against its approach direction (half
    /// band `h` \[rad\]).
    Backlash {
        /// 1-based joint.
        joint: usize,
    },
    /// Row lengths `a`, `b` scale by `1 + alpha (T - T_ref)`, `T_ref` the axis experiments'
    /// mean temperature.
    ThermalExpansion,
    /// An extra harmonic (sin, cos \[rad\]) of order `order` on the joint's transmission
    /// (eq. 8), the lowest order the calibrator does not fit ([`unmodelled_harmonic_order`]).
    GearHarmonic {
        /// 1-based joint.
        joint: usize,
        /// Harmonic order.
        order: usize,
    },
    /// A tilt `(x, y)` \[rad\] of the joint's axis turning at [`WOBBLE_ORDER`] times the joint.
    AxisWobble {
        /// 1-based joint.
        joint: usize,
    },
    /// Measured coordinates `(1 + ppm 1e-6)` times the true ones about the instrument origin.
    InstrumentScale,
}

impl Candidate {
    /// The effect name of `diagnosis.json` (`docs/formats.md#diagnosis-json`).
    pub fn effect_name(&self) -> &'static str {
        match self {
            Candidate::JointCompliance { .. } => "joint_compliance",
            Candidate::Backlash { .. } => "backlash",
            Candidate::ThermalExpansion => "thermal_expansion",
            Candidate::GearHarmonic { .. } => "gear_harmonic",
            Candidate::AxisWobble { .. } => "axis_wobble",
            Candidate::InstrumentScale => "instrument_scale",
        }
    }

    /// The joint, or `None` for whole-robot and instrument effects.
    pub fn joint(&self) -> Option<usize> {
        match *self {
            Candidate::JointCompliance { joint }
            | Candidate::Backlash { joint }
            | Candidate::GearHarmonic { joint, .. }
            | Candidate::AxisWobble { joint } => Some(joint),
            Candidate::ThermalExpansion | Candidate::InstrumentScale => None,
        }
    }

    /// Names (with units) of the effect's parameters.
    pub fn parameter_names(&self) -> Vec<&'static str> {
        match self {
            Candidate::JointCompliance { .. } => vec!["compliance_rad_per_nm"],
            Candidate::Backlash { .. } => vec!["half_band_rad"],
            Candidate::ThermalExpansion => vec!["alpha_per_k"],
            Candidate::GearHarmonic { .. } => vec!["sin_rad", "cos_rad"],
            Candidate::AxisWobble { .. } => vec!["tilt_x_rad", "tilt_y_rad"],
            Candidate::InstrumentScale => vec!["scale_ppm"],
        }
    }

    /// Finite-difference steps of the parameters (the model is linear in them to first order).
    fn steps(&self) -> Vec<f64> {
        match self {
            Candidate::JointCompliance { .. } => vec![1e-8],
            Candidate::Backlash { .. } => vec![1e-5],
            Candidate::ThermalExpansion => vec![1e-5],
            Candidate::GearHarmonic { .. } | Candidate::AxisWobble { .. } => vec![1e-5, 1e-5],
            Candidate::InstrumentScale => vec![10.0],
        }
    }

    /// Every candidate for a robot of revolute joints: per joint compliance, backlash (only
    /// when the joint's approach direction changes over `poses`), the first unfitted gear
    /// harmonic and order-2 wobble; thermal expansion only when the validation temperatures
    /// differ; the instrument scale.
    pub fn all(desc: &RobotDescription, poses: &[Pose]) -> Vec<Candidate> {
        let mut out = Vec::new();
        for (k, j) in desc.joints.iter().enumerate() {
            if j.kind != JointKind::Revolute {
                continue;
            }
            let joint = k + 1;
            out.push(Candidate::JointCompliance { joint });
            let flips = poses.iter().any(|p| p.approach[k] > 0.0) && poses.iter().any(|p| p.approach[k] < 0.0);
            if flips {
                out.push(Candidate::Backlash { joint });
            }
            out.push(Candidate::GearHarmonic {
                joint,
                order: unmodelled_harmonic_order(desc, joint),
            });
            out.push(Candidate::AxisWobble { joint });
        }
        let t0 = poses.first().map_or(0.0, |p| p.temperature_c);
        if poses.iter().any(|p| (p.temperature_c - t0).abs() > 0.0) {
            out.push(Candidate::ThermalExpansion);
        }
        out.push(Candidate::InstrumentScale);
        out
    }
}

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

/// A pose's payload as the candidates assume it: `payload_kg` on the tool frame's origin
/// (the measurement CSV gives only the mass), in the last link's frame; `None` without one.
fn payload_at_tool(model: &crate::kinematics::PhiModel, payload_kg: f64) -> Option<(f64, Point3<f64>)> {
    (payload_kg > 0.0).then(|| (payload_kg, Point3::from(model.last_link_from_tool.translation.vector)))
}

/// The calibrated couplings at the active displacements `active`, for
/// [`coupled_static_deflection`]: the
/// slope of every `coupling_in`; the fractional (eq. 15) and four-bar forms are mechanisms that
/// also carry the driven joint's load back to the actuator below, a gear is kinematic only.
fn passive_slopes(robot: &RobotModel, active: &[f64]) -> Vec<PassiveSlope> {
    PassiveSlope::of_robot(robot, active, |_, g| {
        matches!(g, CouplingFunction::Fractional { .. } | CouplingFunction::FourBar(_))
    })
}

/// The effects of a candidate (and the refit's transmission harmonics live in the robot).
#[derive(Clone, Debug)]
struct CandidateEffects {
    wobble: Vec<AxisWobble>,
    thermal: Option<ThermalEffect>,
    /// Measured coordinates over true ones.
    scale: f64,
}

impl Default for CandidateEffects {
    fn default() -> Self {
        CandidateEffects {
            wobble: Vec::new(),
            thermal: None,
            scale: 1.0,
        }
    }
}

/// The calibrated robot with the refit parameters and one optional candidate: predicts the
/// measured tool targets of a pose.
#[derive(Clone, Debug)]
pub struct Predictor {
    base: RobotModel,
    controller: Controller,
    masses: Vec<LinkMass>,
    tool_targets_m: Vec<Point3<f64>>,
    reference_c: f64,
    /// Per joint, the transmission harmonic orders the calibrator fits.
    harmonic_orders: Vec<usize>,
    /// The candidate effect, if any.
    pub candidate: Option<Candidate>,
    /// What the baseline refits besides the geometry.
    pub scope: RefitScope,
}

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
/// zero offsets, base and tool frames).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
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
    /// tool targets; `reference_c` is the temperature the calibration holds at.
    pub fn new(
        base: &RobotModel,
        desc: &RobotDescription,
        reference_c: f64,
        candidate: Option<Candidate>,
        scope: RefitScope,
    ) -> Self {
        let harmonic_orders = (1..=desc.dof())
            .map(|j| unmodelled_harmonic_order(desc, j).saturating_sub(1))
            .collect();
        Predictor {
            base: base.clone(),
            controller: Controller::from_description(desc),
            masses: LinkMass::from_description(desc),
            tool_targets_m: desc.tool_targets_m(),
            reference_c,
            candidate,
            scope,
            harmonic_orders,
        }
    }

    /// Number of baseline refit parameters: per row `a`, `b` \[m\], `alpha`, `beta` \[rad\]; per
    /// joint a zero offset \[rad\]; with [`RefitScope::Identified`] per joint its fitted
    /// transmission harmonics (sin, cos per order \[rad\]) and the slope of the coupling into
    /// it (unused without one); the base placement and the tool frame, each a translation
    /// \[m\] and a rotation vector \[rad\] (last). Redundant directions, e.g. joint 1's offset
    /// against the base yaw, are dropped by the fit's SVD.
    pub fn geometric_count(&self) -> usize {
        4 * self.base.rows.len() + self.base.dof() + self.shape_count() + 12
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

    /// Number of parameters of the candidate.
    pub fn effect_count(&self) -> usize {
        self.candidate.map_or(0, |c| c.parameter_names().len())
    }

    /// Finite-difference step of every parameter.
    pub fn steps(&self) -> Vec<f64> {
        let mut s = vec![1e-6; self.geometric_count()];
        if let Some(c) = self.candidate {
            s.extend(c.steps());
        }
        s
    }

    /// The refit robot and the candidate's effects for `params`.
    fn robot_and_effects(&self, params: &[f64]) -> (RobotModel, CandidateEffects) {
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
        let mut effects = CandidateEffects::default();
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
                    });
                    i += 2;
                }
            }
        }
        let e = &params[self.geometric_count()..];
        match self.candidate {
            Some(Candidate::GearHarmonic { joint, order }) => harmonics.push(GearHarmonic {
                joint,
                order,
                sin_rad: e[0],
                cos_rad: e[1],
            }),
            Some(Candidate::AxisWobble { joint }) => effects.wobble.push(AxisWobble {
                joint,
                amplitude_rad: e[0].hypot(e[1]),
                phase_rad: e[1].atan2(e[0]),
                order: WOBBLE_ORDER,
            }),
            Some(Candidate::ThermalExpansion) => {
                effects.thermal = Some(ThermalEffect {
                    alpha_per_k: e[0],
                    reference_c: self.reference_c,
                })
            }
            Some(Candidate::InstrumentScale) => effects.scale = 1.0 + e[0] * 1e-6,
            _ => {}
        }
        (with_gear_harmonics(&robot, &harmonics), effects)
    }

    /// The refit phi-model: `robot`'s with the base and tool corrections of `params`.
    fn model(&self, robot: &RobotModel, params: &[f64]) -> crate::kinematics::PhiModel {
        let g = self.geometric_count();
        let iso = |p: &[f64]| {
            Isometry3::from_parts(
                Translation3::new(p[0], p[1], p[2]),
                UnitQuaternion::from_scaled_axis(Vector3::new(p[3], p[4], p[5])),
            )
        };
        let mut model = robot.phi_model();
        model.world_from_base = iso(&params[g - 12..g - 6]) * model.world_from_base;
        model.last_link_from_tool *= iso(&params[g - 6..g]);
        model
    }

    /// Joint values `(q, active displacements)` of command `cmd` on `robot` (fig. 3 controller,
    /// transmissions, the backlash candidate's lag `backlash_half_band_rad` against
    /// `approach`, passive couplings); `None` when a command cannot be executed.
    fn joint_values(
        &self,
        robot: &RobotModel,
        cmd: &[f64],
        approach: &[f64],
        backlash_half_band_rad: f64,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let u = self.controller.decouple(cmd).ok()?;
        let mut active = robot.active_displacements(&u).ok()?;
        if let Some(Candidate::Backlash { joint }) = self.candidate {
            active[joint - 1] -= approach[joint - 1] * backlash_half_band_rad;
        }
        let mut q = active.clone();
        for k in 1..q.len() {
            if let Some(g) = &robot.joints[k].coupling_in {
                q[k] += g.try_passive(active[k - 1]).ok()?;
            }
        }
        Some((q, active))
    }

    /// The static sag of compliance `compliance_rad_per_nm` at `joint` (rigid elsewhere) at
    /// joint values `q` with `payload_kg` at the tool ([`coupled_static_deflection`]); `None`
    /// when the equilibrium is not found (the arm would buckle).
    #[allow(clippy::too_many_arguments)]
    fn sag(
        &self,
        robot: &RobotModel,
        model: &crate::kinematics::PhiModel,
        q: &[f64],
        active: &[f64],
        payload_kg: f64,
        joint: usize,
        compliance_rad_per_nm: f64,
    ) -> Option<Vec<f64>> {
        let mut stiffness_nm_per_rad = vec![f64::INFINITY; q.len()];
        stiffness_nm_per_rad[joint - 1] = 1.0 / compliance_rad_per_nm;
        let compliance = ComplianceEffect {
            stiffness_nm_per_rad,
            gravity_m_s2: GRAVITY_M_S2,
        };
        let payload = payload_at_tool(model, payload_kg);
        let couplings = passive_slopes(robot, active);
        let load = CompliantLoad {
            masses: &self.masses,
            payload,
            compliance: &compliance,
            couplings: &couplings,
        };
        coupled_static_deflection(model, q, &load).ok()
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.base.dof()
    }

    /// The workspace features of `pose` on the calibrated robot (no refit, no candidate):
    /// joint values, the tool point's horizontal distance from the base's vertical axis, and
    /// the gravity torque about every joint with the pose's payload (the actuator load before
    /// any coupling, `first_order_deflection` at unit stiffness). `None` when the command
    /// cannot be executed.
    pub fn pose_features(&self, pose: &Pose) -> Option<PoseFeatures> {
        let n = self.base.dof();
        let (q, _) = self.joint_values(&self.base, &pose.cmd, &pose.approach, 0.0)?;
        let model = self.base.phi_model();
        let tool = model.poses(&q).world_from_link[n - 1] * model.last_link_from_tool;
        let base = model.world_from_base;
        let tool_in_base = base.inverse() * Point3::from(tool.translation.vector);
        let payload = payload_at_tool(&model, pose.payload_kg);
        let unit = ComplianceEffect {
            stiffness_nm_per_rad: vec![1.0; n],
            gravity_m_s2: GRAVITY_M_S2,
        };
        let gravity_torque_nm = crate::physics::first_order_deflection(&model, &q, &self.masses, payload, &unit);
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
        let (robot, effects) = self.robot_and_effects(params);
        let model = self.model(&robot, params);
        let e = &params[self.geometric_count()..];
        let backlash = match self.candidate {
            Some(Candidate::Backlash { .. }) => e[0],
            _ => 0.0,
        };
        let mut out = Vec::with_capacity(poses.len() * 9);
        for pose in poses {
            let (mut q, active) = self.joint_values(&robot, &pose.cmd, &pose.approach, backlash)?;
            let model_t = match &effects.thermal {
                Some(t) => t.expanded(&model, pose.temperature_c),
                None => model.clone(),
            };
            if let Some(Candidate::JointCompliance { joint }) = self.candidate
                && e[0] != 0.0
            {
                let dq = self.sag(&robot, &model_t, &q, &active, pose.payload_kg, joint, e[0])?;
                for (qk, d) in q.iter_mut().zip(dq) {
                    *qk += d;
                }
            }
            let mut links = model_t.poses(&q).world_from_link;
            apply_wobble(&effects.wobble, &model_t, &q, &mut links);
            let tool = links[links.len() - 1] * model_t.last_link_from_tool;
            for (id, measured) in &pose.targets {
                let t = self.tool_targets_m.get(*id)?;
                let p = (tool * t).coords * effects.scale;
                out.extend((measured.coords - p).iter());
            }
        }
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::{CalibrationPlan, PoseConditions, ValidationPlan};
    use crate::robot::commands_to_internal;
    use crate::sim::{Effects, JointDriver};
    use rand::{SeedableRng, rngs::ChaCha12Rng};

    /// The compliance candidate on the truth robot itself reproduces the coupled static
    /// equilibrium (joint 2's sag drives joint 3 through the four-bar) to rounding.
    #[test]
    fn compliance_candidate_reproduces_the_coupled_sag() {
        let desc = RobotDescription::asea_irb6l();
        let mut truth = crate::sim::paper_robot();
        for j in &mut truth.joints {
            j.repeatability_sigma = 0.0;
        }
        let joint = 2;
        let stiffness_nm_per_rad = 2.0e4;
        let mut stiffness = vec![f64::INFINITY; desc.dof()];
        stiffness[joint - 1] = stiffness_nm_per_rad;
        let compliance = ComplianceEffect {
            stiffness_nm_per_rad: stiffness,
            gravity_m_s2: GRAVITY_M_S2,
        };
        let masses = LinkMass::from_description(&desc);
        let mut driver = JointDriver::new(&truth, Controller::from_description(&desc), &Effects::default());
        let model = truth.phi_model();
        let sagged = |driver: &mut JointDriver, cmd: &[f64]| {
            let d = driver.drive(cmd, &mut ChaCha12Rng::seed_from_u64(1)).unwrap();
            let couplings = PassiveSlope::of_linkages(&truth, &d.active);
            let load = CompliantLoad {
                masses: &masses,
                payload: None,
                compliance: &compliance,
                couplings: &couplings,
            };
            let dq = coupled_static_deflection(&model, &d.q, &load).unwrap();
            let q: Vec<f64> = d.q.iter().zip(&dq).map(|(a, b)| a + b).collect();
            model.poses(&q).world_from_link[desc.dof() - 1] * model.last_link_from_tool
        };
        let plan = ValidationPlan {
            poses: 12,
            ..ValidationPlan::workspace_default(desc.dof())
        };
        let reference = CalibrationPlan::table1(desc.dof()).reference;
        let poses: Vec<Pose> = plan
            .commands(&desc, &reference)
            .into_iter()
            .enumerate()
            .map(|(step, c)| {
                let cmd = commands_to_internal(&desc, &c);
                let tool = sagged(&mut driver, &cmd);
                Pose {
                    experiment: "validation".into(),
                    step,
                    cmd,
                    approach: vec![0.0; desc.dof()],
                    temperature_c: PoseConditions::default().temperature_c,
                    payload_kg: 0.0,
                    targets: desc.tool_targets_m().iter().map(|t| tool * t).enumerate().collect(),
                }
            })
            .collect();
        let every: Vec<&Pose> = poses.iter().collect();
        let reference_c = PoseConditions::default().temperature_c;
        let candidate = Candidate::JointCompliance { joint };
        let p = Predictor::new(&truth, &desc, reference_c, Some(candidate), RefitScope::Geometry);
        let rms = |p: &Predictor, params: &[f64]| {
            let r = p.residuals(params, &every).unwrap();
            (r.iter().map(|x| x * x).sum::<f64>() / r.len() as f64).sqrt()
        };
        let mut params = vec![0.0; p.geometric_count() + 1];
        let without = rms(&p, &params);
        params[p.geometric_count()] = 1.0 / stiffness_nm_per_rad;
        let with = rms(&p, &params);
        assert!(without > 1e-4, "the sag is visible: {without} m");
        // Rounding of the equilibrium (1e-13 rad) times the reach.
        assert!(with < 1e-11, "candidate leaves {with} m of {without} m");
    }
}
