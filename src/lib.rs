#![doc = include_str!("../README.md")]
#![warn(missing_docs)]
#![deny(clippy::float_cmp)]

pub mod calibration;
pub mod campaign;
pub mod kinematics;
pub mod measurement;
pub mod robot;
pub mod sim;
#[cfg(feature = "viz")]
pub mod viz;
