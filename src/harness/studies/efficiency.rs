//! Efficiency of the axis estimators against the Cramer-Rao bound, and calibration of the
//! reported uncertainty of the Table-2 rows, over many simulated Table-1 campaigns of the
//! paper robot (isotropic noise, no repeatability jitter by default). The jitter can be
//! switched on: the bound is then that of measurement noise plus independent angle noise of
//! the truth's repeatability on every point of a sweep ([`arc_crb_with_angle_noise`]), and the
//! calibrator can be told the nominal description's repeatability
//! ([`EfficiencyStudy::model_repeatability`]) or not.
//!
//! Truth in the calibrator's own terms: the same campaign without noise, fitted the same way
//! (the paper robot is in the fitted family, so this is exact; see
//! `tests/calibration_procedure.rs`).

use crate::calibration::arc_model::{ArcParams, MeasurementNoise};
use crate::calibration::crb::{arc_crb_with_angle_noise, axis_errors, efficiency, held_joint_axis_covariance};
use crate::calibration::procedure::{AxisExperiment, CalibrationOptions, ProcedureError, axis_experiments, calibrate};
use crate::calibration::transmission_fit::TransmissionForm;
use crate::calibration::{
    ArcFitOptions, CalibrationError, angles, fit_arc, fit_arc_with_angle_noise, fit_axis_paper, fit_circle,
    fit_transmission,
};
use crate::kinematics::AxisLine;
use crate::measurement::{IsotropicNoise, MeasurementModel, MeasurementSet};
use crate::plan::{CalibrationPlan, ValidationPlan};
use crate::robot::commands_to_internal;
use crate::robot::{Controller, RobotDescription, RobotModel, TransmissionFitForm};
use crate::sim::{AnalyticArm, simulate_campaign};
use nalgebra::{Isometry3, Point3, Unit};
use rand::{SeedableRng, rngs::StdRng};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Per-trial seed: SplitMix64 (Steele et al. 2014) of the study seed and the trial index,
/// so a trial's result does not depend on which thread runs it.
pub fn trial_seed(seed: u64, trial: u64) -> u64 {
    let mut z = seed ^ trial.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Why a study stopped.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// A fit failed on one trial.
    #[error("trial {trial}: {source}")]
    Fit {
        /// Trial index.
        trial: usize,
        /// The fit's error.
        source: CalibrationError,
    },
    /// The procedure failed on one trial.
    #[error("trial {trial}: {source}")]
    Procedure {
        /// Trial index.
        trial: usize,
        /// The procedure's error.
        source: ProcedureError,
    },
    /// The noise-free reference fit failed.
    #[error("noise-free reference: {0}")]
    Reference(CalibrationError),
}

/// The study's settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EfficiencyStudy {
    /// Number of simulated campaigns.
    pub trials: usize,
    /// Study seed.
    pub seed: u64,
    /// Measurement noise, 3-D RMS \[mm\].
    pub noise_rms_3d_mm: f64,
    /// Keep the paper robot's repeatability jitter (off by default). On, the bound includes
    /// it as angle noise on every point of a sweep (what the jitter of the swept actuator is).
    #[serde(default)]
    pub repeatability_jitter: bool,
    /// Tell the calibrator the robot's repeatability: the nominal description's
    /// `repeatability_sigma` of each joint, for the axis fits
    /// ([`fit_arc_with_angle_noise`]) and the procedure. Off (default): the calibrator
    /// models measurement noise only, whatever the description says.
    #[serde(default)]
    pub model_repeatability: bool,
}

/// Efficiency of one quantity of one axis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct QuantityEfficiency {
    /// Joint (1-based).
    pub joint: usize,
    /// `direction` (2 components), `position` (2) or a transmission coefficient name.
    pub quantity: String,
    /// Square root of the bound's trace \[rad or mm\] (with jitter: of measurement and angle
    /// noise, plus the bias of the joints held below for the direction and position).
    pub crb_sigma: f64,
    /// ML estimator: RMS error over the trials.
    pub ml_rms_error: f64,
    /// ML estimator: the 1-sigma it reports (square root of the mean reported variance
    /// trace) over its RMS error; the target is within 15 % of 1.
    pub ml_sigma_ratio: f64,
    /// ML estimator: CRB variance / MSE.
    pub ml_efficiency: f64,
    /// Relative standard error of that efficiency.
    pub ml_relative_standard_error: f64,
    /// The paper's estimator (eqs. 1-8): CRB variance / MSE.
    pub paper_efficiency: f64,
    /// Relative standard error of that efficiency.
    pub paper_relative_standard_error: f64,
}

/// Reported against empirical uncertainty of one Table-2 parameter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RowSigmaCheck {
    /// e.g. `row 2 b`.
    pub parameter: String,
    /// Mean reported 1-sigma \[mm or deg\].
    pub reported_sigma: f64,
    /// Standard deviation of the estimates over the trials.
    pub empirical_sigma: f64,
    /// `reported / empirical`.
    pub ratio: f64,
    /// Relative standard error of the empirical sigma, `1/sqrt(2(n-1))`.
    pub relative_standard_error: f64,
}

/// The study's result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StudyReport {
    /// Settings.
    pub study: EfficiencyStudy,
    /// Per axis and quantity.
    pub efficiency: Vec<QuantityEfficiency>,
    /// Per Table-2 parameter (those not fixed by convention).
    pub row_sigma: Vec<RowSigmaCheck>,
}

struct AxisTruth {
    params: ArcParams,
    reference: Point3<f64>,
    form: TransmissionForm,
    /// Actuator commands of the sweep's target-0 points \[rad\].
    commands_rad: Vec<f64>,
    /// The simulated repeatability of the swept joint (0 without jitter) \[rad\].
    jitter_rad: f64,
    /// The repeatability the calibrator is told \[rad\].
    calibrator_rad: f64,
}

struct TrialOutcome {
    /// Per joint: ML errors and paper errors in the bound's quantities.
    ml: Vec<Vec<f64>>,
    paper: Vec<Vec<f64>>,
    /// Per joint: the ML fit's reported variance of each quantity (trace for the 2-D ones).
    ml_reported: Vec<Vec<f64>>,
    /// Table-2 parameters `[a mm, b mm, alpha deg, beta deg]` per row, and their sigmas.
    rows: Vec<[f64; 4]>,
    row_sigma: Vec<[f64; 4]>,
}

fn form_of(f: TransmissionFitForm) -> TransmissionForm {
    match f {
        TransmissionFitForm::Harmonic { order } => TransmissionForm::Harmonic { order },
        TransmissionFitForm::Gear { ratio, order } => TransmissionForm::Gear { ratio, order },
    }
}

fn campaign(truth: &RobotModel, desc: &RobotDescription, noise_mm: f64, seed: u64) -> MeasurementSet {
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
        &mut StdRng::seed_from_u64(seed),
    )
    .expect("the paper campaign runs on the paper robot");
    MeasurementSet::new(desc.dof(), out.rows).expect("simulated rows are consistent")
}

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
fn paper_fit(points: &[Point3<f64>], u: &[f64], form: &TransmissionForm) -> Result<AxisEstimate, CalibrationError> {
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

impl EfficiencyStudy {
    /// Runs the study (in parallel; bit-identical for any thread count).
    pub fn run(&self) -> Result<StudyReport, StudyError> {
        let desc = RobotDescription::asea_irb6l();
        let controller = Controller::from_description(&desc);
        let jittered = crate::sim::paper_robot();
        let mut steady = jittered.clone();
        for j in &mut steady.joints {
            j.repeatability_sigma = 0.0;
        }
        let truth = if self.repeatability_jitter { &jittered } else { &steady };
        let noise_m = self.noise_rms_3d_mm * 1e-3;
        let calibrator_rad: Vec<f64> = desc
            .joints
            .iter()
            .map(|j| {
                if self.model_repeatability {
                    j.repeatability_sigma
                } else {
                    0.0
                }
            })
            .collect();
        // The reference is the jitter-free, noise-free campaign.
        let exact = campaign(&steady, &desc, 0.0, 0);
        let (experiments, _) = axis_experiments(&exact, &desc).expect("the simulated campaign is complete");
        let mut truths: Vec<AxisTruth> = Vec::new();
        for e in &experiments {
            let u = actuator_commands(e, &desc, &controller);
            let form = form_of(desc.joints[e.joint - 1].transmission_fit);
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
        let options = CalibrationOptions {
            noise_rms_3d_mm: self.noise_rms_3d_mm,
            repeatability_sigma_rad: Some(calibrator_rad.clone()),
            ..CalibrationOptions::default()
        };
        let outcomes: Vec<TrialOutcome> = (0..self.trials)
            .into_par_iter()
            .map(|i| -> Result<TrialOutcome, StudyError> {
                let fit_err = |source| StudyError::Fit { trial: i, source };
                let set = campaign(truth, &desc, self.noise_rms_3d_mm, trial_seed(self.seed, i as u64));
                let (experiments, _) = axis_experiments(&set, &desc).expect("the simulated campaign is complete");
                let (mut ml, mut paper) = (Vec::new(), Vec::new());
                let mut ml_reported: Vec<Vec<f64>> = Vec::new();
                let mut fitted: Vec<(usize, ArcParams, AxisLine)> = Vec::new();
                for (e, t) in experiments.iter().zip(&truths) {
                    let u = actuator_commands(e, &desc, &controller);
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
                // The joints held below each swept one: their constant error, as the procedure
                // reports it (from the calibrator's repeatability and its own fitted axes).
                for (reported, (joint, params, axis)) in ml_reported.iter_mut().zip(&fitted) {
                    let held: Vec<(AxisLine, f64)> = fitted
                        .iter()
                        .filter(|(i, _, _)| i < joint && calibrator_rad[i - 1] > 0.0)
                        .map(|(i, _, line)| (*line, calibrator_rad[i - 1]))
                        .collect();
                    let c = held_joint_axis_covariance(axis, &params.u(), &params.v(), &held);
                    reported[0] += c.fixed_view::<2, 2>(0, 0).trace();
                    reported[1] += c.fixed_view::<2, 2>(2, 2).trace();
                }
                let cal =
                    calibrate(&set, &desc, &options).map_err(|source| StudyError::Procedure { trial: i, source })?;
                Ok(TrialOutcome {
                    ml,
                    paper,
                    ml_reported,
                    rows: cal
                        .robot
                        .rows
                        .iter()
                        .map(|r| [r.a_m * 1e3, r.b_m * 1e3, r.alpha_deg, r.beta_deg])
                        .collect(),
                    row_sigma: cal
                        .row_sigma
                        .iter()
                        .map(|s| [s.a_mm, s.b_mm, s.alpha_deg, s.beta_deg])
                        .collect(),
                })
            })
            .collect::<Result<_, _>>()?;
        Ok(self.summarise(&experiments, &truths, &outcomes))
    }

    fn summarise(
        &self,
        experiments: &[AxisExperiment],
        truths: &[AxisTruth],
        outcomes: &[TrialOutcome],
    ) -> StudyReport {
        let mut eff = Vec::new();
        for (k, (e, t)) in experiments.iter().zip(truths).enumerate() {
            let crb = arc_crb_with_angle_noise(
                t.form,
                &t.commands_rad,
                &MeasurementNoise::from_rms_3d(self.noise_rms_3d_mm * 1e-3),
                t.jitter_rad,
                &t.params,
                &t.reference,
            )
            .expect("the bound exists where the fit converged");
            // The bias of the joints held below: it adds to the bound (see
            // `held_joint_axis_covariance`).
            let line = |t: &AxisTruth| AxisLine {
                origin_m: t.params.axis_point_near(&t.reference),
                direction: t.params.normal(),
            };
            let held: Vec<(AxisLine, f64)> = experiments
                .iter()
                .zip(truths)
                .filter(|(ei, ti)| ei.joint < e.joint && ti.jitter_rad > 0.0)
                .map(|(_, ti)| (line(ti), ti.jitter_rad))
                .collect();
            let bias = held_joint_axis_covariance(&line(t), &t.params.u(), &t.params.v(), &held);
            let ml: Vec<Vec<f64>> = outcomes.iter().map(|o| o.ml[k].clone()).collect();
            let paper: Vec<Vec<f64>> = outcomes.iter().map(|o| o.paper[k].clone()).collect();
            let mut quantities = vec![
                (
                    "direction".to_string(),
                    crb.direction.trace() + bias.fixed_view::<2, 2>(0, 0).trace(),
                    0..2,
                    1.0,
                ),
                (
                    "position".to_string(),
                    crb.position.trace() + bias.fixed_view::<2, 2>(2, 2).trace(),
                    2..4,
                    1e3,
                ),
            ];
            for (c, v) in t.form.coefficient_names().into_iter().zip(&crb.coefficient_variance) {
                let i = 4 + quantities.len() - 2;
                quantities.push((c, *v, i..i + 1, 1.0));
            }
            for (index, (name, crb_var, range, scale)) in quantities.into_iter().enumerate() {
                let m = efficiency(crb_var, &ml, range.clone());
                let reported_var =
                    outcomes.iter().map(|o| o.ml_reported[k][index]).sum::<f64>() / outcomes.len() as f64;
                let p = efficiency(crb_var, &paper, range);
                eff.push(QuantityEfficiency {
                    joint: e.joint,
                    quantity: name,
                    crb_sigma: crb_var.sqrt() * scale,
                    ml_rms_error: m.mse.sqrt() * scale,
                    ml_sigma_ratio: (reported_var / m.mse).sqrt(),
                    ml_efficiency: m.efficiency,
                    ml_relative_standard_error: m.relative_standard_error,
                    paper_efficiency: p.efficiency,
                    paper_relative_standard_error: p.relative_standard_error,
                });
            }
        }
        let n = outcomes.len() as f64;
        let mut row_sigma = Vec::new();
        let names = ["a", "b", "alpha", "beta"];
        for r in 0..outcomes.first().map(|o| o.rows.len()).unwrap_or(0) {
            for (p, name) in names.iter().enumerate() {
                let values: Vec<f64> = outcomes.iter().map(|o| o.rows[r][p]).collect();
                let mean = values.iter().sum::<f64>() / n;
                let empirical = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
                let reported = outcomes.iter().map(|o| o.row_sigma[r][p]).sum::<f64>() / n;
                // A parameter the base-frame convention fixes (b1 = 0: the origin is the foot of
                // the common normal) does not move between trials at all.
                if empirical < 1e-9 {
                    continue;
                }
                row_sigma.push(RowSigmaCheck {
                    parameter: format!("row {} {name}", r + 1),
                    reported_sigma: reported,
                    empirical_sigma: empirical,
                    ratio: reported / empirical,
                    relative_standard_error: 1.0 / (2.0 * (n - 1.0)).sqrt(),
                });
            }
        }
        StudyReport {
            study: self.clone(),
            efficiency: eff,
            row_sigma,
        }
    }
}

/// Smallest and mean of some values, with the label of the smallest.
fn min_and_mean<'a>(values: impl Iterator<Item = (String, f64)> + 'a) -> (String, f64, f64) {
    let (mut label, mut min, mut sum, mut n) = (String::new(), f64::INFINITY, 0.0, 0.0);
    for (l, v) in values {
        if v < min {
            (label, min) = (l, v);
        }
        sum += v;
        n += 1.0;
    }
    (label, min, sum / n)
}

impl StudyReport {
    /// The smallest efficiency of each estimator and the range of the reported/empirical
    /// sigma ratios (the targets: ML efficiency >= 0.95, ratios within 15 %).
    pub fn summary_markdown(&self) -> String {
        let label = |q: &QuantityEfficiency| format!("joint {} {}", q.joint, q.quantity);
        let (ml_at, ml_min, ml_mean) = min_and_mean(self.efficiency.iter().map(|q| (label(q), q.ml_efficiency)));
        let ml_se = self
            .efficiency
            .iter()
            .map(|q| q.ml_efficiency * q.ml_relative_standard_error)
            .fold(0.0, f64::max);
        let (paper_at, paper_min, paper_mean) =
            min_and_mean(self.efficiency.iter().map(|q| (label(q), q.paper_efficiency)));
        let ratios = || self.row_sigma.iter().map(|r| r.ratio);
        let (lo, hi) = (ratios().fold(f64::INFINITY, f64::min), ratios().fold(0.0, f64::max));
        let ratio_se = self.row_sigma.first().map_or(0.0, |r| r.relative_standard_error);
        let ml_ratios = || self.efficiency.iter().map(|q| q.ml_sigma_ratio);
        let (ml_lo, ml_hi) = (
            ml_ratios().fold(f64::INFINITY, f64::min),
            ml_ratios().fold(0.0, f64::max),
        );
        format!(
            "## Summary\n\n\
             - ML (default) efficiency: min {ml_min:.3} ({ml_at}), mean {ml_mean:.3} \
             (Monte-Carlo standard error <= {ml_se:.3}; target >= 0.95)\n\
             - paper's estimator efficiency: min {paper_min:.3} ({paper_at}), mean {paper_mean:.3}\n\
             - reported / empirical 1-sigma of the Table-2 rows: {lo:.3} to {hi:.3} \
             (+- {ratio_se:.3}; target within 0.85 to 1.15)\n\
             - ML reported 1-sigma / RMS error of the axis quantities: {ml_lo:.3} to {ml_hi:.3} \
             (+- {:.3})\n\n",
            ml_se / 2.0
        )
    }

    /// The report as Markdown tables.
    pub fn markdown(&self) -> String {
        let jitter = match (self.study.repeatability_jitter, self.study.model_repeatability) {
            (true, true) => {
                "WITH the truth robot's repeatability jitter (in the Cramer-Rao bound as angle noise; the calibrator is told the nominal description's repeatability)"
            }
            (true, false) => {
                "WITH the truth robot's repeatability jitter (in the Cramer-Rao bound as angle noise; the calibrator is NOT told it, so its weights and reported sigma model measurement noise only)"
            }
            (false, true) => {
                "no repeatability jitter (the calibrator nevertheless assumes the nominal description's repeatability)"
            }
            (false, false) => "no repeatability jitter (the noise model the Cramer-Rao bound assumes)",
        };
        let mut s = format!(
            "# Calibrator efficiency study\n\n{} simulated Table-1 campaigns of the paper robot, {:.3} mm 3-D RMS isotropic measurement noise and {jitter}, seed {}.\n\n",
            self.study.trials, self.study.noise_rms_3d_mm, self.study.seed
        );
        s += &self.summary_markdown();
        s += "## Efficiency against the Cramer-Rao bound (CRB variance / MSE)\n\n| joint | quantity | CRB sigma | ML RMS error | ML efficiency | ML reported / RMS error | paper efficiency |\n|---|---|---|---|---|---|---|\n";
        for q in &self.efficiency {
            let unit = if q.quantity == "position" { "mm" } else { "rad" };
            s += &format!(
                "| {} | {} | {:.3e} {unit} | {:.3e} {unit} | {:.3} +- {:.3} | {:.3} +- {:.3} | {:.3} +- {:.3} |\n",
                q.joint,
                q.quantity,
                q.crb_sigma,
                q.ml_rms_error,
                q.ml_efficiency,
                q.ml_efficiency * q.ml_relative_standard_error,
                q.ml_sigma_ratio,
                q.ml_sigma_ratio * q.ml_relative_standard_error / 2.0,
                q.paper_efficiency,
                q.paper_efficiency * q.paper_relative_standard_error
            );
        }
        s += "\n## Reported against empirical 1-sigma of the Table-2 rows\n\n| parameter | reported | empirical | ratio |\n|---|---|---|---|\n";
        for r in &self.row_sigma {
            s += &format!(
                "| {} | {:.4e} | {:.4e} | {:.3} +- {:.3} |\n",
                r.parameter,
                r.reported_sigma,
                r.empirical_sigma,
                r.ratio,
                r.ratio * r.relative_standard_error
            );
        }
        s
    }
}
