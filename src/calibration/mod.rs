//! Independent-axis calibration maths (paper sections 2-3, eqs. 1-15) on point sets: axis fits,
//! observed angles, transmission and coupling fits, and the statistics (Cramer-Rao bound) to
//! judge them. Pure maths: no files, no CLI, no truth model or simulator.
//!
//! - [`axis_circle`]: SVD plane + algebraic (Kasa) circle fit, the initial guess.
//! - [`arc_model`] + [`arc_ml`]: the default estimator, a maximum-likelihood arc fit through
//!   the transmission model (efficient: attains the Cramer-Rao bound).
//! - [`axis_paper`]: the paper's rotary-axis estimator, eqs. (1)-(5).
//! - [`angles`]: observed angles, eqs. (6)-(7); [`transmission_fit`]: eq. (8).
//! - [`sliding`]: sliding axes, eqs. (9)-(13); [`coupling_fit`]: couplings, eqs. (14)-(15).
//! - [`line_ml`]: the maximum-likelihood sliding-axis fit (eqs. 9-13 in one model).
//! - [`noise`]: the instrument noise estimated from the pooled fit residuals.
//! - [`crb`]: Cramer-Rao bound and Monte-Carlo efficiency.
//! - [`free_pose`]: calibration from free poses (no axis experiments): registration, the
//!   identifiable parameters, the fit, outliers, sigmas and a held-out check.
//! - [`export`]: the calibrated kinematics in the files a robot's software loads (UR
//!   `kinematics.yaml`, per-joint URDF origins), each read back and checked.
//! - [`refine`]: the calibrated model refined on free poses (`calibrate --refine`, the
//!   diagnosis's baseline refit).
//! - [`recalibrated`]: the checks that calibrate a file again on its data altered (an
//!   instrument axis' scale undone, named bumps moved back, the scale profile's fits, free
//!   poses' column scales undone).

mod error;

pub mod angles;
pub mod arc_ml;
pub mod arc_model;
pub mod axis_circle;
pub mod axis_paper;
pub mod coupling_fit;
pub mod crb;
pub mod export;
pub mod free_pose;
pub mod line_ml;
pub mod model_parameters;
pub mod noise;
pub mod outputs;
pub mod procedure;
pub mod recalibrated;
pub mod record;
pub mod refine;
pub mod refit_model;
pub mod screened;
pub mod shared_target;
pub mod sliding;
pub mod tool_accuracy;
pub mod tool_map;
pub mod transmission_fit;

pub use arc_ml::{ArcFit, ArcFitOptions, Studies, fit_arc, fit_arc_with_angle_noise, fit_arc_with_angle_noise_studies};
pub use arc_model::{ArcModel, ArcParams, MeasurementNoise};
pub use axis_circle::{CircleFit, fit_circle};
pub use axis_paper::{PaperAxisFit, fit_axis_paper};
pub use error::CalibrationError;
pub use transmission_fit::{TransmissionFit, fit_transmission};
