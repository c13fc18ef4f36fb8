//! The predicted tool error of a calibration plan, before any measurement: what `axiscal plan
//! --optimize` minimises (`docs/method.md#plans-that-buy-accuracy`).
//!
//! A plan's campaign is simulated without noise on the nominal robot (the targets' nominal
//! positions of [`planned_points`]: the axis experiments and the tool observation) and
//! calibrated by the procedure ([`calibrate`]: the parameter covariance comes with its report) with the
//! instrument noise given. Noise-free data put the fit at the truth, and the covariance the
//! calibration reports there is the one a first-order prediction uses: the covariance of a
//! noisy campaign's fit, to first order in the noise (the check against Monte-Carlo is in
//! `docs/validation.md`). That parameter covariance `C_p` is propagated to the tool point as
//! `calibration::tool_accuracy` does (`J C_p J^T`, `J = dT/dp` at each workspace pose). Since the
//! fit is the nominal robot for every plan, `J` does not depend on the plan, and the mean
//! squared 1-sigma norm over the workspace is
//! `mean_i trace(J_i C_p J_i^T) = trace(C_p M)`, `M = mean_i J_i^T J_i` (position rows for the
//! position RMS, rotation rows for the orientation's), built once: a plan then costs one
//! calibration. The diagonal terms `(C_p M)_kk`, summed over a joint's or row's parameters, are
//! the breakdown of the predicted error (they sum to the total; a single term may be negative
//! where parameters are anti-correlated).

use super::{CalibrationPlan, PlanError, SightOptions, ValidationPlan, planned_points};
use crate::calibration::procedure::{CalibrationOptions, ProcedureError, calibrate};
use crate::calibration::tool_accuracy::ToolSensitivity;
use crate::measurement::{Measurement, MeasurementSet};
use crate::robot::{Controller, ModelError, RobotDescription, RobotModel, commands_to_internal};
use nalgebra::DMatrix;

/// Why a plan cannot be predicted.
#[derive(Debug, thiserror::Error)]
pub enum PredictError {
    /// The plan does not fit the robot (joints, spans, limits, targets).
    #[error(transparent)]
    Plan(#[from] PlanError),
    /// The noise-free campaign could not be calibrated (e.g. too few points for a fit).
    #[error("calibrating the plan's noise-free campaign: {0}")]
    Calibration(ProcedureError),
    /// A workspace pose could not be evaluated.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The calibration reported no covariance or one of another model structure.
    #[error("the calibration of the plan reported {0}")]
    Covariance(String),
}

/// The predicted tool 1-sigma of one plan over the workspace.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanPrediction {
    /// RMS over the workspace poses of the tool point's 1-sigma norm \[mm\].
    pub position_rms_mm: f64,
    /// RMS over the workspace poses of the tool orientation's 1-sigma norm \[mrad\].
    pub orientation_rms_mrad: f64,
    /// Planned points of the axis experiments (each target at each pose; the tool observation
    /// not counted), hidden ones included.
    pub axis_points: usize,
    /// Of those, the points hidden from a station on the nominal arm (not measured).
    pub hidden_points: usize,
    /// The position mean square by parameter group (`base`, `row k`, `joint k`, `coupling
    /// j->k`, `tool`) \[mm^2\], largest first; the groups sum to `position_rms_mm^2`.
    pub breakdown_mm2: Vec<(String, f64)>,
}

/// What [`PlanObjective::predict`] needs, built once for a robot, a workspace and a noise.
pub struct PlanObjective {
    desc: RobotDescription,
    sight: SightOptions,
    options: CalibrationOptions,
    names: Vec<String>,
    /// `mean_i J_i^T J_i` of the tool position \[m\] and rotation \[rad\] rows.
    m_position: DMatrix<f64>,
    m_rotation: DMatrix<f64>,
    workspace_poses: usize,
}

/// Central-difference step of every model parameter for the workspace Jacobians (m, rad or
/// dimensionless): far below the model's curvature scale (~0.1 m, ~0.1 rad), far above
/// rounding (1e-16 relative on ~1 m).
const JACOBIAN_STEP: f64 = 1e-7;

impl PlanObjective {
    /// For `desc`, the workspace `workspace` (its poses around `plan`'s reference), lines of
    /// sight `sight` and the calibration `options` (noise, repeatability); `plan` fixes the
    /// model's structure (every plan compared must sweep the same joints with the same targets).
    pub fn new(
        desc: &RobotDescription,
        plan: &CalibrationPlan,
        workspace: &ValidationPlan,
        sight: &SightOptions,
        options: &CalibrationOptions,
    ) -> Result<Self, PredictError> {
        let fit = calibrate_plan(desc, plan, sight, options)?;
        let names = crate::calibration::model_parameters::model_parameter_names(&fit.0);
        let controller = Controller::from_description(desc);
        let steps = DMatrix::from_diagonal_element(names.len(), names.len(), (JACOBIAN_STEP / 1e-3).powi(2));
        let sensitivity = ToolSensitivity::new(&fit.0, &controller, &steps);
        let n = names.len();
        let (mut m_position, mut m_rotation) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
        let poses = workspace.commands(desc, &plan.reference);
        for cmd in &poses {
            let j = sensitivity.jacobian(&commands_to_internal(desc, cmd))?;
            let (p, r) = (j.rows(0, 3), j.rows(3, 3));
            m_position += p.transpose() * p;
            m_rotation += r.transpose() * r;
        }
        let count = poses.len().max(1) as f64;
        Ok(PlanObjective {
            desc: desc.clone(),
            sight: sight.clone(),
            options: options.clone(),
            names,
            m_position: m_position / count,
            m_rotation: m_rotation / count,
            workspace_poses: poses.len(),
        })
    }

    /// Number of workspace poses the RMS is taken over.
    pub fn workspace_poses(&self) -> usize {
        self.workspace_poses
    }

    /// The predicted tool 1-sigma of `plan` over the workspace; an error when the plan leaves
    /// the limits, hides a point from a station or cannot be calibrated.
    pub fn predict(&self, plan: &CalibrationPlan) -> Result<PlanPrediction, PredictError> {
        let (robot, cov, [axis_points, hidden_points]) = calibrate_plan(&self.desc, plan, &self.sight, &self.options)?;
        if crate::calibration::model_parameters::model_parameter_names(&robot) != self.names {
            return Err(PredictError::Covariance(
                "a model of another structure than the reference plan's".into(),
            ));
        }
        let cm = &cov * &self.m_position;
        let position_m2 = cm.trace();
        let rotation_rad2 = (&cov * &self.m_rotation).trace();
        let mut groups: Vec<(String, f64)> = Vec::new();
        for (k, name) in self.names.iter().enumerate() {
            let group = parameter_group(name);
            let value = cm[(k, k)] * 1e6;
            match groups.iter_mut().find(|(g, _)| *g == group) {
                Some(g) => g.1 += value,
                None => groups.push((group, value)),
            }
        }
        groups.sort_by(|a, b| b.1.total_cmp(&a.1));
        Ok(PlanPrediction {
            position_rms_mm: position_m2.max(0.0).sqrt() * 1e3,
            orientation_rms_mrad: rotation_rad2.max(0.0).sqrt() * 1e3,
            axis_points,
            hidden_points,
            breakdown_mm2: groups,
        })
    }
}

/// The group of a parameter name of [`crate::calibration::model_parameters::model_parameter_names`]:
/// its first two words (`row 3`, `joint 5`, `coupling 4->5`) or `base` / `tool`.
fn parameter_group(name: &str) -> String {
    let words: Vec<&str> = name.split_whitespace().collect();
    match words.as_slice() {
        [first @ ("row" | "joint" | "coupling"), second, ..] => format!("{first} {second}"),
        [first, ..] => (*first).to_owned(),
        [] => String::new(),
    }
}

/// The noise-free campaign of `plan` on the nominal robot (axis experiments and tool
/// observation) and its number of planned axis-experiment points; a point hidden from a
/// station on the nominal arm is not measured (it still counts among the planned points); an
/// error when the plan does not fit the robot.
pub fn noise_free_campaign(
    desc: &RobotDescription,
    plan: &CalibrationPlan,
    sight: &SightOptions,
) -> Result<(MeasurementSet, [usize; 2]), PredictError> {
    let no_validation = ValidationPlan {
        poses: 0,
        half_range: vec![],
        seed: 0,
    };
    let mut points = planned_points(desc, plan, &no_validation, sight)?;
    let axis_points = points.iter().filter(|p| p.moved_joint > 0).count();
    points.retain(|p| p.visible.iter().all(|v| *v));
    let hidden = axis_points - points.iter().filter(|p| p.moved_joint > 0).count();
    let rows = points
        .into_iter()
        .map(|p| Measurement {
            experiment: p.experiment,
            moved_joint: p.moved_joint,
            step: p.step,
            target: p.target,
            position_mm: [p.nominal_m.x * 1e3, p.nominal_m.y * 1e3, p.nominal_m.z * 1e3],
            cmd: p.cmd,
            payload_kg: Measurement::DEFAULT_PAYLOAD_KG,
            temperature_c: Measurement::DEFAULT_TEMPERATURE_C,
        })
        .collect();
    let set = MeasurementSet::new(desc.dof(), rows)
        .map_err(|e| PredictError::Covariance(format!("an invalid campaign ({e})")))?;
    Ok((set, [axis_points, hidden]))
}

/// The noise-free campaign of `plan` calibrated: the fitted model, its parameter covariance
/// and the numbers of planned and hidden axis-experiment points.
fn calibrate_plan(
    desc: &RobotDescription,
    plan: &CalibrationPlan,
    sight: &SightOptions,
    options: &CalibrationOptions,
) -> Result<(RobotModel, DMatrix<f64>, [usize; 2]), PredictError> {
    let (set, axis_points) = noise_free_campaign(desc, plan, sight)?;
    // The noise is the prediction's input: an estimate from noise-free data would be ~0 and
    // collapse the covariance.
    let options = CalibrationOptions {
        estimate_noise: false,
        ..options.clone()
    };
    let fit = calibrate(&set, desc, &options)?;
    let cov = fit
        .model_covariance
        .ok_or_else(|| PredictError::Covariance("no model covariance".into()))?;
    Ok((fit.robot, cov.matrix(), axis_points))
}

impl From<ProcedureError> for PredictError {
    fn from(e: ProcedureError) -> Self {
        Self::Calibration(e)
    }
}
