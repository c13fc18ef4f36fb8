//! Finding the columns of a measurement CSV by name in its header (module docs of
//! [`super`]): the known columns, each at most once, and `cmd_1..cmd_N`.

use super::{Columns, MeasurementFileError, POSITION_COLUMNS};
use std::collections::HashMap;
use std::path::Path;

/// The header's known columns by name, and the `cmd_k` columns by joint `k` (1-based); a
/// known column given twice is an error.
type HeaderColumns = (HashMap<String, usize>, HashMap<usize, usize>);

/// Indexes the columns of `header` (at `line` of `path`), see [`HeaderColumns`]. Names are
/// matched without regard to ASCII case (`X_MM` is `x_mm`).
fn index_columns(header: &csv::StringRecord, path: &Path, line: u64) -> Result<HeaderColumns, MeasurementFileError> {
    let mut index: HashMap<String, usize> = HashMap::new();
    let mut cmd: HashMap<usize, usize> = HashMap::new();
    // A byte-order mark (spreadsheet exports) is not part of the first column's name.
    for (i, name) in header
        .iter()
        .map(|n| n.trim_start_matches('\u{feff}').trim().to_ascii_lowercase())
        .enumerate()
    {
        let name = name.as_str();
        let k = name
            .strip_prefix("cmd_")
            .and_then(|k| k.parse::<usize>().ok())
            .filter(|&k| k >= 1);
        let known = k.is_some()
            || [
                "experiment",
                "moved_joint",
                "step",
                "target",
                "payload_kg",
                "temperature_c",
                "setup",
            ]
            .contains(&name)
            || POSITION_COLUMNS.contains(&name);
        if known && index.insert(name.to_owned(), i).is_some() {
            return Err(MeasurementFileError::DuplicateColumn {
                path: path.into(),
                line,
                column: name.into(),
            });
        }
        if let Some(k) = k {
            if name != format!("cmd_{k}") {
                return Err(MeasurementFileError::CommandColumnSpelling {
                    path: path.into(),
                    line,
                    found: crate::csv_lines::shown_cell(name),
                    joint: k,
                    column: format!("cmd_{k}"),
                });
            }
            cmd.insert(k, i);
        }
    }
    Ok((index, cmd))
}

/// The number of joints the `cmd_k` columns (`cmd`: joint to column) give: `joint_count` when
/// given (exactly `cmd_1..cmd_n` required), else as many as there are, without gaps.
fn command_joint_count(
    cmd: &HashMap<usize, usize>,
    joint_count: Option<usize>,
    path: &Path,
    line: u64,
) -> Result<usize, MeasurementFileError> {
    let columns_found = cmd.len();
    Ok(match joint_count {
        Some(n) => {
            let extra = cmd.keys().copied().filter(|&k| k > n).min();
            let missing = (1..=n).find(|k| !cmd.contains_key(k));
            if let Some(k) = extra.or(missing) {
                let column = format!("cmd_{k}");
                return Err(MeasurementFileError::JointCount {
                    path: path.into(),
                    line,
                    column,
                    found: columns_found,
                    expected: n,
                });
            }
            n
        }
        None => {
            let n = columns_found;
            if let Some(k) = (1..=n.max(1)).find(|k| !cmd.contains_key(k)) {
                return Err(MeasurementFileError::MissingColumn {
                    path: path.into(),
                    line,
                    column: format!("cmd_{k}"),
                });
            }
            n
        }
    })
}

/// Columns only another axiscal output (or input) has, and what that file is: a header with one
/// of them and without the measurement's `x_mm` or `cmd_1` is that file, given in the wrong place.
const OTHER_FILES: [(&str, &str); 7] = [
    (
        "radial_mm",
        "the residuals table `calibrate` and `validate` write (residuals.csv)",
    ),
    ("send_x_mm", "`compensate`'s table of corrected commands"),
    (
        "roll_deg",
        "a pose list for `compensate --poses` (target poses, no joint commands)",
    ),
    ("output_unit", "`calibrate`'s joint map (joint_map.csv)"),
    ("offset", "`calibrate`'s zero offsets (zero_offsets.csv)"),
    ("uncal_pos_rms_mm", "a study's table of trials (trials.csv)"),
    ("cal_position_mm", "`evaluate`'s table of test poses (poses.csv)"),
];

/// Which other axiscal file (see [`OTHER_FILES`]) a header of known columns `index` and any
/// column `names` is, if it lacks a measurement's position or first command column.
fn other_file(names: &[String], index: &HashMap<String, usize>) -> Option<&'static str> {
    if index.contains_key("x_mm") && index.contains_key("cmd_1") {
        return None;
    }
    OTHER_FILES
        .iter()
        .find(|(column, _)| names.iter().any(|n| n == column))
        .map(|(_, what)| *what)
}

/// The columns a measurement CSV must have (besides `cmd_1..cmd_N`).
const REQUIRED: [&str; 7] = ["experiment", "moved_joint", "step", "target", "x_mm", "y_mm", "z_mm"];

/// `name` with every character that looks like a space, an underscore or a dash (U+00A0, the
/// Unicode dashes, a full-width low line) written as `_`, lower-cased: `cmd 1` (a non-breaking
/// space copied from a web page or a word processor) reads `cmd_1`.
fn look_alike_name(name: &str) -> String {
    name.trim_start_matches('\u{feff}')
        .trim()
        .chars()
        .map(|c| match c {
            c if c.is_whitespace() => '_',
            '-' | '\u{2010}'..='\u{2015}' | '\u{2212}' | '\u{2017}' | '\u{ff3f}' | '\u{ff0d}' => '_',
            c => c.to_ascii_lowercase(),
        })
        .collect()
}

/// A required column (or `cmd_k` of the `joint_count` expected, or `cmd_1`) missing from
/// `index` whose name a header name spells with a look-alike character ([`look_alike_name`]):
/// an error naming both, rather than the column's absence (or "0 joint command columns").
fn look_alike_columns(
    header: &csv::StringRecord,
    index: &HashMap<String, usize>,
    joint_count: Option<usize>,
    path: &Path,
    line: u64,
) -> Result<(), MeasurementFileError> {
    let commands = (1..=joint_count.unwrap_or(1)).map(|k| format!("cmd_{k}"));
    for column in REQUIRED.iter().map(|c| c.to_string()).chain(commands) {
        if index.contains_key(&column) {
            continue;
        }
        if let Some(found) = header.iter().find(|n| look_alike_name(n) == column) {
            return Err(MeasurementFileError::LookAlikeColumn {
                path: path.into(),
                line,
                column,
                found: found.escape_debug().to_string(),
            });
        }
    }
    Ok(())
}

/// Length units a coordinate column's header may carry, as written after the coordinate's
/// letter with every other character dropped, and the factor to millimetres.
const HEADER_LENGTH_UNITS: [(&str, f64); 6] = [
    ("mm", 1.0),
    ("m", 1e3),
    ("cm", 10.0),
    ("in", 25.4),
    ("inch", 25.4),
    ("um", 1e-3),
];

/// A coordinate column (`x_mm`, `y_mm`, `z_mm`) missing from `index` whose coordinate a header
/// name writes with its unit otherwise (`X [mm]`, `x(m)`, `X`; lower-cased, every character but
/// letters dropped): an error naming both, with the rename (and the conversion to millimetres
/// its unit needs), rather than the column's absence.
fn spelled_coordinates(
    header: &csv::StringRecord,
    index: &HashMap<String, usize>,
    path: &Path,
    line: u64,
) -> Result<(), MeasurementFileError> {
    for axis in ["x", "y", "z"] {
        let column = format!("{axis}_mm");
        if index.contains_key(&column) {
            continue;
        }
        for found in header.iter() {
            let letters: String = found
                .chars()
                .filter(char::is_ascii_alphabetic)
                .map(|c| c.to_ascii_lowercase())
                .collect();
            let Some(unit) = letters.strip_prefix(axis) else {
                continue;
            };
            let advice = match HEADER_LENGTH_UNITS.iter().find(|(u, _)| *u == unit) {
                None if unit.is_empty() => format!(
                    "without a unit: rename it `{column}` if it holds millimetres (else convert it to millimetres first)"
                ),
                None => continue,
                Some((u, _)) if *u == "mm" => format!("in {u}: rename it `{column}`"),
                Some((u, factor)) => format!(
                    "in {u}: multiply it by {} to millimetres and name it `{column}`",
                    crate::measurement::format_f64(*factor)
                ),
            };
            return Err(MeasurementFileError::CoordinateSpelled {
                path: path.into(),
                line,
                column,
                found: found.escape_debug().to_string(),
                advice,
            });
        }
    }
    Ok(())
}

/// The columns of the file's `header` (at `line` of `path`), checked against `joint_count`.
pub(super) fn find_columns(
    header: &csv::StringRecord,
    path: &Path,
    line: u64,
    joint_count: Option<usize>,
) -> Result<Columns, MeasurementFileError> {
    if header.len() == 1
        && let Some(separator) = crate::csv_lines::foreign_separator(header.get(0).unwrap_or_default())
    {
        return Err(MeasurementFileError::WrongSeparator {
            path: path.into(),
            line,
            separator: separator.into(),
        });
    }
    let (index, cmd) = index_columns(header, path, line)?;
    let names: Vec<String> = header.iter().map(|n| n.trim().to_ascii_lowercase()).collect();
    if let Some(what) = other_file(&names, &index) {
        return Err(MeasurementFileError::OtherFile {
            path: path.into(),
            what: what.into(),
        });
    }
    look_alike_columns(header, &index, joint_count, path, line)?;
    spelled_coordinates(header, &index, path, line)?;
    let required = |column: &str| {
        index
            .get(column)
            .copied()
            .ok_or_else(|| MeasurementFileError::MissingColumn {
                path: path.into(),
                line,
                column: column.into(),
            })
    };
    let n = command_joint_count(&cmd, joint_count, path, line)?;
    Ok(Columns {
        experiment: required("experiment")?,
        moved_joint: required("moved_joint")?,
        step: required("step")?,
        target: required("target")?,
        position: [required("x_mm")?, required("y_mm")?, required("z_mm")?],
        cmd: (1..=n).map(|k| cmd[&k]).collect(),
        payload_kg: index.get("payload_kg").copied(),
        temperature_c: index.get("temperature_c").copied(),
        setup: index.get("setup").copied(),
    })
}
