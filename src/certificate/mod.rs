//! The calibration certificate (`axiscal report`): what a calibration engineer hands to a
//! customer, as one self-contained HTML page and its JSON. Pure: the caller reads the files;
//! [`certificate`] assembles the numbers, [`html::render`] writes the page.
//!
//! Uncertainties follow the GUM (JCGM 100:2008): every standard uncertainty `u` is a Type A
//! evaluation (4.2) of the fits' residuals, propagated to the model's parameters to first order
//! with their correlations (5.2, the law of propagation of uncertainty; the propagation is
//! [`crate::calibration::tool_accuracy`]'s `model_covariance`); the expanded uncertainty is
//! `U = k u` with coverage factor `k = 2` (6.2, about 95 % for a normal distribution).

pub mod data;
pub mod held_out;
pub mod html;
mod svg;

pub use data::{DataSection, ExperimentLine, data_mismatches};
pub use held_out::{HELD_OUT_FALSE_ALARM, HeldOut, HeldOutError, held_out};

use crate::calibration::model_parameters::{model_parameter_names, model_parameter_values};
use crate::calibration::procedure::{Calibration, FrameSigma, InvalidCalibration, PointResidual};
use crate::calibration::record::CalibrationRecord;
use crate::iso9283::IsoFigures;
use crate::kinematics::JointKind;
use crate::measurement::MeasurementSet;
use crate::robot::{Placement, RobotDescription, RobotModel};
use serde::Serialize;

/// The coverage factor of the expanded uncertainties.
pub const COVERAGE_FACTOR: f64 = 2.0;

/// Correlations at or beyond this size are listed as pairs the data barely separate.
pub const STRONG_CORRELATION: f64 = 0.95;

/// What a certificate cannot be made from.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CertificateError {
    /// The calibration has no covariance of its parameters.
    #[error(
        "the calibration has no `model_covariance` (a file written before it was recorded): its parameters' uncertainties are not known; recalibrate with `axiscal calibrate`"
    )]
    NoCovariance,
    /// The calibration was made by the paper's estimator, which gives its axes no covariance.
    #[error(
        "the calibration was made by the paper's estimator (`--estimator paper`), which gives its parameters no uncertainty, and a certificate states one: calibrate with `--estimator ml` for a certificate"
    )]
    PaperEstimator,
    /// The covariance is not one of the model's parameters ([`crate::calibration::model_parameters::ModelCovariance::validate`]).
    #[error("the calibration's {0}")]
    Covariance(InvalidCalibration),
}

/// Everything the certificate is made from.
#[derive(Clone, Debug)]
pub struct CertificateInputs<'a> {
    /// The calibration, with the reports written beside it.
    pub calibration: &'a CalibrationRecord,
    /// Its file, as the user named it.
    pub calibration_file: String,
    /// The nominal description.
    pub desc: &'a RobotDescription,
    /// The instrument, in the user's words (make, model, serial number), if given.
    pub instrument: Option<String>,
    /// The data the calibration was made from, with its file name, if given.
    pub data: Option<(String, &'a MeasurementSet)>,
    /// The axis fits' residuals (`residuals.csv` beside the calibration).
    pub residuals: &'a [PointResidual],
    /// The nominal and calibrated models on held-out poses, if measured.
    pub held_out: Option<HeldOut>,
    /// Measured ISO 9283 figures (`iso9283 evaluate`), if any.
    pub iso9283: Option<IsoFigures>,
    /// What reading the inputs warned of (a calibration edited after `axiscal calibrate`
    /// wrote it, another robot's calibration allowed): the certificate says it too.
    pub read_warnings: Vec<String>,
}

/// The certificate's content (`certificate.json`, `docs/formats.md#certificate`).
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Certificate {
    /// The robot.
    pub robot: RobotSection,
    /// The calibration file and method.
    pub calibration: CalibrationSection,
    /// The instrument and the noise.
    pub instrument: InstrumentSection,
    /// The data the calibration was made from; absent when not given.
    pub data: Option<DataSection>,
    /// How the uncertainties were obtained (GUM wording).
    pub uncertainty_statement: String,
    /// `k` of `U = k u`.
    pub coverage_factor: f64,
    /// Every scalar parameter of the model with its uncertainty.
    pub parameters: Vec<ParameterLine>,
    /// The base and tool frames.
    pub frames: Vec<FrameLine>,
    /// The correlations of the parameters with an uncertainty.
    pub correlation: Correlation,
    /// Per axis fit: points, span, residual, condition number, what the data cannot pin down.
    pub axes: Vec<AxisLine>,
    /// The axis fits' residuals, per joint.
    pub residuals: Vec<JointResiduals>,
    /// Before and after calibration on held-out poses; absent when not measured.
    pub held_out: Option<HeldOut>,
    /// Measured ISO 9283 figures; absent when not measured.
    pub iso9283: Option<IsoFigures>,
    /// What was not calibrated, in words.
    pub not_calibrated: Vec<String>,
    /// What a reader must know before trusting the uncertainties, in words (e.g. a given noise
    /// the residuals contradict); empty when nothing.
    pub warnings: Vec<String>,
}

/// The robot.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct RobotSection {
    /// The description's name.
    pub name: String,
    /// The description's geometry hash recorded in the calibration, if any.
    pub geometry_hash: Option<String>,
    /// Joints.
    pub joints: usize,
}

/// The calibration file and method.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct CalibrationSection {
    /// The file.
    pub file: String,
    /// The axiscal version that wrote the certificate.
    pub axiscal_version: String,
    /// The method in words.
    pub method: String,
    /// The base frame's rule in words.
    pub base_rule: Option<String>,
}

/// The instrument and the noise its data show.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct InstrumentSection {
    /// The instrument in the user's words; absent when not given.
    pub description: Option<String>,
    /// The 3-D RMS noise the fits were weighted with \[mm\].
    pub noise_used_rms_3d_mm: Option<f64>,
    /// `estimated` or `given`.
    pub noise_source: Option<String>,
    /// The estimate from the residuals \[mm\] with its interval; absent without one.
    pub noise_estimate: Option<NoiseLine>,
    /// A given noise: the chi-square test of it against the residuals (two-sided p-value).
    pub given_p_value: Option<f64>,
    /// A given noise: whether the residuals contradict it (p < 0.01).
    pub given_contradicted: bool,
}

/// The noise estimate.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct NoiseLine {
    /// 3-D RMS \[mm\].
    pub rms_3d_mm: f64,
    /// Interval low end \[mm\].
    pub low_mm: f64,
    /// Interval high end \[mm\].
    pub high_mm: f64,
    /// Its confidence.
    pub confidence: f64,
    /// Degrees of freedom of the residuals.
    pub dof: usize,
}

/// One scalar parameter.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ParameterLine {
    /// Its name (`row 2 a`, `joint 3 zero offset`, ...).
    pub name: String,
    /// The unit of the values below (`mm`, `mrad`, or `1`).
    pub unit: String,
    /// Its nominal value; absent when the nominal model has no such parameter.
    pub nominal: Option<f64>,
    /// Its identified value.
    pub identified: f64,
    /// Standard uncertainty `u`: the square root of its variance in `model_covariance`.
    pub standard_uncertainty: f64,
    /// Expanded uncertainty `U = k u`.
    pub expanded_uncertainty: f64,
    /// How `u` was obtained: `Type A` (from the fits) or `fixed by the method` (u = 0: the
    /// parameter is set by the model's convention, not measured).
    pub evaluation: String,
}

/// A frame (base or tool).
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct FrameLine {
    /// `base` (the robot in the instrument frame) or `tool` (the tool in the last link).
    pub frame: String,
    /// Nominal.
    pub nominal: Placement,
    /// Identified.
    pub identified: Placement,
    /// Standard uncertainties along and about the frame's own axes.
    pub standard_uncertainty: FrameUncertainty,
    /// Expanded uncertainties `U = k u`.
    pub expanded_uncertainty: FrameUncertainty,
}

/// The uncertainty of a frame along and about its own axes (mm, mrad): the calibration's
/// [`FrameSigma`].
pub type FrameUncertainty = FrameSigma;

/// Correlations of the parameters with an uncertainty.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct Correlation {
    /// The parameters, in order.
    pub names: Vec<String>,
    /// `rho_ij = C_ij / (u_i u_j)`, row by row.
    pub correlation: Vec<Vec<f64>>,
    /// Pairs with `|rho| >=` [`STRONG_CORRELATION`]: what the data barely separate.
    pub strong_pairs: Vec<StrongPair>,
}

/// Two strongly correlated parameters.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct StrongPair {
    /// One.
    pub a: String,
    /// The other.
    pub b: String,
    /// Their correlation.
    pub rho: f64,
}

/// One axis fit.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct AxisLine {
    /// Joint.
    pub joint: usize,
    /// Experiment.
    pub experiment: String,
    /// Points fitted.
    pub points: usize,
    /// Commanded span \[deg or mm\].
    pub span_deg_or_mm: f64,
    /// RMS residual \[mm\].
    pub residual_rms_mm: f64,
    /// Scaled condition number of the fit.
    pub condition_number: f64,
    /// What the data cannot pin down.
    pub identifiability: Vec<String>,
}

/// The residuals of one joint's axis fit.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct JointResiduals {
    /// Joint.
    pub joint: usize,
    /// Whether the axis slides (components across u, across v, along) or turns (radial,
    /// tangential, axial).
    pub sliding: bool,
    /// Per point.
    pub points: Vec<ResidualPoint>,
}

/// One point's residual \[mm\].
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct ResidualPoint {
    /// Experiment.
    pub experiment: String,
    /// Step.
    pub step: usize,
    /// Target.
    pub target: usize,
    /// Radial, or across u \[mm\].
    pub first_mm: f64,
    /// Tangential, or across v \[mm\].
    pub second_mm: f64,
    /// Axial, or along \[mm\].
    pub third_mm: f64,
}

/// The certificate of `inputs` (module docs).
pub fn certificate(inputs: &CertificateInputs<'_>) -> Result<Certificate, CertificateError> {
    let cal = &inputs.calibration.calibration;
    if cal.model_covariance.is_none() && cal.options.estimator == crate::calibration::procedure::AxisEstimator::Paper {
        return Err(CertificateError::PaperEstimator);
    }
    let covariance = cal.model_covariance.as_ref().ok_or(CertificateError::NoCovariance)?;
    covariance.validate(&cal.robot)?;
    let names = model_parameter_names(&cal.robot);
    let c = covariance.matrix();
    let nominal = RobotModel::ideal(inputs.desc);
    let u: Vec<f64> = (0..names.len()).map(|i| c[(i, i)].max(0.0).sqrt()).collect();
    Ok(Certificate {
        robot: RobotSection {
            name: inputs.desc.name.clone(),
            geometry_hash: cal.description.as_ref().map(|d| d.geometry_hash.clone()),
            joints: inputs.desc.dof(),
        },
        calibration: calibration_section(inputs),
        instrument: instrument_section(inputs),
        data: inputs.data.as_ref().map(|(file, set)| data::data_section(file, set)),
        uncertainty_statement: UNCERTAINTY_STATEMENT.into(),
        coverage_factor: COVERAGE_FACTOR,
        parameters: parameter_lines(&cal.robot, &nominal, &names, &u),
        frames: frame_lines(&cal.robot, &nominal, &u),
        correlation: correlation(&names, &c, &u),
        axes: axis_lines(cal),
        residuals: joint_residuals(inputs.residuals),
        held_out: inputs.held_out.clone(),
        iso9283: inputs.iso9283.clone(),
        not_calibrated: not_calibrated(cal, &u, &names),
        warnings: warnings(inputs),
    })
}

/// The uncertainty statement of every certificate.
pub const UNCERTAINTY_STATEMENT: &str = "Standard uncertainties u are Type A evaluations (GUM 4.2) from the residuals of the axis fits, with the measurement noise estimated from those residuals (or the noise given, tested against them), propagated to the model's parameters to first order with their correlations (GUM 5.2, law of propagation of uncertainty). Expanded uncertainties U = k u with coverage factor k = 2 (GUM 6.2), which for a normal distribution gives a coverage probability of about 95 %. Effects the model does not contain (compliance, backlash, thermal expansion, the instrument's own systematic errors) are not included.";

fn calibration_section(inputs: &CertificateInputs<'_>) -> CalibrationSection {
    let (cal, reports) = (&inputs.calibration.calibration, &inputs.calibration.reports);
    let method = if reports.free_poses.is_some() {
        "free poses: every parameter fitted jointly to the measured tool targets".to_string()
    } else {
        format!(
            "independent-axis method (Sultan & Wager): each axis fitted from its own experiment (estimator `{}`), transmissions and couplings fitted on the axes, the phi-model built from them{}",
            cal.options.estimator.name(),
            if reports.refinement.is_some() {
                ", then refined on the free poses"
            } else {
                ""
            }
        )
    };
    CalibrationSection {
        file: inputs.calibration_file.clone(),
        axiscal_version: env!("CARGO_PKG_VERSION").to_string(),
        method,
        base_rule: cal.base_rule.as_ref().map(|b| b.text.clone()),
    }
}

fn instrument_section(inputs: &CertificateInputs<'_>) -> InstrumentSection {
    let noise = inputs.calibration.calibration.noise.as_ref();
    InstrumentSection {
        description: inputs.instrument.clone(),
        noise_used_rms_3d_mm: noise.map(|n| n.used_rms_3d_mm),
        noise_source: noise.map(|n| n.source.clone()),
        noise_estimate: noise.and_then(|n| n.estimate.as_ref()).map(|e| NoiseLine {
            rms_3d_mm: e.rms_3d_mm,
            low_mm: e.interval.low_mm,
            high_mm: e.interval.high_mm,
            confidence: e.confidence,
            dof: e.dof,
        }),
        given_p_value: noise.and_then(|n| n.given_p_value),
        given_contradicted: noise.is_some_and(|n| n.given_contradicted),
    }
}

/// A parameter's display: its name without the unit, the unit, and the factor from the
/// vector's unit.
fn display(name: &str, robot: &RobotModel) -> (String, String, f64) {
    let (bare, unit) = match name.rsplit_once(" [") {
        Some((b, u)) => (b.to_string(), u.trim_end_matches(']')),
        None => (name.to_string(), ""),
    };
    // The geometry's angles (Table 2's alpha, beta, gamma and the joints' phi) in degrees, as
    // robot descriptions give them; the small angles (offsets, harmonics) in mrad.
    let geometry_angle = ["alpha", "beta", "gamma", "phi"].iter().any(|a| bare.ends_with(a));
    let (unit, factor) = match unit {
        "m" => ("mm", 1e3),
        "rad" if geometry_angle => ("deg", 180.0 / std::f64::consts::PI),
        "rad" => ("mrad", 1e3),
        "rad or m" => {
            let joint: Option<usize> = bare
                .strip_prefix("joint ")
                .and_then(|r| r.split(' ').next())
                .and_then(|k| k.parse().ok());
            let sliding = joint
                .and_then(|k| robot.joints.get(k - 1))
                .is_some_and(|j| j.kind == JointKind::Prismatic);
            (if sliding { "mm" } else { "mrad" }, 1e3)
        }
        _ => ("1", 1.0),
    };
    (bare, unit.to_string(), factor)
}

/// Whether parameter `name` is one of the base or tool placement's relative coordinates.
fn is_frame(name: &str) -> bool {
    name.starts_with("base ") || name.starts_with("tool ")
}

fn parameter_lines(robot: &RobotModel, nominal: &RobotModel, names: &[String], u: &[f64]) -> Vec<ParameterLine> {
    let values = model_parameter_values(robot);
    let nominal_names = model_parameter_names(nominal);
    let nominal_values = model_parameter_values(nominal);
    names
        .iter()
        .enumerate()
        .filter(|(_, n)| !is_frame(n))
        .map(|(i, n)| {
            let (name, unit, factor) = display(n, robot);
            let nominal = nominal_names
                .iter()
                .position(|m| m == n)
                .map(|j| nominal_values[j] * factor);
            ParameterLine {
                name,
                unit,
                nominal,
                identified: values[i] * factor,
                standard_uncertainty: u[i] * factor,
                expanded_uncertainty: COVERAGE_FACTOR * u[i] * factor,
                evaluation: if u[i] > 0.0 {
                    "Type A".into()
                } else {
                    "fixed by the method".into()
                },
            }
        })
        .collect()
}

fn frame_uncertainty(u: &[f64], scale: f64) -> FrameUncertainty {
    let s = |i: usize| u[i] * 1e3 * scale;
    FrameUncertainty {
        x_mm: s(0),
        y_mm: s(1),
        z_mm: s(2),
        rx_mrad: s(3),
        ry_mrad: s(4),
        rz_mrad: s(5),
    }
}

fn frame_lines(robot: &RobotModel, nominal: &RobotModel, u: &[f64]) -> Vec<FrameLine> {
    let tool = u.len() - 6;
    [
        ("base", &robot.placement, &nominal.placement, &u[..6]),
        ("tool", &robot.tool_frame, &nominal.tool_frame, &u[tool..]),
    ]
    .into_iter()
    .map(|(frame, identified, nominal, u)| FrameLine {
        frame: frame.into(),
        nominal: *nominal,
        identified: *identified,
        standard_uncertainty: frame_uncertainty(u, 1.0),
        expanded_uncertainty: frame_uncertainty(u, COVERAGE_FACTOR),
    })
    .collect()
}

fn correlation(names: &[String], c: &nalgebra::DMatrix<f64>, u: &[f64]) -> Correlation {
    let kept: Vec<usize> = (0..names.len()).filter(|&i| u[i] > 0.0).collect();
    let rho = |i: usize, j: usize| (c[(i, j)] / (u[i] * u[j])).clamp(-1.0, 1.0);
    let mut strong_pairs = Vec::new();
    for (a, &i) in kept.iter().enumerate() {
        for &j in &kept[a + 1..] {
            if rho(i, j).abs() >= STRONG_CORRELATION {
                strong_pairs.push(StrongPair {
                    a: names[i].clone(),
                    b: names[j].clone(),
                    rho: rho(i, j),
                });
            }
        }
    }
    Correlation {
        names: kept.iter().map(|&i| names[i].clone()).collect(),
        correlation: kept
            .iter()
            .map(|&i| kept.iter().map(|&j| rho(i, j)).collect())
            .collect(),
        strong_pairs,
    }
}

fn axis_lines(cal: &Calibration) -> Vec<AxisLine> {
    cal.axes
        .iter()
        .map(|a| AxisLine {
            joint: a.joint,
            experiment: a.experiment.clone(),
            points: a.points,
            span_deg_or_mm: a.span.value(),
            residual_rms_mm: a.residual_rms_mm,
            condition_number: a.condition_number,
            identifiability: a.identifiability.clone(),
        })
        .collect()
}

fn joint_residuals(residuals: &[PointResidual]) -> Vec<JointResiduals> {
    let mut out: Vec<JointResiduals> = Vec::new();
    for r in residuals {
        let point = ResidualPoint {
            experiment: r.experiment.clone(),
            step: r.step,
            target: r.target,
            first_mm: r.components_mm[0],
            second_mm: r.components_mm[1],
            third_mm: r.components_mm[2],
        };
        match out.iter_mut().find(|j| j.joint == r.joint) {
            Some(j) => j.points.push(point),
            None => out.push(JointResiduals {
                joint: r.joint,
                sliding: r.sliding,
                points: vec![point],
            }),
        }
    }
    out.sort_by_key(|j| j.joint);
    out
}

fn not_calibrated(cal: &Calibration, u: &[f64], names: &[String]) -> Vec<String> {
    let mut out: Vec<String> = cal
        .not_calibrated
        .iter()
        .map(|k| format!("joint {k}: not swept by any experiment, kept nominal"))
        .collect();
    let fixed: Vec<&str> = names
        .iter()
        .zip(u)
        .filter(|(n, s)| **s == 0.0 && !is_frame(n))
        .map(|(n, _)| n.as_str())
        .collect();
    if !fixed.is_empty() {
        out.push(format!(
            "{} parameters fixed by the model's conventions (u = 0): {}",
            fixed.len(),
            fixed.join(", ")
        ));
    }
    out.push(
        "effects the model does not contain: compliance, backlash, thermal expansion (see `axiscal diagnose` for whether the data show any)"
            .into(),
    );
    out
}

/// What a reader must know before trusting the uncertainties and the held-out comparison.
fn warnings(inputs: &CertificateInputs<'_>) -> Vec<String> {
    let (record, held_out) = (inputs.calibration, inputs.held_out.as_ref());
    let cal = &record.calibration;
    let mut out: Vec<String> = inputs.read_warnings.clone();
    out.extend(held_out.and_then(HeldOut::warning));
    if let Some((file, set)) = &inputs.data {
        let mismatches = data_mismatches(record, set);
        if !mismatches.is_empty() {
            out.push(format!(
                "the data summarised ({file}) are not the ones the calibration records: {}",
                mismatches.join("; ")
            ));
        }
    }
    if held_out.is_some() && record.reports.free_poses.is_some() {
        out.push(
            "the calibration was fitted to free poses: the held-out poses are held out only if their file is not the one the calibration was made from"
                .into(),
        );
    }
    if let Some(n) = &cal.noise
        && n.given_contradicted
    {
        let estimate = n.estimate.as_ref().map(|e| e.rms_3d_mm);
        out.push(match estimate {
            Some(e) => format!(
                "the uncertainties are computed with the given noise {:.4} mm, which the residuals contradict (they estimate {e:.4} mm): they are understated about {:.1} times; recalibrate without --noise-mm to state them from the residuals",
                n.used_rms_3d_mm,
                e / n.used_rms_3d_mm
            ),
            None => format!(
                "the uncertainties are computed with the given noise {:.4} mm, which the residuals contradict",
                n.used_rms_3d_mm
            ),
        });
    }
    if cal.noise.is_none() {
        out.push("the calibration records no noise report: the uncertainties rest on the noise it was given".into());
    }
    out
}

impl From<InvalidCalibration> for CertificateError {
    fn from(e: InvalidCalibration) -> Self {
        Self::Covariance(e)
    }
}
