//! Statistics of one metric over the trials of one case (pure, no I/O).

use serde::{Deserialize, Serialize};

/// Which statistic of a metric a threshold looks at.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
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

/// Mean, median, 95 % quantile and maximum of a sample.
///
/// Quantiles use the linear interpolation of the sorted sample (Hyndman & Fan 1996 type 7,
/// R's and NumPy's default): with `x_(0) <= ... <= x_(n-1)` and `h = (n - 1) p`,
/// `Q(p) = x_(floor h) + (h - floor h) (x_(floor h + 1) - x_(floor h))`. The mean sums the
/// sorted sample, so the result does not depend on the order the trials finished in. A NaN
/// anywhere makes every statistic NaN (a failed metric must not pass a threshold); an empty
/// sample gives NaN too.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// Number of values.
    pub n: usize,
    /// Arithmetic mean.
    pub mean: f64,
    /// 50 % quantile (type 7).
    pub median: f64,
    /// 95 % quantile (type 7).
    pub p95: f64,
    /// Largest value.
    pub max: f64,
}

impl Stats {
    /// Statistics of `values` (any order).
    pub fn of(values: &[f64]) -> Self {
        let n = values.len();
        if n == 0 || values.iter().any(|v| v.is_nan()) {
            return Stats {
                n,
                mean: f64::NAN,
                median: f64::NAN,
                p95: f64::NAN,
                max: f64::NAN,
            };
        }
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        Stats {
            n,
            mean: sorted.iter().sum::<f64>() / n as f64,
            median: quantile_sorted(&sorted, 0.5),
            p95: quantile_sorted(&sorted, 0.95),
            max: sorted[n - 1],
        }
    }

    /// The value of statistic `stat`.
    pub fn get(&self, stat: Stat) -> f64 {
        match stat {
            Stat::Mean => self.mean,
            Stat::Median => self.median,
            Stat::P95 => self.p95,
            Stat::Max => self.max,
        }
    }
}

/// Type-7 quantile `p` in `[0, 1]` of an ascending, non-empty sample (see [`Stats`]).
pub fn quantile_sorted(sorted: &[f64], p: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * p.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn type7_quantiles_match_numpy() {
        // numpy.percentile([1..10], [50, 95]) = [5.5, 9.55]
        let v: Vec<f64> = (1..=10).rev().map(f64::from).collect();
        let s = Stats::of(&v);
        assert_eq!(s.n, 10);
        assert_relative_eq!(s.mean, 5.5);
        assert_relative_eq!(s.median, 5.5);
        assert_relative_eq!(s.p95, 9.55, max_relative = 1e-12);
        assert_relative_eq!(s.max, 10.0);
        assert_relative_eq!(s.get(Stat::P95), s.p95);
    }

    #[test]
    fn single_value_and_degenerate_samples() {
        let s = Stats::of(&[2.5]);
        assert_relative_eq!(s.median, 2.5);
        assert_relative_eq!(s.p95, 2.5);
        assert!(Stats::of(&[]).mean.is_nan());
        assert!(Stats::of(&[1.0, f64::NAN]).max.is_nan());
    }

    #[test]
    fn order_does_not_change_any_bit() {
        let v = [0.1, 0.7, 0.2, 1e-9, 3.3, 0.25];
        let mut w = v;
        w.reverse();
        let (a, b) = (Stats::of(&v), Stats::of(&w));
        assert_eq!(a.mean.to_bits(), b.mean.to_bits());
        assert_eq!(a.p95.to_bits(), b.p95.to_bits());
    }
}
