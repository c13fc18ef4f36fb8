//! `axiscal validate --calibration CAL.json DATA.csv --out DIR`: every measured point of DATA
//! predicted by the calibration, written as `residuals.csv` and `summary.json`
//! (`docs/formats.md#validation-summary-json`).

use super::checks;
use super::options::{InRange, NOISE_MM};
use super::output::Outputs;
use anyhow::{Context, Result};
use axiscal::calibration::procedure::{Calibration, CalibrationOptions, ProcedureError, screen_sweeps};
use axiscal::diagnosis::{
    ChiSquare, PositionSummary, Prediction, Validation, ValidationOptions, validate, write_validation_residuals_csv,
};
use axiscal::diagnosis::{
    ValidationBlock, combined_slips_searched, explained_validation_misses, free_pose_outliers, free_poses_only,
    shifted_validation_block, without_outliers,
};
use axiscal::json_file::{self, Schema};
use axiscal::measurement::MeasurementSet;
use axiscal::robot::RobotDescription;
use std::path::PathBuf;

/// The files `validate` writes into its output folder.
const OUTPUTS: [&str; 2] = ["residuals.csv", "summary.json"];

/// Arguments of `axiscal validate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Measurement CSV (`docs/formats.md#measurement-csv`): validation poses, axis experiments
    /// or both, measured with the calibrated robot.
    data: PathBuf,
    /// The calibration (`calibration.json` written by `axiscal calibrate`).
    #[arg(long)]
    calibration: PathBuf,
    /// Nominal robot description (TOML) the calibration was made with, or a shipped robot's
    /// name (`asea-irb6l`).
    #[arg(long, default_value = "asea-irb6l", value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Measurement noise of a point, 3-D RMS (mm), of DATA's instrument. Default: the noise
    /// the calibration was weighted with (its estimate from the residuals, or its `--noise-mm`).
    #[arg(long, value_parser = NOISE_MM)]
    noise_mm: Option<f64>,
    /// Two-sided false-alarm rate of the chi-square verdicts.
    #[arg(long, default_value_t = 0.01, value_parser = InRange::above(0.0, 0.5, ""))]
    false_alarm: f64,
    /// Keep the points the outlier tests flag in the tests: the axis experiments' points (tested
    /// as `calibrate` tests them) and the free-pose points (each is said on stderr either way).
    #[arg(long)]
    keep_outliers: bool,
    /// Replace existing output files.
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    checks: checks::Overrides,
}

/// Runs `axiscal validate`.
pub fn run(args: Args) -> Result<()> {
    let outputs = Outputs::new(args.force)
        .input("--calibration", &args.calibration)
        .input("DATA", &args.data)
        .input("--robot", &args.robot);
    outputs.check_not_folder_of(&args.out, "--calibration")?;
    outputs.check_in(&args.out, &OUTPUTS)?;
    let desc = RobotDescription::from_file(&args.robot)?;
    checks::description_units(&desc, &args.robot, args.checks.skip_unit_check)?;
    let (record, identity) =
        checks::read_calibration_warned(&args.calibration, &desc, &args.robot, args.checks.allow_other_robot)?;
    let (set, mut warnings) = checks::read_data_warned(&args.data, &desc, &args.robot, args.checks)?;
    warnings.splice(0..0, identity);
    checks::print_warnings(&warnings);
    checks::one_setup(&set, &args.data, "validate")?;
    // A free-pose calibration fitted the targets the description may not give.
    let fitted = axiscal::calibration::free_pose::with_fitted_targets(&desc, record.reports.free_poses.as_ref());
    let cal = record.calibration;
    let options = ValidationOptions::given_or_of_calibration(args.noise_mm, &cal, args.false_alarm);
    let validating = || format!("validating on {}", args.data.display());
    let (set, flagged) = without_sweep_outliers(&args, set, &desc, &cal, &options)?;
    checks::print_warnings(&flagged);
    warnings.extend(flagged);
    let v = validate(&set, &cal, &fitted, &options).with_context(validating)?;
    let misses = explained_validation_misses(&set, &cal, &fitted, &v);
    checks::refuse_explained_misses(&misses, &args.data, args.checks.skip_unit_check)?;
    if misses.is_empty() && v.exceeds(false) && !combined_slips_searched(&set) {
        let note = format!(
            "{} (validate a part of the file, e.g. one session's rows, to run it)",
            checks::unsearched_words(set.rows().len(), &args.data)
        );
        eprintln!("note: {note}");
        warnings.push(note);
    }
    let outliers = free_pose_outliers(&v, &set, (&cal, &fitted), args.keep_outliers).with_context(validating)?;
    let flagged = checks::outlier_warnings(&outliers, &args.data, "validated");
    checks::print_warnings(&flagged);
    warnings.extend(flagged);
    let (set, v) = match args.keep_outliers || outliers.is_empty() {
        true => (set, v),
        false => {
            // The first pass's residuals and the full set are let go before the second pass:
            // held to the end they doubled the peak memory of a 1 M-row file.
            drop(v);
            let kept = without_outliers(&set, &outliers);
            drop(set);
            let v = validate(&kept, &cal, &fitted, &options).with_context(validating)?;
            (kept, v)
        }
    };
    if let Some(b) = shifted_validation_block(&set, &cal, &fitted, &v).ok().flatten() {
        let mixed = "the verdicts below mix two setups: validate those rows apart from the others";
        let words = format!("{}: {}", args.data.display(), block_words(&b, mixed));
        eprintln!("warning: {words}");
        warnings.push(words);
    }
    noise_not_far_below(&args, &set, &desc, &v)?;
    drop(set);
    let v = Validation { warnings, ..v };
    let mut staged = outputs.staged_in(&args.out)?;
    staged.write_with(OUTPUTS[0], |file| write_validation_residuals_csv(&v, file))?;
    staged.write(OUTPUTS[1], json_file::to_string(Schema::VALIDATION, &v)?)?;
    staged.commit(&[])?;
    print_summary(&v);
    println!("wrote {}/{{{}}}", args.out.display(), OUTPUTS.join(","));
    Ok(())
}

/// `set` without the axis experiments' points the outlier test flags, as `calibrate` and
/// `diagnose` test them ([`screen_sweeps`], weighted with the noise of `options`, with the
/// calibration's other options), unless `--keep-outliers`; with the warning lines naming each
/// one's file line. A gross error in one sweep row would otherwise be a "model miss" of the axis
/// experiments and inflate their predicted repeatability (its target's mean position moves
/// off the link); with `--keep-outliers` the same points are flagged and kept. Files without
/// sweeps, and sweeps the procedure could not fit, are left as they are; a sweep with more points beyond the fence than
/// [`axiscal::calibration::procedure::OUTLIER_SHARE_MAX`], whose held joints leave the
/// calibration's held tolerance (a step's command shifted), whose swept command does not move
/// (`moved_joint` labels swapped, the tool rows labelled as a sweep) or that repeats another's
/// points is refused, as `calibrate` refuses it: validated, such rows would be blamed on the
/// model or pass with no test at all.
fn without_sweep_outliers(
    args: &Args,
    set: MeasurementSet,
    desc: &RobotDescription,
    cal: &Calibration,
    options: &ValidationOptions,
) -> Result<(MeasurementSet, Vec<String>)> {
    if free_poses_only(&set) {
        return Ok((set, Vec::new()));
    }
    let screening_options = CalibrationOptions {
        noise_rms_3d_mm: options.noise_rms_3d_mm,
        ..cal.options.clone()
    };
    // Screened as if dropped, so that `--keep-outliers` flags the same points (kept in a sweep's
    // refits they would hide its other outliers, nothing is refitted here) and keeps them.
    match screen_sweeps(&set, desc, &screening_options, false) {
        Ok(mut screening) => {
            if args.keep_outliers {
                screening.outliers.iter_mut().for_each(|o| o.dropped = false);
                screening.set = None;
            }
            let flagged = checks::outlier_warnings(&screening.outliers, &args.data, "validated");
            checks::print_approach_notes(&screening.outliers, &args.data, "validated");
            checks::print_sweep_bumps(&screening.bumps, &args.data);
            Ok((screening.set.unwrap_or(set), flagged))
        }
        Err(
            e @ (ProcedureError::TooManyOutliers { .. }
            | ProcedureError::InconsistentCommands { .. }
            | ProcedureError::ZeroSpan { .. }
            | ProcedureError::DuplicateExperiment { .. }),
        ) => Err(anyhow::Error::new(e).context(format!("validating on {}", args.data.display()))),
        Err(_) => Ok((set, Vec::new())),
    }
}

/// A [`ValidationBlock`] in words: where, by how much, how significant, what the validation
/// becomes without it and the fix; `mixed` says what mixes the two setups and how to keep them
/// apart (`validate`: its verdicts; `diagnose`: its diagnosis).
pub(super) fn block_words(b: &ValidationBlock, mixed: &str) -> String {
    let line = |l: Option<u64>| l.map_or_else(|| "?".to_owned(), |l| l.to_string());
    format!(
        "the validation poses of lines {}-{} (steps {}-{}, {} of the {} validated) sit about ({:.2}, {:.2}, {:.2}) mm off \
         the others: their residuals, less the calibration's own error, step there in file order (p {} for the most \
         significant of the {} blocks of consecutive poses tried, against a false-alarm rate of {} shared by them), and \
         with them moved back the validation poses' chi2/dof is {:.3} against {:.3} as written (RMS {:.3} mm against \
         {:.3} mm). The instrument or the \
         robot moved between them (a bump, a re-setup), so {mixed} (or measure them again)",
        line(b.lines.0),
        line(b.lines.1),
        b.steps.0,
        b.steps.1,
        b.poses,
        b.tested,
        b.shift_mm[0],
        b.shift_mm[1],
        b.shift_mm[2],
        super::calibrate::p_value_words(b.p_value),
        b.blocks_tried,
        axiscal::calibration::free_pose::slip::SLIP_FALSE_ALARM,
        b.undone_chi2_per_dof,
        b.written_chi2_per_dof,
        b.undone_rms_mm,
        b.written_rms_mm,
    )
}

/// A verdict that the model misses DATA with `--noise-mm` far below the noise DATA's axis
/// experiments show is refused, as `calibrate` refuses that value ([`checks::noise_far_below`]):
/// the verdict would blame the model for the instrument's noise.
fn noise_not_far_below(args: &Args, set: &MeasurementSet, desc: &RobotDescription, v: &Validation) -> Result<()> {
    let Some(given_mm) = args.noise_mm.filter(|_| v.exceeds(false)) else {
        return Ok(());
    };
    let options = CalibrationOptions {
        noise_rms_3d_mm: given_mm,
        estimate_noise: false,
        ..CalibrationOptions::default()
    };
    let failing = ["the tests", "the calibration's noise"];
    match checks::noise_far_below(set, desc, &options, given_mm, None, failing) {
        Some(too_small) => anyhow::bail!("validating on {}: {too_small}", args.data.display()),
        None => Ok(()),
    }
}

/// `  chi2/dof 1.020 (369 dof, p 0.380) consistent`, or `-` without a test.
fn chi_square_text(c: &Option<ChiSquare>) -> String {
    c.as_ref().map_or("-".into(), |c| {
        format!(
            "chi2/dof {:.3} ({} dof, p {:.3}) {}",
            c.per_dof, c.dof, c.p_value, c.verdict
        )
    })
}

/// `noise 0.2038 + repeatability 0.2101 + calibration 1.1412 mm`: the prediction's parts.
fn parts_text(p: &Prediction, unit: &str) -> String {
    let mut parts = vec![format!("noise {:.4}", p.noise)];
    parts.extend(p.repeatability.map(|r| format!("repeatability {r:.4}")));
    parts.extend(p.calibration.map(|c| format!("calibration {c:.4}")));
    format!("{} {unit}", parts.join(" + "))
}

/// The summaries on stdout.
fn print_summary(v: &Validation) {
    println!("{}", v.verdict);
    println!(
        "  noise {:.4} mm 3-D RMS ({}{}); verdicts at false-alarm rate {}; {}",
        v.noise_rms_3d_mm,
        v.noise_source,
        v.noise_dof.map_or(String::new(), |d| format!(
            ", estimated from {d:.0} degrees of freedom: F tests"
        )),
        v.false_alarm,
        if v.calibration_uncertainty {
            "free poses tested against the noise, the robot's repeatability and the calibration's predicted error"
        } else {
            "free poses tested against the noise and the robot's repeatability (the calibration has no `model_covariance`)"
        }
    );
    let line = |name: &str, s: &Option<PositionSummary>| {
        if let Some(s) = s {
            println!(
                "  {name:<11} {:>5} points  RMS {:.4} mm  max {:.4} mm  predicted {:.4} mm ({})  {}",
                s.points,
                s.rms_mm,
                s.max_mm,
                s.predicted_mm.total,
                parts_text(&s.predicted_mm, "mm"),
                chi_square_text(&s.chi_square)
            );
        }
    };
    line("validation", &v.validation);
    line("tool", &v.tool);
    line("axis", &v.axis);
    if let Some(o) = &v.orientation {
        println!(
            "  {:<11} {:>5} poses   RMS {:.4} mrad  max {:.4} mrad  predicted {:.4} mrad ({})  {}",
            "orientation",
            o.poses,
            o.rms_mrad,
            o.max_mrad,
            o.predicted_mrad.total,
            parts_text(&o.predicted_mrad, "mrad"),
            chi_square_text(&o.chi_square)
        );
    }
}
