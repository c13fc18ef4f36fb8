//! Monte-Carlo studies of the calibrator on simulated campaigns (the answer key is known
//! here, so these live outside `calibration/`, which never sees it).

mod efficiency;

pub use efficiency::{EfficiencyStudy, QuantityEfficiency, RowSigmaCheck, StudyError, StudyReport, trial_seed};
