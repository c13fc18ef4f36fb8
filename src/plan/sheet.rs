//! The measurement plan a user runs on a real robot (`axiscal plan`,
//! `docs/formats.md#measurement-plan`): every point to measure, in the order the campaign
//! visits them, with every joint's command (hold-still commands included), the target, its
//! nominal position and whether each instrument station should see it.
//!
//! Two separate steps: [`planned_points`] turns a choice of poses (a [`CalibrationPlan`] and a
//! [`ValidationPlan`]) into points; [`write_plan_csv`] writes any list of points. Another
//! choice of poses (e.g. an optimised one) reuses the writer.

use super::sight::{link_segments, sees};
use super::{CalibrationPlan, PlanError, TOOL_EXPERIMENT, ValidationPlan};
use crate::measurement::format_f64;
use crate::robot::{Controller, RobotDescription, RobotModel, commands_to_internal};
use nalgebra::Point3;
use std::io::{self, Write};

/// Experiment id of the validation poses (as `simulate` writes them).
pub const VALIDATION_EXPERIMENT: &str = "validation";

/// One point to measure.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedPoint {
    /// 1-based id, in measuring order (the id an instrument export refers to).
    pub point: usize,
    /// 1-based robot pose this point is measured at (consecutive points share a pose).
    pub pose: usize,
    /// Experiment id (`docs/formats.md#experiments-and-targets`).
    pub experiment: String,
    /// The joint the experiment moves (0: free poses).
    pub moved_joint: usize,
    /// 0-based step within the experiment.
    pub step: usize,
    /// Target id.
    pub target: usize,
    /// Commands `cmd_1..cmd_N`, file units (deg or mm).
    pub cmd: Vec<f64>,
    /// The target's position on the nominal robot, instrument frame \[m\].
    pub nominal_m: Point3<f64>,
    /// Per station, whether it should see the target (nominal geometry); empty without stations.
    pub visible: Vec<bool>,
}

/// Where the instrument stands and how thick the arm is, for the line-of-sight columns.
#[derive(Clone, Debug, PartialEq)]
pub struct SightOptions {
    /// The stations, instrument frame \[m\] (none: no line-of-sight columns).
    pub stations_m: Vec<Point3<f64>>,
    /// Radius of every link's capsule \[m\].
    pub link_radius_m: f64,
    /// The sight line stops this short of the target \[m\].
    pub stop_short_m: f64,
}

/// One robot pose of a plan and the targets measured there.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanPose {
    /// Experiment id.
    pub experiment: String,
    /// The joint the experiment moves (0: free poses).
    pub moved_joint: usize,
    /// 0-based step within the experiment.
    pub step: usize,
    /// Commands, file units (deg or mm).
    pub cmd: Vec<f64>,
    /// The targets: id, position in the carrying link's frame \[m\], the 1-based link.
    pub targets: Vec<(usize, Point3<f64>, usize)>,
}

/// The description's tool targets as [`PlanPose::targets`] (on the last link).
pub fn tool_targets(desc: &RobotDescription) -> Vec<(usize, Point3<f64>, usize)> {
    desc.tool_targets_m()
        .into_iter()
        .enumerate()
        .map(|(id, p)| (id, desc.tool.frame.to_isometry() * p, desc.dof()))
        .collect()
}

/// The points of `plan` (axis experiments, in order), the tool observation at the reference,
/// then `validation`'s poses: the rows `simulate` would measure, in the same order.
pub fn planned_points(
    desc: &RobotDescription,
    plan: &CalibrationPlan,
    validation: &ValidationPlan,
    sight: &SightOptions,
) -> Result<Vec<PlannedPoint>, PlanError> {
    plan.validate(desc)?;
    let mut poses: Vec<PlanPose> = Vec::new();
    for (sweep, experiment) in plan.sweeps.iter().zip(plan.experiment_names()) {
        let targets = desc.axis_targets_of(sweep.joint).ok_or(PlanError::Invalid {
            message: format!("joint {} has no axis targets", sweep.joint),
        })?;
        let mut observed = vec![(0, targets.target0.position_m(), targets.target0.link)];
        if let (true, Some(t1)) = (sweep.second_target, targets.target1) {
            observed.push((1, t1.position_m(), t1.link));
        }
        for step in 0..sweep.poses() {
            poses.push(PlanPose {
                experiment: experiment.clone(),
                moved_joint: sweep.joint,
                step,
                cmd: plan.commands(desc, sweep, step),
                targets: observed.clone(),
            });
        }
    }
    let tool = tool_targets(desc);
    poses.push(PlanPose {
        experiment: TOOL_EXPERIMENT.to_owned(),
        moved_joint: 0,
        step: 0,
        cmd: plan.reference.clone(),
        targets: tool.clone(),
    });
    for (step, cmd) in validation.commands(desc, &plan.reference).into_iter().enumerate() {
        poses.push(PlanPose {
            experiment: VALIDATION_EXPERIMENT.to_owned(),
            moved_joint: 0,
            step,
            cmd,
            targets: tool.clone(),
        });
    }
    points_of_poses(desc, poses, sight)
}

/// The points of `poses`, in order: each target's nominal position and whether each station
/// should see it.
pub fn points_of_poses(
    desc: &RobotDescription,
    poses: Vec<PlanPose>,
    sight: &SightOptions,
) -> Result<Vec<PlannedPoint>, PlanError> {
    let nominal = RobotModel::ideal(desc);
    let controller = Controller::from_description(desc);
    let model = desc.nominal_model();
    let mut points = Vec::new();
    for (
        pose,
        PlanPose {
            experiment,
            moved_joint,
            step,
            cmd,
            targets,
        },
    ) in poses.into_iter().enumerate()
    {
        let q = nominal
            .joint_values(&controller, &commands_to_internal(desc, &cmd))
            .map_err(|e| PlanError::Invalid {
                message: format!("{experiment} step {step}: {e}"),
            })?;
        let links = model.poses(&q).world_from_link;
        let segments = link_segments(&model, &q);
        for (target, in_link_m, link) in targets {
            let nominal_m = links[link - 1] * in_link_m;
            let visible = sight
                .stations_m
                .iter()
                .map(|s| sees(s, &nominal_m, &segments, sight.link_radius_m, sight.stop_short_m))
                .collect();
            points.push(PlannedPoint {
                point: points.len() + 1,
                pose: pose + 1,
                experiment: experiment.clone(),
                moved_joint,
                step,
                target,
                cmd: cmd.clone(),
                nominal_m,
                visible,
            });
        }
    }
    Ok(points)
}

/// Writes the plan CSV: `header_comment` (each line starting with `#`), the column header,
/// one row per point (`docs/formats.md#measurement-plan`).
pub fn write_plan_csv<W: Write>(mut w: W, header_comment: &str, points: &[PlannedPoint]) -> io::Result<()> {
    w.write_all(header_comment.as_bytes())?;
    let dof = points.first().map_or(0, |p| p.cmd.len());
    let stations = points.first().map_or(0, |p| p.visible.len());
    let mut header = vec![
        "point".to_owned(),
        "pose".into(),
        "experiment".into(),
        "moved_joint".into(),
    ];
    header.extend(["step".into(), "target".into()]);
    header.extend((1..=dof).map(|k| format!("cmd_{k}")));
    header.extend(["nominal_x_mm".into(), "nominal_y_mm".into(), "nominal_z_mm".into()]);
    header.extend((1..=stations).map(|k| format!("visible_{k}")));
    let mut csv = crate::csv_lines::writer(&mut w);
    csv.write_record(&header)?;
    for p in points {
        let mut row = vec![p.point.to_string(), p.pose.to_string(), p.experiment.clone()];
        row.extend([p.moved_joint.to_string(), p.step.to_string(), p.target.to_string()]);
        row.extend(p.cmd.iter().map(|c| format_f64(*c)));
        row.extend(p.nominal_m.iter().map(|c| format!("{:.3}", c * 1e3)));
        row.extend(p.visible.iter().map(|v| if *v { "yes" } else { "no" }.to_owned()));
        csv.write_record(&row)?;
    }
    csv.flush()
}
