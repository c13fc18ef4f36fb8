//! `axiscal calibrate DATA.csv --robot R --out DIR`: the independent-axis procedure on a
//! measurement CSV, writing `calibration.json` (loadable again), `report.md`, `report.json`
//! and `calibrated.urdf`.

use super::OneOf;
use anyhow::{Context, Result, bail};
use axiscal::calibration::procedure::{
    AxisEstimator, Calibration, CalibrationOptions, UrdfOptions, UrdfRoot, calibrate, findings, joint_map,
    joints_without_speed_limits, markdown, raw_reading_deviation, ros_name, urdf,
};
use axiscal::json_file::{self, Schema};
use axiscal::measurement::{MeasurementSet, read_measurements};
use axiscal::plan::{TOOL_EXPERIMENT, ValidationPlan};
use axiscal::robot::RobotDescription;
use std::path::{Path, PathBuf};

/// The estimators by their command-line names.
const ESTIMATORS: &[(&str, AxisEstimator)] = &[("ml", AxisEstimator::Ml), ("paper", AxisEstimator::Paper)];

/// The URDF roots by their command-line names.
const URDF_ROOTS: &[(&str, UrdfRoot)] = &[("base_link", UrdfRoot::BaseLink), ("instrument", UrdfRoot::Instrument)];

/// The files `calibrate` writes into its output folder.
const OUTPUTS: [&str; 6] = [
    "calibration.json",
    "report.md",
    "report.json",
    "calibrated.urdf",
    "joint_map.csv",
    "zero_offsets.csv",
];

/// Arguments of `axiscal calibrate`.
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
    #[arg(long, default_value_t = 0.19)]
    noise_mm: f64,
    /// The robot's repeatability \[rad\]: standard deviation of a joint value's error per
    /// re-positioning, one value for every joint or one per joint (comma-separated); 0 = model
    /// measurement noise only. Default: the robot description's `repeatability_sigma`.
    #[arg(long, value_delimiter = ',')]
    repeatability_rad: Option<Vec<f64>>,
    /// Replace existing output files.
    #[arg(long)]
    force: bool,
    /// The URDF's root link: `base_link` (the robot's base frame, ROS-Industrial) or
    /// `instrument` (the measuring instrument's frame, the base placed in it).
    #[arg(long, value_parser = OneOf(URDF_ROOTS), default_value = "base_link")]
    urdf_root: UrdfRoot,
    /// The URDF's robot name (default: the description's name as a ROS name).
    #[arg(long)]
    urdf_name: Option<String>,
    /// Step of the tabulated joint map (`joint_map.csv`) \[deg or mm\].
    #[arg(long, default_value_t = 0.1)]
    joint_map_step: f64,
    /// Also write a rerun recording: the measured targets per experiment with their fitted
    /// arcs, axes and residual vectors, the nominal and the calibrated robot side by side at
    /// every pose, the validation errors of both. View it with `axiscal view FILE.rrd`. Needs
    /// a build with `--features viz`.
    #[arg(long, value_name = "FILE.rrd")]
    record: Option<PathBuf>,
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

/// What `calibrate` writes, rendered before anything is written.
struct OutputTexts {
    /// The contents of [`OUTPUTS`], in order.
    files: Vec<String>,
    /// The URDF-fed-raw-readings line printed after the axes table.
    deviation_line: String,
    /// Joints whose URDF speed and effort limits are unknown.
    missing_speed_limits: Vec<usize>,
}

/// Renders every output of `calibrate` (see [`OUTPUTS`]).
fn output_texts(
    args: &Args,
    desc: &RobotDescription,
    set: &MeasurementSet,
    cal: &Calibration,
    source: &str,
) -> Result<OutputTexts> {
    // The deviation over the data's validation poses, else over seeded poses around the
    // reference.
    let mut poses: Vec<Vec<f64>> = set
        .experiments()
        .iter()
        .filter(|e| e.moved_joint == 0 && e.name != TOOL_EXPERIMENT)
        .flat_map(|e| e.by_step().into_values().map(|rows| rows[0].cmd.clone()))
        .collect();
    if poses.is_empty() {
        let plan = ValidationPlan {
            poses: 500,
            ..ValidationPlan::workspace_default(desc.dof())
        };
        poses = plan.commands(desc, &cal.reference_cmd);
    }
    let deviation = raw_reading_deviation(cal, desc, &poses);
    let mut report_findings = findings(cal, desc);
    report_findings.extend(deviation.findings());
    let urdf_options = UrdfOptions {
        robot_name: args.urdf_name.clone().unwrap_or_else(|| ros_name(&desc.name)),
        root: args.urdf_root,
    };
    let map = joint_map(cal, desc, args.joint_map_step);
    let files = vec![
        json_file::to_string(Schema::CALIBRATION, cal)?,
        markdown(cal, desc, source) + &deviation.markdown(),
        json_file::list_to_string(Schema::REPORT, "findings", &report_findings)?,
        urdf(&cal.robot.phi_model(), desc, &urdf_options),
        super::joints::joint_map_csv(&map, &desc.name),
        super::joints::zero_offsets_csv(cal, desc, &poses)?,
    ];
    Ok(OutputTexts {
        files,
        deviation_line: format!(
            "  URDF fed raw controller readings: tool off by up to {:.3} mm, {:.3} mrad over {} poses (use joint_map.csv / `axiscal joints`)",
            deviation.max_position_mm, deviation.max_orientation_mrad, deviation.poses
        ),
        missing_speed_limits: joints_without_speed_limits(desc),
    })
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
    check_noise_mm(args.noise_mm)?;
    super::record::ensure_recordable(args.record.as_deref(), args.force)?;
    let desc = RobotDescription::from_file(&args.robot)?;
    let set = read_measurements(&args.data, Some(desc.dof()))?;
    let options = CalibrationOptions {
        estimator: args.estimator,
        noise_rms_3d_mm: args.noise_mm,
        repeatability_sigma_rad: args.repeatability_rad.clone(),
        ..CalibrationOptions::default()
    };
    options
        .joint_repeatability_rad(&desc)
        .map_err(|e| anyhow::anyhow!("--repeatability-rad: {e}"))?;
    // The procedure's message already contains its cause: one line, not the cause twice.
    let cal =
        calibrate(&set, &desc, &options).map_err(|e| anyhow::anyhow!("calibrating {}: {e}", args.data.display()))?;
    let source = args.data.display().to_string();
    let texts = output_texts(&args, &desc, &set, &cal, &source)?;
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    refuse_existing(&args.out, &OUTPUTS, args.force)?;
    for (name, text) in OUTPUTS.iter().zip(&texts.files) {
        write_output(&args.out, name, text, args.force)?;
    }
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
    println!("{}", texts.deviation_line);
    if !texts.missing_speed_limits.is_empty() {
        eprintln!(
            "warning: the description gives no max_velocity/max_effort for joint(s) {:?}: their URDF <limit> says velocity=0 effort=0",
            texts.missing_speed_limits
        );
    }
    println!("wrote {}/{{{}}}", args.out.display(), OUTPUTS.join(","));
    #[cfg(feature = "viz")]
    if let Some(path) = &args.record {
        let campaign = super::record::calibrated::CalibratedCampaign {
            desc: &desc,
            set: &set,
            calibration: &cal,
            verdict: None,
        };
        super::record::save(path, |p| super::record::calibrated::write_calibrated(p, &campaign))?;
    }
    Ok(())
}
