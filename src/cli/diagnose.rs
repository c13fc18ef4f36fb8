//! `axiscal diagnose DATA.csv --robot R --out DIR`: sim-to-real gap diagnosis
//! (`docs/formats.md#diagnosis-json`), writing `diagnosis.json`, `diagnosis.md` and the plots
//! (`where.{png,svg}`; with validation poses also `candidates.{png,svg}`).

use super::checks;
use super::options::{InRange, NOISE_MM};
use super::output::Outputs;
use super::printer::Printer;
use anyhow::{Context, Result};
use axiscal::calibration::procedure::{
    Calibration, CalibrationOptions, ProcedureError, calibrate, implausible, screen_sweeps,
};
use axiscal::diagnosis::{
    AXES_PLOT_FILES, DiagnosisError, DiagnosisOptions, PLOT_FILES, PlotError, RefitScope, SweepSearch,
    ValidationOptions, axes_markdown, combined_slips_searched, diagnose_axes_with, diagnose_with, estimated_noise,
    free_pose_misses, free_poses_only, markdown, own_sweep_misses, shifted_validation_block, validate,
    validation_outliers, validation_poses, without_outliers, write_axes_plots, write_plots,
};
use axiscal::json_file::{self, Schema};
use axiscal::measurement::MeasurementSet;
use axiscal::robot::RobotDescription;
use std::borrow::Cow;
use std::path::{Path, PathBuf};

/// Arguments of `axiscal diagnose`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Measurement CSV (`docs/formats.md#measurement-csv`): axis experiments plus validation
    /// poses, or free poses only (calibrated from the even poses, diagnosed on the odd ones).
    data: PathBuf,
    /// Nominal robot description (TOML).
    #[arg(long, default_value = "asea-irb6l", value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Measurement noise of a point, 3-D RMS (mm) (default: estimated from the axis
    /// experiments' residuals, as `calibrate` does without it; required for free poses only).
    #[arg(long, value_parser = NOISE_MM)]
    noise_mm: Option<f64>,
    /// Noise-only replicas of the campaign (each recalibrated).
    #[arg(long, default_value_t = DiagnosisOptions::default().noise_trials, value_parser = InRange::closed(2usize, 100_000, ""))]
    noise_trials: usize,
    /// Validation-noise draws per replica.
    #[arg(long, default_value_t = DiagnosisOptions::default().noise_draws, value_parser = InRange::closed(1usize, 10_000, ""))]
    noise_draws: usize,
    /// What the baseline refit adjusts besides the geometry: `identified` (also the fitted
    /// transmission harmonics and coupling slopes) or `geometry`.
    #[arg(long, value_enum, default_value = "identified")]
    refit: Refit,
    /// False-alarm rate of the gap and candidate tests.
    #[arg(long, default_value_t = DiagnosisOptions::default().false_alarm, value_parser = InRange::above(0.0, 0.5, ""))]
    false_alarm: f64,
    /// Noise-only replicas of the axis-experiments-only mode (data without validation poses).
    #[arg(long, default_value_t = DiagnosisOptions::default().axis_replicas, value_parser = InRange::closed(2usize, 1_000_000, ""))]
    axis_replicas: usize,
    /// Score with the description's tool targets as they are, not refined from the
    /// validation poses (the refinement and its warning still run).
    #[arg(long)]
    nominal_tool_targets: bool,
    /// Flag the sweep points and validation points the outlier tests reject but keep them
    /// (`docs/diagnosis.md`, "Outliers").
    #[arg(long)]
    keep_outliers: bool,
    /// Seed of the replicas' noise.
    #[arg(long, value_parser = super::options::SEED, default_value_t = 0)]
    seed: u64,
    /// Validation poses diagnosed at most, evenly spaced through the file: memory grows with
    /// them (about 0.4 MB each at the default replicas and draws).
    #[arg(long, default_value_t = DiagnosisOptions::default().max_poses, value_parser = InRange::closed(4usize, 1_000_000, ""))]
    max_poses: usize,
    /// Print `diagnosis.json` on stdout (the human-readable lines go to stderr, or nowhere with `--quiet`).
    #[arg(long)]
    json: bool,
    /// Replace existing output files.
    #[arg(long)]
    force: bool,
    /// Also write a rerun recording: the data with their fitted arcs and residual vectors,
    /// the nominal and the calibrated robot side by side at every pose, the validation errors,
    /// the verdict in the notes. View it with `axiscal view FILE.rrd`. Needs a build with
    /// `--features viz`.
    #[arg(long, value_name = "FILE.rrd")]
    record: Option<PathBuf>,
    #[command(flatten)]
    checks: checks::Overrides,
}

/// The `--refit` choices ([`RefitScope`]).
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum Refit {
    Identified,
    Geometry,
}

/// The outputs of a run with `args`: its inputs never replaced, files replaced only with
/// `--force`.
fn outputs_of(args: &Args) -> Outputs {
    Outputs::new(args.force)
        .input("DATA", &args.data)
        .input("--robot", &args.robot)
}

/// Runs `axiscal diagnose`.
pub fn run(args: Args, printer: Printer) -> Result<()> {
    let printer = printer.with_json(args.json);
    let outputs = outputs_of(&args);
    super::record::ensure_recordable(args.record.as_deref(), &outputs)?;
    let desc = RobotDescription::from_file(&args.robot)?;
    checks::description_units(&desc, &args.robot, args.checks.skip_unit_check)?;
    let set = checks::read_data(&args.data, &desc, &args.robot, args.checks)?;
    checks::one_setup(&set, &args.data, "diagnose")?;
    let (set, cal) = usable(set, &desc, &args.data, args.noise_mm);
    if let Some(cal) = cal.as_ref().filter(|_| !args.checks.skip_unit_check) {
        refuse_data_slips(&args, &set, cal, &desc)?;
    }
    // The rows as read: the test of the file's own validation poses reads them, once the
    // diagnosis has said whether it needs it.
    let read = set;
    let screened = without_sweep_outliers(&args, &read, &desc)?;
    let set = screened.as_ref().unwrap_or(&read);
    let (noise_mm, noise_source, noise_dof) = noise(&args, set, &desc, printer)?;
    let options = diagnosis_options(&args, noise_mm, noise_dof);
    let source = args.data.display().to_string();
    // Fewer than 4 validation poses cannot be split into training and held-out halves of 2+.
    if validation_poses(set.rows(), &desc).len() < 4 {
        return run_axes(&args, &desc, set, &options, &outputs, noise_source, printer);
    }
    let outliers =
        validation_outliers(set, &desc, &options, args.keep_outliers).map_err(|e| failed(&args, set, &desc, e))?;
    checks::print_outliers(&outliers, &args.data, "diagnosed");
    let set = match args.keep_outliers || outliers.is_empty() {
        true => Cow::Borrowed(set),
        false => Cow::Owned(without_outliers(set, &outliers)),
    };
    let block = cal
        .as_ref()
        .and_then(|cal| shifted_block_warning(&args, &set, cal, &desc));
    if let Some(w) = &block {
        eprintln!("warning: {w}");
    }
    let progress = super::progress::Progress::stage("diagnosing", printer);
    let mut d = diagnose_with(&set, &desc, &options, &progress).map_err(|e| failed(&args, &set, &desc, e))?;
    d.noise_source = noise_source.into();
    d.outliers = outliers;
    d.warnings = block.into_iter().collect();
    drop(progress);
    if let Some(warning) = d.tool_targets.as_ref().and_then(|t| t.warning()) {
        eprintln!("warning: {warning}");
    }
    if d.outcome.effect == "none" {
        print_own_miss(
            cal.as_ref()
                .and_then(|cal| own_poses_miss(cal, &desc, &read, &args.data)),
        );
    }
    let report = Report {
        out: &args.out,
        json: json_file::to_string(Schema::DIAGNOSIS, &d)?,
        markdown: markdown(&d, &source),
        plot_files: &PLOT_FILES,
        outputs: &outputs,
    };
    let written = report.write(|dir| write_plots(&d, dir))?;
    let headline = format!(
        "{}{}{} (confidence {:.2}): gap {:.3} -> {:.3} mm",
        d.outcome.effect,
        d.outcome.joint.map_or(String::new(), |j| format!(" joint {j}")),
        d.member.as_ref().map_or(String::new(), |m| format!(", {m}")),
        d.outcome.confidence,
        d.outcome.gap_before_mm,
        d.outcome.gap_after_mm
    );
    say!(printer, "{headline}");
    let diagnosed = d.poses.training + d.poses.held_out;
    if d.poses.left_out > 0 {
        say!(
            printer,
            "  diagnosed {diagnosed} of the file's {} validation poses, evenly spaced through it (`--max-poses`; memory grows with them)",
            diagnosed + d.poses.left_out
        );
    }
    if d.outcome.effect == "none" {
        say!(
            printer,
            "  with {diagnosed} validation poses ({} held out) the smallest gap this test flags is {:.3} mm; a smaller effect \
             reads `none`: {} to resolve it",
            d.poses.held_out,
            d.detectable_gap_mm,
            if d.poses.left_out > 0 {
                "diagnose more of them (`--max-poses`)"
            } else {
                "measure more validation poses"
            }
        );
    }
    say!(printer, "wrote {written}");
    printer.emit_json(&args.out.join("diagnosis.json"))?;
    record(&args, &desc, &set, noise_mm, &format!("{headline}. {}", d.verdict))
}

/// The diagnosis's options from the arguments, at noise `noise_mm` (3-D RMS) estimated with
/// `noise_dof` degrees of freedom (`None` when given).
fn diagnosis_options(args: &Args, noise_mm: f64, noise_dof: Option<f64>) -> DiagnosisOptions {
    DiagnosisOptions {
        noise_rms_3d_mm: noise_mm,
        noise_trials: args.noise_trials,
        noise_draws: args.noise_draws,
        false_alarm: args.false_alarm,
        refit: match args.refit {
            Refit::Identified => RefitScope::Identified,
            Refit::Geometry => RefitScope::Geometry,
        },
        seed: args.seed,
        axis_replicas: args.axis_replicas,
        refine_tool_targets: !args.nominal_tool_targets,
        noise_dof,
        max_poses: args.max_poses,
        ..DiagnosisOptions::default()
    }
}

/// What `calibrate` warns of the file's own validation poses (`set`, read from `data`) against
/// `cal`, the calibration of its sweeps, with the file named: a miss beyond the prediction.
fn own_poses_miss(cal: &Calibration, desc: &RobotDescription, set: &MeasurementSet, data: &Path) -> Option<String> {
    // A held offset the miss names starts with the file and the sweep's line already.
    let file = data.display().to_string();
    super::calibrate::misses_own_validation_poses(cal, (desc, set, data), (None, SweepSearch::Run, false)).map(|own| {
        let miss = own.text;
        match miss.starts_with(&format!("{file}:")) {
            true => miss,
            false => format!("{file}: {miss}"),
        }
    })
}

/// Prints `miss` ([`own_poses_miss`]) as a warning, where the diagnosis's effect is `none` (its
/// caller tests it first: the test seeks a sweep's cause, a calibration per trial): its refit on
/// the training poses takes in what every validation pose shares (one command column offset in
/// all of them), and the gap it tests is then gone.
fn print_own_miss(miss: Option<String>) {
    if let Some(miss) = miss {
        eprintln!(
            "warning: {miss}; no effect the diagnosis models explains it (it reads `none`: its refit on the training \
             poses takes in what all validation poses share)"
        );
    }
}

/// The warning of a block of `set`'s validation poses shifted in file order against `cal` (the
/// calibration of its sweeps), as `validate` names it ([`shifted_validation_block`]): the
/// diagnosis would read the step between two setups as an effect. `None` when there is none,
/// or the file is beyond the slip search's size.
fn shifted_block_warning(
    args: &Args,
    set: &MeasurementSet,
    cal: &Calibration,
    desc: &RobotDescription,
) -> Option<String> {
    if !combined_slips_searched(set) {
        return None;
    }
    let options = ValidationOptions::given_or_of_calibration(args.noise_mm, cal, args.false_alarm);
    let v = validate(set, cal, desc, &options).ok()?;
    let b = shifted_validation_block(set, cal, desc, &v).ok()??;
    let mixed = "the diagnosis below mixes two setups and may name the step between them as an effect: diagnose \
                 those rows apart from the others";
    Some(format!(
        "{}: {}",
        args.data.display(),
        super::validate::block_words(&b, mixed)
    ))
}

/// Refuses the data when a slip explains the miss of `cal` (the calibration of `set`'s sweeps):
/// a slip in one sweep first ([`own_sweep_misses`]: its calibration absorbed it, the free poses
/// show it), then one in the free poses themselves ([`free_pose_misses`]); either is the data's,
/// not an effect to rank.
fn refuse_data_slips(args: &Args, set: &MeasurementSet, cal: &Calibration, desc: &RobotDescription) -> Result<()> {
    let mut misses = own_sweep_misses(set, cal, desc, args.false_alarm);
    if misses.is_empty() {
        misses = free_pose_misses(set, cal, desc, args.false_alarm)
            .map_err(|e| anyhow::anyhow!("{}: the validation poses: {e}", args.data.display()))?;
    }
    checks::refuse_explained_misses(&misses, &args.data, false)
}

/// `axiscal diagnose` on a campaign without validation poses: the axis experiments only.
fn run_axes(
    args: &Args,
    desc: &RobotDescription,
    set: &MeasurementSet,
    options: &DiagnosisOptions,
    outputs: &Outputs,
    noise_source: &str,
    printer: Printer,
) -> Result<()> {
    let source = args.data.display().to_string();
    let progress = super::progress::Progress::stage("diagnosing the axes", printer);
    let d = diagnose_axes_with(set, desc, options, &progress).map_err(|e| failed(args, set, desc, e))?;
    drop(progress);
    let report = Report {
        out: &args.out,
        json: json_file::to_string(Schema::DIAGNOSIS, &d)?,
        markdown: axes_markdown(&d, &source),
        plot_files: &AXES_PLOT_FILES,
        outputs,
    };
    let written = report.write(|dir| write_axes_plots(&d, dir))?;
    say!(
        printer,
        "no validation poses: axis experiments only (`where`; `which` needs validation poses)"
    );
    if noise_source == "estimated" {
        say!(
            printer,
            "  the noise was estimated from these same arcs: only an axis far worse than the others can be flagged; \
             give --noise-mm for a test against the instrument's noise"
        );
    }
    for w in &d.where_ {
        say!(
            printer,
            "  {:<10} joint {}  residual {:.4} mm  noise only {:.4} mm  ratio {:.2}{}",
            w.experiment,
            w.joint.map_or("-".into(), |j| j.to_string()),
            w.residual_rms_mm,
            w.noise_only_rms_mm,
            w.excess_ratio,
            if d.flagged.iter().any(|f| f.experiment == w.experiment) {
                "  beyond noise"
            } else {
                ""
            }
        );
    }
    say!(printer, "{}: {}", d.outcome.effect, d.verdict);
    say!(printer, "wrote {written}");
    printer.emit_json(&args.out.join("diagnosis.json"))?;
    record(
        args,
        desc,
        set,
        options.noise_rms_3d_mm,
        &format!("{}: {}", d.outcome.effect, d.verdict),
    )
}

/// The diagnosis of `set` failed with `e`: when its calibration failed with a `--noise-mm` far
/// below the noise of the data's axis experiments, what `calibrate` says of that value
/// ([`checks::noise_far_below`]), else `e`, each naming DATA.
fn failed(args: &Args, set: &MeasurementSet, desc: &RobotDescription, e: DiagnosisError) -> anyhow::Error {
    let too_small = match (&e, args.noise_mm) {
        (DiagnosisError::Calibration(failure), Some(given_mm)) => {
            let options = CalibrationOptions {
                noise_rms_3d_mm: given_mm,
                ..CalibrationOptions::default()
            };
            checks::noise_far_below(set, desc, &options, given_mm, failure.joint(), ["the fits", "it"])
        }
        _ => None,
    };
    match too_small {
        Some(message) => anyhow::anyhow!("diagnosing {}: {message}", args.data.display()),
        None => anyhow::Error::new(e).context(format!("diagnosing {}", args.data.display())),
    }
}

/// `set` without the sweep points the outlier test flags ([`screen_sweeps`], as `calibrate`
/// tests them; kept with `--keep-outliers`), each said on stderr; `None` where it drops none.
fn without_sweep_outliers(
    args: &Args,
    set: &MeasurementSet,
    desc: &RobotDescription,
) -> Result<Option<MeasurementSet>> {
    if free_poses_only(set) {
        return Ok(None);
    }
    let options = CalibrationOptions {
        noise_rms_3d_mm: args.noise_mm.unwrap_or(CalibrationOptions::default().noise_rms_3d_mm),
        ..CalibrationOptions::default()
    };
    let screening = screen_sweeps(set, desc, &options, args.keep_outliers)
        .map_err(|e| failed(args, set, desc, DiagnosisError::Calibration(e)))?;
    super::checks::print_outliers(&screening.outliers, &args.data, "diagnosed");
    super::checks::print_sweep_bumps(&screening.bumps, &args.data);
    Ok(screening.set)
}

/// `set`, or, when the independent-axis procedure cannot use its sweeps (the correction for
/// their held joints does not settle: sweeps at their own configurations), every row as a free
/// pose, as `calibrate` fits them, said on stderr; the calibration's implausible results (as
/// `calibrate` warns of them) are said too. With the calibration of `set`'s sweeps, when
/// they could be used, weighted as `calibrate` weights them (`noise_mm` when given, else the
/// noise their residuals estimate): the validation poses' slip search is made against it, and a
/// noise below the data's would make the search's test fail every rewrite.
fn usable(
    set: MeasurementSet,
    desc: &RobotDescription,
    data: &Path,
    noise_mm: Option<f64>,
) -> (MeasurementSet, Option<Calibration>) {
    if free_poses_only(&set) {
        return (set, None);
    }
    let options = CalibrationOptions {
        noise_rms_3d_mm: noise_mm.unwrap_or(CalibrationOptions::default().noise_rms_3d_mm),
        estimate_noise: noise_mm.is_none(),
        ..CalibrationOptions::default()
    };
    match calibrate(&set, desc, &options) {
        // What `calibrate` warns of (a mirrored frame, a flipped axis) the diagnosis cannot see.
        Ok(cal) => {
            for found in implausible(&cal, desc) {
                eprintln!("warning: {}: {found}", data.display());
            }
            (set, Some(cal))
        }
        Err(e @ (ProcedureError::HeldNotConverged { .. } | ProcedureError::HeldDiverged { .. })) => {
            eprintln!(
                "note: {}: {e}; every row is diagnosed as a free pose instead (as `calibrate` fits them)",
                data.display()
            );
            (set.every_row_a_free_pose(), None)
        }
        _ => (set, None),
    }
}

/// The noise of the diagnosis (mm), its source and, when estimated, the estimate's degrees of
/// freedom: `--noise-mm`, or the estimate from the axis experiments' residuals (said on stderr;
/// an error when the data cannot give one).
fn noise(
    args: &Args,
    set: &MeasurementSet,
    desc: &RobotDescription,
    printer: Printer,
) -> Result<(f64, &'static str, Option<f64>)> {
    if let Some(n) = args.noise_mm {
        return Ok((n, "given", None));
    }
    if free_poses_only(set) {
        anyhow::bail!(
            "{} is diagnosed from free poses only (no usable axis experiment): their residuals cannot tell the instrument's noise from the model error the diagnosis looks for; give --noise-mm (the instrument's figure, 3-D RMS of a point)",
            args.data.display()
        );
    }
    let e = estimated_noise(set, desc)
        .with_context(|| format!("estimating the noise of {}", args.data.display()))?
        .filter(|e| e.rms_3d_mm > 0.0)
        .ok_or_else(|| {
            anyhow::anyhow!(
                "{}: the axis experiments leave no residual to estimate the noise from; give --noise-mm",
                args.data.display()
            )
        })?;
    say!(
        printer,
        "noise estimated from the axis experiments' residuals: {:.4} mm 3-D RMS ({:.0} % interval {:.4}-{:.4} mm, \
         {} dof, repeatability share {:.0} %); give --noise-mm to use the instrument's own figure",
        e.rms_3d_mm,
        e.confidence * 100.0,
        e.interval.low_mm,
        e.interval.high_mm,
        e.dof,
        e.jitter_share * 100.0
    );
    Ok((e.rms_3d_mm, "estimated", Some(e.effective_dof)))
}

/// The `--record` recording of the diagnosed data (the standard calibration, weighted first
/// with the diagnosis's noise `noise_mm` and estimating it again when `--noise-mm` is not
/// given; the verdict in the notes); nothing without `--record`.
#[cfg_attr(not(feature = "viz"), allow(unused_variables))]
fn record(args: &Args, desc: &RobotDescription, set: &MeasurementSet, noise_mm: f64, verdict: &str) -> Result<()> {
    #[cfg(feature = "viz")]
    if let Some(path) = &args.record {
        let options = axiscal::calibration::procedure::CalibrationOptions {
            noise_rms_3d_mm: noise_mm,
            estimate_noise: args.noise_mm.is_none(),
            ..Default::default()
        };
        let calibration = axiscal::calibration::procedure::calibrate(set, desc, &options)
            .map_err(|e| anyhow::anyhow!("calibrating {} for the recording: {e}", args.data.display()))?;
        let campaign = super::record::calibrated::CalibratedCampaign {
            desc,
            set,
            calibration: &calibration,
            verdict: Some(verdict),
        };
        super::record::save(path, &outputs_of(args), || {
            super::record::calibrated::write_calibrated(&campaign)
        })?;
    }
    Ok(())
}

/// A diagnosis report's files.
struct Report<'a> {
    out: &'a Path,
    json: String,
    markdown: String,
    /// The files the plots write.
    plot_files: &'a [&'a str],
    outputs: &'a Outputs,
}

impl Report<'_> {
    /// Writes `diagnosis.json`, `diagnosis.md` and, by `plot`, the plots into `out` as one set
    /// (none put in place before all are written), refusing to replace any of them without
    /// `force`; returns `out/{files}` for the user.
    fn write(self, plot: impl FnOnce(&Path) -> Result<Vec<PathBuf>, PlotError>) -> Result<String> {
        let names = ["diagnosis.json", "diagnosis.md"];
        super::output::Outputs::create_folder(self.out)?;
        let all: Vec<&str> = names.iter().chain(self.plot_files).copied().collect();
        // Every file a diagnosis may write: an earlier run's plots this one does not draw
        // (an axes-only diagnosis has no candidates) are removed with the set, not left beside it.
        let any: Vec<&str> = names.iter().chain(&PLOT_FILES).copied().collect();
        self.outputs.check_in(self.out, &any)?;
        let mut staged = self.outputs.staged_in(self.out)?;
        staged.write(names[0], &self.json)?;
        staged.write(names[1], &self.markdown)?;
        staged.draw(self.plot_files, plot)?;
        staged.commit(&any)?;
        Ok(format!("{}/{{{}}}", self.out.display(), all.join(",")))
    }
}
