//! The predicted tool accuracy of a calibration, inside the swept spans and over the
//! workspace, with the map's poses.

use anyhow::Result;
use axiscal::calibration::procedure::Calibration;
use axiscal::calibration::procedure::axis_experiments_with;
use axiscal::calibration::tool_accuracy::{MapPoint, PredictionOptions, ToolAccuracy, predict, swept_ranges};
use axiscal::measurement::MeasurementSet;
use axiscal::robot::RobotDescription;

/// The tool accuracy of `cal` inside the spans of `set`'s sweeps and over the joint limits
/// ([`tool_accuracy`]).
pub(super) fn predict_tool_accuracy(
    cal: &Calibration,
    desc: &RobotDescription,
    set: &MeasurementSet,
    held_tolerance: f64,
) -> Result<(Option<ToolAccuracy>, Vec<MapPoint>)> {
    let (experiments, _) = axis_experiments_with(set, desc, held_tolerance)?;
    let spans = swept_ranges(&experiments, &cal.reference_cmd);
    Ok(tool_accuracy(cal, desc, spans))
}

/// The tool accuracy of a free-pose calibration ([`tool_accuracy`]): "inside the spans" is
/// within the range of every joint's values over the rows of `set`.
pub(super) fn predict_free_pose_accuracy(
    cal: &Calibration,
    desc: &RobotDescription,
    set: &MeasurementSet,
) -> (Option<ToolAccuracy>, Vec<MapPoint>) {
    let spans = (0..desc.dof())
        .map(|k| {
            set.rows()
                .iter()
                .map(|r| r.cmd[k])
                .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], v| [lo.min(v), hi.max(v)])
        })
        .collect();
    tool_accuracy(cal, desc, spans)
}

/// The tool accuracy of `cal` predicted over `spans` and the workspace, with the workspace
/// poses for the map (neither without a model covariance).
pub(super) fn tool_accuracy(
    cal: &Calibration,
    desc: &RobotDescription,
    spans: Vec<[f64; 2]>,
) -> (Option<ToolAccuracy>, Vec<MapPoint>) {
    // The calibration stands without its prediction: a model that cannot execute some drawn
    // pose (a fitted transmission not invertible beyond the data's range) is said, not fatal.
    match predict(cal, desc, spans, PredictionOptions::default()) {
        Ok(Some((accuracy, map))) => (Some(accuracy), map),
        Ok(None) => (None, vec![]),
        Err(e) => {
            eprintln!("warning: the tool accuracy is not predicted: {e}");
            (None, vec![])
        }
    }
}
