//! Which statistic of a metric over the trials of one case a threshold reads (pure, no I/O);
//! the statistics themselves are [`crate::numerics::stats::Stats`].

use serde::{Deserialize, Serialize};

/// Which statistic of a metric a threshold looks at.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Stat {
    /// Arithmetic mean.
    Mean,
    /// 50 % quantile.
    Median,
    /// 95 % quantile.
    P95,
    /// Largest value.
    Max,
}

impl Stat {
    /// The name used in files (`mean`, `median`, `p95`, `max`).
    pub fn name(self) -> &'static str {
        match self {
            Stat::Mean => "mean",
            Stat::Median => "median",
            Stat::P95 => "p95",
            Stat::Max => "max",
        }
    }
}

pub use crate::numerics::stats::Stats;

/// The value of statistic `stat` of `stats`.
pub fn stat_of(stats: &Stats, stat: Stat) -> f64 {
    match stat {
        Stat::Mean => stats.mean,
        Stat::Median => stats.median,
        Stat::P95 => stats.p95,
        Stat::Max => stats.max,
    }
}
