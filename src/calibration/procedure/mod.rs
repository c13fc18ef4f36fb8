//! The independent-axis procedure over a whole campaign (paper sections 2-4): every axis
//! from its own experiment, the transmission functions (eq. 8) and passive couplings
//! (eqs. 14-15), the actual phi-model at the common reference pose with the section-4 base
//! frame, joint zero offsets, and the tool frame from the three tool targets.
//!
//! Conventions (`docs/method.md`, "Joint offsets and the reference pose"): the calibrated joint values at the reference pose are the
//! reference commands; `theta_act_k = f_k^-1(u_k - offset_k)` and
//! `q_k = theta_act_k + g_{k-1,k}(theta_act_{k-1})`, the same semantics as the truth model,
//! so a calibrated robot is expressed as a [`RobotModel`](crate::robot::RobotModel)-shaped model (a data type; no truth
//! value is read).
//!
//! Repeatability ([`CalibrationOptions::repeatability_sigma_rad`], default the description's
//! `repeatability_sigma`): the swept actuator is re-positioned at every step, so its error is
//! noise on each point's angle, which the ML axis fit weights and reports
//! ([`super::fit_arc_with_angle_noise`]). The joints held still below a sweep keep one error
//! through it: a bias of that axis, added to its reported covariance
//! ([`super::crb::held_joint_axis_covariance`]) but not propagated to the rows (the same held
//! error turns all axes above the joint together, which changes no row). Not modelled: the
//! correlation that bias creates between axes, the held error as an error of the joint's
//! value at the reference, and the repeatability in the paper's estimator. The couplings
//! (eqs. 14-15), zero offsets and tool frame get a 1-sigma propagated from the axis fits and
//! the second and tool targets (`propagation`); the coupling fit's own a-posteriori sigma is
//! kept beside it (`CouplingReport::fit_only_sigma`).

mod assembly_cache;
mod axis_fit;
mod coupling_start;
mod error;
mod experiments;
mod frames;
mod height;
mod held;
mod joint_map;
mod joints;
mod misfit;
mod on_axis;
mod options;
mod outlier_point;
mod pipeline;
mod propagation;
mod recorded_coupling;
mod report;
mod result;
mod sanity;
mod screen;
mod second_targets;
mod simulated_sweeps;
mod size;
mod sweeps_agree;
mod uncertainty;
mod urdf;
mod validate;

pub use error::{ProcedureError, ShortSpan};
pub use experiments::{AxisExperiment, COMMAND_TOLERANCE, axis_experiments, axis_experiments_with};
pub use frames::{BaseRule, FramesError, NominalGeometry, common_normal_feet, model_from_axes};
pub use joint_map::{
    JointMap, MapRow, MapTable, ZeroOffsetFit, calibrated_joint_values, controller_zero_offsets, joint_map,
};
pub use misfit::SweepMisfit;
pub use on_axis::{TargetOnAxis, target_on_axis};
pub use options::{AxisEstimator, CalibrationOptions, DEFAULT_HELD_TOLERANCE, Detail};
pub use outlier_point::{OutlierPoint, OutlierTest};
pub use pipeline::{FittedModel, calibrate, calibrate_model};
pub use propagation::{DerivedSigma, FrameSigma, ZeroOffsetSigma};
pub use report::{Finding, findings, markdown, read_residuals_csv, residuals_csv, warnings_section};
pub use result::{
    AxisReport, AxisSpan, Calibration, CouplingReport, DirectionSigma, HarmonicReport, HeldOffset, NoiseReport,
    PointResidual, PositionSigma, RowSigma, SweepReport, ToolPose, ToolReport, harmonics,
};
pub use sanity::{
    ColumnSource, DOUBT_SIGMAS, Implausible, JointSlope, LEAD_SPREAD, MISFIT_RATIO, MisfitSweep,
    PLAUSIBLE_AXIS_TILT_RAD, PLAUSIBLE_LEAD_DEVIATION, PLAUSIBLE_TURN_DEVIATION, Refit, SCALE_SIGMAS, SIZE_TOLERANCE,
    SPACING_SIGMAS, ScaleDoubt, ScaleReach, ScaleSlip, SpacingScale, column_source, free_pose_scale_doubts,
    free_pose_scale_reach, free_pose_scale_slips, implausible, joint_slopes, longest_length_m, named_joints,
    scale_doubts, scale_reach, tool_spacing_scale, with_column_source,
};
pub use screen::{
    OUTLIER_ROUNDS_MAX, OUTLIER_SHARE_MAX, SWEEP_BUMP_FALSE_ALARM, SWEEP_POINTS_FALSE_ALARM, Screening, SweepBump,
    SweepEnd, WorstSecondTarget, bumps_undone, screen_sweeps, screen_wandering_sweeps, wandering_sweep_bumps,
    without_poses,
};
pub use second_targets::SecondTargetData;
pub use simulated_sweeps::simulated_sweeps;
pub use sweeps_agree::{SweepsAgreement, sweeps_agreement};
pub use uncertainty::{AxisCovariance, SIGNIFICANT_SIGMAS, row_sigmas};
pub use urdf::{
    RawReadingDeviation, UrdfOptions, UrdfRoot, joints_without_speed_limits, raw_reading_deviation, ros_name, urdf,
};
pub use validate::{InvalidCalibration, MAX_NOISE_RMS_3D_MM, MAX_PARAMETER_VARIANCE};
