//! The paper's accuracy test (section 4, figs. 9 and 10) closed in the loop: required tool
//! poses, the commands of the uncalibrated controller and of the compensation (fig. 5),
//! executed by the simulated real robot and observed through the instrument; the
//! repeatability test; the noise floor; plots.

mod accuracy;
mod paper;
mod plots;
mod poses;

pub use accuracy::{EvaluationError, Stats, TestBench, ToolError, pose_rng};
pub use paper::{
    PAPER_ORIENTATION_ERROR_RAD, PAPER_POSITION_ERROR_MM, PAPER_REPEATABILITY, PaperOutcome, PaperReport,
    PaperScenario, PoseResult, RegionSummary, RepeatabilitySummary, ScenarioError, evaluate_pose, run_paper_scenario,
    scenario_poses,
};
pub use plots::{PlotError, write_plots};
pub use poses::{JointRanges, Region, TestPose, iso9283_poses, largest_iso9283_cube, random_poses};
