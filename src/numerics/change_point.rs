//! A block of a sequence of 3-D residuals (file order) whose mean sits off the others': the
//! change-point test of an instrument bumped part-way through a measurement.
//!
//! For every block of consecutive elements (at least `min_block` inside and outside) the
//! two-sample Hotelling `T^2` of the block's mean against the others', with the within-group
//! pooled covariance (Mardia, Kent & Bibby, *Multivariate Analysis*, 1979, sec. 3.6.1), finds
//! the block; that block is then tested with the long-run (serially correlated) covariance of
//! the within-group residuals (`serial_test`), its `T^2` read as Hotelling's, an
//! `F(3, n - 4)` multiple, without a shift. The caller multiplies the p-value by the blocks
//! tried (Bonferroni over the candidate change points) and holds it against its false-alarm
//! rate.

use super::stats::f_upper_tail;
use nalgebra::{Matrix3, Vector3};

/// Which blocks are candidates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blocks {
    /// Every block `a..b` with `0 < a` (a block from the first element is the complement of one
    /// to the end).
    Any,
    /// Only blocks that run to the end: one change point, as an instrument moved once and left
    /// there.
    ToEnd,
}

/// The most significant block `start..end` of a sequence (indices into it).
#[derive(Clone, Debug, PartialEq)]
pub struct ChangePoint {
    /// The block's first element.
    pub start: usize,
    /// One past its last.
    pub end: usize,
    /// Its p-value under the serial test, before the multiple-test correction.
    pub p_value: f64,
    /// Blocks tried.
    pub tried: usize,
    /// How much the serial correlation widens the block's test (the plain `T^2` over the
    /// serial one, at least 1).
    pub inflation: f64,
}

/// The block of `x` whose mean differs most significantly from the others' (module docs),
/// among `blocks` with at least `min_block` elements inside and outside; `None` for a sequence
/// too short to test (fewer than `2 min_block` or 6 elements) or a degenerate covariance.
pub fn most_significant_block(x: &[Vector3<f64>], min_block: usize, blocks: Blocks) -> Option<ChangePoint> {
    let n = x.len();
    if n < 2 * min_block || n < 6 {
        return None;
    }
    let centre = x.iter().sum::<Vector3<f64>>() / n as f64;
    let x: Vec<Vector3<f64>> = x.iter().map(|v| v - centre).collect();
    let mut prefix = vec![Vector3::zeros(); n + 1];
    let mut total = Matrix3::zeros();
    for (i, v) in x.iter().enumerate() {
        prefix[i + 1] = prefix[i] + v;
        total += v * v.transpose();
    }
    let nf = n as f64;
    let (mut best, mut tried) = (None::<(f64, usize, usize)>, 0);
    for a in 1..n {
        let first_end = match blocks {
            Blocks::Any => a + min_block,
            Blocks::ToEnd => n,
        };
        for b in first_end..=n {
            let (inside, outside) = ((b - a) as f64, (n - (b - a)) as f64);
            if n - (b - a) < min_block {
                break;
            }
            if b - a < min_block {
                continue;
            }
            tried += 1;
            let sum_in = prefix[b] - prefix[a];
            let (m1, m0) = (sum_in / inside, (prefix[n] - sum_in) / outside);
            let within = (total - m1 * m1.transpose() * inside - m0 * m0.transpose() * outside) / (nf - 2.0);
            let d = m1 - m0;
            let Some(ch) = within.cholesky() else { continue };
            let t2 = inside * outside / nf * d.dot(&ch.solve(&d));
            if best.is_none_or(|(t, _, _)| t2 > t) {
                best = Some((t2, a, b));
            }
        }
    }
    let (t2, start, end) = best?;
    let (t2_serial, p_value) = serial_test(&x, start, end)?;
    Some(ChangePoint {
        start,
        end,
        p_value,
        tried,
        inflation: (t2 / t2_serial).max(1.0),
    })
}

/// The block `start..end` of `x` (centred) tested with the long-run covariance of the
/// within-group residuals instead of their plain covariance: Bartlett weights over
/// `floor(4 (n / 100)^(2/9))` lags (Newey & West, *Rev. Econ. Stud.* 61, 1994, eq. 3.8;
/// Andrews, *Econometrica* 61, 1993, for the change-point test with it), `T^2` then about
/// `chi^2(3)` without a shift. The poses of a real file in file order share unmodelled errors
/// with their neighbours (the real FANUC's: lag-1 correlation 0.7 in z), which the plain
/// covariance takes for independent scatter. Returns `T^2` and its p-value (Hotelling's `F`).
fn serial_test(x: &[Vector3<f64>], start: usize, end: usize) -> Option<(f64, f64)> {
    let n = x.len();
    let inside = |i: usize| (start..end).contains(&i);
    let mean_of = |want: bool| {
        let v: Vec<&Vector3<f64>> = (0..n).filter(|&i| inside(i) == want).map(|i| &x[i]).collect();
        v.iter().copied().sum::<Vector3<f64>>() / v.len() as f64
    };
    let (m1, m0) = (mean_of(true), mean_of(false));
    let e: Vec<Vector3<f64>> = (0..n).map(|i| x[i] - if inside(i) { m1 } else { m0 }).collect();
    let lags = (4.0 * (n as f64 / 100.0).powf(2.0 / 9.0)).floor() as usize;
    let autocovariance =
        |l: usize| -> Matrix3<f64> { (l..n).map(|i| e[i] * e[i - l].transpose()).sum::<Matrix3<f64>>() / n as f64 };
    let mut long_run = autocovariance(0);
    for l in 1..=lags.min(n - 1) {
        let g = autocovariance(l);
        long_run += (g + g.transpose()) * (1.0 - l as f64 / (lags + 1) as f64);
    }
    let (n1, n0) = ((end - start) as f64, (n - (end - start)) as f64);
    let d = m1 - m0;
    let t2 = n1 * n0 / n as f64 * d.dot(&long_run.cholesky()?.solve(&d));
    // Hotelling's two-sample `T^2` on `nu = n - 2` degrees of freedom of the covariance is
    // `nu p / (nu - p + 1)` times an `F(p, nu - p + 1)` (Mardia, Kent & Bibby, eq. 3.6.4,
    // `p = 3`); its tail, far heavier than `chi^2(3)`'s at the Bonferroni level over thousands
    // of blocks, keeps the family-wise rate on white noise.
    let nu = n as f64 - 2.0;
    Some((t2, f_upper_tail(t2 * (nu - 2.0) / (3.0 * nu), 3.0, nu - 2.0)))
}

/// The mean of `x[start..end]` less the mean of the others.
pub fn step_of(x: &[Vector3<f64>], start: usize, end: usize) -> Vector3<f64> {
    let inside: Vector3<f64> = x[start..end].iter().sum();
    let all: Vector3<f64> = x.iter().sum();
    inside / (end - start) as f64 - (all - inside) / (x.len() - (end - start)) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent draws of a fixed-seed generator, 3-D, scale 1.
    fn noise(n: usize, seed: u64) -> Vec<Vector3<f64>> {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand::rngs::ChaCha12Rng::seed_from_u64(seed);
        (0..n)
            .map(|_| Vector3::from_fn(|_, _| StandardNormal.sample(&mut rng)))
            .collect()
    }

    /// A step of 3 sigma in z over the poses 40..70 of 100 is found there (a change point's
    /// place is off by more than one pose with odds of about `Phi(-3 / sqrt 2)^2` per side);
    /// clean noise's smallest p-value times the blocks tried stays above the false-alarm rate
    /// on 20 seeds.
    #[test]
    fn a_middle_block_is_found_and_noise_is_quiet() {
        let mut x = noise(100, 7);
        x[40..70].iter_mut().for_each(|v| v.z += 3.0);
        let f = most_significant_block(&x, 3, Blocks::Any).unwrap();
        assert!(
            f.start.abs_diff(40) <= 1 && f.end.abs_diff(70) <= 1,
            "{}..{}",
            f.start,
            f.end
        );
        assert!(f.p_value * (f.tried as f64) < 1e-4);
        for seed in 0..20 {
            let f = most_significant_block(&noise(100, seed), 3, Blocks::Any).unwrap();
            assert!(f.p_value * (f.tried as f64) > 1e-4, "seed {seed}: {}", f.p_value);
        }
    }

    /// A step to the end is found at its place among the blocks to the end only (`n - 2 min`
    /// + 1 of them), and noise stays quiet on 20 seeds there too.
    #[test]
    fn a_step_to_the_end_is_found_among_blocks_to_the_end() {
        let mut x = noise(16, 3);
        x[11..].iter_mut().for_each(|v| v.y += 6.0);
        let f = most_significant_block(&x, 3, Blocks::ToEnd).unwrap();
        assert_eq!((f.start, f.end, f.tried), (11, 16, 11));
        assert!(f.p_value * (f.tried as f64) < 1e-4, "{}", f.p_value);
        let s = step_of(&x, f.start, f.end);
        assert!((s.y - 6.0).abs() < 4.0 * (1.0 / 5.0 + 1.0 / 11.0f64).sqrt(), "{s}");
        for seed in 0..20 {
            let f = most_significant_block(&noise(16, 100 + seed), 3, Blocks::ToEnd).unwrap();
            assert!(f.p_value * (f.tried as f64) > 1e-4, "seed {seed}: {}", f.p_value);
        }
    }
}
