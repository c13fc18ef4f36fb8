//! `axiscal import FORMAT ...`: converts measurement data written by other groups to the
//! measurement CSV of `docs/formats.md#measurement-csv`.

use super::output::Outputs;
use anyhow::{Context, Result};
use axiscal::kinematics::JointKind;
use axiscal::measurement::import::arrays::{ArrayImport, free_poses, target_unit_slip};
use axiscal::measurement::import::boby_klimchik;
use axiscal::measurement::import::mat_v5;
use axiscal::measurement::import::points::{LengthUnit, PlanSheet, join_points};
use axiscal::measurement::import::rct;
use axiscal::measurement::import::spatial_analyzer;
use axiscal::measurement::import::sscanss2;
use axiscal::measurement::import::table::Table;
use axiscal::measurement::import::wide::{
    WideOptions, import_wide as read_wide, jitter_sweeps_hint, still_tolerance_hint, sweep_order_hint,
};
use axiscal::measurement::{MeasurementSet, write_measurements_to};
use axiscal::robot::RobotDescription;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `axiscal import`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    format: Format,
}

/// The source formats.
#[derive(Debug, clap::Subcommand)]
enum Format {
    /// Boby & Klimchik's laser-tracker data (folder with N1N2N3Jval.csv): six one-joint
    /// blocks of six poses, three SMRs each (targets 0,1,2 = SMRs 2,3,1). cmd_3 = J3 + J2 (the controller reads J3
    /// against the ground).
    BobyKlimchik(DirArgs),
    /// An instrument's point export (`id,x,y,z[,sigma]`, ids or row order, mm or m) joined to
    /// the plan of `axiscal plan` (`docs/formats.md#point-export`).
    Points(PointsArgs),
    /// A wide pose table (one row per pose: `q1..qN` + `m1_x,m1_y,m1_z,...`), as FIGAROH and lab
    /// scripts write it; axis experiments recovered from the joint values
    /// (`docs/formats.md#wide-format`).
    Wide(WideArgs),
    /// SScanSS-2's calibration file (7 columns a point: joint, x, y, z, joint value, type,
    /// home; no header), one joint moved at a time (`docs/formats.md#sscanss-2-calibration-file`).
    Sscanss2(Sscanss2Args),
    /// robot_cal_tools' kinematic measurements (YAML: per observation a fixed camera's `pose`
    /// of a target on the robot and the robot's `target_joints`); experiments recovered from the
    /// joint values as for `wide` (`docs/formats.md#robot_cal_tools-measurements`).
    Rct(RctArgs),
    /// A MATLAB v5 file (`.mat`, `save -v7` or older) of free poses: a joint array (one row per
    /// pose, one column per joint) and one point array per target (one row per pose, x y z).
    Mat(MatArgs),
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum Unit {
    Mm,
    M,
}

impl From<Unit> for LengthUnit {
    fn from(u: Unit) -> Self {
        match u {
            Unit::Mm => LengthUnit::Mm,
            Unit::M => LengthUnit::M,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, clap::ValueEnum)]
enum ExportFormat {
    Csv,
    #[value(name = "spatialanalyzer", alias = "sa")]
    SpatialAnalyzer,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum Angle {
    Rad,
    Deg,
}

/// The output of every import: `--out` and `--force`.
#[derive(Debug, clap::Args)]
struct OutputCsv {
    /// Output measurement CSV.
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
}

/// `import points PLAN EXPORT --out DATA`.
#[derive(Debug, clap::Args)]
struct PointsArgs {
    /// The measurement plan (`axiscal plan`).
    plan: PathBuf,
    /// The instrument's export (CSV: `id,x,y,z`, optional uncertainty column).
    export: PathBuf,
    /// The export's length unit; default: from the column names (`x_mm`, `x_m`) or detected
    /// from the points' spread against the plan's nominal points (and stated on stdout).
    #[arg(long, value_enum)]
    units: Option<Unit>,
    /// Accept planned points the export lacks although the plan expects them visible.
    #[arg(long)]
    allow_missing: bool,
    /// The export's format: a CSV with a header, or SpatialAnalyzer's ASCII export (name
    /// fields, x y z; `docs/formats.md#spatialanalyzer-ascii-export`). Default: SpatialAnalyzer
    /// when the file opens with a `//` comment, else CSV.
    #[arg(long, value_enum)]
    format: Option<ExportFormat>,
    /// SpatialAnalyzer only: the name fields before x y z (3: collection group target, 2: group
    /// target, 1: target, 0: none); default: all but the last 3 fields of every line.
    #[arg(long)]
    sa_names: Option<usize>,
    #[command(flatten)]
    output: OutputCsv,
}

/// `import wide FILE --robot R --angles rad|deg --units mm|m --out DATA`.
#[derive(Debug, clap::Args)]
struct WideArgs {
    /// The wide table (CSV).
    file: PathBuf,
    /// The robot description (joint count and kinds), or a shipped one's name.
    #[arg(long, default_value = "asea-irb6l", value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// Unit of the revolute joint values.
    #[arg(long, value_enum)]
    angles: Angle,
    /// Unit of the marker coordinates and the prismatic joint values.
    #[arg(long, value_enum)]
    units: Unit,
    /// Joint values within this of each other hold the joint still (deg or mm).
    #[arg(long, default_value_t = 1e-6, value_parser = super::options::STILL_TOLERANCE)]
    still_tolerance: f64,
    /// Skip the check of --angles and --units against the description (the sweeps' arcs and
    /// turns, `docs/formats.md#wide-table`) when the units are right after all.
    #[arg(long)]
    skip_unit_check: bool,
    #[command(flatten)]
    output: OutputCsv,
}

/// `import mat FILE --robot R --joints q --targets mA,mB --angles rad --units m --out DATA`.
#[derive(Debug, clap::Args)]
struct MatArgs {
    /// The MAT file.
    file: PathBuf,
    /// The robot description (joint count and kinds), or a shipped one's name.
    #[arg(long, value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// The joint array's variable name.
    #[arg(long)]
    joints: String,
    /// The point arrays' variable names, one per target (ids 0, 1, ... in this order).
    #[arg(long, value_delimiter = ',', required = true)]
    targets: Vec<String>,
    /// Unit of the revolute joint values.
    #[arg(long, value_enum)]
    angles: Angle,
    /// Unit of the points and of the prismatic joint values.
    #[arg(long, value_enum)]
    units: Unit,
    /// The experiment id of the poses.
    #[arg(long, default_value = "poses")]
    experiment: String,
    /// Skip the check of --angles and --units against the description (the free poses' spread,
    /// `docs/formats.md#unit-checks`) when the units are right after all.
    #[arg(long)]
    skip_unit_check: bool,
    #[command(flatten)]
    output: OutputCsv,
}

/// `import sscanss2 FILE --robot R --out DATA`.
#[derive(Debug, clap::Args)]
struct Sscanss2Args {
    /// The calibration file.
    file: PathBuf,
    /// The robot description (joint count and kinds, checked against the file's types), or a
    /// shipped one's name.
    #[arg(long, value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// Unit of the points (SScanSS-2 works in mm).
    #[arg(long, value_enum, default_value = "mm")]
    units: Unit,
    /// Unit of the revolute joint values (SScanSS-2 works in degrees).
    #[arg(long, value_enum, default_value = "deg")]
    angles: Angle,
    /// Skip the check of --angles and --units against the description (the sweeps' arcs and
    /// turns, `docs/formats.md#unit-checks`) when the units are right after all.
    #[arg(long)]
    skip_unit_check: bool,
    #[command(flatten)]
    output: OutputCsv,
}

/// `import rct FILE --robot R --out DATA`.
#[derive(Debug, clap::Args)]
struct RctArgs {
    /// The measurement file (YAML).
    file: PathBuf,
    /// The robot description (joint count and kinds), or a shipped one's name.
    #[arg(long, value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// Also targets 1 and 2, this far along the measured frame's x and y axes (mm): the
    /// camera's orientation as two more points (their noise is the orientation's times this).
    #[arg(long)]
    frame_points: Option<f64>,
    /// Joint values within this of each other hold the joint still (deg or mm).
    #[arg(long, default_value_t = 1e-6, value_parser = super::options::STILL_TOLERANCE)]
    still_tolerance: f64,
    /// Unit of the positions and of the prismatic joint values (robot_cal_tools works in m).
    #[arg(long, value_enum, default_value = "m")]
    units: Unit,
    /// Unit of the revolute joint values (robot_cal_tools works in radians).
    #[arg(long, value_enum, default_value = "rad")]
    angles: Angle,
    /// Skip the check of --angles and --units against the description (the sweeps' arcs and
    /// turns, `docs/formats.md#unit-checks`) when the units are right after all.
    #[arg(long)]
    skip_unit_check: bool,
    #[command(flatten)]
    output: OutputCsv,
}

/// A data-set folder and the output file.
#[derive(Debug, clap::Args)]
struct DirArgs {
    /// The data set's folder.
    dir: PathBuf,
    #[command(flatten)]
    output: OutputCsv,
}

/// Writes `comment` and `set` to `out`, never over `source` (the file imported).
fn write_csv(
    out: &Path,
    force: bool,
    source: &Path,
    comment: &str,
    set: &axiscal::measurement::MeasurementSet,
) -> Result<()> {
    write_csv_from(out, Outputs::new(force).input("DIR", source), source, comment, set)
}

/// Writes `comment` and `set` (imported from `source`) to `out` through `outputs` (which names
/// the inputs).
fn write_csv_from(
    out: &Path,
    outputs: Outputs,
    source: &Path,
    comment: &str,
    set: &axiscal::measurement::MeasurementSet,
) -> Result<()> {
    if set.rows().is_empty() {
        anyhow::bail!(
            "{}: nothing to import: no measured point (a file with a header and no data rows?); {} not written",
            source.display(),
            out.display()
        );
    }
    let mut file = outputs.create(out)?;
    file.write_all(comment.as_bytes())
        .and_then(|_| write_measurements_to(&mut file, set))
        .with_context(|| format!("writing {}", out.display()))?;
    file.commit()
}

/// Runs `axiscal import`.
pub fn run(args: Args) -> Result<()> {
    match args.format {
        Format::Points(a) => import_points(&a),
        Format::Wide(a) => import_wide(&a),
        Format::Mat(a) => import_mat(&a),
        Format::Sscanss2(a) => import_sscanss2(&a),
        Format::Rct(a) => import_rct(&a),
        Format::BobyKlimchik(a) => {
            let source = a.dir.join(boby_klimchik::DATA_FILE);
            Outputs::new(a.output.force)
                .input("DIR", &source)
                .check(&a.output.out)?;
            let set = boby_klimchik::import_dir(&a.dir)?;
            write_csv(
                &a.output.out,
                a.output.force,
                &source,
                &boby_klimchik::provenance_comment(&source),
                &set,
            )?;
            println!(
                "imported {} poses ({} experiments, {} targets each) from {} to {}",
                set.rows().len() / boby_klimchik::TARGETS,
                set.experiments().len(),
                boby_klimchik::TARGETS,
                source.display(),
                a.output.out.display()
            );
            Ok(())
        }
    }
}

fn import_points(a: &PointsArgs) -> Result<()> {
    let outputs = Outputs::new(a.output.force)
        .input("PLAN", &a.plan)
        .input("EXPORT", &a.export);
    outputs.check(&a.output.out)?;
    let plan = PlanSheet::from_table(&Table::read(&a.plan)?)?;
    let text = axiscal::presets::read_text(&a.export).with_context(|| format!("reading {}", a.export.display()))?;
    let sa = match a.format {
        Some(f) => f == ExportFormat::SpatialAnalyzer,
        None => spatial_analyzer::looks_like(&text),
    };
    if a.format.is_none()
        && !sa
        && let Some(line) = spatial_analyzer::headerless_point_line(&text)
    {
        anyhow::bail!(
            "{}: line {line} is a SpatialAnalyzer point line (name fields, then x y z), not a CSV header: the export has no `//` header line; pass --format spatialanalyzer",
            a.export.display()
        );
    }
    if a.sa_names.is_some() && !sa {
        anyhow::bail!("--sa-names applies to a SpatialAnalyzer export (--format spatialanalyzer)");
    }
    let export = if sa {
        spatial_analyzer::to_table(&text, &a.export, a.sa_names)?
    } else {
        Table::parse(text, &a.export)?
    };
    let joined = join_points(&plan, &export, a.units.map(Into::into), a.allow_missing)?;
    let recorded: String = plan
        .comments
        .iter()
        .filter(|c| c.starts_with("axiscal.description "))
        .map(|c| format!("# {c}\n"))
        .collect();
    let comment = format!(
        "{recorded}# {}\n",
        axiscal::csv_lines::one_line(&format!(
            "imported by `axiscal import points` from {} (unit {}) joined to the plan {}",
            a.export.display(),
            joined.unit.name(),
            a.plan.display()
        ))
    );
    write_csv_from(&a.output.out, outputs, &a.export, &comment, &joined.set)?;
    let how = if joined.detected { "detected" } else { "stated" };
    println!(
        "imported {} of {} planned points from {} to {}",
        joined.set.rows().len(),
        plan.rows.len(),
        a.export.display(),
        a.output.out.display()
    );
    println!(
        "  unit: {} ({how}; the points spread {:.4} times the plan's nominal points in mm)",
        joined.unit.name(),
        joined.spread_ratio
    );
    if !joined.missing_hidden.is_empty() {
        println!(
            "  {} point(s) the plan marks hidden are missing (expected)",
            joined.missing_hidden.len()
        );
    }
    if !joined.missing_visible.is_empty() {
        eprintln!(
            "warning: {} point(s) the plan expects visible are missing (--allow-missing)",
            joined.missing_visible.len()
        );
    }
    if !joined.sigmas_mm.is_empty() {
        let rms = (joined.sigmas_mm.iter().map(|s| s * s).sum::<f64>() / joined.sigmas_mm.len() as f64).sqrt();
        let max = joined.sigmas_mm.iter().copied().fold(0.0, f64::max);
        println!(
            "  per-point uncertainty: RMS {rms:.4} mm, largest {max:.4} mm (the measurement CSV has no column for it: \
             pass the 3-D RMS to diagnose --noise-mm)"
        );
    }
    Ok(())
}

fn import_sscanss2(a: &Sscanss2Args) -> Result<()> {
    let outputs = Outputs::new(a.output.force)
        .input("FILE", &a.file)
        .input("--robot", &a.robot);
    outputs.check(&a.output.out)?;
    let desc = RobotDescription::from_file(&a.robot)?;
    let text = axiscal::presets::read_text(&a.file).with_context(|| format!("reading {}", a.file.display()))?;
    let kinds: Vec<_> = desc.joints.iter().map(|j| j.kind).collect();
    let read_as = |radians: bool, lengths: LengthUnit| sscanss2::parse(&text, &a.file, &kinds, lengths, radians);
    let stated = (matches!(a.angles, Angle::Rad), a.units.into());
    let set = read_as(stated.0, stated.1)?;
    if !a.skip_unit_check {
        super::checks::import_units(&set, &desc, &a.file, stated, |r, l| read_as(r, l).ok())?;
        sscanss2::check_homes(&text, &a.file, &kinds, stated.1, stated.0)?;
    }
    let comment = format!(
        "{}{}",
        super::checks::identity_comment(&desc),
        sscanss2::provenance_comment(&a.file)
    );
    write_csv_from(&a.output.out, outputs, &a.file, &comment, &set)?;
    report_experiments(&set, &a.file, &a.output.out);
    Ok(())
}

fn import_rct(a: &RctArgs) -> Result<()> {
    let outputs = Outputs::new(a.output.force)
        .input("FILE", &a.file)
        .input("--robot", &a.robot);
    outputs.check(&a.output.out)?;
    if a.frame_points.is_some_and(|l| !(l.is_finite() && l > 0.0)) {
        anyhow::bail!("--frame-points must be a positive length in mm");
    }
    let desc = RobotDescription::from_file(&a.robot)?;
    let text = axiscal::presets::read_text(&a.file).with_context(|| format!("reading {}", a.file.display()))?;
    let read_as = |radians: bool, lengths: LengthUnit| {
        let options = rct::RctOptions {
            kinds: desc.joints.iter().map(|j| j.kind).collect(),
            frame_points_mm: a.frame_points,
            still_tolerance: a.still_tolerance,
            radians,
            lengths,
        };
        (rct::parse(&text, &a.file, &options), options)
    };
    let stated = (matches!(a.angles, Angle::Rad), a.units.into());
    let (set, options) = read_as(stated.0, stated.1);
    let set = set?;
    if !a.skip_unit_check && !tolerance_explains(&set, a.still_tolerance) {
        super::checks::import_units(&set, &desc, &a.file, stated, |r, l| read_as(r, l).0.ok())?;
    }
    let comment = format!(
        "{}{}",
        super::checks::identity_comment(&desc),
        rct::provenance_comment(&a.file, &options)
    );
    write_csv_from(&a.output.out, outputs, &a.file, &comment, &set)?;
    report_experiments(&set, &a.file, &a.output.out);
    warn_still_tolerance(&set, &desc, &a.file, a.still_tolerance);
    Ok(())
}

/// What an import wrote: its rows and experiments.
fn report_experiments(set: &axiscal::measurement::MeasurementSet, source: &Path, out: &Path) {
    println!(
        "imported {} rows from {} to {}",
        set.rows().len(),
        source.display(),
        out.display()
    );
    for e in set.experiments() {
        println!("  {:<10} moved_joint {}  {} rows", e.name, e.moved_joint, e.rows.len());
    }
}

fn import_wide(a: &WideArgs) -> Result<()> {
    let outputs = Outputs::new(a.output.force)
        .input("FILE", &a.file)
        .input("--robot", &a.robot);
    outputs.check(&a.output.out)?;
    let desc = RobotDescription::from_file(&a.robot)?;
    if !a.skip_unit_check {
        super::checks::print_warnings(&super::checks::description_warning_lines(&desc, &a.robot));
    }
    let table = Table::read(&a.file)?;
    let read_as = |radians: bool, lengths: LengthUnit| {
        let options = WideOptions {
            kinds: desc.joints.iter().map(|j| j.kind).collect(),
            radians,
            lengths,
            still_tolerance: a.still_tolerance,
        };
        read_wide(&table, &options)
    };
    let set = read_as(matches!(a.angles, Angle::Rad), a.units.into())?;
    let unordered = sweep_order_hint(&set, a.still_tolerance);
    if !a.skip_unit_check && !tolerance_explains(&set, a.still_tolerance) && unordered.is_none() {
        let stated = (matches!(a.angles, Angle::Rad), a.units.into());
        super::checks::import_units(&set, &desc, &a.file, stated, |r, l| read_as(r, l).ok())?;
    }
    let comment = format!(
        "{}# imported by `axiscal import wide` from {}\n",
        super::checks::identity_comment(&desc),
        axiscal::csv_lines::one_line(&a.file.display().to_string())
    );
    write_csv_from(&a.output.out, outputs, &a.file, &comment, &set)?;
    report_experiments(&set, &a.file, &a.output.out);
    warn_still_tolerance(&set, &desc, &a.file, a.still_tolerance);
    if let Some(hint) = unordered.filter(|_| still_tolerance_hint(&set, a.still_tolerance).is_none()) {
        eprintln!(
            "warning: {}: {} of its {} rows became free poses (experiment `poses`): the rows are not in sweep order \
             (sorted by their joint values, {} of them form sweeps of one joint); put each sweep's rows together in the \
             order its joint moved (the units were not checked)",
            a.file.display(),
            hint.free_poses,
            hint.poses,
            hint.sorted_axis_poses
        );
    }
    Ok(())
}

/// Whether the still tolerance `tolerance` explains the experiments of `set` going wrong
/// ([`still_tolerance_hint`], [`jitter_sweeps_hint`]): the unit check is then not run (its
/// sweeps are not the robot's).
fn tolerance_explains(set: &MeasurementSet, tolerance: f64) -> bool {
    still_tolerance_hint(set, tolerance).is_some() || jitter_sweeps_hint(set).is_some()
}

/// A warning when an imported table's sweeps of one joint are the next joint's, its recorded
/// value jittering by more than `--still-tolerance` ([`jitter_sweeps_hint`]).
fn warn_jitter_sweeps(set: &MeasurementSet, desc: &RobotDescription, source: &Path, tolerance: f64) {
    let Some(hint) = jitter_sweeps_hint(set) else {
        return;
    };
    let (j, e) = (hint.joint, &hint.experiments);
    let unit = |k: usize| match desc.joints[k - 1].kind {
        JointKind::Revolute => "deg",
        JointKind::Prismatic => "mm",
    };
    let named = match e.as_slice() {
        [one] => format!("`{one}`"),
        [first, .., last] => format!("`{first}` .. `{last}`"),
        [] => String::new(),
    };
    eprintln!(
        "warning: {}: its {} sweeps of joint {j} ({named}) are joint {}'s: in each joint {} moves {:.3} {} or more \
         while joint {j} moves {} {} at most, its recorded value jittering by more than --still-tolerance {tolerance}, so the \
         pair read as joint {j} swept with joint {} held still by its command; pass --still-tolerance {} (above joint \
         {j}'s largest change while joint {} turns; the units were not checked)",
        source.display(),
        e.len(),
        j + 1,
        j + 1,
        hint.next_span,
        unit(j + 1),
        hint.joint_span,
        unit(j),
        j + 1,
        hint.tolerance,
        j + 1
    );
}

/// A warning when nearly every pose of an imported table became a free pose while a larger
/// `--still-tolerance` recovers its axis experiments ([`still_tolerance_hint`]).
fn warn_still_tolerance(set: &MeasurementSet, desc: &RobotDescription, source: &Path, tolerance: f64) {
    let Some(hint) = still_tolerance_hint(set, tolerance) else {
        warn_jitter_sweeps(set, desc, source, tolerance);
        return;
    };
    let kinds: Vec<JointKind> = desc.joints.iter().map(|j| j.kind).collect();
    let unit = if kinds.iter().all(|k| *k == JointKind::Revolute) {
        "deg"
    } else if kinds.iter().all(|k| *k == JointKind::Prismatic) {
        "mm"
    } else {
        "deg or mm"
    };
    eprintln!(
        "warning: {}: {} of its {} poses (table rows) became free poses (experiment `poses`): between consecutive \
         poses their held joints vary by up to {} {unit}, more than --still-tolerance {tolerance}; pass \
         --still-tolerance {} (it makes {} of them axis-experiment poses)",
        source.display(),
        hint.free_poses,
        hint.poses,
        hint.tolerance,
        hint.tolerance,
        hint.recovered
    );
}

fn import_mat(a: &MatArgs) -> Result<()> {
    let outputs = Outputs::new(a.output.force)
        .input("FILE", &a.file)
        .input("--robot", &a.robot);
    outputs.check(&a.output.out)?;
    let desc = RobotDescription::from_file(&a.robot)?;
    let bytes = axiscal::presets::regular_file(&a.file)
        .and_then(|()| std::fs::read(&a.file))
        .with_context(|| format!("reading {}", a.file.display()))?;
    let file = mat_v5::read(&bytes).map_err(|e| anyhow::anyhow!("{}: {e}", a.file.display()))?;
    let read_as = |radians: bool, lengths: LengthUnit| {
        let how = ArrayImport {
            joints: a.joints.clone(),
            targets: a.targets.clone(),
            radians,
            metres_per_unit: lengths.to_mm() * 1e-3,
            experiment: a.experiment.clone(),
        };
        free_poses(&file, &a.file, &desc, &how)
    };
    let stated = (matches!(a.angles, Angle::Rad), a.units.into());
    let set = read_as(stated.0, stated.1)?;
    if !a.skip_unit_check {
        target_unit_slip(&set, &a.file, &a.targets)?;
        super::checks::import_units(&set, &desc, &a.file, stated, |r, l| read_as(r, l).ok())?;
    }
    let source = format!(
        "imported by `axiscal import mat` from {}: joints `{}`, targets {}",
        a.file.display(),
        a.joints,
        a.targets
            .iter()
            .enumerate()
            .map(|(i, t)| format!("{i} = `{t}`"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let comment = format!(
        "{}# {}\n",
        super::checks::identity_comment(&desc),
        axiscal::csv_lines::one_line(&source)
    );
    write_csv_from(&a.output.out, outputs, &a.file, &comment, &set)?;
    println!(
        "imported {} free poses x {} targets from {} to {}",
        set.rows().len() / a.targets.len(),
        a.targets.len(),
        a.file.display(),
        a.output.out.display()
    );
    for (name, why) in &file.skipped {
        println!("  skipped variable `{name}`: {why}");
    }
    Ok(())
}
