#![doc = include_str!("../README.md")]
#![warn(missing_docs)]
#![deny(clippy::float_cmp)]

pub mod blind;
pub mod calibration;
pub mod campaign;
pub mod compensation;
pub mod diagnosis;
pub mod evaluation;
pub mod kinematics;
pub mod measurement;
mod plotting;
pub mod robot;
pub mod scenario;
pub mod sim;
pub mod studies;
pub mod toml_file;
#[cfg(feature = "viz")]
pub mod viz;
