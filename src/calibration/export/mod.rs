//! The calibrated kinematics in the files a robot's software loads: the UR ROS driver's
//! `kinematics.yaml` ([`ur`]) and per-joint URDF origins for a support package's xacro
//! ([`origins_yaml`]). Each is built as an [`OriginChain`] ([`chain`]), optionally with the link
//! frames of a reference ([`anchor`]), written, read back and checked: the tool pose of the file
//! read back against the calibrated model's at [`CHECK_POSES`] random joint configurations
//! ([`deviation`]). Exact (to rounding) or the export names what it left out.

pub mod anchor;
pub mod chain;
pub mod origins_yaml;
pub mod ur;

pub use anchor::{AnchorError, LinkFrames, anchored, link_frames};
pub use chain::{ChainJoint, LinearReading, OriginChain, Unrepresented, linear_readings, reading_chain};

use crate::calibration::procedure::Calibration;
use crate::robot::{Controller, RobotDescription};
use nalgebra::Isometry3;
use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};

/// Random joint configurations of the round-trip check.
pub const CHECK_POSES: usize = 1000;

/// What a file read back must reproduce: the calibrated model's tool pose to 1e-9 m and
/// 1e-9 rad (rounding of the written numbers is ~1e-16 of the lengths).
pub const EXACT_TOLERANCE: f64 = 1e-9;

/// Seed of the round-trip check's configurations (fixed: the same file gets the same check).
const CHECK_SEED: u64 = 9283;

/// How far a chain's tool pose is from the calibrated model's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChainDeviation {
    /// Configurations compared (those the calibrated model can execute).
    pub poses: usize,
    /// Largest tool-position difference \[m\].
    pub max_position_m: f64,
    /// Largest tool-orientation difference \[rad\].
    pub max_rotation_rad: f64,
}

impl ChainDeviation {
    /// Within [`EXACT_TOLERANCE`] in both.
    pub fn is_exact(&self) -> bool {
        self.max_position_m <= EXACT_TOLERANCE && self.max_rotation_rad <= EXACT_TOLERANCE
    }
}

/// [`ChainDeviation`] of `chain` (placed in the instrument frame by its `world_from_root`)
/// from the calibrated model, over [`CHECK_POSES`] controller readings drawn uniformly within
/// the description's limits (internal units), `chain_values` turning readings into the chain's
/// joint variables as the file says to. Readings the calibrated model cannot execute are
/// skipped.
pub fn deviation(
    chain: &OriginChain,
    cal: &Calibration,
    desc: &RobotDescription,
    chain_values: impl Fn(&[f64]) -> Vec<f64>,
) -> ChainDeviation {
    let model = cal.robot.phi_model();
    let controller = Controller::from_description(desc);
    let mut rng = ChaCha12Rng::seed_from_u64(CHECK_SEED);
    let mut out = ChainDeviation {
        poses: 0,
        max_position_m: 0.0,
        max_rotation_rad: 0.0,
    };
    for _ in 0..CHECK_POSES {
        let cmd: Vec<f64> = (0..desc.dof())
            .map(|k| {
                let [lo, hi] = desc.limits_internal(k);
                rng.random_range(lo..=hi)
            })
            .collect();
        let Ok(q) = cal.robot.joint_values(&controller, &cmd) else {
            continue;
        };
        let want = model.world_from_tool(&q);
        let got = chain.world_from_root * chain.root_from_tool(&chain_values(&cmd));
        out.poses += 1;
        out.max_position_m = out
            .max_position_m
            .max((want.translation.vector - got.translation.vector).norm());
        out.max_rotation_rad = out.max_rotation_rad.max(want.rotation.angle_to(&got.rotation));
    }
    out
}

/// `v` as a YAML float every reader takes as one: the shortest text that reads back to the
/// same 64-bit float, with a `.` in the mantissa and a signed exponent (YAML 1.1 readers such
/// as PyYAML, which ROS launch files use, read `1e-05` as a string).
pub fn yaml_float(v: f64) -> String {
    let text = crate::measurement::format_f64(v + 0.0);
    let (mantissa, exponent) = match text.split_once('e') {
        Some((m, e)) => (m.to_string(), Some(e.to_string())),
        None => (text, None),
    };
    let mantissa = if mantissa.contains('.') {
        mantissa
    } else {
        format!("{mantissa}.0")
    };
    match exponent {
        Some(e) if e.starts_with('-') => format!("{mantissa}e{e}"),
        Some(e) => format!("{mantissa}e+{e}"),
        None => mantissa,
    }
}

/// The six numbers of a URDF `<origin>`: `xyz` \[m\] and `rpy` \[rad\], `R = Rz(yaw) Ry(pitch)
/// Rx(roll)`.
pub fn xyz_rpy(t: &Isometry3<f64>) -> [f64; 6] {
    let [r, p, y] = crate::kinematics::roll_pitch_yaw(&t.rotation);
    let v = t.translation.vector;
    [v.x, v.y, v.z, r, p, y]
}

/// The isometry of URDF `xyz` \[m\] and `rpy` \[rad\].
pub fn from_xyz_rpy(v: [f64; 6]) -> Isometry3<f64> {
    Isometry3::from_parts(
        nalgebra::Translation3::new(v[0], v[1], v[2]),
        nalgebra::UnitQuaternion::from_euler_angles(v[3], v[4], v[5]),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yaml_floats_carry_a_point_and_a_signed_exponent_and_read_back_exactly() {
        for (v, text) in [
            (0.0, "0.0"),
            (-0.0, "0.0"),
            (1.0, "1.0"),
            (0.1625, "0.1625"),
            (1e-11, "1.0e-11"),
            (-2.044881182297852e-11, "-2.044881182297852e-11"),
            (2.5e20, "2.5e+20"),
        ] {
            assert_eq!(yaml_float(v), text);
            assert_eq!(text.parse::<f64>().unwrap().to_bits(), (v + 0.0).to_bits());
        }
    }

    #[test]
    fn origins_read_back_as_written() {
        let t = from_xyz_rpy([0.1, -0.2, 0.3, 0.4, -0.5, 2.9]);
        let back = from_xyz_rpy(xyz_rpy(&t));
        assert!((back.translation.vector - t.translation.vector).norm() < 1e-15);
        assert!(back.rotation.angle_to(&t.rotation) < 1e-15);
    }
}
