//! SScanSS-2's calibration file (`docs/formats.md#sscanss-2-calibration-file`): the file its
//! "Generate Robot Model" tool reads. No header; per measured point 7 comma- or
//! white-space-delimited columns: the joint moved (1-based), the point's `x, y, z` (instrument
//! frame), the joint's value at it (deg revolute, mm prismatic), the joint's type
//! (`revolute` / `prismatic`) and the joint's home value. One joint moves at a time, every
//! other at its home value.
//!
//! Each run of consecutive rows of one joint is an axis experiment `joint<k>` (a later run of
//! the same joint `joint<k>-2`, ...) of target 0; a held joint's command is its home value.

use super::points::{LengthUnit, PointsError};
use crate::csv_lines::{foreign_separator, is_decimal_comma, shown_cell};
use crate::kinematics::JointKind;
use crate::measurement::resolution::INSTRUMENT_RESOLUTION_MM;
use crate::measurement::{Measurement, MeasurementSet};
use std::path::{Path, PathBuf};

/// Columns of a row, in order (the names messages use).
const COLUMNS: [&str; 7] = ["joint", "x", "y", "z", "value", "type", "home"];

/// One parsed row.
#[derive(Clone, Debug)]
struct Row {
    line: usize,
    joint: usize,
    point: [f64; 3],
    value: f64,
    kind: JointKind,
    home: f64,
}

/// Reads SScanSS-2's calibration file `text` (`path` labels messages) for a robot whose joints
/// are `kinds`; coordinates in `unit`, revolute joint values in radians when `radians` (the
/// format's are degrees). Every joint type and home value is checked against the others of its
/// joint and the type against `kinds`.
pub fn parse(
    text: &str,
    path: &Path,
    kinds: &[JointKind],
    unit: LengthUnit,
    radians: bool,
) -> Result<MeasurementSet, PointsError> {
    let rows = rows(text, path, kinds.len(), unit, radians)?;
    let homes = homes(&rows, path, kinds)?;
    check_runs(&rows, path)?;
    check_repeats(&rows, path)?;
    let mut out = Vec::with_capacity(rows.len());
    let mut runs = vec![0usize; kinds.len()];
    let mut step = 0;
    for (i, r) in rows.iter().enumerate() {
        if i == 0 || rows[i - 1].joint != r.joint {
            runs[r.joint - 1] += 1;
            step = 0;
        }
        let run = runs[r.joint - 1];
        let mut cmd = homes.clone();
        cmd[r.joint - 1] = r.value;
        out.push(Measurement {
            experiment: if run == 1 {
                format!("joint{}", r.joint)
            } else {
                format!("joint{}-{run}", r.joint)
            },
            moved_joint: r.joint,
            step,
            target: 0,
            position_mm: r.point,
            cmd,
            payload_kg: Measurement::DEFAULT_PAYLOAD_KG,
            temperature_c: Measurement::DEFAULT_TEMPERATURE_C,
        });
        step += 1;
    }
    MeasurementSet::new(kinds.len(), out).map_err(|e| set_error(&rows, e, path))
}

/// A [`crate::measurement::MeasurementSetError`] of the imported rows at the file's line and
/// column (the set's `x_mm` is column `x`, its `cmd_k` the row's `value` or `home`).
fn set_error(rows: &[Row], e: crate::measurement::MeasurementSetError, path: &Path) -> PointsError {
    let Some(r) = rows.get(e.row) else {
        return PointsError::Set {
            path: path.to_owned(),
            cause: e,
        };
    };
    let column = match e.problem.column().as_str() {
        "x_mm" => 1,
        "y_mm" => 2,
        "z_mm" => 3,
        c => match c.strip_prefix("cmd_").and_then(|k| k.parse::<usize>().ok()) {
            Some(k) if k == r.joint => 4,
            Some(_) => 6,
            None => 0,
        },
    };
    row_error(path, r.line, column, e.problem.to_string())
}

/// Refuses a row that repeats an earlier row of its run cell for cell (the same joint value and
/// point, which two measurements never are): a row written twice, which would count twice.
fn check_repeats(rows: &[Row], path: &Path) -> Result<(), PointsError> {
    let mut seen: std::collections::HashMap<(usize, u64, [u64; 3]), usize> = std::collections::HashMap::new();
    for r in rows {
        let key = (r.joint, r.value.to_bits(), r.point.map(f64::to_bits));
        if let Some(first) = seen.insert(key, r.line) {
            return Err(row_error(
                path,
                r.line,
                0,
                format!(
                    "line {} repeats line {first} cell for cell (the joint value and the point the same, which two measurements never are): a row written twice; delete one of them",
                    r.line
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses a run of one row: a sweep needs points, and single rows between other joints' are
/// a file sorted otherwise than by joint (by step, say), which would import as one experiment
/// per row.
fn check_runs(rows: &[Row], path: &Path) -> Result<(), PointsError> {
    let starts: Vec<usize> = (0..rows.len())
        .filter(|&i| i == 0 || rows[i - 1].joint != rows[i].joint)
        .collect();
    let lone: Vec<usize> = (0..starts.len())
        .filter(|&k| starts.get(k + 1).unwrap_or(&rows.len()) - starts[k] == 1)
        .map(|k| starts[k])
        .collect();
    let Some(&first) = lone.first() else {
        return Ok(());
    };
    let r = &rows[first];
    let neighbours: Vec<String> = [first.checked_sub(1), Some(first + 1)]
        .into_iter()
        .flatten()
        .filter_map(|i| rows.get(i))
        .map(|n| format!("line {} is joint {}", n.line, n.joint))
        .collect();
    Err(row_error(
        path,
        r.line,
        0,
        format!(
            "the row of joint {} stands alone ({}; {} of the file's {} runs of one joint have a single row): SScanSS-2 files list each joint's points together; sort the rows by joint, keeping each joint's order",
            r.joint,
            neighbours.join(", "),
            lone.len(),
            starts.len()
        ),
    ))
}

/// The data rows (blank and `#` lines skipped).
fn rows(text: &str, path: &Path, joints: usize, unit: LengthUnit, radians: bool) -> Result<Vec<Row>, PointsError> {
    let mut rows = Vec::new();
    for (i, line) in text.trim_start_matches('\u{feff}').lines().enumerate() {
        let trimmed = line.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        if let Some(separator) = foreign_separator_of(trimmed) {
            return Err(PointsError::File {
                path: path.to_owned(),
                message: format!(
                    "line {}: the cells are separated by {separator} (`{}`): SScanSS-2 calibration files separate \
                     them with commas or white space; export the file with commas (a decimal comma then becomes a \
                     point) or replace each {separator} with a comma",
                    i + 1,
                    shown_cell(trimmed)
                ),
            });
        }
        if rows.is_empty() && is_header(trimmed) {
            return Err(PointsError::File {
                path: path.to_owned(),
                message: format!(
                    "line {} is a header (`{}`): SScanSS-2 calibration files have none and start with data; remove the line",
                    i + 1,
                    shown_cell(trimmed)
                ),
            });
        }
        rows.push(row(trimmed, i + 1, path, joints, unit, radians)?);
    }
    if rows.is_empty() {
        return Err(PointsError::File {
            path: path.to_owned(),
            message: "no data row (SScanSS-2's calibration file: 7 columns per measured point)".into(),
        });
    }
    Ok(rows)
}

/// The separator, in words, a line holds instead of the format's commas and white space
/// ([`foreign_separator`]; a tab is white space here): a file exported with another
/// separator, whose line would otherwise be taken for a header or a row of one cell.
fn foreign_separator_of(line_text: &str) -> Option<&'static str> {
    foreign_separator(line_text).filter(|_| !line_text.contains(',') && !line_text.contains('\t'))
}

/// Whether a line is a header: none of its first two cells (the joint and `x`) is a number.
fn is_header(line_text: &str) -> bool {
    line_text
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|c| !c.is_empty())
        .take(2)
        .all(|c| c.parse::<f64>().is_err())
}

/// One row: `joint, x, y, z, value, type, home` (a revolute joint's values in degrees, converted
/// from radians when `radians`).
fn row(
    line_text: &str,
    line: usize,
    path: &Path,
    joints: usize,
    unit: LengthUnit,
    radians: bool,
) -> Result<Row, PointsError> {
    let cells: Vec<&str> = line_text
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|c| !c.is_empty())
        .collect();
    let error = |column: usize, message: String| PointsError::Row {
        path: path.to_owned(),
        line,
        field: COLUMNS[column].to_owned(),
        message,
    };
    let spaced: Vec<&str> = line_text.split_whitespace().collect();
    if spaced.len() == COLUMNS.len()
        && let Some(comma) = spaced.iter().find(|c| is_decimal_comma(c))
    {
        return Err(PointsError::File {
            path: path.to_owned(),
            message: format!(
                "line {line}: decimal commas (`{}`): the file was written with a comma as the decimal separator, which \
                 SScanSS-2 reads as a column separator; export it again with a decimal point, or replace each decimal \
                 comma by a point",
                shown_cell(comma)
            ),
        });
    }
    if cells.len() != COLUMNS.len() {
        return Err(PointsError::File {
            path: path.to_owned(),
            message: format!(
                "line {line}: {} columns, expected 7 ({}){}",
                cells.len(),
                COLUMNS.join(", "),
                if cells.len() > COLUMNS.len() && line_text.contains(',') {
                    " (a decimal comma splits a value in two: SScanSS-2 files write a decimal point)"
                } else {
                    ""
                }
            ),
        });
    }
    let number = |column: usize| -> Result<f64, PointsError> {
        cells[column]
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                let fix = crate::csv_lines::with_ascii_minus(cells[column])
                    .map(|ascii| format!(": {}; write `{ascii}`", crate::csv_lines::TYPOGRAPHIC_MINUS))
                    .unwrap_or_default();
                error(
                    column,
                    format!("`{}` is not a finite number{fix}", shown_cell(cells[column])),
                )
            })
    };
    let joint = cells[0]
        .parse::<usize>()
        .ok()
        .filter(|j| (1..=joints).contains(j))
        .ok_or_else(|| {
            error(
                0,
                format!("`{}` is not a joint of the robot (1..{joints})", shown_cell(cells[0])),
            )
        })?;
    let kind = match cells[5].to_ascii_lowercase().as_str() {
        "revolute" => JointKind::Revolute,
        "prismatic" => JointKind::Prismatic,
        other => {
            return Err(error(
                5,
                format!("`{}` is neither `revolute` nor `prismatic`", shown_cell(other)),
            ));
        }
    };
    let mm = unit.to_mm();
    let deg = |v: f64| {
        if radians && kind == JointKind::Revolute {
            v.to_degrees()
        } else {
            v
        }
    };
    Ok(Row {
        line,
        joint,
        point: [number(1)? * mm, number(2)? * mm, number(3)? * mm],
        value: deg(number(4)?),
        kind,
        home: deg(number(6)?),
    })
}

/// Each joint's home value (file units); its type checked against `kinds` and every row of
/// the joint giving the same home.
fn homes(rows: &[Row], path: &Path, kinds: &[JointKind]) -> Result<Vec<f64>, PointsError> {
    let mut homes: Vec<Option<(f64, usize)>> = vec![None; kinds.len()];
    for r in rows {
        let k = r.joint - 1;
        if r.kind != kinds[k] {
            return Err(row_error(
                path,
                r.line,
                5,
                format!(
                    "joint {} is {} in the robot description, the file says {}",
                    r.joint,
                    kind_name(kinds[k]),
                    kind_name(r.kind)
                ),
            ));
        }
        match homes[k] {
            None => homes[k] = Some((r.home, r.line)),
            Some((home, first)) if home.to_bits() != r.home.to_bits() => {
                return Err(row_error(
                    path,
                    r.line,
                    6,
                    format!(
                        "joint {}'s home {} differs from {home} on line {first}",
                        r.joint, r.home
                    ),
                ));
            }
            Some(_) => {}
        }
    }
    let missing: Vec<String> = (0..kinds.len())
        .filter(|&k| homes[k].is_none())
        .map(|k| (k + 1).to_string())
        .collect();
    if !missing.is_empty() {
        return Err(PointsError::File {
            path: path.to_owned(),
            message: format!(
                "no row of joint(s) {}: their home values are unknown (every joint of the robot must be measured)",
                missing.join(", ")
            ),
        });
    }
    Ok(homes.into_iter().map(|h| h.map_or(0.0, |(v, _)| v)).collect())
}

/// A joint's home moves the home pose's point along its sweep by more than this many times
/// the sweep's own scatter about its ideal arc or line (noise and the stage's own errors) before
/// it is refused: a 3-sigma fence.
const HOME_FENCE: f64 = 3.0;

/// How far apart \[the sweep's length unit\] the points of a sweep at values `a` and `b` lie
/// per unit of its scale: the chord over the radius of a revolute joint's arc, the travel of a
/// prismatic joint.
fn chord_factor(kind: JointKind, a: f64, b: f64) -> f64 {
    match kind {
        JointKind::Revolute => 2.0 * ((a - b).to_radians().abs() / 2.0).sin(),
        JointKind::Prismatic => (a - b).abs(),
    }
}

/// One joint's sweep, fitted by its points' mutual distances: its scale (radius or travel per
/// unit), its scatter about them \[mm\], and the home value that puts `home_point` on it best.
struct SweepFit {
    scale: f64,
    scatter_mm: f64,
    home: f64,
}

/// The RMS miss \[mm\] of `home_point`'s distances to `rows` against the sweep's at `home`.
fn home_miss(rows: &[&Row], kind: JointKind, scale: f64, home_point: &nalgebra::Vector3<f64>, home: f64) -> f64 {
    let sum: f64 = rows
        .iter()
        .map(|r| (nalgebra::Vector3::from(r.point) - home_point).norm() - scale * chord_factor(kind, r.value, home))
        .map(|d| d * d)
        .sum();
    (sum / rows.len() as f64).sqrt()
}

/// A sweep's scale (an arc's radius, a slide's travel per unit) from its points' mutual
/// distances, and its scatter about them \[mm, at least
/// [`INSTRUMENT_RESOLUTION_MM`]: noise-free data are not judged on rounding\].
fn sweep_scale(rows: &[&Row], kind: JointKind) -> Option<(f64, f64)> {
    let pairs: Vec<(f64, f64)> = (0..rows.len())
        .flat_map(|a| (a + 1..rows.len()).map(move |b| (a, b)))
        .map(|(a, b)| {
            let chord = (nalgebra::Vector3::from(rows[a].point) - nalgebra::Vector3::from(rows[b].point)).norm();
            (chord, chord_factor(kind, rows[a].value, rows[b].value))
        })
        .collect();
    let den: f64 = pairs.iter().map(|(_, g)| g * g).sum();
    if pairs.len() < 2 || den <= 0.0 {
        return None;
    }
    let scale = pairs.iter().map(|(c, g)| c * g).sum::<f64>() / den;
    let scatter_mm = (pairs.iter().map(|(c, g)| (c - scale * g).powi(2)).sum::<f64>() / pairs.len() as f64).sqrt();
    Some((scale, scatter_mm.max(INSTRUMENT_RESOLUTION_MM)))
}

fn fit_sweep(rows: &[&Row], kind: JointKind, home_point: &nalgebra::Vector3<f64>) -> Option<SweepFit> {
    let (scale, scatter_mm) = sweep_scale(rows, kind)?;
    let (lo, hi) = rows.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
        (lo.min(r.value), hi.max(r.value))
    });
    let miss = |h: f64| home_miss(rows, kind, scale, home_point, h);
    // A grid over the sweep and half its span beyond, then a grid over the best's two cells:
    // the home to a millionth of twice the span.
    const GRID: usize = 2000;
    let best_on = |start: f64, step: f64| {
        (0..=GRID)
            .map(|i| start + step * i as f64)
            .min_by(|a, b| miss(*a).total_cmp(&miss(*b)))
    };
    let step = 2.0 * (hi - lo) / GRID as f64;
    let coarse = best_on(lo - (hi - lo) / 2.0, step)?;
    let home = best_on(coarse - step, 2.0 * step / GRID as f64)?;
    Some(SweepFit {
        scale,
        scatter_mm,
        home,
    })
}

/// Refuses a home value (column 7) the data contradict: every joint's sweep is measured with
/// the other joints at their homes, so each sweep passes, at its own joint's home, through the
/// one point of the home pose (taken where sweeps hold a point at their home value: their
/// component-wise median). A sweep that reaches that point at another value than the file's
/// home (beyond `HOME_FENCE`, 3, times its own scatter) names the joint's first line, its home
/// and the value the data give. Nothing is judged unless two or more sweeps, and more than half
/// of those that hold a point at their home value, hold one point there (within the fence of the
/// largest scatter): sweeps of different measured points (each joint's own target) have no one
/// home pose point to judge by.
pub fn check_homes(
    text: &str,
    path: &Path,
    kinds: &[JointKind],
    unit: LengthUnit,
    radians: bool,
) -> Result<(), PointsError> {
    let rows = rows(text, path, kinds.len(), unit, radians)?;
    let sweep = |k: usize| -> Vec<&Row> { rows.iter().filter(|r| r.joint == k + 1).collect() };
    let at_home: Vec<&Row> = (0..kinds.len())
        .filter_map(|k| sweep(k).into_iter().find(|r| r.value.to_bits() == r.home.to_bits()))
        .collect();
    let largest_scatter = (0..kinds.len())
        .filter_map(|k| sweep_scale(&sweep(k), kinds[k]))
        .fold(INSTRUMENT_RESOLUTION_MM, |m, (_, s)| m.max(s));
    let median = |c: usize| {
        let mut v: Vec<f64> = at_home.iter().map(|r| r.point[c]).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    if at_home.len() < 2 {
        return Ok(());
    }
    let home_point = nalgebra::Vector3::new(median(0), median(1), median(2));
    let agree = at_home
        .iter()
        .filter(|r| (nalgebra::Vector3::from(r.point) - home_point).norm() <= HOME_FENCE * largest_scatter)
        .count();
    if agree < 2 || 2 * agree <= at_home.len() {
        return Ok(());
    }
    for (k, &kind) in kinds.iter().enumerate() {
        let sweep = sweep(k);
        let (Some(first), Some(fit)) = (sweep.first(), fit_sweep(&sweep, kind, &home_point)) else {
            continue;
        };
        let shift_mm = fit.scale * chord_factor(kind, first.home, fit.home);
        let off_mm = home_miss(&sweep, kind, fit.scale, &home_point, fit.home);
        if shift_mm > HOME_FENCE * fit.scatter_mm && off_mm > HOME_FENCE * fit.scatter_mm {
            return Err(row_error(
                path,
                first.line,
                1,
                off_sweep(k, &sweep, &home_point, off_mm, fit.scatter_mm),
            ));
        }
        if shift_mm > HOME_FENCE * fit.scatter_mm {
            let unit = kind.file_unit();
            return Err(row_error(
                path,
                first.line,
                6,
                format!(
                    "joint {}'s home is {} {unit}, but the other joints' sweeps were measured where joint {}'s own \
                     sweep stands at {:.3} {unit}: the home pose's point ({:.3}, {:.3}, {:.3}) mm lies {:.3} mm along \
                     the sweep from where a home of {} {unit} puts it, {:.1} times the sweep's own scatter ({:.3} mm; \
                     the limit is {HOME_FENCE}); write the value joint {} stood at while the others moved (about {:.3} \
                     {unit}) in every row of joint {}, or pass --skip-unit-check if the homes are right after all",
                    k + 1,
                    first.home,
                    k + 1,
                    fit.home,
                    home_point.x,
                    home_point.y,
                    home_point.z,
                    shift_mm,
                    first.home,
                    shift_mm / fit.scatter_mm,
                    fit.scatter_mm,
                    k + 1,
                    fit.home,
                    k + 1
                ),
            ));
        }
    }
    Ok(())
}

/// Joint `k`'s (0-based) `sweep` misses the home pose's point by `off_mm` RMS at its best home
/// value, beyond [`HOME_FENCE`] times its `scatter_mm`: no home value puts the point on it, so
/// the joint's coordinates moved (its rows shifted), not its home column; in words.
fn off_sweep(k: usize, sweep: &[&Row], home_point: &nalgebra::Vector3<f64>, off_mm: f64, scatter_mm: f64) -> String {
    let lines = (sweep.first().map_or(0, |r| r.line), sweep.last().map_or(0, |r| r.line));
    format!(
        "joint {}'s sweep (lines {}-{}) misses the point where the other joints' sweeps meet at their homes ({:.3}, \
         {:.3}, {:.3}) mm by {off_mm:.3} mm RMS at any value of joint {}, {:.1} times the sweep's own scatter \
         ({scatter_mm:.3} mm; the limit is {HOME_FENCE}): no home value explains it, so joint {}'s rows' coordinates \
         are shifted (a block of rows moved, or the instrument moved between sweeps); check x, y, z in those lines, \
         or pass --skip-unit-check if they are right after all",
        k + 1,
        lines.0,
        lines.1,
        home_point.x,
        home_point.y,
        home_point.z,
        k + 1,
        off_mm / scatter_mm,
        k + 1
    )
}

fn row_error(path: &Path, line: usize, column: usize, message: String) -> PointsError {
    PointsError::Row {
        path: PathBuf::from(path),
        line,
        field: COLUMNS[column].to_owned(),
        message,
    }
}

fn kind_name(kind: JointKind) -> &'static str {
    match kind {
        JointKind::Revolute => "revolute",
        JointKind::Prismatic => "prismatic",
    }
}

/// The comment line written at the top of an imported file.
pub fn provenance_comment(source: &Path) -> String {
    format!(
        "# imported by `axiscal import sscanss2` from {} (SScanSS-2 calibration file)\n",
        crate::csv_lines::one_line(&source.display().to_string())
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const KINDS: [JointKind; 2] = [JointKind::Revolute, JointKind::Prismatic];

    fn parse_text(text: &str) -> Result<MeasurementSet, PointsError> {
        parse(text, Path::new("cal.txt"), &KINDS, LengthUnit::Mm, false)
    }

    #[test]
    fn runs_become_experiments_with_held_joints_at_home() {
        let set = parse_text(
            "1,1,0,0,-10,revolute,5\n1 2 0 0 0 revolute 5\n\n2\t0\t1\t0\t20\tprismatic\t-3\n2,0,2,0,30,prismatic,-3\n\
             1,3,0,0,10,revolute,5\n1,4,0,0,20,revolute,5\n",
        )
        .unwrap();
        let rows = set.rows();
        assert_eq!(rows.len(), 6);
        assert_eq!(rows[0].experiment, "joint1");
        assert_eq!(rows[0].cmd, vec![-10.0, -3.0]);
        assert_eq!(rows[2].experiment, "joint2");
        assert_eq!(rows[2].cmd, vec![5.0, 20.0]);
        assert_eq!((rows[4].experiment.as_str(), rows[4].step), ("joint1-2", 0));
    }

    #[test]
    fn bad_rows_name_line_and_column() {
        let cases = [
            (
                "1,1,0,0,-10,revolute\n2,0,1,0,20,prismatic,0\n",
                "line 1: 6 columns",
                "expected 7",
            ),
            (
                "1,1,0,0,-10,revolute,0\n3,0,1,0,20,prismatic,0\n",
                "line 2, column joint",
                "1..2",
            ),
            (
                "1,1,0,x,-10,revolute,0\n2,0,1,0,20,prismatic,0\n",
                "line 1, column z",
                "`x`",
            ),
            (
                "1\t-0,5\t0,25\t50\t-10\trevolute\t0\n2\t0\t1\t0\t20\tprismatic\t0\n",
                "line 1: decimal commas (`-0,5`)",
                "replace each decimal comma by a point",
            ),
            (
                "1,1,0,0,-10,revolute,0\n2,0,1,5,0,20,prismatic,0\n",
                "line 2: 8 columns, expected 7",
                "a decimal comma splits a value in two",
            ),
            (
                "1,1,0,0,-10,prismatic,0\n2,0,1,0,20,prismatic,0\n",
                "line 1, column type",
                "revolute in the robot",
            ),
            (
                "1,1,0,0,-10,revolute,0\n1,1,0,0,-5,revolute,1\n2,0,1,0,20,prismatic,0\n",
                "line 2, column home",
                "differs",
            ),
            ("1,1,0,0,-10,revolute,0\n", "cal.txt", "no row of joint(s) 2"),
            (
                "joint,x,y,z,value,type,home\n1,1,0,0,-10,revolute,0\n2,0,1,0,20,prismatic,0\n",
                "line 1 is a header",
                "remove the line",
            ),
            (
                "1,1,0,0,-10,revolute,0\n1,1,0,0,-5,revolute,0\n2,0,1,0,20,prismatic,0\n1,1,0,0,0,revolute,0\n",
                "line 3, column joint",
                "stands alone (line 2 is joint 1, line 4 is joint 1; 2 of the file's 3 runs",
            ),
            (
                "1,1,0,0,-10,hinge,0\n2,0,1,0,20,prismatic,0\n",
                "column type",
                "`hinge`",
            ),
            (
                "1,1,0,0,inf,revolute,0\n2,0,1,0,20,prismatic,0\n",
                "column value",
                "finite",
            ),
            (
                "# a comment\n# another\n1,1,0,0,-10,revolute,0\n1,1e300,0,0,-5,revolute,0\n2,0,1,0,20,prismatic,0\n2,0,2,0,30,prismatic,0\n",
                "line 4, column x",
                "1e300",
            ),
            (
                "1,1,0,0,-10,revolute,0\n1,1,0,0,-10,revolute,0\n2,0,1,0,20,prismatic,0\n2,0,2,0,30,prismatic,0\n",
                "line 2, column joint",
                "repeats line 1 cell for cell",
            ),
        ];
        for (text, place, what) in cases {
            let message = parse_text(text).unwrap_err().to_string();
            assert!(message.contains(place) && message.contains(what), "{text:?}: {message}");
        }
    }
}
