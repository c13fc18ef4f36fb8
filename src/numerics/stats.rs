//! Sample statistics of the noise-only replicas.

/// Mean (NaN when empty).
pub fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// Sample standard deviation (0 with fewer than two values).
pub fn std_dev(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return 0.0;
    }
    let m = mean(v);
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

/// The empirical `p` quantile: the smallest sample with at least a fraction `p` of the
/// samples at or below it (NaN when empty).
pub fn quantile(v: &[f64], p: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let i = ((p * s.len() as f64).ceil() as usize).clamp(1, s.len()) - 1;
    s[i]
}

/// Fraction of `v` at or above `x`.
pub fn upper_tail(v: &[f64], x: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.iter().filter(|&&s| s >= x).count() as f64 / v.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantile_and_tail_of_one_to_hundred() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        approx::assert_relative_eq!(quantile(&v, 0.99), 99.0);
        approx::assert_relative_eq!(quantile(&v, 1.0), 100.0);
        approx::assert_relative_eq!(upper_tail(&v, 96.0), 0.05);
        assert!((mean(&v) - 50.5).abs() < 1e-12);
    }
}
