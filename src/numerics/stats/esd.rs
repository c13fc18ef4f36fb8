//! Rosner's generalized extreme studentized deviate test (*Technometrics* 25, 1983, 165-172)
//! for samples of several coordinates each: up to `r` outliers among `n` samples, with a
//! false-alarm rate that holds for any `n` on Gaussian data.
//!
//! Round `i` takes the samples not yet set aside (`m = n - i + 1`) and sets aside the one
//! farthest from them robustly: the largest, over the coordinates, distance from the
//! coordinate's median in its robust standard deviations ([`median_and_robust_sigma`]). Many
//! gross errors alike move the mean and inflate the standard deviation until a good sample
//! lies farther from the mean than any of them (they mask each other); from the median they
//! stay farthest, so they are set aside before any good sample. The round's statistic is that
//! sample's externally studentised deviation, the largest over its coordinates:
//! `t = |x - mean_{-j}| / (s_{-j} sqrt(1 + 1 / (m - 1)))` (mean and standard deviation of the
//! other `m - 1`), Student's t with `m - 2` degrees of freedom. It is at most the largest `t`
//! of the round's samples, Rosner's statistic, so the false-alarm rate is at most his. The
//! fence `lambda_i` is the t quantile two-sided at `alpha / (r m d)`: Bonferroni over the `m`
//! samples, the `d` coordinates and the `r` rounds. That is Rosner's `lambda_i`, written for
//! `t` rather than the internally studentised deviation, with `alpha` split over the rounds as
//! well: his rate holds because a later round tests a sample whose extreme was removed, but of
//! `d` coordinates only the one that set the sample aside is so truncated, and the others
//! would add nearly `alpha` per round. After `r` rounds, the outliers are the samples of the
//! rounds up to the last whose statistic exceeds its fence, so that several outliers do not
//! mask each other.
//!
//! Every standard deviation of a coordinate, robust or plain, is taken no smaller than the
//! caller's least one for it: the resolution its values are written and computed with, below
//! which scatter is rounding (without it, samples that differ by one rounding step, or by the
//! last bits of a computation, lie 1e60 standard deviations apart). A coordinate whose robust
//! standard deviation is zero (more than half its samples share one value) orders by the plain
//! standard deviation instead; one whose other samples share one value exactly with a least
//! standard deviation of zero is not tested in that round.

use super::{f_upper_quantile, median_and_robust_sigma};

/// A sample set aside as an outlier.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EsdOutlier {
    /// The sample (its index in the caller's slice).
    pub sample: usize,
    /// Its coordinate farthest out.
    pub coordinate: usize,
    /// Its externally studentised deviation along that coordinate.
    pub studentised: f64,
    /// The round's fence it exceeds.
    pub fence: f64,
}

/// The `t > 0` with `P(|T| > t) = tail` for Student's t with `dof` degrees of freedom
/// (`T^2` is `F(1, dof)`).
pub fn student_t_two_sided(tail: f64, dof: f64) -> f64 {
    f_upper_quantile(tail, 1.0, dof).sqrt()
}

/// The outliers among `samples` (module doc) at family-wise false-alarm rate `alpha`, at most
/// `max_outliers` of them (fewer when fewer than four samples would be left), in the order
/// they were set aside; each coordinate's standard deviations at least its `least_sigma`.
pub fn generalized_esd<const D: usize>(
    samples: &[[f64; D]],
    least_sigma: &[f64; D],
    alpha: f64,
    max_outliers: usize,
) -> Vec<EsdOutlier> {
    let mut kept: Vec<usize> = (0..samples.len()).collect();
    let mut rounds: Vec<EsdOutlier> = Vec::new();
    while rounds.len() < max_outliers && kept.len() >= 4 {
        let Some(worst) = extreme_deviate(samples, least_sigma, &kept) else {
            break;
        };
        let m = kept.len() as f64;
        let fence = student_t_two_sided(alpha / (max_outliers as f64 * m * D as f64), m - 2.0);
        kept.retain(|&j| j != worst.0);
        rounds.push(EsdOutlier {
            sample: worst.0,
            coordinate: worst.1,
            studentised: worst.2,
            fence,
        });
    }
    let count = rounds
        .iter()
        .rposition(|r| r.studentised > r.fence)
        .map_or(0, |last| last + 1);
    rounds.truncate(count);
    rounds
}

/// Among the samples `kept`, the one farthest out (module doc): its index, the coordinate of
/// its largest externally studentised deviation, and that deviation; `None` when no coordinate
/// has a scatter to test against.
fn extreme_deviate<const D: usize>(
    samples: &[[f64; D]],
    least_sigma: &[f64; D],
    kept: &[usize],
) -> Option<(usize, usize, f64)> {
    let (columns, scales) = columns_and_scales(samples, least_sigma, kept);
    let robust = |j: usize| {
        (0..D)
            .filter(|&k| scales[k].1 > 0.0)
            .map(|k| (columns[k][j] - scales[k].0).abs() / scales[k].1)
            .fold(0.0, f64::max)
    };
    let far = (0..kept.len()).max_by(|&a, &b| robust(a).total_cmp(&robust(b)))?;
    (0..D)
        .filter_map(|k| Some((kept[far], k, external_deviate(&columns[k], far, least_sigma[k])?)))
        .max_by(|a, b| a.2.total_cmp(&b.2))
}

/// How many of `samples` lie beyond `fence` robust standard deviations from the median along
/// some coordinate ([`median_and_robust_sigma`] of all samples, the plain standard deviation
/// where that is zero, at least `least_sigma`). More gross errors than [`generalized_esd`] has
/// rounds mask each other in every round; from the median they still stand out, so a caller
/// counts them here.
pub fn robustly_beyond<const D: usize>(samples: &[[f64; D]], least_sigma: &[f64; D], fence: f64) -> usize {
    let all: Vec<usize> = (0..samples.len()).collect();
    let (columns, scales) = columns_and_scales(samples, least_sigma, &all);
    (0..samples.len())
        .filter(|&j| (0..D).any(|k| scales[k].1 > 0.0 && (columns[k][j] - scales[k].0).abs() > fence * scales[k].1))
        .count()
}

/// The coordinates of the samples `kept`, column by column, and each column's robust centre
/// and scale ([`robust_centre_and_scale`]).
#[allow(clippy::type_complexity)]
fn columns_and_scales<const D: usize>(
    samples: &[[f64; D]],
    least_sigma: &[f64; D],
    kept: &[usize],
) -> (Vec<Vec<f64>>, Vec<(f64, f64)>) {
    let columns: Vec<Vec<f64>> = (0..D).map(|k| kept.iter().map(|&j| samples[j][k]).collect()).collect();
    let scales = columns
        .iter()
        .zip(least_sigma)
        .map(|(c, &least)| robust_centre_and_scale(c, least))
        .collect();
    (columns, scales)
}

/// A column's median and robust standard deviation, or its mean and standard deviation when
/// more than half its values share one (module doc); the deviation at least `least_sigma`.
fn robust_centre_and_scale(column: &[f64], least_sigma: f64) -> (f64, f64) {
    let (centre, sigma) = median_and_robust_sigma(column);
    if sigma > 0.0 {
        return (centre, sigma.max(least_sigma));
    }
    let mean = column.iter().sum::<f64>() / column.len() as f64;
    let s = (column.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (column.len() as f64 - 1.0)).sqrt();
    (mean, s.max(least_sigma))
}

/// The externally studentised deviation of `column[j]` from the others (module doc), their
/// standard deviation at least `least_sigma`; `None` when that is zero.
fn external_deviate(column: &[f64], j: usize, least_sigma: f64) -> Option<f64> {
    let others = || column.iter().enumerate().filter(|&(i, _)| i != j).map(|(_, &x)| x);
    let m1 = (column.len() - 1) as f64;
    let mean = others().sum::<f64>() / m1;
    let s = (others().map(|x| (x - mean).powi(2)).sum::<f64>() / (m1 - 1.0))
        .sqrt()
        .max(least_sigma);
    (s > 0.0).then(|| (column[j] - mean).abs() / (s * (1.0 + 1.0 / m1).sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::ChaCha12Rng;
    use rand_distr::{Distribution, StandardNormal};

    /// The t quantile against its closed forms: one degree of freedom is Cauchy
    /// (`t = tan(pi (1 - tail) / 2)`), two have `t = sqrt(2 / (tail (2 - tail)) - 2)`.
    #[test]
    fn t_quantile_closed_forms() {
        for tail in [0.5, 0.1, 1e-3, 1e-6] {
            let cauchy = (std::f64::consts::FRAC_PI_2 * (1.0 - tail)).tan();
            assert!((student_t_two_sided(tail, 1.0) / cauchy - 1.0).abs() < 1e-9, "{tail}");
            let two = (2.0 / (tail * (2.0 - tail)) - 2.0).sqrt();
            assert!((student_t_two_sided(tail, 2.0) / two - 1.0).abs() < 1e-9, "{tail}");
        }
    }

    /// The externally studentised deviation against its internal form: with
    /// `r = |x_j - mean| / s` over all `m`,
    /// `t = r sqrt(m (m - 2) / ((m - 1) (m - 1 - r^2 m / (m - 1))))` (from
    /// `x_j - mean_{-j} = (x_j - mean) m / (m - 1)` and
    /// `(m - 2) s_{-j}^2 = (m - 1) s^2 - (x_j - mean)^2 m / (m - 1)`).
    #[test]
    fn external_deviate_matches_the_internal_identity() {
        let column = [1.0, 2.5, -0.3, 0.7, 4.9, 1.1, 0.2];
        let m = column.len() as f64;
        let mean = column.iter().sum::<f64>() / m;
        let s = (column.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (m - 1.0)).sqrt();
        for j in 0..column.len() {
            let r = (column[j] - mean).abs() / s;
            let expected = r * (m * (m - 2.0) / ((m - 1.0) * (m - 1.0 - r * r * m / (m - 1.0)))).sqrt();
            let t = external_deviate(&column, j, 0.0).unwrap();
            assert!((t / expected - 1.0).abs() < 1e-12, "{j}: {t} {expected}");
        }
    }

    /// Gaussian samples of 6 coordinates: the share of sample sets with an outlier stays
    /// within `alpha` (plus 4 binomial sigmas of the trials) for 5 to 60 samples; one sample of
    /// 30 moved by 1000 sigmas along one coordinate, or three moved alike (masking each other
    /// in a single-outlier test), are found and nothing else is.
    #[test]
    fn false_alarms_hold_and_gross_errors_are_found() {
        let mut rng = ChaCha12Rng::seed_from_u64(9283);
        let mut draw = |n: usize| -> Vec<[f64; 6]> {
            (0..n)
                .map(|_| std::array::from_fn(|_| StandardNormal.sample(&mut rng)))
                .collect()
        };
        let (alpha, trials) = (0.05, 2000);
        for n in [5, 8, 12, 30, 60] {
            let alarms = (0..trials)
                .filter(|_| !generalized_esd(&draw(n), &[0.0; 6], alpha, n / 5 + 1).is_empty())
                .count();
            let bound = alpha + 4.0 * (alpha * (1.0 - alpha) / trials as f64).sqrt();
            assert!(
                (alarms as f64) / (trials as f64) <= bound,
                "n {n}: {alarms} of {trials}"
            );
        }
        let mut one = draw(30);
        one[17][4] += 1000.0;
        let found = generalized_esd(&one, &[0.0; 6], 0.01, 7);
        assert_eq!(
            found.iter().map(|o| (o.sample, o.coordinate)).collect::<Vec<_>>(),
            [(17, 4)]
        );
        let mut three = draw(30);
        for j in [3, 11, 25] {
            three[j][0] += 1000.0;
        }
        let mut found: Vec<usize> = generalized_esd(&three, &[0.0; 6], 0.01, 7)
            .iter()
            .map(|o| o.sample)
            .collect();
        found.sort_unstable();
        assert_eq!(found, [3, 11, 25]);
    }

    /// Forty samples rounded to steps of 0.01 (all alike but two one step off) and a coordinate
    /// computed from them (alike to the last bits but one): with zero least standard
    /// deviations the sample off by the last bits lies 1e5 of the others' out and is flagged;
    /// with the step and 1e-9 nothing is, and a sample twenty steps off is found alone.
    #[test]
    fn scatter_below_the_least_standard_deviation_is_not_judged() {
        let mut samples: Vec<[f64; 2]> = (0..40).map(|j| [1.0, 0.3 + 1e-16 * (j % 2) as f64]).collect();
        samples[5][0] = 1.01;
        samples[17][0] = 0.99;
        samples[23][1] = 0.3 + 1e-11;
        assert_eq!(
            generalized_esd(&samples, &[0.0; 2], 0.01, 9)
                .first()
                .map(|o| (o.sample, o.coordinate)),
            Some((23, 1))
        );
        let least = [0.01, 1e-9];
        assert!(generalized_esd(&samples, &least, 0.01, 9).is_empty());
        assert_eq!(robustly_beyond(&samples, &least, 5.0), 0);
        samples[30][0] = 1.2;
        let found: Vec<(usize, usize)> = generalized_esd(&samples, &least, 0.01, 9)
            .iter()
            .map(|o| (o.sample, o.coordinate))
            .collect();
        assert_eq!(found, [(30, 0)]);
        assert_eq!(robustly_beyond(&samples, &least, 5.0), 1);
    }

    /// Twenty-five of 200 samples moved alike by 1000 sigmas along one coordinate: they move the
    /// mean by 125 sigmas and inflate the standard deviation to about 330, so that each lies
    /// only 2.7 of them out, less than the largest good sample along another coordinate. The
    /// robust order sets them aside first; the 25, and nothing else, are found, with 26 rounds.
    #[test]
    fn many_gross_errors_alike_do_not_mask_each_other() {
        let mut rng = ChaCha12Rng::seed_from_u64(33);
        let mut samples: Vec<[f64; 6]> = (0..200)
            .map(|_| std::array::from_fn(|_| StandardNormal.sample(&mut rng)))
            .collect();
        let bad: Vec<usize> = (0..25).map(|i| 3 + 8 * i).collect();
        for &j in &bad {
            samples[j][1] += 1000.0;
        }
        let mut found: Vec<usize> = generalized_esd(&samples, &[0.0; 6], 0.01, 26)
            .iter()
            .map(|o| o.sample)
            .collect();
        found.sort_unstable();
        assert_eq!(found, bad);
    }
}
