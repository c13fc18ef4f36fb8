//! `axiscal calibrate DATA.csv --robot R --out DIR`: the independent-axis procedure on a
//! measurement CSV, writing `calibration.json` (loadable again), `report.md`, `report.json`
//! and `calibrated.urdf`.

use super::OneOf;
use super::checks;
use super::options::{InRange, NOISE_MM};
use super::output::Outputs;
use super::printer::Printer;
use anyhow::Context;
use anyhow::Result;
use axiscal::calibration::free_pose;
use axiscal::calibration::outputs::{self, OUTPUT_FILES, OutputOptions};
use axiscal::calibration::procedure::axis_experiments_with;
use axiscal::calibration::procedure::{
    AxisEstimator, Calibration, CalibrationOptions, ColumnSource, DEFAULT_HELD_TOLERANCE, Implausible, OutlierPoint,
    OutlierTest, PLAUSIBLE_AXIS_TILT_RAD, ProcedureError, RawReadingDeviation, SIZE_TOLERANCE, ScaleSlip, UrdfOptions,
    UrdfRoot, implausible, ros_name,
};
use axiscal::calibration::recalibrated::CoordinateScale;
use axiscal::calibration::record::{CalibrationRecord, Reports};
use axiscal::calibration::refine::{RefineOptions, Refinement, enough_free_poses};
use axiscal::calibration::refit_model::refine::refine_carrying;
use axiscal::calibration::refit_model::validation_poses_at_most;
use axiscal::calibration::screened::{BumpsUndone, CalibrationFailed, FailingSweep, ScreenFailure, calibrate_screened};
use axiscal::calibration::tool_accuracy::{MapPoint, PredictionOptions, ToolAccuracy, predict, swept_ranges};
use axiscal::calibration::tool_map::{TOOL_MAP_FILES, write_tool_map};
use axiscal::diagnosis::{
    Candidate, Diagnosis, MAX_SWEEP_SEARCH_CALIBRATIONS, OwnPoses, OwnPosesCause, OwnPosesMiss, OwnPosesSlips,
    SweepSearch, SweepSearchTooLarge, ToolMoveBeyond, carried_candidates, test_own_validation_poses,
};
use axiscal::json_file::{self, Schema};
use axiscal::measurement::unit_check::axis_scale::NullSpread;
use axiscal::measurement::{Measurement, MeasurementSet, format_f64};
use axiscal::plan::{TOOL_EXPERIMENT, ValidationPlan};
use axiscal::robot::RobotDescription;
use std::path::{Path, PathBuf};

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
    /// the file: memory grows with them (default 1000).
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

/// The URDF-fed-raw-readings line printed after the axes table.
fn deviation_line(d: &RawReadingDeviation) -> String {
    format!(
        "  URDF fed raw controller readings: tool off by up to {:.3} mm, {:.3} mrad over {} poses (use joint_map.csv / `axiscal joints`)",
        d.max_position_mm, d.max_orientation_mrad, d.poses
    )
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
        let mut record = super::calibrate_free::calibrate(&args_view(&args), &set, &desc, printer)?;
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
    let cal = &record.calibration;
    let source = args.data.display().to_string();
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
            super::calibrate_free::print(summary, &desc, &set, &args.data, printer);
            print_tool_accuracy(accuracy, printer);
        }
        None => {
            print_axes((cal, accuracy), &desc, &source, printer);
            print_implausible(&texts.implausible, &desc, &set, &args);
            // The checks that read a sweep's fit as its joint's judge the data with a named bump
            // moved back: the bump is not a scale's or a held joint's too.
            // The rows the screens kept: a point dropped is no sweep's and no held joint's.
            let kept = found.kept.as_ref().unwrap_or(&set);
            let (judged_cal, judged) = found.bumps_undone.as_ref().map_or((cal, kept), |u| (&u.cal, &u.set));
            print_scale_doubts((judged_cal, &desc, judged.rows()), &texts.implausible, &args.data);
            let own = own_poses_miss(cal, (&desc, kept), &args, &texts.implausible);
            print_moved_sweeps(judged_cal, &desc, judged, &args.data, own.as_ref());
            if let Some(own) = own {
                eprintln!("warning: {}", own.text);
            }
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
        column_source: found.column_source.clone(),
        bumps_undone: found.bumps_undone.as_ref().map(|u| implausible(&u.cal, desc)),
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

/// The file lines of the tool rows a [`Implausible::ToolMisfit`] is about (` (FILE lines
/// 3, 4, 5)`), empty for any other finding.
fn tool_rows(found: &Implausible, set: &MeasurementSet, data: &Path) -> String {
    let Implausible::ToolMisfit { experiment, step, .. } = found else {
        return String::new();
    };
    let lines: Vec<String> = set
        .rows()
        .iter()
        .enumerate()
        .filter(|(_, m)| m.experiment == *experiment && m.step == *step)
        .filter_map(|(i, _)| set.line_of(i).map(|l| l.to_string()))
        .collect();
    if lines.is_empty() {
        return String::new();
    }
    format!(" ({} lines {})", data.display(), lines.join(", "))
}

/// A joint's misfit with the file lines of the sweep that carries it (its first and last, and
/// its worst point's), from `set`.
fn with_sweep_lines(mut found: Implausible, set: &MeasurementSet) -> Implausible {
    if let Implausible::Misfit { sweep: Some(s), .. } = &mut found {
        let lines: Vec<(u64, &Measurement)> = set
            .rows()
            .iter()
            .enumerate()
            .filter(|(_, m)| m.experiment == s.experiment)
            .filter_map(|(i, m)| set.line_of(i).map(|l| (l, m)))
            .collect();
        s.lines = lines.first().zip(lines.last()).map(|(a, b)| (a.0, b.0));
        s.worst_line = lines
            .iter()
            .find(|(_, m)| m.step == s.worst.0 && m.target == 0)
            .map(|(l, _)| *l);
    }
    found
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
            .and_then(|s| super::calibrate_free::few_configurations_of(set, desc, s.axis_rows_as_poses.is_some()));
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

/// The options given that the axis-experiment calibration does not use, as one warning each:
/// free-pose options (`--harmonics`, `--effects`), and `--max-poses` without `--refine`.
fn unused_on_axes(args: &Args) -> Vec<String> {
    let data = args.data.display();
    let free_pose_only = [
        ("--harmonics", args.harmonics.is_some()),
        ("--effects", args.effects.is_some()),
        ("--max-poses", args.max_poses.is_some() && !args.refine),
    ];
    free_pose_only
        .iter()
        .filter(|(_, given)| *given)
        .map(|(option, _)| {
            format!(
                "{option} has no effect here: it applies to free-pose calibrations (a file without axis experiments, or --free-poses){}, and {data} has axis experiments",
                if *option == "--max-poses" { " and to --refine" } else { "" }
            )
        })
        .collect()
}

/// The options of the free-pose path.
fn args_view(args: &Args) -> super::calibrate_free::FreeArgs<'_> {
    super::calibrate_free::FreeArgs {
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

/// What the axis-experiment calibration found beside its record ([`calibrate_axes`]).
#[derive(Default)]
struct AxesFound {
    /// The instrument axis whose scale explains the joints' transmission departures
    /// ([`ScreenedCalibration::column_source`]).
    column_source: Option<ColumnSource>,
    /// The data with the sweep screen's named bumps moved back, where it named any.
    bumps_undone: Option<BumpsUndone>,
    /// The rows the screens kept; `None` when they dropped none.
    kept: Option<MeasurementSet>,
}

/// The axis-experiment calibration of `set` after its failure on the rows the screen kept
/// (`failed`): every row a free pose where the independent-axis correction for the held joints
/// does not settle (that fit tests its poses for outliers itself, on every row); else the
/// points flagged and why it failed.
fn calibration_failed(
    args: &Args,
    (set, desc): (&MeasurementSet, &RobotDescription),
    options: &CalibrationOptions,
    failed: CalibrationFailed,
    printer: Printer,
) -> Result<(CalibrationRecord, Vec<MapPoint>, AxesFound)> {
    let sweep = failing_sweep_words(failed.sweep.as_ref());
    if let e @ (ProcedureError::HeldNotConverged { .. } | ProcedureError::HeldDiverged { .. }) = &failed.error
        && !args.refine
    {
        let mut record = sweeps_as_free_poses(args, (set, desc), (e, failed.sweep.as_ref()), printer)?;
        let (accuracy, map) = predict_free_pose_accuracy(&record.calibration, desc, set);
        record.reports.tool_accuracy = accuracy;
        return Ok((record, map, AxesFound::default()));
    }
    checks::print_outliers(&failed.outliers, &args.data, "calibrated");
    let kept = failed.screened.as_ref().unwrap_or(set);
    Err(failure_words(args, (kept, desc), options, (&failed.error, &sweep)))
}

/// The words naming the sweep that carries a joint's failure (empty without one).
fn failing_sweep_words(sweep: Option<&FailingSweep>) -> String {
    let Some(s) = sweep else {
        return String::new();
    };
    let lines = s.lines.map_or_else(String::new, |(a, b)| format!(" (lines {a}-{b})"));
    format!(
        "; the failure is experiment {}'s{lines}: without it the calibration passes, without any other sweep of joint {} \
         it fails: check that sweep's rows (its block moved part-way, a bump of the instrument or the robot, or a held \
         joint's recorded command off through it: a value typed wrong or the joint re-mastered between the sweeps)",
        s.experiment, s.joint
    )
}

/// The outliers of the sweeps whose held joints wander, as warnings naming each row: those the
/// procedure's failed fit named off their sweep's path, dropped with their poses
/// ([`OutlierTest::AxisFit`]), and those the screen of these sweeps' points moved by the
/// calibrated model flagged ([`OutlierTest::Moved`]).
fn print_wandering_outliers(outliers: &[OutlierPoint], desc: &RobotDescription, args: &Args) {
    let path_of = |o: &OutlierPoint| match desc.joints.get(o.joint.wrapping_sub(1)).map(|j| j.kind) {
        Some(axiscal::kinematics::JointKind::Prismatic) => "line",
        _ => "arc",
    };
    for o in outliers.iter().filter(|o| o.test == OutlierTest::AxisFit) {
        let (place, _) = checks::outlier_place(o, &args.data, "calibrated");
        let path = path_of(o);
        eprintln!(
            "warning: {place}: outlier: experiment {} step {} target {}: {:.3} mm off the {path} its sweep's other points \
             draw (or along it, off its command), {:.1} times the noise, beyond the fence {:.1} of their distances: the \
             sweep screen cannot test a sweep whose held joints wander (its points lie on no one {path}), and the axis \
             fit failed with it: calibrated without it and the other targets of its pose (--keep-outliers keeps it, and \
             the fit fails); check this row's coordinates and commands",
            o.experiment, o.step, o.target, o.residual_mm, o.normalised_residual, o.fence
        );
    }
    let moved: Vec<OutlierPoint> = (outliers.iter())
        .filter(|o| o.test == OutlierTest::Moved)
        .cloned()
        .collect();
    for o in moved.iter().filter(|o| o.approach.is_none()) {
        let (place, what) = checks::outlier_place(o, &args.data, "calibrated again");
        let what = match o.dropped || args.keep_outliers {
            true => what,
            false => "kept: the calibration without its pose failed".to_string(),
        };
        let path = path_of(o);
        eprintln!(
            "warning: {place}: outlier: experiment {} step {} target {}: {:.3} mm from the fit of its sweep's other \
             points, {:.1} times their noise, beyond the fence {:.1} (a clean file's sweeps pass it with {:.0} % \
             probability), its sweep's points moved to the design pose by the calibrated model (its held joints wander, \
             so that as measured they lie on no one {path}): {what}; check this row's coordinates and commands",
            o.experiment,
            o.step,
            o.target,
            o.residual_mm,
            o.normalised_residual,
            o.fence,
            100.0 * (1.0 - axiscal::calibration::procedure::SWEEP_POINTS_FALSE_ALARM)
        );
    }
    checks::print_approach_notes(&moved, &args.data, "calibrated again");
}

/// Why the axis-experiment calibration of `screened` failed (`e`, and the words naming the sweep
/// that carries it, [`failing_sweep_words`]), with what `--noise-mm` or
/// `--repeatability-rad` had to do with it.
fn failure_words(
    args: &Args,
    (screened, desc): (&MeasurementSet, &RobotDescription),
    options: &CalibrationOptions,
    (e, sweep): (&ProcedureError, &str),
) -> anyhow::Error {
    if let Some(too_small) = args
        .noise_mm
        .and_then(|n| checks::noise_far_below(screened, desc, options, n, e.joint(), ["the fits", "it"]))
    {
        return anyhow::anyhow!("calibrating {}: {too_small}", args.data.display());
    }
    let hint = match (args.noise_mm, &args.repeatability_rad) {
        (Some(n), _) => format!(
            " (with --noise-mm {n:e}: a noise far below the data's makes the fits trust each point more than the joints' repeatability allows; without --noise-mm it is estimated from the residuals)"
        ),
        (None, Some(r)) => format!(
            " (with --repeatability-rad {}: a repeatability far above the joints' own weights the fits away from their points; without it the description's repeatability_sigma is used)",
            r.iter().map(f64::to_string).collect::<Vec<_>>().join(",")
        ),
        (None, None) => String::new(),
    };
    anyhow::anyhow!("calibrating {}: {e}{sweep}{hint}", args.data.display())
}

/// The independent-axis calibration of `set` (`--refine` applied) with its reports, the
/// tool-accuracy map, and what the checks found beside it ([`AxesFound`]).
fn calibrate_axes(
    args: &Args,
    set: &MeasurementSet,
    desc: &RobotDescription,
    printer: Printer,
) -> Result<(CalibrationRecord, Vec<MapPoint>, AxesFound)> {
    if args.holdout {
        anyhow::bail!(
            "--holdout applies to free-pose files (no axis experiment); {} has axis experiments",
            args.data.display()
        );
    }
    for warning in unused_on_axes(args) {
        eprintln!("warning: {warning}");
    }
    let options = CalibrationOptions {
        estimator: args.estimator,
        noise_rms_3d_mm: args.noise_mm.unwrap_or(CalibrationOptions::default().noise_rms_3d_mm),
        estimate_noise: args.noise_mm.is_none(),
        held_tolerance: args.held_tolerance,
        repeatability_sigma_rad: args.repeatability_rad.clone(),
        ..CalibrationOptions::default()
    };
    options
        .joint_repeatability_rad(desc)
        .map_err(|e| anyhow::anyhow!("--repeatability-rad: {e}"))?;
    let screened = match calibrate_screened(set, desc, &options, args.keep_outliers) {
        Ok(screened) => screened,
        Err(ScreenFailure::Screen(e)) => anyhow::bail!("calibrating {}: {e}", args.data.display()),
        Err(ScreenFailure::Calibration(failed)) => {
            return calibration_failed(args, (set, desc), &options, *failed, printer);
        }
    };
    let screen_outliers: Vec<OutlierPoint> = (screened.cal.outliers.iter())
        .filter(|o| o.test.is_screen())
        .cloned()
        .collect();
    checks::print_outliers(&screen_outliers, &args.data, "calibrated");
    print_wandering_outliers(&screened.cal.outliers, desc, args);
    checks::print_sweep_bumps(&screened.bumps, &args.data);
    let set = screened.screened.as_ref().unwrap_or(set);
    print_coordinate_scale(&screened.coordinate_scale, set, &args.data, printer);
    let cal = screened.cal;
    let (tool_accuracy, map) = predict_tool_accuracy(&cal, desc, set, args.held_tolerance)?;
    // The prediction describes the axis experiments' model and its propagated covariance;
    // `--refine` reports its own covariance and held-out check beside it.
    let (calibration, refinement) = if args.refine {
        let (refined, refinement) = refine(args, set, desc, &cal, printer)?;
        (refined, Some(refinement))
    } else {
        (cal, None)
    };
    let reports = Reports {
        tool_accuracy,
        refinement,
        free_poses: None,
    };
    let found = AxesFound {
        column_source: screened.column_source,
        bumps_undone: screened.bumps_undone,
        kept: screened.screened,
    };
    Ok((CalibrationRecord { calibration, reports }, map, found))
}

/// The coordinate-scale profile's finding on `set` ([`coordinate_scale`]) in words: a scale
/// named as a warning, with a second axis behind it; else a note of how large a scale would
/// pass where that is beyond the test's claim, and with `--verbose` a note of the largest one
/// either way. A scale the free poses' screen named none of is a note.
pub(super) fn print_coordinate_scale(found: &CoordinateScale, set: &MeasurementSet, data: &Path, printer: Printer) {
    match found {
        CoordinateScale::Untested => eprintln!(
            "note: {}: one-axis instrument scales this file cannot show: any column, at any size (the \
             coordinate-scale test could not run: its re-run calibrations did not keep the same poses and \
             parameters, or failed; report.md, \"Detection limits\")",
            data.display()
        ),
        CoordinateScale::SourceNamed => {}
        CoordinateScale::Within(found) => {
            if printer.verbose {
                eprintln!(
                    "note: {}: of the coordinate columns {} reads the most unlike the others: {:.5} times \
                     (+- {:.5}, {:.1} sigma from 1, within the data's reach of 1)",
                    data.display(),
                    found.scaled.columns(),
                    found.factor,
                    found.sigma,
                    (found.factor - 1.0).abs() / found.sigma
                );
            }
            if let Some(reach) = found.reach_note() {
                eprintln!("note: {}: {reach}", data.display());
            }
        }
        CoordinateScale::ScreenNamedNone(found) => eprintln!(
            "note: {}: the coordinate-scale profile reads {} {:.5} times (+- {:.5}, counting every point as \
             independent), but the column-scale screen over the configurations (repeated visits share the model's \
             error at each) names no command column or instrument axis: not named",
            data.display(),
            found.scaled.columns(),
            found.factor,
            found.sigma
        ),
        CoordinateScale::WithinCorrectionError { found, null } => eprintln!(
            "note: {}: the coordinate-scale profile reads {} {:.5} times (+- {:.5} from the noise, {:.1} sigma from \
             1), but {}: the sweeps at other poses enter through the held joints' correction, whose model error reads \
             as a scale (longer sweeps locate the axes better): not named",
            data.display(),
            found.scaled.columns(),
            found.factor,
            found.sigma,
            (found.factor - 1.0).abs() / found.sigma,
            simulated_words(null)
        ),
        CoordinateScale::Named { found, second, null } => {
            let place = match set.line_of(0) {
                Some(line) => format!("{}:{line}", data.display()),
                None => data.display().to_string(),
            };
            let beyond = null.as_ref().map_or(String::new(), |null| {
                format!(
                    " (the sweeps at other poses enter through the held joints' correction, whose model error reads as \
                     a scale; {}, so it stands beyond that)",
                    simulated_words(null)
                )
            });
            eprintln!("warning: {place}: {found}{beyond}");
            if let Some(second) = second {
                eprintln!(
                    "warning: {place}: with {} divided by {:.5} about the data's centroid (the scale named above) \
                     the coordinate-scale profile was run again, and a second axis shows: {second}",
                    found.scaled.columns(),
                    found.factor
                );
            }
        }
    }
}

/// What the files simulated without a scale read ([`NullSpread`]), in words.
fn simulated_words(null: &NullSpread) -> String {
    format!(
        "{} files simulated from this calibration at these commands, with this noise and no scale, read it {:.5} \
         times (+- {:.5}; p = {:.1e} for this file among them)",
        null.files, null.centre, null.sigma, null.p_value
    )
}

/// The free-pose calibration of every row of `set`, for sweeps the independent-axis correction
/// for their held joints does not bring to one pose (`failure`); an error when the sweeps'
/// targets cannot be free poses (on a link before the last), or when the procedure passes
/// without one sweep (`sweep`) and the free-pose fit finds a block of rows shifted off the
/// others: then that sweep is the fault, not the configurations.
fn sweeps_as_free_poses(
    args: &Args,
    (set, desc): (&MeasurementSet, &RobotDescription),
    (failure, sweep): (&ProcedureError, Option<&FailingSweep>),
    printer: Printer,
) -> Result<CalibrationRecord> {
    let sweep_words = failing_sweep_words(sweep);
    if let Some(why_not) = free_pose::poses::why_sweeps_are_not_poses(set, desc) {
        anyhow::bail!(
            "calibrating {}: {failure}{sweep_words}; the sweeps cannot be fitted as free poses either: {why_not}",
            args.data.display()
        );
    }
    let mut view = args_view(args);
    view.all_rows = true;
    if sweep.is_some()
        && let Some(block) = super::calibrate_free::quietly_shifted_block(&view, set, desc)
    {
        let [x, y, z] = block.shift_mm;
        anyhow::bail!(
            "calibrating {}: {failure}{sweep_words}; fitted as free poses instead, the poses {} sit about ({x:.2}, \
             {y:.2}, {z:.2}) mm off the others",
            args.data.display(),
            super::calibrate_free::block_place(&block)
        );
    }
    let why = format!(
        "the independent-axis procedure cannot bring the sweeps from their configurations to one pose ({failure}{sweep_words})"
    );
    eprintln!(
        "warning: {}: {why}; every point is fitted as a free pose instead (docs/method.md, \"Calibration from free poses\")",
        args.data.display()
    );
    let mut record = match (
        super::calibrate_free::calibrate(&view, set, desc, printer),
        failure.misfit(),
    ) {
        (Ok(record), _) => record,
        // The rows named are the likelier cause than the configurations' spread.
        (Err(_), Some(misfit)) => anyhow::bail!(
            "calibrating {}: {misfit}{sweep_words}; fitted as free poses, the sweeps fail too",
            args.data.display()
        ),
        (Err(e), None) => return Err(e),
    };
    if let Some(summary) = record.reports.free_poses.as_mut() {
        summary.axis_rows_as_poses = Some(why);
    }
    Ok(record)
}

/// The sanity checks' findings ([`implausible`]) as warnings; a size off by a factor says
/// that the description, not only the coordinates, may be at fault when the data do not record
/// this very description ([`checks::description_suspect`]).
fn print_implausible(found: &[Implausible], desc: &RobotDescription, set: &MeasurementSet, args: &Args) {
    for f in found {
        let f = &with_sweep_lines(f.clone(), set);
        let rows = tool_rows(f, set, &args.data);
        let suspect = match f {
            Implausible::Size { .. } => {
                let recorded = checks::data_identity(&args.data).ok().flatten();
                checks::description_suspect(desc, &args.robot, recorded.as_ref())
            }
            _ => None,
        };
        match suspect {
            Some(s) => eprintln!("warning: {f}{rows}; {s}"),
            None => eprintln!("warning: {f}{rows}"),
        }
    }
}

/// The joints whose slope a gear's once-per-turn error and a scaled command column explain
/// alike ([`scale_doubts`]) as notes; none beside a size or mirror finding, which explains the
/// slopes.
fn print_scale_doubts(
    (cal, desc, rows): (&Calibration, &RobotDescription, &[Measurement]),
    found: &[Implausible],
    data: &Path,
) {
    if cal.options.estimator == AxisEstimator::Paper {
        eprintln!(
            "note: {}: the command-column scale test does not run on the paper's estimator: its transmission sigmas \
             (eq. 8, a-posteriori, given the fitted axis) leave out the axis's own error and would name scales a clean \
             file does not have; `--estimator ml` tests every column",
            data.display()
        );
        return;
    }
    if found
        .iter()
        .any(|f| matches!(f, Implausible::Size { .. } | Implausible::Mirrored { .. }))
    {
        return;
    }
    for doubt in axiscal::calibration::procedure::scale_doubts(cal, desc) {
        eprintln!("note: {}: {doubt}", data.display());
    }
    // The columns a warning named are said; the line bounds the others.
    let scaled: Vec<ScaleSlip> = found
        .iter()
        .filter_map(|f| match f {
            Implausible::Scaled(s) => Some(s.clone()),
            _ => None,
        })
        .collect();
    let named = axiscal::calibration::procedure::named_joints(&scaled);
    if let Some(reach) = axiscal::calibration::procedure::scale_reach(cal, desc, rows).and_then(|r| r.without(&named)) {
        eprintln!("note: {}: {reach}", data.display());
    }
}

/// report.md's "Detection limits": the command-column scales the transmission test lets pass
/// on this file ([`axiscal::calibration::procedure::scale_reach`], its free-pose form; on the
/// calibration `cal` of `set` the test judged, [`BumpsUndone`] where bumps were named), and
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

/// The sweeps out of place among the sightings of their shared target at the reference pose
/// ([`axiscal::calibration::shared_target::moved_sweeps`], at the calibration's noise) as
/// warnings naming the file and the sweep's first line; where none is, the moves the test
/// lets pass ([`axiscal::calibration::shared_target::block_reach`]) as a note, and in a file
/// without validation poses the held joints' offsets it lets pass
/// ([`axiscal::calibration::shared_target::held_reach`]). The warning of a sweep whose drift the
/// file's own validation poses name (`own`: [`OwnPosesWarning::replaces`]) is left to that
/// warning, which says how the test read the sweep.
fn print_moved_sweeps(
    cal: &Calibration,
    desc: &RobotDescription,
    set: &MeasurementSet,
    data: &Path,
    own: Option<&OwnPosesWarning>,
) {
    let noise = cal
        .noise
        .as_ref()
        .map_or(cal.options.noise_rms_3d_mm, |n| n.used_rms_3d_mm);
    let moved_sweeps = axiscal::calibration::shared_target::moved_sweeps(set, desc, noise);
    let replaced = own.and_then(|o| o.replaces.as_deref());
    for moved in moved_sweeps.iter().filter(|m| Some(m.experiment.as_str()) != replaced) {
        let place = moved.lines.map_or_else(
            || data.display().to_string(),
            |(l, _)| format!("{}:{l}", data.display()),
        );
        // Out of place by the held joints' backlash only: a note.
        let kind = if moved.backlash.is_empty() { "warning" } else { "note" };
        eprintln!("{kind}: {place}: {moved}");
    }
    if moved_sweeps.is_empty()
        && let Some(reach) = axiscal::calibration::shared_target::block_reach(set, desc, noise)
    {
        eprintln!("note: {}: {reach}", data.display());
    }
    // With validation poses, `misses_own_validation_poses` seeks a held offset the sweeps hide.
    let poses = set
        .rows()
        .iter()
        .any(|m| m.moved_joint == 0 && m.experiment != TOOL_EXPERIMENT);
    if moved_sweeps.is_empty()
        && !poses
        && let Some(reach) = axiscal::calibration::shared_target::held_reach(set, desc, noise)
    {
        eprintln!("note: {}: {reach}", data.display());
    }
}

/// The warning of a miss of the file's own validation poses by `cal` (calibrated from `kept`;
/// [`misses_own_validation_poses`]; not with `--refine`, which fits them), seeking a sweep's
/// cause unless the checks `found` a slip of the coordinates ([`SweepSearch::after`]).
fn own_poses_miss(
    cal: &Calibration,
    (desc, kept): (&RobotDescription, &MeasurementSet),
    args: &Args,
    found: &[Implausible],
) -> Option<OwnPosesWarning> {
    if args.refine {
        return None;
    }
    let stated = args.repeatability_rad.as_deref();
    misses_own_validation_poses(
        cal,
        (desc, kept, &args.data),
        (stated, SweepSearch::after(found), args.keep_outliers),
    )
}

/// A miss of the file's own validation poses, in words ([`misses_own_validation_poses`]).
pub(super) struct OwnPosesWarning {
    /// The warning.
    pub text: String,
    /// The experiment whose reading by the reference-pose test (a moved block, a held offset)
    /// it replaces: a drift through that sweep, which the test reads so at the reference pose,
    /// and which fits the validation poses.
    pub replaces: Option<String>,
}

/// The axis-experiment calibration tested on the file's own validation poses, which it did not
/// fit ([`test_own_validation_poses`], seeking a sweep's cause as `search` says), in words: a
/// sweep's cause that makes them pass alone, else the miss with what the slip search `validate`
/// runs names; the paper's estimator's untested miss as a note. The poses' gross errors are
/// warned of as they are found (left out of the test unless `keep`). `None` without validation
/// poses or when they are consistent.
pub(super) fn misses_own_validation_poses(
    cal: &Calibration,
    (desc, set, data): (&RobotDescription, &MeasurementSet, &Path),
    (stated_repeatability, search, keep): (Option<&[f64]>, SweepSearch, bool),
) -> Option<OwnPosesWarning> {
    let place = data.display().to_string();
    let (outliers, tested) = test_own_validation_poses(cal, desc, set, (search, keep));
    checks::print_warnings(&checks::outlier_warnings(
        &outliers,
        data,
        "its own validation poses tested",
    ));
    let miss = match tested? {
        OwnPoses::NotTested(fit) => {
            eprintln!(
                "note: {place}: the calibrated model misses this file's own {} validation poses (not fitted) by {:.3} mm RMS{}; \
                 not tested: the paper's estimator predicts no error of its calibration (the noise and repeatability alone \
                 give {:.3} mm; `--estimator ml` predicts and tests it)",
                fit.poses,
                fit.rms_mm,
                if fit.tool_fitted {
                    ", with the tool frame fitted to them"
                } else {
                    ""
                },
                fit.predicted_mm
            );
            return None;
        }
        OwnPoses::Misses(miss) => miss,
    };
    let (partial, slips) = match &miss.cause {
        OwnPosesCause::Sweep(sweep) => {
            return Some(OwnPosesWarning {
                text: super::sweep_cause::words(sweep, &place, miss.fit.poses),
                replaces: sweep.shadows.as_ref().and(sweep.experiment.clone()),
            });
        }
        OwnPosesCause::Unnamed {
            partial,
            too_large,
            slips,
        } => (partial, (too_large, slips)),
    };
    let (too_large, slips) = slips;
    let sweep_part = partial
        .as_ref()
        .map(|h| super::sweep_cause::part_words(h, &place))
        .unwrap_or_default();
    let first = understated_repeatability(desc, stated_repeatability);
    let cause = own_poses_slips(slips, data);
    let beyond = miss.tool_move.map(tool_move_words).unwrap_or_default();
    let unsearched = too_large.as_ref().map(sweep_search_too_large_words).unwrap_or_default();
    Some(OwnPosesWarning {
        text: format!(
            "{}{beyond}: {first}{sweep_part}{cause}{unsearched}",
            own_miss_words(&miss)
        ),
        replaces: None,
    })
}

/// Why no sweep's cause of a miss was sought ([`SweepSearchTooLarge`]).
fn sweep_search_too_large_words(t: &SweepSearchTooLarge) -> String {
    format!(
        "; no sweep's held command, drift or moved block was tried as its cause (its {} hypotheses would cost {} calibrations, \
         beyond the {MAX_SWEEP_SEARCH_CALIBRATIONS} the search runs; they grow as the square of the joints): check each sweep's \
         held commands against the controller and the reference-pose warnings above",
        t.hypotheses, t.calibrations
    )
}

/// The first clause of a miss of the file's own validation poses: by how much, against what.
fn own_miss_words(miss: &OwnPosesMiss) -> String {
    let (n, rms, predicted) = (miss.fit.poses, miss.fit.rms_mm, miss.fit.predicted_mm);
    let tool = if miss.fit.tool_fitted {
        ", with the tool frame, which no pose measured, fitted to these poses"
    } else {
        ""
    };
    if !miss.exceeds || rms > predicted {
        format!(
            "the calibrated model misses this file's own {n} validation poses (not fitted) by {rms:.3} mm RMS against {predicted:.3} mm predicted (chi2/dof {:.2}{tool})",
            miss.per_dof
        )
    } else {
        format!(
            "the calibrated model's misses of this file's own {n} validation poses (not fitted) fail the prediction's chi-square test (chi2/dof {:.2}{tool}) though their RMS, {rms:.3} mm, is within the {predicted:.3} mm predicted: their pattern, not their size, contradicts it (some poses or directions missed well beyond their own predicted error, where the prediction is tight)",
            miss.per_dof
        )
    }
}

/// What the slip search `validate` runs says of the misses of the file's own validation poses
/// (read from `data`): the slips whose undoing makes every test pass, in
/// `validate`'s words, or, when none does, the causes left: a slip of the whole file the
/// calibration has taken into its geometry from the axis experiments too, the description, or
/// an effect the model lacks (a joint's compliance: `diagnose` models it); with the tool frame fitted
/// to the poses (the search not run), what to check.
fn own_poses_slips(slips: &OwnPosesSlips, data: &Path) -> String {
    match slips {
        OwnPosesSlips::Unsearched { rows } => {
            let words = checks::unsearched_words(*rows, data);
            format!("{words} (`axiscal validate` on a part of the file runs it)")
        }
        OwnPosesSlips::Named(named) => {
            let said: Vec<String> = named.iter().map(|m| checks::explained_miss_words(m, data)).collect();
            format!("`axiscal validate`'s slip search names it: {}", said.join("; "))
        }
        // The nominal tool frame's error would be read as a slip of the coordinates.
        OwnPosesSlips::ToolFitted => "check one experiment's commands or coordinates for a scale or offset the unit checks cannot tell (e.g. gradians), the description's \
             placement and lengths, or an effect the model lacks (`axiscal validate`, `axiscal diagnose` on this file)"
            .to_string(),
        OwnPosesSlips::NoneNamed => "no slip `axiscal validate` tests (a command column scaled or offset, one coordinate column or all three scaled, the \
                coordinates shifted; over these poses or a run of them, one or two at once) makes them pass against this calibration: \
                a slip the axis experiments carry as well, which the calibration has taken into its geometry (see the warnings above, or \
                check each column for a scale or offset throughout the file, e.g. gradians), the description's placement and lengths, or \
                an effect the model lacks, such as joints yielding under the load (`axiscal diagnose` on this file models it)"
            .to_string(),
    }
}

/// What a move of the nominal tool frame that fits the validation poses beyond a description's
/// error says ([`axiscal::diagnosis::ToolMoveBeyond`]): the poses then miss by more than the
/// unmeasured tool frame's error, e.g. along an axis the sweeps cannot place (a SCARA's height).
fn tool_move_words(m: ToolMoveBeyond) -> String {
    format!(
        "; the tool frame would have to move {:.1} mm and turn {:.2} deg from the description's to fit them, beyond a description's error \
         ({:.1} mm, {:.0} % of its longest length; {:.0} deg): the poses are off by more than the unmeasured tool frame explains",
        m.moved_mm,
        m.turned_rad.to_degrees(),
        m.bound_mm,
        SIZE_TOLERANCE * 100.0,
        PLAUSIBLE_AXIS_TILT_RAD.to_degrees()
    )
}

/// The first cause of a miss of the validation poses when `--repeatability-rad` (`stated`) is
/// 0 or below the description's `repeatability_sigma` for some joint: the prediction then
/// leaves out the joints' own scatter. Empty otherwise.
fn understated_repeatability(desc: &RobotDescription, stated: Option<&[f64]>) -> String {
    let Some(stated) = stated else { return String::new() };
    let of_joint = |k: usize| if stated.len() == 1 { stated[0] } else { stated[k] };
    // `--repeatability-rad` holds 1 or one value per joint (checked before calibrating).
    let joints = if stated.len() == 1 {
        desc.dof()
    } else {
        stated.len().min(desc.dof())
    };
    let low = (0..joints).find(|&k| of_joint(k) <= 0.0 || of_joint(k) < desc.joints[k].repeatability_sigma);
    let Some(k) = low else { return String::new() };
    let unit = if desc.joints[k].kind == axiscal::kinematics::JointKind::Revolute {
        "rad"
    } else {
        "m"
    };
    let values: Vec<String> = stated.iter().map(|v| format_f64(*v)).collect();
    format!(
        "the stated repeatability (--repeatability-rad {}: joint {} at {} {unit}, the description's repeatability_sigma \
         {} {unit}) leaves the joints' own scatter out of the prediction: drop --repeatability-rad or give the \
         joints' real repeatability; else ",
        values.join(","),
        k + 1,
        format_f64(of_joint(k)),
        format_f64(desc.joints[k].repeatability_sigma)
    )
}

/// The console summary of an independent-axis calibration and its predicted tool accuracy.
fn print_axes(
    (cal, accuracy): (&Calibration, Option<&ToolAccuracy>),
    desc: &RobotDescription,
    source: &str,
    printer: Printer,
) {
    say!(
        printer,
        "calibrated {} from {} ({} axes)",
        desc.name,
        source,
        cal.axes.len()
    );
    print_scope(cal, desc, printer);
    say!(
        printer,
        "  joint  points  span (deg|mm)  residual RMS (mm)  direction 1-sigma (mrad)"
    );
    for a in &cal.axes {
        let unit = a.span.unit();
        let sigma = a.direction_sigma.major_rad * 1e3;
        // The paper's estimator gives its line no covariance: said, not printed as NaN.
        let sigma = if sigma.is_finite() {
            format!("{sigma:.4}")
        } else {
            "none (paper)".to_owned()
        };
        say!(
            printer,
            "  {:>5}  {:>6}  {:>9.1} {:<3}  {:>17.4}  {:>24}",
            a.joint,
            a.points,
            a.span.value(),
            unit,
            a.residual_rms_mm,
            sigma
        );
    }
    print_tool_accuracy(accuracy, printer);
    if cal.options.estimator == AxisEstimator::Paper {
        say!(
            printer,
            "  no sigmas: the paper's estimator (eqs. 1-8) gives its axes no covariance, so no row, zero-offset or tool \
             sigma and no predicted tool accuracy is computed (null or absent in calibration.json); `--estimator ml` gives them"
        );
    }
}

/// The predicted tool 1-sigma line, when there is one.
pub(super) fn print_tool_accuracy(accuracy: Option<&ToolAccuracy>, printer: Printer) {
    if let Some(a) = accuracy {
        say!(
            printer,
            "  predicted tool 1-sigma: inside the spans RMS {:.3} mm / {:.3} mrad (max {:.3} mm), workspace RMS {:.3} mm / {:.3} mrad (max {:.3} mm)",
            a.spans.position_rms_mm,
            a.spans.orientation_rms_mrad,
            a.spans.position_max_mm,
            a.workspace.position_rms_mm,
            a.workspace.orientation_rms_mrad,
            a.workspace.position_max_mm
        );
    }
}

/// The tool accuracy of `cal` inside the spans of `set`'s sweeps and over the joint limits
/// ([`tool_accuracy`]).
fn predict_tool_accuracy(
    cal: &Calibration,
    desc: &RobotDescription,
    set: &MeasurementSet,
    held_tolerance: f64,
) -> Result<(Option<ToolAccuracy>, Vec<MapPoint>)> {
    let (experiments, _) = axis_experiments_with(set, desc, held_tolerance)?;
    let spans = swept_ranges(&experiments, &cal.reference_cmd);
    Ok(tool_accuracy(cal, desc, spans))
}

/// The tool accuracy of a free-pose calibration ([`tool_accuracy`]): "inside the spans" is
/// within the range of every joint's values over the rows of `set`.
fn predict_free_pose_accuracy(
    cal: &Calibration,
    desc: &RobotDescription,
    set: &MeasurementSet,
) -> (Option<ToolAccuracy>, Vec<MapPoint>) {
    let spans = (0..desc.dof())
        .map(|k| {
            set.rows()
                .iter()
                .map(|r| r.cmd[k])
                .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], v| [lo.min(v), hi.max(v)])
        })
        .collect();
    tool_accuracy(cal, desc, spans)
}

/// The tool accuracy of `cal` predicted over `spans` and the workspace, with the workspace
/// poses for the map (neither without a model covariance).
fn tool_accuracy(
    cal: &Calibration,
    desc: &RobotDescription,
    spans: Vec<[f64; 2]>,
) -> (Option<ToolAccuracy>, Vec<MapPoint>) {
    // The calibration stands without its prediction: a model that cannot execute some drawn
    // pose (a fitted transmission not invertible beyond the data's range) is said, not fatal.
    match predict(cal, desc, spans, PredictionOptions::default()) {
        Ok(Some((accuracy, map))) => (Some(accuracy), map),
        Ok(None) => (None, vec![]),
        Err(e) => {
            eprintln!("warning: the tool accuracy is not predicted: {e}");
            (None, vec![])
        }
    }
}

/// With `--refine`, enough free poses in `set` for its folds, said before any calibration.
fn check_refine_poses(args: &Args, set: &MeasurementSet, desc: &RobotDescription) -> Result<()> {
    if args.refine {
        let (poses, _) = validation_poses_at_most(set.rows(), desc, max_poses(args));
        enough_free_poses(poses.len(), args.refine_folds as usize)
            .map_err(|e| anyhow::anyhow!("--refine on {}: {e}", args.data.display()))?;
    }
    Ok(())
}

/// `cal` refined on the free poses of `set` (`--refine`) and the refinement, its summary
/// printed.
fn refine(
    args: &Args,
    set: &MeasurementSet,
    desc: &RobotDescription,
    cal: &Calibration,
    printer: Printer,
) -> Result<(Calibration, Refinement)> {
    let options = RefineOptions {
        noise_rms_3d_mm: cal
            .noise
            .as_ref()
            .map_or(cal.options.noise_rms_3d_mm, |n| n.used_rms_3d_mm),
        folds: args.refine_folds as usize,
        max_poses: max_poses(args),
        keep_outliers: args.keep_outliers,
        ..RefineOptions::default()
    };
    let carried = match &args.carry {
        Some(path) => carried_effects(path, desc, set)?,
        None => Vec::new(),
    };
    let (refined, r) = refine_carrying(set, desc, cal, &options, &carried)
        .map_err(|e| anyhow::anyhow!("--refine on {}: {e}", args.data.display()))?;
    print_refinement(&r, (set, &args.data), &carried, printer)?;
    Ok((refined, r))
}

/// The console lines of a refinement `r` of the free poses of `set` (read from `data`); an
/// error when its result is implausible.
fn print_refinement(
    r: &Refinement,
    (set, data): (&MeasurementSet, &Path),
    carried: &[Candidate],
    printer: Printer,
) -> Result<()> {
    say!(
        printer,
        "refined on {} free poses: rank {} of {} parameters ({} directions dropped), RMS {:.4} -> {:.4} mm (noise alone {:.4} mm); {}-fold held-out RMS {:.4} -> {:.4} mm",
        r.poses,
        r.rank,
        r.parameters,
        r.dropped.len(),
        r.rms_before_mm,
        r.rms_after_mm,
        r.expected_rms_after_mm,
        r.folds.len(),
        r.heldout_rms_before_mm,
        r.heldout_rms_after_mm
    );
    if r.poses_left_out > 0 {
        say!(
            printer,
            "  refined on {} of the file's {} free poses, evenly spaced through it (`--max-poses`; memory grows with them)",
            r.poses,
            r.poses + r.poses_left_out
        );
    }
    if !r.converged {
        eprintln!("warning: --refine: the Gauss-Newton steps reached their limit without converging");
    }
    checks::print_pose_outliers(&r.outliers, set, data, "refined");
    if let Some(why) = r.implausible() {
        anyhow::bail!(
            "--refine on {}: {why}; nothing written (without --refine the axis calibration stands)",
            data.display()
        );
    }
    print_carried(carried, r, printer);
    Ok(())
}

/// The effects the diagnosis in `path` names, as candidates a model carries (`--carry`).
fn carried_effects(path: &Path, desc: &RobotDescription, set: &MeasurementSet) -> Result<Vec<Candidate>> {
    let text = axiscal::presets::read_text(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let mode: Option<serde_json::Value> = serde_json::from_str(&text).ok();
    if mode.as_ref().and_then(|v| v.get("mode")).and_then(|m| m.as_str()) == Some("axes_only") {
        anyhow::bail!(
            "--carry {}: an axes-only diagnosis (no validation poses) names no effect: nothing to carry",
            path.display()
        );
    }
    let d: Diagnosis = json_file::from_str(Schema::DIAGNOSIS, &text).with_context(|| {
        format!(
            "{}: not a diagnosis JSON (`axiscal diagnose` writes one)",
            path.display()
        )
    })?;
    carried_candidates(&d, desc, set).map_err(|e| anyhow::anyhow!("--carry {}: {e}", path.display()))
}

/// The console lines of the effects `--carry` fitted: each parameter with its sigma, and the
/// warning that only `calibration.json` carries them.
fn print_carried(carried: &[Candidate], r: &Refinement, printer: Printer) {
    if carried.is_empty() {
        return;
    }
    let names: Vec<String> = carried
        .iter()
        .map(|c| match c.joint() {
            Some(j) => format!("{} on joint {j} ({})", c.effect_name(), c.member_name()),
            None => format!("{} ({})", c.effect_name(), c.member_name()),
        })
        .collect();
    say!(printer, "  carried: {}", names.join("; "));
    for p in r
        .changes
        .iter()
        .filter(|p| carried.iter().any(|c| p.name.contains(c.effect_name())))
    {
        say!(printer, "    {} = {:.4e} +- {:.2e}", p.name, p.change, p.refined_sigma);
    }
    eprintln!(
        "warning: the model carries {} (calibration.json robot.effects and transmissions, used by validate and compensate); calibrated.urdf and joint_map.csv hold the geometry only",
        names.join("; ")
    );
}

/// A note where the sweeps of the joints fitted from several miss one another beyond the noise
/// their own fits show ([`sweeps_agreement`] below [`NOISE_TEST_LEVEL`]): the noise estimate
/// then holds the held joints' correction's model error.
fn print_sweeps_disagree(cal: &axiscal::calibration::procedure::Calibration) {
    use axiscal::calibration::noise::NOISE_TEST_LEVEL;
    use axiscal::calibration::procedure::sweeps_agreement;
    let Some(a) = sweeps_agreement(cal).filter(|a| a.p_value < NOISE_TEST_LEVEL) else {
        return;
    };
    let joints: Vec<String> = a.joints.iter().map(ToString::to_string).collect();
    eprintln!(
        "note: the sweeps of joint{} {} miss one another, once the held joints' correction has moved them to one pose, by \
         more than the noise each sweep's own fit shows: the joint fits' residuals are {:.4} mm RMS per coordinate \
         against {:.4} mm in the sweeps' own fits (F = {:.2} on {} and {} dof, p = {:.1e}); the calibrated model that \
         corrects them is that uncertain (longer sweeps locate its axes better), and the noise estimate, every \
         sigma and the coordinate-scale test count that model error as noise",
        if joints.len() == 1 { "" } else { "s" },
        joints.join(", "),
        a.rms_mm[1],
        a.rms_mm[0],
        a.variance_ratio,
        a.dof.0,
        a.dof.1,
        a.p_value
    );
}

/// The noise (estimated, used, contradicted), joints not calibrated, the base-frame rule.
fn print_scope(cal: &axiscal::calibration::procedure::Calibration, desc: &RobotDescription, printer: Printer) {
    if let Some(n) = &cal.noise {
        if let Some(e) = &n.estimate {
            say!(
                printer,
                "  noise from the residuals: {:.4} mm 3-D RMS ({:.0} % interval {:.4}-{:.4} mm, {} dof); fits weighted with {:.4} mm ({})",
                e.rms_3d_mm,
                e.confidence * 100.0,
                e.interval.low_mm,
                e.interval.high_mm,
                e.dof,
                n.used_rms_3d_mm,
                n.source
            );
            print_sweeps_disagree(cal);
        }
        if n.source == "default" && n.estimate.is_some() {
            let (joint, sigma) = desc
                .joints
                .iter()
                .enumerate()
                .map(|(k, j)| (k + 1, j.repeatability_sigma))
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap_or((0, 0.0));
            eprintln!(
                "warning: the residuals give no noise estimate above 0: the joints' repeatability (the description's repeatability_sigma, joint {joint}: {sigma} rad or m) explains all of their scatter; the fits keep the default {:.4} mm and every sigma follows the repeatability: check repeatability_sigma (radians for a turning joint, metres for a sliding one) or give --repeatability-rad",
                n.used_rms_3d_mm
            );
        }
        if n.given_contradicted {
            say!(
                printer,
                "  WARNING: the residuals contradict --noise-mm {:.4} (chi-square p = {:.2e}); see report.md",
                n.used_rms_3d_mm,
                n.given_p_value.unwrap_or(f64::NAN)
            );
        }
    }
    if !cal.not_calibrated.is_empty() {
        eprintln!(
            "warning: joints {:?} not calibrated (no axis experiment: kept nominal): their errors are in no predicted uncertainty; sweep them, or `axiscal validate` tests the model",
            cal.not_calibrated
        );
    }
    if let Some(b) = &cal.base_rule {
        say!(printer, "  base frame: {}", b.text);
    }
    if cal.tool.is_none() && !desc.tool.targets_mm.is_empty() {
        say!(
            printer,
            "  tool frame: nominal (no pose at the reference commands sees all three tool targets): its error is in no predicted uncertainty; `axiscal validate` tests it"
        );
    }
}
