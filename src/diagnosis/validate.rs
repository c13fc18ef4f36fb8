//! Validation of a calibration on measured data (`axiscal validate`,
//! `docs/formats.md#validation-summary-json`): every measured point of a measurement CSV
//! predicted by the calibrated model, the residuals summarised and tested against what the
//! measurement noise predicts.
//!
//! Predictions ([`clean_positions`]): a validation or tool pose's targets through the
//! controller (fig. 3) and the calibrated chain (eqs. A1-A4) to the description's tool
//! targets; an axis experiment's targets at their mean position in their link's frame (the
//! description does not say where the reflector sits on the link), which costs 3 degrees of
//! freedom per experiment and target.
//!
//! Test: with isotropic measurement noise of 3-D RMS `s` (each coordinate `s / sqrt(3)`) and
//! a correct model, `chi2 = sum |r|^2 / (s^2 / 3)` follows a chi-square distribution with
//! `3 n - 3 g` degrees of freedom (`n` points, `g` estimated target positions). A pose with the
//! three tool targets also gives its orientation: the measured tool frame is the rigid fit of
//! the description's tool targets to the measured points ([`rigid_fit`]), its rotation error
//! `w` (tool frame) has the covariance `(s^2 / 3) M^-1`, `M = sum_i (|d_i|^2 I - d_i d_i^T)`
//! (`d_i` a tool target relative to their centroid: the normal matrix of the linearised fit),
//! so `w^T M w / (s^2 / 3)` is chi-square with 3 degrees of freedom per pose.
//!
//! The predicted uncertainty is the measurement noise only: the calibrated parameters'
//! covariance is not propagated to the prediction, so a calibration from few points reads
//! slightly worse than it is (the excess is reported as `excess_rms_mm`).

use super::DiagnosisError;
use super::noise::{calibrated_joint_values, clean_positions};
use crate::calibration::procedure::Calibration;
use crate::kinematics::rigid_fit;
use crate::measurement::{Measurement, MeasurementSet};
use crate::numerics::stats::chi_square_cdf;
use crate::plan::TOOL_EXPERIMENT;
use crate::robot::{Controller, RobotDescription};
use nalgebra::{Isometry3, Matrix3, Point3, Vector3};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};

/// Options of [`validate`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ValidationOptions {
    /// Measurement noise of a point, 3-D RMS \[mm\] (`> 0`).
    pub noise_rms_3d_mm: f64,
    /// Where it comes from (`calibration`, `given`), for the report.
    pub noise_source: String,
    /// Two-sided false-alarm rate of the chi-square verdicts.
    pub false_alarm: f64,
}

/// Which kind of measured point a residual belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PointKind {
    /// A validation pose (`moved_joint = 0`, not `tool`).
    Validation,
    /// The tool observation (`experiment = tool`).
    Tool,
    /// A point of an axis experiment.
    Axis,
}

/// One measured point against its prediction (a row of `residuals.csv`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ValidationResidual {
    /// Experiment id.
    pub experiment: String,
    /// Its kind.
    pub kind: PointKind,
    /// The experiment's moved joint (0 for free poses).
    pub moved_joint: usize,
    /// Step.
    pub step: usize,
    /// Target id.
    pub target: usize,
    /// Measured position, instrument frame \[mm\].
    pub measured_mm: [f64; 3],
    /// Predicted position \[mm\].
    pub predicted_mm: [f64; 3],
    /// `|measured - predicted|` \[mm\].
    pub error_mm: f64,
}

/// A chi-square verdict of residuals against their predicted uncertainty.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ChiSquare {
    /// The statistic.
    pub value: f64,
    /// Its degrees of freedom.
    pub dof: usize,
    /// `value / dof` (1 expected).
    pub per_dof: f64,
    /// Upper-tail probability `P(chi2 >= value)`.
    pub p_value: f64,
    /// `consistent`, `exceeds_noise` (upper tail below half the false-alarm rate) or
    /// `below_noise` (lower tail below it: the stated noise is too large).
    pub verdict: String,
}

impl ChiSquare {
    /// The verdict of `value` with `dof` degrees of freedom at two-sided rate `false_alarm`;
    /// `None` without degrees of freedom.
    pub fn new(value: f64, dof: usize, false_alarm: f64) -> Option<Self> {
        if dof == 0 {
            return None;
        }
        // An infinite or undefined statistic (a residual that overflowed) exceeds any noise.
        let cdf = if value.is_finite() {
            chi_square_cdf(value, dof as f64)
        } else {
            1.0
        };
        let verdict = if 1.0 - cdf < 0.5 * false_alarm {
            "exceeds_noise"
        } else if cdf < 0.5 * false_alarm {
            "below_noise"
        } else {
            "consistent"
        };
        Some(ChiSquare {
            value,
            dof,
            per_dof: value / dof as f64,
            p_value: 1.0 - cdf,
            verdict: verdict.into(),
        })
    }
}

/// Position residuals of one kind of point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PositionSummary {
    /// Measured points.
    pub points: usize,
    /// RMS of `|measured - predicted|` \[mm\].
    pub rms_mm: f64,
    /// Mean \[mm\].
    pub mean_mm: f64,
    /// Largest \[mm\].
    pub max_mm: f64,
    /// The RMS the noise alone predicts \[mm\]: `s sqrt(dof / (3 n))`.
    pub predicted_rms_mm: f64,
    /// `sqrt(max(0, rms^2 - predicted^2))`: the model error beyond the noise \[mm\].
    pub excess_rms_mm: f64,
    /// Target positions estimated from these data (axis experiments: one per experiment and
    /// target).
    pub estimated_targets: usize,
    /// The chi-square test (absent without degrees of freedom).
    pub chi_square: Option<ChiSquare>,
}

/// Orientation errors of the poses with three tool targets.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct OrientationSummary {
    /// Poses.
    pub poses: usize,
    /// RMS of the rotation angle from the predicted to the measured tool frame \[mrad\].
    pub rms_mrad: f64,
    /// Mean \[mrad\].
    pub mean_mrad: f64,
    /// Largest \[mrad\].
    pub max_mrad: f64,
    /// The RMS the noise alone predicts \[mrad\]: `(s / sqrt 3) sqrt(trace M^-1)`.
    pub predicted_rms_mrad: f64,
    /// The chi-square test, 3 degrees of freedom per pose.
    pub chi_square: Option<ChiSquare>,
}

/// The result of [`validate`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Validation {
    /// The noise the residuals are tested against, 3-D RMS \[mm\].
    pub noise_rms_3d_mm: f64,
    /// `calibration` (the calibration's own) or `given` (`--noise-mm`).
    pub noise_source: String,
    /// Two-sided false-alarm rate of the verdicts.
    pub false_alarm: f64,
    /// Validation poses.
    pub validation: Option<PositionSummary>,
    /// The tool observation.
    pub tool: Option<PositionSummary>,
    /// Axis experiments, pooled.
    pub axis: Option<PositionSummary>,
    /// Tool orientation of the free poses (validation and tool) with three tool targets.
    pub orientation: Option<OrientationSummary>,
    /// One line: how the calibration does on these data.
    pub verdict: String,
    /// Per point (written as `residuals.csv`, not in the JSON).
    #[serde(skip)]
    pub residuals: Vec<ValidationResidual>,
}

/// A pose's measured targets by target id \[m\].
type MeasuredTargets = BTreeMap<usize, Point3<f64>>;

/// The kind of `m`.
fn kind_of(m: &Measurement) -> PointKind {
    if m.moved_joint > 0 {
        PointKind::Axis
    } else if m.experiment == TOOL_EXPERIMENT {
        PointKind::Tool
    } else {
        PointKind::Validation
    }
}

/// Predicts every point of `set` with `cal` (see the module docs) and tests the residuals.
pub fn validate(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    options: &ValidationOptions,
) -> Result<Validation, DiagnosisError> {
    let predicted = clean_positions(set, cal, desc)?;
    let residuals: Vec<ValidationResidual> = set
        .rows()
        .iter()
        .zip(&predicted)
        .map(|(m, p)| {
            let p_mm = (p.coords * 1e3).into();
            ValidationResidual {
                experiment: m.experiment.clone(),
                kind: kind_of(m),
                moved_joint: m.moved_joint,
                step: m.step,
                target: m.target,
                measured_mm: m.position_mm,
                predicted_mm: p_mm,
                error_mm: (Vector3::from(m.position_mm) - Vector3::from(p_mm)).norm(),
            }
        })
        .collect();
    let summary = |kind| position_summary(&residuals, kind, options);
    let (validation, tool, axis) = (
        summary(PointKind::Validation),
        summary(PointKind::Tool),
        summary(PointKind::Axis),
    );
    let orientation = orientation_summary(set, cal, desc, options)?;
    let verdict = verdict(validation.as_ref().or(axis.as_ref()), orientation.as_ref());
    Ok(Validation {
        noise_rms_3d_mm: options.noise_rms_3d_mm,
        noise_source: options.noise_source.clone(),
        false_alarm: options.false_alarm,
        validation,
        tool,
        axis,
        orientation,
        verdict,
        residuals,
    })
}

/// The summary of the residuals of `kind`; `None` without such points.
fn position_summary(
    residuals: &[ValidationResidual],
    kind: PointKind,
    options: &ValidationOptions,
) -> Option<PositionSummary> {
    let of_kind: Vec<&ValidationResidual> = residuals.iter().filter(|r| r.kind == kind).collect();
    if of_kind.is_empty() {
        return None;
    }
    let n = of_kind.len();
    let errors: Vec<f64> = of_kind.iter().map(|r| r.error_mm).collect();
    let sum_squares: f64 = errors.iter().map(|e| e * e).sum();
    let estimated_targets = if kind == PointKind::Axis {
        of_kind
            .iter()
            .map(|r| (r.experiment.as_str(), r.target))
            .collect::<BTreeSet<_>>()
            .len()
    } else {
        0
    };
    let dof = (3 * n).saturating_sub(3 * estimated_targets);
    let s = options.noise_rms_3d_mm;
    let rms_mm = (sum_squares / n as f64).sqrt();
    let predicted_rms_mm = s * (dof as f64 / (3 * n) as f64).sqrt();
    Some(PositionSummary {
        points: n,
        rms_mm,
        mean_mm: errors.iter().sum::<f64>() / n as f64,
        max_mm: errors.iter().copied().fold(0.0, f64::max),
        predicted_rms_mm,
        excess_rms_mm: (rms_mm.powi(2) - predicted_rms_mm.powi(2)).max(0.0).sqrt(),
        estimated_targets,
        chi_square: ChiSquare::new(sum_squares / (s * s / 3.0), dof, options.false_alarm),
    })
}

/// The measured tool frame of a pose from its three (or more) tool targets: the rigid fit of
/// the description's tool targets to the measured points, and the normal matrix `M` of the
/// fit's rotation (module docs).
fn measured_tool_frame(
    tool_targets: &[Point3<f64>],
    measured: &BTreeMap<usize, Point3<f64>>,
) -> Option<(Isometry3<f64>, Matrix3<f64>)> {
    let (src, dst): (Vec<Point3<f64>>, Vec<Point3<f64>>) = measured
        .iter()
        .filter_map(|(t, p)| Some((*tool_targets.get(*t)?, *p)))
        .unzip();
    let (world_from_tool, _) = rigid_fit(&src, &dst)?;
    let centroid = src.iter().map(|p| p.coords).sum::<Vector3<f64>>() / src.len() as f64;
    let normal = src.iter().fold(Matrix3::zeros(), |acc, p| {
        let d = p.coords - centroid;
        acc + Matrix3::identity() * d.norm_squared() - d * d.transpose()
    });
    Some((world_from_tool, normal))
}

/// The orientation errors of the free poses with at least three measured tool targets.
fn orientation_summary(
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
    options: &ValidationOptions,
) -> Result<Option<OrientationSummary>, DiagnosisError> {
    let tool_targets = desc.tool_targets_m();
    let mut poses: BTreeMap<(&str, usize), (&Measurement, MeasuredTargets)> = BTreeMap::new();
    for m in set.rows().iter().filter(|m| m.moved_joint == 0) {
        let e = poses
            .entry((m.experiment.as_str(), m.step))
            .or_insert((m, BTreeMap::new()));
        e.1.insert(m.target, m.position_m());
    }
    let controller = Controller::from_description(desc);
    let model = cal.robot.phi_model();
    let variance_coord_m2 = (options.noise_rms_3d_mm * 1e-3).powi(2) / 3.0;
    let (mut angles_mrad, mut chi2, mut predicted_sq) = (Vec::new(), 0.0, 0.0);
    let approach = crate::physics::actuator_approach_by_pose(set.rows(), desc);
    for (m, measured) in poses.values() {
        let Some((measured_frame, normal)) = measured_tool_frame(&tool_targets, measured) else {
            continue;
        };
        let Some(normal_inv) = normal.try_inverse() else {
            continue;
        };
        let q = calibrated_joint_values(&cal.robot, &controller, &model, desc, m, &approach)?;
        let predicted = model.world_from_tool(&q);
        let w = (predicted.rotation.inverse() * measured_frame.rotation).scaled_axis();
        angles_mrad.push(w.norm() * 1e3);
        chi2 += (w.transpose() * normal * w)[0] / variance_coord_m2;
        predicted_sq += variance_coord_m2 * normal_inv.trace();
    }
    if angles_mrad.is_empty() {
        return Ok(None);
    }
    let n = angles_mrad.len();
    Ok(Some(OrientationSummary {
        poses: n,
        rms_mrad: (angles_mrad.iter().map(|a| a * a).sum::<f64>() / n as f64).sqrt(),
        mean_mrad: angles_mrad.iter().sum::<f64>() / n as f64,
        max_mrad: angles_mrad.iter().copied().fold(0.0, f64::max),
        predicted_rms_mrad: (predicted_sq / n as f64).sqrt() * 1e3,
        chi_square: ChiSquare::new(chi2, 3 * n, options.false_alarm),
    }))
}

/// The one-line verdict from the main position summary and the orientation.
fn verdict(position: Option<&PositionSummary>, orientation: Option<&OrientationSummary>) -> String {
    let Some(p) = position else {
        return "no validation poses and no axis experiments: nothing to validate".into();
    };
    let mut text = match p.chi_square.as_ref().map(|c| c.verdict.as_str()) {
        Some("exceeds_noise") => format!(
            "the calibrated model misses these data: position RMS {:.4} mm against {:.4} mm from the noise alone \
             (model error beyond noise {:.4} mm RMS)",
            p.rms_mm, p.predicted_rms_mm, p.excess_rms_mm
        ),
        Some("below_noise") => format!(
            "residuals below the stated noise: position RMS {:.4} mm against {:.4} mm predicted; the noise is \
             overstated",
            p.rms_mm, p.predicted_rms_mm
        ),
        Some(_) => format!(
            "consistent with the measurement noise: position RMS {:.4} mm against {:.4} mm predicted",
            p.rms_mm, p.predicted_rms_mm
        ),
        None => format!("position RMS {:.4} mm (no degrees of freedom for a test)", p.rms_mm),
    };
    if let Some(o) = orientation {
        text.push_str(&format!(
            "; orientation RMS {:.4} mrad against {:.4} mrad predicted ({})",
            o.rms_mrad,
            o.predicted_rms_mrad,
            o.chi_square.as_ref().map_or("no test", |c| c.verdict.as_str())
        ));
    }
    text
}

/// `residuals.csv` of `axiscal validate` (`docs/formats.md#validation-residuals-csv`).
pub fn validation_residuals_csv(v: &Validation) -> String {
    let mut out = String::from(
        "experiment,kind,moved_joint,step,target,x_mm,y_mm,z_mm,predicted_x_mm,predicted_y_mm,predicted_z_mm,dx_mm,dy_mm,dz_mm,error_mm\n",
    );
    for r in &v.residuals {
        let kind = match r.kind {
            PointKind::Validation => "validation",
            PointKind::Tool => "tool",
            PointKind::Axis => "axis",
        };
        let [x, y, z] = r.measured_mm;
        let [px, py, pz] = r.predicted_mm;
        out.push_str(&format!(
            "{},{kind},{},{},{},{x:.4},{y:.4},{z:.4},{px:.4},{py:.4},{pz:.4},{:.4},{:.4},{:.4},{:.4}\n",
            r.experiment,
            r.moved_joint,
            r.step,
            r.target,
            x - px,
            y - py,
            z - pz,
            r.error_mm
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::ChiSquare;

    /// The verdicts at their edges: a statistic at its expectation is consistent, far above it
    /// exceeds, far below it is below the noise, and an overflowed one (infinite, or NaN from
    /// `inf - inf`) exceeds: never "consistent".
    #[test]
    fn verdicts_and_an_overflowed_statistic() {
        let verdict = |v: f64| ChiSquare::new(v, 100, 0.01).unwrap().verdict;
        assert_eq!(verdict(100.0), "consistent");
        assert_eq!(verdict(300.0), "exceeds_noise");
        assert_eq!(verdict(30.0), "below_noise");
        assert_eq!(verdict(f64::INFINITY), "exceeds_noise");
        assert_eq!(verdict(f64::NAN), "exceeds_noise");
        assert!(ChiSquare::new(1.0, 0, 0.01).is_none());
    }
}
