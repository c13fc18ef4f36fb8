//! Checks between a command's inputs before any work: unit slips (`--skip-unit-check`) and
//! the identity of the robot description a calibration or a data file was made with
//! (`--allow-other-robot`).

use anyhow::{Context, Result, bail};
use axiscal::calibration::procedure::{Calibration, CalibrationOptions, calibrate};
use axiscal::calibration::record::CalibrationRecord;
use axiscal::kinematics::JointKind;
use axiscal::measurement::description_check::description_warnings;
use axiscal::measurement::import::points::LengthUnit;
use axiscal::measurement::unit_check::{
    UnitSlip, data_faults, description_slips, free_pose_scale_warning, judged_checks, measurement_slips,
    payload_over_robot_mass, pose_slips,
};
use axiscal::measurement::{MeasurementSet, format_f64};
use axiscal::robot::{DescriptionIdentity, RobotDescription};
use std::io::BufRead;
use std::path::Path;

/// The comment line that records, in a measurement CSV written by axiscal, the description the
/// data were made with: this prefix, then the identity as JSON.
pub const IDENTITY_COMMENT: &str = "# axiscal.description ";

/// The two overrides of these checks, shared by the commands that read a description with a
/// calibration or data made for it (`calibrate`, `diagnose`, `validate`, `compensate`).
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct Overrides {
    /// Skip the unit sanity checks (coordinates in m instead of mm, commands in rad instead of
    /// deg, description lengths in mm instead of m) when the units are right after all.
    #[arg(long)]
    pub skip_unit_check: bool,
    /// Go on even when the calibration or DATA records another robot description than
    /// `--robot` (a different geometry hash).
    #[arg(long)]
    pub allow_other_robot: bool,
}

/// One error naming `file` and every slip, or nothing.
fn refuse_slips(file: &Path, slips: &[UnitSlip]) -> Result<()> {
    if slips.is_empty() {
        return Ok(());
    }
    let all: Vec<String> = slips.iter().map(|s| format!("`{}`: {}", s.field, s.message)).collect();
    bail!(
        "{}: {}; if the units are right after all, pass --skip-unit-check",
        file.display(),
        all.join("; ")
    )
}

/// The description's own lengths (`rows[].a_m` in mm), unless `skip`; its warnings
/// ([`description_warnings`]: twists in radians, lengths zero, in cm or inches) printed.
pub fn description_units(desc: &RobotDescription, path: &Path, skip: bool) -> Result<()> {
    if skip {
        return Ok(());
    }
    refuse_slips(path, &description_slips(desc))?;
    print_warnings(&description_warning_lines(desc, path));
    Ok(())
}

/// [`description_warnings`] of `desc` read from `path`, with the chain its geometry was
/// converted from as the file writes it (read again: the description keeps only the converted
/// rows); a description inlined in a scenario is judged on its rows.
fn warnings_of(desc: &RobotDescription, path: &Path) -> Vec<UnitSlip> {
    let source = axiscal::presets::read_text(path)
        .ok()
        .and_then(|text| RobotDescription::with_source(&text, path).ok())
        .and_then(|(_, source)| source);
    description_warnings(desc, source.map(|(chain, _)| chain).as_ref())
}

/// One line per warning on the description `desc` read from `path`
/// ([`description_warnings`]), without `warning: `.
pub fn description_warning_lines(desc: &RobotDescription, path: &Path) -> Vec<String> {
    warnings_of(desc, path)
        .iter()
        .map(|w| {
            format!(
                "{}: `{}`: {} (--skip-unit-check silences this)",
                path.display(),
                w.field,
                w.message
            )
        })
        .collect()
}

/// A scenario's likely unit slips (its noise in m, its validation half-ranges in rad, its truth
/// model's rows in mm: [`axiscal::harness::scenario::units`]) read from `path`, unless `skip`.
pub fn scenario_units(slips: &[UnitSlip], path: &Path, skip: bool) -> Result<()> {
    if skip {
        return Ok(());
    }
    refuse_slips(path, slips)
}

/// A truth model's rows (`rows[].a_m` in mm) read from `path` (`simulate --truth`, a
/// scenario's `[truth] path`), unless `skip`: the description's row check
/// ([`axiscal::measurement::unit_check::row_slips`]).
pub fn truth_units(truth: &axiscal::robot::RobotModel, path: &Path, skip: bool) -> Result<()> {
    if skip {
        return Ok(());
    }
    refuse_slips(path, &axiscal::measurement::unit_check::row_slips(&truth.rows))
}

/// Required tool positions (a `--poses` file) against the robot's size, unless `skip`.
pub fn pose_units(
    positions_m: &[nalgebra::Point3<f64>],
    desc: &RobotDescription,
    file: &Path,
    skip: bool,
) -> Result<()> {
    if skip || positions_m.is_empty() {
        return Ok(());
    }
    refuse_slips(file, &Vec::from_iter(pose_slips(positions_m, desc)))
}

/// The data's coordinates and commands against the description, unless `skip`: the axis
/// experiments' arcs and the free poses' spread (a spread beyond
/// [`axiscal::measurement::unit_check::SPREAD_WARNING`] but not a slip is a warning, as a
/// command outside the joint limits is); the warnings returned, not printed.
pub fn data_unit_warnings(
    set: &MeasurementSet,
    desc: &RobotDescription,
    data: &Path,
    skip: bool,
    suspect: Option<&str>,
) -> Result<Vec<String>> {
    if skip {
        return Ok(Vec::new());
    }
    let mut slips: Vec<UnitSlip> = copied_command_column(set).into_iter().collect();
    slips.extend(measurement_slips(set, desc));
    if let (Some(last), Some(suspect)) = (slips.last_mut(), suspect) {
        last.message = format!("{}; {suspect}", last.message);
    }
    refuse_slips(data, &slips)?;
    let mut warnings: Vec<String> = commands_outside_limits(set, desc, data).into_iter().collect();
    warnings.extend(payload_over_robot(set, desc, data));
    warnings.extend(spread_warning(set, desc, data, suspect));
    Ok(warnings)
}

/// The free poses' spread beyond [`axiscal::measurement::unit_check::SPREAD_WARNING`] but not a
/// slip ([`free_pose_scale_warning`]) as a warning line about `data`, with `suspect` added.
fn spread_warning(set: &MeasurementSet, desc: &RobotDescription, data: &Path, suspect: Option<&str>) -> Option<String> {
    let scale = free_pose_scale_warning(set, desc)?;
    let suspect = suspect.map_or(String::new(), |s| format!("; {s}"));
    Some(format!(
        "{}: `{}`: {}{suspect} (--skip-unit-check silences this)",
        data.display(),
        scale.field,
        scale.message
    ))
}

/// An imported file without a unit slip that is still another robot's data: a spread no robot of
/// this description gives ([`spread_warning`]), else free poses its nominal robot misses by a
/// good part of their spread ([`axiscal::measurement::unit_check::not_this_robot`]).
fn another_robot(set: &MeasurementSet, desc: &RobotDescription, file: &Path) -> Vec<String> {
    if let Some(spread) = spread_warning(set, desc, file, None) {
        return vec![spread];
    }
    let said = |s: UnitSlip| {
        format!(
            "{}: `{}`: {} (--skip-unit-check silences this)",
            file.display(),
            s.field,
            s.message
        )
    };
    axiscal::measurement::unit_check::not_this_robot(set, desc)
        .map(said)
        .into_iter()
        .collect()
}

/// The options an import's units are read with: revolute joint values in radians (`--angles
/// rad`), and the length unit (`--units`).
pub type ImportUnits = (bool, LengthUnit);

/// `--angles` and `--units` of an import (`wide`, `mat`, `sscanss2`, `rct`) against the
/// description: the imported `set`'s unit slips ([`measurement_slips`], as `calibrate` checks
/// them). When the file read with other values of the options (`read_as`) passes every check
/// (no slip, no scale warning, and judged by as many checks: [`judged_checks`]), an error naming
/// each option and the value that fits; when such a reading shows a fault no unit explains (a
/// mirrored frame), an error naming the fault; other slips are a warning (another robot, or a
/// file's own slip).
pub fn import_units(
    set: &MeasurementSet,
    desc: &RobotDescription,
    file: &Path,
    stated: ImportUnits,
    read_as: impl Fn(bool, LengthUnit) -> Option<MeasurementSet>,
) -> Result<()> {
    let misfits = |set: &MeasurementSet| {
        let mut slips = measurement_slips(set, desc);
        slips.extend(rows_outside_limits(set, desc));
        slips
    };
    let slips = misfits(set);
    if slips.is_empty() {
        // No unit slip, but another robot's data?
        print_warnings(&another_robot(set, desc, file));
        return Ok(());
    }
    let said: Vec<String> = slips.iter().map(|s| format!("`{}`: {}", s.field, s.message)).collect();
    if !data_faults(set, desc).is_empty() {
        // No other --angles or --units mends a mirrored frame, rounded points or mislabelled rows.
        bail!(
            "{}: {}; if the data are right after all, pass --skip-unit-check",
            file.display(),
            said.join("; ")
        );
    }
    let angles = |radians: bool| if radians { "rad" } else { "deg" };
    let read_otherwise = |radians: bool, lengths: LengthUnit| {
        format!(
            "{}: read with --angles {} --units {} the file does not fit the description ({}); read with --angles {} \
             --units {}",
            file.display(),
            angles(stated.0),
            stated.1.name(),
            said.join("; "),
            angles(radians),
            lengths.name()
        )
    };
    let judged = judged_checks(set, desc);
    // Read in other units: (the options, the set) where it is judged as fully as read.
    let others: Vec<(ImportUnits, MeasurementSet)> = [
        (!stated.0, stated.1),
        (stated.0, other_length(stated.1)),
        (!stated.0, other_length(stated.1)),
    ]
    .into_iter()
    .filter_map(|units| Some((units, read_as(units.0, units.1)?)))
    .filter(|(_, other)| judged_checks(other, desc) >= judged)
    .collect();
    let fits = others
        .iter()
        .find(|(_, other)| misfits(other).is_empty() && free_pose_scale_warning(other, desc).is_none())
        .map(|(units, _)| *units);
    if let Some(((radians, lengths), fault)) = others
        .iter()
        .find_map(|(units, other)| Some((*units, data_faults(other, desc).into_iter().next()?)))
        .filter(|_| fits.is_none())
    {
        // The slips as read are this fault seen in the wrong units: the fault alone is said.
        bail!(
            "{}: --angles {} --units {} do not fit the description (`{}`), and read with --angles {} --units {} the \
             data show what no unit explains, `{}`: {}; if the data are right after all, pass --skip-unit-check",
            file.display(),
            angles(stated.0),
            stated.1.name(),
            slips.iter().map(|s| s.field.as_str()).collect::<Vec<_>>().join("`, `"),
            angles(radians),
            lengths.name(),
            fault.field,
            fault.message
        );
    }
    if let Some(((radians, lengths), outside)) = fits.is_none().then(|| units_but_limits(&others, desc)).flatten() {
        bail!(
            "{} its units fit, but `{}`: {}: pass {}, and check those rows' commands (a column scaled on export, or \
             the description's limits); if the units are right after all, pass --skip-unit-check",
            read_otherwise(radians, lengths),
            outside.field,
            outside.message,
            changed_options(stated, (radians, lengths))
        );
    }
    let Some((radians, lengths)) = fits else {
        print_warnings(&[format!(
            "{}: read with --angles {} --units {}: {} (no other --angles or --units explains it: another robot than --robot?; --skip-unit-check silences this)",
            file.display(),
            angles(stated.0),
            stated.1.name(),
            said.join("; ")
        )]);
        return Ok(());
    };
    bail!(
        "{} it does: pass {}; if the units are right after all, pass --skip-unit-check",
        read_otherwise(radians, lengths),
        changed_options(stated, (radians, lengths))
    )
}

/// The options that differ between the `stated` units of an import and `fitting` ones, as
/// command-line words (`--angles rad --units mm`).
fn changed_options(stated: ImportUnits, fitting: ImportUnits) -> String {
    let mut changed = Vec::new();
    if fitting.0 != stated.0 {
        changed.push(format!("--angles {}", if fitting.0 { "rad" } else { "deg" }));
    }
    if fitting.1 != stated.1 {
        changed.push(format!("--units {}", fitting.1.name()));
    }
    changed.join(" ")
}

/// Among the `others` readings of an import, the first whose units fit the description (no
/// unit slip, a plausible free-pose spread) but whose rows command joints outside its limits:
/// the units, and the limits' slip (a column scaled on export, which no unit mends).
fn units_but_limits(
    others: &[(ImportUnits, MeasurementSet)],
    desc: &RobotDescription,
) -> Option<(ImportUnits, UnitSlip)> {
    others.iter().find_map(|(units, other)| {
        let fits = measurement_slips(other, desc).is_empty() && free_pose_scale_warning(other, desc).is_none();
        fits.then(|| rows_outside_limits(other, desc))
            .flatten()
            .map(|slip| (*units, slip))
    })
}

/// The rows of `set` whose commands lie outside the description's joint limits, as a slip of
/// the first one's column: poses the robot cannot reach (`import_units`).
fn rows_outside_limits(set: &MeasurementSet, desc: &RobotDescription) -> Option<UnitSlip> {
    let mut outside = set.rows().iter().filter_map(|m| outside_limits(desc, &m.cmd));
    let (joint, cmd, [lo, hi]) = outside.next()?;
    let unit = axiscal::robot::file_unit(desc, joint - 1);
    Some(UnitSlip {
        field: format!("cmd_{joint}"),
        message: format!(
            "{} of the {} rows command a joint outside the description's limits (the first: cmd_{joint} = {} {unit}, limits [{lo}, {hi}] {unit})",
            outside.count() + 1,
            set.rows().len(),
            format_f64(cmd)
        ),
    })
}

/// The other length unit of an import (`--units mm` or `m`).
fn other_length(unit: LengthUnit) -> LengthUnit {
    match unit {
        LengthUnit::Mm => LengthUnit::M,
        LengthUnit::M => LengthUnit::Mm,
    }
}

/// Prints each of `warnings` as a `warning:` line on stderr.
pub fn print_warnings(warnings: &[String]) {
    for w in warnings {
        eprintln!("warning: {w}");
    }
}

/// A command column that holds a copy of an earlier one: `cmd_b` equal to `cmd_a` (`a < b`) in
/// every row, though an experiment sweeps joint `b` (its sweep holds joint `a` still while
/// joint `b` moves, so real data differ in that sweep at least, whatever the couplings: a
/// hold-still follower is joint `b + 1`, never an earlier one). Exact equality, no tolerance:
/// only a pasted or filled column repeats another to the last digit.
fn copied_command_column(set: &MeasurementSet) -> Option<UnitSlip> {
    let rows = set.rows();
    let dof = rows.first()?.cmd.len();
    let swept: std::collections::BTreeSet<usize> = rows.iter().map(|m| m.moved_joint).collect();
    let (a, b) = (0..dof)
        .flat_map(|b| (0..b).map(move |a| (a, b)))
        .find(|&(a, b)| swept.contains(&(b + 1)) && rows.iter().all(|m| m.cmd[a] == m.cmd[b]))?;
    let sweep = rows.iter().find(|m| m.moved_joint == b + 1)?;
    Some(UnitSlip {
        field: format!("cmd_{}", b + 1),
        message: format!(
            "holds the same value as `cmd_{}` in every one of the {} rows, though experiment {} sweeps joint {} (its \
             sweep holds joint {} still while joint {} moves): the column is a copy of `cmd_{}` (pasted or filled \
             into the wrong column); restore joint {}'s commands",
            a + 1,
            rows.len(),
            sweep.experiment,
            b + 1,
            a + 1,
            b + 1,
            a + 1,
            b + 1
        ),
    })
}

/// A warning naming the first row of `set` (read from `data`) whose command lies outside the
/// description's joint limits, and how many do: a pose the robot cannot reach is a command in
/// other units, a typo, or limits the description gets wrong.
fn commands_outside_limits(set: &MeasurementSet, desc: &RobotDescription, data: &Path) -> Option<String> {
    let mut outside = set
        .rows()
        .iter()
        .enumerate()
        .filter_map(|(r, m)| Some((r, outside_limits(desc, &m.cmd)?)));
    let (row, (joint, cmd, [lo, hi])) = outside.next()?;
    let others = outside.count();
    let place = set
        .line_of(row)
        .map_or_else(|| data.display().to_string(), |l| format!("{}:{l}", data.display()));
    let unit = axiscal::robot::file_unit(desc, joint - 1);
    Some(format!(
        "{place}: cmd_{joint} = {cmd} {unit} is outside joint {joint}'s limits [{lo}, {hi}] {unit}{}: the robot cannot reach it; check the commands' units and the description's limits",
        if others > 0 {
            format!(" ({} rows outside a limit in all)", others + 1)
        } else {
            String::new()
        }
    ))
}

/// A warning naming the first row of `set` (read from `data`) whose payload outweighs the
/// robot's links ([`payload_over_robot_mass`]), and how many rows do.
fn payload_over_robot(set: &MeasurementSet, desc: &RobotDescription, data: &Path) -> Option<String> {
    let (row, payload, robot_kg, rows) = payload_over_robot_mass(set, desc)?;
    let place = set
        .line_of(row)
        .map_or_else(|| data.display().to_string(), |l| format!("{}:{l}", data.display()));
    let all = if rows > 1 {
        format!(" ({rows} rows over it in all)")
    } else {
        String::new()
    };
    Some(format!(
        "{place}: payload_kg = {} kg is more than the robot's own moving mass ({} kg, the description's mass_kg){all}: \
         no arm carries its own weight; grams written as kg, or another robot? (--skip-unit-check silences this)",
        axiscal::measurement::format_f64(payload),
        axiscal::measurement::format_f64(robot_kg)
    ))
}

/// Refuses a set measured from several setups (instrument placements, the `setup` column) for
/// `what`, which takes one instrument frame: its rows would be compared across frames.
pub fn one_setup(set: &MeasurementSet, data: &Path, what: &str) -> Result<()> {
    let names = set.setup_names();
    if names.len() < 2 {
        return Ok(());
    }
    let first_other = (0..set.rows().len()).find(|&r| set.setup_of(r) > 0);
    let at = first_other.and_then(|r| set.line_of(r)).map_or_else(
        || data.display().to_string(),
        |line| format!("{}:{line}", data.display()),
    );
    bail!(
        "{at}: column `setup`: the rows come from {} setups ({}), each an instrument placement of its own; {what} \
         takes one instrument frame: split the file by setup (only the free-pose calibration, `calibrate` of a \
         file of free poses, places the robot in several)",
        names.len(),
        names.join(", ")
    )
}

/// The identity a measurement CSV written by axiscal records (its leading `#` lines), if any;
/// a recorded line that is not the identity's JSON (cut short, edited) is an error naming the
/// line: read as absent, it would skip the check against `--robot` without a word.
pub fn data_identity(path: &Path) -> Result<Option<DescriptionIdentity>> {
    if axiscal::presets::regular_file(path).is_err() {
        return Ok(None);
    }
    let Ok(file) = std::fs::File::open(path) else {
        return Ok(None);
    };
    let lines = std::io::BufReader::new(file).lines().map_while(Result::ok);
    let marker = IDENTITY_COMMENT.trim_end();
    for (i, line) in lines.enumerate().take_while(|(_, l)| l.starts_with('#')) {
        let Some(json) = line.strip_prefix(marker) else {
            continue;
        };
        return serde_json::from_str::<DescriptionIdentity>(json).map(Some).map_err(|e| {
            let why = if e.is_eof() {
                "it ends mid-record, cut short".to_owned()
            } else {
                format!("invalid JSON at column {}", marker.len() + e.column())
            };
            anyhow::anyhow!(
                "{}:{}: the `{marker}` line is not the description's record ({why}): it names the robot description \
                 the data were made with, checked against --robot; restore the line as axiscal wrote it, or delete \
                 it to read the file unchecked",
                path.display(),
                i + 1
            )
        });
    }
    Ok(None)
}

/// The comment line recording `desc` in a measurement CSV (with its line end).
pub fn identity_comment(desc: &RobotDescription) -> String {
    let json = serde_json::to_string(&desc.identity()).unwrap_or_default();
    format!("{IDENTITY_COMMENT}{json}\n")
}

/// Refuses `source` (made with `recorded`) with the description `desc` read from `robot`
/// when their geometries differ, unless `allow` (then a warning). Without a record it warns
/// (older files). The warning returned, not printed.
pub fn same_robot(
    recorded: Option<&DescriptionIdentity>,
    source: &Path,
    desc: &RobotDescription,
    robot: &Path,
    allow: bool,
) -> Result<Option<String>> {
    let current = desc.identity();
    Ok(match recorded {
        Some(r) if r.geometry_hash != current.geometry_hash && !allow => bail!(
            "{} was made with the robot description {r}, but --robot {} is {current}: results would be wrong for \
             this robot; give --robot the description file of \"{}\" (without --robot it is the shipped IRB/L6), \
             or pass --allow-other-robot if the change is intended",
            source.display(),
            robot.display(),
            r.name
        ),
        Some(r) if r.geometry_hash != current.geometry_hash => Some(format!(
            "{} was made with {r}, --robot {} is {current} (--allow-other-robot)",
            source.display(),
            robot.display()
        )),
        None if source.extension().is_some_and(|e| e == "json") => Some(format!(
            "{} records no robot description (written by an older axiscal): cannot check it matches --robot {}",
            source.display(),
            robot.display()
        )),
        _ => None,
    })
}

/// Reads a `calibration.json` (`docs/formats.md#calibration-json`) and checks its values
/// ([`Calibration::validate`]): a damaged file is one error naming the file and the field,
/// never a panic or a silently wrong result later.
pub fn read_calibration_file(path: &Path) -> Result<CalibrationRecord> {
    let text = axiscal::presets::read_text(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let record =
        CalibrationRecord::from_json(&text).with_context(|| format!("{}: not a calibration JSON", path.display()))?;
    record
        .calibration
        .validate()
        .with_context(|| path.display().to_string())?;
    Ok(record)
}

/// The calibration in `path` (`calibration.json` written by `axiscal calibrate`) with the
/// reports beside it, checked against the description `desc` read from `robot`: the same joint
/// count, and the same geometry unless `allow` ([`same_robot`]).
pub fn read_calibration(path: &Path, desc: &RobotDescription, robot: &Path, allow: bool) -> Result<CalibrationRecord> {
    let (record, warnings) = read_calibration_warned(path, desc, robot, allow)?;
    print_warnings(&warnings);
    Ok(record)
}

/// [`read_calibration`] with its warnings returned, not printed.
pub fn read_calibration_warned(
    path: &Path,
    desc: &RobotDescription,
    robot: &Path,
    allow: bool,
) -> Result<(CalibrationRecord, Vec<String>)> {
    let record = read_calibration_file(path)?;
    let cal = &record.calibration;
    let mut warnings = Vec::from_iter(same_robot(cal.description.as_ref(), path, desc, robot, allow)?);
    warnings.extend(edited_model(cal, path));
    if cal.robot.dof() != desc.dof() {
        bail!(
            "{} has {} joints but {} describes {}",
            path.display(),
            cal.robot.dof(),
            robot.display(),
            desc.dof()
        );
    }
    if let Some(k) = (0..desc.dof()).find(|&k| cal.robot.joints[k].kind != desc.joints[k].kind) {
        let kind = |k: JointKind| format!("{k:?}").to_lowercase();
        bail!(
            "{}: field `robot.joints[{k}].kind`: {}, but joint {} of {} is {}: the file was edited or belongs to \
             another robot; restore the file `axiscal calibrate` wrote (or recalibrate)",
            path.display(),
            kind(cal.robot.joints[k].kind),
            k + 1,
            robot.display(),
            kind(desc.joints[k].kind)
        );
    }
    if cal.model_digest.as_deref() != Some(cal.robot.digest().as_str()) {
        cal.plausible_for(desc).with_context(|| path.display().to_string())?;
    }
    Ok((record, warnings))
}

/// A warning when the calibration's `robot` is not the model `axiscal calibrate` wrote (its
/// `model_digest` differs): every result made with it uses the edited values.
fn edited_model(cal: &Calibration, path: &Path) -> Option<String> {
    let Some(recorded) = cal.model_digest.as_deref() else {
        return Some(format!(
            "{}: records no `model_digest` (written by an older axiscal, or removed): an edit of its `robot` cannot \
             be told from the model `axiscal calibrate` wrote; only its values' ranges were checked; recalibrate \
             to get a file that can be verified",
            path.display()
        ));
    };
    let current = cal.robot.digest();
    (recorded != current).then(|| {
        format!(
            "{}: `robot` was edited after `axiscal calibrate` wrote it (`model_digest` {recorded}, the values read \
             {current}): every result below uses the edited values; restore the file calibrate wrote (or \
             recalibrate) unless the edit is intended",
            path.display()
        )
    })
}

/// The measurement CSV `data` for the description `desc` read from `robot`: the robot it
/// records must be `desc` unless `overrides.allow_other_robot` ([`same_robot`]), its units are
/// checked unless `overrides.skip_unit_check` ([`data_unit_warnings`]); the warnings printed.
pub fn read_data(data: &Path, desc: &RobotDescription, robot: &Path, overrides: Overrides) -> Result<MeasurementSet> {
    let (set, warnings) = read_data_warned(data, desc, robot, overrides)?;
    print_warnings(&warnings);
    Ok(set)
}

/// [`read_data`] with its warnings returned, not printed.
pub fn read_data_warned(
    data: &Path,
    desc: &RobotDescription,
    robot: &Path,
    overrides: Overrides,
) -> Result<(MeasurementSet, Vec<String>)> {
    let recorded = data_identity(data);
    let identity = match &recorded {
        Ok(r) => same_robot(r.as_ref(), data, desc, robot, overrides.allow_other_robot)?,
        Err(_) => None,
    };
    let set = axiscal::measurement::read_measurements(data, Some(desc.dof()))?;
    // A record made unreadable by the file's own syntax (another separator, old Mac line
    // ends) is that syntax's error, said by the reader first.
    let mut warnings: Vec<String> = identity.into_iter().collect();
    let suspect = description_suspect(desc, robot, recorded?.as_ref());
    warnings.extend(data_unit_warnings(
        &set,
        desc,
        data,
        overrides.skip_unit_check,
        suspect.as_deref(),
    )?);
    warnings.extend(lone_target_warnings(&set, data));
    Ok((set, warnings))
}

/// A warning per target id seen once, where its step lacks one of the targets every other
/// step of its experiment sees ([`MeasurementSet::lone_targets`]): a mistyped id.
fn lone_target_warnings(set: &MeasurementSet, data: &Path) -> Vec<String> {
    let ids = |ids: &[usize]| ids.iter().map(|&t| set.target_name(t)).collect::<Vec<_>>().join(", ");
    set.lone_targets()
        .iter()
        .map(|l| {
            let at = set
                .line_of(l.row)
                .map_or_else(|| data.display().to_string(), |n| format!("{}:{n}", data.display()));
            format!(
                "{at}: column `target`: target {} is seen once, in this row only (experiment {}, step {}), where every \
                 other step of the experiment sees targets {} and this step lacks target {}: a mistyped id? (the row \
                 is used as a target of its own)",
                set.target_name(l.target),
                l.experiment,
                l.step,
                ids(&l.others),
                set.target_name(l.missing)
            )
        })
        .collect()
}

/// What a unit slip of data against the description `desc` (read from `robot`) may be besides
/// the data's: the description itself, unless the data record this very description (their
/// `# axiscal.description` line, made with it). Its own warnings ([`description_warnings`]) say
/// how; without them its lengths, twists or convention may still be another robot's, which
/// gives every arc another radius just as other units of the coordinates do.
pub fn description_suspect(
    desc: &RobotDescription,
    robot: &Path,
    recorded: Option<&DescriptionIdentity>,
) -> Option<String> {
    if recorded.is_some_and(|r| r.geometry_hash == desc.identity().geometry_hash) {
        return None;
    }
    let why = warnings_of(desc, robot).first().map_or_else(
        || {
            "its lengths, alpha_deg or dh_convention may be wrong (or its joint kinds, axis_targets), which moves \
             every arc too"
                .to_owned()
        },
        |w| format!("`{}`: {}", w.field, w.message),
    );
    let record = match recorded {
        Some(r) => format!("the data record another, {r}"),
        None => "the data record none to tell".to_owned(),
    };
    Some(format!(
        "or the description {} is not this robot's ({record}): {why}",
        robot.display()
    ))
}

/// The first joint whose command `cmd_file` (file units: deg or mm) lies outside the
/// description's limits: `(joint, command, [lower, upper])`.
pub fn outside_limits(desc: &RobotDescription, cmd_file: &[f64]) -> Option<(usize, f64, [f64; 2])> {
    desc.joints.iter().zip(cmd_file).enumerate().find_map(|(k, (j, &c))| {
        let [lo, hi] = j.limits;
        (!(lo..=hi).contains(&c)).then_some((k + 1, c, [lo, hi]))
    })
}

/// One warning line per free pose an outlier test flagged in `set` (read from `data`), with
/// the line of its first row; `done` is what the command did without it (`calibrated`,
/// `refined`).
pub fn print_pose_outliers(
    outliers: &[axiscal::calibration::free_pose::OutlierPose],
    set: &MeasurementSet,
    data: &Path,
    done: &str,
) {
    for o in outliers {
        let row = set
            .rows()
            .iter()
            .position(|m| m.experiment == o.experiment && m.step == o.step);
        let place = row
            .and_then(|r| set.line_of(r))
            .map_or_else(|| data.display().to_string(), |l| format!("{}:{l}", data.display()));
        let what = if o.dropped {
            format!("{done} without it (--keep-outliers keeps it)")
        } else {
            "kept (--keep-outliers)".to_string()
        };
        let check = match (o.spacing_departure_mm, o.spacing_fence_mm) {
            (Some(off), Some(fence)) if off <= fence => format!(
                "its targets agree with each other (their spacings within {off:.3} mm of every pose's, inside the {fence:.3} mm their noise reaches), so the tool as a whole sits off: the robot did not reach this pose as the others (its repeatability, an effect the model lacks) or its commands slipped; check its commands, else measure it again"
            ),
            (Some(off), Some(fence)) => format!(
                "its targets' spacings differ from every other pose's by {off:.3} mm (their noise reaches {fence:.3} mm): a target id swapped, one target's point off or the pose in other units; check its rows' target ids, coordinates and units"
            ),
            _ => "check its rows' target ids, coordinates, commands and units".to_string(),
        };
        let fence = match o.false_alarm {
            Some(rate) => format!(
                "its leverage in the fit and the noise of the poses near it allow, a clean file's poses passing with {:.0} % probability",
                100.0 * (1.0 - rate)
            ),
            None => "Q3 + 3 IQR of the poses' RMS".to_string(),
        };
        eprintln!(
            "warning: {place}: outlier pose: experiment {} step {}: RMS {:.4} mm beyond the fence {:.4} mm ({fence}): {what}; {check}",
            o.experiment, o.step, o.rms_mm, o.fence_mm
        );
    }
}

/// One warning line per point an outlier test flagged in `data` (a sweep's, or a validation
/// point, `joint` 0); `done` is what the command did without it (`calibrated`, `diagnosed`).
pub fn print_outliers(outliers: &[axiscal::calibration::procedure::OutlierPoint], data: &Path, done: &str) {
    print_warnings(&outlier_warnings(outliers, data, done));
    print_approach_notes(outliers, data, done);
}

/// One note per sweep's first point the outlier test found off only by its joint's backlash
/// (`approach`, [`axiscal::calibration::procedure::OutlierPoint`]): not a wrong row, so not a
/// warning; `done` as in [`print_outliers`].
pub fn print_approach_notes(outliers: &[axiscal::calibration::procedure::OutlierPoint], data: &Path, done: &str) {
    for o in outliers {
        let Some(turn) = o.approach else { continue };
        let (place, what) = outlier_place(o, data, done);
        // A turning joint's turn in mrad, a sliding one's travel in mm: both 1e3 times the value.
        eprintln!(
            "note: {place}: experiment {} step {}, the sweep's first point, taken before joint {} moved: {:.3} mm ahead \
             along the sweep's motion of the fit of its other points ({:.1} times their noise), as {:.2} mrad more of \
             the joint's turn (mm of a sliding joint's travel) would put it, and on it across the motion: the joint's backlash \
             (or a reversal's lost motion), taken up on the other side before the sweep's first move, not a wrong row: \
             {what}. Approach every sweep's first point in the direction the sweep then moves to keep it",
            o.experiment,
            o.step,
            o.joint,
            o.residual_mm,
            o.normalised_residual,
            turn * 1e3
        );
    }
}

/// A flagged point's place (`FILE:LINE`) and what the command did with it.
pub(super) fn outlier_place(
    o: &axiscal::calibration::procedure::OutlierPoint,
    data: &Path,
    done: &str,
) -> (String, String) {
    let place = o
        .line
        .map_or_else(|| data.display().to_string(), |l| format!("{}:{l}", data.display()));
    let what = if o.dropped {
        format!("{done} without it (--keep-outliers keeps it)")
    } else {
        "kept (--keep-outliers)".to_string()
    };
    (place, what)
}

/// [`print_outliers`]'s lines, without `warning: `.
pub fn outlier_warnings(
    outliers: &[axiscal::calibration::procedure::OutlierPoint],
    data: &Path,
    done: &str,
) -> Vec<String> {
    let mut lines = Vec::new();
    for o in outliers.iter().filter(|o| o.approach.is_none()) {
        let (place, what) = outlier_place(o, data, done);
        let clean_pass = format!(
            "a clean file's sweeps pass it with {:.0} % probability",
            100.0 * (1.0 - axiscal::calibration::procedure::SWEEP_POINTS_FALSE_ALARM)
        );
        let (from, noise, fence_of, check) = match (o.joint, o.target) {
            (0, _) => (
                "the calibrated model",
                "the noise",
                "Q3 + 3 IQR of every validation point's, at least what the noise reaches once in a hundred clean files), and far from its pose's other targets (an effect moves them alike",
                "coordinates and target id",
            ),
            // A sweep's second target, judged by its passive angle (eqs. 14-15).
            (_, 1) => (
                "the curve of its neighbours' passive angles",
                "their scatter",
                "Q3 + 3 IQR of every sweep point's",
                "coordinates and target id (a reading swapped with another step's)",
            ),
            _ => (
                "the fit of its sweep's other points",
                "the noise of the sweep's other points",
                clean_pass.as_str(),
                "coordinates and commands",
            ),
        };
        lines.push(format!(
            "{place}: outlier: experiment {} step {} target {}: {:.3} mm from {from}, {:.1} times {noise}, beyond the fence {:.1} ({fence_of}): {what}; check this row's {check}",
            o.experiment, o.step, o.target, o.residual_mm, o.normalised_residual, o.fence
        ));
    }
    lines
}

/// Why a calibration (or a validation, a diagnosis) with `--noise-mm given_mm` failed when the
/// data scatter far more than that: the calibration of `set`'s axis experiments weighted with
/// the noise their residuals estimate succeeds, and `given_mm` lies below that estimate's 95 %
/// interval. Names the failed joint `failed_joint` (else the one whose residuals are the
/// largest) and its residual RMS against `given_mm`; `None` when `given_mm` is within the
/// estimate or `set` has no axis experiment to estimate it from. `failing` names what failed
/// (`the fits`), `without` what they are weighted with when `--noise-mm` is not given (`it`:
/// the estimate).
pub fn noise_far_below(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
    given_mm: f64,
    failed_joint: Option<usize>,
    [failing, without]: [&str; 2],
) -> Option<String> {
    // As without --noise-mm: a first pass at the default noise, then the estimate's.
    let estimating = CalibrationOptions {
        estimate_noise: true,
        noise_rms_3d_mm: CalibrationOptions::default().noise_rms_3d_mm,
        ..options.clone()
    };
    let cal = calibrate(set, desc, &estimating).ok()?;
    let estimate = cal.noise.as_ref()?.estimate.as_ref()?;
    if given_mm >= estimate.interval.low_mm {
        return None;
    }
    let largest = || {
        cal.axes
            .iter()
            .max_by(|a, b| a.residual_rms_mm.total_cmp(&b.residual_rms_mm))
    };
    let axis = failed_joint
        .and_then(|j| cal.axes.iter().find(|a| a.joint == j))
        .or_else(largest)?;
    Some(format!(
        "experiment {} (joint {}): the residuals ({:.4} mm RMS) are {:.0} times --noise-mm {}; --noise-mm is too \
         small or the data are bad: {failing} weighted with it fail, while the residuals estimate a noise of {:.4} mm \
         (95 % interval {:.4}-{:.4} mm; without --noise-mm {failing} are weighted with {without})",
        axis.experiment,
        axis.joint,
        axis.residual_rms_mm,
        axis.residual_rms_mm / given_mm,
        axiscal::measurement::format_f64(given_mm),
        estimate.rms_3d_mm,
        estimate.interval.low_mm,
        estimate.interval.high_mm
    ))
}

/// A slip found in `data` ([`axiscal::diagnosis::ExplainedMiss`]) in words: the file and line
/// of its first row, its columns and what it is.
pub fn explained_miss_words(m: &axiscal::diagnosis::ExplainedMiss, data: &Path) -> String {
    let place = m
        .line
        .map_or_else(|| data.display().to_string(), |l| format!("{}:{l}", data.display()));
    format!("{place}: `{}`: {}", m.field, m.message)
}

/// The free-pose misses a slip in `data` explains ([`axiscal::diagnosis::explained_misses`]) as
/// one error naming the file, the first row's line and the column, unless `skip`
/// (`--skip-unit-check`): the model is not blamed for a column in other units.
pub fn refuse_explained_misses(misses: &[axiscal::diagnosis::ExplainedMiss], data: &Path, skip: bool) -> Result<()> {
    if skip || misses.is_empty() {
        return Ok(());
    }
    let all: Vec<String> = misses.iter().map(|m| explained_miss_words(m, data)).collect();
    bail!(
        "{}; if the units are right after all, pass --skip-unit-check",
        all.join("; ")
    )
}

/// The warning of a sweep whose first or last points sit off its others (`end`): the points
/// named by their lines, since two moved points at an end cannot be told from two wrong
/// readings; the offset is the end points' from the others.
fn print_sweep_end(
    b: &axiscal::calibration::procedure::SweepBump,
    end: &axiscal::calibration::procedure::SweepEnd,
    data: &Path,
) {
    let file = data.display();
    let place = end.points[0]
        .1
        .map_or_else(|| file.to_string(), |l| format!("{file}:{l}"));
    let lines: Vec<String> = end.points.iter().filter_map(|p| p.1.map(|l| l.to_string())).collect();
    let steps: Vec<String> = end.points.iter().map(|p| p.0.to_string()).collect();
    let rows = match lines.len() == end.points.len() {
        true => format!("lines {}, steps {}", lines.join(", "), steps.join(", ")),
        false => format!("steps {}", steps.join(", ")),
    };
    let sign = if end.first { -1.0 } else { 1.0 };
    let [x, y, z] = b.shift_mm.map(|v| sign * v);
    let [sx, sy, sz] = b.shift_sigma_mm;
    let (which, others, moved) = match end.first {
        true => (
            "first",
            "later",
            "after them (every later row of the file is then in its new place too)",
        ),
        false => ("last", "earlier", "before them"),
    };
    eprintln!(
        "warning: {place}: experiment {}'s {which} {} of {} points ({rows}) sit ({x:.2}, {y:.2}, {z:.2}) \
         (+- {sx:.2}, {sy:.2}, {sz:.2}) mm off its {others} points (p = {:.1e} over the {} sweep ends tried in the \
         file; the sweep's fit RMS {:.3} mm as written, {:.3} mm with them moved back): the instrument or the target \
         moved {moved}, or these rows are wrong readings (two points at a sweep's end look alike either way). The fits \
         take them into joint {}'s axis and transmission, so a calibration from this file is wrong for that joint: \
         check these rows, measure them again or drop them",
        b.experiment,
        end.points.len(),
        b.tested,
        b.p_value,
        b.blocks_tried,
        b.rms_mm.0,
        b.rms_mm.1,
        b.joint,
    );
}

/// That the search of slips in runs of rows and of two slips at once did not run on `rows` rows
/// (read from `data`): more than [`axiscal::diagnosis::MAX_SEARCH_ROWS`].
pub fn unsearched_words(rows: usize, data: &Path) -> String {
    format!(
        "the search for slips in runs of rows and for two slips at once runs on up to {} rows, and these are {} rows of {}: \
         it was not run",
        axiscal::diagnosis::MAX_SEARCH_ROWS,
        rows,
        data.display()
    )
}

/// One warning per sweep whose points from one step on sit off its earlier ones (two where
/// they shift twice; [`axiscal::calibration::procedure::SweepBump`]): the instrument or the
/// target moved during the sweep.
pub fn print_sweep_bumps(bumps: &[axiscal::calibration::procedure::SweepBump], data: &Path) {
    for b in bumps {
        if let Some(end) = &b.end {
            print_sweep_end(b, end, data);
            continue;
        }
        let place = b
            .line
            .map_or_else(|| data.display().to_string(), |l| format!("{}:{l}", data.display()));
        let [x, y, z] = b.shift_mm;
        let [sx, sy, sz] = b.shift_sigma_mm;
        let (twice, tried, moved) = match b.beside {
            Some(other) => (
                format!(
                    " (one of two steps in this sweep, the other from step {other} on: each block's shift is from \
                     the points before it)"
                ),
                "pairs of change points",
                "both blocks",
            ),
            None => (String::new(), "change points", "them"),
        };
        eprintln!(
            "warning: {place}: experiment {}'s last {} of {} points, from step {} on, sit ({x:.2}, {y:.2}, {z:.2}) \
             (+- {sx:.2}, {sy:.2}, {sz:.2}) mm off its earlier points{twice} (p = {:.1e} over the {} {tried} tried in the \
             file's sweeps; the sweep's fit RMS {:.3} mm as written, {:.3} mm with {moved} moved back): the \
             instrument or the target moved during the sweep (bumped, re-set up, the target re-seated). The fits take \
             the step into joint {}'s axis and transmission, so a calibration from this file is wrong for that joint; \
             if the instrument moved, every later row is in its new place too: measure the sweep again, or split the \
             file at that line",
            b.experiment, b.points, b.tested, b.step, b.p_value, b.blocks_tried, b.rms_mm.0, b.rms_mm.1, b.joint,
        );
    }
}
