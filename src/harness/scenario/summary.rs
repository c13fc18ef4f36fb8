//! Per-case statistics of every metric and the threshold verdicts (pure, no I/O).

use super::metrics::TrialRecord;
use super::resolve::ResolvedScenario;
use super::stats::Stats;
use super::threshold::Verdict;
use serde::{Deserialize, Serialize};

/// Statistics of one metric in one case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MetricSummary {
    /// Metric name.
    pub metric: String,
    /// Its statistics.
    #[serde(flatten)]
    pub stats: Stats,
}

/// Statistics of one case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CaseSummary {
    /// Case name.
    pub case: String,
    /// Trials summarised.
    pub trials: usize,
    /// One entry per metric, in column order.
    pub metrics: Vec<MetricSummary>,
}

/// What `summary.json` holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// Scenario seed.
    pub seed: u64,
    /// Trials per case.
    pub trials_per_case: usize,
    /// Per case.
    pub cases: Vec<CaseSummary>,
    /// One verdict per (threshold, case it applies to).
    pub verdicts: Vec<Verdict>,
    /// Whether every threshold holds.
    pub all_hold: bool,
}

impl Summary {
    /// Summarises `records` (any order) of `scenario` whose values follow `metric_names`.
    pub fn of(scenario: &ResolvedScenario, metric_names: &[String], records: &[TrialRecord]) -> Self {
        let cases: Vec<CaseSummary> = scenario
            .cases
            .iter()
            .enumerate()
            .map(|(c, case)| {
                let rows: Vec<&TrialRecord> = records.iter().filter(|r| r.case == c).collect();
                CaseSummary {
                    case: case.name.clone(),
                    trials: rows.len(),
                    metrics: metric_names
                        .iter()
                        .enumerate()
                        .map(|(i, name)| MetricSummary {
                            metric: name.clone(),
                            stats: Stats::of(&rows.iter().map(|r| r.values[i]).collect::<Vec<_>>()),
                        })
                        .collect(),
                }
            })
            .collect();
        let mut verdicts = Vec::new();
        for t in &scenario.thresholds {
            for c in &cases {
                if t.case.as_ref().is_some_and(|name| name != &c.case) {
                    continue;
                }
                let stats = c
                    .metrics
                    .iter()
                    .find(|m| m.metric == t.metric)
                    .map_or_else(|| Stats::of(&[]), |m| m.stats);
                verdicts.push(t.judge(&c.case, &stats));
            }
        }
        Summary {
            scenario: scenario.name.clone(),
            seed: scenario.seed,
            trials_per_case: scenario.trials,
            all_hold: verdicts.iter().all(|v| v.holds),
            cases,
            verdicts,
        }
    }

    /// The verdicts that failed.
    pub fn failures(&self) -> Vec<&Verdict> {
        self.verdicts.iter().filter(|v| !v.holds).collect()
    }
}
