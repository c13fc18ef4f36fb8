//! Kinematics of the phi-model (paper appendix, eqs. A1-A4): transforms, forward
//! kinematics, the geometric Jacobian and inverse kinematics for arbitrary geometry.

mod chain;
mod jacobian;
mod phi;
mod rigid_fit;

pub use chain::{AxisLine, ChainPoses, PhiJoint, PhiModel};
pub use jacobian::{geometric_jacobian, point_jacobian};
pub use phi::{JointKind, PhiRow, frame_from_phi, joint_motion, link_from_phi};
pub use rigid_fit::rigid_fit;
