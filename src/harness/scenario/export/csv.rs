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

/// Reads a trials file of `scenario`: the metric names (header after `case,trial,seed`, before
/// `error`) and the records, in file order. A file without the `error` column (written before
/// failed trials were recorded) has none. A row without its line end at the end of the file
/// (a run killed while writing it) is dropped when `allow_torn_end`.
pub fn read_trials(path: &Path, scenario: &ResolvedScenario) -> Result<(Vec<String>, Vec<TrialRecord>), ExportError> {
    read_trials_with(path, scenario, false).map(|(names, records, _)| (names, records))
}

/// [`read_trials`] with each record's 1-based file line (for messages naming a row).
pub fn read_trials_located(path: &Path, scenario: &ResolvedScenario) -> Result<TrialsWithLines, ExportError> {
    read_trials_with(path, scenario, false)
}

/// A trials file's metric names, its records and each record's 1-based file line.
pub type TrialsWithLines = (Vec<String>, Vec<TrialRecord>, Vec<u64>);

/// [`read_trials`] of an interrupted run's file: its unfinished last row is dropped.
pub fn read_partial_trials(
    path: &Path,
    scenario: &ResolvedScenario,
) -> Result<(Vec<String>, Vec<TrialRecord>), ExportError> {
    read_trials_with(path, scenario, true).map(|(names, records, _)| (names, records))
}

fn read_trials_with(
    path: &Path,
    scenario: &ResolvedScenario,
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
    if head.len() < 3 || head[..3] != ["case", "trial", "seed"] {
        return Err(bad(1, "header must start with case,trial,seed".into()));
    }
    let has_error = head.last().is_some_and(|h| h == ERROR_COLUMN);
    let names = head[3..head.len() - usize::from(has_error)].to_vec();
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
        records.push(parse_row(&rec, &head, &names, has_error, scenario).map_err(|e| bad(line, e.to_string()))?);
        lines.push(line);
    }
    Ok((names, records, lines))
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
        .ok_or_else(|| TrialRowError::UnknownCase(name.to_owned()))?;
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
                    text: rec[i].to_owned(),
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
