//! Sim-to-real gap diagnosis (`docs/formats.md#diagnosis-json`): from a measurement CSV and the nominal
//! description only, WHERE the calibrated model misses (axis experiments and validation poses
//! against what noise alone predicts), WHICH candidate effect explains the miss (each fitted
//! on training poses, scored on held-out ones), and HOW FAR the gap shrinks.
//!
//! Method:
//! 1. calibrate with the standard procedure (for free poses only, the free-pose calibration
//!    of the training poses); validation poses split into training (even) and held-out (odd)
//!    halves, a repeated configuration in one half ([`training_mask`]);
//! 2. the baseline is the calibrated model refined on the training poses by a geometric refit
//!    (rows `a`, `b`, `alpha`, `beta`, joint zero offsets, base and tool frames; linearised,
//!    redundant directions dropped by an SVD, [`LinearFit`]); transmission and coupling shapes
//!    are not refit, so the candidate effects keep their trace (each candidate reports the
//!    fraction of its signature outside the refit's span);
//! 3. each [`Candidate`] is fitted on the same training poses on top of the refit; its score is
//!    the held-out improvement `(SSR_base - SSR_c) / sigma^2`;
//! 4. thresholds come from noise alone: `noise_trials` replicas of the whole campaign on the
//!    calibrated robot (recalibrated each, [`replica`]), each with `noise_draws` draws of the
//!    validation noise, give the null distribution of the baseline's held-out chi-square, of
//!    every candidate's improvement (standardised to `z`) and of the maximum `z` over the
//!    candidates. At false-alarm rate `alpha`: `none` when the held-out chi-square is below its
//!    noise-only `1 - alpha` quantile; otherwise the candidate with the lowest held-out SSR
//!    among those whose `z` beats the null maximum's quantile is named when the gap it leaves
//!    is at the noise level (its own null quantile) or it removes `explained_fraction` of the
//!    gap's variance; else `unexplained`;
//! 5. gap = `sqrt(max(0, rms^2 - rms_noise^2))` on the held-out poses, `rms_noise^2` the
//!    noise-only mean of the same fit.

mod axes;
mod combined_slips;
mod decide;
mod features;
mod file_scale;
mod noise;
mod outliers;
mod own_poses;
mod plausible;
mod plots;
mod predicted_error;
mod prediction_curvature;
mod refine;
mod report;
mod result;
mod slips;
mod sweep_causes;
mod sweep_slips;
mod targets;
mod validate;
mod validation_block;

pub use crate::calibration::refine::{Block, LinearFit, NULL_DIRECTION_TOLERANCE, sensitivity};
pub use crate::calibration::refit_model::{
    Candidate, DEFAULT_MAX_HARMONIC_ORDER, GRAVITY_M_S2, LoadPath, MIN_THERMAL_ROW_M, MassModel, ModelShape, Pose,
    PoseFeatures, Predictor, RefitScope, SpringSite, ThermalLinks, TiltShape, drives_mechanism, free_poses_only,
    is_geared, reference_temperature, split, target_count, training_mask, unmodelled_harmonic_order, validation_poses,
    validation_poses_at_most,
};
pub use crate::plotting::PlotError;
pub use axes::{AxesDiagnosis, FlaggedAxis, axes_markdown, diagnose_axes, diagnose_axes_with};
pub use combined_slips::{
    MAX_SEARCH_ROWS, combined_slips_searched, explained_combined_slips, explained_validation_misses,
};
pub use file_scale::explained_file_scale;
pub use noise::{CleanCampaign, NoiseModel, ValidationRows, clean_positions, is_validation, replica};
pub use outliers::{PoseResiduals, free_pose_outliers, pose_point_outliers, validation_outliers, without_outliers};
pub use own_poses::{
    OWN_POSES_CHECKED, OWN_POSES_FALSE_ALARM, OwnPoses, OwnPosesCause, OwnPosesFit, OwnPosesMiss, OwnPosesSlips,
    SweepSearch, ToolMoveBeyond, own_validation_poses, test_own_validation_poses,
};
pub use plausible::{
    MAX_ALPHA_PER_K, MAX_ANGLE_RAD, MAX_HALF_BAND_RAD, MAX_PAYLOAD_OFFSET_M, MAX_SCALE_PPM, MIN_ALPHA_PER_K,
    SIGN_K_SIGMA, implausible,
};
pub use plots::{AXES_PLOT_FILES, PLOT_FILES, write_axes_plots, write_plots};
pub use refine::{CARRIABLE, CarryError, carriable, carried_candidates};
pub use report::markdown;
pub use result::{CandidateScore, Diagnosis, FeatureContrast, NamedEffect, Outcome, Parameter, WhereEntry};
pub use slips::{ExplainedMiss, MAX_FITTED_OFFSET, acceptance, explained_misses, free_pose_misses};
pub use sweep_causes::{
    MAX_SWEEP_SEARCH_CALIBRATIONS, SWEEP_CAUSE_FALSE_ALARM, SweepCause, SweepFault, SweepSearchTooLarge, SweepShadow,
    sweep_cause_of_misses,
};
pub use sweep_slips::{explained_sweep_misses, own_sweep_misses};
pub use targets::{FAR_SIGMAS, TargetDistance, ToolTargets};
pub use validate::{
    ChiSquare, Dominant, FittedToolMove, OrientationSummary, PointKind, PositionSummary, Prediction, Validation,
    ValidationOptions, ValidationResidual, Verdict, curvature_counts, residuals_less_calibration_error, validate,
    validate_free_tool, validation_residuals_csv, write_validation_residuals_csv,
};
pub use validation_block::{ValidationBlock, shifted_validation_block};

use crate::calibration::free_pose::{FreePoseOptions, FreePoseSummary, calibrate_free_poses, with_fitted_targets};
use crate::calibration::procedure::{Calibration, CalibrationOptions, ProcedureError, calibrate};
use crate::calibration::refine::{GaussNewtonSteps, refine_from_linear_with};
use crate::measurement::MeasurementSet;
use crate::measurement::bounded::DIAGNOSIS_MAX_POSES;
use crate::robot::RobotDescription;
use nalgebra::{DMatrix, DVector};
use rand::{SeedableRng, rngs::ChaCha12Rng};
use serde::{Deserialize, Serialize};

/// Why a data set could not be diagnosed.
#[derive(Debug, thiserror::Error)]
pub enum DiagnosisError {
    /// The standard calibration failed.
    #[error("calibrating: {0}")]
    Calibration(ProcedureError),
    /// The free-pose calibration of a file without axis experiments failed.
    #[error("calibrating from the free poses: {0}")]
    FreePoses(crate::calibration::free_pose::FreePoseError),
    /// Free poses of several setups (instrument placements): the diagnosis predicts one base.
    #[error(
        "the free poses are measured from {setups} setups; the diagnosis of free poses takes one setup (one instrument placement): diagnose each setup's rows on their own"
    )]
    SeveralSetups {
        /// Setups in the file.
        setups: usize,
    },
    /// Too few validation poses to split.
    #[error("{found} validation poses (moved_joint = 0, not `tool`); at least {needed} needed")]
    TooFewPoses {
        /// Found.
        found: usize,
        /// Needed.
        needed: usize,
    },
    /// The noise-only samples would not fit in memory.
    #[error(
        "--noise-trials {trials} x --noise-draws {draws} noise-only draws of {residuals} residuals are {} values \
         ({:.1} GB with their split): at most {NULL_SAMPLES_MAX} values (about {:.1} GB) are held; lower \
         --noise-trials or --noise-draws (or --max-poses)",
        *trials as f64 * *draws as f64 * *residuals as f64,
        *trials as f64 * *draws as f64 * *residuals as f64 * NULL_SAMPLE_BYTES / 1e9,
        NULL_SAMPLES_MAX as f64 * NULL_SAMPLE_BYTES / 1e9
    )]
    TooManyNullSamples {
        /// Noise-only replicas.
        trials: usize,
        /// Draws per replica.
        draws: usize,
        /// Residuals per draw (3 per validation point).
        residuals: usize,
    },
    /// The model could not predict the data.
    #[error("{message}")]
    Model {
        /// What failed.
        message: String,
    },
}

/// Options of [`diagnose`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct DiagnosisOptions {
    /// Measurement noise, 3-D RMS of a point \[mm\].
    pub noise_rms_3d_mm: f64,
    /// Noise-only replicas of the campaign (each recalibrated).
    pub noise_trials: usize,
    /// Validation-noise draws per replica.
    pub noise_draws: usize,
    /// Seed of the replicas' noise.
    pub seed: u64,
    /// What the baseline refit adjusts besides the geometry.
    pub refit: RefitScope,
    /// False-alarm rate of the gap test and of the candidate test (family-wise over the
    /// candidates).
    pub false_alarm: f64,
    /// A significant candidate that leaves a significant gap is still named when it removes
    /// at least this fraction of the gap's variance (an effect slightly off its candidate's
    /// form); below it the verdict is `unexplained`.
    pub explained_fraction: f64,
    /// Noise-only replicas of the axis-experiments-only diagnosis ([`diagnose_axes`]).
    #[serde(default = "default_axis_replicas")]
    pub axis_replicas: usize,
    /// Refine the tool targets from the training poses before scoring (`diagnosis::targets`);
    /// `false` scores with the description's targets (for comparison).
    #[serde(default = "default_refine_tool_targets")]
    pub refine_tool_targets: bool,
    /// Degrees of freedom of the noise estimate when `noise_rms_3d_mm` was estimated from the
    /// data (`None`: given, known). The replicas then draw the noise level from the estimate's
    /// sampling distribution (`s * sqrt(dof / X)`, `X ~ chi^2(dof)`), so that a low estimate (on few arcs) widens
    /// the noise-only spread instead of passing for a gap.
    #[serde(default)]
    pub noise_dof: Option<f64>,
    /// The validation poses the diagnosis fits at most, evenly spaced through the file (its
    /// memory grows with their number times `noise_trials x noise_draws`): beyond it the
    /// others are left out, and [`Diagnosis::poses`] counts them.
    #[serde(default = "default_max_poses")]
    pub max_poses: usize,
}

fn default_max_poses() -> usize {
    DIAGNOSIS_MAX_POSES
}

fn default_refine_tool_targets() -> bool {
    true
}

fn default_axis_replicas() -> usize {
    200
}

impl Default for DiagnosisOptions {
    fn default() -> Self {
        DiagnosisOptions {
            noise_rms_3d_mm: 0.19,
            noise_trials: 16,
            noise_draws: 32,
            seed: 0,
            refit: RefitScope::default(),
            false_alarm: 0.01,
            explained_fraction: 0.9,
            axis_replicas: default_axis_replicas(),
            noise_dof: None,
            refine_tool_targets: true,
            max_poses: DIAGNOSIS_MAX_POSES,
        }
    }
}

/// The calibrated model, the validation poses and the linearised problem around it.
struct Prepared {
    cal: Calibration,
    predictor: Predictor,
    poses: Vec<Pose>,
    /// Validation poses of the file beyond `poses` (`DiagnosisOptions::max_poses`).
    poses_left_out: usize,
    /// Residual rows of the training poses (the first rows; the held-out ones follow).
    train_rows: usize,
    /// Held-out targets.
    held_targets: usize,
    /// Observed residuals `measured - calibrated model` \[m\], training rows first.
    residuals: DVector<f64>,
    /// Sensitivity to the geometric refit parameters.
    x_geometric: DMatrix<f64>,
    /// The baseline refit's linear fit of `x_geometric` (computed once: every test, the
    /// features and the refinements start from it).
    baseline: LinearFit,
    /// Sensitivity to each candidate's parameters.
    x_candidates: Vec<(Candidate, DMatrix<f64>)>,
}

fn model_error(what: &str) -> DiagnosisError {
    DiagnosisError::Model {
        message: format!("the calibrated model cannot execute a validation command ({what})"),
    }
}

/// [`model_error`] naming the first of `poses` (of `set`) `predictor` cannot execute at
/// `params`.
fn pose_error(
    what: &str,
    predictor: &Predictor,
    params: &[f64],
    poses: &[&Pose],
    set: &MeasurementSet,
) -> DiagnosisError {
    let failing = poses.iter().find(|p| predictor.residuals(params, &[**p]).is_none());
    DiagnosisError::Model {
        message: match failing {
            Some(p) => format!(
                "the calibrated model cannot execute the command of validation pose {} ({what}): a command beyond the range its transmissions were fitted on, or in other units; check that pose's cmd_k",
                crate::calibration::refit_model::refine::pose_label(set, p)
            ),
            None => format!("the calibrated model cannot execute the validation commands ({what})"),
        },
    }
}

/// Training poses then held-out poses.
fn ordered(poses: &[Pose]) -> Vec<&Pose> {
    let (train, held) = split(poses);
    train.into_iter().chain(held).collect()
}

/// The validation poses the diagnosis fits: at most `max_poses` of `set`'s, evenly spaced
/// through the file (the null data's memory grows with them), each with its approach
/// directions from the whole file; and how many it left out.
fn diagnosed_poses(set: &MeasurementSet, desc: &RobotDescription, max_poses: usize) -> (Vec<Pose>, usize) {
    validation_poses_at_most(set.rows(), desc, max_poses)
}

/// Step 1 of the module docs: the standard calibration of `set`'s axis experiments; for free
/// poses only ([`free_poses_only`]) the free-pose calibration of the training poses (the even
/// ones, [`split`]: the held-out poses stay unseen), geometry and harmonics only (an effect in
/// the model would hide what the diagnosis looks for), every pose kept (of the at most
/// `max_poses` the diagnosis takes, the same selection: [`evenly_spaced`](crate::measurement::bounded::evenly_spaced)).
fn calibrate_for(
    set: &MeasurementSet,
    desc: &RobotDescription,
    noise_rms_3d_mm: f64,
    max_poses: usize,
) -> Result<Calibration, DiagnosisError> {
    Ok(calibrate_with_summary(set, desc, noise_rms_3d_mm, max_poses)?.0)
}

/// [`calibrate_for`] with the free-pose calibration's summary, for free poses only.
fn calibrate_with_summary(
    set: &MeasurementSet,
    desc: &RobotDescription,
    noise_rms_3d_mm: f64,
    max_poses: usize,
) -> Result<(Calibration, Option<FreePoseSummary>), DiagnosisError> {
    if !free_poses_only(set) {
        let cal = calibrate(
            set,
            desc,
            &CalibrationOptions {
                noise_rms_3d_mm,
                ..CalibrationOptions::default()
            },
        )?;
        return Ok((cal, None));
    }
    let options = FreePoseOptions {
        keep_outliers: true,
        holdout: true,
        effects: false,
        max_poses,
        ..FreePoseOptions::default()
    };
    let cal = calibrate_free_poses(set, desc, &options)?;
    match cal.summary.setups.len() {
        0 | 1 => {
            let (cal, summary) = cal.into_calibration(desc);
            Ok((cal, Some(summary)))
        }
        setups => Err(DiagnosisError::SeveralSetups { setups }),
    }
}

/// The calibration, the validation poses, the observed residuals and the refit's sensitivity;
/// each candidate's sensitivity too when `with_candidates` (the baseline alone needs none).
fn prepare(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &DiagnosisOptions,
    with_candidates: bool,
) -> Result<Prepared, DiagnosisError> {
    let (noise_rms_3d_mm, scope) = (options.noise_rms_3d_mm, options.refit);
    let cal = calibrate_for(set, desc, noise_rms_3d_mm, options.max_poses)?;
    let (poses, poses_left_out) = diagnosed_poses(set, desc, options.max_poses);
    if poses.len() < 4 {
        return Err(DiagnosisError::TooFewPoses {
            found: poses.len(),
            needed: 4,
        });
    }
    let predictor = Predictor::new(&cal.robot, desc, reference_temperature(set), scope);
    let (train, held) = split(&poses);
    let train_rows = 3 * target_count(&train);
    let held_targets = target_count(&held);
    let order = ordered(&poses);
    let zeros = vec![0.0; predictor.geometric_count()];
    let residuals = DVector::from_vec(
        predictor
            .residuals(&zeros, &order)
            .ok_or_else(|| pose_error("residuals", &predictor, &zeros, &order, set))?,
    );
    let x_geometric = predictor
        .sensitivity(&zeros, 0..zeros.len(), &order, &predictor.steps())
        .ok_or_else(|| model_error("refit sensitivity"))?;
    let mut x_candidates = Vec::new();
    let library = if with_candidates {
        Candidate::library(desc, &poses, DEFAULT_MAX_HARMONIC_ORDER)
    } else {
        Vec::new()
    };
    let joint_x = match library.iter().any(|c| matches!(c, Candidate::JointCompliance { .. })) {
        true => Some(
            predictor
                .joint_sensitivity(&zeros, &order)
                .ok_or_else(|| model_error("joint sensitivity"))?,
        ),
        false => None,
    };
    for c in library {
        let x = candidate_sensitivity(&predictor, c, joint_x.as_ref(), &order)
            .ok_or_else(|| model_error("candidate sensitivity"))?;
        if x.norm() > 0.0 {
            x_candidates.push((c, x));
        }
    }
    let n = x_geometric.nrows();
    let baseline = LinearFit::new(
        &x_geometric.rows(0, train_rows).into_owned(),
        &x_geometric.rows(train_rows, n - train_rows).into_owned(),
    );
    Ok(Prepared {
        cal,
        predictor,
        poses,
        poses_left_out,
        train_rows,
        held_targets,
        residuals,
        x_geometric,
        baseline,
        x_candidates,
    })
}

/// The sensitivity of the residual rows of `order` to candidate `c`'s parameters at zero: a
/// compliance member's by the chain rule through its sag ([`Predictor::compliance_sensitivity`],
/// from the joints' sensitivity `joint_x`), every other's by central differences.
fn candidate_sensitivity(
    predictor: &Predictor,
    c: Candidate,
    joint_x: Option<&DMatrix<f64>>,
    order: &[&Pose],
) -> Option<DMatrix<f64>> {
    let pred = predictor.with_candidates(&[c]);
    if let Some(j) = joint_x
        && let Some(x) = pred.compliance_sensitivity(c, j, order)
    {
        return Some(x);
    }
    let g = pred.geometric_count();
    let p0 = vec![0.0; g + pred.effect_count()];
    pred.sensitivity(&p0, g..p0.len(), order, &pred.steps())
}

impl Prepared {
    fn rows(&self, x: &DMatrix<f64>) -> (DMatrix<f64>, DMatrix<f64>) {
        let n = x.nrows();
        (
            x.rows(0, self.train_rows).into_owned(),
            x.rows(self.train_rows, n - self.train_rows).into_owned(),
        )
    }

    fn baseline_fit(&self) -> &LinearFit {
        &self.baseline
    }

    fn candidate_fit(&self, x_effect: &DMatrix<f64>) -> LinearFit {
        let x = DMatrix::from_fn(
            self.x_geometric.nrows(),
            self.x_geometric.ncols() + x_effect.ncols(),
            |r, c| {
                if c < self.x_geometric.ncols() {
                    self.x_geometric[(r, c)]
                } else {
                    x_effect[(r, c - self.x_geometric.ncols())]
                }
            },
        );
        let (t, h) = self.rows(&x);
        LinearFit::new(&t, &h)
    }

    /// Held-out SSR \[m^2\] of `fit` for each data column of `data` (training rows first).
    fn heldout_ssr(&self, fit: &LinearFit, data: &DMatrix<f64>) -> Vec<f64> {
        let (t, h) = self.rows(data);
        column_ssr(&fit.heldout(&t, &h))
    }
}

/// Sum of squares of each column.
fn column_ssr(r: &DMatrix<f64>) -> Vec<f64> {
    r.column_iter().map(|c| c.norm_squared()).collect()
}

/// A fit of the observed data refined beyond its linearisation ([`Prepared::refine`]).
struct Refined {
    /// Held-out SSR \[m^2\] of the nonlinear model at the fitted parameters.
    heldout_ssr: f64,
    /// Fitted parameters (refit, then the candidate's).
    params: DVector<f64>,
    /// The fit linearised at the parameters (their covariance; before the last step when
    /// refined without `with_fit`).
    fit: LinearFit,
    /// Training residuals at the parameters \[m\].
    r_train: DVector<f64>,
}

impl Prepared {
    /// The observed data fitted by the refit plus `candidate` (with its sensitivity `x_effect`)
    /// with the nonlinear model: the linearised solution, then Gauss-Newton steps re-linearised
    /// at the current parameters ([`refine_from_linear_with`], shared with `calibrate --refine`;
    /// rank-revealing like [`LinearFit`], held-out rows carried along unfitted). A large effect
    /// moves the model far enough that the first-order fit leaves a visible second-order
    /// residual; noise-only data (the null distributions) do not, so the linear null still
    /// applies.
    /// Without `with_fit`, [`Refined::fit`] is linearised before the last step (for a caller
    /// that needs the residuals only: one linearisation less).
    fn refine(&self, candidate: Option<(Candidate, &DMatrix<f64>)>, with_fit: bool) -> Option<Refined> {
        let members: Vec<Candidate> = candidate.iter().map(|c| c.0).collect();
        let pred = self.predictor.with_candidates(&members);
        let order = ordered(&self.poses);
        // The linearised solution is where the tests stand; the refinement starts there.
        let with_candidate;
        let linear = match candidate {
            Some((_, x)) => {
                with_candidate = self.candidate_fit(x);
                &with_candidate
            }
            None => self.baseline_fit(),
        };
        let how = GaussNewtonSteps {
            fit: "diagnosis refit",
            max_steps: REFINE_STEPS,
            truncate_below: NULL_DIRECTION_TOLERANCE,
            small_step: None,
            fit_at_end: with_fit,
        };
        let steps = pred.steps();
        let out = refine_from_linear_with(
            |p| pred.residuals(p, &order),
            |p| pred.sensitivity(p, 0..p.len(), &order, &steps),
            linear,
            &self.residuals.rows(0, self.train_rows).into_owned(),
            self.train_rows,
            how,
        )?;
        let r = out.residual;
        let n = r.len();
        Some(Refined {
            heldout_ssr: r.rows(self.train_rows, n - self.train_rows).norm_squared(),
            params: out.params,
            fit: out.fit,
            r_train: r.rows(0, self.train_rows).into_owned(),
        })
    }
}

/// Gauss-Newton steps of [`Prepared::refine`] after the linearised solution.
const REFINE_STEPS: usize = 2;

/// The most noise-only sample values the diagnosis holds (`noise_trials x noise_draws x`
/// residuals): 2^25, 268 MB of `f64`, and as much again split into training and held-out rows.
pub const NULL_SAMPLES_MAX: usize = 1 << 25;

/// Bytes a noise-only sample value takes, counted twice: the samples and their split.
const NULL_SAMPLE_BYTES: f64 = 16.0;

/// Noise-only data: `noise_trials` recalibrated replicas times `noise_draws` validation-noise
/// draws (columns, training rows first), and each replica's axis-experiment residual RMS^2.
struct NullData {
    samples: DMatrix<f64>,
    /// `samples`' training rows (split once: every candidate's test reads them).
    train: DMatrix<f64>,
    /// `samples`' held-out rows.
    held: DMatrix<f64>,
    axis_rms2: Vec<Vec<f64>>,
}

fn null_data(
    set: &MeasurementSet,
    desc: &RobotDescription,
    prep: &Prepared,
    options: &DiagnosisOptions,
    progress: &dyn crate::progress::Progress,
) -> Result<NullData, DiagnosisError> {
    let n = prep.residuals.len();
    let draws = options.noise_draws.max(1);
    if options.noise_trials.saturating_mul(draws).saturating_mul(n) > NULL_SAMPLES_MAX {
        return Err(DiagnosisError::TooManyNullSamples {
            trials: options.noise_trials,
            draws,
            residuals: n,
        });
    }
    progress.start(options.noise_trials, "noise-only replicas");
    let noise = noise_model(desc, options.noise_rms_3d_mm)?;
    let tool_targets = prep.predictor.tool_targets_m().to_vec();
    let clean = CleanCampaign::new(set, &prep.cal, desc, &tool_targets)?;
    let rows = validation_rows(&prep.cal, desc, &tool_targets, &prep.poses)?;
    let mut rng = ChaCha12Rng::seed_from_u64(options.seed);
    let mut samples = DMatrix::zeros(n, options.noise_trials * draws);
    let mut axis_rms2 = vec![Vec::new(); prep.cal.axes.len()];
    let reference_c = reference_temperature(set);
    for trial in 0..options.noise_trials {
        let level = noise_level_draw(options.noise_dof, &mut rng);
        let noise_trial = NoiseModel {
            noise_rms_3d_m: noise.noise_rms_3d_m * level,
            ..noise.clone()
        };
        let r = replica(set, &clean, &noise_trial, false, &mut rng)?;
        let cal = calibrate_for(&r, desc, options.noise_rms_3d_mm * level, options.max_poses)?;
        for (acc, a) in axis_rms2.iter_mut().zip(&cal.axes) {
            acc.push(a.residual_rms_mm.powi(2));
        }
        let (poses, _) = diagnosed_poses(&r, desc, options.max_poses);
        let pred = Predictor::new(&cal.robot, desc, reference_c, options.refit);
        let zeros = vec![0.0; pred.geometric_count()];
        let systematic = pred
            .residuals(&zeros, &ordered(&poses))
            .filter(|s| s.len() == n)
            .ok_or_else(|| pose_error("noise replica", &pred, &zeros, &ordered(&poses), &r))?;
        for d in 0..draws {
            let mut col: Vec<f64> = systematic.clone();
            let draw = NoiseModel {
                noise_rms_3d_m: noise.noise_rms_3d_m * noise_level_draw(options.noise_dof, &mut rng),
                ..noise.clone()
            };
            rows.validation_draw(&draw, &mut col, &mut rng);
            samples.column_mut(trial * draws + d).copy_from_slice(&col);
        }
        progress.inc();
    }
    let (train, held) = prep.rows(&samples);
    Ok(NullData {
        samples,
        train,
        held,
        axis_rms2,
    })
}

/// The factor on the noise level for one noise-only draw: 1 for a given noise; for one
/// estimated with `dof` degrees of freedom, `sqrt(dof / X)` with `X ~ chi^2(dof)`, the noise
/// level's distribution given its estimate (`s^2 dof / sigma^2 ~ chi^2(dof)`, inverted with a
/// flat prior on `log sigma`). Draws nothing from `rng` for a given noise, so given-noise
/// diagnoses are unchanged by it.
fn noise_level_draw<R: rand::Rng + ?Sized>(dof: Option<f64>, rng: &mut R) -> f64 {
    match dof.filter(|d| d.is_finite() && *d > 0.0) {
        None => 1.0,
        Some(d) => {
            let x: f64 = rand_distr::ChiSquared::new(d).map_or(d, |c| rand_distr::Distribution::sample(&c, rng));
            if x > 0.0 { (d / x).sqrt() } else { 1.0 }
        }
    }
}

/// What the noise-only replicas draw: the instrument noise `noise_rms_3d_mm` and the robot's
/// repeatability as `calibrate` models it (the description's `repeatability_sigma`).
fn noise_model(desc: &RobotDescription, noise_rms_3d_mm: f64) -> Result<NoiseModel, DiagnosisError> {
    Ok(NoiseModel {
        noise_rms_3d_m: noise_rms_3d_mm * 1e-3,
        repeatability_rad: CalibrationOptions::default()
            .joint_repeatability_rad(desc)
            .map_err(ProcedureError::from)?,
    })
}

/// The validation poses `poses` (file order) on `cal` with their residual rows in the
/// training-then-held-out order of [`ordered`].
fn validation_rows(
    cal: &Calibration,
    desc: &RobotDescription,
    tool_targets_m: &[nalgebra::Point3<f64>],
    poses: &[Pose],
) -> Result<ValidationRows, DiagnosisError> {
    // Training poses first, then the held-out ones, each in file order (`split`).
    let mask = training_mask(poses);
    let mut first_row = vec![0; poses.len()];
    let mut row = 0;
    for training in [true, false] {
        for i in (0..poses.len()).filter(|&i| mask[i] == training) {
            first_row[i] = row;
            row += 3 * poses[i].targets.len();
        }
    }
    ValidationRows::new(cal, desc, tool_targets_m, poses, |i, k| first_row[i] + 3 * k)
}

/// Held-out RMS \[mm\] of the baseline (calibration + geometric refit) on `set`: with
/// noise-free data, the trace an effect leaves after the refit (the blind check's detectable
/// size).
pub fn baseline_heldout_rms_mm(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &DiagnosisOptions,
) -> Result<f64, DiagnosisError> {
    let prep = prepare(set, desc, options, false)?;
    let fit = prep.baseline_fit();
    let ssr = prep.heldout_ssr(
        fit,
        &DMatrix::from_column_slice(prep.residuals.len(), 1, prep.residuals.as_slice()),
    );
    Ok((ssr[0] / prep.held_targets.max(1) as f64).sqrt() * 1e3)
}

/// The instrument noise (3-D RMS) of `set` estimated from its axis-experiment residuals, as
/// `calibrate` estimates it without a given noise ([`crate::calibration::noise::estimate_noise`]:
/// the pooled arc-fit residuals, the share the description's repeatability explains
/// subtracted); `None` without degrees of freedom. An effect that bends the arcs inflates it
/// (a conservative diagnosis, never a false alarm from it).
pub fn estimated_noise(
    set: &MeasurementSet,
    desc: &RobotDescription,
) -> Result<Option<crate::calibration::noise::NoiseEstimate>, DiagnosisError> {
    let options = CalibrationOptions {
        estimate_noise: true,
        ..CalibrationOptions::default()
    };
    Ok(calibrate(set, desc, &options)?.noise.and_then(|n| n.estimate))
}

/// Diagnoses `set` (module docs). Deterministic for given options.
pub fn diagnose(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &DiagnosisOptions,
) -> Result<Diagnosis, DiagnosisError> {
    diagnose_with(set, desc, options, &crate::progress::Silent)
}

/// [`diagnose`], counting the noise-only replicas (the bulk of the work) on `progress`.
pub fn diagnose_with(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &DiagnosisOptions,
    progress: &dyn crate::progress::Progress,
) -> Result<Diagnosis, DiagnosisError> {
    let fitted = with_free_pose_targets(set, desc, options)?;
    let desc = fitted.as_ref().unwrap_or(desc);
    let nominal = prepare(set, desc, options, false)?;
    let tool_targets = refined_tool_targets(&nominal, options.noise_rms_3d_mm);
    drop(nominal);
    let refined = tool_targets
        .as_ref()
        .filter(|_| options.refine_tool_targets)
        .map(|t| t.description(desc));
    let desc = refined.as_ref().unwrap_or(desc);
    let prep = prepare(set, desc, options, true)?;
    let null = null_data(set, desc, &prep, options, progress)?;
    let mut d = decide::decide(&prep, &null, options);
    d.tool_targets = tool_targets;
    Ok(d)
}

/// For free poses only ([`free_poses_only`]), `desc` with the tool targets the free-pose
/// calibration fitted (the description may give none); `None` otherwise.
fn with_free_pose_targets(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &DiagnosisOptions,
) -> Result<Option<RobotDescription>, DiagnosisError> {
    Ok(match free_poses_only(set) {
        true => Some(with_fitted_targets(
            desc,
            calibrate_with_summary(set, desc, options.noise_rms_3d_mm, options.max_poses)?
                .1
                .as_ref(),
        )),
        false => None,
    })
}

/// The tool targets refined from the training poses and compared with the description's
/// ([`targets`] module docs); `None` without tool targets or when the refit's refinement
/// fails (the diagnosis then scores with the description's).
fn refined_tool_targets(prep: &Prepared, noise_rms_3d_mm: f64) -> Option<ToolTargets> {
    if prep.predictor.tool_targets_m().is_empty() {
        return None;
    }
    let refined = prep.refine(None, true)?;
    let dof = prep.train_rows.saturating_sub(refined.fit.rank).max(1);
    let sigma2 = (noise_rms_3d_mm * 1e-3).powi(2) / 3.0;
    let variance = sigma2.max(refined.r_train.norm_squared() / dof as f64);
    targets::compare(
        prep.predictor.tool_targets_m(),
        |p| prep.predictor.refit_tool_targets_m(p),
        &refined.params,
        &refined.fit,
        variance,
    )
}

impl From<ProcedureError> for DiagnosisError {
    fn from(e: ProcedureError) -> Self {
        Self::Calibration(e)
    }
}

impl From<crate::calibration::free_pose::FreePoseError> for DiagnosisError {
    fn from(e: crate::calibration::free_pose::FreePoseError) -> Self {
        Self::FreePoses(e)
    }
}

#[cfg(test)]
mod tests {
    use super::noise_level_draw;
    use rand::{SeedableRng, rngs::ChaCha12Rng};

    /// A given noise is used as it is and draws nothing; an estimated one's squared factor
    /// has the inverse-chi-square mean `dof / (dof - 2)` (a second path: the closed form),
    /// within 4 standard errors of the sample mean.
    #[test]
    fn the_noise_level_spreads_as_its_estimate_allows() {
        let mut rng = ChaCha12Rng::seed_from_u64(3);
        assert_eq!(
            noise_level_draw(None, &mut rng).to_bits(),
            1f64.to_bits(),
            "a given noise is used as it is"
        );
        let next = rand::Rng::next_u64(&mut rng);
        let fresh = rand::Rng::next_u64(&mut ChaCha12Rng::seed_from_u64(3));
        assert_eq!(next, fresh, "a given noise draws nothing");
        for dof in [20.0, 78.0, 237.0] {
            let n = 20_000;
            let squares: Vec<f64> = (0..n).map(|_| noise_level_draw(Some(dof), &mut rng).powi(2)).collect();
            let mean = squares.iter().sum::<f64>() / n as f64;
            let var = squares.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
            let expected = dof / (dof - 2.0);
            assert!(
                (mean - expected).abs() < 4.0 * (var / n as f64).sqrt(),
                "dof {dof}: mean {mean}, expected {expected}"
            );
        }
    }
}
