//! Whether the sweeps of each joint fitted from several agree on one axis within the noise
//! their own fits show. A sweep at another pose enters its joint's fit through the held
//! joints' correction, which moves its points with the calibrated model
//! (`docs/formats.md#held-joints`); where that model is uncertain (short sweeps, axes located
//! to millimetres) the corrected sweeps miss one another by more than the noise, and the
//! joint fits' residuals hold that model error beside the noise. A test that reads those
//! residuals as noise (the coordinate-scale profile's F test,
//! [`crate::measurement::unit_check::axis_scale`]) then takes any parameter that absorbs part
//! of the model error for a finding.
//!
//! Each sweep's own axis fit sees its points alone, as measured: its residuals are the noise,
//! whatever the correction did. Pooled over the joints, the joint fits' excess over the own
//! fits, per degree of freedom, against the own fits' residuals per degree of freedom is an F
//! ratio with `(sum dof_joint - sum dof_own, sum dof_own)` degrees of freedom when the sweeps
//! agree (the joint fit is the own fits constrained to one axis and one transmission).

use super::Calibration;
use crate::calibration::noise::ResidualMoments;
use crate::numerics::stats::f_upper_tail;

/// How far the joints' sweeps disagree, pooled over the joints fitted from several.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepsAgreement {
    /// The joints pooled.
    pub joints: Vec<usize>,
    /// The joint fits' excess over the sweeps' own fits per degree of freedom, over the own
    /// fits' residuals per degree of freedom.
    pub variance_ratio: f64,
    /// The degrees of freedom of the excess and of the own fits.
    pub dof: (usize, usize),
    /// The F test's upper tail probability of the ratio: small where the sweeps disagree.
    pub p_value: f64,
    /// The RMS per coordinate of the own fits' residuals and of the joint fits' \[mm\] (over
    /// their degrees of freedom).
    pub rms_mm: [f64; 2],
}

/// The agreement of `cal`'s joints fitted from several sweeps (module docs), `None` where no
/// joint has several sweeps with their own fits and residual moments (a report's
/// calibration only), or where the own fits leave no degree of freedom.
pub fn sweeps_agreement(cal: &Calibration) -> Option<SweepsAgreement> {
    let joints = cal.axes.iter().filter(|a| a.sweeps.len() > 1).filter_map(|axis| {
        let own: Option<Vec<ResidualMoments>> = axis.sweeps.iter().map(|s| s.own_moments).collect();
        Some((axis.joint, axis.moments?, own?))
    });
    pooled(joints)
}

/// The agreement pooled over `joints`: each one's joint fit's moments and its sweeps' own
/// fits'. A joint whose own fits leave no fewer degrees of freedom than its joint fit is left
/// out (nothing constrains them).
fn pooled(joints: impl Iterator<Item = (usize, ResidualMoments, Vec<ResidualMoments>)>) -> Option<SweepsAgreement> {
    let (mut named, mut joint_rss, mut joint_dof, mut own_rss, mut own_dof) = (vec![], 0.0, 0, 0.0, 0);
    for (joint, moments, own) in joints {
        let dof: usize = own.iter().map(|m| m.dof).sum();
        if dof >= moments.dof {
            continue;
        }
        named.push(joint);
        joint_rss += moments.rss_m2;
        joint_dof += moments.dof;
        own_rss += own.iter().map(|m| m.rss_m2).sum::<f64>();
        own_dof += dof;
    }
    if named.is_empty() || own_dof == 0 || own_rss.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let excess_dof = joint_dof - own_dof;
    let own_variance = own_rss / own_dof as f64;
    let variance_ratio = (joint_rss - own_rss).max(0.0) / excess_dof as f64 / own_variance;
    Some(SweepsAgreement {
        joints: named,
        variance_ratio,
        dof: (excess_dof, own_dof),
        p_value: f_upper_tail(variance_ratio, excess_dof as f64, own_dof as f64),
        rms_mm: [own_variance.sqrt() * 1e3, (joint_rss / joint_dof as f64).sqrt() * 1e3],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::ChaCha12Rng;
    use rand_distr::{Distribution, Normal};

    fn moments(rss_m2: f64, dof: usize) -> ResidualMoments {
        ResidualMoments {
            rss_m2,
            dof,
            ..ResidualMoments::default()
        }
    }

    /// The pooled ratio by hand: three joints, one left out (its own fits as free as its joint fit).
    #[test]
    fn the_pooled_ratio_is_the_excess_per_dof_over_the_own_fits_per_dof() {
        let a = pooled(
            [
                (1, moments(4.0, 30), vec![moments(1.0, 7), moments(1.0, 7)]),
                (2, moments(9.0, 10), vec![moments(1.0, 5), moments(1.0, 5)]),
                (3, moments(5.0, 20), vec![moments(2.0, 10)]),
            ]
            .into_iter(),
        )
        .unwrap();
        assert_eq!(a.joints, vec![1, 3]);
        assert_eq!(a.dof, (50 - 24, 24));
        let expected = ((9.0 - 4.0) / 26.0) / (4.0 / 24.0);
        assert!((a.variance_ratio - expected).abs() < 1e-12 * expected);
        assert!((a.rms_mm[0] - (4.0f64 / 24.0).sqrt() * 1e3).abs() < 1e-9);
    }

    /// Sums of squares drawn as chi-squares of one variance for both parts: the test's p-value
    /// is uniform, so about 1 % of draws fall below 0.01 (a second path: the F distribution
    /// checked against draws, not its formula). 2000 draws, binomial sigma 0.22 %.
    #[test]
    fn agreeing_sweeps_fail_at_the_test_rate() {
        let mut rng = ChaCha12Rng::seed_from_u64(65);
        let normal = Normal::new(0.0f64, 1.0).unwrap();
        let mut chi2 = |dof: usize| (0..dof).map(|_| normal.sample(&mut rng).powi(2)).sum::<f64>();
        let draws = 2000;
        let below = (0..draws)
            .filter(|_| {
                let own = [chi2(7), chi2(7), chi2(7)];
                let excess = chi2(15);
                let joint = own.iter().sum::<f64>() + excess;
                let a = pooled(std::iter::once((
                    1,
                    moments(joint, 36),
                    own.map(|r| moments(r, 7)).to_vec(),
                )))
                .unwrap();
                a.p_value < 0.01
            })
            .count();
        let rate = below as f64 / draws as f64;
        let sigma = (0.01f64 * 0.99 / draws as f64).sqrt();
        assert!((rate - 0.01).abs() < 4.0 * sigma, "{below} of {draws} below 0.01");
    }
}
