//! The predicted tool accuracy ([`crate::calibration::tool_accuracy`]) against a Monte-Carlo
//! of calibrations: one simulated Table-1 campaign of the paper robot (jitter-free, isotropic
//! noise) calibrated with [`calibrate`] gives the prediction (its model covariance through the
//! tool Jacobian at each pose); `trials` further campaigns, each with its own noise, are
//! calibrated on the lean path and their tool pose compared with the truth's at the same
//! commands. The Monte-Carlo RMS's standard error comes from the trials' scatter (the poses of
//! one trial share its calibration, so a trial is the independent unit).

use super::efficiency::{campaign, trial_seed};
use crate::calibration::procedure::{
    CalibrationOptions, Detail, ProcedureError, axis_experiments, calibrate, calibrate_model,
};
use crate::calibration::tool_accuracy::{ToolSensitivity, draw_poses, swept_ranges, tool_pose};
use crate::numerics::stats;
use crate::robot::{Controller, ModelError, RobotDescription, RobotModel, commands_to_internal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The check's settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ToolAccuracyStudy {
    /// Monte-Carlo calibrations.
    pub trials: usize,
    /// Seed (the predicting campaign's noise, every trial's, the pose draws).
    pub seed: u64,
    /// Measurement noise, 3-D RMS \[mm\].
    pub noise_rms_3d_mm: f64,
    /// Poses per set (spans, workspace).
    pub poses: usize,
}

/// Predicted against Monte-Carlo over one set of poses.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ToolAccuracyCheck {
    /// `spans` or `workspace`.
    pub poses: String,
    /// Predicted RMS position 1-sigma norm over the poses \[mm\].
    pub predicted_position_rms_mm: f64,
    /// Monte-Carlo RMS position error over trials and poses \[mm\].
    pub monte_carlo_position_rms_mm: f64,
    /// Its standard error \[mm\].
    pub monte_carlo_position_standard_error_mm: f64,
    /// Predicted RMS orientation 1-sigma norm \[mrad\].
    pub predicted_orientation_rms_mrad: f64,
    /// Monte-Carlo RMS orientation error \[mrad\].
    pub monte_carlo_orientation_rms_mrad: f64,
    /// Its standard error \[mrad\].
    pub monte_carlo_orientation_standard_error_mrad: f64,
}

impl ToolAccuracyCheck {
    /// Predicted over Monte-Carlo RMS, position and orientation.
    pub fn ratios(&self) -> [f64; 2] {
        [
            self.predicted_position_rms_mm / self.monte_carlo_position_rms_mm,
            self.predicted_orientation_rms_mrad / self.monte_carlo_orientation_rms_mrad,
        ]
    }
}

/// Why the check stopped.
#[derive(Debug, thiserror::Error)]
pub enum ToolAccuracyError {
    /// A calibration failed.
    #[error("trial {trial}: {cause}")]
    Procedure {
        /// Trial (`None`: the predicting calibration).
        trial: String,
        /// The procedure's error (boxed: it is large, and rare).
        cause: Box<ProcedureError>,
    },
    /// A pose could not be evaluated.
    #[error(transparent)]
    Model(#[from] ModelError),
}

/// Per trial and pose set: mean squared position \[m^2\] and orientation \[rad^2\] error.
type TrialErrors = Vec<[f64; 2]>;

impl ToolAccuracyStudy {
    /// Runs the check (in parallel; bit-identical for any thread count): spans, then workspace.
    pub fn run(&self) -> Result<Vec<ToolAccuracyCheck>, ToolAccuracyError> {
        let desc = RobotDescription::asea_irb6l();
        let controller = Controller::from_description(&desc);
        let mut truth = crate::sim::paper_robot();
        truth.joints.iter_mut().for_each(|j| j.repeatability_sigma = 0.0);
        let options = CalibrationOptions {
            noise_rms_3d_mm: self.noise_rms_3d_mm,
            repeatability_sigma_rad: Some(vec![0.0]),
            ..CalibrationOptions::default()
        };
        let failed = |trial: String| {
            move |source| ToolAccuracyError::Procedure {
                trial,
                cause: Box::new(source),
            }
        };
        let set = campaign(&truth, &desc, self.noise_rms_3d_mm, trial_seed(self.seed, u64::MAX));
        let cal = calibrate(&set, &desc, &options).map_err(failed("prediction".into()))?;
        let (experiments, reference) = axis_experiments(&set, &desc).map_err(failed("prediction".into()))?;
        let limits: Vec<[f64; 2]> = desc.joints.iter().map(|j| j.limits).collect();
        let sets: Vec<(&str, Vec<Vec<f64>>)> =
            [("spans", swept_ranges(&experiments, &reference)), ("workspace", limits)]
                .into_iter()
                .enumerate()
                .map(|(i, (name, ranges))| {
                    let poses = draw_poses(&ranges, self.poses, trial_seed(self.seed, u64::MAX - 1 - i as u64));
                    (name, poses.iter().map(|c| commands_to_internal(&desc, c)).collect())
                })
                .collect();
        let cov = cal
            .model_covariance
            .as_ref()
            .expect("calibrate fills the model covariance")
            .matrix();
        let sensitivity = ToolSensitivity::new(&cal.robot, &controller, &cov);
        let trials: Vec<TrialErrors> = (0..self.trials)
            .into_par_iter()
            .map(|i| {
                let set = campaign(&truth, &desc, self.noise_rms_3d_mm, trial_seed(self.seed, i as u64));
                let fit = calibrate_model(&set, &desc, &options, Detail::Model).map_err(failed(i.to_string()))?;
                let errors = sets
                    .iter()
                    .map(|(_, poses)| mean_squared_errors(&fit.robot, &truth, &controller, poses))
                    .collect::<Result<_, _>>()?;
                Ok::<_, ToolAccuracyError>(errors)
            })
            .collect::<Result<_, _>>()?;
        sets.iter()
            .enumerate()
            .map(|(s, (name, poses))| {
                let predicted: Vec<_> = poses
                    .iter()
                    .map(|c| sensitivity.sigma_at(c))
                    .collect::<Result<_, _>>()?;
                let rms = |f: &dyn Fn(&crate::calibration::tool_accuracy::PoseSigma) -> f64| {
                    (predicted.iter().map(|p| f(p).powi(2)).sum::<f64>() / predicted.len() as f64).sqrt()
                };
                let (pos, pos_se) = rms_and_error(trials.iter().map(|t| t[s][0]));
                let (rot, rot_se) = rms_and_error(trials.iter().map(|t| t[s][1]));
                Ok(ToolAccuracyCheck {
                    poses: name.to_string(),
                    predicted_position_rms_mm: rms(&|p| p.position_norm_mm),
                    monte_carlo_position_rms_mm: pos * 1e3,
                    monte_carlo_position_standard_error_mm: pos_se * 1e3,
                    predicted_orientation_rms_mrad: rms(&|p| p.orientation_norm_mrad),
                    monte_carlo_orientation_rms_mrad: rot * 1e3,
                    monte_carlo_orientation_standard_error_mrad: rot_se * 1e3,
                })
            })
            .collect()
    }
}

/// The RMS `sqrt(mean m_i)` of per-trial mean squares `m_i` and its standard error by the
/// delta method, `sd(m) / sqrt(n) / (2 RMS)`.
fn rms_and_error(m: impl Iterator<Item = f64>) -> (f64, f64) {
    let m: Vec<f64> = m.collect();
    let (mean, error) = stats::mean_and_standard_error(&m);
    let rms = mean.sqrt();
    (rms, error / (2.0 * rms))
}

/// Mean over `poses` (internal commands) of the squared tool position \[m^2\] and orientation
/// \[rad^2\] error of `fitted` against `truth`.
fn mean_squared_errors(
    fitted: &RobotModel,
    truth: &RobotModel,
    controller: &Controller,
    poses: &[Vec<f64>],
) -> Result<[f64; 2], ModelError> {
    let mut sum = [0.0; 2];
    for c in poses {
        let (a, b) = (tool_pose(fitted, controller, c)?, tool_pose(truth, controller, c)?);
        sum[0] += (a.translation.vector - b.translation.vector).norm_squared();
        sum[1] += (a.rotation * b.rotation.inverse()).angle().powi(2);
    }
    Ok(sum.map(|s| s / poses.len() as f64))
}
