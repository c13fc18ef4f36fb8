//! `axiscal report --calibration CAL.json --out DIR`: the calibration certificate
//! (`docs/formats.md#certificate`), `certificate.html` (one self-contained page) and
//! `certificate.json`.

use super::checks;
use super::output::Outputs;
use super::printer::Printer;
use anyhow::{Context, Result, bail};
use axiscal::calibration::procedure::{PointResidual, read_residuals_csv};
use axiscal::calibration::record::CalibrationRecord;
use axiscal::certificate::{
    CertificateInputs, HELD_OUT_FALSE_ALARM, HeldOut, certificate, data_mismatches, held_out, html,
};
use axiscal::diagnosis::free_pose_misses;
use axiscal::iso9283::IsoFigures;
use axiscal::json_file::{self, Schema};
use axiscal::measurement::{MAX_LABEL_CHARS, MeasurementSet, is_format_char};
use axiscal::robot::RobotDescription;
use std::path::{Path, PathBuf};

/// The files `report` writes into its output folder.
const OUTPUTS: [&str; 2] = ["certificate.html", "certificate.json"];

/// Arguments of `axiscal report`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The calibration (`calibration.json` of `axiscal calibrate`); its `residuals.csv`, when
    /// beside it, gives the residual plots.
    #[arg(long)]
    calibration: PathBuf,
    /// Nominal robot description (TOML) the calibration was made with, or a shipped robot's
    /// name: the nominal values.
    #[arg(long, default_value = "asea-irb6l", value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// The measurement CSV the calibration was made from: its experiments are summarised. It
    /// must hold the sweeps the calibration records, with their poses.
    #[arg(long)]
    data: Option<PathBuf>,
    /// Summarise `--data` even when it is not the data the calibration records (other or
    /// missing sweeps, other pose counts), and show `--iso9283` even when another model
    /// commanded its poses (the nominal one, before calibration, or another calibration's); the
    /// certificate then says so in its warnings.
    #[arg(long)]
    allow_other_data: bool,
    /// A measurement CSV with held-out poses (`moved_joint = 0`, not `tool`): the nominal and
    /// the calibrated model compared on them. It may be `--data` itself, whose validation poses
    /// the calibration does not use.
    #[arg(long)]
    held_out: Option<PathBuf>,
    /// `iso9283.json` of `axiscal iso9283 evaluate --calibration` with this calibration: the
    /// ISO 9283 figures.
    #[arg(long)]
    iso9283: Option<PathBuf>,
    /// The instrument, in words (make, model, serial number, its own calibration).
    #[arg(long)]
    instrument: Option<String>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Replace existing output files.
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    checks: checks::Overrides,
}

/// `--instrument`: one line of text for the certificate, without control characters (an
/// escape or bell byte would be written into the HTML and the report as it is), without format
/// characters (a right-to-left override would show the serial number reordered), and no longer
/// than a label ([`MAX_LABEL_CHARS`]). Checked when the command runs, not by the argument
/// parser, which would echo a long value whole.
fn instrument_words(text: &str) -> Result<()> {
    if let Some(c) = text.chars().find(|c| c.is_control()) {
        bail!(
            "--instrument holds the control character {c:?}: the instrument is one line of words (make, model, serial number)"
        );
    }
    if let Some(c) = text.chars().find(|&c| is_format_char(c)) {
        bail!(
            "--instrument holds the invisible format character U+{:04X}: it would change how the certificate shows the words \
             around it (a right-to-left override reverses a serial number); write the instrument as plain text",
            c as u32
        );
    }
    let count = text.chars().count();
    if count > MAX_LABEL_CHARS {
        bail!(
            "--instrument is {count} characters long, more than {MAX_LABEL_CHARS}: the instrument is one line of words (make, \
             model, serial number, its own calibration); shorten it"
        );
    }
    Ok(())
}

/// The residuals beside `calibration` (`residuals.csv`), if there.
fn residuals_beside(calibration: &Path) -> Result<Option<Vec<PointResidual>>> {
    let path = calibration.with_file_name("residuals.csv");
    if !path.is_file() {
        return Ok(None);
    }
    let text = axiscal::presets::read_text(&path).with_context(|| format!("{}: cannot read", path.display()))?;
    let residuals = read_residuals_csv(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    Ok(Some(residuals))
}

/// Refuses `set` (read from `data`) as the calibration's data when it is not what the
/// calibration records ([`data_mismatches`]), unless `--allow-other-data`.
fn same_data(set: &MeasurementSet, record: &CalibrationRecord, data: &Path, args: &Args) -> Result<()> {
    let mismatches = data_mismatches(record, set);
    if mismatches.is_empty() || args.allow_other_data {
        return Ok(());
    }
    bail!(
        "{}: not the data {} was made from: {}; give --data the measurement file the calibration was made from, or pass --allow-other-data to summarise this one anyway",
        data.display(),
        args.calibration.display(),
        mismatches.join("; ")
    )
}

/// The ISO 9283 figures of `iso9283 evaluate` (`--iso9283`), checked to be figures it can have
/// written ([`IsoFigures::impossible_value`]), of this robot, with the poses commanded by this
/// calibration's model; with what to warn of (an older file, another robot or model allowed).
fn read_iso9283(
    p: &Path,
    desc: &RobotDescription,
    record: &CalibrationRecord,
    args: &Args,
) -> Result<(IsoFigures, Vec<String>)> {
    let text = axiscal::presets::read_text(p).with_context(|| format!("{}: cannot read", p.display()))?;
    let iso: IsoFigures =
        json_file::from_str(Schema::ISO9283, &text).with_context(|| format!("{}: not an iso9283.json", p.display()))?;
    if let Some(why) = iso.impossible_value() {
        bail!(
            "{}: {why}; `axiscal iso9283 evaluate` writes no such value (the file was edited or damaged): evaluate the cycles again",
            p.display()
        );
    }
    let mut warnings: Vec<String> =
        checks::same_robot(iso.robot.as_ref(), p, desc, &args.robot, args.checks.allow_other_robot)?
            .into_iter()
            .collect();
    let calibrated = record.calibration.robot.digest();
    // Only an evaluation without --calibration registers the base frame: the nominal model's.
    let before = iso.registration_rms_mm.is_some();
    warnings.extend(iso.warnings.iter().map(|w| format!("{}: {w}", p.display())));
    match &iso.model_digest {
        None if !before => warnings.push(format!(
            "{} records no model_digest (written by an older axiscal): cannot check that {}'s model commanded its poses",
            p.display(),
            args.calibration.display()
        )),
        Some(d) if *d == calibrated && !before => {}
        d => {
            let d = d.as_deref().unwrap_or("not recorded");
            let which = if before {
                "the nominal model, before calibration (evaluated without --calibration)"
            } else {
                "another calibration's model"
            };
            let what = format!(
                "{}: its poses were commanded by {which} (model digest {d}), not by {}'s ({calibrated})",
                p.display(),
                args.calibration.display()
            );
            if !args.allow_other_data {
                bail!(
                    "{what}: the certificate would show them as this calibration's figures; give --iso9283 the figures of \
                     `axiscal iso9283 evaluate DATA --calibration {}`, or pass --allow-other-data to show these anyway (the \
                     certificate then says so)",
                    args.calibration.display()
                );
            }
            warnings.push(format!("{what} (--allow-other-data)"));
        }
    }
    Ok((iso, warnings))
}

/// The nominal and the calibrated model compared on the held-out poses of `p`
/// (`--held-out`), after their unit checks.
fn held_out_poses(
    p: &Path,
    desc: &RobotDescription,
    record: &CalibrationRecord,
    fitted: &RobotDescription,
    args: &Args,
) -> Result<HeldOut> {
    let set = checks::read_data(p, desc, &args.robot, args.checks)?;
    checks::one_setup(&set, p, "the held-out poses' prediction")?;
    if !args.checks.skip_unit_check {
        let misses = free_pose_misses(&set, &record.calibration, fitted, HELD_OUT_FALSE_ALARM)
            .with_context(|| format!("held-out poses of {}", p.display()))?;
        checks::refuse_explained_misses(&misses, p, false)?;
    }
    held_out(&p.display().to_string(), &set, record, fitted)
        .with_context(|| format!("held-out poses of {}", p.display()))
}

/// Runs `axiscal report`.
pub fn run(args: Args, printer: Printer) -> Result<()> {
    args.instrument.as_deref().map(instrument_words).transpose()?;
    let mut outputs = Outputs::new(args.force)
        .input("--calibration", &args.calibration)
        .input("--robot", &args.robot);
    for (name, path) in [
        ("--data", &args.data),
        ("--held-out", &args.held_out),
        ("--iso9283", &args.iso9283),
    ] {
        if let Some(p) = path {
            outputs = outputs.input(name, p);
        }
    }
    outputs.check_in(&args.out, &OUTPUTS)?;
    let desc = RobotDescription::from_file(&args.robot)?;
    // Its warnings go into the certificate's, printed with them.
    let (record, read_warnings) =
        checks::read_calibration_warned(&args.calibration, &desc, &args.robot, args.checks.allow_other_robot)?;
    // A free-pose calibration fitted the targets the description may not give; the data
    // record the description as given.
    let fitted = axiscal::calibration::free_pose::with_fitted_targets(&desc, record.reports.free_poses.as_ref());
    let data = match &args.data {
        Some(p) => {
            let set = checks::read_data(p, &desc, &args.robot, args.checks)?;
            same_data(&set, &record, p, &args)?;
            Some((p.display().to_string(), set))
        }
        None => None,
    };
    let held_out = args
        .held_out
        .as_deref()
        .map(|p| held_out_poses(p, &desc, &record, &fitted, &args))
        .transpose()?;
    let iso = args
        .iso9283
        .as_deref()
        .map(|p| read_iso9283(p, &desc, &record, &args))
        .transpose()?;
    let (iso9283, iso_warnings) = iso.map_or((None, Vec::new()), |(figures, warnings)| (Some(figures), warnings));
    let residuals = residuals_beside(&args.calibration)?;
    if residuals.is_none() {
        say!(
            printer,
            "no residuals.csv beside {}: the certificate has no residual plots",
            args.calibration.display()
        );
    }
    let inputs = CertificateInputs {
        calibration: &record,
        calibration_file: args.calibration.display().to_string(),
        desc: &fitted,
        instrument: args.instrument.clone(),
        data: data.as_ref().map(|(f, s)| (f.clone(), s)),
        residuals: residuals.as_deref().unwrap_or(&[]),
        held_out,
        iso9283,
        read_warnings: read_warnings.into_iter().chain(iso_warnings).collect(),
    };
    let c = certificate(&inputs).with_context(|| format!("the certificate of {}", args.calibration.display()))?;
    let mut staged = outputs.staged_in(&args.out)?;
    staged.write(OUTPUTS[0], html::render(&c))?;
    staged.write(OUTPUTS[1], json_file::to_string(Schema::CERTIFICATE, &c)?)?;
    staged.commit(&[])?;
    for w in &c.warnings {
        eprintln!("warning: {w}");
    }
    say!(
        printer,
        "certificate of {}: {} parameters ({} measured, the rest fixed by the method) and {} frames, U = {} u",
        c.robot.name,
        c.parameters.len(),
        c.parameters.iter().filter(|p| p.standard_uncertainty > 0.0).count(),
        c.frames.len(),
        c.coverage_factor
    );
    if let Some(h) = &c.held_out {
        say!(
            printer,
            "held-out poses: {:.4} mm RMS before calibration, {:.4} mm after ({} points)",
            h.before.rms_mm,
            h.after.rms_mm,
            h.points
        );
    }
    say!(printer, "wrote {}/{{{}}}", args.out.display(), OUTPUTS.join(","));
    Ok(())
}
