//! Pass/fail thresholds on statistics of metrics (pure, no I/O).

use super::stats::{Stat, Stats, stat_of};
use crate::measurement::format_f64;
use serde::{Deserialize, Serialize};

/// The comparison of a threshold.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
pub enum Op {
    /// The statistic must be at most the value.
    #[serde(rename = "<=")]
    AtMost,
    /// The statistic must be at least the value.
    #[serde(rename = ">=")]
    AtLeast,
}

impl Op {
    /// `<=` or `>=`.
    pub fn symbol(self) -> &'static str {
        match self {
            Op::AtMost => "<=",
            Op::AtLeast => ">=",
        }
    }
}

/// `stat(metric) op value`, e.g. `p95(uncal_pos_rms_mm) <= 5`, in every case of the scenario
/// or only in `case`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Threshold {
    /// Metric name (a column of `trials.csv`; its unit is in its name).
    pub metric: String,
    /// Which statistic over the trials.
    pub stat: Stat,
    /// `"<="` or `">="`.
    pub op: Op,
    /// The bound, in the metric's unit.
    pub value: f64,
    /// Restrict to one case (by name); default: every case.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub case: Option<String>,
}

impl Threshold {
    /// `p95(metric) <= value`.
    pub fn describe(&self) -> String {
        if self.metric == super::summary::FAILURE_RATE {
            return format!("{} {} {}", self.metric, self.op.symbol(), format_f64(self.value));
        }
        format!(
            "{}({}) {} {}",
            self.stat.name(),
            self.metric,
            self.op.symbol(),
            format_f64(self.value)
        )
    }

    /// Judges the statistics of this threshold's metric in one case.
    pub fn judge(&self, case: &str, stats: &Stats) -> Verdict {
        let observed = stat_of(stats, self.stat);
        let excess = match self.op {
            Op::AtMost => observed - self.value,
            Op::AtLeast => self.value - observed,
        };
        // NaN fails: `excess <= 0` is false for NaN.
        Verdict {
            threshold: self.clone(),
            case: case.to_owned(),
            observed,
            holds: excess <= 0.0,
            excess,
        }
    }
}

/// The outcome of one threshold in one case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Verdict {
    /// The threshold.
    pub threshold: Threshold,
    /// The case judged.
    pub case: String,
    /// The observed statistic.
    pub observed: f64,
    /// Whether the threshold holds.
    pub holds: bool,
    /// By how much the bound is exceeded, in the metric's unit (positive: failed by that
    /// much; negative: the margin left).
    pub excess: f64,
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let word = if self.holds { "ok  " } else { "FAIL" };
        let (case, threshold) = (&self.case, self.threshold.describe());
        if self.observed.is_nan() {
            return write!(
                f,
                "{word} [{case}] {threshold}: no value (no trial of the case succeeded)"
            );
        }
        write!(f, "{word} [{case}] {threshold}: observed {:.6}", self.observed)?;
        if !self.holds {
            write!(f, " (exceeds the bound by {:.6})", self.excess)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn t(op: Op, value: f64) -> Threshold {
        Threshold {
            metric: "e_mm".into(),
            stat: Stat::Max,
            op,
            value,
            case: None,
        }
    }

    #[test]
    fn verdicts_and_excess() {
        let s = Stats::of(&[1.0, 2.0, 3.0]);
        let v = t(Op::AtMost, 2.5).judge("base", &s);
        assert!(!v.holds);
        assert_relative_eq!(v.excess, 0.5);
        assert!(v.to_string().contains("FAIL") && v.to_string().contains("0.5"));
        assert!(t(Op::AtMost, 3.0).judge("base", &s).holds);
        assert!(t(Op::AtLeast, 3.0).judge("base", &s).holds);
        let v = t(Op::AtLeast, 4.0).judge("base", &s);
        assert!(!v.holds);
        assert_relative_eq!(v.excess, 1.0);
        assert!(!t(Op::AtMost, 1e9).judge("base", &Stats::of(&[f64::NAN])).holds);
    }

    #[test]
    fn parses_from_toml_with_symbols() {
        let th: Threshold = toml::from_str("metric = \"e_mm\"\nstat = \"p95\"\nop = \">=\"\nvalue = 0.9\n").unwrap();
        assert_eq!(th.op, Op::AtLeast);
        assert_eq!(th.stat, Stat::P95);
        assert!(toml::from_str::<Threshold>("metric = \"e\"\nstat = \"p99\"\nop = \"<=\"\nvalue = 1\n").is_err());
    }
}
