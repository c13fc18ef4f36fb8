//! Forward kinematics of a serial arm in the phi-model, eq. (A1).
//!
//! Numbering: the paper counts joints and frames from 1; in code, index `k` (0-based)
//! is joint `k + 1`. Frame `k` is the fixed frame whose Z axis is joint axis `k` (it rides on
//! link `k - 1`), and "link `k`" is the moving frame `frame_k * Trans(0,0,d_k) Rot(z,theta_k)`:
//! everything joint `k` carries is expressed in it. Tool frame: link `N` times a fixed
//! `last_link_from_tool`.

use super::phi::{JointKind, PhiRow, joint_motion, link_from_phi};
use nalgebra::{Isometry3, Point3, Unit, Vector3};
use serde::{Deserialize, Serialize};

/// One joint of the phi-model: its kind and its constant angle `phi_i` (A2).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PhiJoint {
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// The constant angle of Z_phi from X_i \[rad\] (A2); unused by the last joint.
    pub phi_rad: f64,
}

/// The kinematic geometry of an `N`-joint serial arm in the phi-model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhiModel {
    /// The `N` joints, base first.
    pub joints: Vec<PhiJoint>,
    /// The `N - 1` rows of Table 2: `rows\[k\]` places frame `k + 2` in the `phi_{k+1}` frame.
    pub rows: Vec<PhiRow>,
    /// Frame 1 (the robot base frame, Z on axis 1) in the world (instrument) frame.
    pub world_from_base: Isometry3<f64>,
    /// The tool frame in the last link's moving frame.
    pub last_link_from_tool: Isometry3<f64>,
}

/// A joint axis as a line in some frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisLine {
    /// A point on the axis (the origin of frame `i`) \[m\].
    pub origin_m: Point3<f64>,
    /// The axis direction Z_i.
    pub direction: Unit<Vector3<f64>>,
}

/// Every frame of the chain at one joint configuration, in the world frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainPoses {
    /// `world_from_frame\[k\]`: fixed frame of joint `k + 1` (Z on the axis).
    pub world_from_frame: Vec<Isometry3<f64>>,
    /// `world_from_link\[k\]`: moving frame of link `k + 1`.
    pub world_from_link: Vec<Isometry3<f64>>,
    /// The tool frame.
    pub world_from_tool: Isometry3<f64>,
}

impl ChainPoses {
    /// Joint axis `k` (0-based) as a line in the world frame.
    pub fn axis(&self, k: usize) -> AxisLine {
        let f = &self.world_from_frame[k];
        AxisLine {
            origin_m: f * Point3::origin(),
            direction: Unit::new_unchecked(f * Vector3::z()),
        }
    }
}

impl PhiModel {
    /// Number of joints `N`.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// Checks the shape of the model: `N >= 1` joints and `N - 1` rows.
    pub fn is_consistent(&self) -> bool {
        !self.joints.is_empty() && self.rows.len() + 1 == self.joints.len()
    }

    /// `frame_{k+1}` in `link_k` (0-based `k`): `Rot(z, phi_k) R0 * phi_T_{k+1}` (A1, A2 at
    /// zero motion).
    pub fn link_from_next_frame(&self, k: usize) -> Isometry3<f64> {
        link_from_phi(self.joints[k].phi_rad) * self.rows[k].phi_from_next()
    }

    /// All frames at joint values `q` (rad for revolute, m for prismatic joints).
    ///
    /// # Panics
    /// If `q.len() != self.dof()`: a programming error, not a data error.
    pub fn poses(&self, q: &[f64]) -> ChainPoses {
        assert_eq!(
            q.len(),
            self.dof(),
            "joint vector length must equal the number of joints"
        );
        let n = self.dof();
        let mut world_from_frame = Vec::with_capacity(n);
        let mut world_from_link = Vec::with_capacity(n);
        let mut frame = self.world_from_base;
        for (k, (joint, &qk)) in self.joints.iter().zip(q).enumerate() {
            world_from_frame.push(frame);
            let link = frame * joint_motion(joint.kind, qk);
            world_from_link.push(link);
            if k + 1 < n {
                frame = link * self.link_from_next_frame(k);
            }
        }
        let world_from_tool = world_from_link[n - 1] * self.last_link_from_tool;
        ChainPoses {
            world_from_frame,
            world_from_link,
            world_from_tool,
        }
    }

    /// The tool frame in the world frame at joint values `q`.
    pub fn world_from_tool(&self, q: &[f64]) -> Isometry3<f64> {
        let n = self.dof();
        let mut t = self.world_from_base;
        for (k, (joint, &qk)) in self.joints.iter().zip(q).enumerate() {
            t *= joint_motion(joint.kind, qk);
            if k + 1 < n {
                t *= self.link_from_next_frame(k);
            }
        }
        t * self.last_link_from_tool
    }

    /// A point fixed on link `k` (0-based), given in that link's moving frame, in the world.
    pub fn point_on_link(&self, q: &[f64], k: usize, point_in_link_m: &Point3<f64>) -> Point3<f64> {
        self.poses(q).world_from_link[k] * point_in_link_m
    }
}
