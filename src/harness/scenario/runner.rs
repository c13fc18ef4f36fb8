//! Running trial units in parallel (rayon) and sharding them; pure apart from the observer.

use super::metrics::TrialRecord;
use super::resolve::ResolvedScenario;
use super::trial::{Trial, run_unit};
use rayon::prelude::*;
use std::ops::Range;
use std::str::FromStr;
use std::sync::atomic::{AtomicBool, Ordering};

/// The `K`-th of `N` disjoint, contiguous ranges of trial units (`--shard K/N`, 1-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// K, in `1..=count`.
    pub index: usize,
    /// N >= 1.
    pub count: usize,
}

impl Shard {
    /// The whole run as one shard.
    pub const ALL: Shard = Shard { index: 1, count: 1 };

    /// Units `[floor(total (K-1) / N), floor(total K / N))`: the N ranges tile `0..total`.
    pub fn units(&self, total: usize) -> Range<usize> {
        let at = |k: usize| (total as u128 * k as u128 / self.count as u128) as usize;
        at(self.index - 1)..at(self.index)
    }
}

/// Why a `--shard K/N` text is not a shard.
#[derive(Debug, PartialEq, thiserror::Error)]
pub enum ShardError {
    /// No `/`.
    #[error("shard {0:?} is not K/N")]
    NotKOverN(String),
    /// K or N is not a whole number.
    #[error("shard {text:?}: {error}")]
    NotWhole {
        /// The whole text.
        text: String,
        /// Why the part did not parse.
        error: std::num::ParseIntError,
    },
    /// K is 0 or above N.
    #[error("shard {0:?}: need 1 <= K <= N")]
    OutOfRange(String),
}

impl FromStr for Shard {
    type Err = ShardError;

    fn from_str(s: &str) -> Result<Self, ShardError> {
        let (k, n) = s.split_once('/').ok_or_else(|| ShardError::NotKOverN(s.to_owned()))?;
        let parse = |x: &str| {
            x.trim().parse::<usize>().map_err(|error| ShardError::NotWhole {
                text: s.to_owned(),
                error,
            })
        };
        let (index, count) = (parse(k)?, parse(n)?);
        if count == 0 || index == 0 || index > count {
            return Err(ShardError::OutOfRange(s.to_owned()));
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// Runs `units` of `scenario` in parallel on the current rayon pool, calling `on_done` (from
/// worker threads, in completion order) as each finishes. Returns the records sorted by
/// unit; a trial that fails is a record with its error ([`TrialRecord::error`]), the run goes
/// on. Every trial's seed depends only on its index, so the result is bit-identical for any
/// thread count.
pub fn run_units<T: Trial + ?Sized>(
    scenario: &ResolvedScenario,
    trial: &T,
    units: Range<usize>,
    on_done: &(dyn Fn(&TrialRecord) + Sync),
) -> Vec<TrialRecord> {
    run_units_until(scenario, trial, units.collect(), on_done, &AtomicBool::new(false))
}

/// [`run_units`] of any `units` (e.g. the ones an interrupted run left) that starts no
/// further unit once `stop` is set (the units in flight finish
/// and are returned; an interrupted run keeps them).
pub fn run_units_until<T: Trial + ?Sized>(
    scenario: &ResolvedScenario,
    trial: &T,
    units: Vec<usize>,
    on_done: &(dyn Fn(&TrialRecord) + Sync),
    stop: &AtomicBool,
) -> Vec<TrialRecord> {
    let names = trial.metric_names();
    units
        .into_par_iter()
        .filter_map(|u| {
            if stop.load(Ordering::Relaxed) {
                return None;
            }
            let r = run_unit(scenario, trial, &names, u);
            on_done(&r);
            Some(r)
        })
        .collect()
}

/// Why shard records do not make one complete run.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum CoverageError {
    /// A unit appears twice (overlapping shards).
    #[error("trial {trial} of case {case} appears more than once")]
    Duplicate {
        /// Case name.
        case: String,
        /// Trial.
        trial: usize,
    },
    /// Units are missing (a shard not run or not finished).
    #[error("{missing} of {total} trials are missing (first: trial {first_trial} of case {first_case})")]
    Missing {
        /// Count.
        missing: usize,
        /// Expected.
        total: usize,
        /// Case of the first missing unit.
        first_case: String,
        /// Its trial.
        first_trial: usize,
    },
}

/// Sorts records by unit and checks each unit of `scenario` appears exactly once.
pub fn complete_run(
    scenario: &ResolvedScenario,
    mut records: Vec<TrialRecord>,
) -> Result<Vec<TrialRecord>, CoverageError> {
    let n = scenario.trials;
    records.sort_by_key(|r| r.unit(n));
    for w in records.windows(2) {
        if w[0].unit(n) == w[1].unit(n) {
            return Err(CoverageError::Duplicate {
                case: scenario.cases[w[0].case].name.clone(),
                trial: w[0].trial,
            });
        }
    }
    let total = scenario.units();
    if records.len() != total {
        let first = (0..total)
            .find(|u| records.get(*u).is_none_or(|r| r.unit(n) != *u))
            .unwrap_or(0);
        return Err(CoverageError::Missing {
            missing: total - records.len(),
            total,
            first_case: scenario.cases[first / n].name.clone(),
            first_trial: first % n,
        });
    }
    Ok(records)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_tile_the_units() {
        for total in [0, 1, 5, 12, 13] {
            for n in 1..6 {
                let mut next = 0;
                for k in 1..=n {
                    let r = Shard { index: k, count: n }.units(total);
                    assert_eq!(r.start, next);
                    next = r.end;
                }
                assert_eq!(next, total);
            }
        }
    }

    #[test]
    fn parses_k_of_n() {
        assert_eq!("2/4".parse::<Shard>(), Ok(Shard { index: 2, count: 4 }));
        assert!("0/4".parse::<Shard>().is_err());
        assert!("5/4".parse::<Shard>().is_err());
        assert!("x".parse::<Shard>().is_err());
    }
}
