//! The trial function: one simulated campaign per (case, seed), reduced to named metrics.
//!
//! [`Trial`] is the pluggable part of the Monte-Carlo harness; [`CampaignTrial`] is the
//! real one: draw the truth robot, simulate the campaign on it, compare the nominal model's
//! prediction of the validation targets with their measurements.

use super::error::TrialError;
use super::file::SimMode;
use super::metrics::Metrics;
use super::resolve::{Case, ResolvedScenario, ResolvedTruth};
use super::validation_error::validation_errors;
use crate::campaign::{
    AnalyticArm, ArmExecutor, CampaignOutput, ValidationPlan, commands_to_internal, simulate_campaign,
};
use crate::kinematics::PhiModel;
use crate::robot::{Controller, RobotDescription, TruthRobot, perturb};
use rand::{SeedableRng, rngs::StdRng};

/// One Monte-Carlo trial: a pure function of the case and the seed (thread-safe, no I/O).
pub trait Trial: Sync {
    /// Names of the metrics every run returns, in order (the columns of `trials.csv`).
    fn metric_names(&self) -> Vec<String>;

    /// Runs the trial of `case` seeded with `seed`; the metrics follow
    /// [`Trial::metric_names`].
    fn run(&self, case: &Case, seed: u64) -> Result<Metrics, String>;
}

/// The metrics of [`CampaignTrial`], in column order.
pub const CAMPAIGN_METRICS: [&str; 6] = [
    "uncal_pos_rms_mm",
    "uncal_pos_max_mm",
    "uncal_orient_rms_rad",
    "uncal_orient_max_rad",
    "measurements",
    "occluded",
];

/// Simulates the scenario's campaign on a truth robot and measures the uncalibrated error.
///
/// Per trial: an rng seeded with the trial seed draws the truth robot (a fixed robot draws
/// nothing; a fleet draws [`perturb`]), then the campaign's repeatability jitter and
/// measurement noise, in that order.
#[derive(Clone, Debug)]
pub struct CampaignTrial {
    desc: RobotDescription,
    nominal: PhiModel,
    controller: Controller,
    truth: ResolvedTruth,
    validation: ValidationPlan,
    sim: SimMode,
}

impl CampaignTrial {
    /// The trial of `scenario`. Fails for `sim = "rapier"` until the rapier arm is wired in.
    pub fn new(scenario: &ResolvedScenario) -> Result<Self, String> {
        if scenario.sim == SimMode::Rapier {
            // Seam for the rapier arm: build it from the drawn truth in `run` (see
            // `run_on`), like `AnalyticArm`.
            return Err(
                "sim = \"rapier\" is not available yet in `axiscal run` (the rapier arm is not wired in)".into(),
            );
        }
        Ok(CampaignTrial {
            desc: scenario.robot.clone(),
            nominal: scenario.robot.nominal_model(),
            controller: Controller::from_description(&scenario.robot),
            truth: scenario.truth.clone(),
            validation: scenario.validation.clone(),
            sim: scenario.sim,
        })
    }

    fn draw_truth(&self, rng: &mut StdRng) -> Result<TruthRobot, String> {
        match &self.truth {
            ResolvedTruth::Fixed { robot } => Ok(robot.clone()),
            ResolvedTruth::Perturbed { perturbation } => {
                perturb(&self.desc, perturbation, rng).map_err(|e| format!("drawing the robot: {e}"))
            }
        }
    }

    /// Simulates the campaign of `case` on `arm` and reduces it to metrics.
    fn run_on<A: ArmExecutor>(&self, mut arm: A, case: &Case, rng: &mut StdRng) -> Result<Metrics, String> {
        let out = simulate_campaign(
            &self.desc,
            &case.plan,
            &self.validation,
            &mut arm,
            &case.measurement,
            rng,
        )
        .map_err(|e| format!("simulating the campaign: {e}"))?;
        Ok(self.metrics(&out))
    }

    fn metrics(&self, out: &CampaignOutput) -> Metrics {
        let targets = self.desc.tool_targets_m();
        let e = validation_errors(&out.rows, &targets, |cmd| {
            // Nominally the robot reaches exactly the commanded joint values (FORMATS.md 2).
            self.nominal.world_from_tool(&commands_to_internal(&self.desc, cmd))
        });
        let mut m = Metrics::new();
        m.push(CAMPAIGN_METRICS[0], e.pos_rms_mm);
        m.push(CAMPAIGN_METRICS[1], e.pos_max_mm);
        m.push(CAMPAIGN_METRICS[2], e.orient_rms_rad);
        m.push(CAMPAIGN_METRICS[3], e.orient_max_rad);
        m.push(CAMPAIGN_METRICS[4], out.rows.len() as f64);
        m.push(
            CAMPAIGN_METRICS[5],
            out.occluded.iter().map(|(_, n)| *n).sum::<usize>() as f64,
        );
        m
    }
}

impl Trial for CampaignTrial {
    fn metric_names(&self) -> Vec<String> {
        CAMPAIGN_METRICS.iter().map(|s| (*s).to_owned()).collect()
    }

    fn run(&self, case: &Case, seed: u64) -> Result<Metrics, String> {
        let mut rng = StdRng::seed_from_u64(seed);
        let truth = self.draw_truth(&mut rng)?;
        match self.sim {
            SimMode::Analytic => self.run_on(AnalyticArm::new(truth, self.controller.clone()), case, &mut rng),
            SimMode::Rapier => Err("the rapier arm is not wired in".into()),
        }
    }
}

/// Runs `trial` for unit `unit` of `scenario` (see [`ResolvedScenario::units`]) and checks its
/// metric names.
pub(crate) fn run_unit<T: Trial + ?Sized>(
    scenario: &ResolvedScenario,
    trial: &T,
    names: &[String],
    unit: usize,
) -> Result<super::metrics::TrialRecord, TrialError> {
    let (case, index) = (unit / scenario.trials, unit % scenario.trials);
    let seed = super::seed::trial_seed(scenario.seed, index);
    let err = |message: String| TrialError {
        case: scenario.cases[case].name.clone(),
        trial: index,
        seed,
        message,
    };
    let metrics = trial.run(&scenario.cases[case], seed).map_err(err)?;
    if metrics.names() != names {
        return Err(err(format!(
            "returned metrics {:?}, declared {names:?}",
            metrics.names()
        )));
    }
    Ok(super::metrics::TrialRecord {
        case,
        trial: index,
        seed,
        values: metrics.values(),
    })
}
