//! The axis experiments of a measurement set as the procedure needs them: one per joint,
//! target 0 (and target 1) ordered by step, the commands, and the common reference pose
//! every other joint is held at (`docs/formats.md#measurement-csv` and `#controller-semantics`).

use super::ProcedureError;
use crate::measurement::MeasurementSet;
use crate::robot::RobotDescription;
use nalgebra::Point3;

/// Commands that should be equal are taken as equal within this \[deg or mm\]: CSV files
/// written by other programs round the commands they print.
pub const COMMAND_TOLERANCE: f64 = 1e-6;

/// One axis experiment.
#[derive(Clone, Debug)]
pub struct AxisExperiment {
    /// Experiment id.
    pub name: String,
    /// The swept joint (1-based).
    pub joint: usize,
    /// Commands of every observed step, in step order (file units).
    pub commands: Vec<Vec<f64>>,
    /// Target 0 where it was seen \[m\], instrument frame (an occluded target is absent).
    pub target0_m: Vec<Point3<f64>>,
    /// Indices into `commands` of the `target0_m` observations.
    pub target0_steps: Vec<usize>,
    /// Target 1 where it was seen \[m\].
    pub target1_m: Vec<Point3<f64>>,
    /// Indices into `commands` of the `target1_m` observations.
    pub target1_steps: Vec<usize>,
    /// Whether the commands hold actuator `joint + 1` still (the joint-`joint+1` command
    /// follows the nominal coupling slope).
    pub holds_next_still: bool,
}

/// Collects the axis experiments, checks their commands, and finds the reference pose.
pub fn axis_experiments(
    set: &MeasurementSet,
    desc: &RobotDescription,
) -> Result<(Vec<AxisExperiment>, Vec<f64>), ProcedureError> {
    let n = desc.dof();
    let mut out: Vec<AxisExperiment> = Vec::new();
    for e in set.experiments().into_iter().filter(|e| e.moved_joint > 0) {
        let joint = e.moved_joint;
        if let Some(first) = out.iter().find(|x| x.joint == joint) {
            return Err(ProcedureError::DuplicateAxis {
                joint,
                first: first.name.clone(),
                second: e.name.to_string(),
            });
        }
        let by_step = e.by_step();
        let mut commands: Vec<Vec<f64>> = Vec::new();
        let (mut t0, mut s0, mut t1, mut s1) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (step, rows) in &by_step {
            let first = rows[0];
            for r in rows.iter() {
                if let Some((k, _)) = r
                    .cmd
                    .iter()
                    .zip(&first.cmd)
                    .enumerate()
                    .find(|(_, (a, b))| (*a - *b).abs() > COMMAND_TOLERANCE)
                {
                    return Err(ProcedureError::InconsistentCommands {
                        experiment: e.name.to_string(),
                        step: *step,
                        joint: k + 1,
                        reason: "two targets of one pose carry different commands".into(),
                    });
                }
            }
            let index = commands.len();
            commands.push(first.cmd.clone());
            if let Some(r0) = rows.iter().find(|r| r.target == 0) {
                t0.push(r0.position_m());
                s0.push(index);
            }
            if let Some(r1) = rows.iter().find(|r| r.target == 1) {
                t1.push(r1.position_m());
                s1.push(index);
            }
        }
        let holds_next_still = check_sweep_commands(e.name, joint, &commands, desc)?;
        out.push(AxisExperiment {
            name: e.name.to_string(),
            joint,
            commands,
            target0_m: t0,
            target0_steps: s0,
            target1_m: t1,
            target1_steps: s1,
            holds_next_still,
        });
    }
    for joint in 1..=n {
        if !out.iter().any(|e| e.joint == joint) {
            return Err(ProcedureError::MissingAxis { joint });
        }
    }
    let reference = reference_pose(&out, n)?;
    Ok((out, reference))
}

/// The swept joint must move; joint `k+1` either stays or follows the nominal coupling
/// (hold-still); every other joint stays. Returns whether joint `k+1` follows.
fn check_sweep_commands(
    name: &str,
    joint: usize,
    commands: &[Vec<f64>],
    desc: &RobotDescription,
) -> Result<bool, ProcedureError> {
    let k = joint - 1;
    let first = &commands[0];
    let span = commands.iter().map(|c| c[k]).fold(f64::NEG_INFINITY, f64::max)
        - commands.iter().map(|c| c[k]).fold(f64::INFINITY, f64::min);
    if span.is_nan() || span <= COMMAND_TOLERANCE {
        return Err(ProcedureError::ZeroSpan {
            experiment: name.to_owned(),
            joint,
        });
    }
    let slope = desc.nominal_coupling_from(joint);
    let next_moves = k + 1 < first.len()
        && commands
            .iter()
            .any(|c| (c[k + 1] - first[k + 1]).abs() > COMMAND_TOLERANCE);
    for (step, c) in commands.iter().enumerate() {
        for j in 0..c.len() {
            if j == k || (j == k + 1 && next_moves) {
                continue;
            }
            if (c[j] - first[j]).abs() > COMMAND_TOLERANCE {
                return Err(ProcedureError::InconsistentCommands {
                    experiment: name.to_owned(),
                    step,
                    joint: j + 1,
                    reason: format!("joint {} moves while joint {joint} is swept", j + 1),
                });
            }
        }
        if next_moves {
            let Some(s) = slope else {
                return Err(ProcedureError::InconsistentCommands {
                    experiment: name.to_owned(),
                    step,
                    joint: joint + 1,
                    reason: format!(
                        "joint {} moves but has no nominal coupling from joint {joint}",
                        joint + 1
                    ),
                });
            };
            let expect = first[k + 1] + s * (c[k] - first[k]);
            if (c[k + 1] - expect).abs() > COMMAND_TOLERANCE.max(1e-9 * expect.abs()) {
                return Err(ProcedureError::InconsistentCommands {
                    experiment: name.to_owned(),
                    step,
                    joint: joint + 1,
                    reason: format!(
                        "hold-still command {:.6} differs from cmd(0) + {s} * (cmd_{joint} - cmd_{joint}(0)) = {expect:.6}",
                        c[k + 1]
                    ),
                });
            }
        }
    }
    Ok(next_moves)
}

/// The value every joint is held at while other joints are swept.
fn reference_pose(experiments: &[AxisExperiment], n: usize) -> Result<Vec<f64>, ProcedureError> {
    let mut reference: Vec<Option<(f64, &str)>> = vec![None; n];
    for e in experiments {
        for (j, slot) in reference.iter_mut().enumerate() {
            // Skip the swept joint and a hold-still joint k+1 (index `e.joint`): they move.
            if j + 1 == e.joint || (j == e.joint && e.holds_next_still) {
                continue;
            }
            let value = e.commands[0][j];
            match slot {
                None => *slot = Some((value, &e.name)),
                Some((v, first)) if (*v - value).abs() > COMMAND_TOLERANCE => {
                    return Err(ProcedureError::InconsistentCommands {
                        experiment: e.name.to_string(),
                        step: 0,
                        joint: j + 1,
                        reason: format!("reference command {value} differs from {v} in experiment {first}"),
                    });
                }
                Some(_) => {}
            }
        }
    }
    Ok(reference
        .into_iter()
        .enumerate()
        .map(|(j, r)| {
            r.map(|(v, _)| v).unwrap_or_else(|| {
                experiments
                    .iter()
                    .find(|e| e.joint == j + 1)
                    .map(|e| e.commands[0][j])
                    .unwrap_or(0.0)
            })
        })
        .collect())
}
