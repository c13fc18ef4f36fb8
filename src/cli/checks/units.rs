//! The unit checks of a command's inputs (`--skip-unit-check`): a description's lengths and
//! limits, a scenario's and a truth model's values, a data file's coordinates and commands, an
//! import's units.

use super::identity::outside_limits;
use super::print_warnings;
use anyhow::{Result, bail};
use axiscal::measurement::description_check::description_warnings;
use axiscal::measurement::import::points::LengthUnit;
use axiscal::measurement::unit_check::{
    UnitSlip, data_faults, description_slips, free_pose_scale_warning, judged_checks, measurement_slips,
    payload_over_robot_mass, pose_slips,
};
use axiscal::measurement::{MeasurementSet, format_f64};
use axiscal::robot::RobotDescription;
use std::path::Path;

/// The largest of `angles_deg` when every one lies within a radian's turn (+-2 pi, read as
/// degrees) and some exceeds 1: angles written in radians (a tool pointing down has a roll of
/// pi; a joint reading of a few radians). Degrees that small keep every angle within 6.3 deg
/// of zero; `None` otherwise, and for no angles.
pub fn within_a_radians_turn(angles_deg: impl IntoIterator<Item = f64>) -> Option<f64> {
    let largest = angles_deg.into_iter().fold(0.0f64, |m, a| m.max(a.abs()));
    (largest > 1.0 && largest <= std::f64::consts::TAU).then_some(largest)
}

/// One error naming `file` and every slip, or nothing.
pub(super) fn refuse_slips(file: &Path, slips: &[UnitSlip]) -> Result<()> {
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
pub(super) fn warnings_of(desc: &RobotDescription, path: &Path) -> Vec<UnitSlip> {
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
pub(super) fn spread_warning(
    set: &MeasurementSet,
    desc: &RobotDescription,
    data: &Path,
    suspect: Option<&str>,
) -> Option<String> {
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
pub(super) fn another_robot(set: &MeasurementSet, desc: &RobotDescription, file: &Path) -> Vec<String> {
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
pub(super) fn changed_options(stated: ImportUnits, fitting: ImportUnits) -> String {
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
pub(super) fn units_but_limits(
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
pub(super) fn rows_outside_limits(set: &MeasurementSet, desc: &RobotDescription) -> Option<UnitSlip> {
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
pub(super) fn other_length(unit: LengthUnit) -> LengthUnit {
    match unit {
        LengthUnit::Mm => LengthUnit::M,
        LengthUnit::M => LengthUnit::Mm,
    }
}

/// A command column that holds a copy of an earlier one: `cmd_b` equal to `cmd_a` (`a < b`) in
/// every row, though an experiment sweeps joint `b` (its sweep holds joint `a` still while
/// joint `b` moves, so real data differ in that sweep at least, whatever the couplings: a
/// hold-still follower is joint `b + 1`, never an earlier one). Exact equality, no tolerance:
/// only a pasted or filled column repeats another to the last digit.
pub(super) fn copied_command_column(set: &MeasurementSet) -> Option<UnitSlip> {
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
pub(super) fn commands_outside_limits(set: &MeasurementSet, desc: &RobotDescription, data: &Path) -> Option<String> {
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
pub(super) fn payload_over_robot(set: &MeasurementSet, desc: &RobotDescription, data: &Path) -> Option<String> {
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
