//! The F distribution, of the ratio `(X1 / d1) / (X2 / d2)` of two independent chi-square
//! variables: a chi-square statistic computed with a noise that was itself estimated from
//! `d2` degrees of freedom follows it. `F(x; d1, d2) = I_z(d1 / 2, d2 / 2)`,
//! `z = d1 x / (d1 x + d2)`, with the regularised incomplete beta function `I_z(a, b)` by its
//! continued fraction (modified Lentz), on the side where it converges fast
//! (Press et al., *Numerical Recipes*, 3rd ed., section 6.4).

use super::chi_square::ln_gamma;

/// The regularised incomplete beta function `I_x(a, b)`, `a, b > 0`, `x` in `[0, 1]`.
pub fn regularized_incomplete_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let front = (ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln()).exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        (front * beta_fraction(a, b, x) / a).clamp(0.0, 1.0)
    } else {
        (1.0 - front * beta_fraction(b, a, 1.0 - x) / b).clamp(0.0, 1.0)
    }
}

/// The continued fraction of `I_x(a, b)` (modified Lentz).
fn beta_fraction(a: f64, b: f64, x: f64) -> f64 {
    let tiny = 1e-300;
    let guard = |v: f64| if v.abs() < tiny { tiny } else { v };
    let mut c = 1.0;
    let mut d = 1.0 / guard(1.0 - (a + b) * x / (a + 1.0));
    let mut h = d;
    for m in 1..100_000 {
        let m = m as f64;
        let even = m * (b - m) * x / ((a + 2.0 * m - 1.0) * (a + 2.0 * m));
        d = 1.0 / guard(1.0 + even * d);
        c = guard(1.0 + even / c);
        h *= d * c;
        let odd = -(a + m) * (a + b + m) * x / ((a + 2.0 * m) * (a + 2.0 * m + 1.0));
        d = 1.0 / guard(1.0 + odd * d);
        c = guard(1.0 + odd / c);
        let delta = d * c;
        h *= delta;
        if (delta - 1.0).abs() < 1e-16 {
            break;
        }
    }
    h
}

/// The F distribution function `F(x; d1, d2)` (`d1, d2 > 0`).
pub fn f_cdf(x: f64, d1: f64, d2: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    regularized_incomplete_beta(0.5 * d1, 0.5 * d2, d1 * x / (d1 * x + d2))
}

/// The upper tail `1 - F(x; d1, d2)` of the F distribution (`d1, d2 > 0`), without the
/// cancellation of `1 - f_cdf` far out: `I_{d2 / (d1 x + d2)}(d2 / 2, d1 / 2)`.
pub fn f_upper_tail(x: f64, d1: f64, d2: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    regularized_incomplete_beta(0.5 * d2, 0.5 * d1, d2 / (d1 * x + d2))
}

/// The `x` whose upper tail [`f_upper_tail`] is `tail` (`0 < tail < 1`), to a relative 1e-12.
pub fn f_upper_quantile(tail: f64, d1: f64, d2: f64) -> f64 {
    let mut hi = 1.0;
    while f_upper_tail(hi, d1, d2) > tail && hi < 1e300 {
        hi *= 2.0;
    }
    let stop = crate::numerics::roots::Bisection::to_relative_width(1e-12);
    let [_, x] = crate::numerics::roots::bisect_infallible(0.0, hi, stop, |x| f_upper_tail(x, d1, d2) > tail);
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numerics::stats::chi_square_cdf;

    /// Closed forms: `I_x(a, 1) = x^a`, `I_x(1, b) = 1 - (1 - x)^b`, and the symmetry
    /// `I_x(a, b) = 1 - I_{1-x}(b, a)`.
    #[test]
    fn closed_forms_and_symmetry() {
        for x in [0.01, 0.2, 0.5, 0.77, 0.99] {
            for p in [0.5, 3.0, 40.0] {
                assert!((regularized_incomplete_beta(p, 1.0, x) - x.powf(p)).abs() < 1e-13);
                assert!((regularized_incomplete_beta(1.0, p, x) - (1.0 - (1.0 - x).powf(p))).abs() < 1e-13);
                let (a, b) = (p, 270.0);
                let sum = regularized_incomplete_beta(a, b, x) + regularized_incomplete_beta(b, a, 1.0 - x);
                assert!((sum - 1.0).abs() < 1e-12, "{a} {b} {x}");
            }
        }
    }

    /// The upper tail: with one numerator degree of freedom it is Student's t squared, and one
    /// denominator degree makes t Cauchy's, `P(|t| > x) = 1 - 2 atan(x) / pi`; with very many
    /// it is the normal's (1.96^2 for 5 %); it adds to the distribution function to 1; the
    /// quantile inverts it.
    #[test]
    fn upper_tail_and_quantile() {
        for x in [0.3f64, 1.0, 6.0, 300.0] {
            let cauchy = 1.0 - 2.0 * x.atan() / std::f64::consts::PI;
            assert!(
                (f_upper_tail(x * x, 1.0, 1.0) - cauchy).abs() < 1e-12 * cauchy.max(1e-3),
                "{x}"
            );
            assert!(
                (f_upper_tail(x, 2.5, 7.0) + f_cdf(x, 2.5, 7.0) - 1.0).abs() < 1e-12,
                "{x}"
            );
        }
        assert!((f_upper_quantile(0.05, 1.0, 1e8).sqrt() - 1.959_964).abs() < 1e-5);
        for (tail, d1, d2) in [(0.05, 1.0, 3.0), (1e-4, 1.85, 22.0), (1e-6, 3.0, 40.0)] {
            let x = f_upper_quantile(tail, d1, d2);
            assert!((f_upper_tail(x, d1, d2) / tail - 1.0).abs() < 1e-9, "{tail} {d1} {d2}");
        }
    }

    /// A second path: with `d2` very large the denominator is 1 and `F(x; d1, d2)` is the
    /// chi-square distribution of `d1 x` (the gamma function's series and fraction).
    #[test]
    fn a_known_denominator_is_the_chi_square() {
        for d1 in [3.0, 93.0, 540.0] {
            for x in [0.8, 1.0, 1.2] {
                let f = f_cdf(x, d1, 1e9);
                let chi = chi_square_cdf(d1 * x, d1);
                assert!((f - chi).abs() < 1e-4, "{d1} {x}: {f} vs {chi}");
            }
        }
    }

    /// Tabulated quantiles (NIST/SEMATECH e-Handbook, table of the F distribution's upper
    /// 5 % and 1 % points): `F(q; d1, d2)` at them.
    #[test]
    fn tabulated_upper_points() {
        for (d1, d2, q, p) in [
            (5.0, 10.0, 3.326, 0.95),
            (10.0, 20.0, 2.348, 0.95),
            (5.0, 10.0, 5.636, 0.99),
            (20.0, 30.0, 2.549, 0.99),
        ] {
            assert!(
                (f_cdf(q, d1, d2) - p).abs() < 5e-4,
                "F({q}; {d1}, {d2}) = {}",
                f_cdf(q, d1, d2)
            );
        }
    }

    /// Monte-Carlo of the ratio of two chi-square draws: the empirical distribution function
    /// at a few points within 4 binomial standard errors.
    #[test]
    fn drawn_ratios_follow_it() {
        use rand::SeedableRng;
        use rand_distr::{ChiSquared, Distribution};
        let (d1, d2) = (369.0, 199.0);
        let (x1, x2) = (ChiSquared::new(d1).unwrap(), ChiSquared::new(d2).unwrap());
        let mut rng = rand::rngs::ChaCha12Rng::seed_from_u64(7);
        let n = 40_000;
        let ratios: Vec<f64> = (0..n)
            .map(|_| (x1.sample(&mut rng) / d1) / (x2.sample(&mut rng) / d2))
            .collect();
        for x in [0.8, 0.95, 1.0, 1.1, 1.3] {
            let p = f_cdf(x, d1, d2);
            let empirical = ratios.iter().filter(|&&r| r <= x).count() as f64 / n as f64;
            let se = (p * (1.0 - p) / n as f64).sqrt();
            assert!((empirical - p).abs() < 4.0 * se + 1e-12, "{x}: {empirical} vs {p}");
        }
    }
}
