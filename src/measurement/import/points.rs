//! Instrument exports joined to a measurement plan (`axiscal import points`,
//! `docs/formats.md#point-export`): a laser tracker's or theodolite software's `id,x,y,z` list
//! (ids or row order, millimetres or metres stated or detected, an optional per-point
//! uncertainty) matched to the plan's points (`docs/formats.md#measurement-plan`), giving the
//! measurement CSV.
//!
//! Unit detection and slips use distances to the median point, which no change of frame
//! alters: the instrument's frame need not be the description's `placement`.

use super::table::{Row, Table};
use crate::csv_lines::shown_cell;
use crate::measurement::{Measurement, MeasurementSet, MeasurementSetError, unit_check};
use nalgebra::Vector3;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Why an import failed. Lines are 1-based physical lines of the file.
#[derive(Debug, thiserror::Error)]
pub enum PointsError {
    /// A file could not be read.
    #[error("{path}: cannot read: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        cause: std::io::Error,
    },
    /// A problem with a whole file (a missing column, a count that does not match).
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A problem with one row's field.
    #[error("{path}: line {line}, column {field}: {message}")]
    Row {
        /// The file.
        path: PathBuf,
        /// The line.
        line: usize,
        /// The column's name.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The joined rows do not form a valid measurement set.
    #[error("{path}: {cause}")]
    Set {
        /// The file the rows came from.
        path: PathBuf,
        /// The cause.
        cause: MeasurementSetError,
    },
}

/// Length unit of an export.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LengthUnit {
    /// Millimetres.
    Mm,
    /// Metres.
    M,
}

impl LengthUnit {
    /// Millimetres per unit.
    pub fn to_mm(self) -> f64 {
        match self {
            LengthUnit::Mm => 1.0,
            LengthUnit::M => 1e3,
        }
    }

    /// `mm` or `m`.
    pub fn name(self) -> &'static str {
        match self {
            LengthUnit::Mm => "mm",
            LengthUnit::M => "m",
        }
    }
}

/// One point of a plan CSV.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanRow {
    /// Physical line in the plan file.
    pub line: usize,
    /// The point id.
    pub point: usize,
    /// The measurement row without a position (`position_mm` is NaN until joined).
    pub row: Measurement,
    /// Nominal position \[mm\].
    pub nominal_mm: [f64; 3],
    /// Whether every station should see it (true when the plan has no sight columns).
    pub visible: bool,
}

/// A read plan CSV.
#[derive(Clone, Debug)]
pub struct PlanSheet {
    /// The plan file.
    pub path: PathBuf,
    /// Its points in order.
    pub rows: Vec<PlanRow>,
    /// Joint count.
    pub joint_count: usize,
    /// Its comment lines (to carry the recorded robot description along).
    pub comments: Vec<String>,
}

impl PlanSheet {
    /// Reads a plan written by `axiscal plan` (columns by name).
    pub fn from_table(t: &Table) -> Result<Self, PointsError> {
        let joint_count = (1..).take_while(|k| t.column(&[&format!("cmd_{k}")]).is_some()).count();
        if joint_count == 0 {
            return Err(t.required(&["cmd_1"]).unwrap_err());
        }
        let c = PlanColumns {
            cmd: (1..=joint_count)
                .map(|k| t.required(&[&format!("cmd_{k}")]))
                .collect::<Result<_, _>>()?,
            point: t.required(&["point"])?,
            experiment: t.required(&["experiment"])?,
            moved_joint: t.required(&["moved_joint"])?,
            step: t.required(&["step"])?,
            target: t.required(&["target"])?,
            nominal: [
                t.required(&["nominal_x_mm"])?,
                t.required(&["nominal_y_mm"])?,
                t.required(&["nominal_z_mm"])?,
            ],
        };
        let sight: Vec<usize> = (0..t.header.len())
            .filter(|&k| t.header[k].starts_with("visible_"))
            .collect();
        let mut rows = Vec::with_capacity(t.row_count());
        for row in t.rows() {
            rows.push(plan_row(t, &row, &c, &sight)?);
        }
        check_unique(t, &rows)?;
        Ok(PlanSheet {
            path: t.path.clone(),
            rows,
            joint_count,
            comments: t.comments.clone(),
        })
    }
}

struct PlanColumns {
    point: usize,
    experiment: usize,
    moved_joint: usize,
    step: usize,
    target: usize,
    nominal: [usize; 3],
    cmd: Vec<usize>,
}

fn plan_row(t: &Table, row: &Row<'_>, c: &PlanColumns, sight: &[usize]) -> Result<PlanRow, PointsError> {
    let cmd = c.cmd.iter().map(|&k| t.number(row, k)).collect::<Result<Vec<_>, _>>()?;
    let mut visible = true;
    for &k in sight {
        match t.cell(row, k)? {
            "yes" => {}
            "no" => visible = false,
            other => return Err(t.row_error(row.line, k, format!("{:?}: expected yes or no", shown_cell(other)))),
        }
    }
    Ok(PlanRow {
        line: row.line,
        point: t.integer(row, c.point)?,
        row: Measurement {
            experiment: t.cell(row, c.experiment)?.to_owned(),
            moved_joint: t.integer(row, c.moved_joint)?,
            step: t.integer(row, c.step)?,
            target: t.integer(row, c.target)?,
            position_mm: [f64::NAN; 3],
            cmd,
            payload_kg: Measurement::DEFAULT_PAYLOAD_KG,
            temperature_c: Measurement::DEFAULT_TEMPERATURE_C,
        },
        nominal_mm: [
            t.number(row, c.nominal[0])?,
            t.number(row, c.nominal[1])?,
            t.number(row, c.nominal[2])?,
        ],
        visible,
    })
}

fn check_unique(t: &Table, rows: &[PlanRow]) -> Result<(), PointsError> {
    let mut seen = BTreeMap::new();
    for r in rows {
        if let Some(first) = seen.insert(r.point, r.line) {
            let column = t.column(&["point"]).unwrap_or(0);
            return Err(t.row_error(r.line, column, format!("point {} already on line {first}", r.point)));
        }
    }
    Ok(())
}

/// One point of an instrument export.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportPoint {
    /// Physical line.
    pub line: usize,
    /// The id (`None`: matched by row order).
    pub id: Option<usize>,
    /// Position in the file's unit.
    pub position: [f64; 3],
    /// Per-point uncertainty in the file's unit, when the file has the column.
    pub sigma: Option<f64>,
}

/// Column names accepted for the id.
pub const ID_COLUMNS: [&str; 4] = ["id", "point", "point_id", "name"];
/// Column names accepted for the uncertainty (in the file's length unit, or as its suffix says).
pub const SIGMA_COLUMNS: [&str; 4] = ["sigma", "uncertainty", "u", "std"];

/// The id column of an export: the first of [`ID_COLUMNS`] present. Another one present that
/// holds integer ids too (not a text label such as a point's name), different on some row, is
/// an error naming the line: which column holds the ids is not the reader's to guess.
fn id_column(t: &Table) -> Result<Option<usize>, PointsError> {
    let present: Vec<usize> = ID_COLUMNS.iter().filter_map(|n| t.column(&[n])).collect();
    let Some((&id, others)) = present.split_first() else {
        return Ok(None);
    };
    for &other in others {
        let differs = t.rows().find_map(|row| {
            let ids = (t.integer(&row, id).ok()?, t.integer(&row, other).ok()?);
            (ids.0 != ids.1).then_some((row.line, ids))
        });
        let all_integers = t.rows().all(|row| t.integer(&row, other).is_ok());
        if let (true, Some((line, (a, b)))) = (all_integers, differs) {
            return Err(t.row_error(
                line,
                other,
                format!(
                    "{b}, where column `{}` gives {a}: two columns of point ids that disagree; keep the one that numbers the plan's points (delete or rename the other)",
                    t.header_as_written[id]
                ),
            ));
        }
    }
    Ok(Some(id))
}

/// The points of an export (`id,x,y,z[,sigma]`) and the unit its column names state (`x_mm`,
/// `x_m`), if any.
pub fn read_export(t: &Table) -> Result<(Vec<ExportPoint>, Option<LengthUnit>), PointsError> {
    let mut stated = None;
    let mut xyz = [0usize; 3];
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let (mm, m) = (format!("{axis}_mm"), format!("{axis}_m"));
        let names = [*axis, mm.as_str(), m.as_str()];
        xyz[k] = match t.sole_column(&names)? {
            Some(c) => c,
            None => t.required(&names)?,
        };
        let name = &t.header[xyz[k]];
        let unit = match name.as_str() {
            n if n == mm => Some(LengthUnit::Mm),
            n if n == m => Some(LengthUnit::M),
            _ => None,
        };
        if unit.is_some() {
            stated = unit;
        }
    }
    let id = id_column(t)?;
    let sigma_names: Vec<String> = SIGMA_COLUMNS
        .iter()
        .flat_map(|s| [s.to_string(), format!("{s}_mm"), format!("{s}_m")])
        .collect();
    let sigma = t.sole_column(&sigma_names.iter().map(String::as_str).collect::<Vec<_>>())?;
    let mut points = Vec::with_capacity(t.row_count());
    for row in t.rows() {
        let position = [
            t.number(&row, xyz[0])?,
            t.number(&row, xyz[1])?,
            t.number(&row, xyz[2])?,
        ];
        // In mm, or in m when the header says so (an export of unknown unit is read as mm:
        // a value beyond the range in metres is beyond it in mm too).
        let to_mm = stated.map_or(1.0, LengthUnit::to_mm);
        for (c, &k) in xyz.iter().enumerate() {
            if let Some(range) = crate::measurement::data::coordinate_beyond(position[c] * to_mm) {
                return Err(t.row_error(row.line, k, format!("{:e} is outside {range}", position[c])));
            }
        }
        let sigma = match sigma {
            Some(k) => {
                let s = t.number(&row, k)?;
                if s < 0.0 {
                    return Err(t.row_error(row.line, k, format!("{s}: an uncertainty cannot be negative")));
                }
                Some(s)
            }
            None => None,
        };
        points.push(ExportPoint {
            line: row.line,
            id: id.map(|k| t.integer(&row, k)).transpose()?,
            position,
            sigma,
        });
    }
    Ok((points, stated))
}

/// The result of a join.
#[derive(Debug)]
pub struct Joined {
    /// The measurement rows, in plan order.
    pub set: MeasurementSet,
    /// The export's unit.
    pub unit: LengthUnit,
    /// Whether the unit was detected (not stated).
    pub detected: bool,
    /// Spread of the measured points over the nominal ones', in the export's unit per mm.
    pub spread_ratio: f64,
    /// Plan points the export lacks that the plan marks hidden from a station.
    pub missing_hidden: Vec<usize>,
    /// Plan points the export lacks although the plan expects them seen (with `allow_missing`).
    pub missing_visible: Vec<usize>,
    /// The uncertainties \[mm\] of the joined points, when the export gives them.
    pub sigmas_mm: Vec<f64>,
}

/// Joins `export` (read from `export_table`) to `plan`: by id when the export has ids, else by
/// row order (then the counts must be equal). `stated`: the unit given by the user.
pub fn join_points(
    plan: &PlanSheet,
    export_table: &Table,
    stated: Option<LengthUnit>,
    allow_missing: bool,
) -> Result<Joined, PointsError> {
    let (points, named) = read_export(export_table)?;
    let path = &export_table.path;
    let file_error = |message: String| PointsError::File {
        path: path.clone(),
        message,
    };
    if let (Some(s), Some(n)) = (stated, named)
        && s != n
    {
        return Err(file_error(format!(
            "--units {} contradicts the column names, which say {}",
            s.name(),
            n.name()
        )));
    }
    let pairs = match_points(plan, export_table, &points)?;
    let mut missing_hidden = Vec::new();
    let mut missing_visible = Vec::new();
    let matched: std::collections::BTreeSet<usize> = pairs.iter().map(|(p, _)| p.point).collect();
    for r in &plan.rows {
        if !matched.contains(&r.point) {
            if r.visible {
                missing_visible.push(r.point);
            } else {
                missing_hidden.push(r.point);
            }
        }
    }
    if !missing_visible.is_empty() && !allow_missing {
        return Err(file_error(format!(
            "{} planned point(s) the plan expects visible are missing: ids {} (pass --allow-missing if the \
             instrument could not see them)",
            missing_visible.len(),
            list(&missing_visible)
        )));
    }
    let ratio =
        spread_ratio(&pairs).ok_or_else(|| file_error("fewer than 3 distinct points: cannot check units".into()))?;
    let (unit, detected) = match stated.or(named) {
        Some(u) => (u, false),
        None => (detect_unit(ratio).ok_or_else(|| unit_error(path, ratio))?, true),
    };
    if detect_unit(ratio) != Some(unit) {
        let by = if stated.is_some() {
            "--units"
        } else {
            "the column names"
        };
        let fix = match detect_unit(ratio) {
            Some(fits) if stated.is_some() => format!(
                "they look like {}: pass --units {} (or leave --units out: the unit is then told from the spread)",
                fits.name(),
                fits.name()
            ),
            Some(fits) => format!(
                "they look like {}: check the export's unit setting (its column names say {}, its values do not)",
                fits.name(),
                unit.name()
            ),
            None => "neither mm (about 1) nor m (about 0.001) fits: check that the plan is the one measured".into(),
        };
        return Err(file_error(format!(
            "the points are in {} ({by}), but their spread is {ratio:.4} times the plan's nominal spread in mm: {fix}",
            unit.name()
        )));
    }
    check_slips(export_table, &pairs, unit)?;
    let mut sigmas_mm = Vec::new();
    let rows = pairs
        .iter()
        .map(|(plan_row, point)| {
            if let Some(s) = point.sigma {
                sigmas_mm.push(s * unit.to_mm());
            }
            let mut row = plan_row.row.clone();
            row.position_mm = point.position.map(|c| c * unit.to_mm());
            row
        })
        .collect();
    let set = MeasurementSet::new(plan.joint_count, rows).map_err(|source| PointsError::Set {
        path: path.clone(),
        cause: source,
    })?;
    Ok(Joined {
        set,
        unit,
        detected,
        spread_ratio: ratio,
        missing_hidden,
        missing_visible,
        sigmas_mm,
    })
}

fn unit_error(path: &std::path::Path, ratio: f64) -> PointsError {
    PointsError::File {
        path: path.to_owned(),
        message: format!(
            "cannot tell the unit: the points' spread is {ratio:.4} times the plan's nominal spread in mm \
             (about 1: mm, about 0.001: m); state it with --units"
        ),
    }
}

fn list(ids: &[usize]) -> String {
    let shown: Vec<String> = ids.iter().take(10).map(ToString::to_string).collect();
    let more = if ids.len() > 10 {
        format!(" and {} more", ids.len() - 10)
    } else {
        String::new()
    };
    format!("{}{more}", shown.join(", "))
}

/// The plan row of each export point, in plan order; an unknown or repeated id, or a count
/// mismatch in row order, is an error naming the line.
fn match_points<'a>(
    plan: &'a PlanSheet,
    t: &Table,
    points: &'a [ExportPoint],
) -> Result<Vec<(&'a PlanRow, &'a ExportPoint)>, PointsError> {
    let id_column = t.column(&ID_COLUMNS).unwrap_or(0);
    if points.first().is_some_and(|p| p.id.is_none()) {
        if points.len() != plan.rows.len() {
            return Err(PointsError::File {
                path: t.path.clone(),
                message: format!(
                    "{} points without an id column, the plan {} has {}: rows can only be matched by order when \
                     the counts agree (add an id column)",
                    points.len(),
                    plan.path.display(),
                    plan.rows.len()
                ),
            });
        }
        return Ok(plan.rows.iter().zip(points).collect());
    }
    let by_id: BTreeMap<usize, &PlanRow> = plan.rows.iter().map(|r| (r.point, r)).collect();
    let mut seen: BTreeMap<usize, usize> = BTreeMap::new();
    let mut pairs = Vec::with_capacity(points.len());
    for p in points {
        let id = p.id.unwrap_or_default();
        if let Some(first) = seen.insert(id, p.line) {
            return Err(t.row_error(p.line, id_column, format!("id {id} already on line {first}")));
        }
        let row = by_id.get(&id).ok_or_else(|| {
            t.row_error(
                p.line,
                id_column,
                format!("id {id} is not a point of the plan {}", plan.path.display()),
            )
        })?;
        pairs.push((*row, p));
    }
    pairs.sort_by_key(|(r, _)| r.point);
    Ok(pairs)
}

/// The measured points' spread over the nominal points' (file unit per mm,
/// [`unit_check::spread_ratio`]).
fn spread_ratio(pairs: &[(&PlanRow, &ExportPoint)]) -> Option<f64> {
    let measured: Vec<Vector3<f64>> = pairs.iter().map(|(_, p)| Vector3::from(p.position)).collect();
    let nominal: Vec<Vector3<f64>> = pairs.iter().map(|(r, _)| Vector3::from(r.nominal_mm)).collect();
    unit_check::spread_ratio(&measured, &nominal)
}

/// The unit a spread ratio points to: mm within a factor 3 of 1, m within a factor 3 of 1e-3.
pub fn detect_unit(ratio: f64) -> Option<LengthUnit> {
    let decades = ratio.log10();
    if decades.abs() < 3f64.log10() {
        Some(LengthUnit::Mm)
    } else if (decades + 3.0).abs() < 3f64.log10() {
        Some(LengthUnit::M)
    } else {
        None
    }
}

/// One point whose distance to the median point differs from its nominal counterpart's by more
/// than 50 mm plus 20 % of that distance (a real robot's errors are millimetres; a value typed
/// in the other unit is off by a factor 1000) is an error naming its line; in an export without
/// ids (rows matched by order) several such points say the rows are not in the plan's order.
fn check_slips(t: &Table, pairs: &[(&PlanRow, &ExportPoint)], unit: LengthUnit) -> Result<(), PointsError> {
    let measured: Vec<Vector3<f64>> = pairs
        .iter()
        .map(|(_, p)| Vector3::from(p.position) * unit.to_mm())
        .collect();
    let nominal: Vec<Vector3<f64>> = pairs.iter().map(|(r, _)| Vector3::from(r.nominal_mm)).collect();
    let (rm, rn) = (unit_check::radii(&measured), unit_check::radii(&nominal));
    let slipped: Vec<usize> = (0..pairs.len())
        .filter(|&k| (rm[k] - rn[k]).abs() > 50.0 + 0.2 * rn[k])
        .collect();
    let Some(&k) = slipped.first() else { return Ok(()) };
    let (plan_row, point) = pairs[k];
    let cause = match (point.id, slipped.len()) {
        (Some(_), _) => "a unit slip or a wrong id?".to_owned(),
        (None, 1) => "a unit slip in this row? (the export has no ids: its rows are matched to the plan's points \
                      by their order)"
            .to_owned(),
        (None, n) => format!(
            "{n} of the {} rows are so far from their plan points: the export has no id column, so its rows are \
             matched to the plan's points by their order, and these rows are not in the plan's order (sorted or \
             shuffled on export?); export the point ids (an `id` column) or the rows in the plan's order",
            pairs.len()
        ),
    };
    let x = t.column(&["x", "x_mm", "x_m"]).unwrap_or(0);
    Err(t.row_error(
        point.line,
        x,
        format!(
            "point {} is {:.1} mm from the points' median, the plan puts it {:.1} mm away: {cause}",
            plan_row.point, rm[k], rn[k]
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn export(text: &str) -> Result<Vec<ExportPoint>, PointsError> {
        read_export(&Table::parse(text, std::path::Path::new("export.csv"))?).map(|(points, _)| points)
    }

    /// Two columns that both name a coordinate are refused; two id columns are refused where
    /// both hold integer ids that disagree, not where the other is a text label.
    #[test]
    fn two_columns_of_one_quantity_are_not_chosen_between() {
        let err = export("id,x,y,z,x_mm\n1,1,2,3,4\n").unwrap_err().to_string();
        assert!(
            err.contains("columns `x` and `x_mm` both name one of x, x_mm, x_m"),
            "{err}"
        );
        let err = export("id,point,x,y,z\n1,1,0,0,0\n2,3,0,0,0\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("line 3, column point: 3, where column `id` gives 2"),
            "{err}"
        );
        let labelled = export("id,name,x,y,z\n1,P001,0,0,0\n2,P002,0,0,0\n").unwrap();
        assert_eq!(labelled.iter().map(|p| p.id).collect::<Vec<_>>(), [Some(1), Some(2)]);
        let agreeing = export("id,point,x,y,z\n1,1,0,0,0\n2,2,0,0,0\n").unwrap();
        assert_eq!(agreeing.len(), 2);
    }
}
