//! Running a campaign on a simulated robot: the axis experiments of a [`CalibrationPlan`] and
//! the validation poses, each target measured by an instrument, to measurement rows
//! (`docs/formats.md#measurement-csv`).

use crate::kinematics::{JointKind, PhiModel};
use crate::measurement::{Measurement, MeasurementModel, TriangulationError};
use crate::physics::InstrumentScale;
use crate::plan::{CalibrationPlan, PlanError, PoseConditions, TOOL_EXPERIMENT, ValidationPlan};
use crate::robot::RobotDescription;
use crate::robot::commands_to_internal;
use nalgebra::{Isometry3, Point3};
use rand::Rng;

/// The simulated "real robot": executes joint commands and says where its links are.
/// Implemented by the analytic truth model and by the rapier arm; the campaign never sees more.
pub trait ArmExecutor {
    /// Drives the arm to `cmd` (internal units: rad, m), under `conditions`, and returns
    /// `world_from_link` for every link (index `k` = link `k + 1`). Repeatability noise, if
    /// any, is drawn from `rng`.
    fn execute<R: Rng + ?Sized>(
        &mut self,
        cmd: &[f64],
        conditions: &PoseConditions,
        rng: &mut R,
    ) -> Result<Vec<Isometry3<f64>>, ExecuteError>;

    /// Whether the target at `point_m` (world) is seen by every station at the last executed
    /// configuration. The analytic model has no bodies and sees everything.
    fn visible(&self, _point_m: &Point3<f64>) -> bool {
        true
    }

    /// The tool frame in the last link's moving frame.
    fn last_link_from_tool(&self) -> Isometry3<f64>;

    /// The static-equilibrium solves of the poses executed so far, for an arm that settles
    /// each pose by time stepping (the rapier arm in dynamic mode); `None` for one that does
    /// not.
    fn settles(&self) -> Option<crate::sim::SettleTally> {
        None
    }
}

/// The simulated robot could not execute a command.
#[derive(Debug, thiserror::Error)]
#[error("executing commands {cmd_file:?} (deg or mm): {reason}")]
pub struct ExecuteError {
    /// The commands in file units (deg for a revolute joint, mm for a sliding one).
    pub cmd_file: Vec<f64>,
    /// Why.
    pub reason: String,
}

impl ExecuteError {
    /// The error of internal-unit commands `cmd` of `model`'s joints (rad or m).
    pub fn new(model: &PhiModel, cmd: &[f64], reason: String) -> Self {
        let cmd_file = cmd
            .iter()
            .zip(&model.joints)
            .map(|(c, j)| match j.kind {
                JointKind::Revolute => c.to_degrees(),
                JointKind::Prismatic => c * 1e3,
            })
            .collect();
        ExecuteError { cmd_file, reason }
    }
}

/// What a campaign produced.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CampaignOutput {
    /// Measured targets in the order they were observed (rows of `docs/formats.md#measurement-csv`).
    pub rows: Vec<Measurement>,
    /// Targets that were hidden from a station and so not measured, per experiment id.
    pub occluded: Vec<(String, usize)>,
}

/// A campaign could not be simulated.
#[derive(Debug, thiserror::Error)]
pub enum CampaignError {
    /// The plan does not fit the robot.
    #[error("plan: {0}")]
    Plan(PlanError),
    /// The robot could not execute a command.
    #[error(transparent)]
    Execute(#[from] ExecuteError),
    /// The instrument could not measure a target.
    #[error("measuring {experiment} step {step} target {target}: {cause}")]
    Measure {
        /// Experiment id.
        experiment: String,
        /// Step.
        step: usize,
        /// Target.
        target: usize,
        /// Why.
        cause: TriangulationError,
    },
}

/// Campaign-wide settings beyond the plan.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CampaignOptions {
    /// Conditions of every pose (payload, temperature).
    pub conditions: PoseConditions,
    /// The instrument's scale error, if any: measured coordinates are scaled about the
    /// instrument origin after the measurement noise.
    pub instrument_scale: Option<InstrumentScale>,
}

/// Runs the axis experiments of `plan` then the validation poses on `arm`, measuring with
/// `instrument`, every pose under default conditions. Deterministic for a given `rng` state.
pub fn simulate_campaign<A: ArmExecutor, R: Rng + ?Sized>(
    desc: &RobotDescription,
    plan: &CalibrationPlan,
    validation: &ValidationPlan,
    arm: &mut A,
    instrument: &MeasurementModel,
    rng: &mut R,
) -> Result<CampaignOutput, CampaignError> {
    simulate_campaign_with(
        desc,
        plan,
        validation,
        arm,
        instrument,
        &CampaignOptions::default(),
        rng,
    )
}

/// [`simulate_campaign`] with explicit pose conditions and instrument scale error.
pub fn simulate_campaign_with<A: ArmExecutor, R: Rng + ?Sized>(
    desc: &RobotDescription,
    plan: &CalibrationPlan,
    validation: &ValidationPlan,
    arm: &mut A,
    instrument: &MeasurementModel,
    options: &CampaignOptions,
    rng: &mut R,
) -> Result<CampaignOutput, CampaignError> {
    plan.validate(desc)?;
    let validation_commands = validation.commands(desc, &plan.reference);
    let tool_targets = desc.tool_targets_m().len();
    let mut out = CampaignOutput::default();
    // Every target of every pose, the occluded ones included: the rows' room, reserved once.
    let sweep_rows: usize = plan
        .sweeps
        .iter()
        .map(|s| s.poses() * (1 + usize::from(s.second_target)))
        .sum();
    out.rows
        .reserve(sweep_rows + tool_targets * (1 + validation_commands.len()));
    let conditions = options.conditions;
    let instrument = Instrument {
        model: instrument,
        scale: options.instrument_scale,
    };
    for (sweep, experiment) in plan.sweeps.iter().zip(plan.experiment_names()) {
        let targets = desc
            .axis_targets_of(sweep.joint)
            .expect("validated plan: every swept joint has targets");
        let mut observed = vec![(0, targets.target0)];
        if sweep.second_target {
            observed.push((1, targets.target1.expect("validated plan: second target given")));
        }
        for step in 0..sweep.poses() {
            let mut cmd = plan.commands(desc, sweep, step);
            if let Some(range) = plan.held_jitter {
                wander_held(&mut cmd, sweep.joint, range, rng);
            }
            let links = arm.execute(&commands_to_internal(desc, &cmd), &conditions, rng)?;
            for (id, t) in &observed {
                let p = links[t.link - 1] * t.position_m();
                record(
                    &mut out,
                    arm,
                    &instrument,
                    rng,
                    &experiment,
                    sweep.joint,
                    step,
                    *id,
                    p,
                    &cmd,
                    conditions,
                )?;
            }
        }
    }
    // The three tool targets at the reference pose: the calibrator's tool frame.
    observe_tool(
        &mut out,
        desc,
        arm,
        &instrument,
        rng,
        TOOL_EXPERIMENT,
        0,
        &plan.reference,
        conditions,
    )?;
    for (step, cmd) in validation_commands.into_iter().enumerate() {
        observe_tool(
            &mut out,
            desc,
            arm,
            &instrument,
            rng,
            "validation",
            step,
            &cmd,
            conditions,
        )?;
    }
    Ok(out)
}

/// A pose to execute and measure at: its experiment, step and commands (file units).
#[derive(Clone, Debug, PartialEq)]
pub struct PosePlan {
    /// Experiment name of its rows (`moved_joint` 0).
    pub experiment: String,
    /// Step of its rows.
    pub step: usize,
    /// Commands \[deg or mm\].
    pub cmd: Vec<f64>,
}

/// Executes each of `poses` in order on `arm` and measures the description's tool targets at
/// each (as the validation poses of [`simulate_campaign_with`]): e.g. the cycles of an ISO 9283
/// test after a calibration.
pub fn simulate_poses<A: ArmExecutor, R: Rng + ?Sized>(
    desc: &RobotDescription,
    poses: &[PosePlan],
    arm: &mut A,
    instrument: &MeasurementModel,
    options: &CampaignOptions,
    rng: &mut R,
) -> Result<CampaignOutput, CampaignError> {
    let mut out = CampaignOutput::default();
    out.rows.reserve(poses.len() * desc.tool_targets_m().len());
    let instrument = Instrument {
        model: instrument,
        scale: options.instrument_scale,
    };
    for p in poses {
        observe_tool(
            &mut out,
            desc,
            arm,
            &instrument,
            rng,
            &p.experiment,
            p.step,
            &p.cmd,
            options.conditions,
        )?;
    }
    Ok(out)
}

/// The held joints' recorded values (every joint but `joint`) moved by a uniform `|x|` in
/// `[min, max]` with a random sign each (file units): the robot stands where its encoders say.
fn wander_held<R: Rng + ?Sized>(cmd: &mut [f64], joint: usize, [min, max]: [f64; 2], rng: &mut R) {
    use rand::RngExt;
    for (j, c) in cmd.iter_mut().enumerate() {
        if j + 1 != joint {
            let size = if max > min { rng.random_range(min..=max) } else { min };
            *c += if rng.random_bool(0.5) { size } else { -size };
        }
    }
}

/// Executes `cmd` and observes the three tool targets (a `moved_joint = 0` experiment).
#[allow(clippy::too_many_arguments)]
fn observe_tool<A: ArmExecutor, R: Rng + ?Sized>(
    out: &mut CampaignOutput,
    desc: &RobotDescription,
    arm: &mut A,
    instrument: &Instrument<'_>,
    rng: &mut R,
    experiment: &str,
    step: usize,
    cmd: &[f64],
    conditions: PoseConditions,
) -> Result<(), CampaignError> {
    let links = arm.execute(&commands_to_internal(desc, cmd), &conditions, rng)?;
    let world_from_tool = links[desc.dof() - 1] * arm.last_link_from_tool();
    for (id, t) in desc.tool_targets_m().iter().enumerate() {
        record(
            out,
            arm,
            instrument,
            rng,
            experiment,
            0,
            step,
            id,
            world_from_tool * t,
            cmd,
            conditions,
        )?;
    }
    Ok(())
}

/// The measurement model with its (optional) scale error.
struct Instrument<'a> {
    model: &'a MeasurementModel,
    scale: Option<InstrumentScale>,
}

#[allow(clippy::too_many_arguments)]
fn record<A: ArmExecutor, R: Rng + ?Sized>(
    out: &mut CampaignOutput,
    arm: &A,
    instrument: &Instrument<'_>,
    rng: &mut R,
    experiment: &str,
    moved_joint: usize,
    step: usize,
    target: usize,
    point_m: Point3<f64>,
    cmd: &[f64],
    conditions: PoseConditions,
) -> Result<(), CampaignError> {
    if !arm.visible(&point_m) {
        match out.occluded.iter_mut().find(|(e, _)| e == experiment) {
            Some((_, n)) => *n += 1,
            None => out.occluded.push((experiment.to_owned(), 1)),
        }
        return Ok(());
    }
    let m = instrument
        .model
        .measure(&point_m, rng)
        .map_err(|source| CampaignError::Measure {
            experiment: experiment.to_owned(),
            step,
            target,
            cause: source,
        })?;
    let m = instrument.scale.map_or(m, |s| s.applied_to(&m)) * 1e3;
    out.rows.push(Measurement {
        experiment: experiment.to_owned(),
        moved_joint,
        step,
        target,
        position_mm: [m.x, m.y, m.z],
        cmd: cmd.to_vec(),
        payload_kg: conditions.payload_kg,
        temperature_c: conditions.temperature_c,
    });
    Ok(())
}

impl From<PlanError> for CampaignError {
    fn from(e: PlanError) -> Self {
        Self::Plan(e)
    }
}
