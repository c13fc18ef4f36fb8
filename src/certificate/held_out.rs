//! Before and after calibration on held-out poses: the validation poses of a measurement file
//! (rows with `moved_joint = 0` other than the tool observation), which the calibration does
//! not use. After: the calibrated model's prediction of every target ([`validate`], with its
//! chi-square verdict against the noise). Before: the nominal model's, its base frame
//! registered to the same points (the rigid transform that best maps its predictions onto the
//! measurements, [`rigid_fit`]), so that where the robot stands in the instrument frame, which
//! nobody knows before a calibration, is not counted as its error. Points the calibrated model
//! misses beyond its prediction are a warning ([`HeldOut::warning`]): data in other units or of
//! another setup look like a calibration that failed.

use crate::calibration::record::CalibrationRecord;
use crate::diagnosis::{CleanCampaign, ValidationOptions, Verdict, is_validation, validate};
use crate::kinematics::rigid_fit;
use crate::measurement::MeasurementSet;
use crate::robot::{RobotDescription, RobotModel};
use nalgebra::Point3;
use serde::Serialize;

/// The two-sided false-alarm rate of the held-out poses' test (`validate`'s default).
pub const HELD_OUT_FALSE_ALARM: f64 = 0.01;

/// The two models on held-out poses.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct HeldOut {
    /// The file.
    pub file: String,
    /// Held-out points (targets measured at validation poses).
    pub points: usize,
    /// The nominal model, base registered.
    pub before: ErrorLine,
    /// The calibrated model.
    pub after: ErrorLine,
    /// The RMS the noise alone predicts for the calibrated model \[mm\].
    pub noise_predicted_rms_mm: f64,
    /// The calibration's own predicted tool position error, RMS over poses inside its spans
    /// \[mm\] (its covariance propagated, `tool_accuracy`), when it has one.
    pub predicted_tool_spans_rms_mm: Option<f64>,
    /// The same over the workspace (every joint within its limits) \[mm\].
    pub predicted_tool_workspace_rms_mm: Option<f64>,
    /// The RMS error of the calibrated model the noise, the robot's repeatability and the
    /// calibration's own error together predict on these points \[mm\] (`validate`'s
    /// `validation.predicted_mm.total`).
    pub predicted_rms_mm: f64,
    /// Whether the calibrated model misses these points beyond that prediction (`validate`'s
    /// position test of the validation points: `exceeds`).
    pub beyond_prediction: bool,
    /// `validate`'s verdict on the calibrated model, in words.
    pub verdict: String,
}

impl HeldOut {
    /// What to check when the calibrated model misses the held-out points beyond its
    /// prediction; `None` when it does not.
    pub fn warning(&self) -> Option<String> {
        if !self.beyond_prediction {
            return None;
        }
        let worse = if self.after.rms_mm > self.before.rms_mm {
            format!(
                ", worse than the nominal model's {:.4} mm (base registered)",
                self.before.rms_mm
            )
        } else {
            String::new()
        };
        Some(format!(
            "held-out poses of {}: the calibrated model misses them by {:.4} mm RMS (max {:.4} mm) where the noise, the robot's repeatability and the calibration's own error predict {:.4} mm{worse}: check the held-out file's units (coordinates in mm, commands in degrees), its target ids, and that it was measured on this robot in this setup; until then the calibration's accuracy on it is not shown",
            self.file, self.after.rms_mm, self.after.max_mm, self.predicted_rms_mm
        ))
    }
}

/// Position errors of one model.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ErrorLine {
    /// RMS \[mm\].
    pub rms_mm: f64,
    /// Largest \[mm\].
    pub max_mm: f64,
}

/// Why held-out poses could not be compared.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum HeldOutError {
    /// The file has no validation pose.
    #[error("no held-out poses: the file has no rows with moved_joint = 0 other than the tool observation")]
    NoPoses,
    /// A model could not predict the data.
    #[error("{0}")]
    Model(String),
}

/// The errors of predicted against measured points \[mm\].
fn errors(predicted: &[Point3<f64>], measured: &[Point3<f64>]) -> ErrorLine {
    let d: Vec<f64> = predicted
        .iter()
        .zip(measured)
        .map(|(p, m)| (p - m).norm() * 1e3)
        .collect();
    ErrorLine {
        rms_mm: (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt(),
        max_mm: d.iter().copied().fold(0.0, f64::max),
    }
}

/// The nominal and calibrated models on the held-out poses of `set` (`file` its name), the
/// calibrated model tested against the noise it was weighted with, the robot's repeatability
/// and its own predicted error ([`validate`]) and tool accuracy (`record`'s reports).
pub fn held_out(
    file: &str,
    set: &MeasurementSet,
    record: &CalibrationRecord,
    desc: &RobotDescription,
) -> Result<HeldOut, HeldOutError> {
    let cal = &record.calibration;
    let rows: Vec<usize> = (0..set.rows().len())
        .filter(|&i| is_validation(&set.rows()[i]))
        .collect();
    if rows.is_empty() {
        return Err(HeldOutError::NoPoses);
    }
    let model = |e: crate::diagnosis::DiagnosisError| HeldOutError::Model(e.to_string());
    let targets = desc.tool_targets_m();
    let measured: Vec<Point3<f64>> = rows.iter().map(|&i| set.rows()[i].position_m()).collect();
    let pick = |all: Vec<Point3<f64>>| -> Vec<Point3<f64>> { rows.iter().map(|&i| all[i]).collect() };
    let nominal = pick(
        CleanCampaign::on_robot(set, &RobotModel::ideal(desc), desc, &targets)
            .map_err(model)?
            .positions(),
    );
    let calibrated = pick(CleanCampaign::new(set, cal, desc, &targets).map_err(model)?.positions());
    let (registration, _) = rigid_fit(&nominal, &measured).ok_or_else(|| {
        HeldOutError::Model("the held-out points are fewer than three or in a line: no base to register".into())
    })?;
    let registered: Vec<Point3<f64>> = nominal.iter().map(|p| registration * p).collect();
    let (before, after) = (errors(&registered, &measured), errors(&calibrated, &measured));
    // Let go before the validation: a million-row file's points are not held beside its rows.
    drop((nominal, calibrated, registered, measured));
    let v = validate(
        set,
        cal,
        desc,
        &ValidationOptions::of_calibration(cal, HELD_OUT_FALSE_ALARM),
    )
    .map_err(model)?;
    let summary = v.validation.as_ref().ok_or(HeldOutError::NoPoses)?;
    let accuracy = record.reports.tool_accuracy.as_ref();
    Ok(HeldOut {
        file: file.to_string(),
        points: rows.len(),
        before,
        after,
        noise_predicted_rms_mm: summary.predicted_mm.noise,
        predicted_tool_spans_rms_mm: accuracy.map(|t| t.spans.position_rms_mm),
        predicted_tool_workspace_rms_mm: accuracy.map(|t| t.workspace.position_rms_mm),
        predicted_rms_mm: summary.predicted_mm.total,
        beyond_prediction: summary
            .chi_square
            .as_ref()
            .is_some_and(|c| c.verdict == Verdict::Exceeds),
        verdict: v.verdict.clone(),
    })
}
