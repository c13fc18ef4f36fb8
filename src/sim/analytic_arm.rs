//! The analytic truth model as the campaign's simulated robot: commands through the fig. 3
//! controller into the truth's transmissions and couplings, then the actual phi-model, with
//! the unmodelled [`Effects`] that need no rigid bodies (compliance to first order).

use super::campaign::{ArmExecutor, ExecuteError};
use super::effects::Effects;
use super::joint_driver::JointDriver;
use crate::kinematics::FixedFrames;
use crate::physics::{LinkMass, PassiveSlope, coupled_first_order_deflection, with_simulated_load};
use crate::plan::PoseConditions;
use crate::robot::{Controller, RobotDescription, RobotModel};
use nalgebra::Isometry3;
use rand::Rng;

/// The analytic "real robot": exact kinematics, repeatability jitter, no bodies (so every
/// target is visible). Effects (see [`AnalyticArm::with_effects`]): backlash, thermal
/// expansion, gear harmonics and wobble exactly as [`RapierArm`](crate::sim::RapierArm);
/// compliance and payload by the first-order deflection through the passive couplings
/// ([`coupled_first_order_deflection`]) instead of the rigid-body static equilibrium.
#[derive(Clone, Debug)]
pub struct AnalyticArm {
    truth: RobotModel,
    /// The truth's phi-model with its constant frames (the poses of every step).
    frames: FixedFrames,
    driver: JointDriver,
    effects: Effects,
    masses: Vec<LinkMass>,
}

impl AnalyticArm {
    /// The truth robot driven by `controller` (built from the nominal description), no effects.
    pub fn new(truth: RobotModel, controller: Controller) -> Self {
        let frames = FixedFrames::new(truth.phi_model());
        let effects = Effects::default();
        AnalyticArm {
            driver: JointDriver::new(&truth, controller, &effects),
            truth,
            frames,
            effects,
            masses: Vec::new(),
        }
    }

    /// The same arm with unmodelled `effects`; the link masses for compliance are the
    /// effects' own, else `desc`'s ([`Effects::truth_link_masses`]; the truth model carries
    /// none).
    pub fn with_effects(self, effects: Effects, desc: &RobotDescription) -> Self {
        let controller = Controller::from_description(desc);
        AnalyticArm {
            driver: JointDriver::new(&self.truth, controller, &effects),
            masses: effects.truth_gravity_masses(desc),
            effects,
            ..self
        }
    }

    /// The same arm looking its truth's transmission inverses up in `table` first (built for
    /// this arm's driver: [`AnalyticArm::driver`]; call after [`AnalyticArm::with_effects`]).
    pub fn with_inversions(self, table: std::sync::Arc<super::joint_driver::InversionTable>) -> Self {
        AnalyticArm {
            driver: self.driver.with_table(table),
            ..self
        }
    }

    /// The driver of its joints.
    pub fn driver(&self) -> &JointDriver {
        &self.driver
    }

    /// The truth model.
    pub fn truth(&self) -> &RobotModel {
        &self.truth
    }

    /// The effects in force.
    pub fn effects(&self) -> &Effects {
        &self.effects
    }
}

impl ArmExecutor for AnalyticArm {
    fn execute<R: Rng + ?Sized>(
        &mut self,
        cmd: &[f64],
        conditions: &PoseConditions,
        rng: &mut R,
    ) -> Result<Vec<Isometry3<f64>>, ExecuteError> {
        let driven = self
            .driver
            .drive(cmd, rng)
            .map_err(|e| ExecuteError::new(self.frames.model(), cmd, e.to_string()))?;
        let mut q = driven.q;
        // Thermal expansion changes the rows with the pose's temperature; else the truth's
        // constant frames serve every pose.
        let expanded = self
            .effects
            .expanded_model(self.frames.model(), conditions.temperature_c);
        let frames = match expanded {
            Some(model) => &FixedFrames::new(model),
            None => &self.frames,
        };
        let model = frames.model();
        if let Some(compliance) = &self.effects.compliance
            && self.masses.len() == q.len()
        {
            let payload = self
                .effects
                .payload_in_last_link(&model.last_link_from_tool, conditions);
            let couplings = PassiveSlope::of_linkages(&self.truth, &driven.active);
            let dq = with_simulated_load(&self.masses, payload, compliance, &couplings, |load| {
                coupled_first_order_deflection(model, &q, load)
            });
            for (qk, d) in q.iter_mut().zip(dq) {
                *qk += d;
            }
        }
        let mut links = frames.world_from_links(&q);
        self.effects.apply_wobble(model, &q, &mut links);
        Ok(links)
    }

    fn last_link_from_tool(&self) -> Isometry3<f64> {
        self.frames.model().last_link_from_tool
    }
}
