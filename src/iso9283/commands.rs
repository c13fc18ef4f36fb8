//! The commands of the ISO poses' cycles, checked before their figures: every cycle of a pose
//! commands the pose's joint values (`one_command`), and no pose's commands are in radians
//! where the others' are in degrees (`radian_pose`). Either moves the commanded pose that
//! every figure is measured from, and would corrupt the figures silently.

use super::evaluate::{Cycle, IsoError};
use crate::kinematics::{JointKind, rigid_fit};
use crate::measurement::unit_check::SLIP_FACTOR;
use crate::measurement::{Experiment, Measurement, POSE_COMMAND_TOLERANCE};
use crate::robot::{Controller, RobotDescription, RobotModel, commands_to_internal};
use nalgebra::Point3;
use std::collections::{BTreeMap, HashMap};

/// The chance that the cycles of a clean file are refused by `one_command` (over all of a
/// pose's commands).
pub const COMMAND_FALSE_ALARM: f64 = 1e-6;

/// Per joint, how far \[deg or mm\] a cycle's command may lie from its pose's: the rounding of
/// a written command ([`POSE_COMMAND_TOLERANCE`]) plus the normal deviate that `values`
/// commands all stay within but with the chance [`COMMAND_FALSE_ALARM`], times the joint's
/// repeatability (a file that logs the controller's readings rather than the program's
/// commands scatters by it).
fn tolerances(desc: &RobotDescription, values: usize) -> Vec<f64> {
    let p = 1.0 - COMMAND_FALSE_ALARM / values.max(1) as f64;
    let z = crate::numerics::stats::chi_square_quantile(p, 1.0).sqrt();
    desc.joints
        .iter()
        .map(|j| {
            let sigma = match j.kind {
                JointKind::Revolute => j.repeatability_sigma.to_degrees(),
                JointKind::Prismatic => j.repeatability_sigma * 1e3,
            };
            POSE_COMMAND_TOLERANCE + z * sigma
        })
        .collect()
}

/// The per-joint lower median of `commands`.
fn median(commands: &[&[f64]]) -> Vec<f64> {
    let n = commands.first().map_or(0, |c| c.len());
    (0..n)
        .map(|j| {
            let mut v: Vec<f64> = commands.iter().map(|c| c[j]).collect();
            v.sort_by(f64::total_cmp);
            v[(v.len() - 1) / 2]
        })
        .collect()
}

/// `[a, b, c]` with four decimals.
fn list(values: &[f64]) -> String {
    let v: Vec<String> = values.iter().map(|x| format!("{x:.4}")).collect();
    format!("[{}]", v.join(", "))
}

/// Refuses the first cycle of the ISO pose `experiment` whose commands differ from the
/// median of its cycles' beyond [`tolerances`] (one pose, one command): a cycle written in
/// another unit, or holding another pose's commands. `lines`: the file line of each
/// (experiment, step)'s first row.
pub(super) fn one_command(
    experiment: &Experiment<'_>,
    desc: &RobotDescription,
    lines: &HashMap<(&str, usize), u64>,
) -> Result<(), IsoError> {
    let steps: Vec<(usize, &[f64])> = experiment
        .by_step()
        .into_iter()
        .map(|(step, rows)| {
            let first: &Measurement = rows[0];
            (step, first.cmd.as_slice())
        })
        .collect();
    let commands: Vec<&[f64]> = steps.iter().map(|(_, c)| *c).collect();
    if commands.len() < 2 {
        return Ok(());
    }
    let reference = median(&commands);
    let tolerance = tolerances(desc, commands.len() * reference.len());
    let differs = |c: &[f64]| {
        c.iter()
            .zip(&reference)
            .zip(&tolerance)
            .any(|((c, r), t)| (c - r).abs() > *t)
    };
    let Some((step, cmd)) = steps.iter().find(|(_, c)| differs(c)) else {
        return Ok(());
    };
    let agreeing = commands.iter().filter(|c| !differs(c)).count();
    let line = lines
        .get(&(experiment.name, *step))
        .map_or(String::new(), |l| format!("line {l}: "));
    if 2 * agreeing <= commands.len() {
        // No command most cycles share: the experiment holds several poses, not one pose's
        // cycles, so no single cycle is the odd one.
        return Err(IsoError::Cycle {
            experiment: experiment.name.to_string(),
            step: *step,
            problem: format!(
                "{line}commands {}, but the experiment's {} cycles share no command ({agreeing} of them \
                 match the median of each joint's commands): an ISO pose is one command measured once a \
                 cycle, and these rows hold several poses (free poses named `iso-P<k>`?): give each pose's \
                 cycles their own experiment `iso-P<k>`, the cycle in `step`",
                list(cmd),
                commands.len()
            ),
        });
    }
    Err(IsoError::Cycle {
        experiment: experiment.name.to_string(),
        step: *step,
        problem: format!(
            "{line}commands {} where {agreeing} of the pose's {} cycles command {}: one pose, one command; this \
             cycle's commands are in another unit (radians?) or another pose's: correct its rows or remove them",
            list(cmd),
            commands.len(),
            list(&reference)
        ),
    })
}

/// One ISO pose's commands and its cycles' commanded and mean attained positions.
struct PoseCommands<'a> {
    experiment: &'a str,
    cmd: &'a [f64],
    commanded: Point3<f64>,
    attained: Point3<f64>,
}

/// How far the commanded positions miss the attained ones \[mm\]: RMS of the differences, or
/// of the rigid fit's residuals with `register` (a nominal model's base fitted to the data);
/// `None` when the registration has too few poses.
fn misfit(pairs: &[(Point3<f64>, Point3<f64>)], register: bool) -> Option<f64> {
    if register {
        let (src, dst): (Vec<_>, Vec<_>) = pairs.iter().copied().unzip();
        return rigid_fit(&src, &dst).map(|(_, rms)| rms * 1e3);
    }
    let sum: f64 = pairs.iter().map(|(c, a)| (c - a).norm_squared()).sum();
    Some((sum / pairs.len().max(1) as f64).sqrt() * 1e3)
}

/// The commanded position of `cmd` (file units) read as radians for the revolute joints.
fn commanded_as_radians(cmd: &[f64], model: &RobotModel, desc: &RobotDescription) -> Option<Point3<f64>> {
    let degrees: Vec<f64> = cmd
        .iter()
        .zip(&desc.joints)
        .map(|(c, j)| {
            if j.kind == JointKind::Revolute {
                c.to_degrees()
            } else {
                *c
            }
        })
        .collect();
    let controller = Controller::from_description(desc);
    let phi = model.phi_model();
    let q = model
        .joint_values(&controller, &commands_to_internal(desc, &degrees))
        .ok()?;
    let base_from_tool = phi.world_from_base.inverse() * phi.world_from_tool(&q);
    Some(Point3::from(base_from_tool.translation.vector))
}

/// The ISO poses of `cycles`, one each: the first cycle's commands and commanded position, the
/// mean attained position of its cycles.
fn poses(cycles: &BTreeMap<usize, Vec<Cycle>>) -> Vec<PoseCommands<'_>> {
    let mut by_experiment: BTreeMap<&str, Vec<&Cycle>> = BTreeMap::new();
    for c in cycles.values().flatten() {
        by_experiment.entry(c.experiment.as_str()).or_default().push(c);
    }
    by_experiment
        .into_iter()
        .map(|(experiment, c)| {
            let sum = c
                .iter()
                .map(|c| c.attained.translation.vector)
                .sum::<nalgebra::Vector3<f64>>();
            let first: &Cycle = c[0];
            PoseCommands {
                experiment,
                cmd: &first.cmd,
                commanded: Point3::from(first.commanded.translation.vector),
                attained: Point3::from(sum / c.len() as f64),
            }
        })
        .collect()
}

/// The unit check of the ISO poses' commands: one pose (an experiment) whose commands, read
/// as radians, bring its commanded position more than [`SLIP_FACTOR`] times closer to where
/// it was measured (all the poses' misfit, [`misfit`]) is refused as written in radians.
pub(super) fn radian_pose(
    cycles: &BTreeMap<usize, Vec<Cycle>>,
    model: &RobotModel,
    desc: &RobotDescription,
    register: bool,
) -> Result<(), IsoError> {
    let poses = poses(cycles);
    let pairs: Vec<_> = poses.iter().map(|p| (p.commanded, p.attained)).collect();
    let Some(as_read) = misfit(&pairs, register) else {
        return Ok(());
    };
    for (k, p) in poses.iter().enumerate() {
        let Some(radians) = commanded_as_radians(p.cmd, model, desc) else {
            continue;
        };
        let mut other = pairs.clone();
        other[k].0 = radians;
        let Some(as_radians) = misfit(&other, register) else {
            continue;
        };
        if as_radians * SLIP_FACTOR < as_read {
            return Err(IsoError::Cycle {
                experiment: p.experiment.to_string(),
                step: cycles
                    .values()
                    .flatten()
                    .find(|c| c.experiment == p.experiment)
                    .map_or(0, |c| c.step),
                problem: format!(
                    "its commands {} look like radians rather than degrees: as written the poses' commanded \
                     positions miss the measured ones by {as_read:.3} mm RMS{}, with this pose's commands read as \
                     radians by {as_radians:.3} mm; write its revolute joints' commands in degrees (or pass \
                     --skip-unit-check if they are)",
                    list(p.cmd),
                    if register { " (after registering the base)" } else { "" }
                ),
            });
        }
    }
    Ok(())
}
