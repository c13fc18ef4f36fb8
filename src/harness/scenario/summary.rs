//! Per-case statistics of every metric and the threshold verdicts (pure, no I/O).

use super::metrics::TrialRecord;
use super::resolve::ResolvedScenario;
use super::stats::Stat;
use super::stats::Stats;
use super::threshold::{Op, Threshold, Verdict};
use serde::{Deserialize, Serialize};

/// Statistics of one metric in one case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct MetricSummary {
    /// Metric name.
    pub metric: String,
    /// Its statistics.
    #[serde(flatten)]
    pub stats: Stats,
}

/// The pseudo-metric of the failure-rate verdict: the fraction of a case's finished trials
/// that failed (scenario key `max_failure_rate`).
pub const FAILURE_RATE: &str = "failure_rate";

/// Statistics of one case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CaseSummary {
    /// Case name.
    pub case: String,
    /// Trials finished (succeeded or failed).
    pub trials: usize,
    /// Trials that failed (their errors are in `trials.csv`); the statistics are over the others.
    #[serde(default)]
    pub failed: usize,
    /// `failed / trials` (0 without trials).
    #[serde(default)]
    pub failure_rate: f64,
    /// The first failed trial's (lowest trial index) error and how many failed trials share
    /// it; absent when none failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub first_error: Option<FirstError>,
    /// One entry per metric, in column order.
    pub metrics: Vec<MetricSummary>,
}

/// A case's first failed trial and how many failed alike.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct FirstError {
    /// The trial (0-based).
    pub trial: usize,
    /// Its error.
    pub error: String,
    /// Failed trials with this very error (it included).
    pub same: usize,
}

/// What `summary.json` holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// Scenario seed.
    pub seed: u64,
    /// Trials per case.
    pub trials_per_case: usize,
    /// The run was interrupted: the statistics and verdicts are over the trials that finished,
    /// and `all_hold` is false.
    #[serde(default)]
    pub partial: bool,
    /// Per case.
    pub cases: Vec<CaseSummary>,
    /// One verdict per (threshold, case it applies to).
    pub verdicts: Vec<Verdict>,
    /// Whether the run is complete and every threshold holds.
    pub all_hold: bool,
}

impl Summary {
    /// Summarises `records` (any order) of `scenario` whose values follow `metric_names`;
    /// fewer records than the scenario's units make a partial summary.
    pub fn of(scenario: &ResolvedScenario, metric_names: &[String], records: &[TrialRecord]) -> Self {
        let cases: Vec<CaseSummary> = (0..scenario.cases.len())
            .map(|c| case_summary(scenario, c, metric_names, records))
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
        let failure = Threshold {
            metric: FAILURE_RATE.into(),
            stat: Stat::Mean,
            op: Op::AtMost,
            value: scenario.max_failure_rate,
            case: None,
        };
        for c in &cases {
            let mut v = failure.judge(&c.case, &Stats::of(&[c.failure_rate]));
            // Zero trials finished in a case: nothing failed, but nothing passed either.
            v.holds &= c.trials > 0;
            verdicts.push(v);
        }
        let partial = records.len() < scenario.units();
        Summary {
            scenario: scenario.name.clone(),
            seed: scenario.seed,
            trials_per_case: scenario.trials,
            partial,
            all_hold: !partial && verdicts.iter().all(|v| v.holds),
            cases,
            verdicts,
        }
    }

    /// The verdicts that failed.
    pub fn failures(&self) -> Vec<&Verdict> {
        self.verdicts.iter().filter(|v| !v.holds).collect()
    }
}

/// The summary of case `c`: finished and failed trials, statistics over the succeeded ones.
fn case_summary(
    scenario: &ResolvedScenario,
    c: usize,
    metric_names: &[String],
    records: &[TrialRecord],
) -> CaseSummary {
    let finished: Vec<&TrialRecord> = records.iter().filter(|r| r.case == c).collect();
    let ok: Vec<&TrialRecord> = finished.iter().copied().filter(|r| r.succeeded()).collect();
    let failed = finished.len() - ok.len();
    let first_error = finished
        .iter()
        .filter_map(|r| Some((r.trial, r.error.as_ref()?)))
        .min_by_key(|(trial, _)| *trial)
        .map(|(trial, error)| FirstError {
            trial,
            error: error.clone(),
            same: finished.iter().filter(|r| r.error.as_ref() == Some(error)).count(),
        });
    CaseSummary {
        case: scenario.cases[c].name.clone(),
        trials: finished.len(),
        failed,
        failure_rate: if finished.is_empty() {
            0.0
        } else {
            failed as f64 / finished.len() as f64
        },
        first_error,
        metrics: metric_names
            .iter()
            .enumerate()
            .map(|(i, name)| MetricSummary {
                metric: name.clone(),
                stats: Stats::of(&ok.iter().map(|r| r.values[i]).collect::<Vec<_>>()),
            })
            .collect(),
    }
}
