//! Robot performance criteria of ISO 9283:1998 (*Manipulating industrial robots: performance
//! criteria and related test methods*), section 7, computed from attained poses: what a
//! calibration engineer reports to a customer beside the calibration itself. Pure maths on
//! poses: no files, no instrument, no robot model.
//!
//! - [`cube`]: the test cube (6.2, 6.8), its points `P1` .. `P5` and the commands that reach
//!   them.
//! - [`mod@evaluate`]: the figures of a measured campaign (experiments `iso-P<k>`), attained poses
//!   fitted to the tool targets, commanded ones from a robot model.
//! - [`check`]: figures read back from a file are figures `evaluate` can have written.
//! - [`commands`]: every cycle of a pose commands its pose's values, and no pose's commands
//!   are in radians.
//! - [`outliers`]: cycles far from their pose's others, set aside before the figures.
//! - [`frame`]: the instrument frame's scale and handedness against the description.
//! - [`figures`]: pose accuracy and repeatability (7.2.1, 7.2.2), multi-directional pose
//!   accuracy variation (7.2.3), distance accuracy and repeatability (7.3).
//! - [`predict`](mod@predict): the figures predicted before a test, by Monte-Carlo over the
//!   calibration's covariance, the robot's repeatability and the instrument's noise.

pub mod check;
pub mod commands;
pub mod cube;
pub mod evaluate;
pub mod figures;
pub mod frame;
pub mod outliers;
pub mod predict;

pub use cube::{
    Cube, CubeError, MIN_CUBE_JOINTS, approach_commands, check_cube_robot, cube_of_edge, cube_points, largest_cube,
    plan_cube,
};
pub use evaluate::{EvaluateOptions, IsoError, IsoFigures, PoseFigures, evaluate, pose_label};
pub use figures::{
    DirectionalVariation, DistanceFigures, PoseAccuracy, PoseRepeatability, abc, directional_variation,
    distance_figures, pose_accuracy, pose_repeatability,
};
pub use outliers::OutlierCycle;
pub use predict::{CYCLE_ORDER, IsoPrediction, PredictedPose, PredictionError, PredictionInputs, cycle_rows, predict};
