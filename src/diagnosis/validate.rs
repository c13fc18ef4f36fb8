//! Validation of a calibration on measured data (`axiscal validate`,
//! `docs/formats.md#validation-summary-json`): every measured point of a measurement CSV
//! predicted by the calibrated model, the residuals summarised and tested against what the
//! measurement noise predicts.
//!
//! Predictions ([`clean_positions`]): a validation or tool pose's targets through the
//! controller (fig. 3) and the calibrated chain (eqs. A1-A4) to the description's tool
//! targets; an axis experiment's targets at their mean position in their link's frame (the
//! description does not say where the reflector sits on the link), which costs 3 degrees of
//! freedom per experiment and target.
//!
//! Test: with isotropic measurement noise of 3-D RMS `s` (each coordinate `s / sqrt(3)`) and
//! a correct model, `chi2 = sum |r|^2 / (s^2 / 3)` follows a chi-square distribution with
//! `3 n - 3 g` degrees of freedom (`n` points, `g` estimated target positions). A pose with the
//! three tool targets also gives its orientation: the measured tool frame is the rigid fit of
//! the description's tool targets to the measured points ([`rigid_fit`]), its rotation error
//! `w` (tool frame) has the covariance `(s^2 / 3) M^-1`, `M = sum_i (|d_i|^2 I - d_i d_i^T)`
//! (`d_i` a tool target relative to their centroid: the normal matrix of the linearised fit),
//! so `w^T M w / (s^2 / 3)` is chi-square with 3 degrees of freedom per pose.
//!
//! The prediction's own error: a calibration with a `model_covariance` predicts the free poses
//! (validation and tool) with an error of its own, one parameter error shared by every pose
//! ([`super::predicted_error`]). Their residuals are tested against the noise plus that error,
//! `r^T (N + G G^T)^-1 r` with `3 n` degrees of freedom ([`SharedErrorChiSquare`]), and against
//! the noise alone; the verdict is the first. Axis experiments are tested against the noise
//! alone: their target positions are estimated from the same points, which absorbs most of
//! the model's error there.

use super::DiagnosisError;
use super::noise::{CleanCampaign, calibrated_joint_values};
use super::predicted_error::{BlockFactors, PoseError, PredictionError};
use super::prediction_curvature::{Curvature, DrawnFrames};
use crate::calibration::procedure::Calibration;
use crate::kinematics::{PhiModel, rigid_fit};
use crate::measurement::{Measurement, MeasurementSet};
use crate::numerics::stats::{SharedErrorChiSquare, SharedErrorFit, chi_square_cdf, f_cdf};
use crate::plan::TOOL_EXPERIMENT;
use crate::robot::{Controller, RobotDescription, commands_to_internal};
use nalgebra::{DMatrix, DVector, Isometry3, Matrix3, Point3, Vector3};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet, HashMap};

/// Options of [`validate`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ValidationOptions {
    /// Measurement noise of a point, 3-D RMS \[mm\] (`> 0`).
    pub noise_rms_3d_mm: f64,
    /// Where it comes from (`calibration`, `given`), for the report.
    pub noise_source: String,
    /// Two-sided false-alarm rate of the chi-square verdicts.
    pub false_alarm: f64,
    /// The degrees of freedom of the noise when it was estimated from data (the
    /// calibration's effective ones); the verdicts are then F tests. `None`: a known noise.
    pub noise_dof: Option<f64>,
    /// Whether the model's curvature over the calibration's error counts in the prediction of
    /// the free poses ([`curvature_counts`]); `None`: judged on the data validated. A search
    /// that validates many recalibrations of one file against the same poses passes the
    /// judgement of the file as recorded, so that its hypotheses are tested with the same
    /// prediction (and the judgement, the drawn models' tool frames at up to 64 poses, is made
    /// once).
    #[serde(default)]
    pub curvature_counts: Option<bool>,
}

impl ValidationOptions {
    /// A known noise `noise_rms_3d_mm` (`--noise-mm`): chi-square tests.
    pub fn given(noise_rms_3d_mm: f64, false_alarm: f64) -> Self {
        ValidationOptions {
            noise_rms_3d_mm,
            noise_source: "given".into(),
            false_alarm,
            noise_dof: None,
            curvature_counts: None,
        }
    }

    /// The options `v` was made with (its noise, source, false-alarm rate and noise degrees of
    /// freedom, and whether the curvature counted): the slip searches test their rewrites as
    /// `v` tested the file.
    pub fn of_validation(v: &Validation) -> Self {
        ValidationOptions {
            noise_rms_3d_mm: v.noise_rms_3d_mm,
            noise_source: v.noise_source.clone(),
            false_alarm: v.false_alarm,
            noise_dof: v.noise_dof,
            curvature_counts: v.curvature_counted,
        }
    }

    /// The noise `cal` was weighted with; when it was estimated from the calibration's
    /// residuals, with the estimate's effective degrees of freedom (F tests).
    pub fn of_calibration(cal: &Calibration, false_alarm: f64) -> Self {
        let (noise_rms_3d_mm, noise_dof) = match &cal.noise {
            Some(n) => (
                n.used_rms_3d_mm,
                n.estimate
                    .as_ref()
                    .filter(|_| n.source == "estimated")
                    .map(|e| e.effective_dof),
            ),
            None => (cal.options.noise_rms_3d_mm, None),
        };
        ValidationOptions {
            noise_rms_3d_mm,
            noise_source: "calibration".into(),
            false_alarm,
            noise_dof,
            curvature_counts: None,
        }
    }

    /// The noise the user gave (`--noise-mm`), else the one `cal` was weighted with
    /// ([`Self::given`], [`Self::of_calibration`]).
    pub fn given_or_of_calibration(noise_mm: Option<f64>, cal: &Calibration, false_alarm: f64) -> Self {
        match noise_mm {
            Some(mm) => Self::given(mm, false_alarm),
            None => Self::of_calibration(cal, false_alarm),
        }
    }
}

/// Which kind of measured point a residual belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PointKind {
    /// A validation pose (`moved_joint = 0`, not `tool`).
    Validation,
    /// The tool observation (`experiment = tool`).
    Tool,
    /// A point of an axis experiment.
    Axis,
}

/// One measured point against its prediction (a row of `residuals.csv`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ValidationResidual {
    /// Experiment id.
    pub experiment: String,
    /// Its kind.
    pub kind: PointKind,
    /// The experiment's moved joint (0 for free poses).
    pub moved_joint: usize,
    /// Step.
    pub step: usize,
    /// Target id.
    pub target: usize,
    /// Measured position, instrument frame \[mm\].
    pub measured_mm: [f64; 3],
    /// Predicted position \[mm\].
    pub predicted_mm: [f64; 3],
    /// `|measured - predicted|` \[mm\].
    pub error_mm: f64,
}

/// What a chi-square statistic says of the residuals against their predicted uncertainty.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Neither tail below half the false-alarm rate.
    Consistent,
    /// Upper tail below half the false-alarm rate: the model misses these data.
    Exceeds,
    /// Lower tail below half the false-alarm rate: the predicted uncertainty is too large.
    Below,
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Verdict::Consistent => "consistent",
            Verdict::Exceeds => "exceeds",
            Verdict::Below => "below",
        })
    }
}

/// A chi-square verdict of residuals against their predicted uncertainty.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ChiSquare {
    /// The statistic.
    pub value: f64,
    /// Its degrees of freedom.
    pub dof: usize,
    /// `value / dof` (1 expected).
    pub per_dof: f64,
    /// Upper-tail probability `P(chi2 >= value)`, or of `chi2 / dof` under the F
    /// distribution with `noise_dof`.
    pub p_value: f64,
    /// The degrees of freedom of the estimated noise the statistic was computed with (null:
    /// a known noise, a chi-square test).
    pub noise_dof: Option<f64>,
    /// The verdict at the two-sided false-alarm rate.
    pub verdict: Verdict,
}

impl ChiSquare {
    /// The verdict of `value` with `dof` degrees of freedom at two-sided rate `false_alarm`,
    /// computed with a noise estimated from `noise_dof` degrees of freedom (an F test: the
    /// estimate's own scatter widens the acceptance) or known (`None`: a chi-square test);
    /// `None` without degrees of freedom.
    pub fn new(value: f64, dof: usize, false_alarm: f64, noise_dof: Option<f64>) -> Option<Self> {
        if dof == 0 {
            return None;
        }
        // An infinite or undefined statistic (a residual that overflowed) exceeds any noise.
        let cdf = match (value.is_finite(), noise_dof) {
            (false, _) => 1.0,
            (true, None) => chi_square_cdf(value, dof as f64),
            (true, Some(d2)) => f_cdf(value / dof as f64, dof as f64, d2),
        };
        let verdict = if 1.0 - cdf < 0.5 * false_alarm {
            Verdict::Exceeds
        } else if cdf < 0.5 * false_alarm {
            Verdict::Below
        } else {
            Verdict::Consistent
        };
        Some(ChiSquare {
            value,
            dof,
            per_dof: value / dof as f64,
            p_value: 1.0 - cdf,
            noise_dof,
            verdict,
        })
    }
}

/// The largest part of a predicted uncertainty.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Dominant {
    /// The measurement noise.
    Noise,
    /// The robot's repeatability.
    Repeatability,
    /// The calibration's own error.
    Calibration,
}

impl Dominant {
    /// In words, for the verdict.
    fn words(self) -> &'static str {
        match self {
            Dominant::Noise => "the instrument's noise",
            Dominant::Repeatability => "the robot's repeatability",
            Dominant::Calibration => "the calibration's uncertainty",
        }
    }
}

/// The parts of a predicted RMS \[mm or mrad\]: `sqrt` of the sum of their squares and the
/// largest.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Prediction {
    /// The instrument's noise.
    pub noise: f64,
    /// The robot's repeatability (absent where it is not modelled: axis experiments).
    pub repeatability: Option<f64>,
    /// The calibration's own error (absent without a model covariance and for axis
    /// experiments).
    pub calibration: Option<f64>,
    /// `sqrt(noise^2 + repeatability^2 + calibration^2)`.
    pub total: f64,
    /// The largest part.
    pub dominant: Dominant,
}

impl Prediction {
    fn new(noise: f64, repeatability: Option<f64>, calibration: Option<f64>) -> Self {
        let parts = [
            (Dominant::Noise, noise),
            (Dominant::Repeatability, repeatability.unwrap_or(0.0)),
            (Dominant::Calibration, calibration.unwrap_or(0.0)),
        ];
        let dominant = parts
            .iter()
            .fold(parts[0], |best, p| if p.1 > best.1 { *p } else { best })
            .0;
        Prediction {
            noise,
            repeatability,
            calibration,
            total: parts.iter().map(|p| p.1 * p.1).sum::<f64>().sqrt(),
            dominant,
        }
    }

    /// `noise 0.2038, repeatability 0.2100, calibration 1.1000 mm: the calibration's
    /// uncertainty dominates`.
    fn describe(&self, unit: &str) -> String {
        let mut parts = vec![format!("noise {:.4}", self.noise)];
        if let Some(r) = self.repeatability {
            parts.push(format!("repeatability {r:.4}"));
        }
        let left_out = match self.calibration {
            Some(c) => {
                parts.push(format!("calibration {c:.4}"));
                ""
            }
            None if self.repeatability.is_some() => {
                " (the calibration's own error not included: the calibration has no model covariance)"
            }
            None => "",
        };
        format!(
            "{} {unit}{left_out}: {} dominates",
            parts.join(", "),
            self.dominant.words()
        )
    }
}

/// Position residuals of one kind of point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PositionSummary {
    /// Measured points.
    pub points: usize,
    /// RMS of `|measured - predicted|` \[mm\].
    pub rms_mm: f64,
    /// Mean \[mm\].
    pub mean_mm: f64,
    /// Largest \[mm\].
    pub max_mm: f64,
    /// The RMS predicted \[mm\], by part: the noise `s sqrt(dof / (3 n))`, the repeatability
    /// and the calibration's error `sqrt(trace(cov) / n)`.
    pub predicted_mm: Prediction,
    /// `sqrt(max(0, rms^2 - predicted^2))`: the model error beyond the prediction \[mm\].
    pub excess_rms_mm: f64,
    /// Target positions estimated from these data (axis experiments: one per experiment and
    /// target).
    pub estimated_targets: usize,
    /// The test against the whole prediction (absent without degrees of freedom).
    pub chi_square: Option<ChiSquare>,
    /// The test without the calibration's error.
    pub chi_square_without_calibration: Option<ChiSquare>,
}

/// Orientation errors of the poses with three tool targets.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct OrientationSummary {
    /// Poses.
    pub poses: usize,
    /// RMS of the rotation angle from the predicted to the measured tool frame \[mrad\].
    pub rms_mrad: f64,
    /// Mean \[mrad\].
    pub mean_mrad: f64,
    /// Largest \[mrad\].
    pub max_mrad: f64,
    /// The RMS angle predicted \[mrad\], by part: the noise `(s / sqrt 3) sqrt(mean trace
    /// M^-1)`, the repeatability, the calibration's error.
    pub predicted_mrad: Prediction,
    /// The test against the whole prediction, 3 degrees of freedom per pose.
    pub chi_square: Option<ChiSquare>,
    /// The test without the calibration's error.
    pub chi_square_without_calibration: Option<ChiSquare>,
}

/// The result of [`validate`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Validation {
    /// The noise the residuals are tested against, 3-D RMS \[mm\].
    pub noise_rms_3d_mm: f64,
    /// `calibration` (the calibration's own) or `given` (`--noise-mm`).
    pub noise_source: String,
    /// Two-sided false-alarm rate of the verdicts.
    pub false_alarm: f64,
    /// The degrees of freedom of an estimated noise (the verdicts are F tests); null for a
    /// known one.
    pub noise_dof: Option<f64>,
    /// The repeatability of each joint the free poses are tested with (the calibration's)
    /// \[rad or m\].
    pub repeatability_rad_or_m: Vec<f64>,
    /// Whether the free poses' prediction includes the calibration's own error (the
    /// calibration has a `model_covariance`).
    pub calibration_uncertainty: bool,
    /// Validation poses.
    pub validation: Option<PositionSummary>,
    /// The tool observation.
    pub tool: Option<PositionSummary>,
    /// Axis experiments, pooled.
    pub axis: Option<PositionSummary>,
    /// Tool orientation of the free poses (validation and tool) with three tool targets.
    pub orientation: Option<OrientationSummary>,
    /// One line: how the calibration does on these data.
    pub verdict: String,
    /// What the reader must know about the inputs (the `warning:` lines `axiscal validate`
    /// printed: a unit scale, commands outside the joint limits, another robot's files).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Per point (written as `residuals.csv`, not in the JSON).
    #[serde(skip)]
    pub residuals: Vec<ValidationResidual>,
    /// Whether the model's curvature over the calibration's error counted in the prediction
    /// of the free poses ([`ValidationOptions::curvature_counts`]; not in the JSON, `None` for
    /// a validation read back).
    #[serde(skip)]
    pub curvature_counted: Option<bool>,
}

impl Validation {
    /// Whether any position test exceeds, or (unless `positions_only`) the orientations'.
    pub fn exceeds(&self, positions_only: bool) -> bool {
        let exceeds = |c: Option<&ChiSquare>| c.is_some_and(|c| c.verdict == Verdict::Exceeds);
        [&self.validation, &self.tool, &self.axis]
            .into_iter()
            .flatten()
            .any(|s| exceeds(s.chi_square.as_ref()))
            || (!positions_only
                && self
                    .orientation
                    .as_ref()
                    .is_some_and(|o| exceeds(o.chi_square.as_ref())))
    }
}

/// The kind of `m`.
fn kind_of(m: &Measurement) -> PointKind {
    if m.moved_joint > 0 {
        PointKind::Axis
    } else if m.experiment == TOOL_EXPERIMENT {
        PointKind::Tool
    } else {
        PointKind::Validation
    }
}

/// Predicts every point of `set` with `cal` (see the module docs) and tests the residuals.
pub fn validate(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    options: &ValidationOptions,
) -> Result<Validation, DiagnosisError> {
    Ok(validate_with(set, cal, desc, options, false)?.0)
}

/// [`validate`] for a calibration whose tool frame was never measured (`cal.tool` absent:
/// the description's, on the calibrated last link): its error is in no covariance, so the
/// free poses' tests estimate it from their own residuals (6 free components of the
/// shared error, [`SharedErrorChiSquare::with_free`]; up to 6 fewer degrees of freedom) and
/// judge what no tool frame explains. The predicted RMS still leaves the tool frame's error
/// out.
/// Also returns the tool frame the validation poses give, as a move from the calibration's.
pub fn validate_free_tool(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    options: &ValidationOptions,
) -> Result<(Validation, FittedToolMove), DiagnosisError> {
    let (v, fitted) = validate_with(set, cal, desc, options, true)?;
    let [t0, t1, t2, w0, w1, w2] = fitted.as_slice().try_into().unwrap_or([0.0; 6]);
    Ok((
        v,
        FittedToolMove {
            translation_mm: Vector3::new(t0, t1, t2),
            rotation_rad: Vector3::new(w0, w1, w2),
        },
    ))
}

/// The move of the tool frame (in the tool frame) that fits the validation poses best
/// ([`validate_free_tool`]): zero in the directions they do not resolve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FittedToolMove {
    /// Translation \[mm\].
    pub translation_mm: Vector3<f64>,
    /// Rotation vector \[rad\].
    pub rotation_rad: Vector3<f64>,
}

/// Each row of `set` against its prediction `clean` (measured minus predicted).
fn residuals_of(set: &MeasurementSet, clean: &CleanCampaign) -> Vec<ValidationResidual> {
    set.rows()
        .iter()
        .zip(clean.positions())
        .map(|(m, p)| {
            let p_mm = (p.coords * 1e3).into();
            ValidationResidual {
                experiment: m.experiment.clone(),
                kind: kind_of(m),
                moved_joint: m.moved_joint,
                step: m.step,
                target: m.target,
                measured_mm: m.position_mm,
                predicted_mm: p_mm,
                error_mm: (Vector3::from(m.position_mm) - Vector3::from(p_mm)).norm(),
            }
        })
        .collect()
}

/// Whether the model's curvature over `cal`'s error counts in the prediction of `set`'s free
/// poses, as [`validate`] judges it with `options` (where they leave it to be judged): a
/// search passes it to the validations of its rewrites ([`ValidationOptions::curvature_counts`]).
pub fn curvature_counts(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    options: &ValidationOptions,
) -> Result<bool, DiagnosisError> {
    let clean = CleanCampaign::new(set, cal, desc, &desc.tool_targets_m())?;
    let controller = Controller::from_description(desc);
    let (error, _) = prediction_error(set, (cal, desc, &controller), &residuals_of(set, &clean), options)?;
    Ok(error.has_curvature())
}

/// [`validate`], the tool frame estimated from the free poses with `free_tool`, and that
/// estimate (the validation poses' free components; empty without).
fn validate_with(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    options: &ValidationOptions,
    free_tool: bool,
) -> Result<(Validation, DVector<f64>), DiagnosisError> {
    let clean = CleanCampaign::new(set, cal, desc, &desc.tool_targets_m())?;
    let residuals = residuals_of(set, &clean);
    let controller = Controller::from_description(desc);
    let (error, frames) = prediction_error(set, (cal, desc, &controller), &residuals, options)?;
    let free = free_poses(
        set,
        (cal, desc, &controller),
        &residuals,
        (&error, &frames),
        (options, free_tool),
    )?;
    let axis_steps = axis_statistic(set, desc, &clean, &residuals, &error, options)?;
    let summary = |kind, statistic| position_summary(&residuals, kind, statistic, options);
    let (validation, tool, axis) = (
        summary(PointKind::Validation, &free.validation),
        summary(PointKind::Tool, &free.tool),
        summary(PointKind::Axis, &axis_steps),
    );
    let verdict = verdict(&validation, &tool, &axis, free.orientation.as_ref());
    let fitted = free.validation.free_estimate();
    let v = Validation {
        noise_rms_3d_mm: options.noise_rms_3d_mm,
        noise_source: options.noise_source.clone(),
        false_alarm: options.false_alarm,
        noise_dof: options.noise_dof,
        repeatability_rad_or_m: cal
            .options
            .joint_repeatability_rad(desc)
            .map_err(crate::calibration::procedure::ProcedureError::from)?,
        calibration_uncertainty: error.has_calibration(),
        validation,
        tool,
        axis,
        orientation: free.orientation,
        verdict,
        warnings: Vec::new(),
        residuals,
        curvature_counted: Some(error.has_curvature()),
    };
    Ok((v, fitted))
}

/// The residuals of free points (or rotations) against noise, repeatability and the
/// calibration's error: the statistic and the repeatability's summed variance.
struct FreeStatistic {
    chi: SharedErrorChiSquare,
    repeatability_variance: f64,
    with_calibration: bool,
}

impl FreeStatistic {
    /// With the calibration's error of `error` (if it has one) and `free` components without
    /// a prior after it ([`SharedErrorChiSquare::with_free`]).
    fn new(error: &PredictionError, free: usize) -> Self {
        FreeStatistic {
            chi: SharedErrorChiSquare::with_free(error.rank(), free),
            repeatability_variance: 0.0,
            with_calibration: error.has_calibration(),
        }
    }

    /// Adds residual block `r` with noise covariance `noise` and `factors`.
    fn add(&mut self, r: &DVector<f64>, noise: DMatrix<f64>, factors: &BlockFactors) {
        let jitter = &factors.repeatability;
        let covariance = noise + jitter * jitter.transpose();
        let weight = covariance
            .cholesky()
            .map_or_else(|| DMatrix::from_element(r.len(), r.len(), f64::NAN), |ch| ch.inverse());
        self.chi.add(r, &weight, &factors.calibration);
        self.repeatability_variance += jitter.norm_squared();
    }

    /// The sums' statistic, factorised once: none without a block.
    fn finish(self) -> FinishedStatistic {
        FinishedStatistic {
            fit: (!self.chi.is_empty()).then(|| self.chi.fit()),
            noise_alone: self.chi.noise_alone(),
            shared_variance: self.chi.shared_variance(),
            repeatability_variance: self.repeatability_variance,
            with_calibration: self.with_calibration,
        }
    }
}

/// A [`FreeStatistic`] with every block added: its fit and sums.
struct FinishedStatistic {
    /// The statistic with the calibration's error; `None` without a block.
    fit: Option<SharedErrorFit>,
    /// The statistic against the noise and repeatability alone.
    noise_alone: f64,
    /// The calibration's error's summed variance over every residual component.
    shared_variance: f64,
    /// The repeatability's summed variance.
    repeatability_variance: f64,
    /// Whether the calibration's error is included.
    with_calibration: bool,
}

impl FinishedStatistic {
    /// The prediction per point (or rotation) of `n` with the noise part `noise`.
    fn prediction(&self, noise: f64, n: usize, scale: f64) -> Prediction {
        let rms = |variance: f64| (variance / n as f64).sqrt() * scale;
        Prediction::new(
            noise,
            Some(rms(self.repeatability_variance)),
            self.with_calibration.then(|| rms(self.shared_variance)),
        )
    }

    /// The tests with and without the calibration's error, `estimated` target positions
    /// (3 dof each) fitted to the same residuals; none without a block.
    fn tests(&self, options: &ValidationOptions, estimated: usize) -> (Option<ChiSquare>, Option<ChiSquare>) {
        let Some(fit) = &self.fit else {
            return (None, None);
        };
        let dof = fit.dof.saturating_sub(3 * estimated);
        let test = |value| ChiSquare::new(value, dof, options.false_alarm, options.noise_dof);
        (test(fit.value), test(self.noise_alone))
    }

    /// The free components' estimate (empty without a block or free components).
    fn free_estimate(&self) -> DVector<f64> {
        self.fit
            .as_ref()
            .map_or_else(|| DVector::zeros(0), SharedErrorFit::free_estimate)
    }
}

/// The summary of the residuals of `kind`, `statistic` their test against noise,
/// repeatability and (free poses) calibration; `None` without such points.
fn position_summary(
    residuals: &[ValidationResidual],
    kind: PointKind,
    statistic: &FinishedStatistic,
    options: &ValidationOptions,
) -> Option<PositionSummary> {
    let of_kind: Vec<&ValidationResidual> = residuals.iter().filter(|r| r.kind == kind).collect();
    if of_kind.is_empty() {
        return None;
    }
    let n = of_kind.len();
    let errors: Vec<f64> = of_kind.iter().map(|r| r.error_mm).collect();
    let sum_squares: f64 = errors.iter().map(|e| e * e).sum();
    let estimated_targets = if kind == PointKind::Axis {
        of_kind
            .iter()
            .map(|r| (r.experiment.as_str(), r.target))
            .collect::<BTreeSet<_>>()
            .len()
    } else {
        0
    };
    let dof = (3 * n).saturating_sub(3 * estimated_targets);
    let s = options.noise_rms_3d_mm;
    let rms_mm = (sum_squares / n as f64).sqrt();
    let noise_mm = s * (dof as f64 / (3 * n) as f64).sqrt();
    let predicted_mm = statistic.prediction(noise_mm, n, 1.0);
    let (chi_square, chi_square_without_calibration) = statistic.tests(options, estimated_targets);
    Some(PositionSummary {
        points: n,
        rms_mm,
        mean_mm: errors.iter().sum::<f64>() / n as f64,
        max_mm: errors.iter().copied().fold(0.0, f64::max),
        excess_rms_mm: (rms_mm.powi(2) - predicted_mm.total.powi(2)).max(0.0).sqrt(),
        predicted_mm,
        estimated_targets,
        chi_square,
        chi_square_without_calibration,
    })
}

/// The axis experiments' statistic: each experiment's points against the noise and the
/// robot's repeatability as the replicas draw it (`super::noise`): the swept joint re-positions
/// at every step (a draw per step), the held joints keep one draw through the sweep (a draw per
/// experiment, shared by its steps). A held joint that keeps its draw from one experiment to
/// the next is taken as independent in each. With a model covariance, also the calibration's
/// error at each point ([`PredictionError::points`]: a target on a link beyond the swept one,
/// e.g. a coupling's, is not absorbed by its estimated position).
fn axis_statistic(
    set: &MeasurementSet,
    desc: &RobotDescription,
    clean: &CleanCampaign,
    residuals: &[ValidationResidual],
    error: &PredictionError,
    options: &ValidationOptions,
) -> Result<FinishedStatistic, DiagnosisError> {
    let repeatability = error.repeatability();
    let tool_targets = desc.tool_targets_m();
    let mut experiments: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, m) in set.rows().iter().enumerate().filter(|(_, m)| m.moved_joint > 0) {
        experiments.entry(m.experiment.as_str()).or_default().push(i);
    }
    let variance_coord_mm2 = options.noise_rms_3d_mm.powi(2) / 3.0;
    let dof = repeatability.len();
    let mut statistic = FreeStatistic::new(error, 0);
    for rows in experiments.values() {
        let mut steps: BTreeMap<usize, usize> = BTreeMap::new();
        for &i in rows {
            let next = steps.len();
            steps.entry(set.rows()[i].step).or_insert(next);
        }
        // Columns: one per joint (held: shared by every step), then one per step (the swept
        // joint's draw of that step).
        let mut jitter = DMatrix::zeros(3 * rows.len(), dof + steps.len());
        for (k, &i) in rows.iter().enumerate() {
            let m = &set.rows()[i];
            for (joint, sigma) in repeatability.iter().enumerate() {
                let column = if joint + 1 == m.moved_joint {
                    dof + steps[&m.step]
                } else {
                    joint
                };
                let moved_mm = clean.joint_sensitivity(i, joint) * (sigma * 1e3);
                jitter.view_mut((3 * k, column), (3, 1)).copy_from(&moved_mm);
            }
        }
        let subset = MeasurementSet::new(dof, rows.iter().map(|&i| set.rows()[i].clone()).collect())
            .map_err(|e| DiagnosisError::Model { message: e.to_string() })?;
        let factors = BlockFactors {
            calibration: error.points(&subset, desc, &tool_targets)?,
            repeatability: jitter,
        };
        let noise = DMatrix::identity(3 * rows.len(), 3 * rows.len()) * variance_coord_mm2;
        statistic.add(&stacked_residuals(residuals, rows), noise, &factors);
    }
    Ok(statistic.finish())
}

/// The residuals (measured minus predicted) of `rows`, stacked \[mm\].
fn stacked_residuals(residuals: &[ValidationResidual], rows: &[usize]) -> DVector<f64> {
    DVector::from_iterator(
        3 * rows.len(),
        rows.iter().flat_map(|&i| {
            let r = &residuals[i];
            (0..3).map(move |c| r.measured_mm[c] - r.predicted_mm[c])
        }),
    )
}

/// The measured tool frame of a pose from its three (or more) tool targets: the rigid fit of
/// the description's tool targets to the measured points, and the normal matrix `M` of the
/// fit's rotation (module docs).
fn measured_tool_frame(
    tool_targets: &[Point3<f64>],
    measured: &BTreeMap<usize, Point3<f64>>,
) -> Option<(Isometry3<f64>, Matrix3<f64>)> {
    let (src, dst): (Vec<Point3<f64>>, Vec<Point3<f64>>) = measured
        .iter()
        .filter_map(|(t, p)| Some((*tool_targets.get(*t)?, *p)))
        .unzip();
    let (world_from_tool, _) = rigid_fit(&src, &dst)?;
    let centroid = src.iter().map(|p| p.coords).sum::<Vector3<f64>>() / src.len() as f64;
    let normal = src.iter().fold(Matrix3::zeros(), |acc, p| {
        let d = p.coords - centroid;
        acc + Matrix3::identity() * d.norm_squared() - d * d.transpose()
    });
    Some((world_from_tool, normal))
}

/// What [`free_poses`] finds: the statistics of the validation and tool points and of the
/// orientations.
struct FreePoses {
    validation: FinishedStatistic,
    tool: FinishedStatistic,
    orientation: Option<OrientationSummary>,
}

/// A free pose: its first row, every row's index and its measured targets by id \[m\].
struct FreePose<'a> {
    first: &'a Measurement,
    rows: &'a [usize],
    measured: BTreeMap<usize, Point3<f64>>,
}

/// The free rows of `set` (validation and tool poses), each pose's rows together in file order
/// and the poses in (experiment, step) order: one index a row, each pose's [`FreePose`] made
/// when it is tested ([`free_pose_groups`]), not a map entry per pose held for all of them.
fn free_rows_by_pose(set: &MeasurementSet) -> Vec<usize> {
    let rows = set.rows();
    let mut order: Vec<usize> = (0..rows.len()).filter(|&i| rows[i].moved_joint == 0).collect();
    // A stable sort: a pose's rows stay in file order.
    order.sort_by(|&a, &b| {
        (rows[a].experiment.as_str(), rows[a].step).cmp(&(rows[b].experiment.as_str(), rows[b].step))
    });
    order
}

/// The free poses of `order` ([`free_rows_by_pose`]) one by one.
fn free_pose_groups<'a>(set: &'a MeasurementSet, order: &'a [usize]) -> impl Iterator<Item = FreePose<'a>> {
    let rows = set.rows();
    order
        .chunk_by(move |&a, &b| rows[a].experiment == rows[b].experiment && rows[a].step == rows[b].step)
        .map(move |group| FreePose {
            first: &rows[group[0]],
            rows: group,
            measured: group.iter().map(|&i| (rows[i].target, rows[i].position_m())).collect(),
        })
}

/// The free poses' tests: every pose's points, and the orientation of those with at least
/// three measured tool targets.
/// With `free_tool`, the tool frame's error is estimated from them ([`validate_free_tool`]).
fn free_poses(
    set: &MeasurementSet,
    (cal, desc, controller): (&Calibration, &RobotDescription, &Controller),
    residuals: &[ValidationResidual],
    (error, frames): (&PredictionError, &SampledFrames),
    (options, free_tool): (&ValidationOptions, bool),
) -> Result<FreePoses, DiagnosisError> {
    let tool_targets = desc.tool_targets_m();
    let variance_coord_mm2 = options.noise_rms_3d_mm.powi(2) / 3.0;
    let variance_coord_m2 = variance_coord_mm2 * 1e-6;
    let free = if free_tool { PoseError::FREE_TOOL } else { 0 };
    let (mut validation, mut tool, mut rotation) = (
        FreeStatistic::new(error, free),
        FreeStatistic::new(error, free),
        FreeStatistic::new(error, free),
    );
    let (mut angles_mrad, mut noise_sq) = (Vec::new(), 0.0);
    let context = PoseContext::new(set, (cal, desc, controller), residuals, (error, frames), free_tool);
    let order = free_rows_by_pose(set);
    for pose in free_pose_groups(set, &order) {
        let block = context.block(&pose, &tool_targets)?;
        let statistic = if kind_of(pose.first) == PointKind::Tool {
            &mut tool
        } else {
            &mut validation
        };
        let noise = DMatrix::identity(block.r.len(), block.r.len()) * variance_coord_mm2;
        statistic.add(&block.r, noise, &block.factors);
        let Some((measured_frame, normal)) = measured_tool_frame(&tool_targets, &pose.measured) else {
            continue;
        };
        let Some(normal_inv) = normal.try_inverse() else {
            continue;
        };
        let predicted = context.model.world_from_tool(&block.q);
        let w = (predicted.rotation.inverse() * measured_frame.rotation).scaled_axis();
        angles_mrad.push(w.norm() * 1e3);
        noise_sq += variance_coord_m2 * normal_inv.trace();
        let noise = DMatrix::from_column_slice(3, 3, (normal_inv * variance_coord_m2).as_slice());
        rotation.add(
            &DVector::from_column_slice(w.as_slice()),
            noise,
            &block.error.rotation(),
        );
    }
    let orientation = orientation_summary(&angles_mrad, noise_sq, &rotation.finish(), options);
    Ok(FreePoses {
        validation: validation.finish(),
        tool: tool.finish(),
        orientation,
    })
}

/// Free poses [`prediction_error`] samples, evenly spaced through the file.
const CURVATURE_SAMPLE: usize = 64;

/// Free poses beyond which [`prediction_error`] keeps the linear prediction: the drawn
/// remainder costs about two million operations a pose (256 more components), ten seconds at
/// this many.
const CURVATURE_MAX_POSES: usize = 5000;

/// What `set`'s points may miss by beside the noise ([`PredictionError`]), the model's
/// curvature over the calibration's error included where it counts
/// ([`super::prediction_curvature`]): as `options` say ([`ValidationOptions::curvature_counts`]),
/// else judged on at most [`CURVATURE_SAMPLE`] of its free poses, each with its noise
/// (`options.noise_rms_3d_mm`), repeatability and linear calibration covariance. A set without
/// free poses, or with more than [`CURVATURE_MAX_POSES`], keeps the linear prediction.
fn prediction_error<'a>(
    set: &MeasurementSet,
    (cal, desc, controller): (&'a Calibration, &'a RobotDescription, &'a Controller),
    residuals: &[ValidationResidual],
    options: &ValidationOptions,
) -> Result<(PredictionError<'a>, SampledFrames), DiagnosisError> {
    let linear = PredictionError::new(cal, controller, desc)?;
    if options.curvature_counts == Some(false) {
        return Ok((linear, SampledFrames::new()));
    }
    let error = linear.with_curvature();
    if !error.has_curvature() {
        return Ok((error, SampledFrames::new()));
    }
    let order = free_rows_by_pose(set);
    let poses = free_pose_groups(set, &order).count();
    if poses > CURVATURE_MAX_POSES {
        return Ok((error.without_curvature(), SampledFrames::new()));
    }
    if options.curvature_counts == Some(true) {
        return Ok((error, SampledFrames::new()));
    }
    let sampled: BTreeSet<usize> = crate::measurement::bounded::evenly_spaced((0..poses).collect(), CURVATURE_SAMPLE)
        .into_iter()
        .collect();
    let (counts, frames) = {
        let none = SampledFrames::new();
        let context = PoseContext::new(set, (cal, desc, controller), residuals, (&error, &none), false);
        let tool_targets = desc.tool_targets_m();
        let (linear, variance_coord_mm2) = (error.linear_rank(), options.noise_rms_3d_mm.powi(2) / 3.0);
        let (mut blocks, mut frames) = (Vec::with_capacity(sampled.len()), SampledFrames::new());
        for (_, pose) in free_pose_groups(set, &order)
            .enumerate()
            .filter(|(i, _)| sampled.contains(i))
        {
            let PoseBlock { factors, error, .. } = context.block(&pose, &tool_targets)?;
            frames.extend(error.into_drawn_frames().map(|f| (pose.rows[0], f)));
            let (g, jitter) = (factors.calibration.columns(0, linear), &factors.repeatability);
            let n = g.nrows();
            let covariance =
                DMatrix::identity(n, n) * variance_coord_mm2 + jitter * jitter.transpose() + g * g.transpose();
            blocks.push((
                covariance,
                factors.calibration.columns(linear, Curvature::DRAWS).into_owned(),
            ));
        }
        let scale = poses as f64 / sampled.len().max(1) as f64;
        (Curvature::counts(blocks.into_iter(), scale), frames)
    };
    Ok(match counts {
        true => (error, frames),
        false => (error.without_curvature(), SampledFrames::new()),
    })
}

/// The drawn models' tool frames at the free poses [`prediction_error`] sampled, by each pose's
/// first row: the tests take them rather than compute the drawn models' kinematics again.
type SampledFrames = HashMap<usize, DrawnFrames>;

/// One free pose's residuals and what they may miss by beside the noise.
struct PoseBlock<'a> {
    /// The pose's calibrated joint values.
    q: Vec<f64>,
    /// The error factors of its tool frame.
    error: PoseError<'a>,
    /// Its points' residuals (measured minus predicted), stacked \[mm\].
    r: DVector<f64>,
    /// Its points' covariance factors.
    factors: BlockFactors,
}

/// What every free pose's [`PoseBlock`] is made with.
struct PoseContext<'a> {
    set: &'a MeasurementSet,
    cal: &'a Calibration,
    desc: &'a RobotDescription,
    controller: &'a Controller,
    model: PhiModel,
    /// Each pose's actuator approach directions ([`crate::physics::actuator_approach_by_pose`]).
    approach: HashMap<(String, usize), Vec<f64>>,
    /// Every row's residual.
    residuals: &'a [ValidationResidual],
    error: &'a PredictionError<'a>,
    /// The drawn models' tool frames [`prediction_error`] computed.
    frames: &'a SampledFrames,
    /// The tool frame's error free ([`validate_free_tool`]).
    free_tool: bool,
}

impl<'a> PoseContext<'a> {
    fn new(
        set: &'a MeasurementSet,
        (cal, desc, controller): (&'a Calibration, &'a RobotDescription, &'a Controller),
        residuals: &'a [ValidationResidual],
        (error, frames): (&'a PredictionError<'a>, &'a SampledFrames),
        free_tool: bool,
    ) -> Self {
        PoseContext {
            set,
            cal,
            desc,
            controller,
            model: cal.robot.phi_model(),
            approach: crate::physics::actuator_approach_by_pose(set.rows(), desc),
            residuals,
            error,
            frames,
            free_tool,
        }
    }

    /// `pose`'s block.
    fn block(&self, pose: &FreePose<'_>, tool_targets: &[Point3<f64>]) -> Result<PoseBlock<'_>, DiagnosisError> {
        let m = pose.first;
        let q = calibrated_joint_values(
            &self.cal.robot,
            self.controller,
            &self.model,
            self.desc,
            m,
            &self.approach,
        )?;
        let cmd = commands_to_internal(self.desc, &m.cmd);
        let mut error = self.error.at(&self.model, (&cmd, &q), self.frames.get(&pose.rows[0]))?;
        if self.free_tool {
            error = error.with_free_tool();
        }
        let targets: Vec<Point3<f64>> = pose
            .rows
            .iter()
            .map(|&i| tool_targets[self.set.rows()[i].target])
            .collect();
        Ok(PoseBlock {
            factors: error.targets(&targets),
            q,
            error,
            r: stacked_residuals(self.residuals, pose.rows),
        })
    }
}

/// The free points' residuals of `v` (validated on `set` with `cal`) less the calibration's
/// error that all of them estimate together: with `e_hat` the posterior mean of the shared
/// error `e` given every free pose's residuals but those of the poses `left_out` (experiment,
/// step: suspected gross errors, which would drag it; [`SharedErrorFit::estimate`], each
/// pose weighted by its noise and repeatability), each pose's residuals `r_i - G_i e_hat`
/// (`G_i` its factor, `predicted_error::PredictionError`); the rows that are not free keep
/// theirs. A point the calibration's own error moves far (its error is one for every pose)
/// comes back to the noise; a corrupted one stays off. Every residual unchanged without a
/// model covariance.
pub fn residuals_less_calibration_error(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    v: &Validation,
    left_out: &BTreeSet<(&str, usize)>,
) -> Result<Vec<Vector3<f64>>, DiagnosisError> {
    let mut out: Vec<Vector3<f64>> = v
        .residuals
        .iter()
        .map(|r| Vector3::from(r.measured_mm) - Vector3::from(r.predicted_mm))
        .collect();
    let controller = Controller::from_description(desc);
    let options = ValidationOptions::of_validation(v);
    let (error, frames) = prediction_error(set, (cal, desc, &controller), &v.residuals, &options)?;
    if !error.has_calibration() {
        return Ok(out);
    }
    let context = PoseContext::new(set, (cal, desc, &controller), &v.residuals, (&error, &frames), false);
    let tool_targets = desc.tool_targets_m();
    let block = |pose: &FreePose<'_>| context.block(pose, &tool_targets);
    let order = free_rows_by_pose(set);
    let variance_coord_mm2 = v.noise_rms_3d_mm.powi(2) / 3.0;
    let mut shared = FreeStatistic::new(&error, 0);
    let kept = |pose: &FreePose<'_>| !left_out.contains(&(pose.first.experiment.as_str(), pose.first.step));
    for pose in free_pose_groups(set, &order).filter(kept) {
        let b = block(&pose)?;
        shared.add(
            &b.r,
            DMatrix::identity(b.r.len(), b.r.len()) * variance_coord_mm2,
            &b.factors,
        );
    }
    let estimate = shared.chi.fit().estimate;
    for pose in free_pose_groups(set, &order) {
        let explained = &block(&pose)?.factors.calibration * &estimate;
        for (k, &i) in pose.rows.iter().enumerate() {
            out[i] -= explained.fixed_rows::<3>(3 * k);
        }
    }
    Ok(out)
}

/// The orientation summary of the poses' angles, their summed noise variance `noise_sq`
/// \[rad^2\] and their statistic.
fn orientation_summary(
    angles_mrad: &[f64],
    noise_sq: f64,
    statistic: &FinishedStatistic,
    options: &ValidationOptions,
) -> Option<OrientationSummary> {
    if angles_mrad.is_empty() {
        return None;
    }
    let n = angles_mrad.len();
    let (chi_square, chi_square_without_calibration) = statistic.tests(options, 0);
    Some(OrientationSummary {
        poses: n,
        rms_mrad: (angles_mrad.iter().map(|a| a * a).sum::<f64>() / n as f64).sqrt(),
        mean_mrad: angles_mrad.iter().sum::<f64>() / n as f64,
        max_mrad: angles_mrad.iter().copied().fold(0.0, f64::max),
        predicted_mrad: statistic.prediction((noise_sq / n as f64).sqrt() * 1e3, n, 1e3),
        chi_square,
        chi_square_without_calibration,
    })
}

/// The one-line verdict from the main position summary and the orientation.
/// The headline: the validation poses' position test (the axis experiments' without them) with
/// the orientations', led by every other part beyond its prediction, so that it never calls
/// data consistent whose summary line says they exceed.
fn verdict(
    validation: &Option<PositionSummary>,
    tool: &Option<PositionSummary>,
    axis: &Option<PositionSummary>,
    orientation: Option<&OrientationSummary>,
) -> String {
    let exceeds = |c: &Option<ChiSquare>| c.as_ref().is_some_and(|c| c.verdict == Verdict::Exceeds);
    let (p, name, others) = match (validation, axis) {
        (Some(v), _) => (
            v,
            "validation poses",
            [("tool observation's", tool), ("axis experiments'", axis)],
        ),
        (None, Some(a)) => (a, "axis experiments", [("tool observation's", tool), ("", &None)]),
        (None, None) => return "no validation poses and no axis experiments: nothing to validate".into(),
    };
    let mut missed: Vec<String> = others
        .iter()
        .filter_map(|(name, s)| s.as_ref().map(|s| (name, s)))
        .filter(|(_, s)| exceeds(&s.chi_square))
        .map(|(name, s)| {
            format!(
                "the {name} points, RMS {:.4} mm (max {:.4} mm) against {:.4} mm predicted",
                s.rms_mm, s.max_mm, s.predicted_mm.total
            )
        })
        .collect();
    if let Some(o) = orientation.filter(|o| exceeds(&o.chi_square)) {
        missed.push(format!(
            "the tool orientations, RMS {:.4} mrad (max {:.4} mrad) against {:.4} mrad predicted",
            o.rms_mrad, o.max_mrad, o.predicted_mrad.total
        ));
    }
    let text = position_verdict(p, orientation);
    if missed.is_empty() || exceeds(&p.chi_square) {
        return text;
    }
    format!(
        "the calibrated model misses part of these data: {}; the {name}: {text}",
        missed.join("; ")
    )
}

/// The position test of `p` in words, with the orientations' verdict.
fn position_verdict(p: &PositionSummary, orientation: Option<&OrientationSummary>) -> String {
    let parts = p.predicted_mm.describe("mm");
    let mut text = match p.chi_square.as_ref().map(|c| c.verdict) {
        Some(Verdict::Exceeds) => format!(
            "the calibrated model misses these data: position RMS {:.4} mm against {:.4} mm predicted ({parts}; \
             model error beyond the prediction {:.4} mm RMS)",
            p.rms_mm, p.predicted_mm.total, p.excess_rms_mm
        ),
        Some(Verdict::Below) => format!(
            "residuals below the prediction: position RMS {:.4} mm against {:.4} mm predicted ({parts}); the \
             stated noise, repeatability or calibration uncertainty is overstated",
            p.rms_mm, p.predicted_mm.total
        ),
        Some(Verdict::Consistent) => format!(
            "consistent with the prediction: position RMS {:.4} mm against {:.4} mm predicted ({parts})",
            p.rms_mm, p.predicted_mm.total
        ),
        None => format!("position RMS {:.4} mm (no degrees of freedom for a test)", p.rms_mm),
    };
    if let Some(o) = orientation {
        text.push_str(&format!(
            "; orientation RMS {:.4} mrad against {:.4} mrad predicted ({})",
            o.rms_mrad,
            o.predicted_mrad.total,
            o.chi_square
                .as_ref()
                .map_or("no test".into(), |c| c.verdict.to_string())
        ));
    }
    text
}

/// `residuals.csv` of `axiscal validate` (`docs/formats.md#validation-residuals-csv`).
pub fn validation_residuals_csv(v: &Validation) -> String {
    let mut text = Vec::new();
    // Writing into memory has no I/O to fail, and cells are UTF-8 strings.
    write_validation_residuals_csv(v, &mut text).expect("a CSV table into memory");
    String::from_utf8(text).expect("UTF-8 cells")
}

/// [`validation_residuals_csv`] written into `w` row by row, the same bytes: a million-row
/// file's table is not held in memory before it is written.
pub fn write_validation_residuals_csv<W: std::io::Write>(v: &Validation, w: W) -> std::io::Result<()> {
    let header = [
        "experiment",
        "kind",
        "moved_joint",
        "step",
        "target",
        "x_mm",
        "y_mm",
        "z_mm",
        "predicted_x_mm",
        "predicted_y_mm",
        "predicted_z_mm",
        "dx_mm",
        "dy_mm",
        "dz_mm",
        "error_mm",
    ];
    let mut w = crate::csv_lines::writer(w);
    w.write_record(header)?;
    let mut row: Vec<String> = Vec::with_capacity(header.len());
    for r in &v.residuals {
        let kind = match r.kind {
            PointKind::Validation => "validation",
            PointKind::Tool => "tool",
            PointKind::Axis => "axis",
        };
        let (measured, predicted) = (r.measured_mm, r.predicted_mm);
        let difference = [0, 1, 2].map(|i| measured[i] - predicted[i]);
        row.clear();
        row.extend([
            r.experiment.clone(),
            kind.into(),
            r.moved_joint.to_string(),
            r.step.to_string(),
            r.target.to_string(),
        ]);
        let numbers = measured
            .iter()
            .chain(&predicted)
            .chain(&difference)
            .chain([&r.error_mm]);
        row.extend(numbers.map(|x| format!("{x:.4}")));
        w.write_record(&row)?;
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::{ChiSquare, Verdict};

    /// The verdicts at their edges: a statistic at its expectation is consistent, far above it
    /// exceeds, far below it is below the noise, and an overflowed one (infinite, or NaN from
    /// `inf - inf`) exceeds: never "consistent".
    #[test]
    fn verdicts_and_an_overflowed_statistic() {
        let verdict = |v: f64| ChiSquare::new(v, 100, 0.01, None).unwrap().verdict;
        assert_eq!(verdict(100.0), Verdict::Consistent);
        assert_eq!(verdict(300.0), Verdict::Exceeds);
        assert_eq!(verdict(30.0), Verdict::Below);
        assert_eq!(verdict(f64::INFINITY), Verdict::Exceeds);
        assert_eq!(verdict(f64::NAN), Verdict::Exceeds);
        assert!(ChiSquare::new(1.0, 0, 0.01, None).is_none());
        // With an estimated noise the acceptance widens: 1.5 per degree of freedom exceeds a
        // known noise of 100 degrees of freedom, not one estimated from 30.
        assert_eq!(
            ChiSquare::new(150.0, 100, 0.01, None).unwrap().verdict,
            Verdict::Exceeds
        );
        assert_eq!(
            ChiSquare::new(150.0, 100, 0.01, Some(30.0)).unwrap().verdict,
            Verdict::Consistent
        );
    }
}
