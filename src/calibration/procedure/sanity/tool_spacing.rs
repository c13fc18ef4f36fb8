//! A second path to a tool-fit misfit ([`super::Implausible::ToolMisfit`]): the distances
//! between the measured tool targets against the description's, with no fit. When one scale
//! factor brings every spacing within its noise, the coordinates (or the described targets) are
//! scaled, which the rigid tool fit reads as a point off.

/// The outlier test's multiple of a spacing's noise: beyond it, the spacings disagree.
pub const SPACING_SIGMAS: f64 = 3.0;

/// The measured tool targets' spacings as one scale of the described ones.
#[derive(Clone, Debug, PartialEq)]
pub struct SpacingScale {
    /// Measured over described spacing, the least-squares factor \[1\].
    pub scale: f64,
    /// Its 1-sigma \[1\].
    pub sigma: f64,
    /// The largest spacing's departure from `scale` times the described one \[mm\].
    pub worst_mm: f64,
}

/// The [`SpacingScale`] of the targets `measured` (each its index into `described_mm` and its
/// position \[mm\], one pose) against `described_mm` (`[tool] targets_mm`), with `noise_rms_3d_mm`
/// the measurement's 3-D noise: when `scale` brings every spacing within [`SPACING_SIGMAS`] of
/// its noise and departs from 1 by more than that many of its own sigma. The factor is
/// `s = sum(m d) / sum(d^2)` over the pairs of distinct targets (measured spacing `m`, described
/// `d`); a spacing's noise is a difference of two points' distance, `sqrt(2)` times a coordinate's
/// (the 3-D RMS over root 3); the factor's sigma is that over `sqrt(sum(d^2))`. `None` with fewer
/// than two spacings.
pub fn tool_spacing_scale(
    measured: &[(usize, [f64; 3])],
    described_mm: &[[f64; 3]],
    noise_rms_3d_mm: f64,
) -> Option<SpacingScale> {
    let distance = |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
    let pairs: Vec<(f64, f64)> = measured
        .iter()
        .enumerate()
        .flat_map(|(i, a)| measured[i + 1..].iter().map(move |b| (a, b)))
        .filter(|(a, b)| a.0 != b.0 && a.0 < described_mm.len() && b.0 < described_mm.len())
        .map(|(a, b)| (distance(&a.1, &b.1), distance(&described_mm[a.0], &described_mm[b.0])))
        .collect();
    let squares: f64 = pairs.iter().map(|(_, d)| d * d).sum();
    if pairs.len() < 2 || squares <= 0.0 {
        return None;
    }
    let scale = pairs.iter().map(|(m, d)| m * d).sum::<f64>() / squares;
    let spacing_sigma_mm = std::f64::consts::SQRT_2 * noise_rms_3d_mm / 3f64.sqrt();
    let worst_mm = pairs.iter().map(|(m, d)| (m - scale * d).abs()).fold(0.0, f64::max);
    let sigma = spacing_sigma_mm / squares.sqrt();
    let agrees = worst_mm <= SPACING_SIGMAS * spacing_sigma_mm;
    (agrees && (scale - 1.0).abs() > SPACING_SIGMAS * sigma).then_some(SpacingScale { scale, sigma, worst_mm })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Vector3};

    const DESCRIBED: [[f64; 3]; 3] = [[0.0, 0.0, 100.0], [80.0, 0.0, 100.0], [0.0, 60.0, 100.0]];

    /// The described targets scaled by `scale`, turned and moved (a rigid motion keeps the
    /// spacings), one of them `off_mm` along x.
    fn measured(scale: f64, off_mm: f64) -> Vec<(usize, [f64; 3])> {
        let turn = Rotation3::from_euler_angles(0.3, -0.7, 1.1);
        DESCRIBED
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let q = turn * (Vector3::from(*p) * scale) + Vector3::new(500.0, -200.0, 900.0);
                let off = if i == 1 { off_mm } else { 0.0 };
                (i, [q.x + off, q.y, q.z])
            })
            .collect()
    }

    #[test]
    fn a_scale_is_read_from_the_spacings_whatever_the_pose() {
        let found = tool_spacing_scale(&measured(1.01, 0.0), &DESCRIBED, 0.2).unwrap();
        assert!((found.scale - 1.01).abs() < 1e-12, "{found:?}");
        assert!(found.worst_mm < 1e-9);
        // The sigma by its formula: sqrt(2/3) * 0.2 mm over the root of the summed squared
        // spacings 80^2 + 60^2 + 100^2.
        let expected_sigma = (2.0f64 / 3.0).sqrt() * 0.2 / (80f64.powi(2) + 60f64.powi(2) + 100f64.powi(2)).sqrt();
        assert!((found.sigma - expected_sigma).abs() < 1e-15);
    }

    #[test]
    fn no_scale_is_said_for_a_point_off_or_a_scale_within_the_noise() {
        assert_eq!(tool_spacing_scale(&measured(1.0, 20.0), &DESCRIBED, 0.2), None);
        // 3 sigma of the scale is 3 * 0.00116 here: 1.002 is within it.
        assert_eq!(tool_spacing_scale(&measured(1.002, 0.0), &DESCRIBED, 0.2), None);
        assert!(tool_spacing_scale(&measured(1.005, 0.0), &DESCRIBED, 0.2).is_some());
        assert_eq!(tool_spacing_scale(&measured(1.01, 0.0)[..2], &DESCRIBED, 0.2), None);
    }
}
