//! The diagnosis result (`docs/formats.md#diagnosis-json` plus details) and its parts.

use serde::{Deserialize, Serialize};

/// One `where` entry: an experiment's (or a workspace feature's) residual against its
/// noise-only prediction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct WhereEntry {
    /// Experiment id (`validation`: the calibrated model on every validation pose;
    /// `validation_heldout_refit`: the baseline on the held-out poses; `feature:NAME:BIN`:
    /// the held-out poses of one bin of a workspace feature, see [`crate::diagnosis`]).
    pub experiment: String,
    /// The moved joint (or the feature's joint), or `None`.
    pub joint: Option<usize>,
    /// Residual RMS over the noise-only RMS.
    pub excess_ratio: f64,
    /// Residual RMS \[mm\].
    pub residual_rms_mm: f64,
    /// Noise-only RMS \[mm\] (mean over the replicas, in variance).
    pub noise_only_rms_mm: f64,
}

/// How much a workspace feature's bins differ in their held-out excess
/// ([`WhereEntry`]`::excess_ratio` of `feature:NAME:BIN`): a gap that depends on the feature.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FeatureContrast {
    /// Feature name (`reach`, `joint_angle_2`, `gravity_torque_3`, `payload`, `temperature`,
    /// `approach_4`, ...).
    pub feature: String,
    /// The feature's joint, or `None`.
    pub joint: Option<usize>,
    /// Largest bin excess ratio over the smallest (1: the same everywhere).
    pub contrast: f64,
    /// The noise-only replicas' `1 - false_alarm` quantile of the same contrast (per feature,
    /// not family-wise).
    pub noise_only_threshold: f64,
    /// `contrast > noise_only_threshold`.
    pub beyond_noise: bool,
}

/// A fitted parameter with its 1-sigma.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Parameter {
    /// Name with unit.
    pub name: String,
    /// Value.
    pub value: f64,
    /// 1-sigma from the linearised fit's covariance (noise variance the larger of the stated
    /// one and the fit's residual variance).
    pub sigma: f64,
}

/// One scored candidate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CandidateScore {
    /// Effect name.
    pub effect: String,
    /// The member of the effect's family (`docs/diagnosis.md`, "Candidate families"), e.g.
    /// `actuator_spring_serial_load_lumped_moments`: for a compliance it names the load path.
    pub member: String,
    /// Joint, or `None`.
    pub joint: Option<usize>,
    /// Held-out position RMS with the effect \[mm\].
    pub heldout_rms_mm: f64,
    /// Held-out gap with the effect \[mm\].
    pub gap_after_mm: f64,
    /// Held-out improvement over the baseline, `(SSR_base - SSR_c) / sigma^2` (sigma the
    /// per-coordinate noise).
    pub improvement_chi2: f64,
    /// The improvement in sigmas of its noise-only distribution.
    pub z: f64,
    /// Whether `z` beats the noise-only maximum over all candidates at the false-alarm rate.
    pub significant: bool,
    /// Fraction of the candidate's signature (norm over the training poses) the baseline
    /// refit cannot absorb: 0 means the effect leaves no trace after the refit.
    pub outside_refit_fraction: f64,
    /// Akaike-type weight `exp(-SSR_c / 2 sigma^2)` over the nameable candidates (significant
    /// and plausible; 0 for the others).
    pub weight: f64,
    /// Fitted effect parameters.
    pub parameters: Vec<Parameter>,
    /// Why the fitted parameters are physically implausible (`docs/diagnosis.md`,
    /// "Plausibility"; checked for significant candidates only): such a candidate is not named.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub implausible: Option<String>,
}

/// The `docs/formats.md#diagnosis-json` verdict fields of a diagnosis ([`Diagnosis`],
/// [`AxesDiagnosis`](super::AxesDiagnosis)).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Outcome {
    /// `none`, `unexplained`, or a candidate's effect name.
    pub effect: String,
    /// The effect's joint, or `None`.
    pub joint: Option<usize>,
    /// Confidence in `effect` (0..1): for a named effect the summed weight of its family's
    /// members on its joint among the nameable candidates; for `none` the gap test's p-value (how often noise alone leaves at least
    /// this held-out residual); for `unexplained` one minus the p-value of the gap left by the
    /// best candidate. (Axis-experiments-only mode: `1 - p` of the most excessive axis.)
    pub confidence: f64,
    /// Held-out gap of the baseline \[mm\] (axis-experiments-only mode: the arcs' gap).
    pub gap_before_mm: f64,
    /// Held-out gap with the named effect (the baseline's when none is named) \[mm\].
    pub gap_after_mm: f64,
}

/// One of several named effects (`docs/formats.md#diagnosis-json`, `effects`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct NamedEffect {
    /// Effect name.
    pub effect: String,
    /// Its joint, or `None`.
    pub joint: Option<usize>,
    /// Its share of the closed gap (Shapley value over the two orders of adding them; the
    /// shares sum to 1).
    pub share: f64,
}

fn given() -> String {
    "given".into()
}

/// The diagnosis (`docs/formats.md#diagnosis-json` plus details).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Diagnosis {
    /// The `docs/formats.md#diagnosis-json` verdict.
    #[serde(flatten)]
    pub outcome: Outcome,
    /// Experiments and workspace features ranked by excess over noise.
    #[serde(rename = "where")]
    pub where_: Vec<WhereEntry>,
    /// Workspace features by how much the gap depends on them (contrast over its noise-only
    /// threshold, largest first).
    #[serde(default)]
    pub features: Vec<FeatureContrast>,
    /// Present when two effects are named: each with its share of the closed gap; the
    /// verdict's `effect` and `joint` are the one with the larger share.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub effects: Vec<NamedEffect>,
    /// Candidates, best (lowest held-out RMS) first.
    pub candidates: Vec<CandidateScore>,
    /// The named effect's family member (the best-scored nameable candidate of its effect
    /// and joint); `None` for `none` and `unexplained`.
    #[serde(default)]
    pub member: Option<String>,
    /// The named effect's parameters.
    pub parameters: Vec<Parameter>,
    /// Noise assumed, 3-D RMS \[mm\].
    pub noise_rms_3d_mm: f64,
    /// Where `noise_rms_3d_mm` comes from: `given` (`--noise-mm`) or `estimated` (from the
    /// axis experiments' residuals, [`estimated_noise`](super::estimated_noise)).
    #[serde(default = "given")]
    pub noise_source: String,
    /// The tool targets the diagnosis scored with, refined from the training poses, against
    /// the description's (`far` when the nominal guess is far off); absent when the refit
    /// could not be refined.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool_targets: Option<super::ToolTargets>,
    /// Training and held-out pose counts.
    pub poses: PoseSplit,
    /// The validation points the outlier test flagged (`docs/diagnosis.md`, "Outliers"), each
    /// with whether the diagnosis was made without it; absent when none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub outliers: Vec<crate::calibration::procedure::OutlierPoint>,
    /// What the run warned of about the data beside the verdict (a block of validation poses
    /// shifted in file order); absent when none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Baseline held-out RMS \[mm\].
    pub heldout_rms_before_mm: f64,
    /// Noise-only held-out RMS of the baseline \[mm\].
    pub noise_only_rms_mm: f64,
    /// Significance of the baseline gap: held-out chi-square minus its noise-only mean, in
    /// noise-only standard deviations.
    pub gap_sigmas: f64,
    /// The smallest held-out gap the gap test flags at the false-alarm rate \[mm\]: an effect
    /// whose trace after the refit is smaller reads `none`.
    pub detectable_gap_mm: f64,
    /// False-alarm rate of every test.
    pub false_alarm: f64,
    /// Noise-only samples behind the thresholds (replicas x validation-noise draws).
    pub null_samples: usize,
    /// Rank of the baseline refit (identifiable directions) and its parameter count.
    pub refit_rank: RefitRank,
    /// Fraction of the gap's variance the best candidate removes.
    pub fraction_closed: f64,
    /// One sentence.
    pub verdict: String,
}

/// How the validation poses were split.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PoseSplit {
    /// Poses the refits are fitted on.
    pub training: usize,
    /// Poses held out, where the gaps are measured.
    pub held_out: usize,
    /// Validation poses of the file left out of the diagnosis (beyond `--max-poses`, evenly
    /// spaced through the file; absent when every pose is diagnosed).
    #[serde(default, skip_serializing_if = "crate::json_file::is_zero_count")]
    pub left_out: usize,
}

/// The baseline refit's identifiable directions.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RefitRank {
    /// Rank (identifiable directions).
    pub rank: usize,
    /// Parameters refitted.
    pub parameters: usize,
}
