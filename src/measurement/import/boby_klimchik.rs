//! The public laser-tracker data of Boby & Klimchik ("Combination of Geometric and Parametric
//! Approaches for Kinematic Identification of an Industrial Robot", RCIM; repository
//! `RABKKK/LaserTrackerPoseData4KinIdent`), file `N1N2N3Jval.csv`.
//!
//! Source format: no header; one pose per line, 21 white-space separated numbers: x, y, z of
//! three tracker targets (SMRs) on the end-effector \[mm, tracker frame\], six zeros, and the
//! controller's joint readings J1..J6 \[deg\]. Six blocks of six lines, one block per joint
//! moved alone, in the order J1..J6.
//!
//! Conversion (`docs/formats.md#measurement-csv`): block `k` becomes experiment `axis{k}` with
//! `moved_joint = k`, steps in file order, targets 0, 1, 2 = SMRs 2, 3, 1 ([`SMR_OF_TARGET`]):
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
//! by `-J2`, which the data contradict; see the worked example in `docs/validation.md`.)

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
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A line has the wrong number of fields.
    #[error("{path}:{line}: {found} fields, expected {FIELDS_PER_LINE} (9 target coordinates, 6 zeros, J1..J6)")]
    FieldCount {
        /// The file.
        path: PathBuf,
        /// Line.
        line: usize,
        /// Fields found.
        found: usize,
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
    /// The file does not have six blocks of six poses.
    #[error("{path}: {found} data lines, expected {LINES} (six blocks of six poses, one block per joint)")]
    LineCount {
        /// The file.
        path: PathBuf,
        /// Data lines found.
        found: usize,
    },
    /// The converted rows break a measurement-set invariant.
    #[error("{path}: {source}")]
    Set {
        /// The file.
        path: PathBuf,
        /// The invariant broken.
        source: MeasurementSetError,
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

/// Parses the text of `N1N2N3Jval.csv` (`path` only names it in errors).
pub fn parse(text: &str, path: &Path) -> Result<MeasurementSet, ImportError> {
    let mut rows = Vec::with_capacity(LINES * TARGETS);
    let mut pose = 0;
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
            });
        }
        let values: Vec<f64> = fields
            .iter()
            .enumerate()
            .map(|(f, t)| {
                t.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| ImportError::NotANumber {
                        path: path.into(),
                        line: i + 1,
                        field: f + 1,
                        meaning: meaning(f + 1),
                        text: (*t).to_owned(),
                    })
            })
            .collect::<Result<_, _>>()?;
        let joint = pose / POSES_PER_BLOCK + 1;
        let mut j_deg = [0.0; JOINTS];
        j_deg.copy_from_slice(&values[FIRST_JOINT_FIELD..]);
        let cmd = commands_from_readings(&j_deg).to_vec();
        for (t, smr) in SMR_OF_TARGET.iter().enumerate() {
            rows.push(Measurement {
                experiment: format!("axis{joint}"),
                moved_joint: joint,
                step: pose % POSES_PER_BLOCK,
                target: t,
                position_mm: {
                    let f = 3 * (smr - 1);
                    [values[f], values[f + 1], values[f + 2]]
                },
                cmd: cmd.clone(),
                payload_kg: Measurement::DEFAULT_PAYLOAD_KG,
                temperature_c: Measurement::DEFAULT_TEMPERATURE_C,
            });
        }
        pose += 1;
    }
    if pose != LINES {
        return Err(ImportError::LineCount {
            path: path.into(),
            found: pose,
        });
    }
    MeasurementSet::new(JOINTS, rows).map_err(|source| ImportError::Set {
        path: path.into(),
        source,
    })
}

/// Reads `DIR/N1N2N3Jval.csv` of the data set's folder `dir`.
pub fn import_dir(dir: &Path) -> Result<MeasurementSet, ImportError> {
    let path = dir.join(DATA_FILE);
    let text = crate::presets::read_text(&path).map_err(|source| ImportError::Io {
        path: path.clone(),
        source,
    })?;
    parse(&text, &path)
}

/// The comment lines the importer writes above the CSV header (`docs/formats.md#measurement-csv`: `#` lines are
/// comments), recording the source and the joint-3 conversion.
pub fn provenance_comment(source: &Path) -> String {
    format!(
        "# imported by `axiscal import boby-klimchik` from {}\n\
         # targets 0,1,2 = SMRs 2,3,1; cmd_k = controller J_k, except cmd_3 = J3 + J2 (J3 is read against the ground)\n",
        source.display()
    )
}

#[cfg(test)]
mod tests;
