//! The robot description a calibration or a data file was made with, checked against
//! `--robot` (`--allow-other-robot`), and the readers of those files that check it.

use super::IDENTITY_COMMENT;
use super::Overrides;
use super::print_warnings;
use super::units::data_unit_warnings;
use super::units::warnings_of;
use anyhow::{Context, Result, bail};
use axiscal::calibration::procedure::Calibration;
use axiscal::calibration::record::CalibrationRecord;
use axiscal::kinematics::JointKind;
use axiscal::measurement::MeasurementSet;
use axiscal::robot::{DescriptionIdentity, RobotDescription};
use std::io::BufRead;
use std::path::Path;

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
    warnings.extend(record.reports.warnings.iter().map(|w| {
        format!(
            "{}: `axiscal calibrate` warned of this when it wrote the file (key `warnings`), and every result made with \
             it carries it: {w}",
            path.display()
        )
    }));
    Ok((record, warnings))
}

/// A warning when the calibration's `robot` is not the model `axiscal calibrate` wrote (its
/// `model_digest` differs): every result made with it uses the edited values.
pub(super) fn edited_model(cal: &Calibration, path: &Path) -> Option<String> {
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
pub(super) fn lone_target_warnings(set: &MeasurementSet, data: &Path) -> Vec<String> {
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
/// `# axiscal.description` line, made with it). Its own warnings ([`axiscal::measurement::description_check::description_warnings`]) say
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
