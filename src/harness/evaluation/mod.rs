//! The paper's accuracy test (section 4, figs. 9 and 10) closed in the loop: required tool
//! poses, the commands of the uncalibrated controller and of the compensation (fig. 5),
//! executed by the simulated real robot and observed through the instrument; the
//! repeatability test; the noise floor; the paper's gap budget; plots.

mod accuracy;
mod budget;
mod paper;
mod plots;
mod poses;

pub use accuracy::{APPROACH_STEP, EvaluationError, Stats, TestBench, ToolError, pose_rng};
pub use budget::{
    BudgetEffect, BudgetLine, BudgetReport, BudgetSettings, STEEL_ALPHA_PER_K, budget_line, gap_budget,
    gap_budget_with, pooled_error,
};
pub use paper::{
    FloorCheck, PAPER_ORIENTATION_ERROR_RAD, PAPER_POSITION_ERROR_MM, PAPER_REPEATABILITY, PaperOutcome, PaperReport,
    PaperScenario, PoseResult, RegionSummary, RepeatabilitySummary, ScenarioError,
    calibrated_position_error_inside_spans, evaluate_pose, floor_check, floor_check_with, run_paper_scenario,
    run_paper_scenario_with, scenario_poses,
};
pub use plots::{PLOT_FILES, PlotError, write_plots};
pub use poses::{JointRanges, Region, TestPose, iso9283_poses, largest_iso9283_cube, random_poses};
