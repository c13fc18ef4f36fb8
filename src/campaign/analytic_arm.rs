//! The analytic truth model as the campaign's simulated robot: commands through the fig. 3
//! controller into the truth's transmissions and couplings, then the actual phi-model.

use super::simulate::{ArmExecutor, ExecuteError, PoseConditions};
use crate::kinematics::PhiModel;
use crate::robot::{Controller, TruthRobot};
use nalgebra::Isometry3;
use rand::Rng;

/// The analytic "real robot": exact kinematics, repeatability jitter, no bodies (so every
/// target is visible) and no effect of payload or temperature.
#[derive(Clone, Debug)]
pub struct AnalyticArm {
    truth: TruthRobot,
    model: PhiModel,
    controller: Controller,
}

impl AnalyticArm {
    /// The truth robot driven by `controller` (built from the nominal description).
    pub fn new(truth: TruthRobot, controller: Controller) -> Self {
        let model = truth.model();
        AnalyticArm {
            truth,
            model,
            controller,
        }
    }

    /// The truth model.
    pub fn truth(&self) -> &TruthRobot {
        &self.truth
    }
}

impl ArmExecutor for AnalyticArm {
    fn execute<R: Rng + ?Sized>(
        &mut self,
        cmd: &[f64],
        _conditions: &PoseConditions,
        rng: &mut R,
    ) -> Result<Vec<Isometry3<f64>>, ExecuteError> {
        let q = self
            .truth
            .joint_values_executed(&self.controller, cmd, rng)
            .map_err(|e| ExecuteError {
                cmd_deg: cmd.iter().map(|c| c.to_degrees()).collect(),
                reason: e.to_string(),
            })?;
        Ok(self.model.poses(&q).world_from_link)
    }

    fn last_link_from_tool(&self) -> Isometry3<f64> {
        self.model.last_link_from_tool
    }
}
