//! A small CSV table as instruments and lab scripts export it: a header row (the first line
//! that is not a `#` comment or blank), columns found by name (case and surrounding white space
//! ignored), every cell kept with its 1-based physical line for messages.

use super::points::PointsError;
use crate::csv_lines::shown_cell;
use std::path::{Path, PathBuf};

/// A read table.
#[derive(Debug)]
pub struct Table {
    /// The file.
    pub path: PathBuf,
    /// The column names, trimmed, lower case.
    pub header: Vec<String>,
    /// The data rows: 1-based line and cells.
    pub rows: Vec<(usize, Vec<String>)>,
    /// The comment lines before the header (without their `#`).
    pub comments: Vec<String>,
}

impl Table {
    /// Reads `path` (a shipped file's virtual path too).
    pub fn read(path: &Path) -> Result<Self, PointsError> {
        let text = crate::presets::read_text(path).map_err(|source| PointsError::Io {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parses `text`; `path` labels messages.
    pub fn parse(text: &str, path: &Path) -> Result<Self, PointsError> {
        let mut header: Option<Vec<String>> = None;
        let mut rows = Vec::new();
        let mut comments = Vec::new();
        for (i, line) in text.trim_start_matches('\u{feff}').lines().enumerate() {
            let trimmed = line.trim();
            if trimmed.is_empty() || trimmed.starts_with('#') {
                if header.is_none() && trimmed.starts_with('#') {
                    comments.push(trimmed.trim_start_matches('#').trim().to_owned());
                }
                continue;
            }
            let cells = split(line).map_err(|message| PointsError::Row {
                path: path.to_owned(),
                line: i + 1,
                field: String::new(),
                message,
            })?;
            match &header {
                None => header = Some(cells.iter().map(|c| c.to_lowercase()).collect::<Vec<String>>()),
                // More cells than columns: a shifted row would be read into the wrong columns
                // (empty cells past the last column, a writer's trailing separators, are not).
                Some(h) if cells[h.len().min(cells.len())..].iter().any(|c| !c.trim().is_empty()) => {
                    return Err(PointsError::Row {
                        path: path.to_owned(),
                        line: i + 1,
                        field: format!("{} (after the last)", cells.len()),
                        message: format!(
                            "{} cells, the header names {} columns: a separator inside a value, or a missing header name?",
                            cells.len(),
                            h.len()
                        ),
                    });
                }
                Some(_) => rows.push((i + 1, cells)),
            }
        }
        let header = header.ok_or_else(|| PointsError::File {
            path: path.to_owned(),
            message: "no header row".into(),
        })?;
        for (k, name) in header.iter().enumerate() {
            if header[..k].contains(name) {
                return Err(PointsError::File {
                    path: path.to_owned(),
                    message: format!("column {name:?} appears twice"),
                });
            }
        }
        Ok(Table {
            path: path.to_owned(),
            header,
            rows,
            comments,
        })
    }

    /// The index of the first column named one of `names`.
    pub fn column(&self, names: &[&str]) -> Option<usize> {
        names.iter().find_map(|n| self.header.iter().position(|h| h == n))
    }

    /// The index of a column named one of `names`, or an error naming the file and the names.
    pub fn required(&self, names: &[&str]) -> Result<usize, PointsError> {
        self.column(names).ok_or_else(|| PointsError::File {
            path: self.path.clone(),
            message: format!("no column {} (columns: {})", names.join(" or "), self.header.join(",")),
        })
    }

    /// The cell at `column` of the row at `line`, or an error naming file, line and column.
    pub fn cell<'a>(&'a self, line: usize, cells: &'a [String], column: usize) -> Result<&'a str, PointsError> {
        cells.get(column).map(String::as_str).ok_or_else(|| PointsError::Row {
            path: self.path.clone(),
            line,
            field: self.header[column].clone(),
            message: "missing (the row is shorter than the header)".into(),
        })
    }

    /// A finite number at `column`.
    pub fn number(&self, line: usize, cells: &[String], column: usize) -> Result<f64, PointsError> {
        let text = self.cell(line, cells, column)?;
        text.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.row_error(line, column, format!("{:?} is not a finite number", shown_cell(text))))
    }

    /// A non-negative integer at `column`.
    pub fn integer(&self, line: usize, cells: &[String], column: usize) -> Result<usize, PointsError> {
        let text = self.cell(line, cells, column)?;
        text.parse::<usize>().map_err(|_| {
            self.row_error(
                line,
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
            field: self.header.get(column).cloned().unwrap_or_default(),
            message,
        }
    }
}

/// One CSV line's cells (RFC 4180 quoting within the line), trimmed. A line without a quote is
/// split at its commas directly (what the CSV reader would do, without building one per line).
fn split(line: &str) -> Result<Vec<String>, String> {
    if !line.contains('"') {
        return Ok(line.split(',').map(|c| c.trim().to_owned()).collect());
    }
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(line.as_bytes());
    let mut record = csv::StringRecord::new();
    reader.read_record(&mut record).map_err(|e| e.to_string())?;
    Ok(record.iter().map(|c| c.trim().to_owned()).collect())
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
            prop_assert_eq!(split(&line).unwrap(), by_reader(&line));
        }
    }

    #[test]
    fn a_quoted_cell_keeps_its_comma() {
        assert_eq!(split("1,\"a, b\",3").unwrap(), ["1", "a, b", "3"]);
    }
}
