//! The calibrated kinematics as URDF for ROS users: one revolute joint per phi-model joint,
//! each joint's origin the fixed frame `frame_{k+1}` in link `k` (eqs. A1-A3), axis +Z.
//! Transmissions, couplings and zero offsets have no URDF form (only linear `mimic`): they
//! stay in `calibration.json`, and a comment in the file says so.

use crate::kinematics::{JointKind, PhiModel};
use crate::robot::RobotDescription;
use nalgebra::Isometry3;
use std::fmt::Write as _;

fn origin(t: &Isometry3<f64>) -> String {
    let (r, p, y) = t.rotation.euler_angles();
    let v = t.translation.vector;
    format!(
        r#"<origin xyz="{:.9} {:.9} {:.9}" rpy="{:.12} {:.12} {:.12}"/>"#,
        v.x, v.y, v.z, r, p, y
    )
}

/// URDF text of `model`, with the limits of `desc`.
pub fn urdf(model: &PhiModel, desc: &RobotDescription, name: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0"?>"#);
    let _ = writeln!(
        s,
        "<!-- Calibrated by axiscal (phi-model, Sultan & Wager). Joint zero offsets, transmission and"
    );
    let _ = writeln!(
        s,
        "     coupling functions are not representable in URDF: see calibration.json. -->"
    );
    let _ = writeln!(s, r#"<robot name="{name}">"#);
    let _ = writeln!(s, r#"  <link name="instrument"/>"#);
    let _ = writeln!(s, r#"  <link name="base_link"/>"#);
    let _ = writeln!(
        s,
        r#"  <joint name="instrument_to_base" type="fixed"><parent link="instrument"/><child link="base_link"/>{}</joint>"#,
        origin(&model.world_from_base)
    );
    let n = model.dof();
    for k in 0..n {
        let parent = if k == 0 {
            "base_link".to_string()
        } else {
            format!("link{k}")
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
        let [lo, hi] = desc.limits_internal(k);
        let _ = writeln!(s, r#"  <link name="link{}"/>"#, k + 1);
        let _ = writeln!(
            s,
            r#"  <joint name="joint{}" type="{kind}"><parent link="{parent}"/><child link="link{}"/>{}<axis xyz="0 0 1"/><limit lower="{lo:.9}" upper="{hi:.9}" effort="0" velocity="0"/></joint>"#,
            k + 1,
            k + 1,
            origin(&parent_from_frame)
        );
    }
    let _ = writeln!(s, r#"  <link name="tool"/>"#);
    let _ = writeln!(
        s,
        r#"  <joint name="tool_fixed" type="fixed"><parent link="link{n}"/><child link="tool"/>{}</joint>"#,
        origin(&model.last_link_from_tool)
    );
    let _ = writeln!(s, "</robot>");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    /// Chaining the URDF origins (rpy = Rz(y) Ry(p) Rx(r), as URDF defines) reproduces FK.
    #[test]
    fn urdf_chain_reproduces_forward_kinematics() {
        let desc = RobotDescription::asea_irb6l();
        let model = crate::sim::paper_robot().phi_model();
        let text = urdf(&model, &desc, "t");
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
        let fk = model.world_from_tool(&q);
        assert!((t.translation.vector - fk.translation.vector).norm() < 1e-8);
        assert!(t.rotation.angle_to(&fk.rotation) < 1e-9);
    }
}
