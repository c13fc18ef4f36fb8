//! The public laser-tracker data of Boby & Klimchik ("Combination of Geometric and Parametric
//! Approaches for Kinematic Identification of an Industrial Robot", RCIM; repository
//! `RABKKK/LaserTrackerPoseData4KinIdent`), file `N1N2N3Jval.csv`.
//!
//! Source format: no header; one pose per line, 21 white-space separated numbers: x, y, z of
//! three tracker targets (SMRs) on the end-effector \[mm, tracker frame\], six zeros, and the
//! controller's joint readings J1..J6 \[deg\]. Six blocks of six lines, one block per joint
//! moved alone (the published file's order is J1..J6; a copy with its blocks reordered reads
//! the same, each block named by the joint that moves in it).
//!
//! Conversion (`docs/formats.md#measurement-csv`): the block moving joint `k` becomes experiment
//! `axis{k}` with `moved_joint = k`, steps in file order, targets 0, 1, 2 = SMRs 2, 3, 1 ([`SMR_OF_TARGET`]):
//! the procedure fits each axis to target 0, and SMR 1 sits within about 2 mm of axes 4 and 6
//! (its J4 and J6 arcs have a radius near 1.5 mm and would fix those axes' directions only to
//! tens of milliradians), while SMR 2 turns on radii of 0.2 m or more about every axis.
//! The commands are the joint readings, except joint 3:
//!
//! **The J2/J3 coupled reading.** In the J2 block the controller reads `J3 = -J2`, yet the
//! three SMRs turn rigidly about axis 2 by the full J2 span (80.0 deg of tool rotation for
//! 80 deg of J2; the distances between the SMRs stay within 0.1 mm): the forearm keeps its
//! angle to the upper arm. The controller's J3 is therefore measured against the ground
//! (the Fanuc-style J2/J3 interaction), and the forearm's angle to the upper arm, the phi-model
//! joint value of joint 3, is `J3 + J2` (constant in the J2 block, `J3` in the J3 block where
//! `J2 = 0`). `docs/formats.md#controller-semantics` requires that an error-free robot reach its commands as
//! phi-model joint values, so the importer writes this kinematic dependency into the command:
//! `cmd_3 = J3 + J2`. (Keeping `cmd_3 = J3` with a nominal 2->3 coupling of slope -1 would
//! make the controller hold actuator 3 still, as here, but would also move joint 3 passively
//! by `-J2`, which the data contradict; see the worked example in `docs/real-data.md`.)

use super::super::{Measurement, MeasurementSet, MeasurementSetError};
use std::path::{Path, PathBuf};

/// The data file inside the data set's folder.
pub const DATA_FILE: &str = "N1N2N3Jval.csv";
/// Numbers per line.
pub const FIELDS_PER_LINE: usize = 21;
/// Joints of the arm.
pub const JOINTS: usize = 6;
/// Poses per joint block.
pub const POSES_PER_BLOCK: usize = 6;
/// Lines of the file: one block per joint.
pub const LINES: usize = JOINTS * POSES_PER_BLOCK;
/// SMRs observed at every pose.
pub const TARGETS: usize = 3;
/// The SMR (1-based, the file's order) written as target 0, 1, 2.
pub const SMR_OF_TARGET: [usize; TARGETS] = [2, 3, 1];
/// 0-based field of J1 (fields 16..=21, 1-based, are J1..J6).
const FIRST_JOINT_FIELD: usize = 15;

/// Why the file could not be imported. Line and field numbers are 1-based.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// The path given as the data set's folder is a file.
    #[error(
        "{path} is a file; import boby-klimchik takes the data set's folder (the one holding {DATA_FILE}); pass that folder"
    )]
    NotAFolder {
        /// The path given.
        path: PathBuf,
    },
    /// The file could not be read.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        cause: std::io::Error,
    },
    /// A line has the wrong number of fields.
    #[error(
        "{path}:{line}: {found} fields, expected {FIELDS_PER_LINE} (9 target coordinates, 6 zeros, J1..J6){}",
        separator.map_or(String::new(), |s| format!(
            ": the numbers are separated by {s}, where the data set separates them by spaces (write the file back \
             with spaces between the numbers)"
        ))
    )]
    FieldCount {
        /// The file.
        path: PathBuf,
        /// Line.
        line: usize,
        /// Fields found.
        found: usize,
        /// Another separator that splits the line into the expected fields (`` `,` ``), in words.
        separator: Option<&'static str>,
    },
    /// A field is not a finite number.
    #[error("{path}:{line}: field {field} ({meaning}): {text:?} is not a finite number")]
    NotANumber {
        /// The file.
        path: PathBuf,
        /// Line.
        line: usize,
        /// Field.
        field: usize,
        /// What the field holds, e.g. `SMR 2 y_mm` or `J4 deg`.
        meaning: String,
        /// The text.
        text: String,
    },
    /// A field is a number no instrument or joint reads (a coordinate beyond 10 km, a joint
    /// reading beyond 2,800 turns).
    #[error("{path}:{line}: field {field} ({meaning}): {value:e} is outside {range}")]
    OutOfRange {
        /// The file.
        path: PathBuf,
        /// Line.
        line: usize,
        /// Field.
        field: usize,
        /// What the field holds.
        meaning: String,
        /// The value.
        value: f64,
        /// The range it leaves, in words.
        range: &'static str,
    },
    /// The file does not have six blocks of six poses.
    #[error("{path}: {found} data lines, expected {LINES} (six blocks of six poses, one block per joint)")]
    LineCount {
        /// The file.
        path: PathBuf,
        /// Data lines found.
        found: usize,
    },
    /// A block of poses does not move one joint of its own.
    #[error("{path}: lines {}-{} (block {block}): {message}", lines.0, lines.1)]
    Block {
        /// The file.
        path: PathBuf,
        /// The block (1-based).
        block: usize,
        /// Its first and last line.
        lines: (usize, usize),
        /// What is wrong.
        message: String,
    },
    /// The converted rows break a measurement-set invariant.
    #[error("{path}: {cause}")]
    Set {
        /// The file.
        path: PathBuf,
        /// The invariant broken.
        cause: MeasurementSetError,
    },
}

/// What field `field` (1-based) of a line holds.
fn meaning(field: usize) -> String {
    match field {
        1..=9 => format!("SMR {} {}_mm", (field - 1) / 3 + 1, ["x", "y", "z"][(field - 1) % 3]),
        10..=15 => "zero".into(),
        _ => format!("J{} deg", field - FIRST_JOINT_FIELD),
    }
}

/// Phi-model joint values \[deg\] from the controller's readings: joint 3 relative to the
/// upper arm is `J3 + J2` (see the module docs).
pub fn commands_from_readings(j_deg: &[f64; JOINTS]) -> [f64; JOINTS] {
    let mut cmd = *j_deg;
    cmd[2] = j_deg[2] + j_deg[1];
    cmd
}

/// Parses the text of `N1N2N3Jval.csv` (`path` only names it in errors). Each block's joint
/// is the one whose command moves in it, so blocks in another order import as what they are.
pub fn parse(text: &str, path: &Path) -> Result<MeasurementSet, ImportError> {
    let poses = read_poses(text, path)?;
    let joints = block_joints(&poses, path)?;
    let mut rows = Vec::with_capacity(LINES * TARGETS);
    for (pose, (_, values)) in poses.iter().enumerate() {
        let joint = joints[pose / POSES_PER_BLOCK];
        for (t, smr) in SMR_OF_TARGET.iter().enumerate() {
            let f = 3 * (smr - 1);
            rows.push(Measurement {
                experiment: format!("axis{joint}"),
                moved_joint: joint,
                step: pose % POSES_PER_BLOCK,
                target: t,
                position_mm: [values[f], values[f + 1], values[f + 2]],
                cmd: commands(values).to_vec(),
                payload_kg: Measurement::DEFAULT_PAYLOAD_KG,
                temperature_c: Measurement::DEFAULT_TEMPERATURE_C,
            });
        }
    }
    MeasurementSet::new(JOINTS, rows).map_err(|source| ImportError::Set {
        path: path.into(),
        cause: source,
    })
}

/// The separator other than white space (`,`, `;`, `|`) that splits `line` into exactly
/// [`FIELDS_PER_LINE`] fields, in words: a file written back with another separator.
fn other_separator(line: &str) -> Option<&'static str> {
    [(',', "`,`"), (';', "`;`"), ('|', "`|`")]
        .into_iter()
        .find(|(c, _)| line.split(*c).count() == FIELDS_PER_LINE)
        .map(|(_, words)| words)
}

/// One pose of the file: its 1-based line and its numbers.
type Pose = (usize, [f64; FIELDS_PER_LINE]);

/// The file's poses, each line checked; exactly [`LINES`] of them.
fn read_poses(text: &str, path: &Path) -> Result<Vec<Pose>, ImportError> {
    let mut poses = Vec::with_capacity(LINES);
    for (i, line) in text.lines().enumerate() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.is_empty() {
            continue;
        }
        if fields.len() != FIELDS_PER_LINE {
            return Err(ImportError::FieldCount {
                path: path.into(),
                line: i + 1,
                found: fields.len(),
                separator: other_separator(line),
            });
        }
        let mut values = [0.0; FIELDS_PER_LINE];
        for (f, (t, v)) in fields.iter().zip(&mut values).enumerate() {
            *v = t
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| ImportError::NotANumber {
                    path: path.into(),
                    line: i + 1,
                    field: f + 1,
                    meaning: meaning(f + 1),
                    text: (*t).to_owned(),
                })?;
            let beyond = match f + 1 {
                1..=9 => crate::measurement::data::coordinate_beyond(*v),
                10..=15 => None,
                _ => crate::measurement::data::command_beyond(*v),
            };
            if let Some(range) = beyond {
                return Err(ImportError::OutOfRange {
                    path: path.into(),
                    line: i + 1,
                    field: f + 1,
                    meaning: meaning(f + 1),
                    value: *v,
                    range,
                });
            }
        }
        poses.push((i + 1, values));
    }
    if poses.len() != LINES {
        return Err(ImportError::LineCount {
            path: path.into(),
            found: poses.len(),
        });
    }
    Ok(poses)
}

/// The phi-model commands of a pose's numbers ([`commands_from_readings`]).
fn commands(values: &[f64; FIELDS_PER_LINE]) -> [f64; JOINTS] {
    let mut j_deg = [0.0; JOINTS];
    j_deg.copy_from_slice(&values[FIRST_JOINT_FIELD..]);
    commands_from_readings(&j_deg)
}

/// A joint whose commands within one block differ by no more than this \[deg\] holds still:
/// the file writes its readings with 18 significant digits, so a held joint reads one number.
const STILL_DEG: f64 = 1e-9;

/// The joint (1-based) each block of [`POSES_PER_BLOCK`] poses moves: the one whose command
/// moves in it. A block moving no joint or several, or two blocks moving one joint, is an error
/// naming their lines.
fn block_joints(poses: &[Pose], path: &Path) -> Result<Vec<usize>, ImportError> {
    let mut joints: Vec<usize> = Vec::with_capacity(JOINTS);
    for (b, block) in poses.chunks(POSES_PER_BLOCK).enumerate() {
        let lines = (block[0].0, block[block.len() - 1].0);
        let cmd: Vec<[f64; JOINTS]> = block.iter().map(|(_, v)| commands(v)).collect();
        let spans: Vec<(usize, f64)> = (0..JOINTS)
            .map(|k| {
                let (lo, hi) = cmd.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
                    (lo.min(c[k]), hi.max(c[k]))
                });
                (k + 1, hi - lo)
            })
            .filter(|&(_, span)| span > STILL_DEG)
            .collect();
        let problem = match spans.as_slice() {
            [] => Some("no joint moves in this block (each block of six poses moves one joint alone)".to_owned()),
            [(joint, _)] => joints.iter().position(|j| j == joint).map(|earlier| {
                let first = poses[earlier * POSES_PER_BLOCK].0;
                format!(
                    "this block moves J{joint}, as the block of lines {first}-{} did: each joint has one block",
                    first + POSES_PER_BLOCK - 1
                )
            }),
            several => Some(format!(
                "{} move in one block (each block of six poses moves one joint alone; J3 is compared as J3 + J2)",
                several
                    .iter()
                    .map(|(j, span)| format!("J{j} by {span:.3} deg"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        };
        if let Some(message) = problem {
            return Err(ImportError::Block {
                path: path.into(),
                block: b + 1,
                lines,
                message,
            });
        }
        joints.push(spans[0].0);
    }
    Ok(joints)
}

/// Reads `DIR/N1N2N3Jval.csv` of the data set's folder `dir`.
pub fn import_dir(dir: &Path) -> Result<MeasurementSet, ImportError> {
    if dir.is_file() {
        return Err(ImportError::NotAFolder { path: dir.to_owned() });
    }
    let path = dir.join(DATA_FILE);
    let text = crate::presets::read_text(&path).map_err(|source| ImportError::Io {
        path: path.clone(),
        cause: source,
    })?;
    parse(&text, &path)
}

/// The comment lines the importer writes above the CSV header (`docs/formats.md#measurement-csv`: `#` lines are
/// comments), recording the source and the joint-3 conversion.
pub fn provenance_comment(source: &Path) -> String {
    format!(
        "# imported by `axiscal import boby-klimchik` from {}\n\
         # targets 0,1,2 = SMRs 2,3,1; cmd_k = controller J_k, except cmd_3 = J3 + J2 (J3 is read against the ground)\n",
        crate::csv_lines::one_line(&source.display().to_string())
    )
}

#[cfg(test)]
mod tests;
