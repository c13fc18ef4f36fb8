//! Refinement of the calibrated independent-axis model on free poses (validation poses measured
//! anywhere in the workspace): the one implementation shared by `calibrate --refine`
//! ([`refine_free_poses`]) and the diagnosis's baseline refit
//! ([`crate::diagnosis`]).
//!
//! The model is a residual function of small corrections `p` to the calibrated parameters
//! (rows, zero offsets, transmission harmonics, coupling coefficients, base and tool frames;
//! its layout is the caller's, [`RefitParameter`] names each). Both users:
//! 1. linearise it at the calibrated model by central differences ([`sensitivity`]);
//! 2. solve the linearised problem rank-revealingly ([`LinearFit`], a truncated SVD);
//! 3. refine from that solution by Gauss-Newton steps re-linearised at the current parameters
//!    ([`refine_from_linear`]; the program's one least-squares loop,
//!    [`levenberg_marquardt_from`](crate::numerics::lsq::levenberg_marquardt_from), monotone, the same truncation).
//!
//! Pure maths: no files, no CLI, no simulator.

mod free_poses;
mod linear;
mod parameters;
mod prior;
mod report;
mod steps;

pub use free_poses::{
    DroppedDirection, FoldCheck, IMPLAUSIBLE_RMS_OVER_NOISE, ParameterChange, RefineError, RefineOptions, Refinement,
    RefinementResult, enough_free_poses, refine_free_poses,
};
pub use linear::{Block, LinearFit, NULL_DIRECTION_TOLERANCE, sensitivity};
pub use parameters::{DirectionWeight, ParameterUnit, RefitParameter};
pub use prior::unrefined_sigma;
pub use report::markdown;

pub use steps::{GaussNewtonSteps, Refined, refine_from_linear, refine_from_linear_with};
