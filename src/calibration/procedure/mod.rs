//! The independent-axis procedure over a whole campaign (paper sections 2-4): every axis
//! from its own experiment, the transmission functions (eq. 8) and passive couplings
//! (eqs. 14-15), the actual phi-model at the common reference pose with the section-4 base
//! frame, joint zero offsets, and the tool frame from the three tool targets.
//!
//! Conventions (`docs/method.md`, "Joint offsets and the reference pose"): the calibrated joint values at the reference pose are the
//! reference commands; `theta_act_k = f_k^-1(u_k - offset_k)` and
//! `q_k = theta_act_k + g_{k-1,k}(theta_act_{k-1})`, the same semantics as the truth model,
//! so a calibrated robot is expressed as a [`RobotModel`]-shaped model (a data type; no truth
//! value is read).
//!
//! Repeatability ([`CalibrationOptions::repeatability_sigma_rad`], default the description's
//! `repeatability_sigma`): the swept actuator is re-positioned at every step, so its error is
//! noise on each point's angle, which the ML axis fit weights and reports
//! ([`super::fit_arc_with_angle_noise`]). The joints held still below a sweep keep one error
//! through it: a bias of that axis, added to its reported covariance
//! ([`super::crb::held_joint_axis_covariance`]) but not propagated to the rows (the same held
//! error turns all axes above the joint together, which changes no row). Not modelled: the
//! correlation that bias creates between axes, the held error as an error of the joint's
//! value at the reference, and the repeatability in the paper's estimator. The coupling fits
//! (eqs. 14-15) report a-posteriori sigmas, so the swept joint's jitter in their residuals is
//! already counted.

mod axis_fit;
mod experiments;
mod frames;
mod joint_map;
mod joints;
mod report;
mod result;
mod uncertainty;
mod urdf;

pub use experiments::{AxisExperiment, COMMAND_TOLERANCE, axis_experiments};
pub use frames::{FramesError, common_normal_feet, model_from_axes};
pub use joint_map::{
    JointMap, MapRow, MapTable, ZeroOffsetFit, calibrated_joint_values, controller_zero_offsets, joint_map,
};
pub use report::{Finding, SIGNIFICANT_SIGMAS, findings, markdown};
pub use result::{AxisReport, Calibration, CouplingReport, RowSigma, ToolReport};
pub use uncertainty::{AxisCovariance, row_sigmas};
pub use urdf::{
    RawReadingDeviation, UrdfOptions, UrdfRoot, joints_without_speed_limits, raw_reading_deviation, ros_name, urdf,
};

use super::CalibrationError;
use crate::kinematics::{AxisLine, JointKind, PhiModel, rigid_fit};
use crate::measurement::MeasurementSet;
use crate::robot::commands_to_internal;
use crate::robot::{Controller, JointModel, Placement, RobotDescription, RobotModel};
use axis_fit::{AxisFitOutcome, actuator_commands, add_held_joint_covariances, fit_axes};
use joints::Assembly;
use nalgebra::{Isometry3, Point3};
use serde::{Deserialize, Serialize};

/// Which rotary-axis estimator to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AxisEstimator {
    /// Maximum-likelihood arc fit through the transmission model (default; efficient).
    #[default]
    Ml,
    /// The paper's estimator, eqs. (1)-(5), then eqs. (6)-(8).
    Paper,
}

/// Options of the procedure.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationOptions {
    /// The axis estimator.
    pub estimator: AxisEstimator,
    /// Measurement noise as the 3-D RMS error of a point \[mm\] (the paper: 0.19).
    pub noise_rms_3d_mm: f64,
    /// Iteration cap of every nonlinear fit.
    pub max_iterations: usize,
    /// The robot's repeatability per joint \[rad\] (standard deviation of the joint-value
    /// error drawn each time an actuator is re-positioned): one value for every joint or one
    /// per joint. `None` (default): the description's `repeatability_sigma` of each joint
    /// (0 unless the file gives it). A joint with a non-zero value has its axis fitted with
    /// [`super::fit_arc_with_angle_noise`] (ML estimator only), so the weights and the reported
    /// covariance include the angle noise of the sweep; 0 everywhere is the measurement-only
    /// fit, bit for bit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repeatability_sigma_rad: Option<Vec<f64>>,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        CalibrationOptions {
            estimator: AxisEstimator::Ml,
            noise_rms_3d_mm: 0.19,
            max_iterations: 100,
            repeatability_sigma_rad: None,
        }
    }
}

impl CalibrationOptions {
    /// The repeatability \[rad\] the axis fit of each joint of `desc` assumes (see
    /// [`CalibrationOptions::repeatability_sigma_rad`]).
    pub fn joint_repeatability_rad(&self, desc: &RobotDescription) -> Result<Vec<f64>, ProcedureError> {
        let n = desc.dof();
        let sigmas = match &self.repeatability_sigma_rad {
            None => desc.joints.iter().map(|j| j.repeatability_sigma).collect(),
            Some(v) if v.len() == 1 => vec![v[0]; n],
            Some(v) if v.len() == n => v.clone(),
            Some(v) => {
                return Err(ProcedureError::InvalidOption {
                    field: "repeatability_sigma_rad",
                    message: format!("needs 1 or {n} values, got {}", v.len()),
                });
            }
        };
        if let Some(s) = sigmas.iter().find(|s| !(s.is_finite() && **s >= 0.0)) {
            return Err(ProcedureError::InvalidOption {
                field: "repeatability_sigma_rad",
                message: format!("must be finite and >= 0, got {s}"),
            });
        }
        Ok(sigmas)
    }
}

/// Why a campaign could not be calibrated.
#[derive(Debug, thiserror::Error)]
pub enum ProcedureError {
    /// The set has no experiment sweeping this joint.
    #[error("no axis experiment moves joint {joint} (moved_joint = {joint})")]
    MissingAxis {
        /// The joint.
        joint: usize,
    },
    /// Two experiments sweep the same joint.
    #[error("experiments {first} and {second} both move joint {joint}")]
    DuplicateAxis {
        /// The joint.
        joint: usize,
        /// First experiment.
        first: String,
        /// Second experiment.
        second: String,
    },
    /// The swept joint's command does not move.
    #[error("experiment {experiment}: the command of joint {joint} has zero span")]
    ZeroSpan {
        /// Experiment.
        experiment: String,
        /// Joint.
        joint: usize,
    },
    /// Commands contradict the experiment design (`docs/formats.md#controller-semantics`).
    #[error("experiment {experiment}, step {step}, column cmd_{joint}: {reason}")]
    InconsistentCommands {
        /// Experiment.
        experiment: String,
        /// Step.
        step: usize,
        /// Joint.
        joint: usize,
        /// What is inconsistent.
        reason: String,
    },
    /// A coupling needs a second target the experiment does not have.
    #[error(
        "experiment {experiment}: joint {joint} drives a coupling into joint {} that must be measured, but target 1 is seen at only {seen} step(s) (3 needed)",
        joint + 1
    )]
    SecondTargetMissing {
        /// Experiment.
        experiment: String,
        /// Joint.
        joint: usize,
        /// Steps where target 1 was seen.
        seen: usize,
    },
    /// A fit failed.
    #[error("experiment {experiment} (joint {joint}): {source}")]
    Fit {
        /// Experiment.
        experiment: String,
        /// Joint.
        joint: usize,
        /// The fit's error.
        source: CalibrationError,
    },
    /// The axes do not make a phi-model.
    #[error(transparent)]
    Frames(#[from] FramesError),
    /// An option out of range.
    #[error("calibration option `{field}`: {message}")]
    InvalidOption {
        /// The option.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// Prismatic joints are not supported by this procedure yet.
    #[error(
        "joint {joint} is prismatic: the campaign procedure handles rotary joints (use calibration::sliding directly)"
    )]
    Prismatic {
        /// Joint.
        joint: usize,
    },
}

/// Calibrates the robot described (nominally) by `desc` from the axis experiments of `set`
/// (and the tool targets at the reference pose, when observed).
pub fn calibrate(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
) -> Result<Calibration, ProcedureError> {
    if let Some(k) = desc.joints.iter().position(|j| j.kind == JointKind::Prismatic) {
        return Err(ProcedureError::Prismatic { joint: k + 1 });
    }
    let repeatability_rad = options.joint_repeatability_rad(desc)?;
    let (experiments, reference_cmd) = axis_experiments(set, desc)?;
    let controller = Controller::from_description(desc);
    let q_ref = commands_to_internal(desc, &reference_cmd);
    let u_ref = actuator_commands(&controller, desc, &reference_cmd);

    let mut fits = fit_axes(&experiments, desc, &controller, options, &repeatability_rad)?;
    let axes: Vec<AxisLine> = fits.iter().map(|(f, _)| f.axis).collect();
    let geometry = model_from_axes(&desc.nominal_model(), &axes, &q_ref)?;
    let row_sigma = calibrated_row_sigmas(desc, &axes, &q_ref, &fits)?;
    add_held_joint_covariances(&mut fits, &axes, &repeatability_rad);

    let assembly = Assembly {
        desc,
        experiments: &experiments,
        fits: &fits,
        geometry: &geometry,
        q_ref: &q_ref,
        u_ref: &u_ref,
    };
    let (joints, couplings) = assembly.joint_models()?;
    let mut robot = calibrated_robot(desc, joints, &geometry);
    let tool = tool_frame(set, desc, &robot, &reference_cmd, &controller);
    if let Some(t) = &tool {
        robot.tool_frame = placement_of(&t.last_link_from_tool);
    }
    Ok(Calibration {
        robot,
        reference_cmd,
        axes: fits.into_iter().map(|(f, _)| f.report).collect(),
        row_sigma,
        couplings,
        tool,
        options: options.clone(),
        description: Some(desc.identity()),
    })
}

/// The standard deviations of the rows (mm, deg) from the axes' covariances as fitted
/// (before the held joints' bias is added).
fn calibrated_row_sigmas(
    desc: &RobotDescription,
    axes: &[AxisLine],
    q_ref: &[f64],
    fits: &[(AxisFitOutcome, Vec<f64>)],
) -> Result<Vec<RowSigma>, ProcedureError> {
    let covariances: Vec<Option<AxisCovariance>> = fits.iter().map(|(f, _)| f.report.covariance.clone()).collect();
    Ok(row_sigmas(&desc.nominal_model(), axes, q_ref, &covariances)?
        .into_iter()
        .map(|[a, b, alpha, beta]| RowSigma {
            a_mm: a * 1e3,
            b_mm: b * 1e3,
            alpha_deg: alpha.to_degrees(),
            beta_deg: beta.to_degrees(),
        })
        .collect())
}

/// The calibrated robot: the joint models on the rows and base placement of the phi-model
/// `geometry`, with the description's tool frame (replaced when the tool is measured).
fn calibrated_robot(desc: &RobotDescription, joints: Vec<JointModel>, geometry: &PhiModel) -> RobotModel {
    RobotModel {
        name: format!("{} (calibrated)", desc.name),
        joints,
        rows: geometry
            .rows
            .iter()
            .map(|r| crate::robot::RowEntry {
                a_m: r.a_m,
                b_m: r.b_m,
                alpha_deg: r.alpha_rad.to_degrees(),
                beta_deg: r.beta_rad.to_degrees(),
                gamma_deg: r.gamma_rad.to_degrees(),
                h_m: r.h_m,
            })
            .collect(),
        placement: placement_of(&geometry.world_from_base),
        tool_frame: desc.tool.frame,
        four_bars: vec![],
    }
}

/// A placement (mm, roll-pitch-yaw deg) from an isometry.
fn placement_of(iso: &Isometry3<f64>) -> Placement {
    let (r, p, y) = iso.rotation.euler_angles();
    let t = iso.translation.vector * 1e3;
    Placement {
        translation_mm: [t.x, t.y, t.z],
        rpy_deg: [r.to_degrees(), p.to_degrees(), y.to_degrees()],
    }
}

/// The tool frame from the three tool targets observed at the reference pose: experiment
/// `tool`, or any validation pose whose commands are the reference.
fn tool_frame(
    set: &MeasurementSet,
    desc: &RobotDescription,
    robot: &RobotModel,
    reference_cmd: &[f64],
    controller: &Controller,
) -> Option<ToolReport> {
    let targets = desc.tool_targets_m();
    let experiments = set.experiments();
    let candidates = experiments.iter().filter(|e| e.moved_joint == 0);
    for e in candidates {
        for (step, rows) in e.by_step() {
            let at_ref = rows.iter().all(|r| {
                r.cmd
                    .iter()
                    .zip(reference_cmd)
                    .all(|(a, b)| (a - b).abs() <= COMMAND_TOLERANCE)
            });
            let measured: Option<Vec<Point3<f64>>> = (0..targets.len())
                .map(|t| rows.iter().find(|r| r.target == t).map(|r| r.position_m()))
                .collect();
            let (true, Some(measured)) = (at_ref, measured) else {
                continue;
            };
            let (world_from_tool, rms_m) = rigid_fit(&targets, &measured)?;
            let q = robot
                .joint_values(controller, &commands_to_internal(desc, reference_cmd))
                .ok()?;
            let link = robot.phi_model().poses(&q).world_from_link[desc.dof() - 1];
            return Some(ToolReport {
                experiment: e.name.to_string(),
                step,
                last_link_from_tool: link.inverse() * world_from_tool,
                fit_rms_mm: rms_m * 1e3,
            });
        }
    }
    None
}
