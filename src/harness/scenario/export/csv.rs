//! `trials.csv`: `case,trial,seed,<metric...>`, one row per trial. Numbers are written with
//! [`format_f64`] (shortest round-trip text), so reading a file back gives the same bits and
//! merged shards summarise exactly like a single run.

use super::{ExportError, io};
use crate::harness::scenario::metrics::TrialRecord;
use crate::harness::scenario::resolve::ResolvedScenario;
use crate::measurement::format_f64;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

fn header(names: &[String]) -> Vec<String> {
    ["case", "trial", "seed"]
        .iter()
        .map(|s| (*s).to_owned())
        .chain(names.iter().cloned())
        .collect()
}

fn row(scenario: &ResolvedScenario, r: &TrialRecord) -> Vec<String> {
    [
        scenario.cases[r.case].name.clone(),
        r.trial.to_string(),
        r.seed.to_string(),
    ]
    .into_iter()
    .chain(r.values.iter().map(|v| format_f64(*v)))
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
        w.write_record(row(scenario, r))?;
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

fn csv_error(path: &Path, e: csv::Error) -> ExportError {
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
            writer: Mutex::new(writer),
        })
    }

    /// Appends one finished trial.
    pub fn append(&self, scenario: &ResolvedScenario, r: &TrialRecord) -> Result<(), ExportError> {
        let mut w = self.writer.lock().unwrap_or_else(|p| p.into_inner());
        w.write_record(row(scenario, r)).map_err(|e| csv_error(&self.path, e))?;
        w.flush().map_err(io(&self.path))
    }
}

/// Reads a trials file of `scenario`: the metric names (header after `case,trial,seed`) and
/// the records, in file order.
pub fn read_trials(path: &Path, scenario: &ResolvedScenario) -> Result<(Vec<String>, Vec<TrialRecord>), ExportError> {
    let mut reader = csv::Reader::from_path(path).map_err(|e| csv_error(path, e))?;
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
    let names = head[3..].to_vec();
    let mut records = Vec::new();
    for rec in reader.records() {
        let rec = rec.map_err(|e| csv_error(path, e))?;
        let line = rec.position().map_or(0, |p| p.line());
        let name = &rec[0];
        let case = scenario
            .cases
            .iter()
            .position(|c| c.name == name)
            .ok_or_else(|| bad(line, format!("column `case`: unknown case {name:?}")))?;
        let trial: usize = rec[1].parse().map_err(|e| bad(line, format!("column `trial`: {e}")))?;
        if trial >= scenario.trials {
            return Err(bad(
                line,
                format!("column `trial`: {trial} >= trials {}", scenario.trials),
            ));
        }
        let seed: u64 = rec[2].parse().map_err(|e| bad(line, format!("column `seed`: {e}")))?;
        let values = (3..head.len())
            .map(|i| {
                rec[i]
                    .parse::<f64>()
                    .map_err(|e| bad(line, format!("column `{}`: {e}", head[i])))
            })
            .collect::<Result<Vec<_>, _>>()?;
        records.push(TrialRecord {
            case,
            trial,
            seed,
            values,
        });
    }
    Ok((names, records))
}
