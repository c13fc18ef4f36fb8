//! `--record FILE.rrd` of `axiscal calibrate` and `axiscal diagnose`: measured data (real or
//! simulated) replayed with the nominal robot (`world/nominal`, grey) and the calibrated robot
//! (`world/calibrated`, blue) side by side at every commanded pose; the measured targets per
//! experiment with the arcs and axes fitted to them and their residual vectors; at the
//! validation poses, the error vectors of both models (measured minus predicted tool targets);
//! a note with the calibration's summary and, from `diagnose`, the verdict.

use super::{ERROR_EXAGGERATION, log_arc_fits};
use anyhow::{Context, Result};
use axiscal::calibration::procedure::Calibration;
use axiscal::kinematics::{JointKind, PhiModel};
use axiscal::measurement::{Experiment, MeasurementSet};
use axiscal::robot::{Controller, RobotDescription, commands_to_internal};
use axiscal::viz::{ROBOT_COLOR, Recorder};
use nalgebra::{Matrix3, Point3};
use std::fmt::Write as _;

/// Colour of the calibrated robot.
const CALIBRATED_COLOR: [u8; 4] = [60, 110, 200, 255];

/// What the recording is made of.
pub struct CalibratedCampaign<'a> {
    /// Nominal description (controller, nominal model, tool targets).
    pub desc: &'a RobotDescription,
    /// The measured rows.
    pub set: &'a MeasurementSet,
    /// The calibration made from them.
    pub calibration: &'a Calibration,
    /// A verdict to show in the notes (the diagnosis), if any.
    pub verdict: Option<&'a str>,
}

/// The two robots and the controller in front of them.
struct Robots<'a> {
    c: &'a CalibratedCampaign<'a>,
    nominal: PhiModel,
    calibrated: PhiModel,
    controller: Controller,
}

impl Robots<'_> {
    /// Logs both robots at commands `cmd` (file units): the nominal robot reaches the
    /// commanded joint values, the calibrated one turns them through its transmissions and
    /// couplings. Returns the calibrated joint values.
    fn log(&self, rec: &Recorder, cmd: &[f64]) -> Result<Vec<f64>> {
        let q_nominal = commands_to_internal(self.c.desc, cmd);
        let q_calibrated = self.c.calibration.robot.joint_values(&self.controller, &q_nominal)?;
        rec.log_robot_as("world/nominal", &self.nominal, &q_nominal, ROBOT_COLOR);
        rec.log_robot_as("world/calibrated", &self.calibrated, &q_calibrated, CALIBRATED_COLOR);
        Ok(q_calibrated)
    }
}

/// The recording of `c`, as the bytes of an `.rrd` file.
pub fn write_calibrated(c: &CalibratedCampaign) -> Result<Vec<u8>> {
    let rec = Recorder::new("axiscal")?;
    rec.send_default_blueprint();
    let robots = Robots {
        c,
        nominal: c.desc.nominal_model(),
        calibrated: c.calibration.robot.phi_model(),
        controller: Controller::from_description(c.desc),
    };
    // The calibration's noise model: isotropic, `noise_rms_3d_mm` per point.
    let sigma2_m2 = (c.calibration.options.noise_rms_3d_mm * 1e-3).powi(2) / 3.0;
    let covariance = |_: &Point3<f64>| Ok(Matrix3::identity() * sigma2_m2);
    let mut tick: i64 = 0;
    for e in c.set.experiments() {
        if e.moved_joint > 0 {
            log_axis_experiment(&rec, &robots, &covariance, &e, &mut tick)?;
        } else if !e.rows.is_empty() && e.name != axiscal::plan::TOOL_EXPERIMENT {
            log_validation(&rec, &robots, &e, &mut tick)?;
        }
    }
    rec.reset_time();
    rec.log_note("summary", &summary(c));
    Ok(rec.into_rrd()?)
}

/// One axis experiment: both robots and the accumulated targets per step, then the fits.
fn log_axis_experiment(
    rec: &Recorder,
    robots: &Robots,
    covariance: &dyn Fn(&Point3<f64>) -> Result<Matrix3<f64>>,
    e: &Experiment,
    tick: &mut i64,
) -> Result<()> {
    let mut seen: Vec<Point3<f64>> = Vec::new();
    for (step, rows) in e.by_step() {
        rec.set_step(*tick);
        robots
            .log(rec, &rows[0].cmd)
            .with_context(|| format!("replaying {} step {step}", e.name))?;
        seen.extend(rows.iter().map(|r| r.position_m()));
        rec.log_targets(e.name, &seen);
        *tick += 1;
    }
    if robots.c.desc.joints[e.moved_joint - 1].kind == JointKind::Revolute {
        log_arc_fits(rec, covariance, e.name, e.moved_joint, &e.by_step_target());
    }
    Ok(())
}

/// Validation poses: both robots, the measured tool targets and the error vectors of each
/// model, with their running RMS.
fn log_validation(rec: &Recorder, robots: &Robots, e: &Experiment, tick: &mut i64) -> Result<()> {
    let targets = robots.c.desc.tool_targets_m();
    let mut measured = Vec::new();
    let (mut nominal, mut calibrated) = (Vec::new(), Vec::new());
    for (step, rows) in e.by_step() {
        rec.set_step(*tick);
        let q_calibrated = robots
            .log(rec, &rows[0].cmd)
            .with_context(|| format!("replaying {} step {step}", e.name))?;
        let q_nominal = commands_to_internal(robots.c.desc, &rows[0].cmd);
        let tool_nominal = robots.nominal.world_from_tool(&q_nominal);
        let tool_calibrated = robots.calibrated.world_from_tool(&q_calibrated);
        // A row naming a tool target the description lacks has nothing to compare to.
        for (r, t) in rows.iter().filter_map(|r| Some((r, targets.get(r.target)?))) {
            measured.push(r.position_m());
            nominal.push(tool_nominal * t);
            calibrated.push(tool_calibrated * t);
        }
        rec.log_targets(e.name, &measured);
        for (model, predicted) in [("nominal", &nominal), ("calibrated", &calibrated)] {
            let full_scale_m = max_distance_m(predicted, &measured);
            let lengths = rec.log_error_vectors(
                &format!("{}_{model}_x{ERROR_EXAGGERATION}", e.name),
                predicted,
                &measured,
                full_scale_m,
                ERROR_EXAGGERATION,
            )?;
            let rms_m = (lengths.iter().map(|l| l * l).sum::<f64>() / lengths.len().max(1) as f64).sqrt();
            rec.log_scalar(&format!("{}/{model}_error_rms_mm", e.name), rms_m * 1e3);
        }
        *tick += 1;
    }
    Ok(())
}

fn max_distance_m(a: &[Point3<f64>], b: &[Point3<f64>]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max)
}

/// The note shown beside the 3-D view.
fn summary(c: &CalibratedCampaign) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# {}\n", axiscal::markdown::text(&c.desc.name));
    if let Some(v) = c.verdict {
        let _ = writeln!(s, "**Diagnosis:** {v}\n");
    }
    let _ = writeln!(
        s,
        "Grey: the nominal robot; blue: the calibrated robot, both at the commanded poses. \
         Arrows: residuals of the arc fits and validation errors, {ERROR_EXAGGERATION} times longer.\n"
    );
    let _ = writeln!(s, "| joint | points | span | residual RMS (mm) |\n|---|---|---|---|");
    for a in &c.calibration.axes {
        let _ = writeln!(
            s,
            "| {} | {} | {:.1} {} | {:.4} |",
            a.joint,
            a.points,
            a.span.value(),
            a.span.unit(),
            a.residual_rms_mm
        );
    }
    s
}
