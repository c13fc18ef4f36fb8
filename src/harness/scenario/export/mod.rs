//! Writing results: one module per format (like hyperfine's `src/export/`), and the results
//! folder that ties them together.
//!
//! `results/<scenario>/` holds `scenario.resolved.toml`, `trials.csv` (one row per trial,
//! appended as trials finish, rewritten sorted at the end), `summary.json`, `summary.md` and
//! `hist-<metric>.svg`. A shard's folder holds the first two plus `shard.txt`.

pub mod csv;
pub mod json;
pub mod markdown;
pub mod plot;

pub use self::csv::PartialTrials;

use super::metrics::TrialRecord;
use super::resolve::ResolvedScenario;
use super::summary::Summary;
use std::path::{Path, PathBuf};

/// Resolved scenario dump.
pub const RESOLVED_FILE: &str = "scenario.resolved.toml";
/// Per-trial rows.
pub const TRIALS_FILE: &str = "trials.csv";
/// Statistics and verdicts.
pub const SUMMARY_JSON: &str = "summary.json";
/// Human summary.
pub const SUMMARY_MD: &str = "summary.md";
/// Which shard a folder holds.
pub const SHARD_FILE: &str = "shard.txt";

/// Writing results failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// A file could not be written or read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The results folder already holds results.
    #[error("{path} already holds results; pass --force to replace them or choose another --out")]
    Exists {
        /// The folder.
        path: PathBuf,
    },
    /// A trials file is malformed.
    #[error("{path}: line {line}: {message}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: u64,
        /// What is wrong.
        message: String,
    },
    /// A plot could not be drawn.
    #[error("{path}: plotting: {message}")]
    Plot {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

pub(crate) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ExportError + '_ {
    move |source| ExportError::Io {
        path: path.to_owned(),
        source,
    }
}

/// Creates `dir` for a new run. A folder that exists and is not empty is refused unless
/// `force` (then the files of a run are replaced; other files stay).
pub fn prepare_dir(dir: &Path, force: bool) -> Result<(), ExportError> {
    if dir.exists() {
        let mut entries = std::fs::read_dir(dir).map_err(io(dir))?;
        if entries.next().is_some() && !force {
            return Err(ExportError::Exists { path: dir.to_owned() });
        }
    }
    std::fs::create_dir_all(dir).map_err(io(dir))
}

/// Writes the resolved scenario dump.
pub fn write_resolved(dir: &Path, text: &str) -> Result<(), ExportError> {
    let path = dir.join(RESOLVED_FILE);
    std::fs::write(&path, text).map_err(io(&path))
}

/// Final outputs of a complete run (single or merged): sorted `trials.csv`, `summary.json`,
/// `summary.md`, the histogram. Returns the summary.
pub fn write_final(
    dir: &Path,
    scenario: &ResolvedScenario,
    names: &[String],
    records: &[TrialRecord],
) -> Result<Summary, ExportError> {
    csv::write_trials_file(&dir.join(TRIALS_FILE), scenario, names, records)?;
    let summary = Summary::of(scenario, names, records);
    let path = dir.join(SUMMARY_JSON);
    std::fs::write(&path, json::render(&summary)).map_err(io(&path))?;
    let path = dir.join(SUMMARY_MD);
    std::fs::write(&path, markdown::render(scenario, &summary)).map_err(io(&path))?;
    if let Some(i) = names.iter().position(|n| n == &scenario.main_metric) {
        plot::histogram_svg(
            &dir.join(format!("hist-{}.svg", names[i])),
            scenario,
            &names[i],
            i,
            records,
        )?;
    }
    Ok(summary)
}
