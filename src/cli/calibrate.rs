//! `axiscal calibrate DATA.csv --robot R --out DIR`: the independent-axis procedure on a
//! measurement CSV, writing `calibration.json` (loadable again), `report.md`, `report.json`
//! and `calibrated.urdf`.

use super::OneOf;
use super::checks;
use super::options::NOISE_MM;
use super::output::Outputs;
use anyhow::Result;
use axiscal::calibration::procedure::{AxisEstimator, CalibrationOptions, calibrate, findings, markdown, urdf};
use axiscal::json_file::{self, Schema};
use axiscal::measurement::read_measurements;
use axiscal::robot::RobotDescription;
use std::path::PathBuf;

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
    /// uncertainties).
    #[arg(long, default_value_t = 0.19, value_parser = NOISE_MM)]
    noise_mm: f64,
    /// The robot's repeatability \[rad\]: standard deviation of a joint value's error per
    /// re-positioning, one value for every joint or one per joint (comma-separated); 0 = model
    /// measurement noise only. Default: the robot description's `repeatability_sigma`.
    #[arg(long, value_delimiter = ',')]
    repeatability_rad: Option<Vec<f64>>,
    /// Replace existing output files.
    #[arg(long)]
    force: bool,
    /// Skip the unit sanity checks (coordinates in m instead of mm, commands in rad instead of
    /// deg, description lengths in mm instead of m) when the units are right after all.
    #[arg(long)]
    skip_unit_check: bool,
    /// Calibrate even when DATA records another robot description than `--robot`.
    #[arg(long)]
    allow_other_robot: bool,
}

/// Runs `axiscal calibrate`.
pub fn run(args: Args) -> Result<()> {
    let names = ["calibration.json", "report.md", "report.json", "calibrated.urdf"];
    let outputs = Outputs::new(args.force)
        .input("DATA", &args.data)
        .input("--robot", &args.robot);
    outputs.check_in(&args.out, &names)?;
    let desc = RobotDescription::from_file(&args.robot)?;
    checks::description_units(&desc, &args.robot, args.skip_unit_check)?;
    let recorded = checks::data_identity(&args.data);
    checks::same_robot(
        recorded.as_ref(),
        &args.data,
        &desc,
        &args.robot,
        args.allow_other_robot,
    )?;
    let set = read_measurements(&args.data, Some(desc.dof()))?;
    checks::data_units(&set, &desc, &args.data, args.skip_unit_check)?;
    let options = CalibrationOptions {
        estimator: args.estimator,
        noise_rms_3d_mm: args.noise_mm,
        repeatability_sigma_rad: args.repeatability_rad,
        ..CalibrationOptions::default()
    };
    options
        .joint_repeatability_rad(&desc)
        .map_err(|e| anyhow::anyhow!("--repeatability-rad: {e}"))?;
    // The procedure's message already contains its cause: one line, not the cause twice.
    let cal =
        calibrate(&set, &desc, &options).map_err(|e| anyhow::anyhow!("calibrating {}: {e}", args.data.display()))?;
    let source = args.data.display().to_string();
    outputs.write_in(&args.out, names[0], json_file::to_string(Schema::CALIBRATION, &cal)?)?;
    outputs.write_in(&args.out, names[1], markdown(&cal, &desc, &source))?;
    outputs.write_in(
        &args.out,
        names[2],
        json_file::list_to_string(Schema::REPORT, "findings", &findings(&cal, &desc))?,
    )?;
    outputs.write_in(&args.out, names[3], urdf(&cal.robot.phi_model(), &desc, "calibrated"))?;
    print_axes(&cal, &desc, &source);
    println!("wrote {}/{{{}}}", args.out.display(), names.join(","));
    Ok(())
}

/// The calibrated axes, one line each.
fn print_axes(cal: &axiscal::calibration::procedure::Calibration, desc: &RobotDescription, source: &str) {
    println!("calibrated {} from {} ({} axes)", desc.name, source, cal.axes.len());
    println!("  joint  points  span(deg)  residual RMS (mm)  direction 1-sigma (mrad)");
    for a in &cal.axes {
        println!(
            "  {:>5}  {:>6}  {:>9.1}  {:>17.4}  {:>24.4}",
            a.joint,
            a.points,
            a.span_deg,
            a.residual_rms_mm,
            a.direction_sigma_rad[0] * 1e3
        );
    }
}
