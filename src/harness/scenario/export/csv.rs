//! `trials.csv`: `case,trial,seed,<metric...>,error`, one row per trial: a trial that
//! succeeded has its metrics and an empty `error`, one that failed empty metrics and its error.
//! Numbers are written with [`format_f64`] (shortest round-trip text), so reading a file back
//! gives the same bits and merged shards summarise exactly like a single run.

use super::{ExportError, io};
use crate::harness::scenario::metrics::TrialRecord;
use crate::harness::scenario::resolve::ResolvedScenario;
use crate::measurement::format_f64;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The last column: why a trial failed (empty when it succeeded).
pub const ERROR_COLUMN: &str = "error";

fn header(names: &[String]) -> Vec<String> {
    ["case", "trial", "seed"]
        .iter()
        .map(|s| (*s).to_owned())
        .chain(names.iter().cloned())
        .chain([ERROR_COLUMN.to_owned()])
        .collect()
}

fn row(scenario: &ResolvedScenario, names: usize, r: &TrialRecord) -> Vec<String> {
    let values: Vec<String> = match &r.error {
        None => r.values.iter().map(|v| format_f64(*v)).collect(),
        Some(_) => vec![String::new(); names],
    };
    [
        scenario.cases[r.case].name.clone(),
        r.trial.to_string(),
        r.seed.to_string(),
    ]
    .into_iter()
    .chain(values)
    .chain([r.error.clone().unwrap_or_default()])
    .collect()
}

/// Writes the header and `records` (in the order given) to `w`.
pub fn write_trials<W: Write>(
    w: W,
    scenario: &ResolvedScenario,
    names: &[String],
    records: &[TrialRecord],
) -> csv::Result<()> {
    let mut w = csv::Writer::from_writer(w);
    w.write_record(header(names))?;
    for r in records {
        w.write_record(row(scenario, names.len(), r))?;
    }
    w.flush()?;
    Ok(())
}

/// [`write_trials`] to a file (replacing it).
pub fn write_trials_file(
    path: &Path,
    scenario: &ResolvedScenario,
    names: &[String],
    records: &[TrialRecord],
) -> Result<(), ExportError> {
    let file = File::create(path).map_err(io(path))?;
    write_trials(std::io::BufWriter::new(file), scenario, names, records).map_err(|e| csv_error(path, e))
}

pub(crate) fn csv_error(path: &Path, e: csv::Error) -> ExportError {
    ExportError::Malformed {
        path: path.to_owned(),
        line: e.position().map_or(0, |p| p.line()),
        message: e.to_string(),
    }
}

/// Appends rows as trials finish (from any thread), flushing each, so a crash keeps what was
/// done. The final, sorted file replaces it at the end of the run.
pub struct PartialTrials {
    path: PathBuf,
    names: usize,
    writer: Mutex<csv::Writer<File>>,
}

impl PartialTrials {
    /// Creates `path` with the header.
    pub fn create(path: &Path, names: &[String]) -> Result<Self, ExportError> {
        let file = File::create(path).map_err(io(path))?;
        let mut writer = csv::Writer::from_writer(file);
        writer.write_record(header(names)).map_err(|e| csv_error(path, e))?;
        writer.flush().map_err(io(path))?;
        Ok(PartialTrials {
            path: path.to_owned(),
            names: names.len(),
            writer: Mutex::new(writer),
        })
    }

    /// Opens the trials file of an interrupted run for appending, after cutting off a last
    /// row left without its line end (the process was killed while writing it).
    pub fn resume(path: &Path, names: &[String]) -> Result<Self, ExportError> {
        let text = std::fs::read(path).map_err(io(path))?;
        let whole = text.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        let file = std::fs::OpenOptions::new().write(true).open(path).map_err(io(path))?;
        file.set_len(whole as u64).map_err(io(path))?;
        if whole == 0 {
            drop(file);
            return Self::create(path, names);
        }
        let file = std::fs::OpenOptions::new().append(true).open(path).map_err(io(path))?;
        Ok(PartialTrials {
            path: path.to_owned(),
            names: names.len(),
            writer: Mutex::new(csv::Writer::from_writer(file)),
        })
    }

    /// Appends one finished trial.
    pub fn append(&self, scenario: &ResolvedScenario, r: &TrialRecord) -> Result<(), ExportError> {
        let mut w = self.writer.lock().unwrap_or_else(|p| p.into_inner());
        w.write_record(row(scenario, self.names, r))
            .map_err(|e| csv_error(&self.path, e))?;
        w.flush().map_err(io(&self.path))
    }
}

/// Reads a trials file of `scenario` whose metric columns are `expected`, with each record's
/// 1-based file line (for messages naming a row), in file order. A header other than the one
/// written for `expected` is refused, naming its first differing column; a file without the
/// `error` column (written before failed trials were recorded) is read as one whose trials all
/// succeeded.
pub fn read_trials_located(
    path: &Path,
    scenario: &ResolvedScenario,
    expected: &[String],
) -> Result<TrialsWithLines, ExportError> {
    read_trials_with(path, scenario, expected, false)
}

/// A trials file's records and each one's 1-based file line.
pub type TrialsWithLines = (Vec<TrialRecord>, Vec<u64>);

/// [`read_trials_located`] of an interrupted run's file: a row without its line end at the end
/// of the file (the run killed while writing it) is dropped.
pub fn read_partial_trials(
    path: &Path,
    scenario: &ResolvedScenario,
    expected: &[String],
) -> Result<Vec<TrialRecord>, ExportError> {
    read_trials_with(path, scenario, expected, true).map(|(records, _)| records)
}

fn read_trials_with(
    path: &Path,
    scenario: &ResolvedScenario,
    expected: &[String],
    allow_torn_end: bool,
) -> Result<TrialsWithLines, ExportError> {
    let mut bytes = std::fs::read(path).map_err(io(path))?;
    crate::presets::check_encoding(&bytes).map_err(io(path))?;
    if allow_torn_end {
        bytes.truncate(bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1));
    }
    let mut reader = csv::Reader::from_reader(bytes.as_slice());
    let head: Vec<String> = reader
        .headers()
        .map_err(|e| csv_error(path, e))?
        .iter()
        .map(str::to_owned)
        .collect();
    let bad = |line: u64, message: String| ExportError::Malformed {
        path: path.to_owned(),
        line,
        message,
    };
    let has_error = check_header(&head, expected).map_err(|message| bad(1, message))?;
    let (mut records, mut lines) = (Vec::new(), Vec::new());
    for rec in reader.records() {
        let rec = rec.map_err(|e| csv_error(path, e))?;
        let line = rec.position().map_or(0, |p| p.line());
        if rec.len() != head.len() {
            return Err(bad(
                line,
                format!("{} columns, the header has {}", rec.len(), head.len()),
            ));
        }
        records.push(parse_row(&rec, &head, expected, has_error, scenario).map_err(|e| bad(line, e.to_string()))?);
        lines.push(line);
    }
    Ok((records, lines))
}

/// Checks a trials file's header `head` against the one [`header`] writes for the metrics
/// `expected`: whether it ends with the `error` column (a file written before failed trials
/// were recorded does not), or the first column that differs (one extra, missing, renamed or
/// moved), by its 1-based number, with the header expected.
fn check_header(head: &[String], expected: &[String]) -> Result<bool, String> {
    let want = header(expected);
    let listed = || want.join(",");
    if let Some(i) = (0..head.len().min(want.len())).find(|&i| head[i] != want[i]) {
        return Err(format!(
            "column {} is `{}` where this scenario's trials file has `{}` (header `{}`): the file is another \
             scenario's, or a column was added, removed or renamed by hand",
            i + 1,
            crate::csv_lines::shown_cell(&head[i]),
            want[i],
            listed()
        ));
    }
    match head.len() {
        n if n > want.len() => Err(format!(
            "column {} (`{}`) is one too many: this scenario's trials file ends at `{ERROR_COLUMN}` (header `{}`)",
            want.len() + 1,
            crate::csv_lines::shown_cell(&head[want.len()]),
            listed()
        )),
        n if n + 1 < want.len() => Err(format!(
            "the header ends after column {n}; this scenario's trials file has `{}` next (header `{}`)",
            want[n],
            listed()
        )),
        n => Ok(n == want.len()),
    }
}

/// What is wrong with one cell of a trials file.
#[derive(Debug, thiserror::Error)]
enum TrialRowError {
    #[error("column `case`: unknown case {0:?}")]
    UnknownCase(String),
    #[error("column `{column}`: {error}")]
    NotWhole {
        column: &'static str,
        error: std::num::ParseIntError,
    },
    #[error("column `trial`: {trial} >= trials {trials}")]
    TrialBeyond { trial: usize, trials: usize },
    #[error("column `{column}`: {value} is not finite (a trial's metrics are)")]
    NotFinite { column: String, value: f64 },
    #[error("column `{column}`: {text:?}: {error}")]
    NotANumber {
        column: String,
        text: String,
        error: std::num::ParseFloatError,
    },
}

/// One row of a trials file (`rec`, header `head`).
fn parse_row(
    rec: &csv::StringRecord,
    head: &[String],
    names: &[String],
    has_error: bool,
    scenario: &ResolvedScenario,
) -> Result<TrialRecord, TrialRowError> {
    let name = &rec[0];
    let case = scenario
        .cases
        .iter()
        .position(|c| c.name == name)
        .ok_or_else(|| TrialRowError::UnknownCase(crate::csv_lines::shown_cell(name)))?;
    let whole = |column: &'static str, text: &str| {
        text.parse::<u64>()
            .map_err(|error| TrialRowError::NotWhole { column, error })
    };
    let trial = whole("trial", &rec[1])?;
    if trial >= scenario.trials as u64 {
        return Err(TrialRowError::TrialBeyond {
            trial: trial as usize,
            trials: scenario.trials,
        });
    }
    let (trial, seed) = (trial as usize, whole("seed", &rec[2])?);
    let error = Some(rec[head.len() - 1].to_owned()).filter(|e| has_error && !e.is_empty());
    let values = if error.is_some() {
        Vec::new()
    } else {
        (3..3 + names.len())
            .map(|i| match rec[i].parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                Ok(value) => Err(TrialRowError::NotFinite {
                    column: head[i].clone(),
                    value,
                }),
                Err(error) => Err(TrialRowError::NotANumber {
                    column: head[i].clone(),
                    text: crate::csv_lines::shown_cell(&rec[i]),
                    error,
                }),
            })
            .collect::<Result<Vec<_>, _>>()?
    };
    Ok(TrialRecord {
        case,
        trial,
        seed,
        values,
        error,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn head(text: &str) -> Vec<String> {
        text.split(',').map(str::to_owned).collect()
    }

    #[test]
    fn the_header_written_is_read_with_or_without_its_error_column() {
        let names = head("a_mm,b_mm");
        assert_eq!(check_header(&header(&names), &names), Ok(true));
        assert_eq!(check_header(&head("case,trial,seed,a_mm,b_mm"), &names), Ok(false));
    }

    #[test]
    fn a_header_edited_by_hand_is_refused_at_its_first_differing_column() {
        let names = head("a_mm,b_mm");
        let refusal = |text: &str| check_header(&head(text), &names).unwrap_err();
        assert!(refusal("case,trial,seed,a_mm,b_mm,error,note").starts_with("column 7 (`note`) is one too many"));
        assert!(refusal("case,trial,seed,a_mm,note,b_mm,error").starts_with("column 5 is `note` where"));
        assert!(refusal("case,trial,seed,a_mm,b_mm,note").starts_with("column 6 is `note` where"));
        assert!(refusal("case,trial,seed,b_mm,a_mm,error").starts_with("column 4 is `b_mm` where"));
        assert!(
            refusal("case,trial,seed,a_mm")
                .starts_with("the header ends after column 4; this scenario's trials file has `b_mm` next")
        );
        assert!(refusal("trial,case,seed,a_mm,b_mm,error").starts_with("column 1 is `trial` where"));
        let long = format!("case,trial,seed,a_mm,{},error", "x".repeat(10_000));
        assert!(refusal(&long).len() < 300);
    }
}
