//! The instrument noise estimated from the axis fits' residuals (pooled over every arc and
//! line with their degrees of freedom), with a chi-square confidence interval, and the test
//! of a given noise level against it.
//!
//! For one least-squares fit of `n` points (3 coordinates each, `p` parameters) with isotropic
//! weights, the residual vector is `r = (I - H) e`, `H` the hat matrix of the Jacobian. With
//! measurement noise `sigma^2 I` and a joint-angle jitter `s_j` moving point `j` along `t_j`
//! (the robot's repeatability on the swept joint), `E |r|^2 = sigma^2 (3n - p) +
//! sum_j s^2 |(I - H) t_j|^2` (Seber & Lee, *Linear Regression Analysis*, 2nd ed., thm. 3.3,
//! with the jitter's covariance added). Pooled over the fits,
//! `sigma^2 = (sum |r|^2 - sum s^2 J) / nu`, `nu = sum (3n - p)`. Without jitter
//! `nu sigma_hat^2 / sigma^2` is chi-square with `nu` degrees of freedom; with it, the
//! quadratic form's variance `2 tr(C^2)`, `C = sigma^2 (I - H) + s^2 (I - H) T T^T (I - H)`,
//! is `2 (sigma^4 nu + 2 sigma^2 s^2 J + s^4 K)`, `K = |T^T (I - H) T|_F^2`, and the estimate is
//! taken as chi-square with Satterthwaite's effective degrees of freedom
//! `nu_eff = 2 (sigma^2 nu)^2 / Var` (Satterthwaite, *Biometrics Bulletin* 2 (1946) 110),
//! which gives the interval. The 3-D RMS noise (the paper's "net radial error") is
//! `sqrt(3) sigma`.

use crate::numerics::stats::{chi_square_cdf, chi_square_quantile};
use nalgebra::{DMatrix, Vector3};
use serde::{Deserialize, Serialize};

/// The residual moments of one fit, for the pooled estimate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ResidualMoments {
    /// Sum of squared residual lengths \[m^2\].
    pub rss_m2: f64,
    /// Degrees of freedom `3n - p`.
    pub dof: usize,
    /// `sum_j |(I - H) t_j|^2` per unit jitter variance (m^2 per rad^2, or per m^2 for a
    /// sliding joint).
    pub jitter_m2: f64,
    /// The jitter's standard deviation the fit assumed (rad or m); 0 for none.
    pub jitter_sigma: f64,
    /// `K = |T^T (I - H) T|_F^2` per unit jitter variance squared (module docs).
    #[serde(default)]
    pub jitter_m4: f64,
}

impl ResidualMoments {
    /// The moments of a fit with isotropic weights: `jacobian` (3n x p, rows in the same
    /// coordinates as `residuals_m`, any common scale), `residuals_m` (per point, unwhitened),
    /// and optionally the jitter direction `t_j` of each point (same coordinates) with the
    /// jitter sigma. `covariance_unit` is `(J^T J)^-1` of the same Jacobian.
    pub fn of_fit(
        jacobian: &DMatrix<f64>,
        covariance_unit: &DMatrix<f64>,
        residuals_m: &[Vector3<f64>],
        jitter: Option<(&[Vector3<f64>], f64)>,
    ) -> Self {
        let n = residuals_m.len();
        let p = jacobian.ncols();
        let rss_m2 = residuals_m.iter().map(|r| r.norm_squared()).sum();
        let (jitter_m2, jitter_m4, jitter_sigma) = match jitter {
            Some((tangents, sigma)) if sigma > 0.0 => {
                // M = T^T (I - H) T: M_ij = t_i.t_j delta_ij - w_i^T G w_j, w_i = J_i^T t_i
                // (H = J G J^T, G = (J^T J)^-1); J = trace M, K = |M|_F^2.
                let w: Vec<nalgebra::DVector<f64>> = tangents
                    .iter()
                    .enumerate()
                    .map(|(j, t)| jacobian.rows(3 * j, 3).transpose() * t)
                    .collect();
                let gw: Vec<nalgebra::DVector<f64>> = w.iter().map(|x| covariance_unit * x).collect();
                let (mut trace, mut frob) = (0.0, 0.0);
                for (i, (wi, ti)) in w.iter().zip(tangents).enumerate() {
                    for (j, gwj) in gw.iter().enumerate() {
                        let mut m = -wi.dot(gwj);
                        if i == j {
                            m += ti.norm_squared();
                            trace += m;
                        }
                        frob += m * m;
                    }
                }
                (trace, frob, sigma)
            }
            _ => (0.0, 0.0, 0.0),
        };
        ResidualMoments {
            rss_m2,
            dof: (3 * n).saturating_sub(p),
            jitter_m2,
            jitter_sigma,
            jitter_m4,
        }
    }
}

/// Confidence of the reported interval.
pub const NOISE_CONFIDENCE: f64 = 0.95;

/// Significance below which a given noise level is said to be contradicted by the residuals
/// (two-sided chi-square test).
pub const NOISE_TEST_LEVEL: f64 = 0.01;

/// The instrument noise estimated from the pooled residuals.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseEstimate {
    /// Estimated 3-D RMS noise of a point \[mm\].
    pub rms_3d_mm: f64,
    /// Its [`NOISE_CONFIDENCE`] interval \[mm\].
    pub interval_mm: [f64; 2],
    /// Confidence of the interval.
    pub confidence: f64,
    /// Pooled degrees of freedom.
    pub dof: usize,
    /// Satterthwaite's effective degrees of freedom of the estimate (= `dof` without jitter).
    pub effective_dof: f64,
    /// Fits pooled.
    pub fits: usize,
    /// The share of the squared residuals the assumed joint jitter (repeatability) explains,
    /// subtracted before the estimate.
    pub jitter_share: f64,
}

/// The pooled estimate of the parts; `None` without a degree of freedom.
pub fn estimate_noise(parts: &[ResidualMoments]) -> Option<NoiseEstimate> {
    let dof: usize = parts.iter().map(|p| p.dof).sum();
    if dof == 0 {
        return None;
    }
    let rss: f64 = parts.iter().map(|p| p.rss_m2).sum();
    let jitter: f64 = parts.iter().map(|p| p.jitter_sigma.powi(2) * p.jitter_m2).sum();
    let nu = dof as f64;
    let s2 = ((rss - jitter) / nu).max(0.0);
    // Var(rss) / 2 at sigma^2 = s2 (module docs).
    let half_var: f64 = parts
        .iter()
        .map(|p| {
            let v = p.jitter_sigma.powi(2);
            s2 * s2 * p.dof as f64 + 2.0 * s2 * v * p.jitter_m2 + v * v * p.jitter_m4
        })
        .sum();
    // Zero residuals beyond the jitter's (a noiseless simulation) estimate zero: the interval
    // [0, 0] from the plain degrees of freedom (Satterthwaite's would be 0).
    let effective = if s2 > 0.0 && half_var > 0.0 {
        (s2 * nu).powi(2) / half_var
    } else {
        nu
    };
    let alpha = 1.0 - NOISE_CONFIDENCE;
    let to_mm = |var_per_axis: f64| (3.0 * var_per_axis).sqrt() * 1e3;
    Some(NoiseEstimate {
        rms_3d_mm: to_mm(s2),
        interval_mm: [
            to_mm(effective * s2 / chi_square_quantile(1.0 - alpha / 2.0, effective)),
            to_mm(effective * s2 / chi_square_quantile(alpha / 2.0, effective)),
        ],
        confidence: NOISE_CONFIDENCE,
        dof,
        effective_dof: effective,
        fits: parts.len(),
        jitter_share: if rss > 0.0 { (jitter / rss).min(1.0) } else { 0.0 },
    })
}

impl NoiseEstimate {
    /// The two-sided chi-square p-value of a given 3-D RMS noise `given_mm` against the
    /// residuals: `X = nu_eff s^2 / (given^2 / 3)`, `p = 2 min(F(X), 1 - F(X))`.
    pub fn p_value(&self, given_mm: f64) -> f64 {
        let nu = self.effective_dof;
        let x = nu * (self.rms_3d_mm / given_mm).powi(2);
        let f = chi_square_cdf(x, nu);
        (2.0 * f.min(1.0 - f)).min(1.0)
    }

    /// Whether the residuals contradict `given_mm` at [`NOISE_TEST_LEVEL`].
    pub fn contradicts(&self, given_mm: f64) -> bool {
        self.p_value(given_mm) < NOISE_TEST_LEVEL
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{SeedableRng, rngs::ChaCha12Rng};
    use rand_distr::{Distribution, StandardNormal};

    /// A linear fit (a constant 3-vector, p = 3) of pure noise: the estimate is the sample
    /// variance, whose interval covers the truth about 95 % of the time.
    #[test]
    fn interval_covers_the_simulated_noise() {
        let sigma = 1e-4;
        let mut rng = ChaCha12Rng::seed_from_u64(7);
        let mut covered = 0;
        let trials = 400;
        let n = 20;
        let j = DMatrix::from_fn(3 * n, 3, |r, c| if r % 3 == c { 1.0 } else { 0.0 });
        let g = DMatrix::identity(3, 3) / n as f64;
        for _ in 0..trials {
            // Two independent fits, pooled.
            let parts: Vec<ResidualMoments> = (0..2)
                .map(|_| {
                    let pts: Vec<Vector3<f64>> = (0..n)
                        .map(|_| {
                            Vector3::from_fn(|_, _| {
                                let z: f64 = StandardNormal.sample(&mut rng);
                                sigma * z
                            })
                        })
                        .collect();
                    let mean = pts.iter().sum::<Vector3<f64>>() / n as f64;
                    let res: Vec<Vector3<f64>> = pts.iter().map(|p| p - mean).collect();
                    ResidualMoments::of_fit(&j, &g, &res, None)
                })
                .collect();
            assert_eq!(parts[0].dof, 3 * n - 3);
            let e = estimate_noise(&parts).unwrap();
            let truth = 3f64.sqrt() * sigma * 1e3;
            if e.interval_mm[0] <= truth && truth <= e.interval_mm[1] {
                covered += 1;
            }
            assert!(!e.contradicts(e.rms_3d_mm));
        }
        // Binomial(400, 0.95): 4 standard deviations is 17 misses either way.
        let rate = covered as f64 / trials as f64;
        assert!(
            (rate - 0.95).abs() < 4.0 * (0.95f64 * 0.05 / trials as f64).sqrt(),
            "{rate}"
        );
    }
}
