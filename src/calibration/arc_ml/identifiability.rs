//! What an arc fit ([`super::fit_arc`]) tells about its own identifiability: the weakest
//! parameter combinations, the strong correlations, the axis tilt's sigma and what larger spans
//! would give (the Cramer-Rao bound of [`crb::UniformArc`]), in plain-language notes.

use crate::calibration::arc_model::{ArcModel, ArcParams, MeasurementNoise, N_GEOMETRY};
use crate::calibration::{CalibrationError, crb};
use crate::numerics::lsq;
use nalgebra::DMatrix;

/// A poorly determined combination of parameters: an eigenvector of the correlation matrix
/// with a large eigenvalue.
#[derive(Clone, Debug, PartialEq)]
pub struct WeakDirection {
    /// Eigenvalue of the parameter correlation matrix (1 = uncorrelated; large = weak).
    pub correlation_eigenvalue: f64,
    /// Parameters taking part (components of magnitude >= 0.3), by name.
    pub components: Vec<(String, f64)>,
}

/// Which parameters the sweep determines poorly, and what span would help.
#[derive(Clone, Debug, PartialEq)]
pub struct Identifiability {
    /// 2-norm condition number of the whitened Jacobian with unit-scaled columns.
    pub condition_number: f64,
    /// The two weakest parameter combinations.
    pub weak_directions: Vec<WeakDirection>,
    /// Parameter pairs with correlation `|rho| > 0.95`.
    pub strong_correlations: Vec<(String, String, f64)>,
    /// Largest 1-sigma of the axis tilt \[rad\].
    pub tilt_sigma_rad: f64,
    /// `(span \[rad\], tilt 1-sigma \[rad\])` predicted by the Cramer-Rao bound for the same
    /// number of points evenly spread over larger spans from the same start.
    pub tilt_sigma_by_span: Vec<(f64, f64)>,
    /// Plain-language findings.
    pub notes: Vec<String>,
}

impl Identifiability {
    /// The value of a fit that skipped the study ([`Studies::Skip`](super::Studies::Skip)): no finding, and NaN for
    /// the numbers (not computed, never a made-up zero).
    pub fn not_studied() -> Self {
        Identifiability {
            condition_number: f64::NAN,
            weak_directions: vec![],
            strong_correlations: vec![],
            tilt_sigma_rad: f64::NAN,
            tilt_sigma_by_span: vec![],
            notes: vec![],
        }
    }
}

/// How well the fit determines its parameters: the weakest combinations, the strong
/// correlations, the axis tilt's sigma (and what larger spans would give), and notes.
pub(super) fn identifiability(
    model: &ArcModel,
    params: &ArcParams,
    jw: &DMatrix<f64>,
    covariance: &DMatrix<f64>,
    noise: &MeasurementNoise,
) -> Result<Identifiability, CalibrationError> {
    let names = model.param_names();
    let m = covariance.nrows();
    let sd: Vec<f64> = (0..m).map(|k| covariance[(k, k)].sqrt()).collect();
    let corr = DMatrix::from_fn(m, m, |r, c| covariance[(r, c)] / (sd[r] * sd[c]));
    let weak_directions = weak_directions(&corr, &names);
    let strong_correlations = strong_correlations(&corr, &names);
    let tilt = covariance.fixed_view::<2, 2>(3, 3).into_owned();
    let tilt_sigma_rad = tilt.symmetric_eigenvalues().max().sqrt();
    let sigma = noise_sigma_per_axis(noise);
    let tilt_sigma_by_span = tilt_sigma_by_span(model, params, sigma);
    let notes = identifiability_notes(model, params, &names, &sd, tilt_sigma_rad, sigma);
    Ok(Identifiability {
        condition_number: lsq::scaled_condition_number(jw),
        weak_directions,
        strong_correlations,
        tilt_sigma_rad,
        tilt_sigma_by_span,
        notes,
    })
}

/// The two weakest parameter combinations: the eigenvectors of the correlation matrix `corr`
/// with the largest eigenvalues, with their components of magnitude >= 0.3.
fn weak_directions(corr: &DMatrix<f64>, names: &[String]) -> Vec<WeakDirection> {
    let m = corr.nrows();
    let eig = corr.clone().symmetric_eigen();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    order
        .iter()
        .take(2)
        .map(|&k| WeakDirection {
            correlation_eigenvalue: eig.eigenvalues[k],
            components: (0..m)
                .filter(|&r| eig.eigenvectors[(r, k)].abs() >= 0.3)
                .map(|r| (names[r].clone(), eig.eigenvectors[(r, k)]))
                .collect(),
        })
        .collect()
}

/// The parameter pairs with correlation `|rho| > 0.95` in `corr`.
fn strong_correlations(corr: &DMatrix<f64>, names: &[String]) -> Vec<(String, String, f64)> {
    let m = corr.nrows();
    let mut strong_correlations = Vec::new();
    for r in 0..m {
        for c in r + 1..m {
            if corr[(r, c)].abs() > 0.95 {
                strong_correlations.push((names[r].clone(), names[c].clone(), corr[(r, c)]));
            }
        }
    }
    strong_correlations
}

/// The measurement noise's standard deviation per axis (m): the isotropic one, or the RMS over
/// the points' covariances.
fn noise_sigma_per_axis(noise: &MeasurementNoise) -> f64 {
    match noise {
        MeasurementNoise::Isotropic { sigma_per_axis } => *sigma_per_axis,
        MeasurementNoise::PerPoint(c) => (c.iter().map(|m| m.trace()).sum::<f64>() / (3.0 * c.len() as f64)).sqrt(),
    }
}

/// `(span, tilt 1-sigma)` (rad) the Cramer-Rao bound predicts for the same number of points
/// evenly spread from the same start over this sweep's span and larger ones (twice it, a
/// quarter, half and three quarters of a turn), with noise `sigma` (m) per axis.
fn tilt_sigma_by_span(model: &ArcModel, params: &ArcParams, sigma: f64) -> Vec<(f64, f64)> {
    let span = model
        .commands_rad
        .iter()
        .map(|c| (c - model.commands_rad[0]).abs())
        .fold(0.0, f64::max);
    let mut tilt_sigma_by_span = Vec::new();
    let mut spans = vec![
        span,
        2.0 * span,
        0.5 * std::f64::consts::PI,
        std::f64::consts::PI,
        1.5 * std::f64::consts::PI,
    ];
    spans.retain(|&s| s >= span);
    spans.sort_by(f64::total_cmp);
    spans.dedup();
    for s in spans {
        let sweep = crb::UniformArc {
            params,
            form: model.form,
            start_command_rad: model.commands_rad[0],
            span_rad: s,
            n: model.commands_rad.len(),
            sigma_per_axis: sigma,
        };
        if let Ok(b) = sweep.direction_sigma_rad() {
            tilt_sigma_by_span.push((s, b));
        }
    }
    tilt_sigma_by_span
}

/// Plain-language findings: the phase convention, the transmission coefficients determined only
/// through the sweep's curvature, and an axis tilt that moves the arc by more than 3 noise
/// sigmas (`sigma` per axis, m).
fn identifiability_notes(
    model: &ArcModel,
    params: &ArcParams,
    names: &[String],
    sd: &[f64],
    tilt_sigma_rad: f64,
    sigma: f64,
) -> Vec<String> {
    let mut notes = vec![
        "phase is fitted at step 0: a constant command offset is absorbed by the phase, not by the transmission"
            .to_string(),
    ];
    let k = model.form.n_coefficients() / 2;
    for i in 0..k {
        let idx = N_GEOMETRY + k + i;
        let ratio = params.coefficients[k + i].abs() / sd[idx];
        if ratio < 3.0 {
            notes.push(format!(
                "{} is determined only through the curvature of the sweep: {:.2e} +- {:.2e} rad",
                names[idx],
                params.coefficients[k + i],
                sd[idx]
            ));
        }
    }
    if tilt_sigma_rad * params.radius > 3.0 * sigma {
        notes.push(format!(
            "axis tilt 1-sigma {:.2e} rad moves the arc by {:.2e} (> 3 noise sigma); a longer span helps",
            tilt_sigma_rad,
            tilt_sigma_rad * params.radius
        ));
    }
    notes
}
