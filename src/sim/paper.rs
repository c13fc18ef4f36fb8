//! The paper's robot as the simulated truth: the ASEA IRB/L6 as Sultan & Wager calibrated it
//! (Table 2's actual rows and the section-4 transmission and coupling functions).

use crate::robot::RobotModel;
use std::path::Path;

/// Where the paper robot's model file sits in the repository (compiled in).
pub const PAPER_ROBOT_FILE: &str = "scenarios/robots/asea-irb6l-paper-truth.toml";

/// The paper's robot (`scenarios/robots/asea-irb6l-paper-truth.toml`): Table 2 actual rows
/// and the section-4 functions.
pub fn paper_robot() -> RobotModel {
    let text = include_str!("../../scenarios/robots/asea-irb6l-paper-truth.toml");
    RobotModel::from_toml_str(text, Path::new(PAPER_ROBOT_FILE))
        .expect("the shipped paper robot model is valid (checked by tests)")
}
