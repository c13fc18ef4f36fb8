//! A CSV table as instruments and lab scripts export it: a header row (the first line that is
//! not a `#` comment or blank), columns found by name (case and surrounding white space
//! ignored), every cell kept with its 1-based physical line for messages.

use super::points::PointsError;
use crate::csv_lines::{
    CR_ONLY, carriage_returns_only, commented_row, foreign_separator, is_decimal_comma, looks_like_row, shown_cell,
};
use std::borrow::Cow;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// A read table: the file's text and where each data row lies in it; a row's cells are split
/// when it is visited, so a table of a million rows takes about its file's size.
#[derive(Debug)]
pub struct Table {
    /// The file.
    pub path: PathBuf,
    /// The column names, trimmed, lower case (what columns are found by).
    pub header: Vec<String>,
    /// The column names as written, trimmed (what a copy of the table writes).
    pub header_as_written: Vec<String>,
    /// The comment lines before the header (without their `#`).
    pub comments: Vec<String>,
    /// The text the rows are in (the file's, or a normalised one).
    text: String,
    /// Per data row: its 1-based physical line and its byte range in `text`.
    rows: Vec<(usize, Range<usize>)>,
}

/// One data row of a [`Table`]: its 1-based physical line and its cells, trimmed.
#[derive(Clone, Debug)]
pub struct Row<'a> {
    /// The 1-based physical line.
    pub line: usize,
    cells: Vec<Cow<'a, str>>,
}

impl<'a> Row<'a> {
    /// The cell at `column`, if the row has it.
    pub fn get(&self, column: usize) -> Option<&str> {
        self.cells.get(column).map(AsRef::as_ref)
    }

    /// The number of cells.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Whether the row has no cell.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// The cells in order.
    pub fn cells(&self) -> impl Iterator<Item = &str> + '_ {
        self.cells.iter().map(AsRef::as_ref)
    }
}

impl Table {
    /// A table of CSV `text` whose data rows are at `rows` (1-based line, byte range, each a
    /// line that splits, as [`Table::parse`] and a `csv::Writer` make them); the header is
    /// trimmed and lower-cased.
    pub fn from_text(
        path: &Path,
        header: Vec<String>,
        comments: Vec<String>,
        text: String,
        rows: Vec<(usize, Range<usize>)>,
    ) -> Self {
        Table {
            path: path.to_owned(),
            header: header.iter().map(|h| h.trim().to_lowercase()).collect(),
            header_as_written: header.iter().map(|h| h.trim().to_owned()).collect(),
            comments,
            text,
            rows,
        }
    }

    /// The data rows in order.
    pub fn rows(&self) -> impl ExactSizeIterator<Item = Row<'_>> + '_ {
        self.rows.iter().map(|(line, range)| {
            let mut cells = Vec::with_capacity(self.header.len());
            // Every row was split when the table was made.
            let _ = split(&self.text[range.clone()], &mut cells);
            Row { line: *line, cells }
        })
    }

    /// The number of data rows.
    pub fn row_count(&self) -> usize {
        self.rows.len()
    }

    /// Reads `path` (a shipped file's virtual path too).
    pub fn read(path: &Path) -> Result<Self, PointsError> {
        let text = crate::presets::read_text(path).map_err(|source| PointsError::Io {
            path: path.to_owned(),
            cause: source,
        })?;
        Self::parse(text, path)
    }

    /// Parses `text`; `path` labels messages.
    pub fn parse(text: impl Into<String>, path: &Path) -> Result<Self, PointsError> {
        let text = text.into();
        if carriage_returns_only(text.as_bytes()) {
            return Err(PointsError::File {
                path: path.to_owned(),
                message: CR_ONLY.into(),
            });
        }
        let mut header: Option<Vec<String>> = None;
        let mut comments = Vec::new();
        let mut rows = Vec::new();
        let mut cells = Vec::new();
        let body = text.trim_start_matches('\u{feff}');
        let bom = text.len() - body.len();
        let mut start = bom;
        for (i, line) in body.split_inclusive('\n').enumerate() {
            let range = start..start + line.trim_end_matches(['\n', '\r']).len();
            start += line.len();
            let line = &text[range.clone()];
            let trimmed = line.trim();
            if trimmed.is_empty() || trimmed.starts_with('#') {
                match &header {
                    None if trimmed.starts_with('#') => {
                        comments.push(trimmed.trim_start_matches('#').trim().to_owned())
                    }
                    Some(h) => check_comment(path, i + 1, line, h.len())?,
                    None => {}
                }
                continue;
            }
            split(line, &mut cells).map_err(|(cell, message)| PointsError::Row {
                path: path.to_owned(),
                line: i + 1,
                field: header
                    .as_ref()
                    .and_then(|h| h.get(cell))
                    .map_or_else(|| (cell + 1).to_string(), |name| shown_cell(name)),
                message,
            })?;
            match &header {
                None => {
                    if let [only] = &cells[..]
                        && let Some(separator) = foreign_separator(only)
                    {
                        return Err(PointsError::Row {
                            path: path.to_owned(),
                            line: i + 1,
                            field: "header".into(),
                            message: format!(
                                "a single column containing {separator}: the file looks separated by {separator}; this table is comma-separated with decimal points (re-export it as CSV)"
                            ),
                        });
                    }
                    header = Some(cells.iter().map(|c| c.to_string()).collect());
                }
                Some(h) => {
                    check_width(path, h.len(), i + 1, &cells)?;
                    rows.push((i + 1, range));
                }
            }
        }
        drop(cells);
        let header = header.ok_or_else(|| PointsError::File {
            path: path.to_owned(),
            message: "no header row".into(),
        })?;
        let table = Table::from_text(path, header, comments, text, rows);
        table.check_header()?;
        Ok(table)
    }

    /// No column name twice. A first line of data (no header) is left to the columns' lookup,
    /// which says so with the columns the file needs.
    fn check_header(&self) -> Result<(), PointsError> {
        if self.header_is_data() {
            return Ok(());
        }
        for (k, name) in self.header.iter().enumerate() {
            if self.header[..k].contains(name) {
                let unnamed = if name.is_empty() {
                    ": the header has unnamed columns (trailing commas, as a spreadsheet exports empty columns); delete them or name each column"
                } else {
                    ""
                };
                return Err(PointsError::File {
                    path: self.path.clone(),
                    message: format!("column {:?} appears twice{unnamed}", shown_cell(name)),
                });
            }
        }
        Ok(())
    }

    /// The index of the first column named one of `names`.
    pub fn column(&self, names: &[&str]) -> Option<usize> {
        names.iter().find_map(|n| self.header.iter().position(|h| h == n))
    }

    /// The index of the column named one of `names`, if any; two of them present is an error
    /// naming both (which one holds the values is not the file's to leave to the reader).
    pub fn sole_column(&self, names: &[&str]) -> Result<Option<usize>, PointsError> {
        let present: Vec<usize> = names
            .iter()
            .filter_map(|n| self.header.iter().position(|h| h == n))
            .collect();
        match present.as_slice() {
            [first, second, ..] => Err(PointsError::File {
                path: self.path.clone(),
                message: format!(
                    "columns `{}` and `{}` both name one of {}: keep one of them (delete or rename the other)",
                    self.header_as_written[*first],
                    self.header_as_written[*second],
                    names.join(", ")
                ),
            }),
            [one] => Ok(Some(*one)),
            [] => Ok(None),
        }
    }

    /// The index of a column named one of `names`, or an error naming the file and the names.
    /// A header whose cells are mostly numbers is a first line of data: the file has no header.
    pub fn required(&self, names: &[&str]) -> Result<usize, PointsError> {
        self.column(names).ok_or_else(|| PointsError::File {
            path: self.path.clone(),
            message: self.missing_message(&names.join(" or "), &[]),
        })
    }

    /// The index of each column of `names`, every one required: an error names every missing
    /// column and the header the file needs, so that one fix of the header is enough.
    pub fn required_all(&self, names: &[&str]) -> Result<Vec<usize>, PointsError> {
        let missing: Vec<&str> = names.iter().copied().filter(|n| self.column(&[n]).is_none()).collect();
        if missing.is_empty() {
            return Ok(names.iter().filter_map(|n| self.column(&[n])).collect());
        }
        Err(PointsError::File {
            path: self.path.clone(),
            message: self.missing_message(&missing.join(", "), names),
        })
    }

    /// Whether the first line's cells are mostly numbers: a first line of data, not a header.
    fn header_is_data(&self) -> bool {
        let numbers = self.header.iter().filter(|h| h.trim().parse::<f64>().is_ok()).count();
        2 * numbers > self.header.len()
    }

    /// Why the columns `missing` are not found: the first line is data (mostly numbers), or
    /// the header lacks them (the header's cells shown, and `needed`, the columns the file
    /// needs, when given).
    fn missing_message(&self, missing: &str, needed: &[&str]) -> String {
        let columns = self.header.iter().map(|h| shown_cell(h)).collect::<Vec<_>>().join(",");
        if self.header_is_data() {
            let among = if needed.is_empty() {
                missing.to_owned()
            } else {
                needed.join(",")
            };
            return format!(
                "the first line (`{}`) is data, not a header: add a first line naming the columns, with {among} among them",
                shown_cell(&columns),
            );
        }
        let noun = if missing.contains(", ") { "columns" } else { "column" };
        let needs = if needed.is_empty() {
            String::new()
        } else {
            format!("; the header needs {}", needed.join(","))
        };
        format!("no {noun} {missing} (columns: {columns}){needs}")
    }

    /// The cell of `row` at `column`, or an error naming file, line and column.
    pub fn cell<'r>(&self, row: &'r Row<'_>, column: usize) -> Result<&'r str, PointsError> {
        row.get(column).ok_or_else(|| PointsError::Row {
            path: self.path.clone(),
            line: row.line,
            field: shown_cell(&self.header[column]),
            message: "missing (the row is shorter than the header)".into(),
        })
    }

    /// A finite number at `column`; the error says a decimal comma, or the header repeated (two
    /// files joined), where the cell is one.
    pub fn number(&self, row: &Row<'_>, column: usize) -> Result<f64, PointsError> {
        let text = self.cell(row, column)?;
        text.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
            let why = if is_decimal_comma(text.trim()) {
                format!(
                    ": a decimal comma; this table writes decimal points (`{}`)",
                    text.trim().replace(',', ".")
                )
            } else if text.trim() == self.header[column].trim() {
                format!(": line {} repeats the header (files joined?); delete it", row.line)
            } else if let Some(ascii) = crate::csv_lines::with_ascii_minus(text.trim()) {
                format!(": {}; write `{ascii}`", crate::csv_lines::TYPOGRAPHIC_MINUS)
            } else {
                String::new()
            };
            self.row_error(
                row.line,
                column,
                format!("{:?} is not a finite number{why}", shown_cell(text)),
            )
        })
    }

    /// A non-negative integer at `column`.
    pub fn integer(&self, row: &Row<'_>, column: usize) -> Result<usize, PointsError> {
        let text = self.cell(row, column)?;
        text.parse::<usize>().map_err(|_| {
            self.row_error(
                row.line,
                column,
                format!("{:?} is not a non-negative integer", shown_cell(text)),
            )
        })
    }

    /// An error at `line`, `column`.
    pub fn row_error(&self, line: usize, column: usize, message: String) -> PointsError {
        PointsError::Row {
            path: self.path.clone(),
            line,
            field: shown_cell(self.header.get(column).map_or("", String::as_str)),
            message,
        }
    }
}

/// A `#` line among the rows with as many cells as the header, most of them numbers, is a data
/// row whose first cell starts with `#`, not a comment: refused ([`looks_like_row`]).
fn check_comment(path: &Path, line: usize, text: &str, columns: usize) -> Result<(), PointsError> {
    let fields = text.split(',').count();
    let numbers = text.split(',').filter(|c| c.trim().parse::<f64>().is_ok()).count();
    if !looks_like_row(fields, numbers, columns) {
        return Ok(());
    }
    Err(PointsError::File {
        path: path.to_owned(),
        message: format!("line {line}: {}", commented_row(fields)),
    })
}

/// More cells than `columns`: a shifted row would be read into the wrong columns (empty cells
/// past the last column, a writer's trailing separators, are not).
fn check_width(path: &Path, columns: usize, line: usize, cells: &[Cow<'_, str>]) -> Result<(), PointsError> {
    if cells[columns.min(cells.len())..].iter().all(|c| c.trim().is_empty()) {
        return Ok(());
    }
    Err(PointsError::Row {
        path: path.to_owned(),
        line,
        field: format!("{} (after the last)", cells.len()),
        message: format!(
            "{} cells, the header names {columns} columns: a separator inside a value, or a missing header name?",
            cells.len()
        ),
    })
}

/// One CSV line's cells (RFC 4180 quoting within the line), trimmed, into `cells`. A line
/// without a quote is split at its commas directly (what the CSV reader would do, without
/// building one per line).
/// The error names the 0-based cell it is in: a quoted cell left open at the end of the line
/// (a line break inside quotes, which a table of one row per line cannot hold) is refused.
fn split<'l>(line: &'l str, cells: &mut Vec<Cow<'l, str>>) -> Result<(), (usize, String)> {
    cells.clear();
    if !line.contains('"') {
        cells.extend(line.split(',').map(|c| Cow::Borrowed(c.trim())));
        return Ok(());
    }
    if let Some(cell) = open_quote(line) {
        return Err((
            cell,
            "a quoted cell runs past the end of its line (a line break inside quotes): this table has one row \
             per line; remove the line break from the cell"
                .into(),
        ));
    }
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(line.as_bytes());
    let mut record = csv::StringRecord::new();
    reader.read_record(&mut record).map_err(|e| (0, e.to_string()))?;
    cells.extend(record.iter().map(|c| Cow::Owned(c.trim().to_owned())));
    Ok(())
}

/// The 0-based cell of `line` whose quotes (RFC 4180: a cell starting with `"`, `""` a quote
/// inside it) are still open at the end of the line.
fn open_quote(line: &str) -> Option<usize> {
    let (mut cell, mut quoted, mut at_start) = (0, false, true);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                chars.next();
            }
            (true, '"') => quoted = false,
            (false, '"') if at_start => quoted = true,
            (false, ',') => {
                cell += 1;
                at_start = true;
                continue;
            }
            _ => {}
        }
        at_start = false;
    }
    quoted.then_some(cell)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The CSV reader's cells of one line (the path `split` takes for quoted lines).
    fn by_reader(line: &str) -> Vec<String> {
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .from_reader(line.as_bytes());
        let mut record = csv::StringRecord::new();
        reader.read_record(&mut record).unwrap();
        record.iter().map(|c| c.trim().to_owned()).collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// Without quotes, splitting at the commas gives the reader's cells.
        #[test]
        fn an_unquoted_line_splits_as_the_reader_reads_it(line in "[a-z0-9 .,;\t-]{1,40}") {
            prop_assume!(!line.trim().is_empty());
            prop_assert_eq!(cells_of(&line), by_reader(&line));
        }
    }

    #[test]
    fn a_quoted_cell_keeps_its_comma() {
        assert_eq!(cells_of("1,\"a, b\",3"), ["1", "a, b", "3"]);
    }

    #[test]
    fn a_quote_left_open_at_the_end_of_a_line_is_refused_naming_its_column() {
        assert_eq!(open_quote("1,\"a \"\"b\"\" c\",3"), None);
        assert_eq!(open_quote("1,x\"y,3"), None);
        assert_eq!(open_quote("1,\"a\",\"b"), Some(2));
        let e = Table::parse("id,x_mm\n\"p\n1\",2\n", Path::new("p.csv")).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("p.csv: line 2, column id: a quoted cell runs past"),
            "{e}"
        );
    }

    /// `split`'s cells of one line.
    fn cells_of(line: &str) -> Vec<String> {
        let mut cells = Vec::new();
        split(line, &mut cells).unwrap();
        cells.into_iter().map(|c| c.into_owned()).collect()
    }

    /// A `#` line after the header with as many cells, most of them numbers, is a commented-out
    /// row: refused naming its line; a remark with commas, or one before the header, is not.
    #[test]
    fn a_commented_out_row_is_refused() {
        let e = Table::parse("# 1,2,3,4\nid,x,y,z\np1,1,2,3\n#p2,4,5,6\n", Path::new("t.csv"))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.csv: line 4: the line starts with `#` but has 4 fields"),
            "{e}"
        );
        let t = Table::parse(
            "id,x,y,z\np1,1,2,3\n# by J. Smith, room 3, 2024, day 5\n",
            Path::new("t.csv"),
        );
        assert_eq!(t.unwrap().row_count(), 1);
    }

    /// A number cell with a decimal comma, or holding its column's name (a header repeated where
    /// two files were joined), says so with its line; lines ended by a lone CR are refused as
    /// such, not read as one header line.
    #[test]
    fn slips_in_number_cells_and_line_endings_are_named() {
        let number_error = |text: &str| {
            let t = Table::parse(text, Path::new("t.csv")).unwrap();
            let row = t.rows().last().unwrap();
            t.number(&row, 1).unwrap_err().to_string()
        };
        let comma = number_error("id,x\np1,\"1,5\"\n");
        assert!(
            comma.contains("line 2")
                && comma.ends_with(
                    "\"1,5\" is not a finite number: a decimal comma; this table writes decimal points (`1.5`)"
                ),
            "{comma}"
        );
        let header = number_error("id,x\np1,2\nid,x\n");
        assert!(
            header.contains("\"x\" is not a finite number: line 3 repeats the header"),
            "{header}"
        );
        assert_eq!(
            number_error("id,x\np1,abc\n"),
            "t.csv: line 2, column x: \"abc\" is not a finite number"
        );
        let minus = number_error("id,x\np1,\u{2212}3108.36\n");
        assert!(
            minus.contains("a typographic minus sign") && minus.ends_with("write `-3108.36`"),
            "{minus}"
        );
        let unnamed = Table::parse("id,x,,\np1,2,,\n", Path::new("t.csv"))
            .unwrap_err()
            .to_string();
        assert!(
            unnamed.contains("the header has unnamed columns (trailing commas"),
            "{unnamed}"
        );
        let cr = Table::parse("id,x\rp1,2\r", Path::new("t.csv"))
            .unwrap_err()
            .to_string();
        assert!(cr.starts_with("t.csv: its lines end in a lone carriage return"), "{cr}");
    }

    #[test]
    fn rows_keep_their_lines_and_cells() {
        let t = Table::parse(
            "# c
A, B
1, 2

3,
",
            Path::new("t.csv"),
        )
        .unwrap();
        assert_eq!(t.header, ["a", "b"]);
        assert_eq!(t.comments, ["c"]);
        let rows: Vec<(usize, Vec<String>)> = t
            .rows()
            .map(|r| (r.line, r.cells().map(String::from).collect()))
            .collect();
        assert_eq!(
            rows,
            [(3, vec!["1".into(), "2".into()]), (5, vec!["3".into(), String::new()])]
        );
        let last = t.rows().last().unwrap();
        assert_eq!(last.get(2), None);
        assert!(t.number(&last, 1).is_err());
    }
}
