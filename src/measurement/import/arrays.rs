//! Free poses from arrays (a MAT file's variables, [`super::mat_v5`]): a joint array of one row
//! per pose and `N` columns, and one array of one row per pose and 3 columns per target.

use super::mat_v5::{MatArray, MatFile};
use crate::measurement::unit_check::{SLIP_FACTOR, spread_ratio};
use crate::measurement::{Measurement, MeasurementSet, MeasurementSetError, RowProblem, format_f64};
use crate::robot::{RobotDescription, commands_to_file};
use nalgebra::Vector3;
use std::path::{Path, PathBuf};

/// Why arrays do not make free poses.
#[derive(Debug, thiserror::Error)]
pub enum ArraysError {
    /// A named variable is absent.
    #[error("{path}: no variable `{name}` (the file has: {available})")]
    Missing {
        /// The file.
        path: PathBuf,
        /// The variable asked for.
        name: String,
        /// The numeric variables it has.
        available: String,
    },
    /// A variable of that name is there but is no real 2-D matrix (more dimensions, text, a
    /// cell array, ...).
    #[error("{path}: variable `{name}` is not a 2-D real matrix: {why}; expected {expected}")]
    NotAMatrix {
        /// The file.
        path: PathBuf,
        /// The variable.
        name: String,
        /// What it is instead ([`MatFile::skipped`]).
        why: String,
        /// What was expected.
        expected: String,
    },
    /// A variable has the wrong shape.
    #[error("{path}: variable `{name}` is {rows}x{cols}, expected {expected}")]
    Shape {
        /// The file.
        path: PathBuf,
        /// The variable.
        name: String,
        /// Its rows.
        rows: usize,
        /// Its columns.
        cols: usize,
        /// What was expected.
        expected: String,
    },
    /// A value makes a row no measurement takes (a coordinate beyond 10 km, a command beyond
    /// 1e6 deg or mm).
    #[error("{path}: variable `{name}`, row {row}, column {col}: {} as written: {problem}", format_f64(*written))]
    Value {
        /// The file.
        path: PathBuf,
        /// The variable.
        name: String,
        /// 1-based row.
        row: usize,
        /// 1-based column.
        col: usize,
        /// The value in the file.
        written: f64,
        /// What is wrong with it in the measurement CSV's units.
        problem: Box<RowProblem>,
    },
    /// One variable is named for two targets: they would be one point, which no calibration
    /// separates.
    #[error(
        "--targets: variable `{name}` is given twice (targets {first} and {second}): each target is its own point array; name each variable once"
    )]
    Duplicate {
        /// The variable.
        name: String,
        /// The first target id it is given for.
        first: usize,
        /// The second.
        second: usize,
    },
    /// One target variable's points spread a unit slip's factor off the other targets' (see
    /// [`target_unit_slip`]).
    #[error(
        "{path}: variable `{name}`: its points spread {} times as far over the poses as the other targets' ({others}), \
         which ride on the same tool: `{name}` is written in another length unit than they are ({}); write every \
         target variable in one unit (or pass --skip-unit-check if they are right after all)",
        format_f64((*ratio * 1e4).round() / 1e4),
        if *ratio > 1.0 { "a finer one: millimetres among metres?" } else { "a coarser one: metres among millimetres?" }
    )]
    TargetUnit {
        /// The file.
        path: PathBuf,
        /// The variable.
        name: String,
        /// Its spread over the others' median.
        ratio: f64,
        /// The other target variables, as a list.
        others: String,
    },
    /// `--experiment` is no experiment id.
    #[error("--experiment: {problem}")]
    Experiment {
        /// What is wrong with it.
        problem: Box<RowProblem>,
    },
    /// A value is not finite.
    #[error("{path}: variable `{name}`, row {row}, column {col}: {value} is not finite")]
    NotFinite {
        /// The file.
        path: PathBuf,
        /// The variable.
        name: String,
        /// 1-based row.
        row: usize,
        /// 1-based column.
        col: usize,
        /// The value.
        value: f64,
    },
}

/// How the arrays' numbers are read.
#[derive(Clone, Debug, PartialEq)]
pub struct ArrayImport {
    /// The joint array's name.
    pub joints: String,
    /// One point array per target (target ids 0, 1, ... in this order).
    pub targets: Vec<String>,
    /// Revolute joint values are in radians (else degrees).
    pub radians: bool,
    /// Metres per unit of the points and of prismatic joint values.
    pub metres_per_unit: f64,
    /// The experiment id of the poses.
    pub experiment: String,
}

/// Refuses a variable named for two targets.
fn duplicate_target(targets: &[String]) -> Result<(), ArraysError> {
    for (second, name) in targets.iter().enumerate() {
        if let Some(first) = targets[..second].iter().position(|t| t == name) {
            return Err(ArraysError::Duplicate {
                name: name.clone(),
                first,
                second,
            });
        }
    }
    Ok(())
}

/// The free poses of `file` (read from `path`) for the robot `desc`: pose `i` is row `i` of
/// every array, step `i` of one experiment.
pub fn free_poses(
    file: &MatFile,
    path: &Path,
    desc: &RobotDescription,
    how: &ArrayImport,
) -> Result<MeasurementSet, ArraysError> {
    duplicate_target(&how.targets)?;
    let joints = array(file, path, &how.joints, None, desc.dof())?;
    let poses = joints.rows;
    let points: Vec<&MatArray> = how
        .targets
        .iter()
        .map(|name| array(file, path, name, Some(poses), 3))
        .collect::<Result<_, _>>()?;
    let mut rows = Vec::with_capacity(poses * points.len());
    for i in 0..poses {
        let internal: Vec<f64> = (0..desc.dof())
            .map(|k| joint_internal(desc, k, joints.get(i, k), how))
            .collect();
        let cmd = commands_to_file(desc, &internal);
        for (target, p) in points.iter().enumerate() {
            let mm = |c: usize| p.get(i, c) * how.metres_per_unit * 1e3;
            rows.push(Measurement {
                experiment: how.experiment.clone(),
                moved_joint: 0,
                step: i,
                target,
                position_mm: [mm(0), mm(1), mm(2)],
                cmd: cmd.clone(),
                payload_kg: Measurement::DEFAULT_PAYLOAD_KG,
                temperature_c: Measurement::DEFAULT_TEMPERATURE_C,
            });
        }
    }
    MeasurementSet::new(desc.dof(), rows).map_err(|e| in_file_terms(e, path, how, joints, &points))
}

/// `e`, a row built from the arrays that breaks a rule of the measurement CSV (a value out of
/// range, an experiment id that is none), in the file's terms: the variable, its row and
/// column and the value as written; `--experiment` for the id. Row `r` is pose
/// `r / targets`, target `r % targets`.
fn in_file_terms(
    e: MeasurementSetError,
    path: &Path,
    how: &ArrayImport,
    joints: &MatArray,
    points: &[&MatArray],
) -> ArraysError {
    let (pose, target) = (e.row / points.len(), e.row % points.len());
    let column = e.problem.column();
    let (name, array, col) = match column.strip_prefix("cmd_").and_then(|k| k.parse::<usize>().ok()) {
        Some(k) => (&how.joints, joints, k - 1),
        None => match ["x_mm", "y_mm", "z_mm"].iter().position(|a| *a == column) {
            Some(c) => (&how.targets[target], points[target], c),
            None => {
                return ArraysError::Experiment {
                    problem: Box::new(e.problem),
                };
            }
        },
    };
    ArraysError::Value {
        path: path.to_owned(),
        name: name.clone(),
        row: pose + 1,
        col: col + 1,
        written: array.get(pose, col),
        problem: Box::new(e.problem),
    }
}

/// Joint `k`'s value in internal units (rad or m).
fn joint_internal(desc: &RobotDescription, k: usize, v: f64, how: &ArrayImport) -> f64 {
    match desc.joints[k].kind {
        crate::kinematics::JointKind::Revolute if how.radians => v,
        crate::kinematics::JointKind::Revolute => v.to_radians(),
        crate::kinematics::JointKind::Prismatic => v * how.metres_per_unit,
    }
}

/// The variable `name`, checked: `rows` rows (any when `None`), `cols` columns, finite.
fn array<'a>(
    file: &'a MatFile,
    path: &Path,
    name: &str,
    rows: Option<usize>,
    cols: usize,
) -> Result<&'a MatArray, ArraysError> {
    let expected = || match rows {
        Some(r) => format!("{r}x{cols} (one row per pose)"),
        None => format!("one row per pose and {cols} columns"),
    };
    let a = file
        .array(name)
        .ok_or_else(|| match file.skipped.iter().find(|(n, _)| n == name) {
            Some((_, why)) => ArraysError::NotAMatrix {
                path: path.to_owned(),
                name: name.into(),
                why: why.clone(),
                expected: expected(),
            },
            None => ArraysError::Missing {
                path: path.to_owned(),
                name: name.into(),
                available: file
                    .arrays
                    .iter()
                    .map(|a| a.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            },
        })?;
    if a.cols != cols || rows.is_some_and(|r| r != a.rows) || a.rows == 0 {
        return Err(ArraysError::Shape {
            path: path.to_owned(),
            name: name.into(),
            rows: a.rows,
            cols: a.cols,
            expected: expected(),
        });
    }
    for row in 0..a.rows {
        for col in 0..a.cols {
            let value = a.get(row, col);
            if !value.is_finite() {
                return Err(ArraysError::NotFinite {
                    path: path.to_owned(),
                    name: name.into(),
                    row: row + 1,
                    col: col + 1,
                    value,
                });
            }
        }
    }
    Ok(a)
}

/// The target variable of `set` (imported by [`free_poses`] from `path` with `targets`) whose
/// points spread more than [`SLIP_FACTOR`] times as far (or as little) over the poses as the
/// median target's ([`spread_ratio`]): targets on one tool move together, their spreads
/// differing by the tool's size at most, so such a target's variable is in another unit.
/// Judged with three targets or more (two cannot tell which one slipped).
pub fn target_unit_slip(set: &MeasurementSet, path: &Path, targets: &[String]) -> Result<(), ArraysError> {
    if targets.len() < 3 {
        return Ok(());
    }
    let points = |t: usize| -> Vec<Vector3<f64>> {
        set.rows()
            .iter()
            .filter(|m| m.target == t)
            .map(|m| Vector3::from(m.position_mm))
            .collect()
    };
    let first = points(0);
    let ratios: Vec<f64> = (0..targets.len())
        .map(|t| spread_ratio(&points(t), &first).unwrap_or(1.0))
        .collect();
    let mut sorted = ratios.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let Some((t, ratio)) = ratios
        .iter()
        .map(|r| r / median)
        .enumerate()
        .find(|(_, r)| r.ln().abs() > SLIP_FACTOR.ln())
    else {
        return Ok(());
    };
    let others: Vec<String> = (0..targets.len())
        .filter(|&o| o != t)
        .map(|o| format!("`{}`", targets[o]))
        .collect();
    Err(ArraysError::TargetUnit {
        path: path.to_owned(),
        name: targets[t].clone(),
        ratio,
        others: others.join(", "),
    })
}
