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
//! `tests/it/calibration_procedure.rs`).

mod campaign_bound;
mod trial;

pub use campaign_bound::CampaignBoundSummary;
pub(super) use trial::campaign;

use crate::calibration::CalibrationError;
use crate::calibration::arc_model::MeasurementNoise;
use crate::calibration::crb::{arc_crb_with_angle_noise, efficiency, held_joint_axis_covariance};
use crate::calibration::procedure::{AxisExperiment, CalibrationOptions, ProcedureError};
use crate::kinematics::AxisLine;
use crate::robot::{Controller, RobotDescription, RobotModel};
use campaign_bound::{ConvergedBound, converged_bound};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::ops::Range;
use trial::{AxisTruth, TrialOutcome, Trials, reference_truths};

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
    #[error("trial {trial}: {cause}")]
    Fit {
        /// Trial index.
        trial: usize,
        /// The fit's error.
        cause: CalibrationError,
    },
    /// The procedure failed on one trial.
    #[error("trial {trial}: {cause}")]
    Procedure {
        /// Trial index.
        trial: usize,
        /// The procedure's error.
        cause: ProcedureError,
    },
    /// The noise-free reference fit failed.
    #[error("noise-free reference: {0}")]
    Reference(CalibrationError),
    /// The noise-free campaign's calibration (the whole-campaign bound's point) failed.
    #[error("noise-free calibration: {0}")]
    Converged(ProcedureError),
    /// The whole-campaign bound could not be evaluated.
    #[error("whole-campaign Cramer-Rao bound: {0}")]
    Bound(String),
}

/// The study's settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
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
    /// ([`fit_arc_with_angle_noise`](crate::calibration::fit_arc_with_angle_noise)) and the
    /// procedure. Off (default): the calibrator models measurement noise only, whatever the
    /// description says.
    #[serde(default)]
    pub model_repeatability: bool,
}

/// Efficiency of one quantity of one axis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct QuantityEfficiency {
    /// Joint (1-based).
    pub joint: usize,
    /// `direction` (2 components), `position` (2) or a transmission coefficient name.
    pub quantity: String,
    /// Square root of the bound's trace \[rad or mm\] (with jitter: of measurement and angle
    /// noise, plus the bias of the joints held below for the direction and position).
    #[serde(rename = "crb_sigma_rad_or_mm")]
    pub crb_sigma: f64,
    /// ML estimator: RMS error over the trials \[rad or mm\].
    #[serde(rename = "ml_rms_error_rad_or_mm")]
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
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RowSigmaCheck {
    /// e.g. `row 2 b`.
    pub parameter: String,
    /// Mean reported 1-sigma \[mm or deg\].
    #[serde(rename = "reported_sigma_mm_or_deg")]
    pub reported_sigma: f64,
    /// Standard deviation of the estimates over the trials \[mm or deg\].
    #[serde(rename = "empirical_sigma_mm_or_deg")]
    pub empirical_sigma: f64,
    /// `reported / empirical`.
    pub ratio: f64,
    /// Relative standard error of the empirical sigma, `1/sqrt(2(n-1))`.
    pub relative_standard_error: f64,
}

/// Efficiency of one derived quantity (coupling coefficient, zero offset, tool frame
/// component) against the whole-campaign Cramer-Rao bound, the trials' errors taken about the
/// noise-free fit's value (the point the estimator converges to, where the bound is evaluated).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct DerivedEfficiency {
    /// As in [`StudyReport::derived_sigma`] (its unit in the name: rad unless `mm`/`mrad`).
    pub quantity: String,
    /// The noise-free fit's value.
    pub converged_value: f64,
    /// Square root of the bound; null where the quantity is not estimable from the campaign.
    pub crb_sigma: Option<f64>,
    /// RMS of the trials' errors about the converged value.
    pub rms_error: f64,
    /// Mean of those errors (the noise-induced bias).
    pub mean_error: f64,
    /// Its Monte-Carlo standard error (`scatter / sqrt(trials)`).
    pub mean_error_standard_error: f64,
    /// Standard deviation of the trials' values.
    pub scatter: f64,
    /// CRB variance / mean squared error (null without a bound).
    pub efficiency: Option<f64>,
    /// CRB variance / scatter^2 (the efficiency with the bias taken out; null without a bound).
    pub variance_over_scatter: Option<f64>,
    /// Relative standard error of the mean squared error, hence of `efficiency`.
    pub relative_standard_error: f64,
    /// Its share in a direction the estimator's conventions leave unfixed and the points do
    /// not determine (column-scaled; no bound from 1e-5 up).
    #[serde(default)]
    pub undetermined_share: Option<f64>,
}

/// The study's result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct StudyReport {
    /// Settings.
    pub study: EfficiencyStudy,
    /// Per axis and quantity.
    pub efficiency: Vec<QuantityEfficiency>,
    /// Per Table-2 parameter (those not fixed by convention).
    pub row_sigma: Vec<RowSigmaCheck>,
    /// Per coupling parameter, zero offset and tool frame component (and each coupling
    /// parameter's fit-only sigma, for comparison).
    #[serde(default)]
    pub derived_sigma: Vec<RowSigmaCheck>,
    /// Couplings, zero offsets and tool frame against the whole-campaign bound (empty with the
    /// repeatability jitter: the bound is for measurement noise only).
    #[serde(default)]
    pub derived_efficiency: Vec<DerivedEfficiency>,
    /// What the whole-campaign bound rests on (null with the repeatability jitter).
    #[serde(default)]
    pub campaign_bound: Option<CampaignBoundSummary>,
}

/// One quantity of an axis whose efficiency is measured: its name, the bound's variance (trace
/// for the 2-D ones), its components in the errors of [`crate::calibration::crb::axis_errors`],
/// and the scale of its sigmas in the report.
type BoundQuantity = (String, f64, Range<usize>, f64);

/// The axis line of a truth: through its axis point nearest its reference, along its normal.
fn truth_line(t: &AxisTruth) -> AxisLine {
    AxisLine {
        origin_m: t.params.axis_point_near(&t.reference),
        direction: t.params.normal(),
    }
}

/// The paper robot with its repeatability jitter and the same robot without it (jitter-free).
fn jittered_and_steady_robots() -> (RobotModel, RobotModel) {
    let jittered = crate::sim::paper_robot();
    let mut steady = jittered.clone();
    for j in &mut steady.joints {
        j.repeatability_sigma = 0.0;
    }
    (jittered, steady)
}

impl EfficiencyStudy {
    /// Runs the study (in parallel; bit-identical for any thread count).
    pub fn run(&self) -> Result<StudyReport, StudyError> {
        self.run_with(&crate::progress::Silent)
    }

    /// [`Self::run`], counting the trials done on `progress`.
    pub fn run_with(&self, progress: &dyn crate::progress::Progress) -> Result<StudyReport, StudyError> {
        let desc = RobotDescription::asea_irb6l();
        let controller = Controller::from_description(&desc);
        let (jittered, steady) = jittered_and_steady_robots();
        let truth = if self.repeatability_jitter { &jittered } else { &steady };
        let noise_m = self.noise_rms_3d_mm * 1e-3;
        let calibrator_rad = self.calibrator_repeatability_rad(&desc);
        // The reference is the jitter-free, noise-free campaign.
        let (experiments, truths) = reference_truths(&desc, &controller, &steady, truth, &calibrator_rad, noise_m)?;
        let options = CalibrationOptions {
            noise_rms_3d_mm: self.noise_rms_3d_mm,
            repeatability_sigma_rad: Some(calibrator_rad.clone()),
            ..CalibrationOptions::default()
        };
        // Once per study: the whole-campaign bound (measurement noise only).
        let bound = if self.repeatability_jitter {
            None
        } else {
            Some(converged_bound(
                &desc,
                &steady,
                &options,
                noise_m,
                &experiments,
                &truths,
            )?)
        };
        let trials = Trials {
            desc: &desc,
            controller: &controller,
            truth,
            truths: &truths,
            calibrator_rad: &calibrator_rad,
            options: &options,
            noise_rms_3d_mm: self.noise_rms_3d_mm,
            seed: self.seed,
        };
        progress.start(self.trials, "trials");
        let outcomes: Vec<TrialOutcome> = (0..self.trials)
            .into_par_iter()
            .map(|i| {
                let outcome = trials.run(i);
                progress.inc();
                outcome
            })
            .collect::<Result<_, _>>()?;
        let mut report = self.summarise(&experiments, &truths, &outcomes);
        if let Some(b) = bound {
            report.derived_efficiency = derived_efficiency(&b, &outcomes);
            report.campaign_bound = Some(b.summary);
        }
        Ok(report)
    }

    /// The repeatability \[rad\] the calibrator is told for each joint of `desc`: the
    /// description's when [`EfficiencyStudy::model_repeatability`], else 0.
    fn calibrator_repeatability_rad(&self, desc: &RobotDescription) -> Vec<f64> {
        desc.joints
            .iter()
            .map(|j| {
                if self.model_repeatability {
                    j.repeatability_sigma
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// The efficiency of every axis quantity and the check of the rows' reported sigmas.
    fn summarise(
        &self,
        experiments: &[AxisExperiment],
        truths: &[AxisTruth],
        outcomes: &[TrialOutcome],
    ) -> StudyReport {
        let mut eff = Vec::new();
        for (k, (e, t)) in experiments.iter().zip(truths).enumerate() {
            let quantities = self.bound_quantities(e, t, experiments, truths);
            eff.extend(axis_efficiency(k, e.joint, quantities, outcomes));
        }
        StudyReport {
            study: self.clone(),
            efficiency: eff,
            row_sigma: row_sigma_checks(outcomes),
            derived_sigma: derived_sigma_checks(outcomes),
            derived_efficiency: vec![],
            campaign_bound: None,
        }
    }

    /// The quantities of axis `e` (truth `t`) with their Cramer-Rao bounds: direction,
    /// position and each transmission coefficient.
    fn bound_quantities(
        &self,
        e: &AxisExperiment,
        t: &AxisTruth,
        experiments: &[AxisExperiment],
        truths: &[AxisTruth],
    ) -> Vec<BoundQuantity> {
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
        let held: Vec<(AxisLine, f64)> = experiments
            .iter()
            .zip(truths)
            .filter(|(ei, ti)| ei.joint < e.joint && ti.jitter_rad > 0.0)
            .map(|(_, ti)| (truth_line(ti), ti.jitter_rad))
            .collect();
        let bias = held_joint_axis_covariance(&truth_line(t), &t.params.u(), &t.params.v(), &held);
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
        quantities
    }
}

/// The efficiency of both estimators for each quantity of axis `k` (joint `joint`, 1-based)
/// over the trials' `outcomes`.
fn axis_efficiency(
    k: usize,
    joint: usize,
    quantities: Vec<BoundQuantity>,
    outcomes: &[TrialOutcome],
) -> Vec<QuantityEfficiency> {
    let ml: Vec<Vec<f64>> = outcomes.iter().map(|o| o.ml[k].clone()).collect();
    let paper: Vec<Vec<f64>> = outcomes.iter().map(|o| o.paper[k].clone()).collect();
    let mut eff = Vec::new();
    for (index, (name, crb_var, range, scale)) in quantities.into_iter().enumerate() {
        let m = efficiency(crb_var, &ml, range.clone());
        let reported_var = outcomes.iter().map(|o| o.ml_reported[k][index]).sum::<f64>() / outcomes.len() as f64;
        let p = efficiency(crb_var, &paper, range);
        eff.push(QuantityEfficiency {
            joint,
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
    eff
}

/// Reported against empirical 1-sigma of every Table-2 parameter the base-frame convention
/// does not fix, over the trials' `outcomes`.
fn row_sigma_checks(outcomes: &[TrialOutcome]) -> Vec<RowSigmaCheck> {
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
    row_sigma
}

/// Reported against empirical 1-sigma of every derived quantity over the trials' `outcomes`
/// (the reported one as the root of the mean reported variance).
fn derived_sigma_checks(outcomes: &[TrialOutcome]) -> Vec<RowSigmaCheck> {
    let n = outcomes.len() as f64;
    let Some(first) = outcomes.first() else {
        return vec![];
    };
    let mut out = Vec::new();
    let mut resolved = true;
    for (i, (name, _, _)) in first.derived.iter().enumerate() {
        let values: Vec<f64> = outcomes.iter().map(|o| o.derived[i].1).collect();
        let mean = values.iter().sum::<f64>() / n;
        let empirical = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let reported = (outcomes.iter().map(|o| o.derived[i].2.powi(2)).sum::<f64>() / n).sqrt();
        // A harmonic's amplitude and phase are Gaussian only when the amplitude is well
        // resolved (> 5 sigma); near zero the amplitude is Rayleigh-distributed (scatter 0.66
        // of the coefficients' sigma) and the phase undefined: those are checked through their
        // sin/cos coefficients (the efficiency table) instead.
        if name.ends_with("amplitude") {
            resolved = mean.abs() > 5.0 * reported;
        }
        // A quantity the procedure fixes by convention (a joint not swept) does not move.
        if empirical < 1e-12 || (name.contains("harmonic") && !resolved) {
            continue;
        }
        out.push(RowSigmaCheck {
            parameter: name.clone(),
            reported_sigma: reported,
            empirical_sigma: empirical,
            ratio: reported / empirical,
            relative_standard_error: 1.0 / (2.0 * (n - 1.0)).sqrt(),
        });
    }
    out
}

/// The efficiency of every derived quantity of `bound` over the trials' `outcomes` (matched
/// by name: the trials' and the noise-free fit's derived quantities come from the same code).
fn derived_efficiency(bound: &ConvergedBound, outcomes: &[TrialOutcome]) -> Vec<DerivedEfficiency> {
    let n = outcomes.len() as f64;
    let mut out = Vec::new();
    for (name, converged, crb_var, share) in &bound.quantities {
        let Some(i) = outcomes
            .first()
            .and_then(|o| o.derived.iter().position(|d| d.0 == *name))
        else {
            continue;
        };
        // `(fit only)`: the same values with another sigma.
        if name.ends_with(')') {
            continue;
        }
        let errors: Vec<Vec<f64>> = outcomes.iter().map(|o| vec![o.derived[i].1 - converged]).collect();
        let mean = errors.iter().map(|e| e[0]).sum::<f64>() / n;
        let scatter = (errors.iter().map(|e| (e[0] - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
        // A quantity the procedure fixes (a joint not swept) does not move: nothing to judge.
        if scatter < 1e-12 {
            continue;
        }
        let e = efficiency(crb_var.unwrap_or(f64::NAN), &errors, 0..1);
        out.push(DerivedEfficiency {
            quantity: name.clone(),
            converged_value: *converged,
            crb_sigma: crb_var.map(f64::sqrt),
            rms_error: e.mse.sqrt(),
            mean_error: mean,
            mean_error_standard_error: scatter / n.sqrt(),
            scatter,
            efficiency: crb_var.map(|_| e.efficiency),
            variance_over_scatter: crb_var.map(|v| v / (scatter * scatter)),
            relative_standard_error: e.relative_standard_error,
            undetermined_share: *share,
        });
    }
    out
}

/// A Markdown section `## {head} | reported | empirical | ratio |` of the `checks`.
fn sigma_table(head: &str, checks: &[RowSigmaCheck]) -> String {
    let mut s = format!("\n## {head} | reported | empirical | ratio |\n|---|---|---|---|\n");
    for r in checks {
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
        s += &sigma_table(
            "Reported against empirical 1-sigma of the Table-2 rows\n\n| parameter",
            &self.row_sigma,
        );
        s += &sigma_table(
            "Reported against empirical 1-sigma of the harmonics, couplings, zero offsets and tool frame\n\n(rad for harmonics, couplings and zero offsets, mm and mrad for the tool frame; only harmonics resolved > 5 sigma; `(fit only)`: the coupling fit's own a-posteriori sigma, without the axes and transmissions it is built on)\n\n| quantity",
            &self.derived_sigma,
        );
        s += &self.campaign_markdown();
        s
    }

    /// The derived quantities against the whole-campaign bound, and what it rests on.
    fn campaign_markdown(&self) -> String {
        let Some(b) = &self.campaign_bound else {
            return "\n## Couplings, zero offsets and tool frame against the whole-campaign Cramer-Rao bound\n\nNot computed: the bound is for measurement noise only (no repeatability jitter).\n".into();
        };
        let mut s = format!(
            "\n## Couplings, zero offsets and tool frame against the whole-campaign Cramer-Rao bound\n\n\
             Fisher information of every point of the campaign from the complete parameter vector \
             ({} parameters: the model's estimated ones and 3 per axis target; {} coordinates), \
             evaluated at the noise-free fit; errors about that fit. Rank {}: {} unidentifiable \
             direction(s) (gauge freedoms), spanned by {} parameter(s) (with their share): {}. \
             The estimator fixes them by its conventions (each joint's zero at the reference pose, \
             the base frame on the axes): its model parameters move in a {}-dimensional subspace \
             (the range of the propagated model covariance, with each fractional coupling's \
             start convention), and the bound below is the \
             constrained bound on it (on the parameters estimable without conventions it \
             equals the rank-revealing bound to {:.1e}). That subspace still holds {} direction(s) \
             the points do not determine; the parameters with a share in it get no bound: {}.\n\n\
             | quantity | CRB sigma | RMS error | efficiency (CRB / MSE) | CRB / scatter^2 | mean error (bias) | undetermined share |\n|---|---|---|---|---|---|---|\n",
            b.parameters,
            b.coordinates,
            b.rank,
            b.parameters - b.rank,
            b.unidentifiable.len(),
            b.unidentifiable
                .iter()
                .map(|(n, share)| format!("{n} ({share:.1e})"))
                .collect::<Vec<_>>()
                .join(", "),
            b.convention_rank,
            b.convention_agreement,
            b.convention_null_directions,
            b.convention_unidentifiable
                .iter()
                .map(|(n, share)| format!("{n} ({share:.1e})"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let opt = |x: Option<f64>, f: &dyn Fn(f64) -> String| x.map_or("no bound".to_string(), f);
        for d in &self.derived_efficiency {
            let se = d.relative_standard_error;
            s += &format!(
                "| {} | {} | {:.3e} | {} | {} | {:.2e} +- {:.2e} | {:.1e} |\n",
                d.quantity,
                opt(d.crb_sigma, &|v| format!("{v:.3e}")),
                d.rms_error,
                opt(d.efficiency, &|v| format!("{v:.3} +- {:.3}", v * se)),
                opt(d.variance_over_scatter, &|v| format!("{v:.3} +- {:.3}", v * se)),
                d.mean_error,
                d.mean_error_standard_error,
                d.undetermined_share.unwrap_or(f64::NAN)
            );
        }
        let pairs = |v: &[(String, f64)], prec: usize| {
            v.iter()
                .map(|(n, x)| format!("{n} {x:.prec$}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        s += &format!(
            "\nSecond route: whole-campaign bound / per-arc bound of each transmission harmonic \
             (var sin_k + var cos_k; 1 where no other experiment informs it, below 1 where one \
             does): {}.\n\nForm misfit of each coupling \
             (the noise-free fit's angle residual RMS, rad): {}.\n",
            pairs(&b.transmission_bound_ratio, 4),
            b.coupling_form_residual_rad
                .iter()
                .map(|(n, x)| format!("{n} {x:.2e}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        s
    }
}
