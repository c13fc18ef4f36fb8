//! The calibrated kinematics as URDF for ROS users, with the ROS-Industrial names
//! (`base_link`, `link_1`.., `joint_1`.., `flange`, `tool0`): one revolute or prismatic joint
//! per phi-model joint, each joint's origin the fixed frame `frame_{k+1}` in link `k`
//! (eqs. A1-A3), axis +Z.
//!
//! URDF joint values are the phi-model's joint values `q`, NOT the controller's readings:
//! transmissions, couplings and zero offsets have no URDF form (only linear `mimic`), so a
//! `joint_states` publisher must turn the readings into `q` first (the joint map,
//! [`super::joint_map`], `axiscal joints`). [`raw_reading_deviation`] says how far off the
//! tool is when it does not.

use super::Calibration;
use crate::kinematics::{JointKind, PhiModel};
use crate::measurement::format_f64;
use crate::robot::{Controller, RobotDescription, commands_to_internal};
use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// Which link is the URDF's root.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum UrdfRoot {
    /// `base_link`, the robot's base frame (frame 1: Z on axis 1), as ROS-Industrial expects.
    #[default]
    BaseLink,
    /// `instrument`, the measuring instrument's frame, with `base_link` placed in it: the
    /// calibrated base placement travels with the file.
    Instrument,
}

/// How the URDF is written.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfOptions {
    /// The `<robot name>`.
    pub robot_name: String,
    /// The root link.
    pub root: UrdfRoot,
}

/// `text` as a URDF/ROS name: lower case, anything but letters, digits and `_` made `_`.
pub fn ros_name(text: &str) -> String {
    let s: String = text
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect();
    let s = s.trim_matches('_').to_string();
    if s.is_empty() { "robot".into() } else { s }
}

/// An `<origin>` with every number written exactly (shortest text that reads back to the same
/// 64-bit float), so the file reproduces the model to rounding.
fn origin(t: &Isometry3<f64>) -> String {
    let [r, p, y] = crate::kinematics::roll_pitch_yaw(&t.rotation);
    let v = t.translation.vector;
    // `+ 0.0` writes a negative zero as 0.
    let n = |x: f64| format_f64(x + 0.0);
    format!(
        r#"<origin xyz="{} {} {}" rpy="{} {} {}"/>"#,
        n(v.x),
        n(v.y),
        n(v.z),
        n(r),
        n(p),
        n(y)
    )
}

/// The `<limit>` of joint `k` (0-based): position limits from the description (internal
/// units), speed and effort from its `max_velocity`/`max_effort` (converted to rad/s or m/s),
/// or 0 with a comment when the description does not give them.
fn limit(desc: &RobotDescription, k: usize) -> String {
    let [lo, hi] = desc.limits_internal(k);
    let j = &desc.joints[k];
    let to_internal = |v: f64| match j.kind {
        JointKind::Revolute => v.to_radians(),
        JointKind::Prismatic => v * 1e-3,
    };
    let velocity = j.max_velocity.map_or(0.0, to_internal);
    let effort = j.max_effort.unwrap_or(0.0);
    let missing = if j.max_velocity.is_none() || j.max_effort.is_none() {
        " <!-- velocity/effort unknown: give max_velocity and max_effort in the robot description -->"
    } else {
        ""
    };
    format!(
        r#"<limit lower="{}" upper="{}" effort="{}" velocity="{}"/>{missing}"#,
        format_f64(lo),
        format_f64(hi),
        format_f64(effort),
        format_f64(velocity)
    )
}

/// Joints of `desc` whose speed or effort limit the description does not give.
pub fn joints_without_speed_limits(desc: &RobotDescription) -> Vec<usize> {
    (0..desc.dof())
        .filter(|&k| desc.joints[k].max_velocity.is_none() || desc.joints[k].max_effort.is_none())
        .map(|k| k + 1)
        .collect()
}

/// URDF text of `model`, with the limits of `desc`.
pub fn urdf(model: &PhiModel, desc: &RobotDescription, options: &UrdfOptions) -> String {
    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0"?>"#);
    let _ = writeln!(
        s,
        "<!-- Calibrated by axiscal (phi-model, Sultan & Wager). Joint values are the phi-model's\n     \
         joint values q, not the controller's readings: turn readings into q with the joint map\n     \
         (joint_map.csv, `axiscal joints`); transmissions, couplings and zero offsets have no URDF\n     \
         form and live in calibration.json. -->"
    );
    let _ = writeln!(s, r#"<robot name="{}">"#, options.robot_name);
    if options.root == UrdfRoot::Instrument {
        let _ = writeln!(s, r#"  <link name="instrument"/>"#);
        let _ = writeln!(
            s,
            r#"  <joint name="instrument-base_link" type="fixed"><parent link="instrument"/><child link="base_link"/>{}</joint>"#,
            origin(&model.world_from_base)
        );
    }
    let _ = writeln!(s, r#"  <link name="base_link"/>"#);
    let n = model.dof();
    for k in 0..n {
        let parent = if k == 0 {
            "base_link".to_string()
        } else {
            format!("link_{k}")
        };
        let parent_from_frame = if k == 0 {
            Isometry3::identity()
        } else {
            model.link_from_next_frame(k - 1)
        };
        let kind = match model.joints[k].kind {
            JointKind::Revolute => "revolute",
            JointKind::Prismatic => "prismatic",
        };
        let _ = writeln!(s, r#"  <link name="link_{}"/>"#, k + 1);
        let _ = writeln!(
            s,
            r#"  <joint name="joint_{}" type="{kind}"><parent link="{parent}"/><child link="link_{}"/>{}<axis xyz="0 0 1"/>{}</joint>"#,
            k + 1,
            k + 1,
            origin(&parent_from_frame),
            limit(desc, k)
        );
    }
    // The last link's moving frame is the flange; the tool frame is tool0.
    let _ = writeln!(s, r#"  <link name="flange"/>"#);
    let _ = writeln!(
        s,
        r#"  <joint name="link_{n}-flange" type="fixed"><parent link="link_{n}"/><child link="flange"/>{}</joint>"#,
        origin(&Isometry3::identity())
    );
    let _ = writeln!(s, r#"  <link name="tool0"/>"#);
    let _ = writeln!(
        s,
        r#"  <joint name="flange-tool0" type="fixed"><parent link="flange"/><child link="tool0"/>{}</joint>"#,
        origin(&model.last_link_from_tool)
    );
    let _ = writeln!(s, "</robot>");
    s
}

/// How far the URDF is off when fed the controller's readings (the commands) as joint values
/// instead of the calibrated joint values: the largest tool-point distance \[mm\] and tool
/// rotation \[mrad\] between `FK_calibrated(q(cmd))` and `FK_calibrated(cmd)` over `commands`
/// (file units), with the command where each occurs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RawReadingDeviation {
    /// Commands compared.
    pub poses: usize,
    /// Largest tool-point deviation \[mm\].
    pub max_position_mm: f64,
    /// RMS tool-point deviation \[mm\].
    pub rms_position_mm: f64,
    /// Largest tool rotation \[mrad\].
    pub max_orientation_mrad: f64,
    /// Largest difference between a reading and its calibrated joint value, per joint \[deg or
    /// mm\].
    pub max_joint_difference: Vec<f64>,
}

impl RawReadingDeviation {
    /// The deviation as report findings (`report.json`): no sigma, it is a property of the
    /// calibrated model, not an estimate.
    pub fn findings(&self) -> Vec<super::Finding> {
        let finding = |subject: &str, value: f64, unit: &str, text: String| super::Finding {
            subject: subject.into(),
            value,
            sigma: f64::NAN,
            unit: unit.into(),
            significant: true,
            text,
        };
        vec![
            finding(
                "urdf fed raw readings: position",
                self.max_position_mm,
                "mm",
                format!(
                    "the URDF fed the controller's readings instead of the calibrated joint values puts the tool up to {:.3} mm off (RMS {:.3} mm over {} poses): use the joint map",
                    self.max_position_mm, self.rms_position_mm, self.poses
                ),
            ),
            finding(
                "urdf fed raw readings: orientation",
                self.max_orientation_mrad,
                "mrad",
                format!("... and turns it by up to {:.3} mrad", self.max_orientation_mrad),
            ),
        ]
    }

    /// A Markdown section for `report.md`.
    pub fn markdown(&self) -> String {
        let joints: Vec<String> = self
            .max_joint_difference
            .iter()
            .enumerate()
            .map(|(k, d)| format!("{}: {d:.4}", k + 1))
            .collect();
        format!(
            "\n## URDF and the controller's readings\n\nURDF joint values are the calibrated joint values, not the controller's readings. \
             Fed the readings directly over {} poses, the URDF puts the tool up to {:.3} mm off (RMS {:.3} mm) and turns it by up to {:.3} mrad; \
             the largest reading-to-joint-value difference per joint (deg or mm) is {}. Convert readings with `joint_map.csv` or \
             `axiscal joints` first.\n",
            self.poses,
            self.max_position_mm,
            self.rms_position_mm,
            self.max_orientation_mrad,
            joints.join(", ")
        )
    }
}

/// [`RawReadingDeviation`] of `cal` over `commands` (file units); commands the calibrated
/// model cannot execute are skipped.
pub fn raw_reading_deviation(cal: &Calibration, desc: &RobotDescription, commands: &[Vec<f64>]) -> RawReadingDeviation {
    let model = cal.robot.phi_model();
    let controller = Controller::from_description(desc);
    let mut out = RawReadingDeviation {
        poses: 0,
        max_position_mm: 0.0,
        rms_position_mm: 0.0,
        max_orientation_mrad: 0.0,
        max_joint_difference: vec![0.0; desc.dof()],
    };
    let mut sum_sq = 0.0;
    for cmd in commands {
        let raw = commands_to_internal(desc, cmd);
        let Ok(q) = cal.robot.joint_values(&controller, &raw) else {
            continue;
        };
        let (exact, naive) = (model.world_from_tool(&q), model.world_from_tool(&raw));
        let d_mm = (exact.translation.vector - naive.translation.vector).norm() * 1e3;
        out.poses += 1;
        sum_sq += d_mm * d_mm;
        out.max_position_mm = out.max_position_mm.max(d_mm);
        out.max_orientation_mrad = out
            .max_orientation_mrad
            .max(exact.rotation.angle_to(&naive.rotation) * 1e3);
        for (k, (a, b)) in q.iter().zip(&raw).enumerate() {
            let scale = match desc.joints[k].kind {
                JointKind::Revolute => 1f64.to_degrees(),
                JointKind::Prismatic => 1e3,
            };
            out.max_joint_difference[k] = out.max_joint_difference[k].max((a - b).abs() * scale);
        }
    }
    out.rms_position_mm = (sum_sq / out.poses.max(1) as f64).sqrt();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    /// Chaining the URDF origins (rpy = Rz(y) Ry(p) Rx(r), as URDF defines) reproduces FK to
    /// rounding, with either root.
    #[test]
    fn urdf_chain_reproduces_forward_kinematics() {
        let desc = RobotDescription::asea_irb6l();
        let model = crate::sim::paper_robot().phi_model();
        for root in [UrdfRoot::BaseLink, UrdfRoot::Instrument] {
            let options = UrdfOptions {
                robot_name: ros_name(&desc.name),
                root,
            };
            let text = urdf(&model, &desc, &options);
            let q = [0.3, -0.2, 0.4, 0.5, -0.6, 0.7];
            let mut t = Isometry3::identity();
            let mut k = 0;
            for line in text.lines().filter(|l| l.contains("<origin")) {
                let grab = |key: &str| -> Vec<f64> {
                    let start = line.find(&format!("{key}=\"")).unwrap() + key.len() + 2;
                    let end = start + line[start..].find('"').unwrap();
                    line[start..end].split(' ').map(|v| v.parse().unwrap()).collect()
                };
                let (xyz, rpy) = (grab("xyz"), grab("rpy"));
                t *= Isometry3::from_parts(
                    Translation3::new(xyz[0], xyz[1], xyz[2]),
                    UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
                );
                if line.contains("<axis") {
                    t *= Isometry3::rotation(nalgebra::Vector3::z() * q[k]);
                    k += 1;
                }
            }
            let fk = match root {
                UrdfRoot::Instrument => model.world_from_tool(&q),
                UrdfRoot::BaseLink => model.world_from_base.inverse() * model.world_from_tool(&q),
            };
            // A few ulps of a few metres through seven transforms; rpy near pitch = pi/2 (joint
            // 2's origin: 1.5633 rad) splits roll and yaw with 1/cos(pitch) ~ 130 times the
            // rounding of a rotation matrix entry.
            let d = (t.translation.vector - fk.translation.vector).norm();
            let a = t.rotation.angle_to(&fk.rotation);
            assert!(d < 1e-13 && a < 1e-12, "{root:?}: {d:e} m, {a:e} rad");
            for name in ["base_link", "link_1", "joint_6", "flange", "tool0"] {
                assert!(text.contains(&format!("\"{name}\"")), "{name} missing");
            }
        }
    }

    #[test]
    fn names_are_ros_names() {
        assert_eq!(ros_name("ASEA IRB/L6"), "asea_irb_l6");
        assert_eq!(ros_name("--"), "robot");
    }
}
