//! What both recordings draw: the arcs fitted to an axis experiment's targets, with their
//! residual vectors.

use anyhow::Result;
use axiscal::calibration::{ArcFitOptions, ArcModel, MeasurementNoise, fit_arc};
use axiscal::measurement::Measurement;
use axiscal::robot::TransmissionFitForm;
use axiscal::viz::Recorder;
use nalgebra::{Matrix3, Point3};
use std::collections::{BTreeMap, BTreeSet};

/// Residual and error vectors are also drawn this many times longer than they are.
pub const ERROR_EXAGGERATION: f64 = 100.0;

/// Fits an arc (harmonic transmission of order 1, the commands in degrees) to each target of
/// the axis experiment `name` of joint `joint` and logs it with its axis, its residual vectors
/// (measured minus fitted, [`ERROR_EXAGGERATION`] times longer, at
/// `world/residuals/{name}/target{t}`) and its residual RMS. `covariance_m2` is a point's
/// measurement covariance (m^2). A target whose fit fails is reported on stderr and skipped:
/// the recording is a view, not a calibration.
pub fn log_arc_fits(
    rec: &Recorder,
    covariance_m2: &dyn Fn(&Point3<f64>) -> Result<Matrix3<f64>>,
    name: &str,
    joint: usize,
    rows: &BTreeMap<(usize, usize), &Measurement>,
) {
    let targets: BTreeSet<usize> = rows.keys().map(|(_, t)| *t).collect();
    for target in targets {
        let (points, commands): (Vec<Point3<f64>>, Vec<f64>) = rows
            .iter()
            .filter(|((_, t), _)| *t == target)
            .map(|(_, r)| (r.position_m(), r.cmd[joint - 1].to_radians()))
            .unzip();
        let label = format!("{name}/target{target}");
        if let Err(e) = log_arc_fit(rec, covariance_m2, &label, &points, &commands) {
            eprintln!("warning: no arc drawn for {label}: {e:#}");
        }
    }
}

/// One target's arc, axis, residual vectors and residual RMS (see [`log_arc_fits`]).
fn log_arc_fit(
    rec: &Recorder,
    covariance_m2: &dyn Fn(&Point3<f64>) -> Result<Matrix3<f64>>,
    label: &str,
    points: &[Point3<f64>],
    commands_rad: &[f64],
) -> Result<()> {
    let covariances: Vec<Matrix3<f64>> = points.iter().map(covariance_m2).collect::<Result<_>>()?;
    let noise = MeasurementNoise::PerPoint(covariances);
    let form = TransmissionFitForm::Harmonic { order: 1 };
    let options = ArcFitOptions {
        form,
        noise: noise.clone(),
        reference_point: points.first().copied().unwrap_or_else(Point3::origin),
        max_iterations: 100,
    };
    let fit = fit_arc(points, commands_rad, &options)?;
    rec.log_arc_fit(label, &fit, commands_rad, 1.0)?;
    let fitted = ArcModel::new(form, commands_rad, &noise)?.predict(&fit.params)?;
    let full_scale_m = points
        .iter()
        .zip(&fitted)
        .map(|(m, f)| (m - f).norm())
        .fold(0.0, f64::max);
    rec.log_vectors(
        &format!("world/residuals/{label}"),
        &fitted,
        points,
        full_scale_m,
        ERROR_EXAGGERATION,
    )?;
    rec.log_scalar(&format!("fits/{label}/residual_rms_mm"), fit.residual_rms * 1e3);
    Ok(())
}
