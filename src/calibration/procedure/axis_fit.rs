//! Every axis of a campaign from its own experiment: the ML arc fit through the transmission
//! model, or the paper's estimator (eqs. 1-5, then eqs. 6-8), and the held joints'
//! repeatability added to each axis's covariance.

use super::{AxisCovariance, AxisEstimator, AxisExperiment, AxisReport, CalibrationOptions, ProcedureError};
use crate::calibration::arc_model::{MeasurementNoise, axis_quantities_gradient};
use crate::calibration::transmission_fit::TransmissionForm;
use crate::calibration::{
    ArcFitOptions, CalibrationError, angles, fit_arc_with_angle_noise, fit_axis_paper, fit_circle, fit_transmission,
};
use crate::kinematics::AxisLine;
use crate::robot::commands_to_internal;
use crate::robot::{Controller, RobotDescription, Transmission};
use nalgebra::{Isometry3, Point3};

/// One fitted axis: the line, the transmission in the fit's own zero (`theta_a = f^-1(u)`
/// up to a constant) and the report.
pub(super) struct AxisFitOutcome {
    /// The fitted axis (instrument frame).
    pub(super) axis: AxisLine,
    /// The fitted transmission, in the fit's own zero.
    pub(super) transmission: Transmission,
    /// The axis's report.
    pub(super) report: AxisReport,
}

/// Fits the axis of experiment `e` from target 0 and the actuator commands `u` (rad) of its
/// observations, with the estimator of `options`.
fn fit_one_axis(
    e: &AxisExperiment,
    u: &[f64],
    form: TransmissionForm,
    options: &CalibrationOptions,
    repeatability_rad: f64,
) -> Result<AxisFitOutcome, CalibrationError> {
    let noise = MeasurementNoise::from_rms_3d(options.noise_rms_3d_mm * 1e-3);
    let points = &e.target0_m;
    let centroid = Point3::from(points.iter().map(|p| p.coords).sum::<nalgebra::Vector3<f64>>() / points.len() as f64);
    let span_rad =
        u.iter().cloned().fold(f64::NEG_INFINITY, f64::max) - u.iter().cloned().fold(f64::INFINITY, f64::min);
    match options.estimator {
        AxisEstimator::Ml => {
            let fit = fit_arc_with_angle_noise(
                points,
                u,
                &ArcFitOptions {
                    form,
                    noise,
                    reference_point: centroid,
                    max_iterations: options.max_iterations,
                },
                repeatability_rad,
            )?;
            let g = axis_quantities_gradient(&fit.params, &centroid);
            let q = &g * &fit.covariance * g.transpose();
            let mut report = AxisReport::from_ml(e, &fit, &form, span_rad);
            report.covariance = Some(AxisCovariance::new(
                fit.params.u().into_inner(),
                fit.params.v().into_inner(),
                &q.fixed_view::<4, 4>(0, 0).into(),
            ));
            Ok(AxisFitOutcome {
                axis: fit.axis,
                transmission: fit.transmission,
                report,
            })
        }
        AxisEstimator::Paper => {
            // Orient the axis so that increasing commands turn positively about it.
            let circle = fit_circle(points)?;
            let sign = if u[u.len() - 1] >= u[0] { 1.0 } else { -1.0 };
            let guess = nalgebra::Unit::new_unchecked(circle.normal.into_inner() * sign);
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
            let local: Vec<Point3<f64>> = local.iter().map(|p| Point3::new(p.x, p.y, p.z)).collect();
            let increments = angles::displacements_from_start(&local)?;
            let t = fit_transmission(&form, &increments, u)?;
            let report = AxisReport::from_paper(e, &fit, &t, &form, span_rad);
            Ok(AxisFitOutcome {
                axis,
                transmission: t.transmission,
                report,
            })
        }
    }
}
/// The actuator commands (rad, the controller's decoupled `u`) of the file commands `cmd`.
pub(super) fn actuator_commands(controller: &Controller, desc: &RobotDescription, cmd: &[f64]) -> Vec<f64> {
    controller
        .decouple(&commands_to_internal(desc, cmd))
        .expect("commands have the description's joint count (checked by MeasurementSet)")
}

/// Axes and transmissions, in the order the experiments were run (Table 1: 6..1): each
/// joint's fit with the actuator commands (rad) of its joint at every step of its sweep,
/// indexed by joint (0-based).
pub(super) fn fit_axes(
    experiments: &[AxisExperiment],
    desc: &RobotDescription,
    controller: &Controller,
    options: &CalibrationOptions,
    repeatability_rad: &[f64],
) -> Result<Vec<(AxisFitOutcome, Vec<f64>)>, ProcedureError> {
    let n = desc.dof();
    let mut fits: Vec<Option<(AxisFitOutcome, Vec<f64>)>> = (0..n).map(|_| None).collect();
    for e in experiments {
        let k = e.joint - 1;
        let u: Vec<f64> = e
            .commands
            .iter()
            .map(|c| actuator_commands(controller, desc, c)[k])
            .collect();
        let u0: Vec<f64> = e.target0_steps.iter().map(|&j| u[j]).collect();
        let form = TransmissionForm::from(desc.joints[k].transmission_fit_form());
        let outcome =
            fit_one_axis(e, &u0, form, options, repeatability_rad[k]).map_err(|source| ProcedureError::Fit {
                experiment: e.name.clone(),
                joint: e.joint,
                source,
            })?;
        fits[k] = Some((outcome, u));
    }
    Ok(fits
        .into_iter()
        .map(|f| f.expect("every joint has an experiment"))
        .collect())
}

/// The joints below each swept one hold still with their re-positioning error: a bias of
/// the whole sweep (not noise of its points), added to the axis's reported covariance in
/// the instrument frame. Not to the rows above: the campaign leaves a held actuator where
/// it is from one sweep to the next, so the same error turns every axis above it together,
/// which changes no row (it is an error of that joint's value at the reference, as large as
/// its repeatability).
pub(super) fn add_held_joint_covariances(
    fits: &mut [(AxisFitOutcome, Vec<f64>)],
    axes: &[AxisLine],
    repeatability_rad: &[f64],
) {
    for (k, (fit, _)) in fits.iter_mut().enumerate() {
        let held: Vec<(AxisLine, f64)> = (0..k)
            .filter(|&i| repeatability_rad[i] > 0.0)
            .map(|i| (axes[i], repeatability_rad[i]))
            .collect();
        if !held.is_empty() {
            fit.report.add_held_joint_covariance(&axes[k], &held);
        }
    }
}
