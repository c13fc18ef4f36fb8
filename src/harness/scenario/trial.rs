//! The trial function: one simulated campaign per (case, seed), reduced to named metrics.
//!
//! [`Trial`] is the pluggable part of the Monte-Carlo harness; [`CampaignTrial`] is the
//! real one: draw the truth robot, simulate the campaign on it, calibrate, and compare the
//! nominal and the calibrated models' predictions of the validation targets with their
//! measurements.

use super::file::SimMode;
use super::iso::{ISO_METRICS, IsoTrial};
use super::metrics::Metrics;
use super::resolve::{Case, ResolvedScenario, ResolvedTruth};
use super::validation_error::validation_errors;
use crate::calibration::procedure::{CalibrationOptions, Detail, calibrate_model};
use crate::kinematics::FixedFrames;
use crate::measurement::{Measurement, MeasurementSet};
use crate::plan::{PoseConditions, TOOL_EXPERIMENT, VALIDATION_EXPERIMENT, ValidationPlan};
use crate::robot::commands_to_internal;
use crate::robot::{Controller, ModelError, RobotDescription, RobotModel};
use crate::sim::perturb;
use crate::sim::{AnalyticArm, ArmExecutor, CampaignOptions, Effects, InversionTable, simulate_campaign_with};
use crate::sim::{RapierArm, RapierArmOptions};
use nalgebra::{Isometry3, Vector3};
use rand::{SeedableRng, rngs::ChaCha12Rng};

/// Why a Monte-Carlo trial failed: its record's `error` cell in `trials.csv`, on one line.
#[derive(Debug, thiserror::Error)]
pub enum TrialError {
    /// The perturbed robot could not be built.
    #[error("drawing the robot: {0}")]
    DrawRobot(ModelError),
    /// The campaign's simulation failed.
    #[error("simulating the campaign: {0}")]
    Simulate(crate::sim::CampaignError),
    /// The simulated rows do not make a measurement set.
    #[error("measurement set: {0}")]
    Set(crate::measurement::MeasurementSetError),
    /// The instrument's noise at the robot's base cannot be computed.
    #[error("measurement noise at the robot: {0}")]
    Noise(crate::measurement::TriangulationError),
    /// The calibration failed.
    #[error("calibrating: {0}")]
    Calibrate(crate::calibration::procedure::ProcedureError),
    /// The calibrated model cannot invert a measured pose's commands.
    #[error("the calibrated model cannot predict {experiment} step {step}: {cause}")]
    Predict {
        /// The pose's experiment.
        experiment: String,
        /// The pose's step.
        step: usize,
        /// Why.
        cause: ModelError,
    },
    /// The truth model cannot reach a measured pose's commands.
    #[error("{experiment} step {step}: {cause}")]
    Truth {
        /// The pose's experiment.
        experiment: String,
        /// The pose's step.
        step: usize,
        /// Why.
        cause: ModelError,
    },
    /// The ISO 9283 part of the trial failed.
    #[error("{0}")]
    Iso(super::iso::IsoTrialError),
    /// The trial returned other metrics than it declared.
    #[error("returned metrics {returned:?}, declared {declared:?}")]
    MetricNames {
        /// The metrics' names returned.
        returned: Vec<String>,
        /// The names declared.
        declared: Vec<String>,
    },
    /// A metric is not finite.
    #[error("metric {metric} is {value} (not finite)")]
    NotFinite {
        /// The metric's name.
        metric: String,
        /// Its value.
        value: f64,
    },
}

/// One Monte-Carlo trial: a pure function of the case and the seed (thread-safe, no I/O).
pub trait Trial: Sync {
    /// Names of the metrics every run returns, in order (the columns of `trials.csv`).
    fn metric_names(&self) -> Vec<String>;

    /// Runs the trial of `case` seeded with `seed`; the metrics follow
    /// [`Trial::metric_names`].
    fn run(&self, case: &Case, seed: u64) -> Result<Metrics, TrialError>;
}

/// The metrics of [`CampaignTrial`], in column order. `uncal_*`: the nominal model's
/// prediction of the validation targets from the commands; `cal_*`: the calibrated model's
/// (through the same controller), i.e. what the fig. 5 compensation can achieve to first
/// order. `cal_tool_pos_rms_mm`: the calibrated model's tool point against the truth model's at
/// the validation poses' commands, without measurement noise, repeatability jitter or effects:
/// the calibration's own error, what `axiscal plan --optimize` predicts.
pub const CAMPAIGN_METRICS: [&str; 11] = [
    "uncal_pos_rms_mm",
    "uncal_pos_max_mm",
    "uncal_orient_rms_rad",
    "uncal_orient_max_rad",
    "cal_pos_rms_mm",
    "cal_pos_max_mm",
    "cal_orient_rms_rad",
    "cal_orient_max_rad",
    "measurements",
    "occluded",
    "cal_tool_pos_rms_mm",
];

/// The metrics a trial on the rapier arm in dynamic mode (a `compliance` effect) adds after
/// [`CAMPAIGN_METRICS`]: the static-equilibrium solves of its poses (`sim::SettleTally`),
/// mean and largest rapier steps per pose (the long-step approach included) and the largest
/// tool speed left at the end of a settle \[micrometre/s\].
pub const SETTLE_METRICS: [&str; 3] = ["settle_steps_mean", "settle_steps_max", "settle_speed_max_um_s"];

/// Simulates the scenario's campaign on a truth robot and measures the uncalibrated error.
///
/// Per trial: an rng seeded with the trial seed draws the truth robot (a fixed robot draws
/// nothing; a fleet draws [`perturb`]), then the campaign's repeatability jitter and
/// measurement noise, in that order.
#[derive(Clone, Debug)]
pub struct CampaignTrial {
    desc: RobotDescription,
    /// The nominal phi-model with its constant frames.
    nominal: FixedFrames,
    controller: Controller,
    truth: ResolvedTruth,
    validation: ValidationPlan,
    sim: SimMode,
    effects: Effects,
    options: CampaignOptions,
    occlusion: bool,
    /// The ISO 9283 test after each calibration, if any.
    iso: Option<super::file::IsoSection>,
    /// The predictions at the measured poses that every trial of a case shares, per distinct
    /// reference pose of the cases.
    fixed: Vec<PosePredictions>,
    /// A fixed truth's transmission inverses at the cases' planned commands, shared by the
    /// analytic arms of every trial ([`InversionTable`]).
    inversions: Option<std::sync::Arc<InversionTable>>,
}

/// What a trial predicts at the measured poses of a case that does not depend on the trial:
/// the nominal model's tool frame at each pose's commands and, for a fixed truth robot, the
/// truth's tool point (kinematics only), computed once instead of in every trial: the same
/// functions of the same commands, so the same numbers. A row is served from here only when
/// its commands are the ones computed for its pose (held-joint wander or a plan change falls
/// back to the computation).
#[derive(Clone, Debug)]
struct PosePredictions {
    /// The plan's reference commands (file units): which cases these are for.
    reference: Vec<f64>,
    /// Commands (file units) of the tool observation (index 0) and of validation step `s`
    /// (index `1 + s`).
    commands: Vec<Vec<f64>>,
    /// The nominal model's `world_from_tool` at each.
    nominal: Vec<Isometry3<f64>>,
    /// The fixed truth's tool point \[m\] at each (`None` where its transmissions cannot reach
    /// it); `None` when the truth is drawn per trial.
    truth_tool_m: Option<Vec<Option<Vector3<f64>>>>,
}

impl PosePredictions {
    /// The predictions of the poses at `reference` (file units).
    fn new(trial: &CampaignTrial, reference: &[f64]) -> Self {
        let commands: Vec<Vec<f64>> = std::iter::once(reference.to_vec())
            .chain(trial.validation.commands(&trial.desc, reference))
            .collect();
        let nominal = commands.iter().map(|cmd| trial.nominal_tool(cmd)).collect();
        let truth_tool_m = match &trial.truth {
            ResolvedTruth::Fixed { robot } => {
                let model = FixedFrames::new(robot.phi_model());
                Some(
                    commands
                        .iter()
                        .map(|cmd| trial.truth_tool_m(robot, &model, cmd).ok())
                        .collect(),
                )
            }
            ResolvedTruth::Perturbed { .. } => None,
        };
        PosePredictions {
            reference: reference.to_vec(),
            commands,
            nominal,
            truth_tool_m,
        }
    }

    /// The index of `row`'s pose, if it is one of these with these commands.
    fn index(&self, row: &Measurement) -> Option<usize> {
        let i = match row.experiment.as_str() {
            TOOL_EXPERIMENT if row.step == 0 => 0,
            VALIDATION_EXPERIMENT => 1 + row.step,
            _ => return None,
        };
        (self.commands.get(i)? == &row.cmd).then_some(i)
    }

    /// The nominal tool frame of `row`'s pose, if known.
    fn nominal(&self, row: &Measurement) -> Option<Isometry3<f64>> {
        self.index(row).map(|i| self.nominal[i])
    }

    /// The fixed truth's tool point of `row`'s pose, if known and reachable.
    fn truth_tool_m(&self, row: &Measurement) -> Option<Vector3<f64>> {
        self.truth_tool_m.as_ref()?[self.index(row)?]
    }
}

impl CampaignTrial {
    /// The trial of `scenario` (analytic or rapier arm, as its `sim` key says).
    pub fn new(scenario: &ResolvedScenario) -> Self {
        let mut trial = CampaignTrial {
            desc: scenario.robot.clone(),
            nominal: FixedFrames::new(scenario.robot.nominal_model()),
            controller: Controller::from_description(&scenario.robot),
            truth: scenario.truth.clone(),
            validation: scenario.validation.clone(),
            sim: scenario.sim,
            effects: scenario.effects.clone(),
            options: CampaignOptions {
                conditions: PoseConditions {
                    payload_kg: scenario.conditions.payload_kg,
                    temperature_c: scenario.conditions.temperature_c,
                },
                instrument_scale: scenario.effects.instrument_scale,
            },
            occlusion: scenario.occlusion,
            iso: scenario.iso9283.clone(),
            fixed: Vec::new(),
            inversions: None,
        };
        for case in &scenario.cases {
            let reference = &case.plan.reference;
            if reference.len() == trial.desc.dof() && trial.fixed_for(reference).is_none() {
                let fixed = PosePredictions::new(&trial, reference);
                trial.fixed.push(fixed);
            }
        }
        trial.inversions = trial.inversion_table(scenario).map(std::sync::Arc::new);
        trial
    }

    /// The analytic arm of `truth` with the trial's controller and effects.
    fn analytic_arm(&self, truth: RobotModel) -> AnalyticArm {
        AnalyticArm::new(truth, self.controller.clone()).with_effects(self.effects.clone(), &self.desc)
    }

    /// For a fixed truth on the analytic arm: its transmission inverses at every planned
    /// command of the scenario's cases (axis sweeps, tool and validation poses).
    fn inversion_table(&self, scenario: &ResolvedScenario) -> Option<InversionTable> {
        let (SimMode::Analytic, ResolvedTruth::Fixed { robot }) = (self.sim, &self.truth) else {
            return None;
        };
        let mut commands: Vec<Vec<f64>> = Vec::new();
        for case in scenario.cases.iter().filter(|c| c.plan.validate(&self.desc).is_ok()) {
            let plan = &case.plan;
            for sweep in &plan.sweeps {
                commands.extend((0..sweep.poses()).map(|step| plan.commands(&self.desc, sweep, step)));
            }
        }
        commands.extend(self.fixed.iter().flat_map(|f| f.commands.iter().cloned()));
        let internal: Vec<Vec<f64>> = commands.iter().map(|c| commands_to_internal(&self.desc, c)).collect();
        let arm = self.analytic_arm(robot.as_ref().clone());
        Some(InversionTable::new(arm.driver(), internal.iter().map(Vec::as_slice)))
    }

    /// The trial-independent predictions of the cases with this reference pose.
    fn fixed_for(&self, reference: &[f64]) -> Option<&PosePredictions> {
        self.fixed.iter().find(|f| f.reference == reference)
    }

    /// The nominal model's tool frame at file-unit commands `cmd`: nominally the robot
    /// reaches exactly the commanded joint values (`docs/formats.md#controller-semantics`).
    fn nominal_tool(&self, cmd: &[f64]) -> Isometry3<f64> {
        self.nominal.world_from_tool(&commands_to_internal(&self.desc, cmd))
    }

    /// The tool point \[m\] of `truth` (its constant frames: `model`) at file-unit commands
    /// `cmd` through the controller (kinematics only).
    fn truth_tool_m(&self, truth: &RobotModel, model: &FixedFrames, cmd: &[f64]) -> Result<Vector3<f64>, ModelError> {
        let q = truth.joint_values(&self.controller, &commands_to_internal(&self.desc, cmd))?;
        Ok(model.world_from_tool(&q).translation.vector)
    }

    /// Whether the trial runs the rapier arm in dynamic mode (it then reports
    /// [`SETTLE_METRICS`]).
    fn settles(&self) -> bool {
        self.sim == SimMode::Rapier && self.effects.compliance.is_some()
    }

    fn draw_truth(&self, rng: &mut ChaCha12Rng) -> Result<RobotModel, TrialError> {
        match &self.truth {
            ResolvedTruth::Fixed { robot } => Ok(robot.as_ref().clone()),
            ResolvedTruth::Perturbed { perturbation } => {
                perturb(&self.desc, perturbation, rng).map_err(TrialError::DrawRobot)
            }
        }
    }

    /// Simulates the campaign of `case` on `arm` and reduces it to metrics.
    fn run_on<A: ArmExecutor>(
        &self,
        mut arm: A,
        case: &Case,
        rng: &mut ChaCha12Rng,
        truth: &RobotModel,
    ) -> Result<Metrics, TrialError> {
        let out = simulate_campaign_with(
            &self.desc,
            &case.plan,
            &self.validation,
            &mut arm,
            &case.measurement,
            &self.options,
            rng,
        )
        .map_err(TrialError::Simulate)?;
        let settles = arm.settles();
        let occluded: usize = out.occluded.iter().map(|(_, n)| *n).sum();
        let set = MeasurementSet::new(self.desc.dof(), out.rows).map_err(TrialError::Set)?;
        // The calibrator is told the instrument's 3-D RMS noise where the robot stands.
        let base = nalgebra::Point3::from(self.desc.placement.to_isometry().translation.vector);
        let noise_mm = case
            .measurement
            .covariance_m2(&base)
            .map_err(TrialError::Noise)?
            .trace()
            .sqrt()
            * 1e3;
        let options = CalibrationOptions {
            noise_rms_3d_mm: noise_mm,
            ..CalibrationOptions::default()
        };
        // The lean path: a trial needs the model, not the report (and its covariance for an
        // ISO prediction).
        let detail = if self.iso.is_some() {
            Detail::ModelCovariance
        } else {
            Detail::Model
        };
        let cal = calibrate_model(&set, &self.desc, &options, detail).map_err(TrialError::Calibrate)?;
        let predicted = self.predicted_tool(set.rows(), &cal.robot)?;
        let fixed = self.fixed_for(&case.plan.reference);
        let mut m = self.metrics(set.rows(), occluded, &predicted, fixed);
        m.push(CAMPAIGN_METRICS[10], self.tool_error_rms_mm(&predicted, truth, fixed)?);
        if let Some(t) = settles {
            m.push(SETTLE_METRICS[0], t.mean_steps());
            m.push(SETTLE_METRICS[1], t.max_steps as f64);
            m.push(SETTLE_METRICS[2], t.max_speed_m_s * 1e6);
        }
        if let Some(section) = &self.iso {
            let iso = IsoTrial {
                section,
                desc: &self.desc,
                instrument: &case.measurement,
                options: &self.options,
                reference: &case.plan.reference,
            };
            m.extend(iso.run(&mut arm, &cal, rng).map_err(TrialError::Iso)?);
        }
        Ok(m)
    }

    /// The calibrated model's tool frame at each measured pose ([`measured_poses`]: once per
    /// pose, not per target row), with the pose's first row; a command the calibrated
    /// transmissions cannot invert fails the trial, naming the pose.
    fn predicted_tool<'r>(
        &self,
        rows: &'r [Measurement],
        calibrated: &RobotModel,
    ) -> Result<Vec<(&'r Measurement, Isometry3<f64>)>, TrialError> {
        let model = FixedFrames::new(calibrated.phi_model());
        measured_poses(rows)
            .map(|row| {
                let q = calibrated
                    .joint_values(&self.controller, &commands_to_internal(&self.desc, &row.cmd))
                    .map_err(|cause| TrialError::Predict {
                        experiment: row.experiment.clone(),
                        step: row.step,
                        cause,
                    })?;
                Ok((row, model.world_from_tool(&q)))
            })
            .collect()
    }

    /// RMS over the measured poses of the distance between the calibrated model's tool
    /// points (`predicted`, [`CampaignTrial::predicted_tool`]) and the truth model's at the
    /// same commands \[mm\] (kinematics only); a fixed truth's points from `fixed`.
    fn tool_error_rms_mm(
        &self,
        predicted: &[(&Measurement, Isometry3<f64>)],
        truth: &RobotModel,
        fixed: Option<&PosePredictions>,
    ) -> Result<f64, TrialError> {
        let mut truth_model = None;
        let mut sum_m2 = 0.0;
        for (row, world_from_tool) in predicted {
            let at = |cause| TrialError::Truth {
                experiment: row.experiment.clone(),
                step: row.step,
                cause,
            };
            let truth_m = match fixed.and_then(|f| f.truth_tool_m(row)) {
                Some(known) => known,
                // Drawn per trial, or a fixed truth that cannot reach the pose (computed again
                // for the reason).
                None => {
                    let model = truth_model.get_or_insert_with(|| FixedFrames::new(truth.phi_model()));
                    self.truth_tool_m(truth, model, &row.cmd).map_err(at)?
                }
            };
            let d = world_from_tool.translation.vector - truth_m;
            sum_m2 += d.norm_squared();
        }
        // No pose measured (all occluded): no number, as `validation_errors` gives.
        Ok(if predicted.is_empty() {
            f64::NAN
        } else {
            (sum_m2 / predicted.len() as f64).sqrt() * 1e3
        })
    }

    /// The validation errors of the nominal model and of the calibrated one (its tool frame
    /// at each measured pose: `predicted`) over the campaign's `rows`, with the number of
    /// `occluded` targets (the nominal tool frames from `fixed` where it has them).
    fn metrics(
        &self,
        rows: &[Measurement],
        occluded: usize,
        predicted: &[(&Measurement, Isometry3<f64>)],
        fixed: Option<&PosePredictions>,
    ) -> Metrics {
        let targets = self.desc.tool_targets_m();
        let e = validation_errors(rows, &targets, |row| {
            fixed
                .and_then(|f| f.nominal(row))
                .unwrap_or_else(|| self.nominal_tool(&row.cmd))
        });
        // The prediction made from this very row, else from one with the same commands (the
        // same number: a function of the commands).
        let c = validation_errors(rows, &targets, |row| {
            predicted
                .iter()
                .find(|(r, _)| std::ptr::eq(*r, row))
                .or_else(|| predicted.iter().find(|(r, _)| r.cmd == row.cmd))
                .map_or(Isometry3::translation(f64::NAN, f64::NAN, f64::NAN), |p| p.1)
        });
        let mut m = Metrics::new();
        m.push(CAMPAIGN_METRICS[0], e.pos_rms_mm);
        m.push(CAMPAIGN_METRICS[1], e.pos_max_mm);
        m.push(CAMPAIGN_METRICS[2], e.orient_rms_rad);
        m.push(CAMPAIGN_METRICS[3], e.orient_max_rad);
        m.push(CAMPAIGN_METRICS[4], c.pos_rms_mm);
        m.push(CAMPAIGN_METRICS[5], c.pos_max_mm);
        m.push(CAMPAIGN_METRICS[6], c.orient_rms_rad);
        m.push(CAMPAIGN_METRICS[7], c.orient_max_rad);
        m.push(CAMPAIGN_METRICS[8], rows.len() as f64);
        m.push(CAMPAIGN_METRICS[9], occluded as f64);
        m
    }
}

/// The first row of each measured pose with no moved joint (the validation poses and the tool
/// observation), in file order: a pose's targets are consecutive rows of one step.
fn measured_poses(rows: &[Measurement]) -> impl Iterator<Item = &Measurement> {
    let mut last: Option<(&str, usize)> = None;
    rows.iter().filter(|r| r.moved_joint == 0).filter(move |r| {
        let pose = Some((r.experiment.as_str(), r.step));
        let first = last != pose;
        last = pose;
        first
    })
}

impl Trial for CampaignTrial {
    fn metric_names(&self) -> Vec<String> {
        let settle: &[&str] = if self.settles() { &SETTLE_METRICS } else { &[] };
        let iso: &[&str] = if self.iso.is_some() { &ISO_METRICS } else { &[] };
        CAMPAIGN_METRICS
            .iter()
            .chain(settle)
            .chain(iso)
            .map(|s| (*s).to_owned())
            .collect()
    }

    fn run(&self, case: &Case, seed: u64) -> Result<Metrics, TrialError> {
        let mut rng = ChaCha12Rng::seed_from_u64(seed);
        let truth = self.draw_truth(&mut rng)?;
        let kinematic_truth = truth.clone();
        match self.sim {
            SimMode::Analytic => {
                let arm = match &self.inversions {
                    Some(table) => self.analytic_arm(truth).with_inversions(table.clone()),
                    None => self.analytic_arm(truth),
                };
                self.run_on(arm, case, &mut rng, &kinematic_truth)
            }
            SimMode::Rapier => {
                let options = RapierArmOptions {
                    stations_m: if self.occlusion {
                        case.measurement.stations_m()
                    } else {
                        vec![]
                    },
                    ..RapierArmOptions::new(self.desc.dof())
                };
                self.run_on(
                    RapierArm::new(truth, &self.desc, self.effects.clone(), options),
                    case,
                    &mut rng,
                    &kinematic_truth,
                )
            }
        }
    }
}

/// Runs `trial` for unit `unit` of `scenario` (see [`ResolvedScenario::units`]). A trial
/// that fails, returns other metric names than declared or a value that is not finite becomes
/// a failed record: its error, on one line, instead of its values.
pub(crate) fn run_unit<T: Trial + ?Sized>(
    scenario: &ResolvedScenario,
    trial: &T,
    names: &[String],
    unit: usize,
) -> super::metrics::TrialRecord {
    let (case, index) = (unit / scenario.trials, unit % scenario.trials);
    let seed = super::seed::trial_seed(scenario.seed, index);
    let outcome = trial.run(&scenario.cases[case], seed).and_then(|metrics| {
        if metrics.names() != names {
            return Err(TrialError::MetricNames {
                returned: metrics.names(),
                declared: names.to_vec(),
            });
        }
        let values = metrics.values();
        match values.iter().position(|v| !v.is_finite()) {
            Some(i) => Err(TrialError::NotFinite {
                metric: names[i].clone(),
                value: values[i],
            }),
            None => Ok(values),
        }
    });
    let (values, error) = match outcome {
        Ok(values) => (values, None),
        Err(e) => (Vec::new(), Some(one_line(&e.to_string()))),
    };
    super::metrics::TrialRecord {
        case,
        trial: index,
        seed,
        values,
        error,
    }
}

/// `message` on one line (a trials.csv cell): line breaks folded into `; `.
fn one_line(message: &str) -> String {
    message
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measured_poses_gives_each_pose_with_no_moved_joint_once() {
        let at_rest = Measurement {
            experiment: String::new(),
            moved_joint: 0,
            step: 0,
            target: 0,
            position_mm: [0.0; 3],
            cmd: Vec::new(),
            payload_kg: 0.0,
            temperature_c: 20.0,
        };
        let row = |experiment: &str, moved_joint, step, target| Measurement {
            experiment: experiment.into(),
            moved_joint,
            step,
            target,
            ..at_rest.clone()
        };
        let rows = [
            row("j1", 1, 0, 0),
            row("tool", 0, 0, 0),
            row("tool", 0, 0, 1),
            row("validation", 0, 0, 0),
            row("validation", 0, 0, 2),
            row("validation", 0, 1, 1),
            row("j2", 2, 1, 0),
            row("validation", 0, 2, 0),
        ];
        let poses: Vec<(&str, usize)> = measured_poses(&rows).map(|r| (r.experiment.as_str(), r.step)).collect();
        assert_eq!(
            poses,
            [("tool", 0), ("validation", 0), ("validation", 1), ("validation", 2)]
        );
        assert_eq!(measured_poses(&rows[..1]).count(), 0);
    }
}
