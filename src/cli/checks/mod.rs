//! Checks between a command's inputs before any work: unit slips (`--skip-unit-check`,
//! [`units`]) and the identity of the robot description a calibration or a data file was made
//! with (`--allow-other-robot`, [`identity`]); and what the fits found in the data, said by the
//! file's lines ([`findings`]).

mod findings;
mod identity;
mod units;

pub(super) use findings::outlier_place;
pub use findings::{
    explained_miss_words, noise_far_below, outlier_warnings, print_approach_notes, print_outliers, print_pose_outliers,
    print_sweep_bumps, refuse_explained_misses, unsearched_words,
};
pub use identity::{
    data_identity, description_suspect, identity_comment, one_setup, outside_limits, read_calibration,
    read_calibration_warned, read_data, read_data_warned, same_robot,
};
pub use units::{
    description_units, description_warning_lines, import_units, pose_units, scenario_units, truth_units,
    within_a_radians_turn,
};

/// The comment line that records, in a measurement CSV written by axiscal, the description the
/// data were made with: this prefix, then the identity as JSON.
pub const IDENTITY_COMMENT: &str = "# axiscal.description ";

/// The two overrides of these checks, shared by the commands that read a description with a
/// calibration or data made for it (`calibrate`, `diagnose`, `validate`, `compensate`).
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct Overrides {
    /// Skip the unit sanity checks (coordinates in m instead of mm, commands in rad instead of
    /// deg, description lengths in mm instead of m) when the units are right after all.
    #[arg(long)]
    pub skip_unit_check: bool,
    /// Go on even when the calibration or DATA records another robot description than
    /// `--robot` (a different geometry hash).
    #[arg(long)]
    pub allow_other_robot: bool,
}

/// Prints each of `warnings` as a `warning:` line on stderr.
pub fn print_warnings(warnings: &[String]) {
    for w in warnings {
        eprintln!("warning: {w}");
    }
}
