//! The default (efficient) rotary-axis estimator: a maximum-likelihood fit of one joint
//! sweep through the transmission model, folding the paper's eqs. (1)-(8) into one weighted
//! least-squares problem on the observed points (model in [`super::arc_model`]):
//! `p_j = c + r (cos(phi0 + D_j) u + sin(phi0 + D_j) v)`, `D_j = f^-1(theta_c^j) - f^-1(theta_c^0)`.
//!
//! Levenberg-Marquardt (Marquardt-scaled) started from the circle fit ([`super::axis_circle`])
//! and a linear transmission fit ([`super::transmission_fit`], eq. 8) of the circle's angles.
//! Unlike the paper's two-stage procedure, the commanded angles help locate the axis, which
//! is what makes the estimator efficient (it attains the Cramer-Rao bound, [`super::crb`]).
//!
//! [`fit_arc_with_angle_noise`] adds independent noise on each point's joint angle (a robot's
//! repeatability) to the measurement noise: a fit with the first-order per-point covariance
//! `Sigma_meas + sigma_theta^2 t_j t_j^T` (effective variance, Orear 1982), the tangents
//! `t_j` taken at the starting point.

mod identifiability;

use nalgebra::{DMatrix, Matrix2, Point3, Rotation3, Vector3};

use super::CalibrationError;
use super::arc_model::{
    ArcModel, ArcParams, MeasurementNoise, N_GEOMETRY, axis_quantities_gradient, check_angle_sigma,
};
use super::axis_circle::fit_circle;
use super::noise::ResidualMoments;
use super::transmission_fit::fit_transmission_passes;
use crate::kinematics::AxisLine;
use crate::numerics::lsq;
use crate::robot::Transmission;
use crate::robot::TransmissionFitForm;
use identifiability::identifiability;
pub use identifiability::{Identifiability, WeakDirection};

const FIT: &str = "arc maximum-likelihood fit";

/// The fit stops where the Gauss-Newton step would lower the (whitened) cost by at most this
/// ([`lsq::LmOptions::negligible_decrease`]): within about `sqrt(1e-10)` = 1e-5 standard
/// deviations of the optimum, far below the estimate's own uncertainty, and well above the
/// cost's rounding noise (~1e-14 of a cost of ~3n), where further iterations only wander.
const NEGLIGIBLE_DECREASE: f64 = 1e-10;

/// Options of [`fit_arc`].
#[derive(Clone, Debug, PartialEq)]
pub struct ArcFitOptions {
    /// Transmission form whose coefficients are fitted with the geometry.
    pub form: TransmissionFitForm,
    /// Measurement noise (weights the fit; the reported covariance assumes it).
    pub noise: MeasurementNoise,
    /// The reported axis point is the one closest to this point (points' unit).
    pub reference_point: Point3<f64>,
    /// Iteration limit of Levenberg-Marquardt.
    pub max_iterations: usize,
}

/// The result of [`fit_arc`].
#[derive(Clone, Debug, PartialEq)]
pub struct ArcFit {
    /// Parameters at the optimum.
    pub params: ArcParams,
    /// The axis: point closest to the reference point (points' unit; the field name says
    /// metres, true when the points are in metres) and unit direction (the joint's +Z).
    pub axis: AxisLine,
    /// Radius of the arc (points' unit).
    pub radius: f64,
    /// The fitted transmission `theta_c = f(theta_a)`.
    pub transmission: Transmission,
    /// `f^-1(theta_c^0)`: actual displacement at step 0 \[rad\].
    pub actual_start_rad: f64,
    /// Parameter names in covariance order.
    pub param_names: Vec<String>,
    /// `(J^T W J)^-1` in the local parameters at the optimum, NOT scaled by the
    /// a-posteriori variance factor (it trusts the given noise; multiply by
    /// `variance_factor` for the scaled one).
    pub covariance: DMatrix<f64>,
    /// Covariance of the axis direction's components along `u, v` \[rad^2\].
    pub axis_direction_covariance: Matrix2<f64>,
    /// Covariance of the axis point's components along `u, v` (points' unit squared).
    pub axis_position_covariance: Matrix2<f64>,
    /// 1-sigma of each transmission coefficient \[rad\] (unscaled covariance).
    pub coefficient_sigma: Vec<f64>,
    /// `chi^2 / (3n - p)`; about 1 when the noise model is right.
    pub variance_factor: f64,
    /// RMS length of the point residuals (points' unit).
    pub residual_rms: f64,
    /// Levenberg-Marquardt iterations used.
    pub iterations: usize,
    /// Identifiability report.
    pub identifiability: Identifiability,
    /// Residual moments of the measurement-noise-only fit, with the swept joint's jitter
    /// term when [`fit_arc_with_angle_noise`] was given one (for the noise estimate,
    /// [`super::noise`]).
    pub moments: ResidualMoments,
}

/// The eq.-8 passes of the starting point ([`fit_transmission_passes`]): its coefficients
/// are then within about the coefficients' size squared (~1e-5 rad) of eq. 8's fixed point,
/// which the maximum-likelihood fit moves anyway.
const START_PASSES: usize = 1;

/// Starting parameters: circle fit + a linear transmission fit of the circle angles.
pub fn initial_params(
    points: &[Point3<f64>],
    commands_rad: &[f64],
    form: &TransmissionFitForm,
) -> Result<ArcParams, CalibrationError> {
    let circle = fit_circle(points)?;
    let (u, mut v, mut normal) = (circle.u.into_inner(), circle.v.into_inner(), circle.normal.into_inner());
    let mut increments = Vec::with_capacity(points.len());
    let mut last = 0.0;
    for p in points {
        let d = p - circle.centre;
        let a = d.dot(&v).atan2(d.dot(&u));
        // Unwrap: successive steps are far below half a turn.
        let k = ((last - a) / std::f64::consts::TAU).round();
        last = a + k * std::f64::consts::TAU;
        increments.push(last);
    }
    // The circle's normal turns the points positively in their order; a sweep whose commands
    // fall along that order (run from its high end down) turns the other way about the axis
    // its commands turn positively about (eq. 8's increments grow with the command).
    if falls_with_commands(&increments, commands_rad) {
        (v, normal) = (-v, -normal);
        increments.iter_mut().for_each(|a| *a = -*a);
    }
    let t = fit_transmission_passes(form, &increments, commands_rad, START_PASSES)?;
    let frame = Rotation3::from_basis_unchecked(&[u, v, normal]);
    Ok(ArcParams {
        centre: circle.centre,
        frame,
        radius: circle.radius,
        phase_rad: 0.0,
        coefficients: t.coefficients,
    })
}

/// Whether the angles fall as the commands rise: the sign of their covariance.
fn falls_with_commands(angles_rad: &[f64], commands_rad: &[f64]) -> bool {
    let n = angles_rad.len() as f64;
    let (a_mean, c_mean) = (angles_rad.iter().sum::<f64>() / n, commands_rad.iter().sum::<f64>() / n);
    let covariance: f64 = angles_rad
        .iter()
        .zip(commands_rad)
        .map(|(a, c)| (a - a_mean) * (c - c_mean))
        .sum();
    covariance < 0.0
}

/// Maximum-likelihood arc fit of `points` observed at absolute `commands_rad`.
pub fn fit_arc(
    points: &[Point3<f64>],
    commands_rad: &[f64],
    options: &ArcFitOptions,
) -> Result<ArcFit, CalibrationError> {
    fit_arc_from(points, commands_rad, options, None, Studies::Run)
}

/// Whether a fit runs the identifiability study ([`Identifiability`]: the correlation
/// eigen-analysis and the Cramer-Rao tilt for larger spans) after the estimate, and whether it
/// computes the residual moments (for the noise estimate, [`super::noise`]). The estimate and
/// its covariance are the same in every case, bit for bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Studies {
    /// Run it (what a calibration report shows).
    Run,
    /// Skip it (a Monte-Carlo trial only needs the estimate): [`Identifiability::not_studied`].
    /// The residual moments are computed.
    Skip,
    /// Skip the study and the residuals: only the estimate and its covariance (a trial that
    /// does not estimate the noise). [`ArcFit::moments`] is then
    /// [`ResidualMoments::default`] and [`ArcFit::residual_rms`] NaN (not computed).
    EstimateOnly,
}

/// [`fit_arc`] when, besides the measurement noise, each point's joint angle carries an
/// independent Gaussian error of standard deviation `angle_sigma_rad` (a robot's
/// repeatability: the swept actuator is re-positioned at every step, so each point gets a
/// fresh error on its actual joint angle).
///
/// To first order the angle error moves point `j` along the arc's tangent
/// `t_j = dp_j/dtheta_j` ([`ArcModel::angle_derivatives`]), so its covariance is
/// `Sigma_j = Sigma_meas,j + sigma_theta^2 t_j t_j^T` (the effective-variance method, Orear,
/// Am. J. Phys. 50 (1982) 912, eq. 2; [`MeasurementNoise::with_angle_noise`]). `t_j` depends on
/// the parameters, so the fit is two-step feasible generalised least squares (Carroll &
/// Ruppert, *Transformation and Weighting in Regression*, 1988, section 2.1, the
/// iteratively reweighted estimate stopped after one re-weighting): evaluate `Sigma_j` at a
/// consistent preliminary estimate, here the starting point ([`initial_params`]: the circle
/// fit and eq. 8), and fit once with these per-point weights. Any consistent first stage gives
/// the same first-order distribution (ibid.): the start's error of order `sigma` turns the
/// tangents by about `sigma / r`, which moves the estimate by a small fraction of its own
/// standard error. Against the measurement-only fit's optimum as the first stage (one
/// whole fit more) the paper trials' calibrated errors moved by
/// at most 1.3e-4 of their spread (`docs/validation.md`, "The first stage at the starting
/// point"). The reported covariance is the weighted fit's `(J^T Sigma^-1 J)^-1`, i.e. it
/// includes the angle noise. The dependence of `Sigma_j` on the parameters carries
/// information of its own (the trace term of the Gaussian Fisher information, Kay eq. 3.31),
/// which the fit ignores; it is of relative order `(sigma / r)^2` against the mean term, far
/// below 1e-6 here. With [`Studies::Run`] or [`Studies::Skip`] the measurement-only fit is run
/// as well, for the residual moments (the noise estimate) only.
///
/// `angle_sigma_rad == 0` is [`fit_arc`] exactly (one pass, the same arithmetic).
pub fn fit_arc_with_angle_noise(
    points: &[Point3<f64>],
    commands_rad: &[f64],
    options: &ArcFitOptions,
    angle_sigma_rad: f64,
) -> Result<ArcFit, CalibrationError> {
    fit_arc_with_angle_noise_studies(points, commands_rad, options, angle_sigma_rad, Studies::Run)
}

/// [`fit_arc_with_angle_noise`] with the identifiability study run or skipped (`studies`).
pub fn fit_arc_with_angle_noise_studies(
    points: &[Point3<f64>],
    commands_rad: &[f64],
    options: &ArcFitOptions,
    angle_sigma_rad: f64,
    studies: Studies,
) -> Result<ArcFit, CalibrationError> {
    check_angle_sigma(angle_sigma_rad, FIT)?;
    if angle_sigma_rad == 0.0 {
        return fit_arc_from(points, commands_rad, options, None, studies);
    }
    let model = checked_model(points, commands_rad, options)?;
    let start = initial_params(points, commands_rad, &options.form)?;
    // The first stage: the tangents at the starting point weight the fit.
    let tangents = model.angle_derivatives(&start)?;
    // The measurement-only fit only feeds the residual moments (the noise estimate).
    let first_residuals = match studies {
        Studies::EstimateOnly => None,
        Studies::Run | Studies::Skip => {
            let (first, residuals) = fit_arc_core(points, commands_rad, options, Some(start.clone()), Studies::Skip)?;
            let first_tangents = match residuals.as_ref().and_then(|(jw, _)| model.angle_derivatives_from(jw)) {
                Some(t) => t,
                None => model.angle_derivatives(&first.params)?,
            };
            residuals.map(|r| (r, first.covariance, first_tangents))
        }
    };
    let noise = options.noise.with_angle_noise(&tangents, angle_sigma_rad)?;
    let weighted = ArcFitOptions {
        noise,
        ..options.clone()
    };
    let mut fit = fit_arc_from(points, commands_rad, &weighted, Some(start), studies)?;
    // The noise estimate reads the measurement-only fit (its whitened Jacobian and residuals
    // at its optimum), with the jitter's share at its tangents.
    if let Some(((jw, residuals), covariance, first_tangents)) = first_residuals {
        fit.moments = ResidualMoments::of_fit(&jw, &covariance, &residuals, Some((&first_tangents, angle_sigma_rad)));
    }
    Ok(fit)
}

/// [`fit_arc`] from `start` (default: [`initial_params`]).
fn fit_arc_from(
    points: &[Point3<f64>],
    commands_rad: &[f64],
    options: &ArcFitOptions,
    start: Option<ArcParams>,
    studies: Studies,
) -> Result<ArcFit, CalibrationError> {
    fit_arc_core(points, commands_rad, options, start, studies).map(|(fit, _)| fit)
}

/// The whitened Jacobian at the optimum and the point residuals (observed - predicted).
type FitResiduals = (DMatrix<f64>, Vec<Vector3<f64>>);

/// [`fit_arc_from`], with the whitened Jacobian and the residuals at the optimum (unless
/// `studies` is [`Studies::EstimateOnly`]).
fn fit_arc_core(
    points: &[Point3<f64>],
    commands_rad: &[f64],
    options: &ArcFitOptions,
    start: Option<ArcParams>,
    studies: Studies,
) -> Result<(ArcFit, Option<FitResiduals>), CalibrationError> {
    let n = points.len();
    let model = checked_model(points, commands_rad, options)?;
    let p_count = model.n_params();
    let start = match start {
        Some(s) => s,
        None => initial_params(points, commands_rad, &options.form)?,
    };
    let outcome = estimate(&model, points, options, start)?;
    let params = outcome.state;
    let (r, jw) = (outcome.residual, outcome.jacobian);
    let covariance = lsq::inverse_normal_given(&jw, outcome.normal, FIT)?;
    let (residual_rms, moments, residuals) = if studies == Studies::EstimateOnly {
        (f64::NAN, ResidualMoments::default(), None)
    } else {
        let pred = model.predict(&params)?;
        let residuals: Vec<Vector3<f64>> = pred.iter().zip(points).map(|(a, b)| b - a).collect();
        let rms = (residuals.iter().map(|r| r.norm_squared()).sum::<f64>() / n as f64).sqrt();
        let moments = ResidualMoments::of_fit(&jw, &covariance, &residuals, None);
        (rms, moments, Some(residuals))
    };
    let g = axis_quantities_gradient(&params, &options.reference_point);
    let q = &g * &covariance * g.transpose();
    let transmission = options.form.build(&params.coefficients);
    let actual_start_rad =
        transmission
            .actual_from_command(commands_rad[0])
            .ok_or(CalibrationError::NotInvertible {
                fit: FIT,
                command_rad: commands_rad[0],
            })?;
    let identifiability = match studies {
        Studies::Run => identifiability(&model, &params, &jw, &covariance, &options.noise)?,
        Studies::Skip | Studies::EstimateOnly => Identifiability::not_studied(),
    };
    let fit = ArcFit {
        axis: AxisLine {
            origin_m: params.axis_point_near(&options.reference_point),
            direction: params.normal(),
        },
        radius: params.radius,
        transmission,
        actual_start_rad,
        param_names: model.param_names(),
        axis_direction_covariance: q.fixed_view::<2, 2>(0, 0).into(),
        axis_position_covariance: q.fixed_view::<2, 2>(2, 2).into(),
        coefficient_sigma: (N_GEOMETRY..p_count).map(|k| covariance[(k, k)].sqrt()).collect(),
        variance_factor: r.norm_squared() / (3 * n - p_count) as f64,
        residual_rms,
        iterations: outcome.iterations,
        covariance,
        identifiability,
        moments,
        params,
    };
    Ok((fit, residuals.map(|r| (jw, r))))
}

/// The arc model of these points and commands, checked: as many commands as points, and
/// more coordinates than parameters.
fn checked_model(
    points: &[Point3<f64>],
    commands_rad: &[f64],
    options: &ArcFitOptions,
) -> Result<ArcModel, CalibrationError> {
    let n = points.len();
    if commands_rad.len() != n {
        return Err(CalibrationError::LengthMismatch {
            fit: FIT,
            what: "commands",
            got: commands_rad.len(),
            expected: n,
        });
    }
    let model = ArcModel::new(options.form, commands_rad, &options.noise)?;
    if 3 * n <= model.n_params() {
        return Err(CalibrationError::TooFewPoints {
            fit: FIT,
            got: n,
            needed: model.n_params() / 3 + 1,
        });
    }
    Ok(model)
}

/// The Levenberg-Marquardt estimate of `model`'s parameters from `start` (converged).
fn estimate(
    model: &ArcModel,
    points: &[Point3<f64>],
    options: &ArcFitOptions,
    start: ArcParams,
) -> Result<lsq::LmOutcome<ArcParams>, CalibrationError> {
    let lm = lsq::LmOptions {
        negligible_decrease: Some(NEGLIGIBLE_DECREASE),
        ..lsq::LmOptions::marquardt(FIT, options.max_iterations)
    };
    Ok(lsq::levenberg_marquardt(
        start,
        &lm,
        |s| model.whitened_residual_and_jacobian(s, points),
        |s, d| Ok::<_, CalibrationError>(s.perturbed(d.as_slice())),
    )?
    .converged(FIT, None)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::arc_model::{ArcModel, axis_quantities};
    use approx::assert_relative_eq;
    use nalgebra::Matrix3;

    #[test]
    fn recovers_a_noiseless_gear_sweep_with_per_point_covariance() {
        let form = TransmissionFitForm::Gear {
            ratio: 32.0 / 19.0,
            order: 1,
        };
        let commands: Vec<f64> = (0..16).map(|j| -0.5 + 0.07 * j as f64).collect();
        let truth = ArcParams {
            centre: Point3::new(-3.1, 4.4, -0.5),
            frame: Rotation3::new(Vector3::new(1.2, 0.1, -0.4)),
            radius: 0.6,
            phase_rad: 1.0,
            coefficients: vec![0.041227, -0.000013],
        };
        let covs = (0..16)
            .map(|k| Matrix3::from_diagonal(&Vector3::new(1.0, 2.0, 0.5 + k as f64 * 0.1)) * 1e-8)
            .collect();
        let noise = MeasurementNoise::PerPoint(covs);
        let model = ArcModel::new(form, &commands, &noise).unwrap();
        let pts = model.predict(&truth).unwrap();
        let options = ArcFitOptions {
            form,
            noise,
            reference_point: truth.centre,
            max_iterations: 100,
        };
        let fit = fit_arc(&pts, &commands, &options).unwrap();
        assert_relative_eq!(
            fit.axis.direction.into_inner(),
            truth.normal().into_inner(),
            epsilon = 1e-9
        );
        assert_relative_eq!(fit.axis.origin_m, truth.centre, epsilon = 1e-9);
        for (a, b) in fit.params.coefficients.iter().zip(&truth.coefficients) {
            assert_relative_eq!(a, b, epsilon = 1e-9);
        }
        assert!(fit.residual_rms < 1e-9);
        let id = &fit.identifiability;
        assert!(id.condition_number > 1.0 && id.tilt_sigma_rad > 0.0);
        // Longer spans determine the tilt better.
        let sig: Vec<f64> = id.tilt_sigma_by_span.iter().map(|s| s.1).collect();
        assert!(sig.windows(2).all(|w| w[1] < w[0]));
    }

    #[test]
    fn zero_angle_noise_is_the_measurement_only_fit_bit_for_bit() {
        let form = TransmissionFitForm::Harmonic { order: 1 };
        let commands: Vec<f64> = (0..12).map(|j| -0.3 + 0.06 * j as f64).collect();
        let truth = crate::calibration::arc_model::tests::sample_params();
        let noise = MeasurementNoise::from_rms_3d(1e-4);
        let model = ArcModel::new(form, &commands, &noise).unwrap();
        // Deterministic "noise": a fixed pattern of 0.1 mm.
        let pts: Vec<Point3<f64>> = model
            .predict(&truth)
            .unwrap()
            .iter()
            .enumerate()
            .map(|(j, p)| p + Vector3::new((j as f64).sin(), (2.0 * j as f64).cos(), 0.5) * 1e-4)
            .collect();
        let options = ArcFitOptions {
            form,
            noise,
            reference_point: truth.centre,
            max_iterations: 100,
        };
        let old = fit_arc(&pts, &commands, &options).unwrap();
        assert_eq!(fit_arc_with_angle_noise(&pts, &commands, &options, 0.0).unwrap(), old);
        // With angle noise the reported uncertainty grows (the tangential direction is
        // noisier), and the estimate stays close.
        let with = fit_arc_with_angle_noise(&pts, &commands, &options, 2e-4).unwrap();
        for k in 0..old.covariance.nrows() {
            assert!(with.covariance[(k, k)] >= old.covariance[(k, k)] * (1.0 - 1e-9), "{k}");
        }
        assert!(with.coefficient_sigma[1] > 1.2 * old.coefficient_sigma[1]);
        assert!(fit_arc_with_angle_noise(&pts, &commands, &options, f64::NAN).is_err());
    }

    /// A sweep of `truth` whose points each turn about the axis by their own jitter
    /// (`angle_sigma_rad`) and carry isotropic measurement noise (`sigma_per_axis`).
    fn jittered_sweep(
        model: &ArcModel,
        truth: &ArcParams,
        (angle_sigma_rad, sigma_per_axis): (f64, f64),
        seed: u64,
    ) -> Vec<Point3<f64>> {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand::rngs::ChaCha12Rng::seed_from_u64(seed);
        let mut normal = || -> f64 { StandardNormal.sample(&mut rng) };
        let axis = truth.normal();
        let pts = model.predict(truth).unwrap();
        pts.iter()
            .map(|p| {
                let turn = Rotation3::from_axis_angle(&axis, angle_sigma_rad * normal());
                let noise = Vector3::new(normal(), normal(), normal()) * sigma_per_axis;
                truth.centre + turn * (p - truth.centre) + noise
            })
            .collect()
    }

    #[test]
    fn weights_at_the_start_match_weights_at_the_measurement_only_optimum() {
        // Two-step feasible GLS with either consistent first stage: the tangents differ by
        // about sigma / r, so the estimates differ by that fraction of their own sigma (times
        // a few for the sqrt(p) parameters); tangents that were wrong (e.g. radial) would move
        // them by a large part of a sigma, as the angle noise dominates here.
        let cases = [
            (TransmissionFitForm::Harmonic { order: 1 }, 0.7, 16),
            (
                TransmissionFitForm::Gear {
                    ratio: 32.0 / 19.0,
                    order: 1,
                },
                0.25,
                11,
            ),
        ];
        for (k, (form, radius, n)) in cases.into_iter().enumerate() {
            let commands: Vec<f64> = (0..n).map(|j| -0.8 + 1.5 * j as f64 / n as f64).collect();
            let truth = ArcParams {
                radius,
                ..crate::calibration::arc_model::tests::sample_params()
            };
            let sigma_per_axis = 1e-4;
            let angle_sigma_rad = 3.0 * sigma_per_axis / radius;
            let noise = MeasurementNoise::Isotropic { sigma_per_axis };
            let model = ArcModel::new(form, &commands, &noise).unwrap();
            let options = ArcFitOptions {
                form,
                noise: noise.clone(),
                reference_point: truth.centre,
                max_iterations: 100,
            };
            for seed in 0..4 {
                let pts = jittered_sweep(&model, &truth, (angle_sigma_rad, sigma_per_axis), 10 * k as u64 + seed);
                let fit = fit_arc_with_angle_noise(&pts, &commands, &options, angle_sigma_rad).unwrap();
                // The former first stage: the measurement-only optimum.
                let first = fit_arc(&pts, &commands, &options).unwrap();
                let tangents = model.angle_derivatives(&first.params).unwrap();
                let weighted = ArcFitOptions {
                    noise: noise.with_angle_noise(&tangents, angle_sigma_rad).unwrap(),
                    ..options.clone()
                };
                let reference = fit_arc_from(&pts, &commands, &weighted, Some(first.params), Studies::Run).unwrap();
                let (u, v) = (reference.params.u().into_inner(), reference.params.v().into_inner());
                let g = axis_quantities_gradient(&reference.params, &truth.centre);
                let sigmas = (&g * &reference.covariance * g.transpose()).diagonal().map(f64::sqrt);
                let a = axis_quantities(&fit.params, &truth.centre, &u, &v);
                let b = axis_quantities(&reference.params, &truth.centre, &u, &v);
                let tolerance = 3.0 * (model.n_params() as f64).sqrt() * 3f64.sqrt() * sigma_per_axis / radius;
                for (q, ((a, b), s)) in a.iter().zip(&b).zip(sigmas.iter()).enumerate() {
                    assert!(
                        (a - b).abs() <= tolerance * s,
                        "case {k} seed {seed} quantity {q}: {a} vs {b}, sigma {s}, tolerance {tolerance} sigma"
                    );
                }
            }
        }
    }

    #[test]
    fn mismatched_inputs_are_errors() {
        let options = ArcFitOptions {
            form: TransmissionFitForm::Harmonic { order: 1 },
            noise: MeasurementNoise::from_rms_3d(1e-4),
            reference_point: Point3::origin(),
            max_iterations: 10,
        };
        let p = [Point3::origin(); 3];
        assert!(matches!(
            fit_arc(&p, &[0.0; 2], &options),
            Err(CalibrationError::LengthMismatch { .. })
        ));
        assert!(matches!(
            fit_arc(&p, &[0.0, 0.1, 0.2], &options),
            Err(CalibrationError::TooFewPoints { .. })
        ));
    }
}
