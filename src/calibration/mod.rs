//! Independent-axis calibration maths (paper sections 2-3, eqs. 1-15) on point sets: axis fits,
//! observed angles, transmission and coupling fits, and the statistics (Cramer-Rao bound) to
//! judge them. Pure maths: no files, no CLI, no truth model.
//!
//! - [`axis_circle`]: SVD plane + algebraic circle fit (the initial guess).
//! - [`arc_ml`]: the default estimator, a maximum-likelihood arc fit through the transmission.
//! - [`axis_paper`]: the paper's rotary-axis estimator, eqs. (1)-(5).
//! - [`crb`]: Cramer-Rao bound and Monte-Carlo efficiency.

mod error;
mod lsq;

pub mod arc_ml;
pub mod arc_model;
pub mod axis_circle;
pub mod transmission_fit;

pub mod crb;

pub use error::CalibrationError;
pub mod angles;
pub mod axis_paper;
pub mod coupling_fit;
