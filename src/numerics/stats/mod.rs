//! Sample statistics, the one implementation of each: moments, standard errors, the two
//! quantile definitions the program uses (named, never mixed up), tail fractions, and the
//! summary of a sample that reports and thresholds read ([`Stats`]), the chi-square
//! distribution (the calibration's noise estimate), the F distribution (a statistic with an
//! estimated noise), Student's t and the generalized ESD outlier test ([`generalized_esd`]) and the chi-square statistic of residuals that share one error
//! ([`SharedErrorChiSquare`]).

mod chi_square;
mod esd;
mod f_ratio;
mod shared_error;

pub use chi_square::{chi_square_cdf, chi_square_quantile, ln_gamma, regularized_lower_gamma};
pub use esd::{EsdOutlier, generalized_esd, robustly_beyond, student_t_two_sided};
pub use f_ratio::{f_cdf, f_upper_quantile, f_upper_tail, regularized_incomplete_beta};
use serde::{Deserialize, Serialize};
pub use shared_error::{SharedErrorChiSquare, SharedErrorFit};

/// RMS distance of `points` from their centroid (0 for none): the spread a fit's RMS is
/// judged against.
pub fn rms_spread(points: &[nalgebra::Point3<f64>]) -> f64 {
    let n = points.len().max(1) as f64;
    let centroid = points.iter().fold(nalgebra::Vector3::zeros(), |a, p| a + p.coords) / n;
    (points.iter().map(|p| (p.coords - centroid).norm_squared()).sum::<f64>() / n).sqrt()
}

/// RMS distance of `points` from their best-fitting straight line (0 for fewer than 3): the
/// root of the two smaller eigenvalues of their scatter about the centroid, over the count.
pub fn rms_off_line(points: &[nalgebra::Point3<f64>]) -> f64 {
    if points.len() < 3 {
        return 0.0;
    }
    let n = points.len() as f64;
    let centroid = points.iter().fold(nalgebra::Vector3::zeros(), |a, p| a + p.coords) / n;
    let scatter: nalgebra::Matrix3<f64> = points
        .iter()
        .map(|p| (p.coords - centroid) * (p.coords - centroid).transpose())
        .sum();
    let eigenvalues = scatter.symmetric_eigenvalues();
    let off_line = eigenvalues.sum() - eigenvalues.max();
    (off_line.max(0.0) / n).sqrt()
}

/// A fit whose RMS exceeds this fraction of its points' spread about their centroid
/// ([`rms_spread`]) is no calibration: the model leaves a quarter of a percent of the points'
/// variance (`0.05^2`) unexplained, where a robot its description fits leaves parts per
/// million (0.2 mm of misfit over a spread of half a metre; 0.03 mm over an arc of 50 mm).
pub const ABSURD_SHARE: f64 = 0.05;

/// Points whose RMS spread about their centroid ([`rms_spread`]) is within this many times the
/// noise of a point (3-D RMS) show no motion the instrument resolves (a fit of them that fails
/// or misses them says so): noise alone spreads `n`
/// points by `noise sqrt((n - 1) / n)` (a chi distribution with `3 (n - 1)` degrees of freedom,
/// whose chance of twice its scale is below 1e-7 from five points up).
pub const UNRESOLVED_SPREAD_OVER_NOISE: f64 = 2.0;

/// A rotary sweep whose arc bows from its chord by less than this many times the noise of a
/// point (3-D RMS) is too short to locate its axis when its fit fails or misses it: the radius
/// of an arc of sagitta `s` measured with noise `sigma` is uncertain by about `sigma / s` of
/// itself, more than a fifth below this, where the fit's iterations wander.
pub const SHORT_ARC_SAGITTA_OVER_NOISE: f64 = 5.0;

/// Tukey's "far out" fence factor (*Exploratory Data Analysis*, 1977, ch. 2): a value beyond
/// the upper quartile by 3 interquartile ranges.
pub const FAR_OUT: f64 = 3.0;

/// Tukey's far-out fence of `v`: `Q3 + 3 (Q3 - Q1)` (linear quartiles). The outlier tests'
/// fence: a gross error lies far beyond it, while a heavy tail of clean data (what a model
/// misses) lifts it with the quartiles, as it would not a Gaussian quantile.
pub fn far_out_fence(v: &[f64]) -> f64 {
    let q1 = quantile(v, 0.25, QuantileMethod::Linear);
    let q3 = quantile(v, 0.75, QuantileMethod::Linear);
    q3 + FAR_OUT * (q3 - q1)
}

/// The far-out fence of the 3-D norms of isotropic Gaussian errors over their median:
/// `(Q3 + 3 IQR) / Q2` of the chi distribution with 3 degrees of freedom (3.12).
pub fn chi3_far_out_over_median() -> f64 {
    chi_far_out_over_median(3.0)
}

/// `(Q3 + 3 IQR) / Q2` of the chi distribution with `dof` degrees of freedom: for one, the
/// norms of 3-D Gaussian errors all along one direction (5.40), the heaviest tail a 3-D error
/// of a given RMS has (a theodolite pair's depth error nearly is one).
pub fn chi_far_out_over_median(dof: f64) -> f64 {
    let q = |p: f64| chi_square_quantile(p, dof).sqrt();
    (q(0.75) + FAR_OUT * (q(0.75) - q(0.25))) / q(0.5)
}

/// Mean (NaN when empty).
pub fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// Sample standard deviation, `n - 1` in the denominator (0 with fewer than two values).
pub fn std_dev(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return 0.0;
    }
    let m = mean(v);
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

/// The mean and its standard error `s / sqrt(n)` (`s` with `n - 1`, taken as 1 for a single
/// value so the error is the spread itself, 0).
pub fn mean_and_standard_error(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, (var / n).sqrt())
}

/// How a quantile is read off a sample (Hyndman & Fan, "Sample quantiles in statistical
/// packages", *The American Statistician* 50, 1996).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QuantileMethod {
    /// Type 1, the inverse of the empirical distribution function: the smallest sample with at
    /// least a fraction `p` of the samples at or below it. Always a sample value; what a
    /// Monte-Carlo critical value ("beaten by at most a fraction `1 - p` of the null draws")
    /// needs.
    InverseCdf,
    /// Type 7, linear interpolation of the sorted sample (R's and NumPy's default): with
    /// `x_(0) <= ... <= x_(n-1)` and `h = (n - 1) p`,
    /// `Q(p) = x_(floor h) + (h - floor h) (x_(floor h + 1) - x_(floor h))`. What summaries
    /// of a metric report.
    Linear,
}

/// The `p` quantile (`p` in `[0, 1]`) of an ascending, non-empty sample by `method`.
pub fn quantile_sorted(sorted: &[f64], p: f64, method: QuantileMethod) -> f64 {
    let n = sorted.len();
    match method {
        QuantileMethod::InverseCdf => sorted[((p * n as f64).ceil() as usize).clamp(1, n) - 1],
        QuantileMethod::Linear => {
            let h = (n - 1) as f64 * p.clamp(0.0, 1.0);
            let lo = h.floor() as usize;
            let hi = (lo + 1).min(n - 1);
            sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
        }
    }
}

/// The `p` quantile of a sample in any order by `method` (NaN when empty).
pub fn quantile(v: &[f64], p: f64, method: QuantileMethod) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    quantile_sorted(&s, p, method)
}

/// The median of a sample in any order: the mean of the middle two for an even count
/// ([`QuantileMethod::Linear`] at 1/2; NaN when empty).
pub fn median(v: &[f64]) -> f64 {
    quantile(v, 0.5, QuantileMethod::Linear)
}

/// Standard deviations per median absolute deviation for Gaussian data (`1 / Phi^-1(3/4)`).
pub const SIGMA_PER_MAD: f64 = 1.4826;

/// The median of a sample and its robust standard deviation: [`SIGMA_PER_MAD`] times the
/// median absolute deviation from that median, which gross errors in fewer than half the
/// sample barely move (NaN when empty).
pub fn median_and_robust_sigma(v: &[f64]) -> (f64, f64) {
    let centre = median(v);
    let mad = median(&v.iter().map(|x| (x - centre).abs()).collect::<Vec<_>>());
    (centre, SIGMA_PER_MAD * mad)
}

/// Fraction of `v` at or above `x` (NaN when empty).
pub fn upper_tail(v: &[f64], x: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.iter().filter(|&&s| s >= x).count() as f64 / v.len() as f64
}

/// Count, mean, root mean square, median, 95 % quantile and maximum of a sample.
///
/// Quantiles are [`QuantileMethod::Linear`]. The mean sums the sorted sample, so the result
/// does not depend on the order the values arrived in (trials finishing on several threads).
/// A NaN anywhere makes every statistic NaN (a failed metric must not pass a threshold); an
/// empty sample gives NaN too.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Stats {
    /// Number of values.
    pub n: usize,
    /// Arithmetic mean.
    pub mean: f64,
    /// Root mean square.
    pub rms: f64,
    /// 50 % quantile.
    pub median: f64,
    /// 95 % quantile.
    pub p95: f64,
    /// Largest value.
    pub max: f64,
}

impl Stats {
    fn undefined(n: usize) -> Self {
        Stats {
            n,
            mean: f64::NAN,
            rms: f64::NAN,
            median: f64::NAN,
            p95: f64::NAN,
            max: f64::NAN,
        }
    }

    /// Statistics of `values` (any order).
    pub fn of(values: &[f64]) -> Self {
        let n = values.len();
        if n == 0 || values.iter().any(|v| v.is_nan()) {
            return Self::undefined(n);
        }
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        Stats {
            n,
            mean: sorted.iter().sum::<f64>() / n as f64,
            rms: (sorted.iter().map(|x| x * x).sum::<f64>() / n as f64).sqrt(),
            median: quantile_sorted(&sorted, 0.5, QuantileMethod::Linear),
            p95: quantile_sorted(&sorted, 0.95, QuantileMethod::Linear),
            max: sorted[n - 1],
        }
    }

    /// Statistics of the union of the samples that `parts` summarise: count, mean, RMS and
    /// maximum are exact; the quantiles of a union cannot be had from the parts' summaries and
    /// are NaN. Empty parts are skipped; NaN when every part is empty.
    pub fn pooled(parts: &[Stats]) -> Self {
        let parts: Vec<&Stats> = parts.iter().filter(|p| p.n > 0).collect();
        let n: usize = parts.iter().map(|p| p.n).sum();
        if n == 0 {
            return Self::undefined(0);
        }
        let weighted = |f: fn(&Stats) -> f64| parts.iter().map(|p| p.n as f64 * f(p)).sum::<f64>() / n as f64;
        Stats {
            n,
            mean: weighted(|p| p.mean),
            rms: weighted(|p| p.rms * p.rms).sqrt(),
            median: f64::NAN,
            p95: f64::NAN,
            max: parts.iter().map(|p| p.max).fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

/// Draws of a zero-mean multivariate normal with covariance `C` (symmetric, positive
/// semi-definite): `x = V sqrt(L) z` with `C = V L V^T` (eigen-decomposition, negative
/// rounding eigenvalues taken as 0) and `z` standard normal, one per dimension in order.
#[derive(Clone, Debug)]
pub struct CorrelatedNormal {
    factor: nalgebra::DMatrix<f64>,
}

impl CorrelatedNormal {
    /// The distribution of covariance `c`; an error (in words) for a matrix that is empty, not
    /// square, or holds a number that is not finite: none has a factor (the eigen-decomposition
    /// needs a non-empty finite square matrix).
    pub fn new(c: &nalgebra::DMatrix<f64>) -> Result<Self, String> {
        if c.is_empty() || !c.is_square() {
            return Err(format!(
                "a covariance of {} x {} numbers has no factor (a non-empty square matrix is needed)",
                c.nrows(),
                c.ncols()
            ));
        }
        if let Some(i) = c.iter().position(|x| !x.is_finite()) {
            return Err(format!(
                "covariance entry ({}, {}) is {}: no factor",
                i % c.nrows(),
                i / c.nrows(),
                c[i]
            ));
        }
        let sym = 0.5 * (c + c.transpose());
        let eig = nalgebra::SymmetricEigen::new(sym);
        let roots = eig.eigenvalues.map(|l| l.max(0.0).sqrt());
        Ok(CorrelatedNormal {
            factor: eig.eigenvectors * nalgebra::DMatrix::from_diagonal(&roots),
        })
    }

    /// `V sqrt(L)`: the factor `F` with `F F^T = C`.
    pub fn factor(&self) -> &nalgebra::DMatrix<f64> {
        &self.factor
    }

    /// One draw.
    pub fn draw<R: rand::Rng + ?Sized>(&self, rng: &mut R) -> nalgebra::DVector<f64> {
        use rand_distr::{Distribution, StandardNormal};
        let z = nalgebra::DVector::from_fn(self.factor.ncols(), |_, _| StandardNormal.sample(rng));
        &self.factor * z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points at known distances from a known line, by a second path: each point's distance
    /// is its offset across the line, chosen, so the RMS is known; rigidly moved, it stays.
    #[test]
    fn the_rms_off_a_line_is_the_points_distance_from_it() {
        use nalgebra::{Point3, Rotation3, Vector3};
        // Pairs along x, one point `d` to each side in y: the best line is the x axis.
        let (d, n) = (0.3, 10);
        let turn = Rotation3::from_euler_angles(0.4, -1.1, 2.0);
        let points: Vec<Point3<f64>> = (0..2 * n)
            .map(|i| {
                let across = if i % 2 == 0 { d } else { -d };
                Point3::from(turn * Vector3::new((i / 2) as f64, across, 0.0) + Vector3::new(5.0, -2.0, 7.0))
            })
            .collect();
        assert!((rms_off_line(&points) - d).abs() < 1e-12, "{}", rms_off_line(&points));
        let on_line: Vec<Point3<f64>> = (0..n).map(|i| Point3::new(i as f64, 2.0 * i as f64, 3.0)).collect();
        assert!(rms_off_line(&on_line) < 1e-12);
        // Two points always lie on a line: exactly 0 (the short path, not a fit).
        assert!(rms_off_line(&points[..2]).abs() < f64::MIN_POSITIVE);
    }

    /// An empty matrix, a non-square one, or one holding a NaN or an infinity has no factor:
    /// an error naming it, not a panic (hostile run 13: an empty model covariance); a 1 x 1
    /// covariance's factor is its square root, by hand.
    #[test]
    fn a_covariance_without_a_factor_is_an_error() {
        use nalgebra::DMatrix;
        assert!(
            CorrelatedNormal::new(&DMatrix::zeros(0, 0))
                .unwrap_err()
                .contains("0 x 0")
        );
        assert!(CorrelatedNormal::new(&DMatrix::zeros(2, 3)).is_err());
        let nan = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, f64::NAN]);
        assert!(CorrelatedNormal::new(&nan).unwrap_err().contains("(1, 1) is NaN"));
        let inf = DMatrix::from_row_slice(2, 2, &[1.0, f64::INFINITY, 0.0, 1.0]);
        assert!(CorrelatedNormal::new(&inf).unwrap_err().contains("(0, 1) is inf"));
        let one = CorrelatedNormal::new(&DMatrix::from_element(1, 1, 6.25)).unwrap();
        assert!((one.factor()[(0, 0)].abs() - 2.5).abs() < 1e-15);
    }

    /// The sample covariance of many draws recovers the covariance: each entry within 5
    /// standard errors (`sqrt((C_ii C_jj + C_ij^2) / n)`), a singular direction drawn as 0.
    #[test]
    fn correlated_normal_draws_have_the_covariance() {
        use rand::SeedableRng;
        let c = nalgebra::DMatrix::from_row_slice(3, 3, &[4.0, 1.2, 0.0, 1.2, 1.0, 0.0, 0.0, 0.0, 0.0]);
        let dist = CorrelatedNormal::new(&c).unwrap();
        let mut rng = rand::rngs::ChaCha12Rng::seed_from_u64(5);
        let n = 20_000;
        let mut s = nalgebra::DMatrix::<f64>::zeros(3, 3);
        for _ in 0..n {
            let x = dist.draw(&mut rng);
            s += &x * x.transpose();
        }
        s /= n as f64;
        for i in 0..3 {
            for j in 0..3 {
                let se = ((c[(i, i)] * c[(j, j)] + c[(i, j)].powi(2)) / n as f64).sqrt();
                assert!(
                    (s[(i, j)] - c[(i, j)]).abs() <= 5.0 * se + 1e-15,
                    "({i},{j}): {} vs {}",
                    s[(i, j)],
                    c[(i, j)]
                );
            }
        }
    }
    use approx::assert_relative_eq;

    #[test]
    fn inverse_cdf_quantile_and_tail_of_one_to_hundred() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_relative_eq!(quantile(&v, 0.99, QuantileMethod::InverseCdf), 99.0);
        assert_relative_eq!(quantile(&v, 1.0, QuantileMethod::InverseCdf), 100.0);
        assert_relative_eq!(upper_tail(&v, 96.0), 0.05);
        assert!((mean(&v) - 50.5).abs() < 1e-12);
    }

    #[test]
    fn linear_quantiles_match_numpy() {
        // numpy.percentile([1..10], [50, 95]) = [5.5, 9.55]
        let v: Vec<f64> = (1..=10).rev().map(f64::from).collect();
        let s = Stats::of(&v);
        assert_eq!(s.n, 10);
        assert_relative_eq!(s.mean, 5.5);
        assert_relative_eq!(s.median, 5.5);
        assert_relative_eq!(s.p95, 9.55, max_relative = 1e-12);
        assert_relative_eq!(s.max, 10.0);
        // sqrt(385 / 10)
        assert_relative_eq!(s.rms, 38.5f64.sqrt(), max_relative = 1e-15);
        assert_relative_eq!(quantile(&v, 0.95, QuantileMethod::Linear), 9.55, max_relative = 1e-12);
    }

    #[test]
    fn single_value_and_degenerate_samples() {
        let s = Stats::of(&[2.5]);
        assert_relative_eq!(s.median, 2.5);
        assert_relative_eq!(s.p95, 2.5);
        assert!(Stats::of(&[]).mean.is_nan());
        assert!(Stats::of(&[1.0, f64::NAN]).max.is_nan());
        assert!(quantile(&[], 0.5, QuantileMethod::Linear).is_nan());
    }

    #[test]
    fn order_does_not_change_any_bit() {
        let v = [0.1, 0.7, 0.2, 1e-9, 3.3, 0.25];
        let mut w = v;
        w.reverse();
        let (a, b) = (Stats::of(&v), Stats::of(&w));
        assert_eq!(a.mean.to_bits(), b.mean.to_bits());
        assert_eq!(a.rms.to_bits(), b.rms.to_bits());
        assert_eq!(a.p95.to_bits(), b.p95.to_bits());
    }

    #[test]
    fn pooled_moments_equal_those_of_the_union() {
        let (a, b) = ([1.0, 2.0, 4.0], [3.0, 7.0]);
        let union = Stats::of(&[1.0, 2.0, 4.0, 3.0, 7.0]);
        let pooled = Stats::pooled(&[Stats::of(&a), Stats::of(&b), Stats::of(&[])]);
        assert_eq!(pooled.n, 5);
        assert_relative_eq!(pooled.mean, union.mean, max_relative = 1e-15);
        assert_relative_eq!(pooled.rms, union.rms, max_relative = 1e-15);
        assert_relative_eq!(pooled.max, 7.0);
        assert!(pooled.median.is_nan());
        assert!(Stats::pooled(&[]).mean.is_nan());
    }

    #[test]
    fn standard_error_of_a_known_sample() {
        // s^2 = 2.5 for 1..5; se = sqrt(2.5 / 5)
        let (m, se) = mean_and_standard_error(&[1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_relative_eq!(m, 3.0);
        assert_relative_eq!(se, 0.5f64.sqrt(), max_relative = 1e-15);
        assert_relative_eq!(std_dev(&[1.0, 2.0, 3.0, 4.0, 5.0]), 2.5f64.sqrt(), max_relative = 1e-15);
    }
}
