//! The ISO 9283 test a trial runs after its calibration (`[iso9283]` of a scenario): the cube
//! planned through the calibrated model (fig. 5) around the centre commands, its cycles
//! executed on the simulated robot and measured by the trial's instrument, the figures
//! evaluated ([`crate::iso9283::evaluate()`]) and predicted from the calibration's covariance,
//! the robot's repeatability (the description's) and the trial's instrument
//! ([`crate::iso9283::predict()`]). The
//! ratios of measured to predicted figures are what the prediction's honesty is judged by:
//! their mean over trials is 1 when the prediction is right.

use super::file::IsoSection;
use super::metrics::Metrics;
use crate::calibration::procedure::FittedModel;
use crate::compensation::Compensator;
use crate::iso9283::{CYCLE_ORDER, EvaluateOptions, PredictionInputs, evaluate, largest_cube, plan_cube, predict};
use crate::measurement::{MeasurementModel, MeasurementSet};
use crate::robot::RobotDescription;
use crate::sim::{ArmExecutor, CampaignOptions, PosePlan, simulate_poses};
use rand::{Rng, RngExt};

/// The metrics a trial with an `[iso9283]` section adds, in order: the cube's edge, the mean
/// over the five poses of `AP_P` and of `RP_l` (measured, predicted mean, and their ratio),
/// and `AD_P`, `RD_P` between `P2` and `P4`.
pub const ISO_METRICS: [&str; 9] = [
    "iso_edge_mm",
    "iso_ap_p_mm",
    "iso_ap_p_predicted_mm",
    "iso_ap_p_ratio",
    "iso_rp_l_mm",
    "iso_rp_l_predicted_mm",
    "iso_rp_l_ratio",
    "iso_ad_p_mm",
    "iso_rd_p_mm",
];

/// What the test needs of the trial.
pub struct IsoTrial<'a> {
    /// The section.
    pub section: &'a IsoSection,
    /// The nominal description.
    pub desc: &'a RobotDescription,
    /// The trial's instrument.
    pub instrument: &'a MeasurementModel,
    /// The trial's campaign options (conditions, instrument scale).
    pub options: &'a CampaignOptions,
    /// The plan's reference commands: the default centre.
    pub reference: &'a [f64],
}

/// Why an ISO 9283 trial failed (a failed record's `error` cell in `trials.csv`).
#[derive(Debug, thiserror::Error)]
pub enum IsoTrialError {
    /// The calibrated model gives no compensator.
    #[error("ISO cube: {0}")]
    Compensator(crate::compensation::CompensationError),
    /// No cube fits around the centre.
    #[error("ISO cube: {0}")]
    Cube(crate::iso9283::CubeError),
    /// The cycles' simulation failed.
    #[error("ISO cycles: {0}")]
    Cycles(crate::sim::CampaignError),
    /// The cycles' rows do not make a measurement set.
    #[error("ISO cycles: {0}")]
    CycleSet(crate::measurement::MeasurementSetError),
    /// The figures cannot be evaluated.
    #[error("ISO figures: {0}")]
    Figures(crate::iso9283::IsoError),
    /// The prediction needs the calibration's model covariance.
    #[error("ISO prediction: the calibration has no model covariance")]
    NoCovariance,
    /// The prediction failed.
    #[error("ISO prediction: {0}")]
    Prediction(crate::iso9283::PredictionError),
    /// A pose was run once only (`figures` or `prediction`), so it has no repeatability.
    #[error("ISO {0}: a pose has a single cycle")]
    SingleCycle(&'static str),
    /// The cycles give no distance between P2 and P4.
    #[error("ISO figures: no P2-P4 distance")]
    NoDistance,
}

impl IsoTrial<'_> {
    /// Runs the test on `arm` after calibration `fit` (with its model covariance), drawing
    /// from `rng`, and returns [`ISO_METRICS`].
    pub fn run<A: ArmExecutor, R: Rng + ?Sized>(
        &self,
        arm: &mut A,
        fit: &FittedModel,
        rng: &mut R,
    ) -> Result<Metrics, IsoTrialError> {
        let compensator = Compensator::new(&fit.robot, self.desc).map_err(IsoTrialError::Compensator)?;
        let centre = self.section.centre_cmd.as_deref().unwrap_or(self.reference);
        let cube = match self.section.edge_mm {
            Some(mm) => plan_cube(&compensator, self.desc, centre, mm * 1e-3),
            None => largest_cube(&compensator, self.desc, centre, 0.5),
        }
        .map_err(IsoTrialError::Cube)?;
        let poses: Vec<PosePlan> = (0..self.section.cycles)
            .flat_map(|cycle| {
                CYCLE_ORDER.map(|k| PosePlan {
                    experiment: format!("iso-P{k}"),
                    step: cycle,
                    cmd: cube.commands[k - 1].clone(),
                })
            })
            .collect();
        let out = simulate_poses(self.desc, &poses, arm, self.instrument, self.options, rng)
            .map_err(IsoTrialError::Cycles)?;
        let set = MeasurementSet::new(self.desc.dof(), out.rows).map_err(IsoTrialError::CycleSet)?;
        // Every simulated cycle counts, as in the prediction's: no screen for gross errors the
        // simulation does not make.
        let options = EvaluateOptions {
            register_base: false,
            keep_outliers: true,
            screen: false,
            unit_check: false,
        };
        let measured = evaluate(&set, &fit.robot, self.desc, options).map_err(IsoTrialError::Figures)?;
        let covariance = fit
            .model_covariance
            .as_ref()
            .ok_or(IsoTrialError::NoCovariance)?
            .matrix();
        let repeatability: Vec<f64> = self.desc.joints.iter().map(|j| j.repeatability_sigma).collect();
        let inputs = PredictionInputs {
            model: &fit.robot,
            covariance: &covariance,
            desc: self.desc,
            repeatability_rad_or_m: &repeatability,
            instrument: self.instrument,
        };
        let seed: u64 = rng.random();
        let predicted = predict(
            &inputs,
            &cube.commands,
            self.section.cycles,
            self.section.prediction_trials,
            seed,
        )
        .map_err(IsoTrialError::Prediction)?;
        let ap = measured.mean_ap_p_mm();
        let rp = measured.mean_rp_l_mm().ok_or(IsoTrialError::SingleCycle("figures"))?;
        let rp_predicted = predicted
            .mean_rp_l_mm
            .ok_or(IsoTrialError::SingleCycle("prediction"))?
            .mean;
        let distance = measured.distance_p2_p4.ok_or(IsoTrialError::NoDistance)?;
        let mut m = Metrics::new();
        m.push(ISO_METRICS[0], cube.edge_m * 1e3);
        m.push(ISO_METRICS[1], ap);
        m.push(ISO_METRICS[2], predicted.mean_ap_p_mm.mean);
        m.push(ISO_METRICS[3], ap / predicted.mean_ap_p_mm.mean);
        m.push(ISO_METRICS[4], rp);
        m.push(ISO_METRICS[5], rp_predicted);
        m.push(ISO_METRICS[6], rp / rp_predicted);
        m.push(ISO_METRICS[7], distance.ad_p_mm);
        m.push(ISO_METRICS[8], distance.rd_p_mm);
        Ok(m)
    }
}
