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
pub mod resume;

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
/// Held (an OS file lock) while a run or merge writes into the folder.
pub const LOCK_FILE: &str = ".axiscal.lock";
/// Every file a run or merge writes, besides `hist-<metric>.svg` (see [`run_outputs_in`]).
pub const RUN_FILES: [&str; 5] = [RESOLVED_FILE, TRIALS_FILE, SUMMARY_JSON, SUMMARY_MD, SHARD_FILE];

/// Writing results failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// A file could not be written or read.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        cause: std::io::Error,
    },
    /// The results folder already holds results.
    #[error("{path} {state}; pass --force to replace them (or choose another --out)")]
    Exists {
        /// The folder.
        path: PathBuf,
        /// What it holds, in words (a complete run, a partial one and how to continue it).
        state: String,
    },
    /// Another run writes into the folder.
    #[error(
        "{path}: another axiscal run or merge is writing into this folder ({holder}); wait for it or choose another --out"
    )]
    Locked {
        /// The folder.
        path: PathBuf,
        /// What the lock file says about its holder.
        holder: String,
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
    #[error("{path}: plotting: {cause}")]
    Plot {
        /// The file.
        path: PathBuf,
        /// What plotters said.
        cause: crate::plotting::DrawError,
    },
}

pub(crate) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ExportError + '_ {
    move |source| ExportError::Io {
        path: path.to_owned(),
        cause: source,
    }
}

/// What `dir`'s results are, in words, for a refusal to replace them.
pub fn describe_results(dir: &Path) -> String {
    let trials = dir.join(TRIALS_FILE);
    let rows = std::fs::read(&trials)
        .map(|b| b.iter().filter(|&&c| c == b'\n').count().saturating_sub(1))
        .ok();
    let summary = std::fs::read_to_string(dir.join(SUMMARY_JSON)).ok();
    let partial = summary.as_deref().is_some_and(|s| s.contains("\"partial\": true"));
    match (rows, summary) {
        (Some(n), None) if !dir.join(SHARD_FILE).exists() => format!(
            "holds a PARTIAL run ({n} trial(s) in {TRIALS_FILE}, no summary: interrupted or failed); continue it with \
             `axiscal run SCENARIO --out {} --resume`",
            dir.display()
        ),
        (Some(n), Some(_)) if partial => format!(
            "holds a PARTIAL run ({n} trial(s) finished, summary marked partial); continue it with `axiscal run \
             SCENARIO --out {} --resume`",
            dir.display()
        ),
        (Some(n), _) => format!("holds the results of a run ({n} trial(s))"),
        (None, _) => "is not empty".into(),
    }
}

/// Refuses to write a new run into `dir` when it holds anything but the lock file, unless
/// `force` ([`ExportError::Exists`], saying what it holds).
pub fn check_replace(dir: &Path, force: bool) -> Result<(), ExportError> {
    if !force && dir.exists() && existing_entries(dir)?.iter().any(|n| n != LOCK_FILE) {
        return Err(ExportError::Exists {
            path: dir.to_owned(),
            state: describe_results(dir),
        });
    }
    Ok(())
}

/// The names of the files in `dir`.
fn existing_entries(dir: &Path) -> Result<Vec<String>, ExportError> {
    Ok(std::fs::read_dir(dir)
        .map_err(io(dir))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect())
}

/// The files of an earlier run or merge in `dir` ([`RUN_FILES`]; none when `dir` is
/// missing): a `hist-<metric>.svg` only where `<metric>` is a column of the folder's
/// `trials.csv` (a run draws the histogram of one of its metrics; another such file is the
/// user's).
pub fn run_outputs_in(dir: &Path) -> Vec<String> {
    let metrics = trial_columns(&dir.join(TRIALS_FILE));
    let drawn = |n: &str| {
        n.strip_prefix("hist-")
            .and_then(|n| n.strip_suffix(".svg"))
            .is_some_and(|m| metrics.iter().any(|c| c == m))
    };
    existing_entries(dir)
        .unwrap_or_default()
        .into_iter()
        .filter(|n| RUN_FILES.contains(&n.as_str()) || drawn(n))
        .collect()
}

/// The column names of the header of the trials file `path` (its first line not a `#`
/// comment; the first 64 KiB read); none when it cannot be read.
fn trial_columns(path: &Path) -> Vec<String> {
    use std::io::{BufRead, Read};
    let Ok(file) = std::fs::File::open(path) else {
        return Vec::new();
    };
    std::io::BufReader::new(file.take(1 << 16))
        .lines()
        .map_while(Result::ok)
        .find(|l| !l.starts_with('#'))
        .map(|header| header.split(',').map(|c| c.trim().to_owned()).collect())
        .unwrap_or_default()
}

/// Creates `dir` for a new run. A folder holding anything but the lock file is refused unless
/// `force` ([`check_replace`]); with `force` the files of an earlier run ([`run_outputs_in`]) are
/// deleted first (other files stay), so no old summary sits beside new trials.
pub fn prepare_dir(dir: &Path, force: bool) -> Result<(), ExportError> {
    check_replace(dir, force)?;
    for name in run_outputs_in(dir) {
        let path = dir.join(name);
        std::fs::remove_file(&path).map_err(io(&path))?;
    }
    std::fs::create_dir_all(dir).map_err(io(dir))
}

/// The lock a run or merge holds on its results folder (released when dropped, or by the
/// system when the process dies).
#[derive(Debug)]
pub struct RunLock {
    _file: std::fs::File,
}

impl RunLock {
    /// Creates `dir` and takes its lock, writing this process's id and host into the lock
    /// file; fails with [`ExportError::Locked`] when another process holds it.
    pub fn acquire(dir: &Path) -> Result<Self, ExportError> {
        use std::io::{Seek, Write};
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let path = dir.join(LOCK_FILE);
        let mut options = std::fs::OpenOptions::new();
        options.read(true).write(true).create(true).truncate(false);
        // Never through a link: the lock file is written, and a link would have it written
        // over whatever it points at (a scenario file).
        #[cfg(unix)]
        std::os::unix::fs::OpenOptionsExt::custom_flags(&mut options, libc::O_NOFOLLOW);
        if path.symlink_metadata().is_ok_and(|m| !m.is_file()) {
            return Err(ExportError::Io {
                path: path.clone(),
                cause: std::io::Error::other(
                    "the lock file is a link or not a regular file; remove it (axiscal creates its own)",
                ),
            });
        }
        let mut file = options.open(&path).map_err(io(&path))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                return Err(ExportError::Locked {
                    path: dir.to_owned(),
                    holder: lock_holder(&mut file),
                });
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(io(&path)(e)),
        }
        let host = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap_or_default();
        let me = format!("pid {} on {}", std::process::id(), host.trim());
        file.set_len(0)
            .and_then(|()| file.rewind())
            .and_then(|()| file.write_all(me.as_bytes()))
            .map_err(io(&path))?;
        Ok(RunLock { _file: file })
    }
}

/// Reads at most this many times a lock file its holder has not written yet.
const HOLDER_READS: usize = 10;

/// Who holds a run's lock, as its lock file says (`pid N on HOST`). The holder writes it just
/// after taking the lock, so a file read empty is read again a few times, 20 ms apart; still
/// empty, the words say so rather than show nothing.
fn lock_holder(file: &mut std::fs::File) -> String {
    use std::io::{Read, Seek};
    for _ in 0..HOLDER_READS {
        let mut holder = String::new();
        let read = file.rewind().and_then(|()| file.read_to_string(&mut holder));
        if read.is_ok() && !holder.trim().is_empty() {
            return holder.trim().chars().take(200).collect();
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    "a process that took the lock this instant and has not written its id yet".to_owned()
}

/// Writes the resolved scenario dump.
pub fn write_resolved(dir: &Path, text: &str) -> Result<(), ExportError> {
    let path = dir.join(RESOLVED_FILE);
    std::fs::write(&path, text).map_err(io(&path))
}

/// Files to write, each name with its bytes.
pub type NamedFiles = Vec<(&'static str, Vec<u8>)>;

/// The final text files of a complete run (single or merged), each name with its bytes: sorted
/// `trials.csv`, `summary.json`, `summary.md`; and the summary. `dir` names the folder in messages.
pub fn render_final(
    dir: &Path,
    scenario: &ResolvedScenario,
    names: &[String],
    records: &[TrialRecord],
) -> Result<(NamedFiles, Summary), ExportError> {
    let mut trials = Vec::new();
    csv::write_trials(&mut trials, scenario, names, records).map_err(|e| csv::csv_error(&dir.join(TRIALS_FILE), e))?;
    let summary = Summary::of(scenario, names, records);
    let files = vec![
        (TRIALS_FILE, trials),
        (SUMMARY_JSON, json::render(&summary).into_bytes()),
        (SUMMARY_MD, markdown::render(scenario, &summary).into_bytes()),
    ];
    Ok((files, summary))
}

/// The histogram's file name (`hist-<main metric>.svg`), when the run has the main metric.
pub fn histogram_name(scenario: &ResolvedScenario, names: &[String]) -> Option<String> {
    names
        .iter()
        .find(|n| **n == scenario.main_metric)
        .map(|n| format!("hist-{n}.svg"))
}

/// Draws the histogram of the main metric into `dir` (nothing when the run has no main
/// metric); the files drawn.
pub fn draw_histogram(
    dir: &Path,
    scenario: &ResolvedScenario,
    names: &[String],
    records: &[TrialRecord],
) -> Result<Vec<PathBuf>, ExportError> {
    let Some(i) = names.iter().position(|n| n == &scenario.main_metric) else {
        return Ok(Vec::new());
    };
    let path = dir.join(format!("hist-{}.svg", names[i]));
    plot::histogram_svg(&path, scenario, &names[i], i, records)?;
    Ok(vec![path])
}

/// Final outputs of a complete run (single or merged), written into `dir` one by one: the
/// files of [`render_final`] and the histogram. Returns the summary.
pub fn write_final(
    dir: &Path,
    scenario: &ResolvedScenario,
    names: &[String],
    records: &[TrialRecord],
) -> Result<Summary, ExportError> {
    let (files, summary) = render_final(dir, scenario, names, records)?;
    for (name, bytes) in files {
        let path = dir.join(name);
        std::fs::write(&path, bytes).map_err(io(&path))?;
    }
    draw_histogram(dir, scenario, names, records)?;
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A second run into a folder another holds is refused naming the holder's process; a
    /// holder that has not yet written its id is said to be one, never shown as nothing.
    #[test]
    fn a_locked_folder_names_its_holder() {
        let dir = tempfile::tempdir().unwrap();
        let first = RunLock::acquire(dir.path()).unwrap();
        let holder = |e: Result<RunLock, ExportError>| match e {
            Err(ExportError::Locked { holder, .. }) => holder,
            other => panic!("{other:?}"),
        };
        let named = holder(RunLock::acquire(dir.path()));
        assert!(named.starts_with(&format!("pid {} on ", std::process::id())), "{named}");
        drop(first);
        let other = tempfile::tempdir().unwrap();
        let path = other.path().join(LOCK_FILE);
        let silent = std::fs::File::create(&path).unwrap();
        silent.try_lock().unwrap();
        let named = holder(RunLock::acquire(other.path()));
        assert!(named.contains("has not written its id yet"), "{named}");
    }
}
