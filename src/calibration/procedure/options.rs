//! The procedure's options: the axis estimator, the noise and repeatability it weights the
//! fits with, the held-joint tolerance, and how much a calibration computes besides the model.

use crate::robot::RobotDescription;
use serde::{Deserialize, Serialize};

/// How far a held joint may move within one axis experiment (file units: deg for a revolute,
/// mm for a prismatic joint); the default of [`CalibrationOptions::held_tolerance`].
pub const DEFAULT_HELD_TOLERANCE: f64 = 0.5;

/// Which rotary-axis estimator to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum AxisEstimator {
    /// Maximum-likelihood arc fit through the transmission model (default; efficient).
    #[default]
    Ml,
    /// The paper's estimator, eqs. (1)-(5), then eqs. (6)-(8).
    Paper,
}

impl AxisEstimator {
    /// Its name as `--estimator` spells it (`ml`, `paper`).
    pub fn name(self) -> &'static str {
        match self {
            AxisEstimator::Ml => "ml",
            AxisEstimator::Paper => "paper",
        }
    }
}

/// Options of the procedure.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
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
    /// [`crate::calibration::fit_arc_with_angle_noise`] (ML estimator only), so the weights and the reported
    /// covariance include the angle noise of the sweep; 0 everywhere is the measurement-only
    /// fit, bit for bit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repeatability_sigma_rad: Option<Vec<f64>>,
    /// Weight the fits with the noise estimated from the residuals (`noise_rms_3d_mm` is then
    /// only the first pass's value): what `axiscal calibrate` does without `--noise-mm`.
    #[serde(default)]
    pub estimate_noise: bool,
    /// How far a held joint may wander within one axis experiment (deg for a revolute, mm for
    /// a prismatic joint; `docs/formats.md#held-joints`).
    #[serde(
        default = "default_held_tolerance",
        rename = "held_tolerance_deg_or_mm",
        alias = "held_tolerance"
    )]
    pub held_tolerance: f64,
}

fn default_held_tolerance() -> f64 {
    DEFAULT_HELD_TOLERANCE
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        CalibrationOptions {
            estimator: AxisEstimator::Ml,
            noise_rms_3d_mm: 0.19,
            max_iterations: 100,
            repeatability_sigma_rad: None,
            estimate_noise: false,
            held_tolerance: DEFAULT_HELD_TOLERANCE,
        }
    }
}

impl CalibrationOptions {
    /// The repeatability \[rad\] the axis fit of each joint of `desc` assumes (see
    /// [`CalibrationOptions::repeatability_sigma_rad`]).
    pub fn joint_repeatability_rad(&self, desc: &RobotDescription) -> Result<Vec<f64>, InvalidOption> {
        let n = desc.dof();
        let sigmas = match &self.repeatability_sigma_rad {
            None => desc.joints.iter().map(|j| j.repeatability_sigma).collect(),
            Some(v) if v.len() == 1 => vec![v[0]; n],
            Some(v) if v.len() == n => v.clone(),
            Some(v) => {
                return Err(InvalidOption {
                    field: "repeatability_sigma_rad",
                    message: format!("needs 1 or {n} values, got {}", v.len()),
                });
            }
        };
        if let Some(s) = sigmas.iter().find(|s| !(s.is_finite() && **s >= 0.0)) {
            return Err(InvalidOption {
                field: "repeatability_sigma_rad",
                message: format!("must be finite and >= 0, got {s}"),
            });
        }
        Ok(sigmas)
    }
}

/// How much a calibration computes besides the fitted model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Detail {
    /// The fitted model only: what a Monte-Carlo trial needs ([`calibrate_model`](super::calibrate_model)).
    Model,
    /// The model and the 1-sigma of its rows ([`FittedModel::row_sigma`](super::FittedModel::row_sigma)).
    ModelAndCovariance,
    /// [`Detail::ModelAndCovariance`] and the covariance of the model's whole parameter vector
    /// ([`FittedModel::model_covariance`](super::FittedModel::model_covariance)): what a Monte-Carlo of the tool's error needs.
    ModelCovariance,
    /// Everything [`Calibration`](super::Calibration) holds: per-axis reports with their covariances and
    /// identifiability studies, per-sweep reports, residuals, the noise report ([`calibrate`](super::calibrate)).
    Report,
}

/// A calibration option out of range: the option and what is wrong with it.
#[derive(Debug, thiserror::Error)]
#[error("calibration option `{field}`: {message}")]
pub struct InvalidOption {
    /// The option.
    pub field: &'static str,
    /// What is wrong.
    pub message: String,
}
