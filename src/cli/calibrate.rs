//! `axiscal calibrate DATA.csv --robot R --out DIR`: the independent-axis procedure on a
//! measurement CSV, writing `calibration.json` (loadable again), `report.md`, `report.json`
//! and `calibrated.urdf`.

use super::OneOf;
use anyhow::{Context, Result, bail};
use axiscal::calibration::procedure::{
    AxisEstimator, CalibrationOptions, DEFAULT_HELD_TOLERANCE, calibrate, findings, markdown, residuals_csv, urdf,
};
use axiscal::json_file::{self, Schema};
use axiscal::measurement::read_measurements;
use axiscal::robot::RobotDescription;
use std::path::{Path, PathBuf};

/// Arguments of `axiscal calibrate`.
/// The estimators by their command-line names.
const ESTIMATORS: &[(&str, AxisEstimator)] = &[("ml", AxisEstimator::Ml), ("paper", AxisEstimator::Paper)];

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Measurement CSV (`docs/formats.md#measurement-csv`).
    data: PathBuf,
    /// Nominal robot description (TOML).
    #[arg(long, default_value = "scenarios/robots/asea-irb6l.toml")]
    robot: PathBuf,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Rotary-axis estimator.
    #[arg(long, value_parser = OneOf(ESTIMATORS), default_value = "ml")]
    estimator: AxisEstimator,
    /// Measurement noise of a point, 3-D RMS \[mm\] (weights the fits and scales the reported
    /// uncertainties). Default: estimated from the fits' residuals (reported with its
    /// interval); a given value the residuals contradict is flagged in the report.
    #[arg(long)]
    noise_mm: Option<f64>,
    /// How far a held joint may wander within one axis experiment \[deg or mm\]: recorded
    /// encoder values within it are modelled, beyond it the experiment moves two joints.
    #[arg(long, default_value_t = DEFAULT_HELD_TOLERANCE)]
    held_tolerance: f64,
    /// The robot's repeatability \[rad\]: standard deviation of a joint value's error per
    /// re-positioning, one value for every joint or one per joint (comma-separated); 0 = model
    /// measurement noise only. Default: the robot description's `repeatability_sigma`.
    #[arg(long, value_delimiter = ',')]
    repeatability_rad: Option<Vec<f64>>,
    /// Replace existing output files.
    #[arg(long)]
    force: bool,
}

/// Writes `text` to `dir/name`, refusing to replace a file unless `force`.
pub fn write_output(dir: &Path, name: &str, text: &str, force: bool) -> Result<()> {
    let path = dir.join(name);
    if path.exists() && !force {
        bail!("{} exists; pass --force to replace it", path.display());
    }
    std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))
}

/// Refuses, before any work is written, to replace any of `names` in `dir` unless `force`.
pub fn refuse_existing(dir: &Path, names: &[&str], force: bool) -> Result<()> {
    if !force {
        for n in names {
            let p = dir.join(n);
            if p.exists() {
                bail!("{} exists; pass --force to replace it", p.display());
            }
        }
    }
    Ok(())
}

/// Checks a `--noise-mm` argument: a positive number of millimetres.
pub fn check_noise_mm(noise_mm: f64) -> Result<()> {
    if !(noise_mm.is_finite() && noise_mm > 0.0) {
        bail!("--noise-mm must be a positive number of millimetres, got {noise_mm}");
    }
    Ok(())
}

/// Runs `axiscal calibrate`.
pub fn run(args: Args) -> Result<()> {
    if let Some(n) = args.noise_mm {
        check_noise_mm(n)?;
    }
    if !(args.held_tolerance.is_finite() && args.held_tolerance >= 0.0) {
        bail!(
            "--held-tolerance must be a number >= 0 (deg or mm), got {}",
            args.held_tolerance
        );
    }
    let desc = RobotDescription::from_file(&args.robot)?;
    let set = read_measurements(&args.data, Some(desc.dof())).with_context(|| {
        format!(
            "the robot description {} has {} joints: the file needs cmd_1..cmd_{} (every joint's command, also of joints not swept)",
            args.robot.display(),
            desc.dof(),
            desc.dof()
        )
    })?;
    let options = CalibrationOptions {
        estimator: args.estimator,
        noise_rms_3d_mm: args.noise_mm.unwrap_or(CalibrationOptions::default().noise_rms_3d_mm),
        estimate_noise: args.noise_mm.is_none(),
        held_tolerance: args.held_tolerance,
        repeatability_sigma_rad: args.repeatability_rad,
        ..CalibrationOptions::default()
    };
    options
        .joint_repeatability_rad(&desc)
        .map_err(|e| anyhow::anyhow!("--repeatability-rad: {e}"))?;
    // The procedure's message already contains its cause: one line, not the cause twice.
    let cal =
        calibrate(&set, &desc, &options).map_err(|e| anyhow::anyhow!("calibrating {}: {e}", args.data.display()))?;
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let source = args.data.display().to_string();
    let names = [
        "calibration.json",
        "report.md",
        "report.json",
        "calibrated.urdf",
        "residuals.csv",
    ];
    refuse_existing(&args.out, &names, args.force)?;
    write_output(
        &args.out,
        names[0],
        &json_file::to_string(Schema::CALIBRATION, &cal)?,
        args.force,
    )?;
    write_output(&args.out, names[1], &markdown(&cal, &desc, &source), args.force)?;
    write_output(
        &args.out,
        names[2],
        &json_file::list_to_string(Schema::REPORT, "findings", &findings(&cal, &desc))?,
        args.force,
    )?;
    write_output(
        &args.out,
        names[3],
        &urdf(&cal.robot.phi_model(), &desc, "calibrated"),
        args.force,
    )?;
    write_output(&args.out, names[4], &residuals_csv(&cal), args.force)?;
    println!("calibrated {} from {} ({} axes)", desc.name, source, cal.axes.len());
    print_scope(&cal);
    println!("  joint  points  span (deg|mm)  residual RMS (mm)  direction 1-sigma (mrad)");
    for a in &cal.axes {
        let unit = if a.kind == "prismatic" { "mm" } else { "deg" };
        println!(
            "  {:>5}  {:>6}  {:>9.1} {:<3}  {:>17.4}  {:>24.4}",
            a.joint,
            a.points,
            a.span_deg,
            unit,
            a.residual_rms_mm,
            a.direction_sigma_rad[0] * 1e3
        );
    }
    println!("wrote {}/{{{}}}", args.out.display(), names.join(","));
    Ok(())
}

/// The noise (estimated, used, contradicted), joints not calibrated, the base-frame rule.
fn print_scope(cal: &axiscal::calibration::procedure::Calibration) {
    if let Some(n) = &cal.noise {
        if let Some(e) = &n.estimate {
            println!(
                "  noise from the residuals: {:.4} mm 3-D RMS ({:.0} % interval {:.4}-{:.4} mm, {} dof); fits weighted with {:.4} mm ({})",
                e.rms_3d_mm,
                e.confidence * 100.0,
                e.interval_mm[0],
                e.interval_mm[1],
                e.dof,
                n.used_rms_3d_mm,
                n.source
            );
        }
        if n.given_contradicted {
            println!(
                "  WARNING: the residuals contradict --noise-mm {:.4} (chi-square p = {:.2e}); see report.md",
                n.used_rms_3d_mm,
                n.given_p_value.unwrap_or(f64::NAN)
            );
        }
    }
    if !cal.not_calibrated.is_empty() {
        println!(
            "  not calibrated (no axis experiment, kept nominal): joints {:?}",
            cal.not_calibrated
        );
    }
    if let Some(b) = &cal.base_rule {
        println!("  base frame: {}", b.text);
    }
}
