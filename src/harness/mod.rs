//! Harnesses: the code that knows both sides of the truth boundary. Each simulates a robot
//! ([`crate::sim`]), hands only the measurements and the nominal description to the
//! calibrator or the diagnoser, and then compares what they found with what was simulated.
//!
//! - [`evaluation`]: the paper scenario end to end (simulate, calibrate, compensate, the
//!   accuracy and repeatability tests of section 4, the noise floor) and the gap budget.
//! - [`scenario`]: Monte-Carlo scenario files, trials, statistics, thresholds, shards.
//! - [`studies`]: the calibrator's efficiency against the Cramer-Rao bound.
//! - [`blind`]: the blind check of the diagnosis (hidden keys, confusion matrix).

pub mod blind;
pub mod evaluation;
pub mod scenario;
pub mod studies;
