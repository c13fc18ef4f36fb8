//! Kinematics of the phi-model (paper appendix, eqs. A1-A4): transforms, forward
//! kinematics, the geometric Jacobian, inverse kinematics for arbitrary geometry, and the
//! conversion to Denavit-Hartenberg parameters (and why it fails on parallel axes), and the
//! conversion of classic DH, modified DH and URDF chains to the phi-model.

mod chain;
mod dh;
mod ik;
mod jacobian;
mod phi;
mod rigid_fit;
mod source;

pub use chain::{AxisLine, ChainPoses, FixedFrames, PhiJoint, PhiModel};
pub use dh::{
    CommonNormal, DhError, DhRow, DhTable, PARALLEL_TOLERANCE_RAD, ParallelPair, TiltSensitivity, common_normal,
    dh_from_phi, parallel_tilt_sensitivity,
};
pub use ik::{
    ClosedFormError, ClosedFormSolution, IkError, IkOptions, IkReport, IkSolution, REDUCED_ORIENTATION_WEIGHT_M,
    REDUCED_POSITION_TOLERANCE_M, ik_from_seed, nominal_closed_form, pose_error, rotation_vector, solve_ik,
    solve_seeded_by_nominal,
};
pub use jacobian::{geometric_jacobian, point_jacobian};
pub use phi::{JointKind, NEAR_LOCK_RAD, PhiRow, frame_from_phi, joint_motion, link_from_phi, roll_pitch_yaw};
pub use rigid_fit::{MIRROR_RATIO, centroid, mirror_fit_rms, rigid_fit};
pub use source::{DhConvention, DhParams, SourceChain, UrdfJoint, phi_model_of, phi_rule, row_to_line};
