//! Why a free-pose calibration failed ([`FreePoseError`]), in the words a metrology engineer
//! checks the poses with.

use crate::numerics::lsq::LsqError;

/// The fewest poses a free-pose calibration registers the robot's base to: two poses leave a
/// turn about the line through their tool points undetermined.
pub const MIN_POSES: usize = 3;

/// Why a free-pose calibration failed.
#[derive(Debug, thiserror::Error)]
pub enum FreePoseError {
    /// Too few poses for the parameters.
    #[error(
        "{poses} free poses with {points} points: fitting {parameters} parameters needs at least {needed} points (3 coordinates each) on at least {MIN_POSES} poses"
    )]
    TooFewPoints {
        /// Poses.
        poses: usize,
        /// Points.
        points: usize,
        /// Parameters of the registration.
        parameters: usize,
        /// Points needed.
        needed: usize,
    },
    /// One pose's rows name different setups.
    #[error("{pose}: its rows name different setups (one pose is measured from one instrument placement)")]
    SetupsDiffer {
        /// The pose.
        pose: String,
    },
    /// A setup's poses do not place the instrument.
    #[error("setup {setup}: its points do not place the instrument (fewer than three non-collinear tool positions)")]
    SetupUnplaced {
        /// The setup's label.
        setup: String,
    },
    /// The model cannot execute a pose's commands: the fit moved a transmission until it turns
    /// back on itself at this pose's command.
    #[error(
        "{pose}: the fit moved the model so far from the description that no joint angle gives this pose's \
         commands (a fitted transmission turns back on itself there): the points pull the model where the \
         description's robot cannot go; check this pose's rows, the units of the commands and coordinates, the \
         joint order and the target ids against the description"
    )]
    Unexecutable {
        /// The pose.
        pose: String,
    },
    /// The closed-form registration failed.
    #[error("the points do not fix the instrument frame (fewer than three non-collinear tool positions)")]
    Registration,
    /// The least-squares fit failed.
    #[error("{}", fit_words(.0))]
    Fit(LsqError),
    /// The calibrated model misses the points by a good part of their own spread.
    #[error(
        "the calibrated model misses the points by {rms_mm:.3} mm RMS, {percent:.1} % of their spread about their centroid ({spread_mm:.1} mm): the description does not describe this robot or these data (check the robot file, the joint order and directions, the units of the commands and coordinates, and that each target id is one physical target)"
    )]
    Absurd {
        /// Calibrated RMS \[mm\].
        rms_mm: f64,
        /// The points' RMS distance from their centroid \[mm\].
        spread_mm: f64,
        /// The ratio in percent.
        percent: f64,
    },
    /// Too many outliers.
    #[error(
        "{flagged} of {poses} poses fail the outlier test: the nominal description, not single poses, misses these data (check the robot, the units and the joint directions)"
    )]
    TooManyOutliers {
        /// Poses flagged.
        flagged: usize,
        /// Poses fitted.
        poses: usize,
    },
}

/// A failed free-pose fit in words: what it means for the poses and what to do.
fn fit_words(e: &LsqError) -> String {
    match e {
        LsqError::IllConditioned { condition_number, .. } => format!(
            "the poses do not determine the model: some change of its parameters moves none of the measured points \
             (the fit's sensitivities to them are dependent, condition number {condition_number:.1e}): too few \
             distinct configurations, a joint that does not move among the poses, or a description whose joints \
             are not this robot's; measure the robot at more configurations across its workspace, or check the \
             description and the joint order"
        ),
        LsqError::NotConverged {
            iterations,
            residual_rms,
            ..
        } => format!(
            "the fit does not settle: after {iterations} steps its parameters still move, with the points {:.3} mm \
             RMS (per coordinate) from the model: the poses leave a combination of parameters free (too few distinct \
             configurations, or joints that barely move among them), or they fit no model near the description's; \
             measure the robot at more configurations across its workspace, or check the description and the \
             units",
            residual_rms * 1e3
        ),
    }
}
