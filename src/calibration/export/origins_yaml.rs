//! Per-joint URDF origins as YAML, for the xacro of a robot's support package (ROS-Industrial's
//! ABB, Motoman, Fanuc stacks load such a file with `xacro.load_yaml` and write
//! `<origin xyz="${c['joint_2']['x']} ..."/>`). One mapping per joint of `calibrated.urdf`'s
//! names (`joint_1` .. `joint_N`: `parent`, `child`, `type`, the origin in the parent link as
//! `x`, `y`, `z` (m) and `roll`, `pitch`, `yaw` (rad, `R = Rz(yaw) Ry(pitch) Rx(roll)`), axis
//! +Z), and two fixed ones: `flange-tool0` (the tool frame in the last link) and
//! `instrument-base_link` (the base in the instrument frame). The joint variables are the
//! controller's readings; each joint's zero offset is either in its origin
//! ([`OffsetsIn::Origins`]) or, with the origins those of the calibrated joint values, written
//! as ros_control's simple transmission (`mechanical_reduction`, `offset`: joint position =
//! reading / reduction + offset; [`OffsetsIn::Transmission`]), which also holds a sliding
//! joint's scale error.

use super::chain::{LinearReading, OriginChain, Unrepresented, linear_readings, reading_chain};
use super::{ChainDeviation, deviation, from_xyz_rpy, xyz_rpy, yaml_float};
use crate::calibration::procedure::Calibration;
use crate::kinematics::JointKind;
use crate::robot::RobotDescription;
use nalgebra::Isometry3;
use std::fmt::Write as _;
use yaml_rust2::Yaml;

/// Where the joints' zero offsets go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OffsetsIn {
    /// Into the origins (the joint variable is the reading).
    Origins,
    /// Into `mechanical_reduction` and `offset` per joint (ros_control's simple transmission).
    Transmission,
}

/// The origin keys, `xyz` then `rpy`.
const KEYS: [&str; 6] = ["x", "y", "z", "roll", "pitch", "yaw"];

/// The file written and how well it holds the calibration.
#[derive(Clone, Debug, PartialEq)]
pub struct OriginsExport {
    /// The YAML text, without comments.
    pub yaml: String,
    /// What the file does not hold (empty: exact).
    pub left_out: Vec<Unrepresented>,
    /// The file read back against the calibrated model.
    pub deviation: ChainDeviation,
}

/// What is wrong with an origins file read back.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum OriginsError {
    /// Not YAML, or a key missing or not a number.
    #[error("{0}")]
    Read(String),
    /// The file read back misses the calibrated model where nothing was left out.
    #[error(
        "the written origins read back miss the calibrated model by {position_m:e} m and {rotation_rad:e} rad (more than 1e-9): not written"
    )]
    RoundTrip {
        /// Largest position difference \[m\].
        position_m: f64,
        /// Largest orientation difference \[rad\].
        rotation_rad: f64,
    },
}

fn write_origin(s: &mut String, t: &Isometry3<f64>) {
    for (key, v) in KEYS.iter().zip(xyz_rpy(t)) {
        let _ = writeln!(s, "  {key}: {}", yaml_float(v));
    }
}

/// The YAML of `chain` (joint variables as `maps` say when given).
fn to_yaml(chain: &OriginChain, maps: Option<&[LinearReading]>) -> String {
    let mut s = String::new();
    let n = chain.dof();
    for (k, joint) in chain.joints.iter().enumerate() {
        let parent = if k == 0 {
            "base_link".to_string()
        } else {
            format!("link_{k}")
        };
        let kind = match joint.kind {
            JointKind::Revolute => "revolute",
            JointKind::Prismatic => "prismatic",
        };
        let _ = writeln!(
            s,
            "joint_{}:\n  parent: {parent}\n  child: link_{}\n  type: {kind}",
            k + 1,
            k + 1
        );
        write_origin(&mut s, &joint.parent_from_joint);
        if let Some(map) = maps.map(|m| m[k]) {
            let _ = writeln!(s, "  mechanical_reduction: {}", yaml_float(map.reduction));
            let _ = writeln!(s, "  offset: {}", yaml_float(map.offset));
        }
    }
    let _ = writeln!(s, "flange-tool0:\n  parent: link_{n}\n  child: tool0\n  type: fixed");
    write_origin(&mut s, &chain.last_link_from_tool);
    let _ = writeln!(
        s,
        "instrument-base_link:\n  parent: instrument\n  child: base_link\n  type: fixed"
    );
    write_origin(&mut s, &chain.world_from_root);
    s
}

fn number(node: &Yaml, key: &str) -> Result<f64, OriginsError> {
    match node {
        Yaml::Real(t) => t.parse::<f64>().ok(),
        Yaml::Integer(i) => Some(*i as f64),
        _ => None,
    }
    .filter(|v| v.is_finite())
    .ok_or_else(|| OriginsError::Read(format!("`{key}`: missing or not a finite number")))
}

fn read_origin(node: &Yaml, name: &str) -> Result<Isometry3<f64>, OriginsError> {
    let mut v = [0.0; 6];
    for (i, key) in KEYS.iter().enumerate() {
        v[i] = number(&node[*key], &format!("{name}.{key}"))?;
    }
    Ok(from_xyz_rpy(v))
}

/// The chain and the per-joint maps (when written) of an origins file's text, for the
/// description's joint kinds.
fn read_back(text: &str, kinds: &[JointKind]) -> Result<(OriginChain, Option<Vec<LinearReading>>), OriginsError> {
    let docs = crate::yaml_file::load(text).map_err(|e| OriginsError::Read(e.to_string()))?;
    let root = docs.first().unwrap_or(&Yaml::BadValue);
    let mut joints = Vec::with_capacity(kinds.len());
    let mut maps = Vec::new();
    for (k, kind) in kinds.iter().enumerate() {
        let name = format!("joint_{}", k + 1);
        let node = &root[name.as_str()];
        joints.push(super::ChainJoint {
            kind: *kind,
            parent_from_joint: read_origin(node, &name)?,
        });
        if !node["offset"].is_badvalue() {
            maps.push(LinearReading {
                reduction: number(&node["mechanical_reduction"], &format!("{name}.mechanical_reduction"))?,
                offset: number(&node["offset"], &format!("{name}.offset"))?,
            });
        }
    }
    let chain = OriginChain {
        joints,
        last_link_from_tool: read_origin(&root["flange-tool0"], "flange-tool0")?,
        world_from_root: read_origin(&root["instrument-base_link"], "instrument-base_link")?,
    };
    Ok((chain, (!maps.is_empty()).then_some(maps)))
}

/// `cal` as per-joint origins, zero offsets as `offsets` says, written, read back and checked
/// against the calibrated model at random readings. Fails only when nothing was left out and
/// the file read back still misses (a defect of the export).
pub fn export(cal: &Calibration, desc: &RobotDescription, offsets: OffsetsIn) -> Result<OriginsExport, OriginsError> {
    let (yaml, left_out) = match offsets {
        OffsetsIn::Origins => {
            let (chain, left_out) = reading_chain(cal, desc);
            (to_yaml(&chain, None), left_out)
        }
        OffsetsIn::Transmission => {
            let (maps, left_out) = linear_readings(cal, desc);
            let chain = OriginChain::of_phi_model(&cal.robot.phi_model());
            (to_yaml(&chain, Some(&maps)), left_out)
        }
    };
    let kinds: Vec<JointKind> = desc.joints.iter().map(|j| j.kind).collect();
    let (chain, maps) = read_back(&yaml, &kinds)?;
    let values = |u: &[f64]| -> Vec<f64> {
        match &maps {
            Some(m) => u.iter().zip(m).map(|(u, m)| m.joint_value(*u)).collect(),
            None => u.to_vec(),
        }
    };
    let dev = deviation(&chain, cal, desc, values);
    if left_out.is_empty() && !dev.is_exact() {
        return Err(OriginsError::RoundTrip {
            position_m: dev.max_position_m,
            rotation_rad: dev.max_rotation_rad,
        });
    }
    Ok(OriginsExport {
        yaml,
        left_out,
        deviation: dev,
    })
}
