//! The robot's size and how far a description may be off it: shared by the sanity checks
//! (`sanity/`) and the pipeline (`height.rs`'s move along parallel axes), which must not
//! import each other.

use crate::robot::RobotDescription;

/// The size factor may differ from 1 by this much before it is said: a description of the
/// robot measured is within a few per cent of it.
pub const SIZE_TOLERANCE: f64 = 0.2;

/// The lengths `a`, `b`, `h` of every row of `rows` \[m\].
pub(super) fn row_lengths(rows: &[crate::kinematics::PhiRow]) -> Vec<f64> {
    rows.iter().flat_map(|r| [r.a_m, r.b_m, r.h_m]).collect()
}

/// The longest length of the description's rows \[m\]: the robot's size, which
/// `SIGNIFICANT_LENGTH` (`sanity/`) and [`SIZE_TOLERANCE`] are shares of.
pub fn longest_length_m(desc: &RobotDescription) -> f64 {
    row_lengths(&desc.nominal_model().rows)
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()))
}
