//! Every swept axis from its experiments: the ML arc fit through the transmission model (or
//! the paper's estimator, eqs. 1-5 then 6-8) for a rotary joint, the ML line fit (or eqs. 9-13)
//! for a sliding one; several sweeps of one joint jointly as one axis; the held joints'
//! repeatability added to each axis's covariance; the per-point residuals.

use super::experiments::actuator_commands;
use super::options::InvalidOption;
use super::propagation::LocalFit;
use super::{
    AxisCovariance, AxisEstimator, AxisExperiment, AxisReport, CalibrationOptions, Detail, PointResidual,
    ProcedureError, ShortSpan, SweepReport,
};
use crate::calibration::arc_model::{ArcModel, MeasurementNoise, axis_quantities_gradient};
use crate::calibration::line_ml::fit_line;
use crate::calibration::noise::ResidualMoments;
use crate::calibration::sliding::{fit_sliding_axis, fit_sliding_function};
use crate::calibration::{
    ArcFitOptions, CalibrationError, Studies, angles, fit_arc, fit_arc_with_angle_noise_studies, fit_axis_paper,
    fit_circle, fit_transmission,
};
use crate::kinematics::{AxisLine, JointKind};
use crate::robot::TransmissionFitForm;
use crate::robot::{Controller, RobotDescription, Transmission};
use nalgebra::{Isometry3, Point3, Unit, Vector3};

/// One fitted axis: the line (a sliding axis: its direction through the target's first
/// point), the transmission in the fit's own zero (`theta_a = f^-1(u)` up to a constant) and
/// the report.
pub(super) struct AxisFitOutcome {
    /// The fitted axis (instrument frame).
    pub(super) axis: AxisLine,
    /// The transmission form fitted (the description's, or lower where the sweeps do not
    /// resolve it).
    pub(super) form: TransmissionFitForm,
    /// The fitted transmission, in the fit's own zero.
    pub(super) transmission: Transmission,
    /// The axis's report.
    pub(super) report: AxisReport,
    /// Residual moments for the noise estimate (none for the paper's estimator).
    pub(super) moments: Option<ResidualMoments>,
    /// Per-point residuals.
    pub(super) residuals: Vec<PointResidual>,
    /// The ML fit's parameters and covariance, to propagate (not for the paper's estimator,
    /// nor on the lean path without covariance).
    pub(super) local: Option<LocalFit>,
}

/// The points of one joint's sweeps: target 0 of each, the actuator command of the joint at
/// each point, and where each point comes from.
pub(super) struct JointData<'a> {
    /// The sweeps.
    pub(super) sweeps: Vec<&'a AxisExperiment>,
    /// Target-0 points of each sweep (corrected to the design pose or as measured).
    pub(super) points: Vec<Vec<Point3<f64>>>,
    /// Whether the fit only starts the held joints' correction (its points as measured, the
    /// held joints' wander still in them): the gate of a fit that misses its points by a
    /// good part of their spread ([`crate::numerics::stats::ABSURD_SHARE`]) then waits for
    /// the corrected points.
    pub(super) start_only: bool,
}

fn span(u: &[f64]) -> f64 {
    u.iter().cloned().fold(f64::NEG_INFINITY, f64::max) - u.iter().cloned().fold(f64::INFINITY, f64::min)
}

/// The rotary residual of `p` against the predicted point `pred` on the arc (centre `c`,
/// normal `n`): `[radial, tangential, axial]`.
fn arc_components(p: &Point3<f64>, pred: &Point3<f64>, c: &Point3<f64>, n: &Vector3<f64>) -> [f64; 3] {
    let e = p - pred;
    let w = pred - c;
    let radial = (w - n * w.dot(n)).normalize();
    let tangential = n.cross(&radial);
    [e.dot(&radial), e.dot(&tangential), e.dot(n)]
}

impl JointData<'_> {
    fn joint(&self) -> usize {
        self.sweeps[0].joint
    }

    fn name(&self) -> String {
        self.sweeps
            .iter()
            .map(|e| e.name.as_str())
            .collect::<Vec<_>>()
            .join("+")
    }

    /// All points and the joint's actuator command at each.
    fn flat(&self, controller: &Controller, desc: &RobotDescription) -> (Vec<Point3<f64>>, Vec<f64>) {
        let k = self.joint() - 1;
        let mut pts = Vec::new();
        let mut u = Vec::new();
        for (e, p) in self.sweeps.iter().zip(&self.points) {
            pts.extend(p.iter().copied());
            u.extend(
                e.target0_steps
                    .iter()
                    .map(|&i| actuator_commands(controller, desc, &e.commands[i])[k]),
            );
        }
        (pts, u)
    }

    /// Every sweep's target-0 points; an error when there is none (every row names another
    /// target: the ids, not the span, are wrong), for a joint of `kind`.
    fn target0_points(&self, kind: JointKind) -> Result<Vec<Point3<f64>>, ProcedureError> {
        let points: Vec<Point3<f64>> = self.points.iter().flatten().copied().collect();
        if points.is_empty() {
            return Err(ProcedureError::Fit {
                experiment: self.name(),
                joint: self.joint(),
                error: CalibrationError::TooFewPoints {
                    fit: "target 0 (the target on the swept link; check the rows' target ids)",
                    got: 0,
                    needed: if kind == JointKind::Revolute { 3 } else { 2 },
                },
            });
        }
        Ok(points)
    }

    /// The span of the joint's command (file units) over its widest sweep, and the span its
    /// points would need (`needed`, same unit, when known).
    fn short_span(&self, kind: JointKind, needed: Option<f64>) -> ShortSpan {
        let k = self.joint() - 1;
        let written = self
            .sweeps
            .iter()
            .map(|e| {
                let column = || e.target0_steps.iter().map(|&i| e.commands[i][k]);
                column().fold(f64::NEG_INFINITY, f64::max) - column().fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        ShortSpan { written, needed, kind }
    }

    /// The error of a rotary joint whose points lie within
    /// [`crate::numerics::stats::UNRESOLVED_SPREAD_OVER_NOISE`] times the noise `noise_mm` of a
    /// straight line (RMS, [`crate::numerics::stats::rms_off_line`]): a turning target moves on
    /// an arc; `None` when they bow beyond it.
    fn straight(&self, points: &[Point3<f64>], noise_mm: f64) -> Option<ProcedureError> {
        let off_line_mm = crate::numerics::stats::rms_off_line(points) * 1e3;
        (off_line_mm < crate::numerics::stats::UNRESOLVED_SPREAD_OVER_NOISE * noise_mm).then(|| {
            ProcedureError::Straight {
                experiment: self.name(),
                joint: self.joint(),
                off_line_mm,
                noise_mm,
                span: self.short_span(JointKind::Revolute, None),
            }
        })
    }

    /// The error of a rotary joint whose widest sweep's arc bows from its chord by less than
    /// [`crate::numerics::stats::SHORT_ARC_SAGITTA_OVER_NOISE`] times the noise `noise_mm`
    /// (its radius from the chord and the span as written), with the span whose arc would bow
    /// that much; `None` for a longer arc or a sweep of half a turn or more.
    fn short_arc(&self, noise_mm: f64) -> Option<ProcedureError> {
        let k = self.joint() - 1;
        let factor = crate::numerics::stats::SHORT_ARC_SAGITTA_OVER_NOISE;
        let (sagitta_mm, radius_mm) = self
            .sweeps
            .iter()
            .zip(&self.points)
            .filter_map(|(e, points)| {
                let by_command = |a: &&usize, b: &&usize| {
                    e.commands[e.target0_steps[**a]][k].total_cmp(&e.commands[e.target0_steps[**b]][k])
                };
                let all: Vec<usize> = (0..points.len()).collect();
                let (lo, hi) = (*all.iter().min_by(by_command)?, *all.iter().max_by(by_command)?);
                let span = e.commands[e.target0_steps[hi]][k] - e.commands[e.target0_steps[lo]][k];
                let half = (span / 2.0).to_radians();
                let radius_mm = (points[hi] - points[lo]).norm() * 1e3 / (2.0 * half.sin());
                (half < std::f64::consts::FRAC_PI_2).then_some((radius_mm * (1.0 - half.cos()), radius_mm))
            })
            .max_by(|a, b| a.0.total_cmp(&b.0))?;
        if sagitta_mm.partial_cmp(&(factor * noise_mm)) != Some(std::cmp::Ordering::Less) {
            return None;
        }
        let bow = factor * noise_mm / radius_mm;
        let needed = (bow < 2.0).then(|| 2.0 * (1.0 - bow).acos().to_degrees());
        Some(ProcedureError::ShortArc {
            experiment: self.name(),
            joint: self.joint(),
            sagitta_mm,
            radius_mm,
            noise_mm,
            span: self.short_span(JointKind::Revolute, needed),
        })
    }

    /// The failure `e` of this joint's axis fit with what its points show
    /// ([`super::misfit::sweep_misfit`]), or `e` when they show none of its causes.
    fn misfit(
        &self,
        e: ProcedureError,
        (controller, desc): (&Controller, &RobotDescription),
        noise_mm: f64,
    ) -> ProcedureError {
        let (points, u) = self.flat(controller, desc);
        let mut labels = self.labels().into_iter();
        let kind = desc.joints[self.joint() - 1].kind;
        let mut start = 0;
        let findings = self
            .points
            .iter()
            .filter_map(|sweep| {
                let range = start..start + sweep.len();
                start = range.end;
                let one = super::misfit::SweepPoints {
                    points: &points[range.clone()],
                    u: &u[range.clone()],
                    labels: labels.by_ref().take(range.len()).collect(),
                    joint: self.joint(),
                };
                super::misfit::sweep_misfit(&one, kind, noise_mm)
            })
            .collect();
        match super::misfit::merged(findings) {
            Some(finding) => ProcedureError::Misfit {
                experiment: self.name(),
                joint: self.joint(),
                failure: super::error::failure_words(&e),
                finding,
            },
            None => e,
        }
    }

    /// `(experiment, step)` of each flat point.
    fn labels(&self) -> Vec<(String, usize)> {
        self.sweeps
            .iter()
            .flat_map(|e| e.target0_steps.iter().map(move |&i| (e.name.clone(), e.steps[i])))
            .collect()
    }
}

/// The error of a turning joint's sweep whose points spread within the noise (`spread_mm`,
/// `noise_mm`) because the description places its target 0 on the joint's own axis
/// ([`super::on_axis::target_on_axis`] at the sweep's first commands). `None` when it does not
/// (then the span or the data are the cause, said by the caller).
fn on_axis(
    data: &JointData<'_>,
    desc: &RobotDescription,
    controller: &Controller,
    (spread_mm, noise_mm): (f64, f64),
) -> Option<ProcedureError> {
    let joint = data.joint();
    if desc.joints[joint - 1].kind != JointKind::Revolute {
        return None;
    }
    let first_cmd = data.sweeps.first()?.commands.first()?;
    let span_rad = data.short_span(JointKind::Revolute, None).written.to_radians();
    let t = super::on_axis::target_on_axis(desc, controller, joint, first_cmd, span_rad, noise_mm)?;
    Some(ProcedureError::TargetOnAxis {
        experiment: data.name(),
        joint,
        spread_mm,
        noise_mm,
        factor: crate::numerics::stats::UNRESOLVED_SPREAD_OVER_NOISE,
        link: t.link,
        position_mm: t.position_mm,
        off_axis_mm: t.off_axis_mm,
        needed_mm: t.needed_mm,
    })
}

/// Fits one joint's axis from its sweeps with the estimator of `options`.
pub(super) fn fit_joint(
    data: &JointData<'_>,
    desc: &RobotDescription,
    controller: &Controller,
    options: &CalibrationOptions,
    noise_mm: f64,
    repeatability: f64,
    detail: Detail,
) -> Result<AxisFitOutcome, ProcedureError> {
    let joint = data.joint();
    let kind = desc.joints[joint - 1].kind;
    let points = data.target0_points(kind)?;
    let spread_mm = crate::numerics::stats::rms_spread(&points) * 1e3;
    // Points within the noise of their centroid (by the noise assumed: an estimated one may be
    // far smaller) explain a fit that fails or misses them: said instead.
    let factor = crate::numerics::stats::UNRESOLVED_SPREAD_OVER_NOISE;
    let unresolved = || ProcedureError::Unresolved {
        experiment: data.name(),
        joint,
        spread_mm,
        noise_mm,
        factor,
        // Points evenly along a segment of length `L` spread `L / sqrt(12)` about their
        // centroid: the travel whose spread is `factor` times the noise.
        span: data.short_span(
            kind,
            (kind == JointKind::Prismatic).then(|| 12f64.sqrt() * factor * noise_mm),
        ),
    };
    let within_noise = spread_mm < factor * noise_mm;
    let unresolved = || on_axis(data, desc, controller, (spread_mm, noise_mm)).unwrap_or_else(unresolved);
    // Why a fit failed or missed its points, when the points say it: no motion, an arc too
    // short to bow beyond the noise, or a turning joint's points on a straight line.
    let explained = || {
        if within_noise {
            return Some(unresolved());
        }
        (kind == JointKind::Revolute)
            .then(|| data.short_arc(noise_mm).or_else(|| data.straight(&points, noise_mm)))
            .flatten()
    };
    let requested = desc.joints[joint - 1].transmission_fit_form();
    let mut form = requested;
    let setting = FitSetting {
        desc,
        controller,
        options,
        noise_mm,
        repeatability,
        detail,
    };
    let mut out = loop {
        match fit_joint_as(data, form, &setting) {
            Err(ProcedureError::Fit {
                error: CalibrationError::NotInvertible { .. },
                ..
            }) if form.order() > 0 => form = form.one_order_lower().unwrap_or(form),
            // Too few points is its own cause, whatever their spread.
            Err(
                e @ ProcedureError::Fit {
                    error: CalibrationError::TooFewPoints { .. },
                    ..
                },
            ) => return Err(naming_the_order(e, desc, form)),
            Err(e) => return Err(explained().unwrap_or_else(|| data.misfit(e, (controller, desc), noise_mm))),
            Ok(fitted) => break fitted,
        }
    };
    if !data.start_only && out.report.residual_rms_mm > crate::numerics::stats::ABSURD_SHARE * spread_mm {
        if let Some(cause) = explained() {
            return Err(cause);
        }
        let absurd = ProcedureError::Absurd {
            experiment: data.name(),
            joint,
            rms_mm: out.report.residual_rms_mm,
            spread_mm,
            share: 100.0 * out.report.residual_rms_mm / spread_mm,
        };
        return Err(data.misfit(absurd, (controller, desc), noise_mm));
    }
    if form != requested {
        out.report.identifiability.push(format!(
            "transmission: the sweeps do not resolve order {} (its fitted harmonics make the transmission non-monotonic over the sweep): fitted to order {}",
            requested.order(),
            form.order()
        ));
    }
    if detail == Detail::Report {
        out.report.moments = out.moments;
        out.report.sweeps = sweep_reports(data, &out, desc, controller, options, noise_mm * 1e-3 / 3f64.sqrt());
        for (sweep, rms) in out.report.sweeps.iter_mut().zip(rms_without_each(data, form, &setting)) {
            sweep.without_rms_mm = rms;
        }
    }
    Ok(out)
}

/// With several sweeps: the residual RMS \[mm\] of the joint's fit (transmission `form`)
/// from every sweep but each in turn (none where that fit fails, nor with one sweep): the
/// leave-one-out that tells the sweep carrying a joint's misfit (`sanity/`).
fn rms_without_each(data: &JointData<'_>, form: TransmissionFitForm, setting: &FitSetting<'_>) -> Vec<Option<f64>> {
    let n = data.sweeps.len();
    if n < 2 {
        return vec![None; n];
    }
    let lean = FitSetting {
        detail: Detail::Model,
        ..*setting
    };
    (0..n)
        .map(|i| {
            let keep = |v: usize| v != i;
            let others = JointData {
                sweeps: data
                    .sweeps
                    .iter()
                    .enumerate()
                    .filter(|(v, _)| keep(*v))
                    .map(|(_, s)| *s)
                    .collect(),
                points: data
                    .points
                    .iter()
                    .enumerate()
                    .filter(|(v, _)| keep(*v))
                    .map(|(_, p)| p.clone())
                    .collect(),
                start_only: false,
            };
            fit_joint_as(&others, form, &lean)
                .ok()
                .map(|f| f.report.residual_rms_mm)
        })
        .collect()
}

/// A fit error `e` of too few points as the description's transmission order's fault, when
/// its `transmission_fit` asks for an order above the default 1 (`form`, the order tried).
fn naming_the_order(e: ProcedureError, desc: &RobotDescription, form: TransmissionFitForm) -> ProcedureError {
    match e {
        ProcedureError::Fit {
            experiment,
            joint,
            error: source,
        } if desc.joints[joint - 1].transmission_fit.is_some() && form.order() > 1 => ProcedureError::FitOrder {
            experiment,
            joint,
            order: form.order(),
            source: Box::new(source),
        },
        other => other,
    }
}

/// What every transmission order tried for one joint shares ([`fit_joint`]'s arguments).
struct FitSetting<'a> {
    desc: &'a RobotDescription,
    controller: &'a Controller,
    options: &'a CalibrationOptions,
    noise_mm: f64,
    repeatability: f64,
    detail: Detail,
}

/// Fits one joint's axis with the transmission `form`: the highest order the sweeps resolve
/// is picked by [`fit_joint`] (eq. 8: the transmission must be invertible over the sweep).
fn fit_joint_as(
    data: &JointData<'_>,
    form: TransmissionFitForm,
    setting: &FitSetting<'_>,
) -> Result<AxisFitOutcome, ProcedureError> {
    let (desc, options, detail) = (setting.desc, setting.options, setting.detail);
    let joint = data.joint();
    let (points, u) = data.flat(setting.controller, desc);
    let err = |error| ProcedureError::Fit {
        experiment: data.name(),
        joint,
        error,
    };
    let kind = desc.joints[joint - 1].kind;
    let paper = options.estimator == AxisEstimator::Paper;
    if paper && data.sweeps.len() > 1 {
        return Err(ProcedureError::InvalidOption(InvalidOption {
            field: "estimator",
            message: format!(
                "joint {joint} is swept {} times ({}): the paper's estimator fits one sweep per joint; use the ML estimator",
                data.sweeps.len(),
                data.name()
            ),
        }));
    }
    let sigma = setting.noise_mm * 1e-3 / 3f64.sqrt();
    match (kind, paper) {
        (JointKind::Revolute, false) => {
            fit_arc_ml(data, &points, &u, form, options, sigma, setting.repeatability, detail).map_err(err)
        }
        (JointKind::Revolute, true) => fit_arc_paper(data, &points, &u, form, options).map_err(err),
        (JointKind::Prismatic, false) => {
            fit_line_ml(data, &points, &u, form, options, sigma, setting.repeatability, detail).map_err(err)
        }
        (JointKind::Prismatic, true) => fit_line_paper(data, &points, &u, form, options).map_err(err),
    }
}

/// The ML arc fit of one joint; the identifiability study, the covariance and the residuals
/// only as far as `detail` asks.
#[allow(clippy::too_many_arguments)]
fn fit_arc_ml(
    data: &JointData<'_>,
    points: &[Point3<f64>],
    u: &[f64],
    form: TransmissionFitForm,
    options: &CalibrationOptions,
    sigma: f64,
    repeatability_rad: f64,
    detail: Detail,
) -> Result<AxisFitOutcome, CalibrationError> {
    let centroid = Point3::from(points.iter().map(|p| p.coords).sum::<Vector3<f64>>() / points.len() as f64);
    let arc_options = ArcFitOptions {
        form,
        noise: MeasurementNoise::Isotropic { sigma_per_axis: sigma },
        reference_point: centroid,
        max_iterations: options.max_iterations,
    };
    // A model without a report needs the residual moments only to estimate the noise.
    let studies = match detail {
        Detail::Report => Studies::Run,
        _ if options.estimate_noise => Studies::Skip,
        _ => Studies::EstimateOnly,
    };
    let fit = fit_arc_with_angle_noise_studies(points, u, &arc_options, repeatability_rad, studies)?;
    let mut report = AxisReport::from_arc(data.joint(), &data.name(), points.len(), &fit, &form, span(u));
    if detail != Detail::Model {
        let g = axis_quantities_gradient(&fit.params, &centroid);
        let q = &g * &fit.covariance * g.transpose();
        report.covariance = Some(AxisCovariance::new(
            fit.params.u().into_inner(),
            fit.params.v().into_inner(),
            &q.fixed_view::<4, 4>(0, 0).into(),
        ));
    }
    let local = (detail != Detail::Model).then(|| LocalFit::Arc {
        params: fit.params.clone(),
        reference: centroid,
        form,
        covariance: fit.covariance.clone(),
    });
    if detail != Detail::Report {
        return Ok(AxisFitOutcome {
            form,
            axis: fit.axis,
            transmission: fit.transmission,
            report,
            moments: (studies != Studies::EstimateOnly).then_some(fit.moments),
            residuals: vec![],
            local,
        });
    }
    let pred = ArcModel::new(form, u, &arc_options.noise)?.predict(&fit.params)?;
    let n = fit.params.normal().into_inner();
    let residuals = data
        .labels()
        .into_iter()
        .zip(points.iter().zip(&pred))
        .map(|((experiment, step), (p, pr))| PointResidual {
            experiment,
            joint: data.joint(),
            step,
            target: 0,
            components_mm: arc_components(p, pr, &fit.params.centre, &n).map(|c| c * 1e3),
            sliding: false,
        })
        .collect();
    Ok(AxisFitOutcome {
        form,
        axis: fit.axis,
        transmission: fit.transmission.clone(),
        report,
        moments: Some(fit.moments),
        residuals,
        local,
    })
}

/// The ML line fit of one sliding joint; the residuals only for a report (`detail`).
#[allow(clippy::too_many_arguments)]
fn fit_line_ml(
    data: &JointData<'_>,
    points: &[Point3<f64>],
    u: &[f64],
    form: TransmissionFitForm,
    options: &CalibrationOptions,
    sigma: f64,
    repeatability_m: f64,
    detail: Detail,
) -> Result<AxisFitOutcome, CalibrationError> {
    let fit = fit_line(points, u, &form, sigma, repeatability_m, options.max_iterations)?;
    let report = AxisReport::from_line(data.joint(), &data.name(), &fit, &form, span(u));
    let labels = if detail == Detail::Report {
        data.labels()
    } else {
        vec![]
    };
    let residuals = labels
        .into_iter()
        .zip(&fit.residuals)
        .map(|((experiment, step), r)| PointResidual {
            experiment,
            joint: data.joint(),
            step,
            target: 0,
            components_mm: [r.x * 1e3, r.y * 1e3, r.z * 1e3],
            sliding: true,
        })
        .collect();
    Ok(AxisFitOutcome {
        form,
        axis: AxisLine {
            origin_m: fit.params.start,
            direction: fit.direction,
        },
        transmission: fit.transmission.clone(),
        report,
        moments: Some(fit.moments),
        residuals,
        local: (detail != Detail::Model).then(|| LocalFit::Line {
            params: fit.params.clone(),
            form,
            covariance: fit.covariance.clone(),
        }),
    })
}

/// The paper's estimator, eqs. (1)-(5), then eqs. (6)-(8) (one sweep).
fn fit_arc_paper(
    data: &JointData<'_>,
    points: &[Point3<f64>],
    u: &[f64],
    form: TransmissionFitForm,
    options: &CalibrationOptions,
) -> Result<AxisFitOutcome, CalibrationError> {
    // Orient the axis so that increasing commands turn positively about it.
    let circle = fit_circle(points)?;
    let sign = if u[u.len() - 1] >= u[0] { 1.0 } else { -1.0 };
    let guess = Unit::new_unchecked(circle.normal.into_inner() * sign);
    let fit = fit_axis_paper(points, Some(&guess), options.max_iterations)?;
    let mut axis = fit.axis;
    if axis.direction.dot(&guess) < 0.0 {
        axis.direction = -axis.direction;
    }
    let frame = Isometry3::face_towards(
        &axis.origin_m,
        &(axis.origin_m + axis.direction.into_inner()),
        &circle.u,
    );
    // Points in a frame with Z on the axis: eqs. (6)-(7), then eq. (8).
    let local: Vec<Point3<f64>> = points.iter().map(|p| frame.inverse_transform_point(p)).collect();
    let increments = angles::displacements_from_start(&local)?;
    let t = fit_transmission(&form, &increments, u)?;
    let report = AxisReport::from_paper(data.sweeps[0], &fit, &t, &form, span(u));
    Ok(AxisFitOutcome {
        form,
        axis,
        transmission: t.transmission,
        report,
        moments: None,
        residuals: vec![],
        local: None,
    })
}

/// The paper's sliding-axis estimator, eqs. (9)-(12), then eq. (13) (one sweep).
fn fit_line_paper(
    data: &JointData<'_>,
    points: &[Point3<f64>],
    u: &[f64],
    form: TransmissionFitForm,
    options: &CalibrationOptions,
) -> Result<AxisFitOutcome, CalibrationError> {
    let fit = fit_sliding_axis(points, options.max_iterations)?;
    let f = fit_sliding_function(&fit.displacements, u, form.n_coefficients())?;
    // S_c - S_c^0 = sum_k c_k S^k with S from step 0: f(S) = S + u_0 + (c_1 - 1) S + c_2 S^2 ..
    let mut c = f.coefficients.clone();
    c[0] -= 1.0;
    let transmission = Transmission::Polynomial { c0: u[0], c };
    let e = data.sweeps[0];
    let report = AxisReport {
        joint: e.joint,
        experiment: e.name.clone(),
        estimator: AxisEstimator::Paper,
        points: points.len(),
        span: super::result::AxisSpan::Mm(span(u) * 1e3),
        point_mm: (points[0].coords * 1e3).into(),
        direction: fit.direction.into_inner().into(),
        // The paper's estimator reports no covariance of the line.
        direction_sigma: [f64::NAN; 2].into(),
        position_sigma: super::result::PositionSigma::NONE,
        transmission: transmission.clone(),
        coefficient_names: form.coefficient_names(),
        coefficient_sigma: f.sigma.clone(),
        residual_rms_mm: f.residual_rms * 1e3,
        condition_number: f64::NAN,
        identifiability: vec![],
        covariance: None,
        kind: crate::kinematics::JointKind::Prismatic,
        harmonics: vec![],
        sweeps: vec![],
        moments: None,
    };
    Ok(AxisFitOutcome {
        form,
        axis: AxisLine {
            origin_m: points[0],
            direction: fit.direction,
        },
        transmission,
        report,
        moments: None,
        residuals: vec![],
        local: None,
    })
}

/// Per sweep of a joint: its points, residual RMS in the joint fit, held offsets and wander,
/// and (several sweeps) how far its own axis lies from the joint's.
fn sweep_reports(
    data: &JointData<'_>,
    out: &AxisFitOutcome,
    desc: &RobotDescription,
    controller: &Controller,
    options: &CalibrationOptions,
    sigma: f64,
) -> Vec<SweepReport> {
    let k = data.joint() - 1;
    let mut start = 0;
    data.sweeps
        .iter()
        .zip(&data.points)
        .map(|(e, pts)| {
            let res = &out.residuals.get(start..start + pts.len()).unwrap_or(&[]);
            start += pts.len();
            let rms = (res
                .iter()
                .map(|r| r.components_mm.iter().map(|c| c * c).sum::<f64>())
                .sum::<f64>()
                / pts.len().max(1) as f64)
                .sqrt();
            let (offsets, wander) = held_offsets(e, desc, &out.report);
            let own = (data.sweeps.len() > 1)
                .then(|| own_axis(e, pts, k, desc, controller, options, sigma, &out.axis, out.form))
                .flatten();
            SweepReport {
                experiment: e.name.clone(),
                points: pts.len(),
                residual_rms_mm: rms,
                held_offsets: offsets.into_iter().map(Into::into).collect(),
                held_wander: wander,
                own_axis_angle_mrad: own.map(|o| o.angle_mrad),
                own_axis_offset_mm: own.and_then(|o| o.offset_mm),
                without_rms_mm: None,
                own_moments: own.map(|o| o.moments),
            }
        })
        .collect()
}

/// The held joints of `e` whose median differs from the reference (recorded in the report's
/// experiment's reference, file units), and the largest wander about the medians.
fn held_offsets(e: &AxisExperiment, desc: &RobotDescription, _report: &AxisReport) -> (Vec<(usize, f64)>, f64) {
    use crate::numerics::stats::{QuantileMethod, quantile};
    let mut offsets = Vec::new();
    let mut wander: f64 = 0.0;
    for j in (0..desc.dof()).filter(|&j| e.holds_constant(j)) {
        let v: Vec<f64> = e.commands.iter().map(|c| c[j]).collect();
        let m = quantile(&v, 0.5, QuantileMethod::Linear);
        wander = v.iter().fold(wander, |w, x| w.max((x - m).abs()));
        offsets.push((j + 1, m));
    }
    (offsets, wander)
}

/// A sweep's own axis fit against its joint's.
#[derive(Clone, Copy)]
struct OwnAxis {
    /// The angle between the two axes \[mrad\].
    angle_mrad: f64,
    /// (Rotary) the own axis's distance from the joint's at its point \[mm\].
    offset_mm: Option<f64>,
    /// The own fit's residual moments: the noise of the sweep's points alone.
    moments: ResidualMoments,
}

/// This sweep's own axis against the joint's ([`OwnAxis`]).
#[allow(clippy::too_many_arguments)]
fn own_axis(
    e: &AxisExperiment,
    pts: &[Point3<f64>],
    k: usize,
    desc: &RobotDescription,
    controller: &Controller,
    options: &CalibrationOptions,
    sigma: f64,
    joint_axis: &AxisLine,
    form: TransmissionFitForm,
) -> Option<OwnAxis> {
    let u: Vec<f64> = e
        .target0_steps
        .iter()
        .map(|&i| actuator_commands(controller, desc, &e.commands[i])[k])
        .collect();
    let dir_angle = |d: &Vector3<f64>| d.angle(&joint_axis.direction) * 1e3;
    match desc.joints[k].kind {
        JointKind::Revolute => {
            let fit = fit_arc(
                pts,
                &u,
                &ArcFitOptions {
                    form,
                    noise: MeasurementNoise::Isotropic { sigma_per_axis: sigma },
                    reference_point: joint_axis.origin_m,
                    max_iterations: options.max_iterations,
                },
            )
            .ok()?;
            let w = fit.axis.origin_m - joint_axis.origin_m;
            let across = w - joint_axis.direction.into_inner() * w.dot(&joint_axis.direction);
            Some(OwnAxis {
                angle_mrad: dir_angle(&fit.axis.direction),
                offset_mm: Some(across.norm() * 1e3),
                moments: fit.moments,
            })
        }
        JointKind::Prismatic => {
            let fit = fit_line(pts, &u, &form, sigma, 0.0, options.max_iterations).ok()?;
            Some(OwnAxis {
                angle_mrad: dir_angle(&fit.direction),
                offset_mm: None,
                moments: fit.moments,
            })
        }
    }
}

/// The joints below each swept one hold still with their re-positioning error: a bias of
/// the whole sweep (not noise of its points), added to the axis's reported covariance in
/// the instrument frame. Not to the rows above: the campaign leaves a held actuator where
/// it is from one sweep to the next, so the same error turns every axis above it together,
/// which changes no row (it is an error of that joint's value at the reference, as large as
/// its repeatability). Only rotary joints below turn an axis; a sliding joint's error moves
/// it parallel, which changes no direction and (for a rotary axis) is its position's bias,
/// not modelled.
pub(super) fn add_held_joint_covariances(
    fits: &mut [Option<AxisFitOutcome>],
    axes: &[Option<AxisLine>],
    kinds: &[JointKind],
    repeatability: &[f64],
) {
    for k in 0..fits.len() {
        let held: Vec<(AxisLine, f64)> = (0..k)
            .filter(|&i| repeatability[i] > 0.0 && kinds[i] == JointKind::Revolute)
            .filter_map(|i| axes[i].map(|a| (a, repeatability[i])))
            .collect();
        if let (Some(fit), Some(axis)) = (&mut fits[k], axes[k])
            && !held.is_empty()
        {
            fit.report.add_held_joint_covariance(&axis, &held);
        }
    }
}
