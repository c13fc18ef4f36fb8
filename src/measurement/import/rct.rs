//! robot_cal_tools' kinematic measurement file (`docs/formats.md#robot_cal_tools-measurements`):
//! a YAML map, one entry per observation (keyed by a time stamp, in file order), each with
//! `pose` (a fixed camera's measurement of a target on the robot: position `x, y, z` in metres
//! and orientation quaternion `qw, qx, qy, qz`), `target_joints` (the robot's recorded joint
//! values, rad for revolute, m for prismatic) and `camera_joints` (empty: the camera stands
//! still).
//!
//! The target's position is target 0; with `frame_points_mm = L`, targets 1 and 2 are the points
//! `L` along the measured frame's x and y axes (the orientation as two more points). The
//! experiments are recovered from the joint values as for a wide table
//! (`docs/formats.md#wide-format`): runs in which one joint moves are axis experiments, every
//! other pose is free.

use super::points::{LengthUnit, PointsError};
use super::wide::{Pose, rows_of};
use crate::csv_lines::shown_cell;
use crate::kinematics::JointKind;
use crate::measurement::MeasurementSet;
use crate::measurement::data::{command_beyond, coordinate_beyond};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use std::path::Path;
use yaml_rust2::Yaml;

/// How the file is read.
#[derive(Clone, Debug, PartialEq)]
pub struct RctOptions {
    /// The robot's joints, base first.
    pub kinds: Vec<JointKind>,
    /// Targets 1 and 2 this far along the measured frame's x and y axes \[mm\]; `None`: the
    /// position only.
    pub frame_points_mm: Option<f64>,
    /// Two poses whose joint value differs by at most this (deg or mm) hold the joint still.
    pub still_tolerance: f64,
    /// Revolute `target_joints` in radians (the format's), else degrees.
    pub radians: bool,
    /// Unit of `pose.x, y, z` and of prismatic `target_joints` (the format's: metres).
    pub lengths: LengthUnit,
}

/// A quaternion whose norm is further from 1 than this is not a rotation (a unit quaternion
/// printed with 6 or more significant digits is within 1e-5).
const UNIT_TOLERANCE: f64 = 1e-3;

/// Reads the measurements `text` (`path` labels messages).
pub fn parse(text: &str, path: &Path, options: &RctOptions) -> Result<MeasurementSet, PointsError> {
    let file_error = |message: String| PointsError::File {
        path: path.to_owned(),
        message,
    };
    let docs = crate::yaml_file::load(text).map_err(|e| file_error(e.to_string()))?;
    let Some(Yaml::Hash(entries)) = docs.first() else {
        return Err(file_error(
            "expected a map of observations (robot_cal_tools' kinematic measurements: each with pose, target_joints, camera_joints)".into(),
        ));
    };
    let mut poses: Vec<Pose> = Vec::with_capacity(entries.len());
    for (i, (key, entry)) in entries.iter().enumerate() {
        let name = shown_cell(&key_name(key));
        let error = |field: &str, message: String| file_error(format!("entry `{name}`, field `{field}`: {message}"));
        if let Some(what) = not_an_observation(entry) {
            return Err(file_error(format!(
                "entry `{name}` is {what}, not an observation (a map with pose, target_joints, camera_joints): the file is a map of observations keyed by name (a time stamp), each at the top level, not a list under `{name}:`"
            )));
        }
        let (cmd, markers) = observation(entry, options, &error)?;
        poses.push((i + 1, cmd, markers));
    }
    if poses.is_empty() {
        return Err(file_error("no observation".into()));
    }
    rows_of(&poses, options.kinds.len(), (options.still_tolerance, false), path)
}

/// One entry's commands (deg / mm) and target points (mm).
#[allow(clippy::type_complexity)]
fn observation(
    entry: &Yaml,
    options: &RctOptions,
    error: &dyn Fn(&str, String) -> PointsError,
) -> Result<(Vec<f64>, Vec<Option<[f64; 3]>>), PointsError> {
    if entry["camera_joints"].as_vec().is_some_and(|v| !v.is_empty()) {
        return Err(error(
            "camera_joints",
            "the camera moves (a camera on a robot): only a fixed camera's measurements are read".into(),
        ));
    }
    let joints = entry["target_joints"]
        .as_vec()
        .ok_or_else(|| error("target_joints", "missing or not a list".into()))?;
    if joints.len() != options.kinds.len() {
        return Err(error(
            "target_joints",
            format!("{} values, the robot has {} joints", joints.len(), options.kinds.len()),
        ));
    }
    let cmd = joints
        .iter()
        .zip(&options.kinds)
        .enumerate()
        .map(|(k, (written, kind))| {
            let field = format!("target_joints[{k}]");
            let v = number(written).ok_or_else(|| error(&field, "not a finite number".into()))?;
            let (cmd, unit) = match kind {
                JointKind::Revolute if options.radians => (v.to_degrees(), "rad"),
                JointKind::Revolute => (v, "deg"),
                JointKind::Prismatic => (v * options.lengths.to_mm(), options.lengths.name()),
            };
            match command_beyond(cmd) {
                Some(range) => Err(error(
                    &field,
                    format!("{} {unit} is outside {range}", as_written(written)),
                )),
                None => Ok(cmd),
            }
        })
        .collect::<Result<Vec<f64>, PointsError>>()?;
    let pose = &entry["pose"];
    let field = |name: &str| {
        number(&pose[name]).ok_or_else(|| error(&format!("pose.{name}"), "missing or not a finite number".into()))
    };
    let coordinate_mm = |name: &str| {
        let mm = field(name)? * options.lengths.to_mm();
        match coordinate_beyond(mm) {
            Some(range) => Err(error(
                &format!("pose.{name}"),
                format!(
                    "{} {} is outside {range}",
                    as_written(&pose[name]),
                    options.lengths.name()
                ),
            )),
            None => Ok(mm),
        }
    };
    let position_mm = Vector3::new(coordinate_mm("x")?, coordinate_mm("y")?, coordinate_mm("z")?);
    let mut markers = vec![Some(position_mm.into())];
    if let Some(length) = options.frame_points_mm {
        let q = Quaternion::new(field("qw")?, field("qx")?, field("qy")?, field("qz")?);
        if (q.norm() - 1.0).abs() > UNIT_TOLERANCE {
            return Err(error(
                "pose.qw",
                format!("the quaternion's norm is {:.6}, not 1", q.norm()),
            ));
        }
        let rotation = UnitQuaternion::from_quaternion(q);
        for axis in [Vector3::x(), Vector3::y()] {
            markers.push(Some((position_mm + rotation * axis * length).into()));
        }
    }
    Ok((cmd, markers))
}

/// What an entry is when it is not a map (an observation): `an empty list`, `a list of 3`, `a
/// number`, ...
fn not_an_observation(entry: &Yaml) -> Option<String> {
    Some(match entry {
        Yaml::Hash(_) => return None,
        Yaml::Array(items) if items.is_empty() => "an empty list".into(),
        Yaml::Array(items) => format!("a list of {}", items.len()),
        Yaml::String(_) => "text".into(),
        Yaml::Real(_) | Yaml::Integer(_) => "a number".into(),
        Yaml::Boolean(_) => "a boolean".into(),
        _ => "empty".into(),
    })
}

/// A finite number (YAML real or integer).
fn number(v: &Yaml) -> Option<f64> {
    v.as_f64()
        .or_else(|| v.as_i64().map(|i| i as f64))
        .filter(|x| x.is_finite())
}

/// A number as the file writes it (shortened when long).
fn as_written(v: &Yaml) -> String {
    match v {
        Yaml::Real(s) => shown_cell(s),
        Yaml::Integer(i) => i.to_string(),
        other => format!("{other:?}"),
    }
}

/// An entry's key as written.
fn key_name(key: &Yaml) -> String {
    match key {
        Yaml::String(s) | Yaml::Real(s) => s.clone(),
        Yaml::Integer(i) => i.to_string(),
        other => format!("{other:?}"),
    }
}

/// The comment line written at the top of an imported file.
pub fn provenance_comment(source: &Path, options: &RctOptions) -> String {
    let targets = match options.frame_points_mm {
        Some(l) => format!("target 0 the measured position, targets 1-2 {l} mm along its frame's x and y"),
        None => "target 0 the measured position".into(),
    };
    // The format's units are said by nothing; others than its own by the options read with.
    let units = if options.radians && options.lengths == LengthUnit::M {
        String::new()
    } else {
        format!(
            "; read with --angles {} --units {}",
            if options.radians { "rad" } else { "deg" },
            options.lengths.name()
        )
    };
    format!(
        "# imported by `axiscal import rct` from {} (robot_cal_tools kinematic measurements; {targets}{units})\n",
        crate::csv_lines::one_line(&source.display().to_string())
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options(frame_points_mm: Option<f64>) -> RctOptions {
        RctOptions {
            kinds: vec![JointKind::Revolute, JointKind::Prismatic],
            frame_points_mm,
            still_tolerance: 1e-6,
            radians: true,
            lengths: LengthUnit::M,
        }
    }

    fn entry(key: &str, j: [f64; 2], p: [f64; 3], q: [f64; 4]) -> String {
        format!(
            "'{key}':\n  camera_joints: []\n  pose:\n    qw: {}\n    qx: {}\n    qy: {}\n    qz: {}\n    x: {}\n    y: {}\n    z: {}\n  target_joints:\n  - {}\n  - {}\n",
            q[0], q[1], q[2], q[3], p[0], p[1], p[2], j[0], j[1]
        )
    }

    /// Three poses turning joint 1 make one axis experiment; the units become deg, mm; the frame
    /// points sit `L` along the measured frame's axes (a quarter turn about z: x -> y, y -> -x).
    #[test]
    fn poses_become_rows_in_file_units_with_frame_points() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let text: String = (0..3)
            .map(|i| {
                entry(
                    &format!("{i}"),
                    [0.1 * i as f64, 0.25],
                    [1.0, 2.0, 0.5],
                    [h, 0.0, 0.0, h],
                )
            })
            .collect();
        let set = parse(&text, Path::new("m.yaml"), &options(Some(100.0))).unwrap();
        let rows = set.rows();
        assert_eq!(rows.len(), 9);
        assert_eq!((rows[0].experiment.as_str(), rows[0].moved_joint), ("axis1", 1));
        assert!((rows[3].cmd[0] - 0.1f64.to_degrees()).abs() < 1e-12);
        assert!((rows[0].cmd[1] - 250.0).abs() < 1e-12);
        let p = |k: usize| rows[k].position_mm;
        assert!((p(0)[0] - 1000.0).abs() < 1e-9 && (p(0)[1] - 2000.0).abs() < 1e-9);
        assert!((p(1)[1] - 2100.0).abs() < 1e-9 && (p(1)[0] - 1000.0).abs() < 1e-9);
        assert!((p(2)[0] - 900.0).abs() < 1e-9 && (p(2)[1] - 2000.0).abs() < 1e-9);
    }

    #[test]
    fn bad_entries_name_the_entry_and_field() {
        let good = entry("a", [0.0, 0.0], [1.0, 2.0, 3.0], [1.0, 0.0, 0.0, 0.0]);
        let cases = [
            (
                good.replace("  - 0\n  - 0\n", "  - 0\n"),
                "entry `a`, field `target_joints`: 1 values",
            ),
            (good.replace("x: 1", "x: abc"), "field `pose.x`"),
            (good.replace("qw: 1", "qw: 2"), "norm is 2.000000"),
            (
                good.replace("camera_joints: []", "camera_joints: [0.1]"),
                "the camera moves",
            ),
            ("- 1\n- 2\n".to_string(), "expected a map"),
            ("a: [\n".to_string(), "not YAML"),
        ];
        for (text, what) in cases {
            let message = parse(&text, Path::new("m.yaml"), &options(Some(50.0)))
                .unwrap_err()
                .to_string();
            assert!(message.contains(what), "{text:?}: {message}");
        }
    }
}
