//! Link frames of a reference chain kept in an export. A robot's software hangs meshes and
//! tools on its own link frames (ur_description's `shoulder_link`, a support package's
//! `link_3`); the phi-model's frames are placed by the phi rule. Each link frame of the
//! calibrated chain is moved to where the reference's is on the nominal robot:
//!
//! - `B = L^R_1 (L^N_1)^-1`: the root of the reference from the phi base (joint 1's frame is the
//!   reference's, so the calibrated base sits where the reference's first joint does);
//! - `C_k = (L^N_k)^-1 B^-1 L^R_k`: link `k` of the reference in the nominal phi link `k`, at all
//!   joint values 0 (`L^N_k`, `L^R_k` the links in their roots), kept only in the part that
//!   commutes with the joint's motion (a turn about and a shift along +Z for a revolute joint, a
//!   turn about +Z and any shift for a prismatic one);
//! - origins `B o_1 C_1`, `C_(k-1)^-1 o_k C_k`, tool `C_N^-1 T`: the products telescope, so the
//!   tool's forward kinematics is the calibrated model's exactly, whatever the `C_k`.

use super::chain::OriginChain;
use crate::kinematics::JointKind;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// Why a reference's link frames cannot be kept.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum AnchorError {
    /// The reference has another number of joints.
    #[error("the reference has {found} joints, the robot description {expected}")]
    JointCount {
        /// The description's.
        expected: usize,
        /// The reference's.
        found: usize,
    },
    /// A joint is revolute in one and prismatic in the other.
    #[error("joint {joint} is {nominal:?} in the robot description but {reference:?} in the reference")]
    JointKind {
        /// 1-based.
        joint: usize,
        /// The description's.
        nominal: JointKind,
        /// The reference's.
        reference: JointKind,
    },
    /// A joint's axis points the other way in the reference (its readings turn the other way).
    #[error(
        "joint {joint}'s axis in the reference is {tilt_deg:.1} deg from the robot description's at all joints 0: the two count the joint the other way (or are different robots)"
    )]
    ReversedAxis {
        /// 1-based.
        joint: usize,
        /// The angle between the two axes \[deg\].
        tilt_deg: f64,
    },
    /// The reference's axes lie farther from the description's than a factory calibration
    /// moves them: another robot's file.
    #[error(
        "its axes lie up to {offset_mm:.1} mm and {tilt_mrad:.1} mrad from the robot description's at all joints 0 (a factory calibration moves them by less than {max_mm} mm and {max_mrad:.0} mrad): it is another robot's kinematics; give that robot's own file"
    )]
    OtherRobot {
        /// The largest distance of a reference's axis from the description's \[mm\].
        offset_mm: f64,
        /// The largest angle between them \[mrad\].
        tilt_mrad: f64,
        /// [`FACTORY_AXIS_OFFSET_M`] in mm.
        max_mm: f64,
        /// [`FACTORY_AXIS_TILT_RAD`] in mrad.
        max_mrad: f64,
    },
}

/// The farthest \[m\] a reference's axis may lie from the description's for the two to be one
/// robot model: a robot's axes are built within tenths of a millimetre to a few millimetres of
/// its drawing, and that is what a factory calibration corrects; two models of one family
/// differ by centimetres to metres (UR5e and UR10e by 188 mm in the upper arm alone).
pub const FACTORY_AXIS_OFFSET_M: f64 = 0.01;

/// The largest angle \[rad\] between a reference's axis and the description's for the two to
/// be one robot model: the calibration's own bound on an axis against its drawing
/// ([`PLAUSIBLE_AXIS_TILT_RAD`](crate::calibration::procedure::PLAUSIBLE_AXIS_TILT_RAD),
/// a degree or two of build error and room for the description's rounding).
pub const FACTORY_AXIS_TILT_RAD: f64 = crate::calibration::procedure::PLAUSIBLE_AXIS_TILT_RAD;

/// The link frames of a reference, relative to the phi-model's.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkFrames {
    /// `B`: the phi base frame in the reference's root.
    pub root_from_base: Isometry3<f64>,
    /// `C_k`, k = 1..N: the reference's link `k` in the phi-model's link `k`.
    pub link_from_reference_link: Vec<Isometry3<f64>>,
    /// The largest angle between a reference's axis and the nominal one \[rad\]: what was
    /// dropped to keep each `C_k` commuting with its joint's motion (a calibrated reference's
    /// own corrections, or a description that differs from the reference).
    pub largest_tilt_rad: f64,
    /// The largest distance between a reference's axis and the nominal one, at the link frame's
    /// origin \[m\] (revolute joints).
    pub largest_offset_m: f64,
}

/// The part of `c` that commutes with the motion of a joint of `kind` along +Z, and the tilt
/// \[rad\] and offset \[m\] it drops.
fn commuting_part(c: &Isometry3<f64>, kind: JointKind) -> (Isometry3<f64>, f64, f64) {
    let r = c.rotation.to_rotation_matrix();
    let m = r.matrix();
    // The turn about Z closest to R (Frobenius): maximises cos a (R00 + R11) + sin a (R10 - R01).
    let angle = (m[(1, 0)] - m[(0, 1)]).atan2(m[(0, 0)] + m[(1, 1)]);
    let tilt = (r * Vector3::z()).angle(&Vector3::z());
    let t = c.translation.vector;
    let (shift, offset) = match kind {
        JointKind::Revolute => (Vector3::new(0.0, 0.0, t.z), t.xy().norm()),
        JointKind::Prismatic => (t, 0.0),
    };
    let kept = Isometry3::from_parts(
        Translation3::from(shift),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), angle),
    );
    (kept, tilt, offset)
}

/// The link frames of `reference` relative to `nominal` (the description's nominal chain, the
/// same joint variables), compared at all joint values 0.
pub fn link_frames(nominal: &OriginChain, reference: &OriginChain) -> Result<LinkFrames, AnchorError> {
    let n = nominal.dof();
    if reference.dof() != n {
        return Err(AnchorError::JointCount {
            expected: n,
            found: reference.dof(),
        });
    }
    for (k, (a, b)) in nominal.joints.iter().zip(&reference.joints).enumerate() {
        if a.kind != b.kind {
            return Err(AnchorError::JointKind {
                joint: k + 1,
                nominal: a.kind,
                reference: b.kind,
            });
        }
    }
    let zeros = vec![0.0; n];
    let root_from_base = reference.root_from_link(&zeros, 1) * nominal.root_from_link(&zeros, 1).inverse();
    let mut frames = LinkFrames {
        root_from_base,
        link_from_reference_link: Vec::with_capacity(n),
        largest_tilt_rad: 0.0,
        largest_offset_m: 0.0,
    };
    for k in 1..=n {
        let c = nominal.root_from_link(&zeros, k).inverse()
            * root_from_base.inverse()
            * reference.root_from_link(&zeros, k);
        let (kept, tilt, offset) = commuting_part(&c, nominal.joints[k - 1].kind);
        if tilt > std::f64::consts::FRAC_PI_2 {
            return Err(AnchorError::ReversedAxis {
                joint: k,
                tilt_deg: tilt.to_degrees(),
            });
        }
        frames.largest_tilt_rad = frames.largest_tilt_rad.max(tilt);
        frames.largest_offset_m = frames.largest_offset_m.max(offset);
        frames.link_from_reference_link.push(kept);
    }
    Ok(frames)
}

impl LinkFrames {
    /// Refuses a reference whose axes lie farther from the description's than a factory
    /// calibration moves them ([`FACTORY_AXIS_OFFSET_M`], [`FACTORY_AXIS_TILT_RAD`]): keeping
    /// its link frames would hang another robot's meshes on this one.
    pub fn check_same_robot(&self) -> Result<(), AnchorError> {
        if self.largest_offset_m > FACTORY_AXIS_OFFSET_M || self.largest_tilt_rad > FACTORY_AXIS_TILT_RAD {
            return Err(AnchorError::OtherRobot {
                offset_mm: self.largest_offset_m * 1e3,
                tilt_mrad: self.largest_tilt_rad * 1e3,
                max_mm: FACTORY_AXIS_OFFSET_M * 1e3,
                max_mrad: FACTORY_AXIS_TILT_RAD * 1e3,
            });
        }
        Ok(())
    }
}

/// `chain` with its link frames moved to `frames` (module docs): the same tool pose at every
/// joint value, rooted in the reference's root.
pub fn anchored(chain: &OriginChain, frames: &LinkFrames) -> OriginChain {
    let c = &frames.link_from_reference_link;
    let mut out = chain.clone();
    for (k, joint) in out.joints.iter_mut().enumerate() {
        let before = if k == 0 {
            frames.root_from_base
        } else {
            c[k - 1].inverse()
        };
        joint.parent_from_joint = before * joint.parent_from_joint * c[k];
    }
    out.last_link_from_tool = c[chain.dof() - 1].inverse() * chain.last_link_from_tool;
    out.world_from_root = chain.world_from_root * frames.root_from_base.inverse();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::joint_motion;

    fn paper_chain() -> OriginChain {
        OriginChain::of_phi_model(&crate::robot::RobotDescription::asea_irb6l().nominal_model())
    }

    /// A reference whose link `k` frame is the nominal's moved by `moves[k]` (a tilt included),
    /// its root anywhere.
    fn moved(chain: &OriginChain, root: Isometry3<f64>, moves: &[Isometry3<f64>]) -> OriginChain {
        let mut out = chain.clone();
        for (k, joint) in out.joints.iter_mut().enumerate() {
            let before = if k == 0 { root } else { moves[k - 1].inverse() };
            joint.parent_from_joint = before * joint.parent_from_joint * moves[k];
        }
        out
    }

    fn some_move(k: usize) -> Isometry3<f64> {
        let f = k as f64;
        Isometry3::new(
            Vector3::new(0.01 * f, -0.02, 0.1 * f),
            Vector3::new(0.002 * f, -0.001, 0.3 * f - 1.0),
        )
    }

    #[test]
    fn anchoring_keeps_the_tool_pose_and_takes_the_references_frames_up_to_its_tilt() {
        let nominal = paper_chain();
        // Link 1 of the reference is the phi base frame's (as UR's shoulder link is).
        let moves: Vec<_> = (0..nominal.dof())
            .map(|k| if k == 0 { Isometry3::identity() } else { some_move(k) })
            .collect();
        let root = Isometry3::new(Vector3::new(0.3, 0.1, -0.2), Vector3::new(0.0, 0.0, 2.0));
        let reference = moved(&nominal, root, &moves);
        let frames = link_frames(&nominal, &reference).unwrap();
        // Each move comes back in its part along the joint; its tilt is what was dropped.
        let tilts = moves.iter().map(|m| (m.rotation * Vector3::z()).angle(&Vector3::z()));
        assert!((frames.largest_tilt_rad - tilts.fold(0.0, f64::max)).abs() < 1e-12);
        for (c, m) in frames.link_from_reference_link.iter().zip(&moves).skip(1) {
            assert!(
                (c.translation.vector.z - m.translation.vector.z).abs() < 1e-12,
                "{c} vs {m}"
            );
        }
        let out = anchored(&nominal, &frames);
        let q = [0.3, -0.2, 0.4, 0.5, -0.6, 0.7];
        let want = frames.root_from_base * nominal.root_from_tool(&q);
        let got = out.root_from_tool(&q);
        assert!((want.translation.vector - got.translation.vector).norm() < 1e-12);
        assert!(want.rotation.angle_to(&got.rotation) < 1e-12);
        // Each origin still commutes with its joint's motion: a turn of the joint alone moves
        // only the links after it.
        for (k, joint) in out.joints.iter().enumerate() {
            let c = &frames.link_from_reference_link[k];
            let m = joint_motion(joint.kind, 0.7);
            assert!((c * m).rotation.angle_to(&(m * c).rotation) < 1e-12);
            assert!(((c * m).translation.vector - (m * c).translation.vector).norm() < 1e-12);
        }
    }

    #[test]
    fn a_reference_counting_a_joint_the_other_way_is_refused_by_name() {
        let nominal = paper_chain();
        let mut moves = vec![Isometry3::identity(); nominal.dof()];
        moves[3] = Isometry3::rotation(Vector3::x() * std::f64::consts::PI);
        let reference = moved(&nominal, Isometry3::identity(), &moves);
        assert_eq!(
            link_frames(&nominal, &reference),
            Err(AnchorError::ReversedAxis {
                joint: 4,
                tilt_deg: 180.0
            })
        );
    }
}
