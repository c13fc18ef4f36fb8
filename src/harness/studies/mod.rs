//! Monte-Carlo studies of the calibrator on simulated campaigns (the answer key is known
//! here, so these live outside `calibration/`, which never sees it).

mod efficiency;
mod tool_accuracy;

pub use efficiency::{
    CampaignBoundSummary, DerivedEfficiency, EfficiencyStudy, QuantityEfficiency, RowSigmaCheck, StudyError,
    StudyReport, trial_seed,
};
pub use tool_accuracy::{ToolAccuracyCheck, ToolAccuracyError, ToolAccuracyStudy};
