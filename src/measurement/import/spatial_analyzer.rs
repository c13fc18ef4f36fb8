//! SpatialAnalyzer's ASCII point export (`docs/formats.md#spatialanalyzer-ascii-export`), read
//! into the [`Table`] of a point export so that it joins to a plan like any other
//! (`super::points::join_points`).
//!
//! SpatialAnalyzer writes one point a line, space- or comma-separated, optionally preceded by
//! `//` comment lines (its version, the working frame): the point's name in 0 to 3 fields
//! (its "Point Name" option: `Collection Group Target`, `Group Target`, `Target` or none), then
//! `x y z` in the working unit, then whatever extra fields were asked for (tolerances,
//! uncertainties, time stamps), which are kept as columns `extra1`, ... and not read. The
//! target's name gives the plan's point id: its trailing digits (`17`, `P017`, `SMR_17`).

use super::points::PointsError;
use super::table::Table;
use crate::csv_lines::{is_decimal_comma, shown_cell};
use std::path::Path;

/// The name fields, in SpatialAnalyzer's order, their last one the target.
const NAME_FIELDS: [&str; 3] = ["collection", "group", "id"];

/// Whether `text` looks like a SpatialAnalyzer export: its first non-blank line is a `//`
/// comment (SpatialAnalyzer's header option) rather than a CSV header.
pub fn looks_like(text: &str) -> bool {
    text.trim_start_matches('\u{feff}')
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .is_some_and(|l| l.starts_with("//"))
}

/// The line of `text`'s first non-blank line when it is a SpatialAnalyzer point line rather than
/// a CSV header: no comma, at least three white-space-separated fields, the last three numbers
/// (`G 1 -3108.48 5269.52 13.80`): an export saved without its `//` header line.
pub fn headerless_point_line(text: &str) -> Option<usize> {
    let (i, line) = text
        .trim_start_matches('\u{feff}')
        .lines()
        .enumerate()
        .find(|(_, l)| !l.trim().is_empty())?;
    let cells: Vec<&str> = line.split_whitespace().collect();
    let numbers = cells.len() >= 3 && cells[cells.len() - 3..].iter().all(|c| c.parse::<f64>().is_ok());
    (!line.contains(',') && numbers).then_some(i + 1)
}

/// The first of `cells` (white-space-separated) written with a decimal comma (`-3108,48`:
/// digits, one comma, digits), when the last three (`x y z`) all are.
fn decimal_comma<'a>(cells: &[&'a str]) -> Option<&'a str> {
    let xyz = cells.get(cells.len().checked_sub(3)?..)?;
    xyz.iter().all(|c| is_decimal_comma(c)).then_some(xyz[0])
}

/// Reads the export `text` (`path` labels messages) with `names` name fields before `x y z`
/// (`None`: every line has 3 to 6 fields and the name fields are all but the last 3).
pub fn to_table(text: &str, path: &Path, names: Option<usize>) -> Result<Table, PointsError> {
    let mut rows: Vec<(usize, Vec<&str>)> = Vec::new();
    let mut comments = Vec::new();
    for (i, line) in text.trim_start_matches('\u{feff}').lines().enumerate() {
        let trimmed = line.trim();
        if trimmed.is_empty() {
            continue;
        }
        if let Some(comment) = trimmed.strip_prefix("//") {
            comments.push(comment.trim().to_owned());
            continue;
        }
        if let Some(cell) = decimal_comma(&trimmed.split_whitespace().collect::<Vec<_>>()) {
            return Err(PointsError::File {
                path: path.to_owned(),
                message: format!(
                    "line {}: decimal commas (`{}`): the export was written with a comma as the decimal separator; export it again with a decimal point, or replace each comma by a point",
                    i + 1,
                    shown_cell(cell)
                ),
            });
        }
        let cells: Vec<&str> = if trimmed.contains(',') {
            trimmed.split(',').map(str::trim).collect()
        } else {
            trimmed.split_whitespace().collect()
        };
        rows.push((i + 1, cells));
    }
    let file_error = |message: String| PointsError::File {
        path: path.to_owned(),
        message,
    };
    let (first_line, first) = rows
        .first()
        .ok_or_else(|| file_error("no point line (SpatialAnalyzer ASCII export)".into()))?;
    let names = match names {
        Some(n) if n <= 3 => n,
        Some(n) => {
            return Err(file_error(format!(
                "--sa-names {n}: SpatialAnalyzer writes 0 to 3 name fields"
            )));
        }
        None => {
            let n = first.len().checked_sub(3).filter(|&n| n <= 3).ok_or_else(|| {
                file_error(format!(
                    "line {first_line}: {} fields; give --sa-names (0-3: the name fields before x y z) when the export has extra fields",
                    first.len()
                ))
            })?;
            if let Some((line, cells)) = rows.iter().find(|(_, c)| c.len() != first.len()) {
                return Err(file_error(format!(
                    "line {line}: {} fields where line {first_line} has {}; give --sa-names (0-3)",
                    cells.len(),
                    first.len()
                )));
            }
            n
        }
    };
    let width = rows.iter().map(|(_, c)| c.len()).max().unwrap_or(0);
    if let Some((line, cells)) = rows.iter().find(|(_, c)| c.len() < names + 3) {
        return Err(file_error(format!(
            "line {line}: {} fields, fewer than {names} name field(s) and x y z",
            cells.len()
        )));
    }
    let mut header: Vec<String> = NAME_FIELDS[3 - names..].iter().map(|s| s.to_string()).collect();
    header.extend(["x", "y", "z"].map(String::from));
    header.extend((1..=width - names - 3).map(|k| format!("extra{k}")));
    let mut csv = csv::WriterBuilder::new().has_headers(false).from_writer(Vec::new());
    let mut ranges = Vec::with_capacity(rows.len());
    for (line, mut cells) in rows {
        if names > 0 {
            cells[names - 1] = trailing_number(cells[names - 1], path, line)?;
        }
        let start = csv.get_ref().len();
        let written = csv.write_record(&cells).and_then(|()| Ok(csv.flush()?));
        written.map_err(|e| file_error(format!("line {line}: {e}")))?;
        ranges.push((line, start..csv.get_ref().len() - 1));
    }
    let text = csv.into_inner().map_err(|e| file_error(e.to_string()))?;
    let text = String::from_utf8(text).map_err(|e| file_error(e.to_string()))?;
    Ok(Table::from_text(path, header, comments, text, ranges))
}

/// The trailing digits of a target name (`P012` -> `012`), the plan's point id.
fn trailing_number<'a>(target: &'a str, path: &Path, line: usize) -> Result<&'a str, PointsError> {
    let digits = target.trim_end_matches(|c: char| c.is_ascii_digit());
    let id = &target[digits.len()..];
    if id.is_empty() {
        return Err(PointsError::Row {
            path: path.to_owned(),
            line,
            field: "id".into(),
            message: format!(
                "target name `{}` ends in no digits: the plan's point id is its trailing number",
                shown_cell(target)
            ),
        });
    }
    Ok(id)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measurement::import::points::read_export;

    const EXPORT: &str = "// SpatialAnalyzer 2023.1\n// Working frame: Tracker\nA Robot P001 1000.5 -20.25 300\nA Robot P002 1001.5 -21.25 301\n";

    #[test]
    fn names_become_ids_and_positions_read_as_a_point_export() {
        assert!(looks_like(EXPORT));
        assert_eq!(headerless_point_line(EXPORT), None);
        assert_eq!(headerless_point_line("\nA Robot P001 1000.5 -20.25 300\n"), Some(2));
        assert_eq!(headerless_point_line("id,x,y,z\n1,2,3,4\n"), None);
        let table = to_table(EXPORT, Path::new("sa.txt"), None).unwrap();
        assert_eq!(table.header, ["collection", "group", "id", "x", "y", "z"]);
        let (points, unit) = read_export(&table).unwrap();
        assert_eq!(unit, None);
        assert_eq!(points[1].id, Some(2));
        // Parsed from the same decimal text: the same doubles.
        assert_eq!(
            points[1].position.map(f64::to_bits),
            [1001.5, -21.25, 301.0].map(f64::to_bits)
        );
        let commas = to_table("17,1,2,3,0.01\n18,4,5,6,0.02\n", Path::new("sa.csv"), Some(1)).unwrap();
        assert_eq!(commas.header, ["id", "x", "y", "z", "extra1"]);
        assert_eq!(read_export(&commas).unwrap().0[0].id, Some(17));
    }

    #[test]
    fn bad_exports_say_what_to_give() {
        let cases = [
            ("A Robot P001 1 2 3 0.1 0.2\n", None, "give --sa-names"),
            ("A Robot P001 1 2 3\nA Robot 1 2 3\n", None, "line 2: 5 fields"),
            ("A Robot Pa 1 2 3\n", None, "line 1, column id"),
            ("1 2\n", Some(0), "fewer than 0 name field(s)"),
            ("// only comments\n", None, "no point line"),
            ("A 1 2 3\n", Some(4), "0 to 3 name fields"),
            (
                "// SA\nG 1 -3108,48 5269,5 13,8\n",
                None,
                "line 2: decimal commas (`-3108,48`)",
            ),
        ];
        for (text, names, what) in cases {
            let message = to_table(text, Path::new("sa.txt"), names).unwrap_err().to_string();
            assert!(message.contains(what), "{text:?}: {message}");
        }
    }
}
