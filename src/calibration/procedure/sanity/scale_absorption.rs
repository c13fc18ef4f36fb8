//! How much of a command column's scale a joint's fitted transmission takes up, and so the
//! smallest scale the transmission test names: Baarda's minimum detectable bias of the test's
//! statistic (Baarda 1968, "A testing procedure for use in geodetic networks", Netherlands
//! Geodetic Commission, Publications on Geodesy 2(5), sec. 3; Teunissen 2000, "Testing theory",
//! sec. 4.2: the bias `s d` an observation set carries is detectable where the part of it the
//! model does not take up, seen by the test, reaches the test's threshold plus its power margin).
//!
//! A column scaled by `1 + s` moves joint k's commanded position at each of its configurations
//! `j` by `s q_j` (`q_j` its commanded position in rad or m: a column's unit is a factor). The
//! fit explains a joint's commands by its transmission's coefficients and a zero offset (the
//! arc fit's start angle, the free-pose fit's offset): the columns `B` are a constant and
//! `d f(q_j) / d c_i` for each fitted coefficient `c_i` (`f` the transmission, eq. 8).
//! Least squares takes up `P q`, `P = B (B^T B)^-1 B^T`: the coefficients move by
//! `s (B^T B)^-1 B^T q`, which moves the fitted mean slope over the joint's range by `g s` (`g`
//! the share of the scale the test sees: 0.99 over a 50-deg sweep with one harmonic, 0.25 over
//! 320 deg), and leaves `s (I - P) q` in the fit's misses, which the a-posteriori noise takes
//! in: the slope's variance grows by `s^2 rho^2 a`, `rho^2 = |(I - P) q|^2 / (n - p)` the
//! misses' variance per unit scale and `a = sum_i (dm / dc_i)^2 [(B^T B)^-1]_ii` the mean slope
//! `m`'s variance per unit variance of a position (the coefficients' correlation left out, as
//! the test leaves it out). The test names a departure beyond `k` sigmas of the fit's (`sigma`)
//! and a drive's (`sigma_d`) combined, so it names every scale with
//! `|g s| > k sqrt(sigma^2 + sigma_d^2 + s^2 rho^2 a)`, that is beyond
//! `k sqrt(sigma^2 + sigma_d^2) / sqrt(g^2 - k^2 rho^2 a)`, and none where `g^2 <= k^2 rho^2 a`
//! (the fit takes the scale into the transmission as fast as the misses it leaves hide it).
//! The misses go into the noise the fit's sigmas are scaled by where that noise is estimated
//! from the residuals: pooled over `nu` degrees of freedom (coordinates less parameters) with
//! `m` points per configuration, the position variance per unit scale grows by
//! `m |(I - P) q|^2 / nu` (the angle misses of one joint put `r e_j` into one coordinate of a
//! point at lever `r`, whose sigma of angle is the coordinate noise over `r`), that is `rho^2`
//! times `m (n - p) / nu`; a given noise (`--noise-mm`) does not grow. The part of
//! a scale the geometry takes up (an axis' place or direction moving with the joint's angle) is
//! left out: the injection check of `docs/formats.md` ("Detection limits") measures that.

use crate::robot::Transmission;
use nalgebra::{DMatrix, DVector};

/// What a fitted transmission does with a command column's scale (module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Absorption {
    /// The share `g` of the scale that reaches the fitted mean slope over the range \[1\].
    pub transfer: f64,
    /// `rho^2 a`: the growth of the mean slope's variance (relative to the nominal slope's
    /// square) per squared unit scale, from the misses the scale leaves.
    pub spill: f64,
}

impl Absorption {
    /// The smallest scale a test that names departures beyond `k` sigmas of `sigma` (the
    /// fit's) and `drive` combined names whatever the scale's sign; `None` where no scale is
    /// named (module doc).
    pub fn smallest_named(&self, k: f64, sigma: f64, drive: f64) -> Option<f64> {
        let room = self.transfer.powi(2) - k.powi(2) * self.spill;
        let bound = k * sigma.hypot(drive) / room.sqrt();
        (room > 0.0 && bound.is_finite()).then_some(bound)
    }
}

/// The transmission with its fitted coefficients (`[sin.., cos..]` or `[c_1..]`) replaced.
pub fn with_coefficients(t: &Transmission, coefficients: &[f64]) -> Transmission {
    match t {
        Transmission::Harmonic { sin, .. } => Transmission::Harmonic {
            sin: coefficients[..sin.len()].to_vec(),
            cos: coefficients[sin.len()..].to_vec(),
        },
        Transmission::Gear { ratio, sin, .. } => Transmission::Gear {
            ratio: *ratio,
            sin: coefficients[..sin.len()].to_vec(),
            cos: coefficients[sin.len()..].to_vec(),
        },
        Transmission::Polynomial { c0, .. } => Transmission::Polynomial {
            c0: *c0,
            c: coefficients.to_vec(),
        },
    }
}

/// `(f(b) - f(a)) / (b - a)`.
pub fn mean_slope(t: &Transmission, (a, b): (f64, f64)) -> f64 {
    (t.value_and_slope(b).0 - t.value_and_slope(a).0) / (b - a)
}

/// Each fitted coefficient's column: `f` with the coefficient moved by one, less `f` (the
/// transmissions are linear in their coefficients).
fn coefficient_effects(t: &Transmission) -> Vec<Transmission> {
    let coefficients = t.coefficients();
    (0..coefficients.len())
        .map(|i| {
            let mut moved = coefficients.clone();
            moved[i] += 1.0;
            with_coefficients(t, &moved)
        })
        .collect()
}

/// How the noise that scales a fit's sigmas takes in the misses a scale leaves (module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NoiseSource {
    /// Given: it does not grow.
    Given,
    /// Estimated from the residuals: `(points per configuration, its degrees of freedom)`.
    Estimated(f64, f64),
}

/// The [`Absorption`] of transmission `t` fitted at the commanded positions `positions` (one
/// per configuration, rad or m), its mean slope taken over `range` against `nominal_slope`,
/// its sigma scaled by a noise from `noise`; every scale taken up (`transfer` 0) where the
/// positions are fewer than the fit's columns or leave them undetermined.
pub fn absorption(
    t: &Transmission,
    positions: &[f64],
    (range, nominal_slope): ((f64, f64), f64),
    noise: NoiseSource,
) -> Absorption {
    let taken = Absorption {
        transfer: 0.0,
        spill: 0.0,
    };
    let effects = coefficient_effects(t);
    let (n, p) = (positions.len(), effects.len() + 1);
    if n <= p || range.1 <= range.0 || nominal_slope == 0.0 {
        return taken;
    }
    let base: Vec<f64> = positions.iter().map(|&q| t.value_and_slope(q).0).collect();
    let b = DMatrix::from_fn(n, p, |j, c| match c {
        0 => 1.0,
        _ => effects[c - 1].value_and_slope(positions[j]).0 - base[j],
    });
    let q = DVector::from_column_slice(positions);
    let Some(inverse) = (b.transpose() * &b).try_inverse() else {
        return taken;
    };
    let moved = &inverse * b.transpose() * &q;
    let misses = &q - &b * &moved;
    let at_range = mean_slope(t, range);
    let gradient: Vec<f64> = effects
        .iter()
        .map(|e| (mean_slope(e, range) - at_range) / nominal_slope)
        .collect();
    let transfer: f64 = gradient.iter().enumerate().map(|(i, g)| g * moved[i + 1]).sum();
    let per_position: f64 = gradient
        .iter()
        .enumerate()
        .map(|(i, g)| g * g * inverse[(i + 1, i + 1)])
        .sum();
    let growth = match noise {
        NoiseSource::Given => 0.0,
        NoiseSource::Estimated(targets, dof) if dof > 0.0 => targets * misses.norm_squared() / dof,
        NoiseSource::Estimated(..) => misses.norm_squared() / (n - p) as f64,
    };
    let spill = growth * per_position;
    if !(transfer.is_finite() && spill.is_finite()) {
        return taken;
    }
    Absorption {
        transfer: transfer.abs(),
        spill,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A noise estimated from the joint's own configurations alone.
    const OWN: NoiseSource = NoiseSource::Estimated(1.0, 0.0);

    /// `n` positions evenly over `span_deg` centred on 0 \[rad\].
    fn sweep(span_deg: f64, n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| (-span_deg / 2.0 + span_deg * i as f64 / (n - 1) as f64).to_radians())
            .collect()
    }

    fn first_harmonic() -> Transmission {
        Transmission::Harmonic {
            sin: vec![0.001],
            cos: vec![-0.002],
        }
    }

    /// A second path: the share `g` is what a refit of the scaled positions moves the mean
    /// slope by, with the least squares solved by an independent route (QR of `B`), and the
    /// spill the refit's misses times the slope's variance per position.
    #[test]
    fn the_share_and_spill_match_a_refit_of_the_scaled_positions() {
        for (span, n) in [(50.0, 9), (180.0, 12), (320.0, 11)] {
            let positions = sweep(span, n);
            let range = (positions[0], positions[n - 1]);
            let t = first_harmonic();
            let found = absorption(
                &t,
                &positions,
                (range, 1.0),
                NoiseSource::Estimated(1.0, (n - 3) as f64),
            );
            let s = 1e-3;
            // f(q) = q + a sin q + b cos q + c fitted to (1 + s) f_0(q).
            let b = DMatrix::from_fn(n, 3, |j, c| match c {
                0 => 1.0,
                1 => positions[j].sin(),
                _ => positions[j].cos(),
            });
            let target = DVector::from_fn(n, |j, _| s * positions[j]);
            let x = b.clone().svd(true, true).solve(&target, 1e-14).unwrap();
            let g_sin = (range.1.sin() - range.0.sin()) / (range.1 - range.0);
            let g_cos = (range.1.cos() - range.0.cos()) / (range.1 - range.0);
            let refit_share = (g_sin * x[1] + g_cos * x[2]).abs() / s;
            assert!(
                (refit_share - found.transfer).abs() < 1e-9,
                "{span}: {refit_share} {found:?}"
            );
            let misses = (&target - &b * &x).norm_squared() / (s * s * (n - 3) as f64);
            let inverse = (b.transpose() * &b).try_inverse().unwrap();
            let spill = misses * (g_sin.powi(2) * inverse[(1, 1)] + g_cos.powi(2) * inverse[(2, 2)]);
            assert!(
                (spill - found.spill).abs() <= 1e-9 * spill.max(1e-12),
                "{span}: {spill} {found:?}"
            );
        }
    }

    /// Over a short sweep the first harmonic carries nearly the whole scale into the mean
    /// slope; over most of a turn little of it, and the misses hide the rest.
    #[test]
    fn a_short_sweep_shows_a_scale_and_most_of_a_turn_hides_it() {
        let short = sweep(50.0, 11);
        let a = absorption(&first_harmonic(), &short, ((short[0], short[10]), 1.0), OWN);
        assert!(a.transfer > 0.98, "{a:?}");
        let bound = a.smallest_named(6.0, 0.0, 0.0012).unwrap();
        assert!(bound > 6.0 * 0.0012 && bound < 6.0 * 0.0012 / 0.98, "{bound}");
        let turn = sweep(340.0, 16);
        let a = absorption(&first_harmonic(), &turn, ((turn[0], turn[15]), 1.0), OWN);
        assert!(a.transfer < 0.2, "{a:?}");
        assert_eq!(a.smallest_named(6.0, 0.0, 0.0012), None, "{a:?}");
    }

    /// A slide's linear lead term takes the scale whole into its slope, leaving no misses.
    #[test]
    fn a_lead_term_carries_a_scale_whole() {
        let t = Transmission::Polynomial { c0: 0.0, c: vec![0.0] };
        let positions: Vec<f64> = (0..8).map(|i| 0.05 * i as f64).collect();
        let a = absorption(&t, &positions, ((0.0, 0.35), 1.0), OWN);
        assert!((a.transfer - 1.0).abs() < 1e-9 && a.spill < 1e-20, "{a:?}");
    }

    /// A given noise does not take the misses in: a wide sweep still shows a scale.
    #[test]
    fn a_given_noise_keeps_a_wide_sweeps_bound() {
        let turn = sweep(340.0, 16);
        let range = (turn[0], turn[15]);
        let own = absorption(&first_harmonic(), &turn, (range, 1.0), OWN);
        let given = absorption(&first_harmonic(), &turn, (range, 1.0), NoiseSource::Given);
        assert_eq!(own.smallest_named(6.0, 0.0, 0.0012), None, "{own:?}");
        let bound = given.smallest_named(6.0, 0.0, 0.0012).unwrap();
        assert!(
            (bound - 6.0 * 0.0012 / given.transfer).abs() < 1e-12,
            "{bound} {given:?}"
        );
    }

    /// Fewer configurations than the fit's columns: the fit takes any scale.
    #[test]
    fn too_few_configurations_take_every_scale() {
        let a = absorption(&first_harmonic(), &[0.0, 0.1, 0.2], ((0.0, 0.2), 1.0), OWN);
        assert_eq!(a.smallest_named(6.0, 0.001, 0.0012), None);
    }
}
