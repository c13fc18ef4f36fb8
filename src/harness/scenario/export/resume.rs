//! Continuing an interrupted run (`run --resume`): the finished trials of its folder, once
//! they are known to belong to the same resolved scenario, metrics and shard.

use super::csv::read_partial_trials;
use super::{ExportError, RESOLVED_FILE, TRIALS_FILE};
use crate::csv_lines::shown_cell;
use crate::harness::scenario::metrics::TrialRecord;
use crate::harness::scenario::resolve::ResolvedScenario;
use crate::harness::scenario::runner::Shard;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The folder cannot be resumed.
#[derive(Debug, thiserror::Error)]
pub enum ResumeError {
    /// The folder holds no resolved scenario.
    #[error("--resume: nothing to resume in {folder}: {cause}")]
    Nothing {
        /// The results folder.
        folder: PathBuf,
        /// Why its resolved scenario could not be read.
        cause: std::io::Error,
    },
    /// The folder's resolved scenario is not the one resolved now.
    #[error(
        "--resume: {path} differs from the scenario resolved now (another scenario, or other --trials/--seed): {difference}; start over with --force instead"
    )]
    OtherScenario {
        /// The folder's `scenario.resolved.toml`.
        path: PathBuf,
        /// Where the two first differ: the line number and both texts.
        difference: String,
    },
    /// The trials file cannot be read.
    #[error(transparent)]
    Trials(#[from] ExportError),
    /// The trials file holds a trial of another shard.
    #[error("--resume: {path} holds trial {trial} of case {case}, outside shard {shard} (units {start}..{end})")]
    OutsideShard {
        /// The trials file.
        path: PathBuf,
        /// The trial's number in its case.
        trial: usize,
        /// The case's name.
        case: String,
        /// The shard resumed.
        shard: Shard,
        /// Its first unit.
        start: usize,
        /// One past its last unit.
        end: usize,
    },
}

/// The finished trials of the interrupted run in `folder` (one per unit, sorted by unit),
/// after checking that the folder's resolved scenario is `resolved_text`, its metric columns
/// are `names` and its trials belong to `shard`. A folder without a trials file has none.
pub fn previous_trials(
    folder: &Path,
    scenario: &ResolvedScenario,
    resolved_text: &str,
    names: &[String],
    shard: Shard,
) -> Result<Vec<TrialRecord>, ResumeError> {
    let resolved = folder.join(RESOLVED_FILE);
    let text = std::fs::read_to_string(&resolved).map_err(|cause| ResumeError::Nothing {
        folder: folder.to_owned(),
        cause,
    })?;
    if text != resolved_text {
        return Err(ResumeError::OtherScenario {
            path: resolved,
            difference: first_difference(&text, resolved_text),
        });
    }
    let trials = folder.join(TRIALS_FILE);
    if !trials.exists() {
        return Ok(Vec::new());
    }
    let records = read_partial_trials(&trials, scenario, names)?;
    let units = shard.units(scenario.units());
    let n = scenario.trials;
    if let Some(r) = records.iter().find(|r| !units.contains(&r.unit(n))) {
        return Err(ResumeError::OutsideShard {
            path: trials,
            trial: r.trial,
            case: scenario.cases[r.case].name.clone(),
            shard,
            start: units.start,
            end: units.end,
        });
    }
    let mut seen = BTreeMap::new();
    for r in records {
        seen.entry(r.unit(n)).or_insert(r);
    }
    Ok(seen.into_values().collect())
}

/// Where the resolved scenario `then` (the folder's) first differs from `now`, in words: its
/// line number, the table it is in and both lines (long lines cut short).
fn first_difference(then: &str, now: &str) -> String {
    let shown = |line: Option<&str>| line.map_or("the end of the file".to_owned(), |l| format!("`{}`", shown_cell(l)));
    let (mut a, mut b) = (then.lines(), now.lines());
    let mut table = None;
    for number in 1.. {
        let (x, y) = (a.next(), b.next());
        if x == y {
            match x {
                None => break,
                Some(l) if l.starts_with('[') => table = Some(l),
                Some(_) => {}
            }
            continue;
        }
        let within = table.map_or(String::new(), |t| format!(" (in {t})"));
        return format!("line {number}{within} reads {} there, {} now", shown(x), shown(y));
    }
    "their line endings differ".to_owned()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::harness::scenario::export::PartialTrials;
    use crate::harness::scenario::resolve::Overrides;

    fn smoke() -> ResolvedScenario {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/ci-smoke.toml");
        let overrides = Overrides {
            trials: Some(4),
            seed: None,
        };
        ResolvedScenario::from_file(&path, overrides).unwrap()
    }

    /// A folder of a run of `scenario` interrupted after `units` (successful records, value 1).
    fn interrupted(scenario: &ResolvedScenario, names: &[String], units: &[usize]) -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(RESOLVED_FILE), "resolved").unwrap();
        let trials = PartialTrials::create(&dir.path().join(TRIALS_FILE), names).unwrap();
        for &u in units {
            let record = TrialRecord {
                case: u / scenario.trials,
                trial: u % scenario.trials,
                seed: u as u64,
                values: vec![1.0; names.len()],
                error: None,
            };
            trials.append(scenario, &record).unwrap();
        }
        dir
    }

    #[test]
    fn a_folder_of_the_same_run_gives_its_trials_once_each_by_unit() {
        let scenario = smoke();
        let names = vec!["a_mm".to_owned(), "b_mm".to_owned()];
        let dir = interrupted(&scenario, &names, &[2, 0, 2]);
        let records = previous_trials(dir.path(), &scenario, "resolved", &names, Shard::ALL).unwrap();
        let units: Vec<usize> = records.iter().map(|r| r.unit(scenario.trials)).collect();
        assert_eq!(units, [0, 2]);
    }

    #[test]
    fn the_first_difference_is_named_by_line_table_and_both_texts() {
        let then = "trials = 4\n\n[measurement]\nnet_radial_rms_mm = 0.19\n";
        let now = "trials = 4\n\n[measurement]\nnet_radial_rms_mm = 0.3\n";
        assert_eq!(
            first_difference(then, now),
            "line 4 (in [measurement]) reads `net_radial_rms_mm = 0.19` there, `net_radial_rms_mm = 0.3` now"
        );
        assert_eq!(
            first_difference("trials = 4\n", "trials = 4\nseed = 2\n"),
            "line 2 reads the end of the file there, `seed = 2` now"
        );
        assert_eq!(first_difference("a = 1\n", "a = 1\r\n"), "their line endings differ");
        let long = format!("half_range = [{}]", vec!["40.0"; 40].join(", "));
        assert!(first_difference("x = 1\n", &long).contains("characters]"));
    }

    #[test]
    fn another_scenario_metrics_or_shard_is_refused() {
        let scenario = smoke();
        let names = vec!["a_mm".to_owned()];
        let dir = interrupted(&scenario, &names, &[0, 3]);
        let empty = tempfile::tempdir().unwrap();
        let nothing = previous_trials(empty.path(), &scenario, "resolved", &names, Shard::ALL);
        assert!(matches!(nothing, Err(ResumeError::Nothing { .. })));
        let other = previous_trials(dir.path(), &scenario, "another", &names, Shard::ALL);
        assert!(matches!(other, Err(ResumeError::OtherScenario { .. })));
        let metrics = previous_trials(dir.path(), &scenario, "resolved", &["b_mm".to_owned()], Shard::ALL);
        let Err(ResumeError::Trials(ExportError::Malformed { line: 1, message, .. })) = metrics else {
            panic!("{metrics:?}")
        };
        assert!(
            message.starts_with("column 4 is `a_mm` where this scenario's trials file has `b_mm`"),
            "{message}"
        );
        let first_half = Shard { index: 1, count: 2 };
        let shard = previous_trials(dir.path(), &scenario, "resolved", &names, first_half);
        assert!(
            matches!(shard, Err(ResumeError::OutsideShard { trial: 3, .. })),
            "{shard:?}"
        );
    }
}
