//! The scenario file as written by a user (`scenarios/*.toml`): every key optional except
//! `trials`, every unit in the key name. [`super::resolve`] turns it into a checked
//! [`ResolvedScenario`](super::ResolvedScenario).

use super::threshold::Threshold;
use crate::plan::{AxisSweep, ValidationPlan};
use crate::sim::Effects;
use crate::sim::PerturbationSpec;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// A scenario file (see the module docs and `docs/formats.md#scenario-file`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFile {
    /// Name; default the file stem. Results go to `results/<name>/`.
    pub name: Option<String>,
    /// One line saying what the scenario studies.
    #[serde(default)]
    pub description: String,
    /// Nominal robot description, relative to the scenario file; default the IRB/L6 of
    /// `scenarios/robots/asea-irb6l.toml`.
    pub robot: Option<PathBuf>,
    /// Trials per case (>= 1).
    pub trials: usize,
    /// Scenario seed; trial `i` uses `trial_seed(seed, i)`.
    #[serde(default)]
    pub seed: u64,
    /// Simulator of the real robot.
    #[serde(default)]
    pub sim: SimMode,
    /// The simulated real robot.
    #[serde(default)]
    pub truth: TruthSection,
    /// The instrument.
    #[serde(default)]
    pub measurement: MeasurementSection,
    /// The calibration plan.
    #[serde(default)]
    pub plan: PlanSection,
    /// The validation (evaluation) poses; default
    /// [`ValidationPlan::workspace_default`]: keys `poses`, `half_range` \[deg or mm per
    /// joint\], `seed`.
    pub validation: Option<ValidationPlan>,
    /// Unmodelled effects of the real robot (`docs/formats.md#effects-file`); the analytic arm
    /// applies compliance and payload to first order, the rapier arm physically.
    #[serde(default)]
    pub effects: Effects,
    /// Payload and temperature of every pose.
    #[serde(default)]
    pub conditions: ConditionsSection,
    /// With `sim = "rapier"`: targets hidden by the links from a station are not measured
    /// (default true).
    #[serde(default = "default_occlusion")]
    pub occlusion: bool,
    /// At most one swept parameter; each value is one case.
    pub sweep: Option<SweepSection>,
    /// An ISO 9283 test after each trial's calibration: the `iso_*` metrics, measured and
    /// predicted.
    pub iso9283: Option<IsoSection>,
    /// The metric plotted as a histogram per case; default `uncal_pos_rms_mm`.
    pub main_metric: Option<String>,
    /// Pass/fail criteria (exit code 1 when one fails).
    #[serde(default)]
    pub thresholds: Vec<Threshold>,
    /// The largest fraction of each case's trials that may fail (calibration not converged,
    /// ...) before the run fails (exit 1); in `0..=1`, default 0: any failed trial fails it.
    #[serde(default)]
    pub max_failure_rate: f64,
}

fn default_occlusion() -> bool {
    true
}

/// Which simulator plays the real robot.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SimMode {
    /// The analytic truth model ([`AnalyticArm`](crate::sim::AnalyticArm)).
    #[default]
    Analytic,
    /// The rapier multibody ([`RapierArm`](crate::sim::RapierArm): line of sight, compliance
    /// by static equilibrium).
    Rapier,
}

/// Where the simulated real robot comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum TruthSection {
    /// The paper's robot: Table 2 actual rows and the section-4 functions. A struct variant
    /// without fields, so that a key beside `kind = "paper"` (a `path`) is refused.
    Paper {},
    /// A truth-model file (relative to the scenario file).
    File {
        /// Path of the [`RobotModel`](crate::robot::RobotModel) TOML.
        path: PathBuf,
    },
    /// A fleet: each trial draws a robot around the nominal description.
    Perturbed {
        /// Distributions (`normal`, `uniform`, `truncated_normal`) per kind of quantity.
        perturbation: Box<PerturbationSpec>,
    },
}

impl Default for TruthSection {
    /// The paper's robot.
    fn default() -> Self {
        TruthSection::Paper {}
    }
}

/// Which instrument and how noisy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Instrument {
    /// Two theodolites at the paper's stations, angular noise calibrated to the net radial
    /// error.
    #[default]
    Theodolite,
    /// Isotropic Gaussian noise of the same 3-D RMS.
    Isotropic,
}

/// The measurement model.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MeasurementSection {
    /// Theodolites or isotropic noise.
    #[serde(default)]
    pub instrument: Instrument,
    /// 3-D RMS of the measurement error \[mm\] (paper: 0.19).
    #[serde(default = "paper_net_radial_rms_mm")]
    pub net_radial_rms_mm: f64,
}

fn paper_net_radial_rms_mm() -> f64 {
    crate::measurement::PAPER_NET_RADIAL_RMS_MM
}

impl Default for MeasurementSection {
    fn default() -> Self {
        MeasurementSection {
            instrument: Instrument::Theodolite,
            net_radial_rms_mm: paper_net_radial_rms_mm(),
        }
    }
}

/// The calibration plan: paper Table 1 unless `sweeps` is given.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlanSection {
    /// Commands of the common reference pose \[deg or mm\]; default all zero.
    pub reference: Option<Vec<f64>>,
    /// The axis experiments in run order (`joint`, `span` \[deg or mm\], `intervals`,
    /// `second_target`, `start`); default Table 1 (order 6..1).
    pub sweeps: Option<Vec<AxisSweep>>,
    /// Multiplies every span (1 = as given).
    #[serde(default = "one")]
    pub span_scale: f64,
}

fn one() -> f64 {
    1.0
}

impl Default for PlanSection {
    fn default() -> Self {
        PlanSection {
            reference: None,
            sweeps: None,
            span_scale: 1.0,
        }
    }
}

/// Conditions every pose of the campaign is measured under (`docs/formats.md#measurement-csv`, optional columns);
/// the effects that depend on them (payload through compliance, thermal expansion) act only
/// when switched on in `[effects]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConditionsSection {
    /// Payload at the tool \[kg\] (default 0).
    #[serde(default)]
    pub payload_kg: f64,
    /// Ambient temperature \[deg C\] (default 20).
    #[serde(default = "default_temperature")]
    pub temperature_c: f64,
}

fn default_temperature() -> f64 {
    20.0
}

impl Default for ConditionsSection {
    fn default() -> Self {
        ConditionsSection {
            payload_kg: 0.0,
            temperature_c: default_temperature(),
        }
    }
}

/// One swept parameter (set exactly one key); every value becomes a case named
/// `<key>=<value>` (spans: `spans=<index>`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SweepSection {
    /// Net radial measurement error \[mm\], replacing `measurement.net_radial_rms_mm`.
    pub net_radial_rms_mm: Option<Vec<f64>>,
    /// Span multiplier, replacing `plan.span_scale`.
    pub span_scale: Option<Vec<f64>>,
    /// Whole span lists \[deg or mm\], one per plan sweep in plan order, replacing the spans.
    pub spans: Option<Vec<Vec<f64>>>,
    /// Whole plan files (`docs/formats.md#plan-file`, relative to the scenario file), each
    /// replacing the plan; the case is named `plan=<file stem>`.
    pub plans: Option<Vec<PathBuf>>,
}

/// The ISO 9283 test a trial runs after its calibration (`docs/formats.md#scenario-file`): the
/// cube planned through the calibrated model (fig. 5), its cycles executed on the simulated
/// robot and measured, the figures evaluated, and predicted from the calibration's covariance
/// ([`crate::iso9283::predict()`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct IsoSection {
    /// Cycles (ISO 9283: 30), 2 to 1000.
    #[serde(default = "iso_cycles")]
    pub cycles: usize,
    /// The cube's edge \[mm\]; default the largest to 10 mm, at most 500 mm, whose points are
    /// inside the joint limits.
    pub edge_mm: Option<f64>,
    /// The commands of the cube's centre \[deg or mm\]; default the plan's reference pose.
    pub centre_cmd: Option<Vec<f64>>,
    /// Simulated tests of the prediction, 1 to 10000.
    #[serde(default = "iso_prediction_trials")]
    pub prediction_trials: usize,
}

fn iso_cycles() -> usize {
    30
}

fn iso_prediction_trials() -> usize {
    100
}
