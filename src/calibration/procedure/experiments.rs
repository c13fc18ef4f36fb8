//! The axis experiments of a measurement set as the procedure needs them: target 0 (and
//! target 1) ordered by step, the recorded commands of every step, which joints each
//! experiment holds, and the common reference pose (`docs/formats.md#measurement-csv`,
//! `#held-joints` and `#controller-semantics`).
//!
//! Any subset of joints may be swept, a joint any number of times. A held joint's recorded
//! values are taken as recorded (the pose the robot stood at; the procedure models them,
//! [`super::held`]); within one experiment they must stay within the held tolerance of their
//! median, else the experiment moves two joints and is an error naming the joint and how far
//! it moved. Between experiments the held values may differ (sweeps at other poses).

use super::error::ProcedureError;
use super::options::DEFAULT_HELD_TOLERANCE;
use crate::kinematics::JointKind;
use crate::measurement::MeasurementSet;
use crate::numerics::stats::{QuantileMethod, quantile};
use crate::robot::{Controller, RobotDescription, commands_to_internal};
use nalgebra::Point3;

/// Commands that differ by no more than this \[deg or mm\] are one reading: the tolerance of
/// the targets of one pose ([`crate::measurement::POSE_COMMAND_TOLERANCE`]), of a held joint
/// standing still and of a sweep that does not move.
pub const COMMAND_TOLERANCE: f64 = crate::measurement::POSE_COMMAND_TOLERANCE;

/// One axis experiment.
#[derive(Clone, Debug)]
pub struct AxisExperiment {
    /// Experiment id.
    pub name: String,
    /// The swept joint (1-based).
    pub joint: usize,
    /// Commands of every observed step, in step order (file units, as recorded).
    pub commands: Vec<Vec<f64>>,
    /// The file's step number of each entry of `commands`.
    pub steps: Vec<usize>,
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
    /// The file lines of its first and last row, when the set was read from a file.
    pub lines: Option<(u64, u64)>,
}

impl AxisExperiment {
    /// How far its held joints stand from `reference`, worst step: the sum over constant held
    /// joints of `|cmd_j - reference_j|` (file units).
    pub fn held_distance(&self, reference: &[f64]) -> f64 {
        self.commands
            .iter()
            .map(|c| {
                (0..c.len())
                    .filter(|&j| self.holds_constant(j))
                    .map(|j| (c[j] - reference[j]).abs())
                    .sum::<f64>()
            })
            .fold(0.0, f64::max)
    }

    /// Whether joint `j` (0-based) is held at a constant command in this experiment.
    pub fn holds_constant(&self, j: usize) -> bool {
        j + 1 != self.joint && !(j == self.joint && self.holds_next_still)
    }
}

/// Collects the axis experiments and checks their commands (held tolerance `tolerance`, file
/// units), and finds the reference pose: per joint, the median of its held values over every
/// step of every experiment that holds it (for a joint no experiment holds, its command in the
/// tool observation, else the first sweep's step 0).
pub fn axis_experiments_with(
    set: &MeasurementSet,
    desc: &RobotDescription,
    tolerance: f64,
) -> Result<(Vec<AxisExperiment>, Vec<f64>), ProcedureError> {
    let mut out: Vec<AxisExperiment> = Vec::new();
    for e in set.experiments().into_iter().filter(|e| e.moved_joint > 0) {
        let rows_by_step = e.rows_by_step();
        let by_step = rows_by_step.chunk_by(|a, b| a.step == b.step);
        let n = by_step.clone().count();
        let mut x = AxisExperiment {
            name: e.name.to_string(),
            joint: e.moved_joint,
            commands: Vec::with_capacity(n),
            steps: Vec::with_capacity(n),
            target0_m: Vec::with_capacity(n),
            target0_steps: Vec::with_capacity(n),
            target1_m: Vec::with_capacity(n),
            target1_steps: Vec::with_capacity(n),
            holds_next_still: false,
            lines: e.lines,
        };
        for rows in by_step {
            // One pose's rows carry one reading of the commands (a `MeasurementSet` invariant).
            let (first, step) = (rows[0], &rows[0].step);
            let index = x.commands.len();
            x.commands.push(first.cmd.clone());
            x.steps.push(*step);
            if let Some(r0) = rows.iter().find(|r| r.target == 0) {
                x.target0_m.push(r0.position_m());
                x.target0_steps.push(index);
            }
            if let Some(r1) = rows.iter().find(|r| r.target == 1) {
                x.target1_m.push(r1.position_m());
                x.target1_steps.push(index);
            }
        }
        x.holds_next_still = check_sweep_commands(&x, desc, tolerance)?;
        out.push(x);
    }
    if out.is_empty() {
        return Err(ProcedureError::NoAxisExperiment);
    }
    check_no_copies(&out)?;
    let reference = reference_pose(&out, desc.dof());
    let reference = at_the_tool_observation(set, desc, &out, reference);
    Ok((out, reference))
}

/// `reference` with each joint no experiment holds (every experiment sweeps it: a one-joint
/// robot, or sweeps of one joint only) set to its command in the first free pose that sees
/// every tool target with the held joints at `reference`: the tool observation, where the
/// tool frame is fitted. Unchanged when there is none.
fn at_the_tool_observation(
    set: &MeasurementSet,
    desc: &RobotDescription,
    experiments: &[AxisExperiment],
    mut reference: Vec<f64>,
) -> Vec<f64> {
    let unheld: Vec<usize> = (0..desc.dof())
        .filter(|&j| !experiments.iter().any(|e| e.holds_constant(j)))
        .collect();
    let targets = desc.tool_targets_m().len();
    if unheld.is_empty() || targets < 3 {
        return reference;
    }
    let free = set.experiments();
    let observation = free.iter().filter(|e| e.moved_joint == 0).find_map(|e| {
        e.by_step().into_values().find(|rows| {
            let held_at_reference = rows.iter().all(|r| {
                (0..desc.dof())
                    .filter(|j| !unheld.contains(j))
                    .all(|j| (r.cmd[j] - reference[j]).abs() <= COMMAND_TOLERANCE)
            });
            held_at_reference && (0..targets).all(|t| rows.iter().any(|r| r.target == t))
        })
    });
    if let Some(rows) = observation {
        for &j in &unheld {
            reference[j] = rows[0].cmd[j];
        }
    }
    reference
}

/// No two experiments of one joint hold the same target-0 points bit for bit: measured
/// points repeat to the last digit only when rows were copied.
fn check_no_copies(experiments: &[AxisExperiment]) -> Result<(), ProcedureError> {
    let lines = |e: &AxisExperiment| match e.lines {
        Some((a, b)) => format!("lines {a}-{b}"),
        None => "no file lines".to_owned(),
    };
    for (i, a) in experiments.iter().enumerate() {
        let copy = experiments[i + 1..]
            .iter()
            .find(|b| b.joint == a.joint && !a.target0_m.is_empty() && b.target0_m == a.target0_m);
        if let Some(b) = copy {
            return Err(ProcedureError::DuplicateExperiment {
                first: a.name.clone(),
                first_lines: lines(a),
                second: b.name.clone(),
                second_lines: lines(b),
                joint: a.joint,
                points: a.target0_m.len(),
            });
        }
    }
    Ok(())
}

/// [`axis_experiments_with`] at the default held tolerance.
pub fn axis_experiments(
    set: &MeasurementSet,
    desc: &RobotDescription,
) -> Result<(Vec<AxisExperiment>, Vec<f64>), ProcedureError> {
    axis_experiments_with(set, desc, DEFAULT_HELD_TOLERANCE)
}

/// The unit of a joint's file values.
fn unit(desc: &RobotDescription, j: usize) -> &'static str {
    match desc.joints[j].kind {
        JointKind::Revolute => "deg",
        JointKind::Prismatic => "mm",
    }
}

/// The largest deviation of `values` from their median, and the step where it is.
fn spread(values: &[f64]) -> (f64, usize, f64) {
    let m = quantile(values, 0.5, QuantileMethod::Linear);
    let (i, d) = values
        .iter()
        .map(|v| (v - m).abs())
        .enumerate()
        .fold((0, 0.0), |best, (i, d)| if d > best.1 { (i, d) } else { best });
    (d, i, m)
}

/// The swept joint must move; joint `k+1` either stays or follows the nominal coupling
/// (hold-still), within `tolerance`; every other joint stays within `tolerance` of its median.
/// Returns whether joint `k+1` follows.
fn check_sweep_commands(e: &AxisExperiment, desc: &RobotDescription, tolerance: f64) -> Result<bool, ProcedureError> {
    let (k, commands) = (e.joint - 1, &e.commands);
    let column = |j: usize| -> Vec<f64> { commands.iter().map(|c| c[j]).collect() };
    let swept = column(k);
    let span =
        swept.iter().cloned().fold(f64::NEG_INFINITY, f64::max) - swept.iter().cloned().fold(f64::INFINITY, f64::min);
    if span.is_nan() || span <= COMMAND_TOLERANCE {
        return Err(ProcedureError::ZeroSpan {
            experiment: e.name.clone(),
            joint: e.joint,
            lines: e.lines,
            cause: zero_span_cause(e, desc, tolerance),
        });
    }
    let too_far = |j: usize, i: usize, d: f64, what: &str| ProcedureError::InconsistentCommands {
        experiment: e.name.clone(),
        step: e.steps[i],
        joint: j + 1,
        reason: format!(
            "joint {} is held while joint {} is swept but {what} by {d:.4} {} (held tolerance {tolerance} {}; `--held-tolerance`)",
            j + 1,
            e.joint,
            unit(desc, j),
            unit(desc, j)
        ),
    };
    let mut follows = false;
    if k + 1 < desc.dof() {
        let next = column(k + 1);
        let (d_const, i_const, _) = spread(&next);
        let follower = desc.nominal_coupling_from(e.joint).map(|s| {
            let resid: Vec<f64> = next.iter().zip(&swept).map(|(c, u)| c - s * (u - swept[0])).collect();
            spread(&resid)
        });
        match follower {
            Some((d_f, _, _)) if d_f < d_const && d_f <= tolerance => follows = true,
            Some((d_f, i_f, _)) if d_const > tolerance && d_f > tolerance => {
                if let Some(slip) = scaled_follower(e, desc, (&next, &swept), tolerance) {
                    return Err(slip);
                }
                let (f, j) = (e.joint + 1, e.joint);
                return Err(too_far(
                    k + 1,
                    i_f,
                    d_f,
                    &format!(
                        "its command leaves the hold-still formula cmd_{f}(s) = cmd_{f}(0) + slope (cmd_{j}(s) - cmd_{j}(0)) \
                         (slope {}: the formula reads the columns cmd_{j} and cmd_{f}{}) at its farthest step",
                        desc.nominal_coupling_from(e.joint).unwrap_or(f64::NAN),
                        lines_words(e.lines)
                    ),
                ));
            }
            _ if d_const > tolerance => return Err(too_far(k + 1, i_const, d_const, "moves")),
            _ => {}
        }
    }
    for j in (0..desc.dof()).filter(|&j| j != k && j != k + 1) {
        let (d, i, _) = spread(&column(j));
        if d > tolerance {
            return Err(too_far(j, i, d, "moves"));
        }
    }
    Ok(follows)
}

/// A follower column that keeps to the hold-still formula's line, but at another slope: the
/// two columns' ratio is off by one factor, the swept column scaled on export (a gear ratio or
/// unit applied to it alone), or the follower's. Named on the swept column, whose sweep the
/// fit would otherwise take the factor into. `None` when the follower's commands leave every
/// line through step 0 by more than `tolerance`.
fn scaled_follower(
    e: &AxisExperiment,
    desc: &RobotDescription,
    (next, swept): (&[f64], &[f64]),
    tolerance: f64,
) -> Option<ProcedureError> {
    let slope = desc.nominal_coupling_from(e.joint)?;
    let du: Vec<f64> = swept.iter().map(|u| u - swept[0]).collect();
    let dc: Vec<f64> = next.iter().map(|c| c - next[0]).collect();
    let uu: f64 = du.iter().map(|d| d * d).sum();
    let ratio = du.iter().zip(&dc).map(|(u, c)| u * c).sum::<f64>() / uu / slope;
    let (worst, _, _) = spread(
        &dc.iter()
            .zip(&du)
            .map(|(c, u)| c - ratio * slope * u)
            .collect::<Vec<_>>(),
    );
    if !(ratio.is_finite() && ratio != 0.0 && worst <= tolerance) {
        return None;
    }
    let (k, f) = (e.joint, e.joint + 1);
    if ratio < 0.0 {
        return Some(negated_follower(e, desc, (slope, ratio, worst)));
    }
    Some(ProcedureError::InconsistentCommands {
        experiment: e.name.clone(),
        step: e.steps[0],
        joint: k,
        reason: format!(
            "joint {f} is held while joint {k} is swept, and its command follows cmd_{k} on a straight line as the \
             hold-still formula cmd_{f}(0) + slope (cmd_{k} - cmd_{k}(0)) says, but at {ratio:.4} times the description's \
             slope {slope} (every step within {worst:.4} {} of that line): cmd_{k} looks scaled by {:.4} on export (a gear ratio or unit \
             applied to it alone), or cmd_{f} by {ratio:.4}; check cmd_{k} against the controller's reading at two poses",
            unit(desc, f - 1),
            1.0 / ratio,
        ),
    })
}

/// The file lines of a sweep (`lines`), in words: ` (lines A-B of the file)`, empty when unknown.
fn lines_words(lines: Option<(u64, u64)>) -> String {
    lines.map_or(String::new(), |(a, b)| format!("; the sweep's lines {a}-{b}"))
}

/// A follower column that keeps to a straight line through step 0 against the swept column,
/// but with the slope's sign turned (`ratio` below 0 times the description's `slope`, every
/// step within `worst` of that line): one of the two columns the hold-still formula reads is
/// negated, most often the swept one (an export's direction convention). Named on the swept
/// column, with the sweep's lines and the fix.
fn negated_follower(
    e: &AxisExperiment,
    desc: &RobotDescription,
    (slope, ratio, worst): (f64, f64, f64),
) -> ProcedureError {
    let (k, f) = (e.joint, e.joint + 1);
    ProcedureError::InconsistentCommands {
        experiment: e.name.clone(),
        step: e.steps[0],
        joint: k,
        reason: format!(
            "joint {f} is held while joint {k} is swept, and its command follows cmd_{k} on a straight line, but \
             opposite to the hold-still formula cmd_{f}(s) = cmd_{f}(0) + slope (cmd_{k}(s) - cmd_{k}(0)) (the formula \
             reads the columns cmd_{k} and cmd_{f}; slope {slope}): at {ratio:.4} times the slope (every step within \
             {worst:.4} {} of that line{}): cmd_{k} looks negated on export (the controller's direction of joint {k} \
             turned), or cmd_{f}; check cmd_{k} and cmd_{f} against the controller's readings at two poses and negate \
             the column that differs",
            unit(desc, f - 1),
            lines_words(e.lines).replace("; the sweep's", ", the sweep's"),
        ),
    }
}

/// Why the swept joint's command of `e` does not move, in words: a single step (one row's id
/// mistyped), the joints that move instead (the rows of another joint's sweep: a label or
/// `moved_joint` swapped, blocks of rows out of order), or none (one pose repeated).
fn zero_span_cause(e: &AxisExperiment, desc: &RobotDescription, tolerance: f64) -> String {
    let steps = e.commands.len();
    if steps < 2 {
        return "; the experiment has a single step, a sweep needs several poses (one row's experiment id mistyped?)"
            .into();
    }
    let moving: Vec<(usize, f64)> = (0..desc.dof())
        .map(|j| {
            let (lo, hi) = e
                .commands
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
                    (lo.min(c[j]), hi.max(c[j]))
                });
            (j, hi - lo)
        })
        .filter(|&(_, span)| span > tolerance)
        .collect();
    match moving.first() {
        None => format!("; no joint's command moves over its {steps} steps (one pose repeated)"),
        Some(&(j, _)) => format!(
            "; {} over its {steps} steps: these are the rows of joint {}'s sweep, not joint {}'s (check the experiment id and `moved_joint`: labels swapped, or rows of another sweep)",
            moving
                .iter()
                .map(|&(k, span)| format!("cmd_{} moves by {span:.4} {}", k + 1, unit(desc, k)))
                .collect::<Vec<_>>()
                .join(", "),
            j + 1,
            e.joint
        ),
    }
}

/// Per joint, the median of its held values over every step of the experiments that hold it;
/// for a joint no experiment holds, step 0 of its first sweep.
fn reference_pose(experiments: &[AxisExperiment], n: usize) -> Vec<f64> {
    (0..n)
        .map(|j| {
            let held: Vec<f64> = experiments
                .iter()
                .filter(|e| e.holds_constant(j))
                .flat_map(|e| e.commands.iter().map(move |c| c[j]))
                .collect();
            if held.is_empty() {
                experiments
                    .iter()
                    .find(|e| e.joint == j + 1)
                    .map(|e| e.commands[0][j])
                    .unwrap_or(0.0)
            } else {
                quantile(&held, 0.5, QuantileMethod::Linear)
            }
        })
        .collect()
}

/// The actuator commands (rad or m, the controller's decoupled `u`) of the file commands `cmd`.
pub(super) fn actuator_commands(controller: &Controller, desc: &RobotDescription, cmd: &[f64]) -> Vec<f64> {
    controller
        .decouple(&commands_to_internal(desc, cmd))
        .expect("commands have the description's joint count (checked by MeasurementSet)")
}
