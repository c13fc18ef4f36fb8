//! `--record FILE.rrd` of `axiscal simulate`: replays the simulated campaign into a rerun
//! recording. The robot is drawn as the truth model reaches each command (without
//! repeatability jitter); targets and errors are the measured rows.

use super::{ERROR_EXAGGERATION, log_arc_fits};
use anyhow::{Context, Result};
use axiscal::kinematics::{JointKind, PhiModel};
use axiscal::measurement::{MeasurementModel, MeasurementSet};
use axiscal::plan::CalibrationPlan;
use axiscal::robot::commands_to_internal;
use axiscal::robot::{Controller, RobotDescription, RobotModel};
use axiscal::viz::{Recorder, four_bar_loop_m};
use nalgebra::Point3;

/// What the recording is made of.
pub struct Campaign<'a> {
    /// Nominal description (controller, plan, nominal model for the validation errors).
    pub desc: &'a RobotDescription,
    /// The simulated robot.
    pub truth: &'a RobotModel,
    /// The axis experiments.
    pub plan: &'a CalibrationPlan,
    /// The measured rows.
    pub set: &'a MeasurementSet,
    /// The instrument (its covariance weights the arc fits).
    pub instrument: &'a MeasurementModel,
}

/// Logs the robot (and its four-bars) as the truth reaches `cmd` (file units).
fn log_pose(rec: &Recorder, c: &Campaign, model: &PhiModel, controller: &Controller, cmd: &[f64]) -> Result<()> {
    let cmd = commands_to_internal(c.desc, cmd);
    let q = c.truth.joint_values(controller, &cmd)?;
    rec.log_robot(model, &q);
    if !c.truth.four_bars.is_empty() {
        let theta = c.truth.active_displacements(&controller.decouple(&cmd)?)?;
        let poses = model.poses(&q);
        for fb in &c.truth.four_bars {
            let k = fb.from - 1;
            let (Some(frame), Some(next), Ok(passive)) = (
                poses.world_from_frame.get(k),
                poses.world_from_frame.get(k + 1),
                fb.geometry.passive(theta[k]),
            ) else {
                continue;
            };
            let points = four_bar_loop_m(&fb.geometry, frame, &(next * Point3::origin()), theta[k], passive);
            rec.log_four_bar(&points);
        }
    }
    Ok(())
}

/// The recording of campaign `c`, as the bytes of an `.rrd` file.
pub fn write(c: &Campaign) -> Result<Vec<u8>> {
    let rec = Recorder::new("axiscal")?;
    rec.send_default_blueprint();
    let model = c.truth.phi_model();
    let nominal = c.desc.nominal_model();
    let controller = Controller::from_description(c.desc);
    rec.set_trial(0);
    let mut tick: i64 = 0;
    for sweep in &c.plan.sweeps {
        let name = format!("axis{}", sweep.joint);
        let Some(experiment) = c.set.experiment(&name) else {
            continue;
        };
        let by_step = experiment.by_step();
        let mut seen: Vec<Point3<f64>> = Vec::new();
        for (step, rows) in &by_step {
            rec.set_step(tick);
            log_pose(&rec, c, &model, &controller, &rows[0].cmd)
                .with_context(|| format!("replaying {name} step {step}"))?;
            seen.extend(rows.iter().map(|r| r.position_m()));
            rec.log_targets(&name, &seen);
            tick += 1;
        }
        if c.desc.joints[sweep.joint - 1].kind == JointKind::Revolute {
            let covariance = |p: &Point3<f64>| Ok(c.instrument.covariance_m2(p)?);
            log_arc_fits(&rec, &covariance, &name, sweep.joint, &experiment.by_step_target());
        }
    }
    if let Some(validation) = c.set.experiment("validation") {
        let targets = c.desc.tool_targets_m();
        let mut predicted = Vec::new();
        let mut measured = Vec::new();
        let mut poses = Vec::new();
        for rows in validation.by_step().values() {
            let q = commands_to_internal(c.desc, &rows[0].cmd);
            let world_from_tool = nominal.world_from_tool(&q);
            let errors: Vec<f64> = rows
                .iter()
                // A row naming a tool target the description lacks has nothing to compare to.
                .filter_map(|r| Some((r, targets.get(r.target)?)))
                .map(|(r, t)| {
                    let p = world_from_tool * t;
                    predicted.push(p);
                    measured.push(r.position_m());
                    (r.position_m() - p).norm()
                })
                .collect();
            poses.push((rows[0].cmd.clone(), errors));
        }
        let full_scale_m = predicted
            .iter()
            .zip(&measured)
            .map(|(p, m)| (m - p).norm())
            .fold(0.0, f64::max);
        let mut shown = 0;
        let mut sum_sq = 0.0;
        for (cmd, errors) in &poses {
            rec.set_step(tick);
            log_pose(&rec, c, &model, &controller, cmd).context("replaying a validation pose")?;
            shown += errors.len();
            let (from, to) = (&predicted[..shown], &measured[..shown]);
            rec.log_error_vectors("validation", from, to, full_scale_m, 1.0)?;
            rec.log_error_vectors(
                &format!("validation_x{ERROR_EXAGGERATION}"),
                from,
                to,
                full_scale_m,
                ERROR_EXAGGERATION,
            )?;
            for e in errors {
                sum_sq += e * e;
            }
            let worst = errors.iter().copied().fold(0.0, f64::max);
            rec.log_scalar("validation/nominal_error_max_mm", worst * 1e3);
            rec.log_scalar("validation/nominal_error_rms_mm", (sum_sq / shown as f64).sqrt() * 1e3);
            tick += 1;
        }
    }
    Ok(rec.into_rrd()?)
}
