//! The UR ROS driver's `kinematics.yaml` (ur_description's `config/<ur_type>/default_kinematics.yaml`,
//! the file `ur_calibration` extracts from a robot): under `kinematics`, six segments
//! `shoulder`, `upper_arm`, `forearm`, `wrist_1`, `wrist_2`, `wrist_3`, each the origin of its
//! joint (`shoulder_pan_joint` .. `wrist_3_joint`) in the parent link as URDF `xyz` (`x`, `y`,
//! `z`, m) and `rpy` (`roll`, `pitch`, `yaw`, rad, `R = Rz(yaw) Ry(pitch) Rx(roll)`), every
//! joint turning about its +Z; and `hash`, the checksum of the controller's own calibration the
//! file belongs to: the driver compares it with the connected robot's and warns when they
//! differ.
//!
//! ur_description roots the arm in `base_link`, with `base_link_inertia` turned by pi about Z
//! (the controller's base frame) as the shoulder's parent; `tool0` coincides with
//! `wrist_3_link` (its two fixed turns, via `flange`, cancel). The file has no tool: the
//! calibrated tool frame is reported as a TCP in `tool0`.

use super::chain::{ChainJoint, OriginChain, Unrepresented, reading_chain};
use super::{ChainDeviation, LinkFrames, anchored, deviation, from_xyz_rpy, link_frames, xyz_rpy, yaml_float};
use crate::calibration::procedure::Calibration;
use crate::kinematics::JointKind;
use crate::robot::RobotDescription;
use nalgebra::{Isometry3, Vector3};
use std::fmt::Write as _;
use yaml_rust2::Yaml;

/// The segment names, base first.
pub const SEGMENTS: [&str; 6] = ["shoulder", "upper_arm", "forearm", "wrist_1", "wrist_2", "wrist_3"];

/// The keys of a segment: `xyz` then `rpy`.
const KEYS: [&str; 6] = ["x", "y", "z", "roll", "pitch", "yaw"];

/// The longest a segment's offset \[m\] of a UR arm may be: the longest link of the family
/// (UR20's and UR30's upper arm, 0.86 m; UR5e's 0.425 m) with room for other six-axis arms a
/// driver file may describe. Offsets in millimetres are hundreds of times longer.
pub const MAX_SEGMENT_M: f64 = 5.0;

/// The largest magnitude \[rad\] of a segment's `roll`, `pitch` or `yaw`: a turn. The driver
/// and `ur_calibration` write them within (-pi, pi]; degrees (90, 180) lie beyond.
pub const MAX_ANGLE_RAD: f64 = std::f64::consts::TAU;

/// What is wrong with a UR kinematics file or export.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum UrError {
    /// Not YAML at all.
    #[error("{file}: not YAML: {message}")]
    Yaml {
        /// The file.
        file: String,
        /// The parser's message.
        message: String,
    },
    /// A key missing or not what it must be.
    #[error("{file}: `{key}`: {problem}")]
    Key {
        /// The file.
        file: String,
        /// The key path (`kinematics.upper_arm.roll`).
        key: String,
        /// What is wrong.
        problem: String,
    },
    /// The robot is not a six-revolute arm.
    #[error("the UR kinematics holds six revolute joints; the robot description has {0}")]
    NotSixRevolute(String),
    /// A hash that is not one plain word.
    #[error(
        "{given_by}: the hash `{hash}` must be letters, digits and `_` (as `calib_12788084448423163542`): write it so, or give --hash"
    )]
    Hash {
        /// Where it was given: `--hash`, or the reference file and its key.
        given_by: String,
        /// The hash as given.
        hash: String,
    },
    /// The reference's link frames cannot be kept.
    #[error("the reference kinematics: {0}")]
    Anchor(super::AnchorError),
    /// The file read back does not reproduce the calibrated model (a defect of the export).
    #[error(
        "the written kinematics read back misses the calibrated model by {position_m:e} m and {rotation_rad:e} rad (more than 1e-9): not written"
    )]
    RoundTrip {
        /// Largest position difference \[m\].
        position_m: f64,
        /// Largest orientation difference \[rad\].
        rotation_rad: f64,
    },
}

/// A UR `kinematics.yaml`: the six joint origins and the hash.
#[derive(Clone, Debug, PartialEq)]
pub struct UrKinematics {
    /// Per segment (base first): `x, y, z, roll, pitch, yaw` (m, rad).
    pub segments: [[f64; 6]; 6],
    /// The `hash` value.
    pub hash: String,
    /// The file it was read from, as errors name it.
    pub file: String,
}

/// `base_link_inertia` in `base_link`: a turn by pi about Z.
fn base_link_from_inertia() -> Isometry3<f64> {
    Isometry3::rotation(Vector3::z() * std::f64::consts::PI)
}

fn key_error(file: &str, key: String, problem: impl Into<String>) -> UrError {
    UrError::Key {
        file: file.into(),
        key,
        problem: problem.into(),
    }
}

/// A number of the file (YAML float or integer).
fn number(node: &Yaml, file: &str, key: String) -> Result<f64, UrError> {
    let v = match node {
        Yaml::Real(text) => text.parse::<f64>().ok(),
        Yaml::Integer(i) => Some(*i as f64),
        Yaml::BadValue => return Err(key_error(file, key, "missing")),
        _ => None,
    };
    match v {
        Some(v) if v.is_finite() => Ok(v),
        _ => Err(key_error(file, key, format!("must be a finite number, found {node:?}"))),
    }
}

/// Refuses a hash that is not one plain YAML word; `given_by` says where it was given.
fn checked_hash(hash: &str, given_by: impl Into<String>) -> Result<String, UrError> {
    if !hash.is_empty() && hash.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        Ok(hash.to_string())
    } else {
        Err(UrError::Hash {
            given_by: given_by.into(),
            hash: crate::csv_lines::shown_cell(hash),
        })
    }
}

/// Refuses segments in other units than the driver's (m, rad): an offset beyond
/// [`MAX_SEGMENT_M`] (millimetres) or an angle beyond [`MAX_ANGLE_RAD`] (degrees), naming the
/// largest.
fn units(segments: &[[f64; 6]; 6], file: &str) -> Result<(), UrError> {
    let largest = |keys: std::ops::Range<usize>| {
        let mut all = segments
            .iter()
            .enumerate()
            .flat_map(|(s, v)| keys.clone().map(move |k| (s, k, v[k])));
        let first = all.next()?;
        Some(all.fold(first, |m, c| if c.2.abs() > m.2.abs() { c } else { m }))
    };
    let key = |(s, k, _): (usize, usize, f64)| format!("kinematics.{}.{}", SEGMENTS[s], KEYS[k]);
    if let Some(l) = largest(0..3).filter(|l| l.2.abs() > MAX_SEGMENT_M) {
        return Err(key_error(
            file,
            key(l),
            format!(
                "{} m is longer than any arm's link (at most {MAX_SEGMENT_M} m): x, y, z look like mm (the driver's file is in m); divide them by 1000",
                super::yaml_float(l.2)
            ),
        ));
    }
    if let Some(a) = largest(3..6).filter(|a| a.2.abs() > MAX_ANGLE_RAD) {
        return Err(key_error(
            file,
            key(a),
            format!(
                "{} rad is more than a turn: roll, pitch, yaw look like degrees (the driver's file is in rad); convert them to radians",
                super::yaml_float(a.2)
            ),
        ));
    }
    Ok(())
}

impl UrKinematics {
    /// Reads the text of a `kinematics.yaml`; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Self, UrError> {
        let docs = crate::yaml_file::load(text).map_err(|e| UrError::Yaml {
            file: file.into(),
            message: e.to_string(),
        })?;
        let root = docs.first().unwrap_or(&Yaml::BadValue);
        if root.as_hash().is_none() {
            let what = if crate::toml_file::looks_like_csv(text) {
                "a CSV table"
            } else {
                "not a YAML mapping of keys"
            };
            return Err(key_error(
                file,
                "kinematics".into(),
                format!(
                    "missing: the file is {what}, not the UR driver's calibration YAML (a `kinematics:` mapping of six segments, as ur_calibration writes)"
                ),
            ));
        }
        let kin = &root["kinematics"];
        if kin.as_hash().is_none() {
            return Err(key_error(
                file,
                "kinematics".into(),
                "missing (the UR driver's file has its six segments under it)",
            ));
        }
        let mut segments = [[0.0; 6]; 6];
        for (s, name) in SEGMENTS.iter().enumerate() {
            for (i, key) in KEYS.iter().enumerate() {
                segments[s][i] = number(&kin[*name][*key], file, format!("kinematics.{name}.{key}"))?;
            }
        }
        units(&segments, file)?;
        let hash = match &kin["hash"] {
            Yaml::String(h) => h.clone(),
            Yaml::Integer(i) => i.to_string(),
            Yaml::BadValue => String::new(),
            other => {
                return Err(key_error(
                    file,
                    "kinematics.hash".into(),
                    format!("must be a word, found {other:?}"),
                ));
            }
        };
        Ok(Self {
            segments,
            hash,
            file: file.into(),
        })
    }

    /// The chain the file describes, rooted in `base_link`, joint variables the controller's
    /// readings, the tool at `tool0` (= `wrist_3_link`).
    pub fn chain(&self) -> OriginChain {
        let joints = self
            .segments
            .iter()
            .enumerate()
            .map(|(s, v)| ChainJoint {
                kind: JointKind::Revolute,
                parent_from_joint: if s == 0 {
                    base_link_from_inertia() * from_xyz_rpy(*v)
                } else {
                    from_xyz_rpy(*v)
                },
            })
            .collect();
        OriginChain {
            joints,
            last_link_from_tool: Isometry3::identity(),
            world_from_root: Isometry3::identity(),
        }
    }

    /// The file of a six-revolute chain rooted in `base_link`.
    fn of_chain(chain: &OriginChain, hash: String) -> Self {
        let mut segments = [[0.0; 6]; 6];
        for (s, joint) in chain.joints.iter().enumerate() {
            let origin = if s == 0 {
                base_link_from_inertia().inverse() * joint.parent_from_joint
            } else {
                joint.parent_from_joint
            };
            segments[s] = xyz_rpy(&origin);
        }
        Self {
            segments,
            hash,
            file: "the written file".into(),
        }
    }

    /// The YAML text (`comments` first, each line prefixed `# `, its control characters escaped),
    /// numbers exact.
    pub fn to_yaml(&self, comments: &[String]) -> String {
        let mut s = String::new();
        for line in comments {
            let _ = writeln!(s, "# {}", crate::csv_lines::one_line(line));
        }
        let _ = writeln!(s, "kinematics:");
        for (name, values) in SEGMENTS.iter().zip(&self.segments) {
            let _ = writeln!(s, "  {name}:");
            for (key, v) in KEYS.iter().zip(values) {
                let _ = writeln!(s, "    {key}: {}", yaml_float(*v));
            }
        }
        let _ = writeln!(s, "  hash: {}", self.hash);
        s
    }
}

/// A calibration written as a UR `kinematics.yaml`.
#[derive(Clone, Debug, PartialEq)]
pub struct UrExport {
    /// The file's values.
    pub kinematics: UrKinematics,
    /// The reference's link frames the file keeps.
    pub frames: LinkFrames,
    /// What the file does not hold (empty: exact).
    pub left_out: Vec<Unrepresented>,
    /// The file read back against the calibrated model (tool at the TCP).
    pub deviation: ChainDeviation,
    /// The calibrated tool frame in `tool0`: the TCP to set on the controller.
    pub tool0_from_tcp: Isometry3<f64>,
    /// `base_link` in the instrument frame.
    pub world_from_base_link: Isometry3<f64>,
}

/// `cal` as a UR `kinematics.yaml` with the link frames of `reference` (the robot's current
/// file) and `hash` (default the reference's). Zero offsets go into the origins; what a UR
/// file cannot hold is listed in [`UrExport::left_out`]. Fails when the robot is not six
/// revolute joints, the reference does not fit the description, or the file read back misses
/// the calibrated model (beyond what it left out).
pub fn export(
    cal: &Calibration,
    desc: &RobotDescription,
    reference: &UrKinematics,
    hash: Option<&str>,
) -> Result<UrExport, UrError> {
    if desc.dof() != 6 || desc.joints.iter().any(|j| j.kind != JointKind::Revolute) {
        let kinds: Vec<String> = desc
            .joints
            .iter()
            .map(|j| format!("{:?}", j.kind).to_lowercase())
            .collect();
        return Err(UrError::NotSixRevolute(format!(
            "{} ({})",
            desc.dof(),
            kinds.join(", ")
        )));
    }
    let hash = match hash {
        Some(h) => checked_hash(h, "--hash")?,
        None if reference.hash.is_empty() => {
            return Err(key_error(
                &reference.file,
                "kinematics.hash".into(),
                "missing: give --hash (the checksum of the controller's own calibration, as the robot's file holds it)",
            ));
        }
        None => checked_hash(&reference.hash, format!("{}: `kinematics.hash`", reference.file))?,
    };
    let (chain, left_out) = reading_chain(cal, desc);
    let nominal = OriginChain::of_phi_model(&desc.nominal_model());
    let frames = link_frames(&nominal, &reference.chain())?;
    frames.check_same_robot()?;
    let written = anchored(&chain, &frames);
    let kinematics = UrKinematics::of_chain(&written, hash);
    let mut read_back = UrKinematics::parse(&kinematics.to_yaml(&[]), "the written file")?.chain();
    read_back.last_link_from_tool = written.last_link_from_tool;
    read_back.world_from_root = written.world_from_root;
    let dev = deviation(&read_back, cal, desc, |u| u.to_vec());
    if left_out.is_empty() && !dev.is_exact() {
        return Err(UrError::RoundTrip {
            position_m: dev.max_position_m,
            rotation_rad: dev.max_rotation_rad,
        });
    }
    Ok(UrExport {
        kinematics,
        tool0_from_tcp: written.last_link_from_tool,
        world_from_base_link: written.world_from_root,
        frames,
        left_out,
        deviation: dev,
    })
}

/// A pose as the UR controller writes one, `p[x, y, z, rx, ry, rz]` (m, rotation vector in
/// rad), each number the shortest text that reads back to the same float.
pub fn ur_pose(t: &Isometry3<f64>) -> String {
    let v = t.translation.vector;
    let r = t.rotation.scaled_axis();
    let n: Vec<String> = [v.x, v.y, v.z, r.x, r.y, r.z]
        .iter()
        .map(|x| crate::measurement::format_f64(x + 0.0))
        .collect();
    format!("p[{}]", n.join(", "))
}

impl From<super::AnchorError> for UrError {
    fn from(e: super::AnchorError) -> Self {
        Self::Anchor(e)
    }
}
