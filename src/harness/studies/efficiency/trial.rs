//! One simulated campaign of the efficiency study: the truth of each axis in the calibrator's
//! own terms (the noise-free campaign fitted the same way) and, per trial, the errors of both
//! axis estimators and the procedure's Table-2 rows.

use super::{StudyError, trial_seed};
use crate::calibration::arc_model::{ArcParams, MeasurementNoise, N_GEOMETRY};
use crate::calibration::crb::{axis_errors, held_joint_axis_covariance};
use crate::calibration::procedure::{
    AxisExperiment, CalibrationOptions, Detail, FittedModel, axis_experiments, calibrate_model, harmonics,
};
use crate::calibration::{
    ArcFitOptions, CalibrationError, angles, fit_arc, fit_arc_with_angle_noise, fit_axis_paper, fit_circle,
    fit_transmission,
};
use crate::kinematics::AxisLine;
use crate::measurement::{IsotropicNoise, MeasurementModel, MeasurementSet};
use crate::plan::{CalibrationPlan, ValidationPlan};
use crate::robot::TransmissionFitForm;
use crate::robot::commands_to_internal;
use crate::robot::{Controller, RobotDescription, RobotModel};
use crate::sim::{AnalyticArm, simulate_campaign};
use nalgebra::{Isometry3, Point3, Unit};
use rand::{SeedableRng, rngs::ChaCha12Rng};

/// One axis as the noise-free campaign gives it, and what its trials are fitted with.
pub(super) struct AxisTruth {
    /// The noise-free ML fit's parameters.
    pub(super) params: ArcParams,
    /// The reference point of the fit (the noise-free circle's centre) \[m\].
    pub(super) reference: Point3<f64>,
    /// The joint's transmission form.
    pub(super) form: TransmissionFitForm,
    /// Actuator commands of the sweep's target-0 points \[rad\].
    pub(super) commands_rad: Vec<f64>,
    /// The simulated repeatability of the swept joint (0 without jitter) \[rad\].
    pub(super) jitter_rad: f64,
    /// The repeatability the calibrator is told \[rad\].
    pub(super) calibrator_rad: f64,
}

/// What one trial gives.
pub(super) struct TrialOutcome {
    /// Per joint: ML errors in the bound's quantities.
    pub(super) ml: Vec<Vec<f64>>,
    /// Per joint: the paper estimator's errors in the bound's quantities.
    pub(super) paper: Vec<Vec<f64>>,
    /// Per joint: the ML fit's reported variance of each quantity (trace for the 2-D ones).
    pub(super) ml_reported: Vec<Vec<f64>>,
    /// Table-2 parameters `[a mm, b mm, alpha deg, beta deg]` per row.
    pub(super) rows: Vec<[f64; 4]>,
    /// Their reported sigmas, in the same units.
    pub(super) row_sigma: Vec<[f64; 4]>,
    /// The derived quantities (couplings, zero offsets, tool frame): name, value and reported
    /// 1-sigma; a coupling parameter also under `(fit only)` with its fit's own sigma.
    pub(super) derived: Vec<(String, f64, f64)>,
}

/// The couplings', zero offsets' and tool frame's values and reported 1-sigma of `cal` (rad,
/// mm and mrad; the tool frame relative to the description's).
pub(super) fn derived_quantities(cal: &FittedModel, desc: &RobotDescription) -> Vec<(String, f64, f64)> {
    let mut out = Vec::new();
    for c in &cal.couplings {
        for (i, name) in c.parameter_names.iter().enumerate() {
            let label = format!("coupling {}->{} {name}", c.from, c.to);
            out.push((label.clone(), c.parameters[i], c.sigma[i]));
            out.push((format!("{label} (fit only)"), c.parameters[i], c.fit_only_sigma[i]));
        }
    }
    let Some(d) = &cal.derived_sigma else {
        return out;
    };
    for (k, (j, s)) in cal.robot.joints.iter().zip(&d.zero_offsets).enumerate() {
        out.push((format!("joint {} zero offset", k + 1), j.transducer_offset, *s));
    }
    if let Some(t) = d.tool {
        let rel = desc.tool.frame.to_isometry().inverse() * cal.robot.tool_frame.to_isometry();
        let (p, r) = (rel.translation.vector * 1e3, rel.rotation.scaled_axis() * 1e3);
        let sigma = [t.x_mm, t.y_mm, t.z_mm, t.rx_mrad, t.ry_mrad, t.rz_mrad];
        let names = ["x mm", "y mm", "z mm", "rx mrad", "ry mrad", "rz mrad"];
        for (i, name) in names.iter().enumerate() {
            let v = if i < 3 { p[i] } else { r[i - 3] };
            out.push((format!("tool {name}"), v, sigma[i]));
        }
    }
    out
}

/// The fit form of a transmission as the description gives it.
pub(in crate::harness::studies) fn campaign(
    truth: &RobotModel,
    desc: &RobotDescription,
    noise_mm: f64,
    seed: u64,
) -> MeasurementSet {
    let mut arm = AnalyticArm::new(truth.clone(), Controller::from_description(desc));
    let instrument = MeasurementModel::Isotropic(IsotropicNoise {
        net_radial_rms_mm: noise_mm,
    });
    let validation = ValidationPlan {
        poses: 0,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    let out = simulate_campaign(
        desc,
        &CalibrationPlan::table1(desc.dof()),
        &validation,
        &mut arm,
        &instrument,
        &mut ChaCha12Rng::seed_from_u64(seed),
    )
    .expect("the paper campaign runs on the paper robot");
    MeasurementSet::new(desc.dof(), out.rows).expect("simulated rows are consistent")
}

/// The actuator commands \[rad\] of the swept joint of `e` at every step.
fn actuator_commands(e: &AxisExperiment, desc: &RobotDescription, controller: &Controller) -> Vec<f64> {
    e.commands
        .iter()
        .map(|c| {
            controller
                .decouple(&commands_to_internal(desc, c))
                .expect("joint count checked")[e.joint - 1]
        })
        .collect()
}

/// An axis direction, a point on it, and transmission coefficients.
type AxisEstimate = (Unit<nalgebra::Vector3<f64>>, Point3<f64>, Vec<f64>);

/// The paper's estimator on one sweep: eqs. (1)-(5), then (6)-(8).
fn paper_fit(points: &[Point3<f64>], u: &[f64], form: &TransmissionFitForm) -> Result<AxisEstimate, CalibrationError> {
    let circle = fit_circle(points)?;
    let fit = fit_axis_paper(points, Some(&circle.normal), 100)?;
    let mut d = fit.axis.direction;
    if d.dot(&circle.normal) < 0.0 {
        d = -d;
    }
    let frame = Isometry3::face_towards(&fit.axis.origin_m, &(fit.axis.origin_m + d.into_inner()), &circle.u);
    let local: Vec<Point3<f64>> = points.iter().map(|p| frame.inverse_transform_point(p)).collect();
    let t = fit_transmission(form, &angles::displacements_from_start(&local)?, u)?;
    Ok((d, fit.axis.origin_m, t.coefficients))
}

/// The truth of each axis in the calibrator's own terms: the jitter-free, noise-free campaign
/// of `steady` fitted by ML (the jitter and the repeatability told to the calibrator taken from
/// `truth` and `calibrator_rad`); with the campaign's experiments.
pub(super) fn reference_truths(
    desc: &RobotDescription,
    controller: &Controller,
    steady: &RobotModel,
    truth: &RobotModel,
    calibrator_rad: &[f64],
    noise_m: f64,
) -> Result<(Vec<AxisExperiment>, Vec<AxisTruth>), StudyError> {
    let exact = campaign(steady, desc, 0.0, 0);
    let (experiments, _) = axis_experiments(&exact, desc).expect("the simulated campaign is complete");
    let mut truths: Vec<AxisTruth> = Vec::new();
    for e in &experiments {
        let u = actuator_commands(e, desc, controller);
        let form = desc.joints[e.joint - 1].transmission_fit_form();
        let noise = MeasurementNoise::from_rms_3d(noise_m);
        let fit = fit_arc(
            &e.target0_m,
            &u,
            &ArcFitOptions {
                form,
                noise: noise.clone(),
                reference_point: e.target0_m[0],
                max_iterations: 100,
            },
        )
        .map_err(StudyError::Reference)?;
        let reference = fit.params.centre;
        truths.push(AxisTruth {
            params: fit.params,
            reference,
            form,
            commands_rad: u,
            jitter_rad: truth.joints[e.joint - 1].repeatability_sigma,
            calibrator_rad: calibrator_rad[e.joint - 1],
        });
    }
    Ok((experiments, truths))
}

/// The axis fits of one trial.
struct TrialAxes {
    /// Per joint: ML errors in the bound's quantities.
    ml: Vec<Vec<f64>>,
    /// Per joint: the paper estimator's errors.
    paper: Vec<Vec<f64>>,
    /// Per joint: the ML fit's reported variances.
    ml_reported: Vec<Vec<f64>>,
    /// Per joint (1-based): the ML fit's parameters and axis.
    fitted: Vec<(usize, ArcParams, AxisLine)>,
    /// Each harmonic's amplitude and phase with their reported 1-sigma.
    harmonics: Vec<(String, f64, f64)>,
}

/// What every trial shares.
pub(super) struct Trials<'a> {
    /// The nominal description.
    pub(super) desc: &'a RobotDescription,
    /// Its controller.
    pub(super) controller: &'a Controller,
    /// The simulated robot.
    pub(super) truth: &'a RobotModel,
    /// The truth of each axis, in experiment order.
    pub(super) truths: &'a [AxisTruth],
    /// The repeatability the calibrator is told, per joint \[rad\].
    pub(super) calibrator_rad: &'a [f64],
    /// The procedure's options.
    pub(super) options: &'a CalibrationOptions,
    /// Measurement noise, 3-D RMS \[mm\].
    pub(super) noise_rms_3d_mm: f64,
    /// Study seed.
    pub(super) seed: u64,
}

impl Trials<'_> {
    /// Runs trial `i`: a noisy campaign, both axis estimators on every sweep, and the procedure.
    pub(super) fn run(&self, i: usize) -> Result<TrialOutcome, StudyError> {
        let desc = self.desc;
        let set = campaign(self.truth, desc, self.noise_rms_3d_mm, trial_seed(self.seed, i as u64));
        let (experiments, _) = axis_experiments(&set, desc).expect("the simulated campaign is complete");
        let mut axes = self.fit_axes(i, &experiments)?;
        self.add_held_joint_variances(&mut axes);
        // The lean path with the rows' covariance: the study reads the rows and their sigmas.
        let cal = calibrate_model(&set, desc, self.options, Detail::ModelAndCovariance).map_err(|source| {
            StudyError::Procedure {
                trial: i,
                cause: source,
            }
        })?;
        let mut derived = std::mem::take(&mut axes.harmonics);
        derived.extend(derived_quantities(&cal, desc));
        Ok(TrialOutcome {
            ml: axes.ml,
            paper: axes.paper,
            ml_reported: axes.ml_reported,
            rows: cal
                .robot
                .rows
                .iter()
                .map(|r| [r.a_m * 1e3, r.b_m * 1e3, r.alpha_deg, r.beta_deg])
                .collect(),
            row_sigma: cal
                .row_sigma
                .unwrap_or_default()
                .iter()
                .map(|s| [s.a_mm, s.b_mm, s.alpha_deg, s.beta_deg])
                .collect(),
            derived,
        })
    }

    /// Both axis estimators on every sweep of trial `i`, with their errors against the truth.
    fn fit_axes(&self, i: usize, experiments: &[AxisExperiment]) -> Result<TrialAxes, StudyError> {
        let (desc, controller) = (self.desc, self.controller);
        let noise_m = self.noise_rms_3d_mm * 1e-3;
        let fit_err = |source| StudyError::Fit {
            trial: i,
            cause: source,
        };
        let (mut ml, mut paper) = (Vec::new(), Vec::new());
        let mut ml_reported: Vec<Vec<f64>> = Vec::new();
        let mut fitted: Vec<(usize, ArcParams, AxisLine)> = Vec::new();
        let mut harmonic = Vec::new();
        for (e, t) in experiments.iter().zip(self.truths) {
            let u = actuator_commands(e, desc, controller);
            let fit = fit_arc_with_angle_noise(
                &e.target0_m,
                &u,
                &ArcFitOptions {
                    form: t.form,
                    noise: MeasurementNoise::from_rms_3d(noise_m),
                    reference_point: t.reference,
                    max_iterations: 100,
                },
                t.calibrator_rad,
            )
            .map_err(fit_err)?;
            ml_reported.push(
                [
                    fit.axis_direction_covariance.trace(),
                    fit.axis_position_covariance.trace(),
                ]
                .into_iter()
                .chain(fit.coefficient_sigma.iter().map(|s| s * s))
                .collect(),
            );
            fitted.push((e.joint, fit.params.clone(), fit.axis));
            let cov = |a: usize, b: usize| fit.covariance[(N_GEOMETRY + a, N_GEOMETRY + b)];
            for h in harmonics(&fit.transmission, &cov) {
                let name = format!("joint {} harmonic {}", e.joint, h.order);
                harmonic.push((format!("{name} amplitude"), h.amplitude_rad, h.amplitude_sigma_rad));
                harmonic.push((format!("{name} phase"), h.phase_rad, h.phase_sigma_rad));
            }
            ml.push(axis_errors(
                &fit.axis.direction,
                &fit.axis.origin_m,
                &fit.params.coefficients,
                &t.params,
                &t.reference,
            ));
            let (d, p, c) = paper_fit(&e.target0_m, &u, &t.form).map_err(fit_err)?;
            paper.push(axis_errors(&d, &p, &c, &t.params, &t.reference));
        }
        Ok(TrialAxes {
            ml,
            paper,
            ml_reported,
            fitted,
            harmonics: harmonic,
        })
    }

    /// The joints held below each swept one: their constant error, as the procedure reports it
    /// (from the calibrator's repeatability and its own fitted axes), added to the ML fit's
    /// reported direction and position variances.
    fn add_held_joint_variances(&self, axes: &mut TrialAxes) {
        let calibrator_rad = self.calibrator_rad;
        let fitted = &axes.fitted;
        for (reported, (joint, params, axis)) in axes.ml_reported.iter_mut().zip(fitted) {
            let held: Vec<(AxisLine, f64)> = fitted
                .iter()
                .filter(|(i, _, _)| i < joint && calibrator_rad[i - 1] > 0.0)
                .map(|(i, _, line)| (*line, calibrator_rad[i - 1]))
                .collect();
            let c = held_joint_axis_covariance(axis, &params.u(), &params.v(), &held);
            reported[0] += c.fixed_view::<2, 2>(0, 0).trace();
            reported[1] += c.fixed_view::<2, 2>(2, 2).trace();
        }
    }
}
