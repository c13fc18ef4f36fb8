//! `axiscal calibrate DATA.csv --robot R --out DIR`: the independent-axis procedure on a
//! measurement CSV, writing `calibration.json` (loadable again), `report.md`, `report.json`
//! and `calibrated.urdf`.

mod accuracy;
mod axes;
mod findings;
mod free_poses;
mod own_poses;
mod refine;
mod summary;

use super::OneOf;
use super::checks;
use super::options::{InRange, NOISE_MM};
use super::output::Outputs;
use super::printer::Printer;
use anyhow::Result;
use axiscal::calibration::outputs::{self, OUTPUT_FILES, OutputOptions};
use axiscal::calibration::procedure::{
    AxisEstimator, Calibration, DEFAULT_HELD_TOLERANCE, Implausible, UrdfOptions, UrdfRoot, implausible, ros_name,
};
use axiscal::calibration::record::CalibrationRecord;
use axiscal::calibration::tool_map::{TOOL_MAP_FILES, write_tool_map};
use axiscal::measurement::MeasurementSet;
use axiscal::plan::{TOOL_EXPERIMENT, ValidationPlan};
use axiscal::robot::RobotDescription;
use std::path::PathBuf;

use accuracy::predict_free_pose_accuracy;
use axes::{AxesFound, calibrate_axes};
use findings::{implausible_warnings, print_moved_sweeps, print_scale_doubts};
use own_poses::own_poses_miss;
use refine::check_refine_poses;
use summary::{deviation_line, print_axes, print_tool_accuracy};

pub(super) use axes::print_coordinate_scale;
pub(super) use free_poses::p_value_words;
pub(super) use own_poses::misses_own_validation_poses;

/// The warnings on a calibration's results, printed as they are found and kept for
/// `calibration.json`'s `warnings` ([`axiscal::calibration::record::Reports::warnings`]).
#[derive(Debug, Default)]
pub(super) struct Said(Vec<String>);

impl Said {
    /// Prints `text` as a warning and keeps it.
    pub(super) fn warn(&mut self, text: String) {
        eprintln!("warning: {text}");
        self.0.push(text);
    }

    /// The warnings kept, in the order they were said.
    pub(super) fn into_warnings(self) -> Vec<String> {
        self.0
    }
}

/// The estimators by their command-line names.
const ESTIMATORS: &[(&str, AxisEstimator)] = &[("ml", AxisEstimator::Ml), ("paper", AxisEstimator::Paper)];

/// The URDF roots by their command-line names.
const URDF_ROOTS: &[(&str, UrdfRoot)] = &[("base_link", UrdfRoot::BaseLink), ("instrument", UrdfRoot::Instrument)];

/// The most poses the URDF deviation and the zero-offset fit use.
const EXPORT_POSES: usize = 500;

/// Arguments of `axiscal calibrate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Measurement CSV (`docs/formats.md#measurement-csv`).
    data: PathBuf,
    /// Nominal robot description (TOML).
    #[arg(long, default_value = "asea-irb6l", value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Rotary-axis estimator.
    #[arg(long, value_parser = OneOf(ESTIMATORS), default_value = "ml")]
    estimator: AxisEstimator,
    /// Measurement noise of a point, 3-D RMS (mm) (weights the fits and scales the reported
    /// uncertainties). Default: estimated from the fits' residuals (reported with its
    /// interval); a given value the residuals contradict is flagged in the report.
    #[arg(long, value_parser = NOISE_MM)]
    noise_mm: Option<f64>,
    /// How far a held joint may wander within one axis experiment (deg or mm): recorded
    /// encoder values within it are modelled, beyond it the experiment moves two joints.
    #[arg(long, default_value_t = DEFAULT_HELD_TOLERANCE, value_parser = InRange::closed(0.0, 360.0, "deg or mm"))]
    held_tolerance: f64,
    /// The robot's repeatability (rad): standard deviation of a joint value's error per
    /// re-positioning, one value for every joint or one per joint (comma-separated); 0 = model
    /// measurement noise only. Default: the robot description's `repeatability_sigma`.
    #[arg(long, value_delimiter = ',', value_parser = super::options::REPEATABILITY_RAD)]
    repeatability_rad: Option<Vec<f64>>,
    /// Print `report.json` on stdout (the human-readable lines go to stderr, or nowhere with `--quiet`).
    #[arg(long)]
    json: bool,
    /// Replace existing output files.
    #[arg(long)]
    force: bool,
    /// The URDF's root link: `base_link` (the robot's base frame, ROS-Industrial) or
    /// `instrument` (the measuring instrument's frame, the base placed in it).
    #[arg(long, value_parser = OneOf(URDF_ROOTS), default_value = "base_link")]
    urdf_root: UrdfRoot,
    /// The URDF's robot name, a ROS name (default: the description's name as one).
    #[arg(long, value_parser = super::options::ros_robot_name)]
    urdf_name: Option<String>,
    /// Step of the tabulated joint map (`joint_map.csv`) (deg or mm) (finer than 0.001 writes
    /// millions of rows per joint).
    #[arg(long, default_value_t = 0.1, value_parser = InRange::closed(0.001, 90.0, "deg or mm"))]
    joint_map_step: f64,
    /// Also write a rerun recording: the measured targets per experiment with their fitted
    /// arcs, axes and residual vectors, the nominal and the calibrated robot side by side at
    /// every pose, the validation errors of both. View it with `axiscal view FILE.rrd`. Needs
    /// a build with `--features viz`.
    #[arg(long, value_name = "FILE.rrd")]
    record: Option<PathBuf>,
    /// Refine the calibrated model on the file's free poses (experiments named `validation`,
    /// `moved_joint = 0`): the identifiable combination of rows, zero offsets, transmission
    /// harmonics, couplings, base and tool frames, with its covariance, the changes in sigmas
    /// and a k-fold held-out check (`docs/method.md`, "Refinement on free poses").
    #[arg(long)]
    refine: bool,
    /// With `--refine`: also fit the effects a diagnosis of this file names (`axiscal diagnose`'s
    /// `diagnosis.json`) and carry them in the model (`robot.effects` and the transmissions,
    /// used by `validate` and `compensate`; `docs/method.md`, "Effects carried from a
    /// diagnosis"): a joint compliance, a backlash, a gear harmonic in the transmission's period.
    #[arg(long, value_name = "DIAGNOSIS.json", requires = "refine")]
    carry: Option<PathBuf>,
    /// Free poses `--refine` and the free-pose calibration fit at most, evenly spaced through
    /// the file: memory grows with them (default 5000).
    #[arg(long, value_parser = super::options::InRange::closed(3usize, 1_000_000, ""))]
    max_poses: Option<usize>,
    /// Folds of `--refine`'s held-out check.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(2..), requires = "refine")]
    refine_folds: u64,
    /// Free-pose files only: fit on the even configurations (in order of first appearance)
    /// and report the odd ones as held out, like `validate`.
    #[arg(long)]
    holdout: bool,
    /// Flag the sweep points (or free poses) the outlier test rejects but keep them in the fit.
    #[arg(long)]
    keep_outliers: bool,
    /// Calibrate every row as a free pose (the free-pose method, `docs/method.md`), the axis
    /// experiments' rows too: for data whose every target sits on the last link, e.g. sweeps
    /// the independent-axis procedure cannot use.
    #[arg(long)]
    free_poses: bool,
    /// Free-pose files only: the highest transmission-harmonic order tried (0: geometry only,
    /// default 2); each order is kept only where the data resolve it (`docs/method.md`).
    #[arg(long, value_parser = clap::value_parser!(u64).range(0..=8))]
    harmonics: Option<u64>,
    /// Free-pose files only: the non-geometric effects tried in the model: `auto` tries the
    /// joints' sag under gravity and their backlash and keeps what predicts held-out
    /// configurations best (into `robot.effects`, used by every command that reads the
    /// calibration); `none` fits the geometry only (`docs/method.md`, "Effects in the model").
    /// On a file with axis experiments, `--refine --carry` carries a diagnosis's effects.
    /// Default `auto`.
    #[arg(long, value_parser = ["auto", "none"])]
    effects: Option<String>,
    #[command(flatten)]
    checks: checks::Overrides,
}

/// The commands the outputs' raw-reading deviation and zero offsets are computed over: the
/// data's validation poses (at most [`EXPORT_POSES`], evenly spaced through the file: a
/// million-row file must not make these checks the slowest part of the calibration), else
/// seeded poses around the reference.
fn export_poses(set: &MeasurementSet, desc: &RobotDescription, cal: &Calibration) -> Vec<Vec<f64>> {
    let all: Vec<Vec<f64>> = set
        .experiments()
        .iter()
        .filter(|e| e.moved_joint == 0 && e.name != TOOL_EXPERIMENT)
        .flat_map(|e| e.by_step().into_values().map(|rows| rows[0].cmd.clone()))
        .collect();
    let stride = all.len().div_ceil(EXPORT_POSES).max(1);
    let poses: Vec<Vec<f64>> = all.into_iter().step_by(stride).collect();
    if !poses.is_empty() {
        return poses;
    }
    let plan = ValidationPlan {
        poses: EXPORT_POSES,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    plan.commands(desc, &cal.reference_cmd)
}

/// Runs `axiscal calibrate`.
pub fn run(args: Args, printer: Printer) -> Result<()> {
    let mut outputs = Outputs::new(args.force)
        .input("DATA", &args.data)
        .input("--robot", &args.robot);
    if let Some(carry) = &args.carry {
        outputs = outputs.input("--carry", carry);
    }
    let printer = printer.with_json(args.json);
    outputs.check_in(&args.out, &OUTPUT_FILES)?;
    outputs.check_in(&args.out, &TOOL_MAP_FILES)?;
    super::record::ensure_recordable(args.record.as_deref(), &outputs)?;
    let desc = RobotDescription::from_file(&args.robot)?;
    checks::description_units(&desc, &args.robot, args.checks.skip_unit_check)?;
    let set = checks::read_data(&args.data, &desc, &args.robot, args.checks)?;
    check_refine_poses(&args, &set, &desc)?;
    let free_poses_only = args.free_poses || !set.experiments().iter().any(|e| e.moved_joint > 0);
    let (mut record, map, found) = if free_poses_only {
        if let Some(noise) = args.noise_mm {
            eprintln!(
                "warning: --noise-mm {noise} has no effect here: a free-pose calibration weights its poses alike and \
                 estimates the noise from their residuals (report.md, \"Noise from the residuals\"); it applies to axis experiments"
            );
        }
        let mut record = free_poses::calibrate(&args_view(&args), &set, &desc, printer)?;
        let (accuracy, map) = predict_free_pose_accuracy(&record.calibration, &desc, &set);
        record.reports.tool_accuracy = accuracy;
        (record, map, AxesFound::default())
    } else {
        checks::one_setup(&set, &args.data, "the axis-experiment calibration")?;
        calibrate_axes(&args, &set, &desc, printer)?
    };
    record.calibration.data_digest = Some(set.digest());
    record.calibration.model_digest = Some(record.calibration.robot.digest());
    readable(&record, &args, (&set, &desc))?;
    let judged = judge(&mut record, &args, (&desc, &set), &found);
    let cal = &record.calibration;
    let texts = render(&record, &args, (&desc, &set), &found)?;
    // Every file is written before any is put in place; an output left out must not leave an
    // earlier run's file beside the new calibration.
    let mut staged = outputs.staged_in(&args.out)?;
    for (name, text) in &texts.files {
        staged.write(name, text)?;
    }
    let mut written: Vec<&str> = texts.files.iter().map(|(name, _)| *name).collect();
    if !map.is_empty() {
        staged.draw(&TOOL_MAP_FILES, |dir| write_tool_map(&map, dir))?;
        written.extend(TOOL_MAP_FILES);
    }
    staged.commit(&[&OUTPUT_FILES[..], &TOOL_MAP_FILES[..]].concat())?;
    let accuracy = record.reports.tool_accuracy.as_ref();
    match &record.reports.free_poses {
        Some(summary) => {
            free_poses::print(summary, &desc, &set, &args.data, printer);
            print_tool_accuracy(accuracy, printer);
        }
        None => {
            print_axes((cal, accuracy), &desc, &args.data.display().to_string(), printer);
            print_axis_findings(&judged, (cal, &desc, &set), &found, &args.data);
        }
    }
    say!(printer, "{}", deviation_line(&texts.deviation));
    // The URDF says so beside each such `<limit>`; a note, not a warning on every run.
    if !texts.missing_speed_limits.is_empty() && printer.verbose {
        eprintln!(
            "note: the description gives no max_velocity/max_effort for joint(s) {:?}: their URDF <limit> says velocity=0 effort=0",
            texts.missing_speed_limits
        );
    }
    for warning in &texts.left_out {
        eprintln!("warning: {warning}");
    }
    say!(printer, "wrote {}/{{{}}}", args.out.display(), written.join(","));
    printer.emit_json(&args.out.join(OUTPUT_FILES[2]))?;
    #[cfg(feature = "viz")]
    if let Some(path) = &args.record {
        let campaign = super::record::calibrated::CalibratedCampaign {
            desc: &desc,
            set: &set,
            calibration: cal,
            verdict: None,
        };
        super::record::save(path, &outputs, || {
            super::record::calibrated::write_calibrated(&campaign)
        })?;
    }
    Ok(())
}

/// What the checks said of an axis-experiment calibration before it is written.
struct Judged {
    /// The sanity checks' findings ([`sanity_findings`]).
    sanity: Vec<Implausible>,
    /// Them in words, with the file lines they are about.
    sanity_said: Vec<String>,
    /// The miss of the file's own validation poses.
    own: Option<own_poses::OwnPosesWarning>,
}

/// The sanity checks and the test on the file's own validation poses of `record`'s
/// calibration (an axis-experiment one: a free-pose fit judges itself), their warnings kept in
/// `record` after those the calibration gave, for every command that reads it.
fn judge(
    record: &mut CalibrationRecord,
    args: &Args,
    (desc, set): (&RobotDescription, &MeasurementSet),
    found: &AxesFound,
) -> Judged {
    let sanity = sanity_findings(record, desc, found);
    // The rows the screens kept: a point dropped is no sweep's and no held joint's.
    let kept = found.kept.as_ref().unwrap_or(set);
    let own = match &record.reports.free_poses {
        None => own_poses_miss(&record.calibration, (desc, kept), args, &sanity),
        Some(_) => None,
    };
    let sanity_said = implausible_warnings(&sanity, desc, set, args);
    record
        .reports
        .warnings
        .extend(sanity_said.iter().chain(own.as_ref().map(|o| &o.text)).cloned());
    Judged {
        sanity,
        sanity_said,
        own,
    }
}

/// The warnings and notes on an axis-experiment calibration `cal` of `set`: what `judged`
/// found, the command-column scale doubts and the sweeps out of place.
fn print_axis_findings(
    judged: &Judged,
    (cal, desc, set): (&Calibration, &RobotDescription, &MeasurementSet),
    found: &AxesFound,
    data: &std::path::Path,
) {
    for warning in &judged.sanity_said {
        eprintln!("warning: {warning}");
    }
    // The checks that read a sweep's fit as its joint's judge the data with a named bump
    // moved back: the bump is not a scale's or a held joint's too; a point the screens dropped
    // is no sweep's and no held joint's.
    let kept = found.kept.as_ref().unwrap_or(set);
    let (judged_cal, judged_set) = found.bumps_undone.as_ref().map_or((cal, kept), |u| (&u.cal, &u.set));
    print_scale_doubts((judged_cal, desc, judged_set.rows()), &judged.sanity, data);
    print_moved_sweeps(judged_cal, desc, judged_set, data, judged.own.as_ref());
    if let Some(own) = &judged.own {
        eprintln!("warning: {}", own.text);
    }
}

/// The sanity checks' findings on `record` ([`outputs::sanity_findings`]), with the
/// instrument axis and the bumps the sweep screen found.
fn sanity_findings(record: &CalibrationRecord, desc: &RobotDescription, found: &AxesFound) -> Vec<Implausible> {
    outputs::sanity_findings(
        record,
        desc,
        found.column_source.as_ref(),
        found.bumps_undone.as_ref().map(|u| implausible(&u.cal, desc)),
    )
}

/// Every output of `record` rendered (`outputs::render` with the options `args` give), with
/// the detection limits in `report.md`.
fn render(
    record: &CalibrationRecord,
    args: &Args,
    (desc, set): (&RobotDescription, &MeasurementSet),
    found: &AxesFound,
) -> Result<outputs::CalibrationOutputs> {
    let options = OutputOptions {
        urdf: UrdfOptions {
            robot_name: args.urdf_name.clone().unwrap_or_else(|| ros_name(&desc.name)),
            root: args.urdf_root,
        },
        joint_map_step: args.joint_map_step,
    };
    let source = args.data.display().to_string();
    let poses = export_poses(set, desc, &record.calibration);
    let mut texts = outputs::render(record, desc, &source, &poses, &options)?;
    let judged = found.bumps_undone.as_ref().map(|u| (&u.cal, &u.set));
    add_detection_limits(
        &mut texts.files,
        record,
        desc,
        judged.unwrap_or((&record.calibration, found.kept.as_ref().unwrap_or(set))),
    );
    Ok(texts)
}

/// `cal` passes the checks every command makes when it reads `calibration.json`: a parameter
/// the data leave free is said here, before anything is written, not by the next command (with
/// free poses at too few configurations as its cause, when they are).
fn readable(record: &CalibrationRecord, args: &Args, (set, desc): (&MeasurementSet, &RobotDescription)) -> Result<()> {
    let (data, cal) = (&args.data, &record.calibration);
    if let Some((_, name, variance)) = cal.model_covariance.as_ref().and_then(|c| c.undetermined()) {
        let few = record
            .reports
            .free_poses
            .as_ref()
            .and_then(|s| free_poses::few_configurations_of(set, desc, s.axis_rows_as_poses.is_some()));
        anyhow::bail!(
            "calibrating {}: the data do not determine `{name}` (1-sigma {:.3e}, beyond 1 in its unit): nothing written; {}",
            data.display(),
            variance.sqrt(),
            match (few.or_else(|| absorbed_scales(record)), weighting_options(args, cal)) {
                (Some(few), _) => few,
                (None, Some(options)) => format!(
                    "every sigma grows with the noise the fits assume: {options}; without them the noise is estimated from the residuals and the repeatability is the description's"
                ),
                (None, None) => "the fitted axes leave it free (two axes parallel or on one line where the description's rows make \
                         them meet, or a joint swept too little to fix it): check the description's rows against the robot \
                         (`axiscal describe`) and the sweeps' spans"
                    .to_owned(),
            }
        );
    }
    cal.validate().map_err(|e| {
        anyhow::anyhow!(
            "calibrating {}: the calibrated model is none a robot can have ({e}): the data do not fit this \
             description; check the warnings above (a coordinate column scaled or shifted, commands in other units), the \
             description's rows and units, and each sweep's rows; nothing written",
            data.display()
        )
    })
}

/// The column scales the free-pose screen named, in words, as the cause of a parameter left
/// free: the fit of the file as written absorbed them into the geometry.
fn absorbed_scales(record: &CalibrationRecord) -> Option<String> {
    let summary = record.reports.free_poses.as_ref().filter(|s| !s.scales.is_empty())?;
    let columns: Vec<String> = summary
        .scales
        .iter()
        .map(|n| format!("`{}` divided by {:.5}", n.scale.column, n.scale.factor))
        .collect();
    Some(format!(
        "the fit of the file as written took the column scale named above into the geometry, which leaves it free: \
         correct the export ({}) and calibrate again",
        columns.join(", ")
    ))
}

/// The options that set the noise the fits assume (`--noise-mm`, `--repeatability-rad`), as
/// given, with the residuals' own noise estimate beside `--noise-mm`; `None` when neither is.
fn weighting_options(args: &Args, cal: &Calibration) -> Option<String> {
    let estimate = cal
        .noise
        .as_ref()
        .and_then(|n| n.estimate.as_ref())
        .map(|e| e.rms_3d_mm);
    let noise = args.noise_mm.map(|n| match estimate {
        Some(e) if e > 0.0 => format!(
            "--noise-mm {n} ({:.1} times the {e:.4} mm the residuals estimate)",
            n / e
        ),
        _ => format!("--noise-mm {n}"),
    });
    let repeatability = args.repeatability_rad.as_ref().map(|r| {
        format!(
            "--repeatability-rad {}",
            r.iter().map(f64::to_string).collect::<Vec<_>>().join(",")
        )
    });
    let given: Vec<String> = noise.into_iter().chain(repeatability).collect();
    (!given.is_empty()).then(|| given.join(" and "))
}

/// `--max-poses`, or its default.
fn max_poses(args: &Args) -> usize {
    args.max_poses.unwrap_or(axiscal::measurement::bounded::FIT_MAX_POSES)
}

/// The options of the free-pose path.
fn args_view(args: &Args) -> free_poses::FreeArgs<'_> {
    free_poses::FreeArgs {
        data: &args.data,
        holdout: args.holdout,
        keep_outliers: args.keep_outliers,
        harmonics: args.harmonics.map_or(
            axiscal::calibration::free_pose::FreePoseOptions::default().max_harmonic_order,
            |h| h as usize,
        ),
        effects: args.effects.as_deref() != Some("none"),
        all_rows: args.free_poses,
        refine: args.refine,
        max_poses: max_poses(args),
    }
}

/// report.md's "Detection limits": the command-column scales the transmission test lets pass
/// on this file ([`axiscal::calibration::procedure::scale_reach`], its free-pose form; on the
/// calibration `cal` of `set` the test judged, [`axiscal::calibration::screened::BumpsUndone`] where bumps were named), and
/// what the coordinate-scale note means where it was printed.
fn add_detection_limits(
    files: &mut [(&'static str, String)],
    record: &CalibrationRecord,
    desc: &RobotDescription,
    (cal, set): (&Calibration, &MeasurementSet),
) {
    let Some((_, report)) = files.iter_mut().find(|(name, _)| *name == "report.md") else {
        return;
    };
    let reach = match &record.reports.free_poses {
        None => axiscal::calibration::procedure::scale_reach(cal, desc, set.rows()),
        Some(summary) => axiscal::calibration::procedure::free_pose_scale_reach((cal, summary), desc, set.rows()),
    };
    let commands = reach.map(|r| format!("{}\n\n", r.words())).unwrap_or_default();
    report.push_str(&format!(
        "\n## Detection limits\n\n{commands}{}\n",
        axiscal::measurement::unit_check::axis_scale::axis_reach_words()
    ));
}
