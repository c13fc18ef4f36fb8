//! Reading and writing the measurement CSV (`docs/formats.md#measurement-csv`).
//!
//! Header required; columns found by name in any order (surrounding white space ignored);
//! `#` lines are comments; unknown columns are ignored. Every malformed file gives one
//! [`MeasurementFileError`] naming the file, the 1-based line and the column.

mod columns;

use super::data::{MAX_LABEL_CHARS, Measurement, MeasurementSet, RowProblem, too_long};
use crate::csv_lines::{LineIndex, LineTracking, commented_row, shown_cell};
use columns::find_columns;
use std::fs::OpenOptions;
use std::io;
use std::num::FpCategory;
use std::path::{Path, PathBuf};

/// A problem reading or writing a measurement file.
#[derive(Debug, thiserror::Error)]
pub enum MeasurementFileError {
    /// The file could not be opened, read or written.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        cause: io::Error,
    },
    /// The output file exists and overwriting was not allowed.
    #[error("{path}: file exists; refusing to overwrite it")]
    Exists {
        /// The file.
        path: PathBuf,
    },
    /// The file is not valid CSV (e.g. not UTF-8, unterminated quote).
    #[error("{path}:{line}: malformed CSV: {message}")]
    Csv {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// What the CSV parser said.
        message: String,
    },
    /// The file has no header row (nothing, or white space only).
    #[error("{path}: empty file (nothing but white space): no header row")]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// The file has a header but no data rows.
    #[error("{path}:{line}: no measurement rows after the header")]
    NoRows {
        /// The file.
        path: PathBuf,
        /// 1-based line of the header.
        line: u64,
    },
    /// A required column is absent from the header.
    #[error("{path}:{line}: column `{column}`: missing from the header")]
    MissingColumn {
        /// The file.
        path: PathBuf,
        /// 1-based line of the header.
        line: u64,
        /// The missing column.
        column: String,
    },
    /// The header is one column holding another separator (`;`, tab): not comma-separated.
    #[error(
        "{path}:{line}: the header is a single column containing {separator}: the file looks separated by {separator}, \
         but the measurement CSV is comma-separated with decimal points (re-export it as CSV)"
    )]
    WrongSeparator {
        /// The file.
        path: PathBuf,
        /// 1-based line of the header.
        line: u64,
        /// The separator found, in words (`';'`, `a tab`).
        separator: String,
    },
    /// A coordinate column is missing and a header name is that coordinate with its unit written
    /// otherwise (`X [mm]`, `x (m)`, `X`): another tool's name for it.
    #[error(
        "{path}:{line}: column `{column}`: missing; the header has \"{found}\", which looks like the same coordinate \
         {advice}"
    )]
    CoordinateSpelled {
        /// The file.
        path: PathBuf,
        /// 1-based line of the header.
        line: u64,
        /// The missing column (`x_mm`).
        column: String,
        /// The header name (non-ASCII characters escaped).
        found: String,
        /// Its unit in words and what to do (`in m: multiply it by 1000 ...`).
        advice: String,
    },
    /// A required column is missing and a header name spells it with a look-alike character
    /// (a non-breaking space, a Unicode dash).
    #[error(
        "{path}:{line}: column `{column}`: missing; the header has \"{found}\", which reads `{column}` but holds a character that only looks like `_` or a space (a non-breaking space or a Unicode dash, copied from a web page or a word processor): retype the header name as `{column}`"
    )]
    LookAlikeColumn {
        /// The file.
        path: PathBuf,
        /// 1-based line of the header.
        line: u64,
        /// The missing column.
        column: String,
        /// The header name that looks like it (non-ASCII characters escaped).
        found: String,
    },
    /// A joint command column spelled otherwise than `cmd_k` (`cmd_02`, `cmd_+2`): another
    /// tool's name for it, or a second column of the same joint.
    #[error(
        "{path}:{line}: column `{found}`: reads as joint {joint}'s command but is not spelled `{column}`: rename it `{column}` (or, if the file has `{column}` too, remove one of them)"
    )]
    CommandColumnSpelling {
        /// The file.
        path: PathBuf,
        /// 1-based line of the header.
        line: u64,
        /// The header name as written (lower-cased).
        found: String,
        /// The joint (1-based).
        joint: usize,
        /// Its column's name, `cmd_k`.
        column: String,
    },
    /// A column appears twice in the header.
    #[error("{path}:{line}: column `{column}`: appears more than once in the header")]
    DuplicateColumn {
        /// The file.
        path: PathBuf,
        /// 1-based line of the header.
        line: u64,
        /// The column.
        column: String,
    },
    /// The `cmd_k` columns do not match the robot's joint count.
    #[error(
        "{path}:{line}: column `{column}`: the file has {found} joint command columns, expected {expected} (every joint of the robot description, also joints not swept: a file cut to fewer joints is refused)"
    )]
    JointCount {
        /// The file.
        path: PathBuf,
        /// 1-based line of the header.
        line: u64,
        /// The first offending (extra or missing) `cmd_k` column.
        column: String,
        /// Number of `cmd_k` columns in the file.
        found: usize,
        /// N.
        expected: usize,
    },
    /// A `#` line among the rows has as many fields as the row above it: a data row whose
    /// experiment id starts with `#`, which the reader would skip as a comment.
    #[error("{path}:{line}: {}", commented_row(*fields))]
    CommentedRow {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// Its comma-separated fields.
        fields: usize,
    },
    /// The lines end in a lone carriage return (classic Mac OS), which the reader does not split.
    #[error("{path}: {}", crate::csv_lines::CR_ONLY)]
    CarriageReturnsOnly {
        /// The file.
        path: PathBuf,
    },
    /// A row has more non-empty fields than the header names columns: a shifted row.
    #[error("{path}:{line}: {}", crate::csv_lines::wider_than_header(*fields, *columns))]
    LongRow {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// Its fields (up to the last non-empty one).
        fields: usize,
        /// The header's columns.
        columns: usize,
    },
    /// The file is not a text CSV (JSON, binary): no column could be named in it.
    #[error("{path}: not a measurement CSV: {what}")]
    NotCsv {
        /// The file.
        path: PathBuf,
        /// What it looks like instead.
        what: String,
    },
    /// The file is another axiscal command's output (residuals, compensate's table, the joint
    /// map...) or a pose list, not measurements.
    #[error(
        "{path}: this is {what}, not a measurement CSV (no `x_mm` or `cmd_1` column): give the measurement file \
         (the CSV `import` or `simulate` wrote, which `calibrate` read)"
    )]
    OtherFile {
        /// The file.
        path: PathBuf,
        /// What it is, in words.
        what: String,
    },
    /// A line repeats the header: files joined end to end, or a header pasted twice.
    #[error(
        "{path}:{line}: the line repeats the header (line {header_line}): two files joined end to end, or a header \
         pasted twice; delete the line (and the rows repeated after it, if the same rows come twice)"
    )]
    RepeatedHeader {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// The header's line.
        header_line: u64,
    },
    /// A field holds an ASCII control byte, which no value or label contains.
    #[error(
        "{path}:{line}: column `{column}`: holds the control byte 0x{byte:02x}{}: not text a value or label \
         contains (a DOS end-of-file mark, padding, or a damaged copy); delete it",
        if *only { ", and nothing else" } else { "" }
    )]
    ControlByte {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// The column (its header name, or `field N` beyond the header).
        column: String,
        /// The first control byte.
        byte: u8,
        /// Whether the line holds nothing else but white space.
        only: bool,
    },
    /// A field the file's reading needs is not UTF-8 text.
    #[error(
        "{path}:{line}: column `{column}`: not UTF-8 text (a byte of another encoding, e.g. Latin-1): save the file \
         as UTF-8"
    )]
    NotUtf8Field {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// The column.
        column: String,
    },
    /// A data row is one field holding another separator (`;`, tab), in a comma-separated file.
    #[error(
        "{path}:{line}: the row is a single field containing {separator}: it looks separated by {separator} where \
         the header and the measurement CSV are comma-separated (type it again with commas)"
    )]
    RowSeparator {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// The separator found, in words (`';'`, `a tab`).
        separator: String,
    },
    /// A row ends before this column.
    #[error("{path}:{line}: column `{column}`: missing value (row shorter than the header)")]
    MissingField {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// The column.
        column: String,
    },
    /// A value is not a number.
    #[error(
        "{path}:{line}: column `{column}`: {value:?} is not a number{}",
        typographic_minus_hint(value)
    )]
    NotANumber {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// The column.
        column: String,
        /// The text found.
        value: String,
    },
    /// A value is NaN or infinite.
    #[error("{path}:{line}: column `{column}`: {value:?} is not finite")]
    NotFinite {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// The column.
        column: String,
        /// The text found.
        value: String,
    },
    /// An integer column holds something else.
    #[error("{path}:{line}: column `{column}`: {value:?} is not a non-negative integer")]
    NotAnInteger {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// The column.
        column: String,
        /// The text found.
        value: String,
    },
    /// A target's name or a setup's label is longer than [`MAX_LABEL_CHARS`].
    #[error(
        "{path}:{line}: column `{column}`: {value:?} is longer than {MAX_LABEL_CHARS} characters: a label names a \
         target or a setup (`T1`, `A`); shorten it"
    )]
    LongLabel {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// The column.
        column: String,
        /// The text found, shortened ([`shown_cell`]).
        value: String,
    },
    /// Target ids mix integers and names.
    #[error(
        "{path}:{line}: column `target`: {value:?} is {found}, but earlier rows' target ids are {earlier}: ids are either all integers or all names"
    )]
    MixedTargetIds {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// The text found.
        value: String,
        /// What it is (`an integer`, `a name`).
        found: &'static str,
        /// What the earlier ones are.
        earlier: &'static str,
    },
    /// An integer column holds a negative value.
    #[error("{path}:{line}: column `{column}`: {value:?} is negative")]
    Negative {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// The column.
        column: String,
        /// The text found.
        value: String,
    },
    /// A row breaks a data-set rule (range, duplicate key, consistency).
    #[error("{path}:{line}: column `{column}`: {problem}")]
    InvalidRow {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// The column.
        column: String,
        /// What is wrong (a `DuplicateKey`'s `first_at` and a `PoseCommandsDiffer`'s `reading_at`
        /// are line numbers).
        problem: Box<RowProblem>,
    },
}

/// What a cell that is a number but for a typographic minus sign should be written as.
fn typographic_minus_hint(value: &str) -> String {
    crate::csv_lines::with_ascii_minus(value)
        .map(|ascii| format!(": {}; write `{ascii}`", crate::csv_lines::TYPOGRAPHIC_MINUS))
        .unwrap_or_default()
}

/// Column positions found in the header.
struct Columns {
    experiment: usize,
    moved_joint: usize,
    step: usize,
    target: usize,
    position: [usize; 3],
    cmd: Vec<usize>,
    payload_kg: Option<usize>,
    temperature_c: Option<usize>,
    setup: Option<usize>,
}

impl Columns {
    /// Whether the reading uses column `i`.
    fn reads(&self, i: usize) -> bool {
        [self.experiment, self.moved_joint, self.step, self.target].contains(&i)
            || self.position.contains(&i)
            || self.cmd.contains(&i)
            || [self.payload_kg, self.temperature_c, self.setup].contains(&Some(i))
    }
}

const POSITION_COLUMNS: [&str; 3] = ["x_mm", "y_mm", "z_mm"];

/// Reads a measurement file. `joint_count`: N from the robot description; when `None`, N is
/// the number of `cmd_k` columns, which must be `cmd_1..cmd_N`.
pub fn read_measurements(path: &Path, joint_count: Option<usize>) -> Result<MeasurementSet, MeasurementFileError> {
    let io_error = |source| MeasurementFileError::Io {
        path: path.into(),
        cause: source,
    };
    let file = crate::presets::regular_file(path)
        .and_then(|()| std::fs::File::open(path))
        .map_err(io_error)?;
    let mut reader = io::BufReader::with_capacity(1 << 16, file);
    let start = io::BufRead::fill_buf(&mut reader).map_err(io_error)?;
    crate::presets::check_encoding(start).map_err(io_error)?;
    if crate::csv_lines::carriage_returns_only(start) {
        return Err(MeasurementFileError::CarriageReturnsOnly { path: path.into() });
    }
    let whole = std::fs::metadata(path).is_ok_and(|m| m.len() == start.len() as u64);
    if whole && start.iter().all(u8::is_ascii_whitespace) {
        return Err(MeasurementFileError::Empty { path: path.into() });
    }
    if let Some(what) = crate::csv_lines::not_text_csv(start) {
        return Err(MeasurementFileError::NotCsv {
            path: path.into(),
            what,
        });
    }
    read_measurements_from(reader, path, joint_count)
}

/// [`read_measurements`] from any reader; `path` only labels errors. One streaming pass:
/// time linear in the file, memory that of the rows kept (line numbers from
/// [`crate::csv_lines`]).
pub fn read_measurements_from<R: io::Read>(
    reader: R,
    path: &Path,
    joint_count: Option<usize>,
) -> Result<MeasurementSet, MeasurementFileError> {
    let (reader, index) = LineTracking::new(reader);
    let line_at = |position: Option<&csv::Position>| position.map_or(0, |p| index.line_of(p.byte()));
    let mut csv = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .flexible(true)
        .has_headers(true)
        .from_reader(reader);
    let csv_error = |e: csv::Error| {
        let (line, message) = (line_at(e.position()), e.to_string());
        match e.into_kind() {
            csv::ErrorKind::Io(source) => MeasurementFileError::Io {
                path: path.into(),
                cause: source,
            },
            _ => MeasurementFileError::Csv {
                path: path.into(),
                line,
                message,
            },
        }
    };
    let header = csv.headers().map_err(csv_error)?.clone();
    if header.is_empty() {
        return Err(MeasurementFileError::Empty { path: path.into() });
    }
    let header_line = line_at(header.position());
    let columns = find_columns(&header, path, header_line, joint_count)?;
    let mut rows = Vec::new();
    let mut lines = Vec::new();
    let (mut record, mut bytes) = (csv::StringRecord::new(), csv::ByteRecord::new());
    let mut targets = TargetIds::default();
    let mut setups = Labels::default();
    let mut row_setups = Vec::new();
    while csv.read_byte_record(&mut bytes).map_err(csv_error)? {
        let line = line_at(bytes.position());
        as_text(&bytes, (&header, &columns), (path, line), &mut record)?;
        // A blank line (csv-core also returns a trailing comment split over two reads so).
        if record.len() == 1 && record[0].trim().is_empty() {
            continue;
        }
        commented_row_before(&index, line, path)?;
        stray_line(&record, &header, path, (line, header_line))?;
        // Checked before any value: a decimal comma shifts every later cell into the wrong
        // column, where it would be read as some other, wrong, number.
        let fields = (0..record.len())
            .rev()
            .find(|&i| !record[i].trim().is_empty())
            .map_or(0, |i| i + 1);
        if fields > header.len() {
            return Err(MeasurementFileError::LongRow {
                path: path.into(),
                line,
                fields,
                columns: header.len(),
            });
        }
        let cells = Cells {
            record: &record,
            header: &header,
            path,
            line,
        };
        let target = targets.id(&cells, columns.target)?;
        if let Some(c) = columns.setup {
            row_setups.push(setups.id(cells.label(c)?));
        }
        rows.push(parse_row(&cells, &columns, target)?);
        lines.push(line);
    }
    commented_row_before(&index, u64::MAX, path)?;
    if rows.is_empty() {
        return Err(MeasurementFileError::NoRows {
            path: path.into(),
            line: header_line,
        });
    }
    let invalid = |e: super::MeasurementSetError| {
        let column = e.problem.column();
        let problem = Box::new(with_lines(e.problem, &lines));
        MeasurementFileError::InvalidRow {
            path: path.into(),
            line: lines[e.row],
            column,
            problem,
        }
    };
    let set = MeasurementSet::new(columns.cmd.len(), rows).map_err(invalid)?;
    if let Some((row, problem)) = super::data::axis_id_of_free_poses(set.rows()) {
        return Err(invalid(super::MeasurementSetError { row, problem }));
    }
    Ok(set
        .with_target_names(targets.names)
        .with_setups(row_setups, setups.names)
        .with_lines(lines))
}

/// A row that is no data row: a repeat of the header, or a field with an ASCII control byte
/// (tab aside), each an error naming the line (`lines`: the row's and the header's).
/// `bytes` as text in `record`: a field of a column the reading needs (`columns`) must be
/// UTF-8; any other (an extra column, which is not read) is taken as empty where it is not.
fn as_text(
    bytes: &csv::ByteRecord,
    (header, columns): (&csv::StringRecord, &Columns),
    (path, line): (&Path, u64),
    record: &mut csv::StringRecord,
) -> Result<(), MeasurementFileError> {
    record.clear();
    for (i, field) in bytes.iter().enumerate() {
        match std::str::from_utf8(field) {
            Ok(text) => record.push_field(text),
            Err(_) if columns.reads(i) => {
                return Err(MeasurementFileError::NotUtf8Field {
                    path: path.into(),
                    line,
                    column: header.get(i).unwrap_or_default().to_owned(),
                });
            }
            Err(_) => record.push_field(""),
        }
    }
    record.set_position(bytes.position().cloned());
    Ok(())
}

/// A data row of one field holding `;` or a tab under a header of several columns: pasted from
/// a file separated otherwise.
fn one_field_row(
    record: &csv::StringRecord,
    header: &csv::StringRecord,
    path: &Path,
    line: u64,
) -> Result<(), MeasurementFileError> {
    if record.len() != 1 || header.len() < 2 {
        return Ok(());
    }
    let separator = match record[0] {
        ref f if f.contains(';') => "';'",
        ref f if f.contains('\t') => "a tab",
        _ => return Ok(()),
    };
    Err(MeasurementFileError::RowSeparator {
        path: path.into(),
        line,
        separator: separator.to_owned(),
    })
}

/// A data line that is not a row of the file: one field holding another separator
/// ([`one_field_row`]), the header repeated, or a control byte.
fn stray_line(
    record: &csv::StringRecord,
    header: &csv::StringRecord,
    path: &Path,
    (line, header_line): (u64, u64),
) -> Result<(), MeasurementFileError> {
    one_field_row(record, header, path, line)?;
    if record.len() == header.len() && record.iter().zip(header).all(|(a, b)| a.trim() == b.trim()) {
        return Err(MeasurementFileError::RepeatedHeader {
            path: path.into(),
            line,
            header_line,
        });
    }
    let control = |b: &u8| b.is_ascii_control() && !matches!(b, b'\t' | b'\r' | b'\n');
    let Some((i, byte)) = record
        .iter()
        .enumerate()
        .find_map(|(i, field)| Some((i, *field.as_bytes().iter().find(|b| control(b))?)))
    else {
        return Ok(());
    };
    let only = record
        .iter()
        .flat_map(|f| f.bytes())
        .all(|b| control(&b) || b.is_ascii_whitespace());
    Err(MeasurementFileError::ControlByte {
        path: path.into(),
        line,
        column: header.get(i).map_or_else(|| format!("field {}", i + 1), str::to_owned),
        byte,
        only,
    })
}

/// `problem` of a set read from a file with the rows' `lines`: its row indices as lines.
fn with_lines(problem: RowProblem, lines: &[u64]) -> RowProblem {
    match problem {
        RowProblem::DuplicateKey {
            experiment,
            step,
            target,
            first_at,
        } => RowProblem::DuplicateKey {
            experiment,
            step,
            target,
            first_at: lines[first_at as usize],
        },
        RowProblem::PoseCommandsDiffer {
            experiment,
            step,
            joint,
            value,
            reading,
            reading_at,
            majority,
        } => RowProblem::PoseCommandsDiffer {
            experiment,
            step,
            joint,
            value,
            reading,
            reading_at: lines[reading_at as usize],
            majority,
        },
        other => other,
    }
}

/// Refuses a `#` line before `line` that looks like a data row ([`LineIndex::commented_row`]).
fn commented_row_before(index: &LineIndex, line: u64, path: &Path) -> Result<(), MeasurementFileError> {
    match index.commented_row() {
        Some((at, fields)) if at < line => Err(MeasurementFileError::CommentedRow {
            path: path.into(),
            line: at,
            fields,
        }),
        _ => Ok(()),
    }
}

/// Labels numbered 0, 1, ... in the order they first appear.
#[derive(Default)]
struct Labels {
    names: Vec<String>,
}

impl Labels {
    fn id(&mut self, text: &str) -> usize {
        self.names.iter().position(|n| n == text).unwrap_or_else(|| {
            self.names.push(text.to_string());
            self.names.len() - 1
        })
    }
}

/// One data record with what is needed to name its cells in errors.
struct Cells<'a> {
    record: &'a csv::StringRecord,
    header: &'a csv::StringRecord,
    path: &'a Path,
    line: u64,
}

impl Cells<'_> {
    fn column(&self, i: usize) -> String {
        self.header
            .get(i)
            .unwrap_or_default()
            .trim_start_matches('\u{feff}')
            .trim()
            .to_string()
    }

    fn text(&self, i: usize) -> Result<&str, MeasurementFileError> {
        self.record
            .get(i)
            .map(str::trim)
            .ok_or_else(|| MeasurementFileError::MissingField {
                path: self.path.into(),
                line: self.line,
                column: self.column(i),
            })
    }

    /// A label (a target's name, a setup's): at most [`MAX_LABEL_CHARS`] characters.
    fn label(&self, i: usize) -> Result<&str, MeasurementFileError> {
        let text = self.text(i)?;
        if too_long(text) {
            return Err(MeasurementFileError::LongLabel {
                path: self.path.into(),
                line: self.line,
                column: self.column(i),
                value: shown_cell(text),
            });
        }
        Ok(text)
    }

    fn number(&self, i: usize) -> Result<f64, MeasurementFileError> {
        let text = self.text(i)?;
        // The error's strings are built only on the error path: this runs for every cell.
        let parts = || (self.path.into(), self.line, self.column(i), shown_cell(text));
        match text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => {
                let (path, line, column, value) = parts();
                Err(MeasurementFileError::NotFinite {
                    path,
                    line,
                    column,
                    value,
                })
            }
            Err(_) => {
                let (path, line, column, value) = parts();
                Err(MeasurementFileError::NotANumber {
                    path,
                    line,
                    column,
                    value,
                })
            }
        }
    }

    fn optional_number(&self, i: Option<usize>, default: f64) -> Result<f64, MeasurementFileError> {
        match i {
            Some(i) if !self.record.get(i).unwrap_or_default().trim().is_empty() => self.number(i),
            _ => Ok(default),
        }
    }

    fn integer(&self, i: usize) -> Result<usize, MeasurementFileError> {
        let text = self.text(i)?;
        if let Ok(v) = text.parse::<usize>() {
            return Ok(v);
        }
        let (path, line, column, value) = (self.path.into(), self.line, self.column(i), shown_cell(text));
        match text.parse::<i128>() {
            Ok(v) if v < 0 => Err(MeasurementFileError::Negative {
                path,
                line,
                column,
                value,
            }),
            _ => Err(MeasurementFileError::NotAnInteger {
                path,
                line,
                column,
                value,
            }),
        }
    }
}

/// The target ids of a file: integers as written, or names (`T1`, `SMR2`, `A`) numbered 0, 1,
/// ... in the order they first appear; one file uses one kind.
#[derive(Default)]
struct TargetIds {
    /// The names in id order, when the file names its targets.
    names: Vec<String>,
    /// Whether the rows so far gave integers.
    integers: bool,
}

impl TargetIds {
    /// The id of the `target` cell of `cells`.
    fn id(&mut self, cells: &Cells<'_>, column: usize) -> Result<usize, MeasurementFileError> {
        let text = cells.label(column)?;
        let integer = text.parse::<usize>().ok();
        let mixed = |found, earlier| MeasurementFileError::MixedTargetIds {
            path: cells.path.into(),
            line: cells.line,
            value: shown_cell(text),
            found,
            earlier,
        };
        match integer {
            Some(_) if !self.names.is_empty() => Err(mixed("an integer", "names")),
            Some(v) => {
                self.integers = true;
                Ok(v)
            }
            // A negative or fractional number is a malformed integer, not a name.
            None if self.integers || text.is_empty() || text.parse::<f64>().is_ok() => {
                if self.integers && text.parse::<f64>().is_err() && !text.is_empty() {
                    return Err(mixed("a name", "integers"));
                }
                cells.integer(column)
            }
            None => Ok(match self.names.iter().position(|n| n == text) {
                Some(i) => i,
                None => {
                    self.names.push(text.to_string());
                    self.names.len() - 1
                }
            }),
        }
    }
}

fn parse_row(cells: &Cells<'_>, columns: &Columns, target: usize) -> Result<Measurement, MeasurementFileError> {
    let [x, y, z] = columns.position;
    Ok(Measurement {
        experiment: cells.text(columns.experiment)?.to_string(),
        moved_joint: cells.integer(columns.moved_joint)?,
        step: cells.integer(columns.step)?,
        target,
        position_mm: [cells.number(x)?, cells.number(y)?, cells.number(z)?],
        cmd: columns.cmd.iter().map(|&i| cells.number(i)).collect::<Result<_, _>>()?,
        payload_kg: cells.optional_number(columns.payload_kg, Measurement::DEFAULT_PAYLOAD_KG)?,
        temperature_c: cells.optional_number(columns.temperature_c, Measurement::DEFAULT_TEMPERATURE_C)?,
    })
}

/// Shortest text that parses back to the same `f64` bit pattern (Rust's shortest
/// round-trip formatting; exponent form outside [1e-5, 1e16) to stay short).
pub fn format_f64(v: f64) -> String {
    let a = v.abs();
    if v.classify() == FpCategory::Zero || (1e-5..1e16).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// `values` as a TOML array writes them, `[a, b, ...]`, each by [`format_f64`].
pub fn format_f64_list(values: &[f64]) -> String {
    let v: Vec<String> = values.iter().map(|v| format_f64(*v)).collect();
    format!("[{}]", v.join(", "))
}

/// [`format_f64`] of `v` rounded to 12 significant digits: a value converted for a message
/// (0.00019 m as 0.19 mm, not 0.19000000000000003 mm), where the last bits of the product are
/// the conversion's, not the user's.
pub fn format_f64_converted(v: f64) -> String {
    format_f64(format!("{v:.11e}").parse().unwrap_or(v))
}

/// Writes `set` to `path` with the header
/// `experiment,moved_joint,step,target,x_mm,y_mm,z_mm,cmd_1..cmd_N,payload_kg,temperature_c`.
/// Fails with [`MeasurementFileError::Exists`] if the file exists and `overwrite` is false.
pub fn write_measurements(path: &Path, set: &MeasurementSet, overwrite: bool) -> Result<(), MeasurementFileError> {
    let io_error = |source| MeasurementFileError::Io {
        path: path.into(),
        cause: source,
    };
    let file = OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .create_new(!overwrite)
        .open(path);
    let file = file.map_err(|source| match source.kind() {
        io::ErrorKind::AlreadyExists => MeasurementFileError::Exists { path: path.into() },
        _ => io_error(source),
    })?;
    write_measurements_to(io::BufWriter::new(file), set).map_err(io_error)
}

/// [`write_measurements`] to any writer.
pub fn write_measurements_to<W: io::Write>(writer: W, set: &MeasurementSet) -> io::Result<()> {
    let mut csv = crate::csv_lines::writer(writer);
    let mut header: Vec<String> = ["experiment", "moved_joint", "step", "target"]
        .map(String::from)
        .to_vec();
    header.extend(POSITION_COLUMNS.map(String::from));
    header.extend((1..=set.joint_count()).map(|k| format!("cmd_{k}")));
    header.extend(["payload_kg".to_string(), "temperature_c".to_string()]);
    // Only files with several setups carry the column: every other file is written as before.
    let setups = set.setup_names().len() > 1;
    if setups {
        header.push("setup".into());
    }
    csv.write_record(&header)?;
    for (row, m) in set.rows().iter().enumerate() {
        let mut record = vec![
            m.experiment.clone(),
            m.moved_joint.to_string(),
            m.step.to_string(),
            set.target_name(m.target),
        ];
        record.extend(m.position_mm.iter().chain(&m.cmd).map(|&v| format_f64(v)));
        record.extend([format_f64(m.payload_kg), format_f64(m.temperature_c)]);
        if setups {
            record.push(set.setup_names()[set.setup_of(row)].clone());
        }
        csv.write_record(&record)?;
    }
    csv.flush()
}

#[cfg(test)]
mod tests;
