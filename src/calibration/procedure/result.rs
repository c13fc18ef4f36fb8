//! What the procedure returns: the calibrated robot plus, per axis and coupling, the fit and
//! its uncertainty. Serialisable: `calibration.json` is loaded again by axiscal.

use super::experiments::AxisExperiment;
use super::frames::BaseRule;
use super::propagation::{FrameSigma, ZeroOffsetSigma};
use super::second_targets::SecondTargetData;
use super::uncertainty::AxisCovariance;
use super::{AxisEstimator, CalibrationOptions};
use crate::calibration::arc_model::N_GEOMETRY;
use crate::calibration::coupling_fit::{CouplingFit, CouplingForm};
use crate::calibration::crb::held_joint_axis_covariance;
use crate::calibration::line_ml::LineFit;
use crate::calibration::model_parameters::ModelCovariance;
use crate::calibration::noise::{NoiseEstimate, ResidualMoments};
use crate::calibration::transmission_fit::TransmissionFit;
use crate::calibration::{ArcFit, PaperAxisFit};
use crate::json_file;
use crate::kinematics::{AxisLine, JointKind};
use crate::robot::TransmissionFitForm;
use crate::robot::{CouplingFunction, DescriptionIdentity, RobotModel, Transmission};
use nalgebra::{Isometry3, Matrix2, Matrix4, Vector3};
use serde::{Deserialize, Serialize};

/// One calibrated axis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct AxisReport {
    /// The joint (1-based).
    pub joint: usize,
    /// The experiment it comes from.
    pub experiment: String,
    /// The estimator that fitted it (`ml` or `paper`).
    pub estimator: AxisEstimator,
    /// Poses used.
    pub points: usize,
    /// Commanded span of the actuator: `span_deg` of a rotary joint, `span_mm` of a sliding one.
    #[serde(flatten)]
    pub span: AxisSpan,
    /// A point on the axis, instrument frame \[mm\].
    pub point_mm: [f64; 3],
    /// Unit direction, instrument frame.
    pub direction: [f64; 3],
    /// 1-sigma of the axis direction in two perpendicular directions (principal values).
    #[serde(
        rename = "direction_sigma",
        alias = "direction_sigma_rad",
        deserialize_with = "json_file::named_or_old::<_, DirectionSigma, [f64; 2]>"
    )]
    pub direction_sigma: DirectionSigma,
    /// 1-sigma of the axis position across the axis (principal values); NaN (null in JSON) for
    /// a sliding axis, which has a direction only (eq. 9).
    #[serde(
        rename = "position_sigma",
        alias = "position_sigma_mm",
        deserialize_with = "json_file::named_or_old::<_, PositionSigma, [Option<f64>; 2]>"
    )]
    pub position_sigma: PositionSigma,
    /// The fitted transmission `theta_c = f(theta_a)` in the fit's own zero.
    pub transmission: Transmission,
    /// Names of its coefficients (`sin1`, `cos1`, ...).
    pub coefficient_names: Vec<String>,
    /// 1-sigma of each coefficient \[rad\].
    pub coefficient_sigma: Vec<f64>,
    /// RMS of the point residuals \[mm\].
    pub residual_rms_mm: f64,
    /// Scaled condition number of the fit; NaN (null in JSON) for a sliding axis fitted by the
    /// paper's estimator, which computes none.
    #[serde(deserialize_with = "nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub condition_number: f64,
    /// What the data cannot pin down, in words.
    pub identifiability: Vec<String>,
    /// Covariance of the line (ML estimator only; the paper's estimator reports none).
    pub covariance: Option<AxisCovariance>,
    /// `revolute` or `prismatic` (a sliding axis has a direction only: its `point_mm` is the
    /// target's line at the first step and its position sigma is null).
    #[serde(default = "revolute")]
    pub kind: JointKind,
    /// Each harmonic of a rotary joint's transmission as amplitude and phase, with their
    /// 1-sigma from the coefficients' covariance (empty for a sliding joint and in older
    /// files).
    #[serde(default)]
    pub harmonics: Vec<HarmonicReport>,
    /// The sweeps fitted jointly as this axis, and what differs between them.
    #[serde(default)]
    pub sweeps: Vec<SweepReport>,
    /// The joint fit's residual moments (a calibration's report only): what its sweeps'
    /// agreement is tested with (`sweeps_agree.rs`). Not written to `calibration.json`.
    #[serde(skip)]
    #[schemars(skip)]
    pub moments: Option<ResidualMoments>,
}

/// The principal 1-sigmas of an axis direction, largest first; NaN (null in JSON) for an axis
/// fitted by the paper's estimator, which gives its line no covariance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct DirectionSigma {
    /// The largest \[rad\].
    #[serde(deserialize_with = "nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub major_rad: f64,
    /// The smallest \[rad\].
    #[serde(deserialize_with = "nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub minor_rad: f64,
}

impl From<[f64; 2]> for DirectionSigma {
    fn from([major_rad, minor_rad]: [f64; 2]) -> Self {
        DirectionSigma { major_rad, minor_rad }
    }
}

/// The principal 1-sigmas of an axis position across the axis, largest first; NaN (null in
/// JSON) for a sliding axis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PositionSigma {
    /// The largest \[mm\].
    #[serde(deserialize_with = "nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub major_mm: f64,
    /// The smallest \[mm\].
    #[serde(deserialize_with = "nan_from_null")]
    #[schemars(with = "Option<f64>")]
    pub minor_mm: f64,
}

impl PositionSigma {
    /// A sliding axis's: none.
    pub const NONE: PositionSigma = PositionSigma {
        major_mm: f64::NAN,
        minor_mm: f64::NAN,
    };
}

impl From<[f64; 2]> for PositionSigma {
    fn from([major_mm, minor_mm]: [f64; 2]) -> Self {
        PositionSigma { major_mm, minor_mm }
    }
}

/// Before schema 2 (`[major, minor]`, null for a sliding axis).
impl From<[Option<f64>; 2]> for PositionSigma {
    fn from(v: [Option<f64>; 2]) -> Self {
        v.map(|x| x.unwrap_or(f64::NAN)).into()
    }
}

fn revolute() -> JointKind {
    JointKind::Revolute
}

/// A sweep's commanded span, in its joint's file unit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub enum AxisSpan {
    /// A rotary joint's span \[deg\].
    #[serde(rename = "span_deg")]
    Deg(f64),
    /// A sliding joint's span \[mm\].
    #[serde(rename = "span_mm")]
    Mm(f64),
}

impl AxisSpan {
    /// The span in its unit.
    pub fn value(self) -> f64 {
        match self {
            AxisSpan::Deg(v) | AxisSpan::Mm(v) => v,
        }
    }

    /// Its unit, `deg` or `mm`.
    pub fn unit(self) -> &'static str {
        match self {
            AxisSpan::Deg(_) => "deg",
            AxisSpan::Mm(_) => "mm",
        }
    }
}

/// One sweep of a jointly fitted axis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SweepReport {
    /// The experiment.
    pub experiment: String,
    /// Points of target 0 used.
    pub points: usize,
    /// RMS of its points' residuals in the joint fit \[mm\].
    pub residual_rms_mm: f64,
    /// The held joints whose value in this sweep differs from the reference pose.
    #[serde(deserialize_with = "json_file::each_named_or_old::<_, HeldOffset, (usize, f64)>")]
    pub held_offsets: Vec<HeldOffset>,
    /// Largest deviation of a held joint from its median within the sweep \[deg or mm\]: the
    /// recorded wander the procedure modelled.
    #[serde(rename = "held_wander_deg_or_mm", alias = "held_wander")]
    pub held_wander: f64,
    /// With several sweeps: the angle between this sweep's own axis and the joint fit's
    /// \[mrad\] (null when fitted alone or not fittable alone).
    pub own_axis_angle_mrad: Option<f64>,
    /// With several sweeps (rotary): the distance of this sweep's own axis from the joint
    /// fit's at the axis point \[mm\].
    pub own_axis_offset_mm: Option<f64>,
    /// With several sweeps: the residual RMS of the joint's fit from its other sweeps
    /// \[mm\] (null when that fit fails): the leave-one-out the misfit check names a sweep by
    /// (`sanity/`). Not written to `calibration.json`.
    #[serde(skip)]
    #[schemars(skip)]
    pub without_rms_mm: Option<f64>,
    /// With several sweeps: the residual moments of this sweep's own axis fit, the noise of
    /// its points whatever the held joints' correction did (`sweeps_agree.rs`). Not written to
    /// `calibration.json`.
    #[serde(skip)]
    #[schemars(skip)]
    pub own_moments: Option<ResidualMoments>,
}

/// A held joint whose value in a sweep differs from the reference pose.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct HeldOffset {
    /// The joint (1-based).
    pub joint: usize,
    /// Its median offset from the reference pose \[deg or mm\] (file units of the joint).
    pub offset_deg_or_mm: f64,
}

/// Before schema 2: `[joint, offset]`.
impl From<(usize, f64)> for HeldOffset {
    fn from((joint, offset_deg_or_mm): (usize, f64)) -> Self {
        HeldOffset {
            joint,
            offset_deg_or_mm,
        }
    }
}

/// The residual of one observed point in its axis fit (`residuals.csv`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PointResidual {
    /// Experiment.
    pub experiment: String,
    /// Swept joint.
    pub joint: usize,
    /// Step.
    pub step: usize,
    /// Target.
    pub target: usize,
    /// Rotary axes: `[radial, tangential, axial]`; sliding axes: `[across u, across v, along]`
    /// \[mm\] (observed minus fitted).
    pub components_mm: [f64; 3],
    /// Whether the axis slides.
    pub sliding: bool,
}

fn principal_sigmas(c: &Matrix2<f64>) -> [f64; 2] {
    let e = c.symmetric_eigen().eigenvalues;
    let (a, b) = (e[0].max(0.0).sqrt(), e[1].max(0.0).sqrt());
    [a.max(b), a.min(b)]
}

impl AxisReport {
    pub(super) fn from_arc(
        joint: usize,
        experiment: &str,
        points: usize,
        fit: &ArcFit,
        form: &TransmissionFitForm,
        span_rad: f64,
    ) -> Self {
        let mut notes = fit.identifiability.notes.clone();
        for (span, sigma) in &fit.identifiability.tilt_sigma_by_span {
            notes.push(format!(
                "axis tilt 1-sigma with a {:.0} deg span: {:.2e} rad",
                span.to_degrees(),
                sigma
            ));
        }
        AxisReport {
            joint,
            experiment: experiment.to_string(),
            estimator: AxisEstimator::Ml,
            points,
            span: AxisSpan::Deg(span_rad.to_degrees()),
            point_mm: (fit.axis.origin_m.coords * 1e3).into(),
            direction: fit.axis.direction.into_inner().into(),
            direction_sigma: principal_sigmas(&fit.axis_direction_covariance).into(),
            position_sigma: principal_sigmas(&fit.axis_position_covariance).map(|s| s * 1e3).into(),
            transmission: fit.transmission.clone(),
            coefficient_names: form.coefficient_names(),
            coefficient_sigma: fit.coefficient_sigma.clone(),
            residual_rms_mm: fit.residual_rms * 1e3,
            condition_number: fit.identifiability.condition_number,
            identifiability: notes,
            covariance: None,
            kind: revolute(),
            sweeps: vec![],
            moments: None,
            harmonics: harmonics(&fit.transmission, &|a, b| {
                fit.covariance[(N_GEOMETRY + a, N_GEOMETRY + b)]
            }),
        }
    }

    pub(super) fn from_line(
        joint: usize,
        experiment: &str,
        fit: &LineFit,
        form: &TransmissionFitForm,
        span_m: f64,
    ) -> Self {
        let mut c = Matrix4::zeros();
        c.fixed_view_mut::<2, 2>(0, 0).copy_from(&fit.direction_covariance);
        let (u, v) = (
            fit.params.frame.matrix().column(0).into(),
            fit.params.frame.matrix().column(1).into(),
        );
        AxisReport {
            joint,
            experiment: experiment.to_string(),
            estimator: AxisEstimator::Ml,
            points: fit.residuals.len(),
            span: AxisSpan::Mm(span_m * 1e3),
            point_mm: (fit.params.start.coords * 1e3).into(),
            direction: fit.direction.into_inner().into(),
            direction_sigma: principal_sigmas(&fit.direction_covariance).into(),
            position_sigma: PositionSigma::NONE,
            transmission: fit.transmission.clone(),
            coefficient_names: form.coefficient_names(),
            coefficient_sigma: fit.coefficient_sigma.clone(),
            residual_rms_mm: fit.residual_rms * 1e3,
            condition_number: fit.condition_number,
            identifiability: vec!["a sliding axis has a direction only (eq. 9): its position is a convention".into()],
            covariance: Some(AxisCovariance::new(u, v, &c)),
            kind: JointKind::Prismatic,
            harmonics: vec![],
            sweeps: vec![],
            moments: None,
        }
    }

    /// Adds the bias of the joints held still below this axis during its sweep
    /// ([`crate::calibration::crb::held_joint_axis_covariance`]) to the line's covariance and
    /// its principal sigmas. No-op without a covariance (the paper's estimator).
    pub(super) fn add_held_joint_covariance(&mut self, axis: &AxisLine, held: &[(AxisLine, f64)]) {
        let Some(c) = &self.covariance else { return };
        let (u, v) = (Vector3::from(c.u), Vector3::from(c.v));
        let mut total = Matrix4::from_fn(|a, b| c.covariance[a][b]) + held_joint_axis_covariance(axis, &u, &v, held);
        if self.kind == JointKind::Prismatic {
            // Only the direction of a sliding axis is used.
            total.fixed_view_mut::<2, 2>(2, 2).fill(0.0);
            total.fixed_view_mut::<2, 2>(0, 2).fill(0.0);
            total.fixed_view_mut::<2, 2>(2, 0).fill(0.0);
        } else {
            self.position_sigma = principal_sigmas(&total.fixed_view::<2, 2>(2, 2).into())
                .map(|s| s * 1e3)
                .into();
        }
        self.direction_sigma = principal_sigmas(&total.fixed_view::<2, 2>(0, 0).into()).into();
        self.covariance = Some(AxisCovariance::new(u, v, &total));
    }

    pub(super) fn from_paper(
        e: &AxisExperiment,
        fit: &PaperAxisFit,
        t: &TransmissionFit,
        form: &TransmissionFitForm,
        span_rad: f64,
    ) -> Self {
        AxisReport {
            joint: e.joint,
            experiment: e.name.clone(),
            estimator: AxisEstimator::Paper,
            points: e.target0_m.len(),
            span: AxisSpan::Deg(span_rad.to_degrees()),
            point_mm: (fit.axis.origin_m.coords * 1e3).into(),
            direction: fit.axis.direction.into_inner().into(),
            // The paper's estimator reports no covariance of the line.
            direction_sigma: [f64::NAN; 2].into(),
            position_sigma: PositionSigma::NONE,
            transmission: t.transmission.clone(),
            coefficient_names: form.coefficient_names(),
            coefficient_sigma: t.sigma.clone(),
            residual_rms_mm: (fit.axial_rms.powi(2) + fit.radial_rms.powi(2)).sqrt() * 1e3,
            condition_number: fit.condition_number,
            identifiability: vec![],
            covariance: None,
            kind: revolute(),
            sweeps: vec![],
            moments: None,
            // The paper's estimator gives no correlation of the coefficients: taken as none.
            harmonics: harmonics(&t.transmission, &|a, b| if a == b { t.sigma[a].powi(2) } else { 0.0 }),
        }
    }
}

/// One harmonic of a transmission (eq. 8) as amplitude and phase,
/// `s sin(k x) + c cos(k x) = A sin(k x + phase)`, with first-order 1-sigma from the
/// covariance of `(s, c)` (gradients `(s, c) / A` and `(c, -s) / A^2`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct HarmonicReport {
    /// Harmonic order `k`.
    pub order: usize,
    /// Amplitude in joint angle (a gear's: N times its gear-angle amplitude) \[rad\].
    pub amplitude_rad: f64,
    /// Its 1-sigma \[rad\].
    pub amplitude_sigma_rad: f64,
    /// Phase \[rad\].
    pub phase_rad: f64,
    /// Its 1-sigma \[rad\] (first order: meaningless when the amplitude is within a few
    /// sigma of zero).
    pub phase_sigma_rad: f64,
}

/// The harmonics of `transmission` (none for a polynomial), `cov(a, b)` the covariance of its
/// coefficients `[sin.., cos..]` \[rad^2\].
pub fn harmonics(transmission: &Transmission, cov: &dyn Fn(usize, usize) -> f64) -> Vec<HarmonicReport> {
    let (sin, cos, to_joint) = match transmission {
        Transmission::Harmonic { sin, cos } => (sin, cos, 1.0),
        Transmission::Gear { ratio, sin, cos } => (sin, cos, *ratio),
        Transmission::Polynomial { .. } => return vec![],
    };
    let k = sin.len();
    (0..k)
        .map(|h| {
            let (s, c) = (sin[h], cos[h]);
            let a = s.hypot(c);
            let (ss, cc, sc) = (cov(h, h), cov(k + h, k + h), cov(h, k + h));
            let var_a = (s * s * ss + c * c * cc + 2.0 * s * c * sc) / (a * a);
            let var_p = (c * c * ss + s * s * cc - 2.0 * s * c * sc) / (a * a * a * a);
            HarmonicReport {
                order: h + 1,
                amplitude_rad: to_joint * a,
                amplitude_sigma_rad: to_joint * var_a.max(0.0).sqrt(),
                phase_rad: c.atan2(s),
                phase_sigma_rad: var_p.max(0.0).sqrt(),
            }
        })
        .collect()
}

/// 1-sigma of one Table-2 row, in Table 2's units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RowSigma {
    /// \[mm\]
    pub a_mm: f64,
    /// \[mm\]
    pub b_mm: f64,
    /// \[deg\]
    pub alpha_deg: f64,
    /// \[deg\]
    pub beta_deg: f64,
}

/// One calibrated passive coupling.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CouplingReport {
    /// Driving joint (1-based).
    pub from: usize,
    /// Driven joint.
    pub to: usize,
    /// Experiment it comes from.
    pub experiment: String,
    /// Fitted function.
    pub function: CouplingFunction,
    /// Parameter names.
    pub parameter_names: Vec<String>,
    /// Parameters.
    pub parameters: Vec<f64>,
    /// Their 1-sigma: propagated from the fitted axes and transmissions the passive angles
    /// are built on and from the second target's noise (`calibration::procedure`'s
    /// propagation); the coupling fit's own a-posteriori sigma on the lean path.
    pub sigma: Vec<f64>,
    /// The coupling fit's own a-posteriori 1-sigma (`s^2 (J^T J)^-1`: the second target's
    /// noise only, as the fitted axes were exact); for comparison with `sigma`.
    #[serde(default)]
    pub fit_only_sigma: Vec<f64>,
    /// RMS of the angle residuals \[rad\].
    pub residual_rms_rad: f64,
    /// The second-target data the coupling was fitted to, in memory only (the outlier test
    /// refits them).
    #[serde(skip)]
    #[schemars(skip)]
    pub second_target: SecondTargetData,
}

impl CouplingReport {
    pub(super) fn new(from: usize, e: &AxisExperiment, fit: &CouplingFit, form: &CouplingForm) -> Self {
        let parameter_names = match *form {
            CouplingForm::Fractional => ["n0", "n1", "n2", "d0", "d1"].map(String::from).to_vec(),
            CouplingForm::Gear { fit_ratio, order, .. } => {
                let mut v: Vec<String> = if fit_ratio { vec!["ratio".into()] } else { vec![] };
                v.extend((1..=order).map(|i| format!("sin{i}")));
                v.extend((1..=order).map(|i| format!("cos{i}")));
                v
            }
        };
        CouplingReport {
            from,
            to: from + 1,
            experiment: e.name.clone(),
            function: fit.function.clone(),
            parameter_names,
            parameters: fit.parameters.clone(),
            sigma: fit.sigma.clone(),
            fit_only_sigma: fit.sigma.clone(),
            residual_rms_rad: fit.residual_rms_rad,
            second_target: SecondTargetData::default(),
        }
    }
}

/// The tool frame, fitted from the three tool targets at the reference pose.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ToolReport {
    /// The experiment observed.
    pub experiment: String,
    /// Its step.
    pub step: usize,
    /// The calibrated tool frame in the last link (in the file: [`ToolPose`]).
    #[serde(with = "tool_pose")]
    #[schemars(with = "ToolPose")]
    pub last_link_from_tool: Isometry3<f64>,
    /// RMS of the three-point fit \[mm\] (noise only, for a rigid tool).
    pub fit_rms_mm: f64,
    /// 1-sigma of the tool frame in its own axes, propagated from the axes, couplings and
    /// tool targets (absent on the lean path and in older files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma: Option<FrameSigma>,
}

/// A frame in the file: translation in mm and rotation as a unit quaternion `[x, y, z, w]`
/// (exact, unlike roll-pitch-yaw).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ToolPose {
    /// Translation \[mm\].
    pub translation_mm: [f64; 3],
    /// Rotation, unit quaternion `[x, y, z, w]`.
    pub rotation_xyzw: [f64; 4],
}

/// Before schema 2: nalgebra's layout, translation in metres.
#[derive(Deserialize)]
struct ToolPoseM {
    translation: [f64; 3],
    rotation: [f64; 4],
}

impl From<ToolPoseM> for ToolPose {
    fn from(p: ToolPoseM) -> Self {
        ToolPose {
            translation_mm: p.translation.map(|x| x * 1e3),
            rotation_xyzw: p.rotation,
        }
    }
}

/// `Isometry3` (metres) as [`ToolPose`] (mm), reading the old layout too.
mod tool_pose {
    use super::{ToolPose, ToolPoseM};
    use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

    pub fn serialize<S: serde::Serializer>(iso: &Isometry3<f64>, s: S) -> Result<S::Ok, S::Error> {
        let t = iso.translation.vector * 1e3;
        let q = iso.rotation.quaternion().coords;
        serde::Serialize::serialize(
            &ToolPose {
                translation_mm: [t.x, t.y, t.z],
                rotation_xyzw: [q.x, q.y, q.z, q.w],
            },
            s,
        )
    }

    pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Isometry3<f64>, D::Error> {
        let p: ToolPose = crate::json_file::named_or_old::<_, ToolPose, ToolPoseM>(d)?;
        let [x, y, z] = p.translation_mm.map(|v| v / 1e3);
        let [i, j, k, w] = p.rotation_xyzw;
        let q = Quaternion::new(w, i, j, k);
        // As written (bit for bit) when it is a unit quaternion to rounding; else normalised.
        let rotation = if (q.norm() - 1.0).abs() < 1e-12 {
            UnitQuaternion::new_unchecked(q)
        } else {
            UnitQuaternion::new_normalize(q)
        };
        Ok(Isometry3::from_parts(Translation3::new(x, y, z), rotation))
    }
}

/// The result of [`super::calibrate`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Calibration {
    /// The calibrated robot: actual rows, transmissions, couplings, offsets, tool.
    pub robot: RobotModel,
    /// The common reference pose (file units).
    pub reference_cmd: Vec<f64>,
    /// Per joint, base first.
    pub axes: Vec<AxisReport>,
    /// 1-sigma of each Table-2 row of `robot` (propagated from the axes).
    pub row_sigma: Vec<RowSigma>,
    /// Measured couplings.
    pub couplings: Vec<CouplingReport>,
    /// 1-sigma of each joint's zero offset (`transducer_offset`), propagated from the axis
    /// fits and the couplings (empty in files written before it was reported).
    #[serde(default)]
    pub zero_offset_sigma: Vec<ZeroOffsetSigma>,
    /// The tool frame, when observed at the reference pose.
    pub tool: Option<ToolReport>,
    /// The options used.
    pub options: CalibrationOptions,
    /// The nominal description the calibration was made with (name and geometry hash);
    /// absent in files written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<DescriptionIdentity>,
    /// [`crate::measurement::MeasurementSet::digest`] of the data file the calibration was made
    /// from, as read (before any outlier was set aside): filled by `axiscal calibrate`, not by
    /// [`super::calibrate`]; absent in files written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub data_digest: Option<String>,
    /// [`RobotModel::digest`] of `robot` as `axiscal calibrate` wrote it: a file whose `robot`
    /// no longer has it was edited since; absent in files written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_digest: Option<String>,
    /// How the base frame was placed (`docs/method.md`, "Base frame").
    #[serde(default)]
    pub base_rule: Option<BaseRule>,
    /// Joints not swept by any experiment: kept nominal, "not calibrated" (1-based).
    #[serde(default)]
    pub not_calibrated: Vec<usize>,
    /// The noise: estimated from the residuals, the value used, and the test of a given one.
    #[serde(default)]
    pub noise: Option<NoiseReport>,
    /// Fit-and-correct passes for the held joints' recorded values (1: none needed).
    #[serde(default)]
    pub held_passes: usize,
    /// The covariance of the calibrated model's parameters, propagated from the axis fits and
    /// the second and tool targets ([`crate::calibration::model_parameters`]); absent in older
    /// files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_covariance: Option<ModelCovariance>,
    /// The sweep points the outlier test flagged ([`super::screen_sweeps`]), each with whether
    /// the calibration was made without it (absent when none was flagged).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub outliers: Vec<super::OutlierPoint>,
    /// Per-point residuals of the axis fits (written as `residuals.csv`, not in the JSON).
    #[serde(skip)]
    pub residuals: Vec<PointResidual>,
}

/// The measurement noise of a calibration (`docs/formats.md#calibration-json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct NoiseReport {
    /// The estimate from the pooled residuals (null without degrees of freedom).
    pub estimate: Option<NoiseEstimate>,
    /// The 3-D RMS noise the fits were weighted with \[mm\].
    pub used_rms_3d_mm: f64,
    /// `given` (`--noise-mm`), `estimated`, or `default` (the estimate is 0 or none: the
    /// default noise kept).
    pub source: String,
    /// For a given noise: the two-sided chi-square p-value of it against the residuals.
    pub given_p_value: Option<f64>,
    /// For a given noise: whether the residuals contradict it (p < 0.01).
    pub given_contradicted: bool,
}

/// Reads numbers that JSON writes as null when they are NaN (`serde_json` writes NaN as null).
fn nan_from_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let v: Option<f64> = Deserialize::deserialize(d)?;
    Ok(v.unwrap_or(f64::NAN))
}
