#![doc = include_str!("../README.md")]
#![warn(missing_docs)]
#![deny(clippy::float_cmp)]

pub mod kinematics;
pub mod robot;
pub mod sim;
