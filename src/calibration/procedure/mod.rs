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

mod experiments;
mod frames;
mod report;
mod result;
mod uncertainty;
mod urdf;

pub use experiments::{AxisExperiment, COMMAND_TOLERANCE, axis_experiments};
pub use frames::{FramesError, common_normal_feet, model_from_axes};
pub use report::{Finding, SIGNIFICANT_SIGMAS, findings, markdown};
pub use result::{AxisReport, Calibration, CouplingReport, RowSigma, ToolReport};
pub use uncertainty::{AxisCovariance, row_sigmas};
pub use urdf::urdf;

use super::arc_model::MeasurementNoise;
use super::coupling_fit::{CouplingForm, fit_coupling, passive_displacements};
use super::transmission_fit::TransmissionForm;
use super::{CalibrationError, angles, fit_arc_with_angle_noise, fit_axis_paper, fit_circle, fit_transmission};
use crate::kinematics::{AxisLine, JointKind, rigid_fit};
use crate::measurement::MeasurementSet;
use crate::robot::commands_to_internal;
use crate::robot::{
    Controller, CouplingFitForm, CouplingFunction, JointModel, Placement, RobotDescription, RobotModel, Transmission,
    TransmissionFitForm,
};
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

fn transmission_form(f: TransmissionFitForm) -> TransmissionForm {
    match f {
        TransmissionFitForm::Harmonic { order } => TransmissionForm::Harmonic { order },
        TransmissionFitForm::Gear { ratio, order } => TransmissionForm::Gear { ratio, order },
    }
}

/// One fitted axis: the line, the transmission in the fit's own zero (`theta_a = f^-1(u)`
/// up to a constant) and the report.
struct AxisFitOutcome {
    axis: AxisLine,
    transmission: Transmission,
    report: AxisReport,
}

fn fit_one_axis(
    e: &AxisExperiment,
    u: &[f64],
    form: TransmissionForm,
    options: &CalibrationOptions,
    repeatability_rad: f64,
) -> Result<AxisFitOutcome, CalibrationError> {
    let noise = MeasurementNoise::from_rms_3d(options.noise_rms_3d_mm * 1e-3);
    let points = &e.target0_m;
    let centroid = Point3::from(points.iter().map(|p| p.coords).sum::<nalgebra::Vector3<f64>>() / points.len() as f64);
    let span_rad =
        u.iter().cloned().fold(f64::NEG_INFINITY, f64::max) - u.iter().cloned().fold(f64::INFINITY, f64::min);
    match options.estimator {
        AxisEstimator::Ml => {
            let fit = fit_arc_with_angle_noise(
                points,
                u,
                &super::ArcFitOptions {
                    form,
                    noise,
                    reference_point: centroid,
                    max_iterations: options.max_iterations,
                },
                repeatability_rad,
            )?;
            let g = super::arc_model::axis_quantities_gradient(&fit.params, &centroid);
            let q = &g * &fit.covariance * g.transpose();
            let mut report = AxisReport::from_ml(e, &fit, &form, span_rad);
            report.covariance = Some(AxisCovariance::new(
                fit.params.u().into_inner(),
                fit.params.v().into_inner(),
                &q.fixed_view::<4, 4>(0, 0).into(),
            ));
            Ok(AxisFitOutcome {
                axis: fit.axis,
                transmission: fit.transmission,
                report,
            })
        }
        AxisEstimator::Paper => {
            // Orient the axis so that increasing commands turn positively about it.
            let circle = fit_circle(points)?;
            let sign = if u[u.len() - 1] >= u[0] { 1.0 } else { -1.0 };
            let guess = nalgebra::Unit::new_unchecked(circle.normal.into_inner() * sign);
            let fit = fit_axis_paper(points, Some(&guess), options.max_iterations)?;
            let mut axis = fit.axis;
            if axis.direction.dot(&guess) < 0.0 {
                axis.direction = -axis.direction;
            }
            let frame = Isometry3::face_towards(
                &axis.origin_m,
                &(axis.origin_m + axis.direction.into_inner()),
                &circle.u,
            );
            // Points in a frame with Z on the axis: eqs. (6)-(7), then eq. (8).
            let local: Vec<Point3<f64>> = points.iter().map(|p| frame.inverse_transform_point(p)).collect();
            let local: Vec<Point3<f64>> = local.iter().map(|p| Point3::new(p.x, p.y, p.z)).collect();
            let increments = angles::displacements_from_start(&local)?;
            let t = fit_transmission(&form, &increments, u)?;
            let report = AxisReport::from_paper(e, &fit, &t, &form, span_rad);
            Ok(AxisFitOutcome {
                axis,
                transmission: t.transmission,
                report,
            })
        }
    }
}

/// Calibrates the robot described (nominally) by `desc` from the axis experiments of `set`
/// (and the tool targets at the reference pose, when observed).
pub fn calibrate(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
) -> Result<Calibration, ProcedureError> {
    let n = desc.dof();
    if let Some(k) = desc.joints.iter().position(|j| j.kind == JointKind::Prismatic) {
        return Err(ProcedureError::Prismatic { joint: k + 1 });
    }
    let repeatability_rad = options.joint_repeatability_rad(desc)?;
    let (experiments, reference_cmd) = axis_experiments(set, desc)?;
    let controller = Controller::from_description(desc);
    let q_ref = commands_to_internal(desc, &reference_cmd);
    let u_of = |cmd: &[f64]| -> Vec<f64> {
        controller
            .decouple(&commands_to_internal(desc, cmd))
            .expect("commands have the description's joint count (checked by MeasurementSet)")
    };
    let u_ref = u_of(&reference_cmd);

    // Axes and transmissions, in the order the experiments were run (Table 1: 6..1).
    let mut fits: Vec<Option<(AxisFitOutcome, Vec<f64>)>> = (0..n).map(|_| None).collect();
    for e in &experiments {
        let k = e.joint - 1;
        let u: Vec<f64> = e.commands.iter().map(|c| u_of(c)[k]).collect();
        let u0: Vec<f64> = e.target0_steps.iter().map(|&j| u[j]).collect();
        let form = transmission_form(desc.joints[k].transmission_fit);
        let outcome =
            fit_one_axis(e, &u0, form, options, repeatability_rad[k]).map_err(|source| ProcedureError::Fit {
                experiment: e.name.clone(),
                joint: e.joint,
                source,
            })?;
        fits[k] = Some((outcome, u));
    }
    let mut fits: Vec<(AxisFitOutcome, Vec<f64>)> = fits
        .into_iter()
        .map(|f| f.expect("every joint has an experiment"))
        .collect();
    let axes: Vec<AxisLine> = fits.iter().map(|(f, _)| f.axis).collect();
    let geometry = model_from_axes(&desc.nominal_model(), &axes, &q_ref)?;
    let covariances: Vec<Option<AxisCovariance>> = fits.iter().map(|(f, _)| f.report.covariance.clone()).collect();
    let row_sigma: Vec<RowSigma> = row_sigmas(&desc.nominal_model(), &axes, &q_ref, &covariances)?
        .into_iter()
        .map(|[a, b, alpha, beta]| RowSigma {
            a_mm: a * 1e3,
            b_mm: b * 1e3,
            alpha_deg: alpha.to_degrees(),
            beta_deg: beta.to_degrees(),
        })
        .collect();
    // The joints below each swept one hold still with their re-positioning error: a bias of
    // the whole sweep (not noise of its points), added to the axis's reported covariance in
    // the instrument frame. Not to the rows above: the campaign leaves a held actuator where
    // it is from one sweep to the next, so the same error turns every axis above it together,
    // which changes no row (it is an error of that joint's value at the reference, as large as
    // its repeatability).
    for (k, (fit, _)) in fits.iter_mut().enumerate() {
        let held: Vec<(AxisLine, f64)> = (0..k)
            .filter(|&i| repeatability_rad[i] > 0.0)
            .map(|i| (axes[i], repeatability_rad[i]))
            .collect();
        if !held.is_empty() {
            fit.report.add_held_joint_covariance(&axes[k], &held);
        }
    }

    // Ascending: joint k's zero needs the coupling into k, which needs joint k-1's zero.
    let mut joints: Vec<JointModel> = Vec::with_capacity(n);
    let mut couplings = Vec::new();
    let mut theta_ref: Vec<f64> = Vec::with_capacity(n);
    // The calibrated active angle of joint k is `f_k^-1(u) + shift[k]`.
    let mut shift: Vec<f64> = Vec::with_capacity(n);
    for k in 0..n {
        let (fit, _) = &fits[k];
        let not_invertible = |u: f64| ProcedureError::Fit {
            experiment: experiments
                .iter()
                .find(|e| e.joint == k + 1)
                .map(|e| e.name.clone())
                .unwrap_or_default(),
            joint: k + 1,
            source: CalibrationError::NotInvertible {
                fit: "calibrated transmission",
                command_rad: u,
            },
        };
        let coupling_in: Option<CouplingFunction> = if k == 0 {
            None
        } else {
            coupling_into(
                k,
                desc,
                &experiments,
                &fits,
                &shift,
                &geometry,
                &q_ref,
                &u_ref,
                &mut couplings,
                options,
            )?
        };
        let passive_ref = match (&coupling_in, k) {
            (Some(g), k) if k > 0 => g
                .try_passive(theta_ref[k - 1])
                .map_err(|_| not_invertible(u_ref[k - 1]))?,
            _ => 0.0,
        };
        let theta_a_ref = q_ref[k] - passive_ref;
        let raw_ref = fit
            .transmission
            .actual_from_command(u_ref[k])
            .ok_or_else(|| not_invertible(u_ref[k]))?;
        let c = theta_a_ref - raw_ref;
        theta_ref.push(theta_a_ref);
        shift.push(c);
        joints.push(JointModel {
            kind: desc.joints[k].kind,
            phi_deg: desc.joints[k].phi_deg,
            transmission: fit.transmission.shifted(c),
            coupling_in,
            transducer_offset: -c,
            repeatability_sigma: 0.0,
        });
    }

    let mut robot = RobotModel {
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
    };
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
    })
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

/// The coupling into joint `k` (0-based) from joint `k-1`: fitted from the second target of
/// the joint-`k` sweep (1-based `k`) when observed (eqs. 14-15), else the nominal one.
#[allow(clippy::too_many_arguments)]
fn coupling_into(
    k: usize,
    desc: &RobotDescription,
    experiments: &[AxisExperiment],
    fits: &[(AxisFitOutcome, Vec<f64>)],
    shift: &[f64],
    geometry: &crate::kinematics::PhiModel,
    q_ref: &[f64],
    u_ref: &[f64],
    couplings: &mut Vec<CouplingReport>,
    options: &CalibrationOptions,
) -> Result<Option<CouplingFunction>, ProcedureError> {
    let from = k; // 1-based number of the driving joint
    let Some(slope) = desc.nominal_coupling_from(from) else {
        return Ok(None);
    };
    let nominal = CouplingFunction::linear(slope);
    let e = experiments
        .iter()
        .find(|e| e.joint == from)
        .expect("every joint has an experiment");
    let form = desc.couplings.iter().find(|c| c.from == from).and_then(|c| c.fit);
    let Some(form) = form else {
        return Ok(Some(nominal));
    };
    if e.target1_m.len() < 3 {
        return Err(ProcedureError::SecondTargetMissing {
            experiment: e.name.clone(),
            joint: from,
            seen: e.target1_m.len(),
        });
    }
    let second = &e.target1_m;
    if !e.holds_next_still {
        return Err(ProcedureError::InconsistentCommands {
            experiment: e.name.clone(),
            step: 0,
            joint: from + 1,
            reason:
                "a coupling is measured only while actuator k+1 is held still (`docs/formats.md#controller-semantics`)"
                    .into(),
        });
    }
    let fit_err = |source| ProcedureError::Fit {
        experiment: e.name.clone(),
        joint: from,
        source,
    };
    let (fit_from, u_all) = &fits[k - 1];
    let u: Vec<f64> = e.target1_steps.iter().map(|&j| u_all[j]).collect();
    let active: Vec<f64> = u
        .iter()
        .map(|&uj| fit_from.transmission.actual_from_command(uj).map(|t| t + shift[k - 1]))
        .collect::<Option<_>>()
        .ok_or_else(|| {
            fit_err(CalibrationError::NotInvertible {
                fit: "coupling active angles",
                command_rad: u[0],
            })
        })?;
    let theta_ref_from = fit_from
        .transmission
        .actual_from_command(u_ref[k - 1])
        .map(|t| t + shift[k - 1])
        .unwrap_or(q_ref[k - 1]);
    // Axis k+1 (1-based) at step 0 of this sweep: the reference frame turned about axis k by
    // the active motion from the reference to step 0.
    let mut q0 = q_ref.to_vec();
    q0[k - 1] += active[0] - theta_ref_from;
    let frame_next = geometry.poses(&q0).world_from_frame[k];
    let axis_from = geometry.poses(q_ref).axis(k - 1);
    let t_from_start: Vec<f64> = active.iter().map(|a| a - active[0]).collect();
    let passive = passive_displacements(&frame_next, &axis_from, &t_from_start, second).map_err(fit_err)?;
    let (cform, passive_start) = match form {
        CouplingFitForm::Fractional => (CouplingForm::Fractional, slope * active[0]),
        CouplingFitForm::Gear { order, fit_ratio } => {
            let cform = CouplingForm::Gear {
                ratio: slope,
                fit_ratio,
                order,
            };
            (cform, gear_passive_start(slope, order, &active, &passive))
        }
    };
    let fit = fit_coupling(&cform, &active, &passive, passive_start).map_err(fit_err)?;
    let _ = options;
    couplings.push(CouplingReport::new(from, e, &fit, &cform));
    Ok(Some(fit.function))
}

/// The absolute passive angle at step 0 for a gear form `N t + sum (s sin kNt + c cos kNt)`,
/// which has no free constant: linear least squares of the increments on `[sin, cos, -1]`.
fn gear_passive_start(ratio: f64, order: usize, active: &[f64], passive_from_start: &[f64]) -> f64 {
    let m = active.len();
    let cols = 2 * order + 1;
    let mut a = nalgebra::DMatrix::zeros(m, cols);
    let mut b = nalgebra::DVector::zeros(m);
    for (j, (&t, &y)) in active.iter().zip(passive_from_start).enumerate() {
        for h in 0..order {
            let x = (h + 1) as f64 * ratio * t;
            a[(j, h)] = x.sin();
            a[(j, order + h)] = x.cos();
        }
        a[(j, 2 * order)] = -1.0;
        b[j] = y - ratio * t;
    }
    match a.svd(true, true).solve(&b, 1e-12) {
        Ok(x) => x[2 * order],
        Err(_) => ratio * active[0],
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
