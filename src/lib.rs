#![doc = include_str!("../README.md")]
#![warn(missing_docs)]
#![deny(clippy::float_cmp)]

pub mod calibration;
pub mod compensation;
pub mod diagnosis;
pub mod harness;
pub mod kinematics;
pub mod measurement;
pub mod numerics;
pub mod physics;
pub mod plan;
mod plotting;
pub mod robot;
pub mod sim;
pub mod toml_file;
#[cfg(feature = "viz")]
pub mod viz;
