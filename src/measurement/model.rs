//! The measurement model used by the simulator: what the instrument reports for a true
//! target position.

use super::noise_calibration::{NoiseCalibration, PAPER_NET_RADIAL_RMS_MM};
use super::theodolite::{TheodolitePair, TriangulationError};
use nalgebra::{Matrix3, Point3, Vector3};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// Isotropic Gaussian position noise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct IsotropicNoise {
    /// 3-D RMS of the error vector \[mm\]; each axis gets `net_radial_rms_mm / sqrt(3)`.
    pub net_radial_rms_mm: f64,
}

impl IsotropicNoise {
    /// Standard deviation along each axis \[m\].
    pub fn sigma_per_axis_m(&self) -> f64 {
        self.net_radial_rms_mm * 1e-3 / 3f64.sqrt()
    }
}

/// How measured target positions are generated from true ones.
///
/// In a scenario TOML: `kind = "theodolite"` with the fields of [`TheodolitePair`], or
/// `kind = "isotropic"` with `net_radial_rms_mm`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum MeasurementModel {
    /// Two theodolites with angular noise; the point is triangulated.
    Theodolite(TheodolitePair),
    /// Isotropic Gaussian noise on each coordinate.
    Isotropic(IsotropicNoise),
}

impl MeasurementModel {
    /// The paper's instrument: two theodolites calibrated to 0.19 mm net radial error
    /// (see [`TheodolitePair::paper`]), with the calibration report.
    pub fn paper_theodolites() -> Result<(Self, NoiseCalibration), TriangulationError> {
        let (pair, calibration) = TheodolitePair::paper()?;
        Ok((Self::Theodolite(pair), calibration))
    }

    /// Two theodolites at `stations_m` (`[left, right]`, instrument frame \[m\]) calibrated to
    /// the paper's 0.19 mm net radial error around a robot base at `base_m`
    /// ([`TheodolitePair::around_robot_base`]), with the calibration report.
    pub fn theodolites_around(
        stations_m: [Point3<f64>; 2],
        base_m: &Point3<f64>,
    ) -> Result<(Self, NoiseCalibration), TriangulationError> {
        let (pair, calibration) =
            TheodolitePair::around_robot_base(stations_m, base_m, PAPER_NET_RADIAL_RMS_MM * 1e-3)?;
        Ok((Self::Theodolite(pair), calibration))
    }

    /// Isotropic noise with the paper's 0.19 mm net radial error.
    pub fn paper_isotropic() -> Self {
        Self::Isotropic(IsotropicNoise {
            net_radial_rms_mm: PAPER_NET_RADIAL_RMS_MM,
        })
    }

    /// One simulated measurement of the true point `p_world_m` (instrument frame) \[m\].
    pub fn measure<R: Rng + ?Sized>(
        &self,
        p_world_m: &Point3<f64>,
        rng: &mut R,
    ) -> Result<Point3<f64>, TriangulationError> {
        match self {
            Self::Theodolite(pair) => pair.measure(p_world_m, rng),
            Self::Isotropic(noise) => {
                let sigma_m = noise.sigma_per_axis_m();
                let e = Vector3::from_fn(|_, _| {
                    let z: f64 = StandardNormal.sample(rng);
                    sigma_m * z
                });
                Ok(p_world_m + e)
            }
        }
    }

    /// First-order covariance of a measurement at `p_world_m` \[m^2\].
    pub fn covariance_m2(&self, p_world_m: &Point3<f64>) -> Result<Matrix3<f64>, TriangulationError> {
        match self {
            Self::Theodolite(pair) => pair.covariance_m2(p_world_m),
            Self::Isotropic(noise) => Ok(Matrix3::identity() * noise.sigma_per_axis_m().powi(2)),
        }
    }

    /// The instrument's station centres \[m\], from which lines of sight start; empty for a
    /// model without stations (isotropic: every target is visible).
    pub fn stations_m(&self) -> Vec<Point3<f64>> {
        match self {
            Self::Theodolite(pair) => pair.stations_m().to_vec(),
            Self::Isotropic(_) => Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measurement::noise_calibration::{PAPER_ROBOT_BASE_MM, ReferenceVolume};
    use approx::assert_relative_eq;
    use rand::SeedableRng;
    use rand::rngs::ChaCha12Rng;
    use rand_distr::Uniform;

    const SAMPLES: usize = 10_000;

    fn robot_base_m() -> Point3<f64> {
        Point3::from(Vector3::from(PAPER_ROBOT_BASE_MM)) * 1e-3
    }

    /// Empirical 3-D RMS error over random points of the reference volume must match the
    /// calibrated 0.19 mm. Sampling error of a mean square over n samples of a sum of 3
    /// squared Gaussians is about sqrt(2/(3n)) relative (~0.8 % for n = 1e4), plus the
    /// point-to-point spread of the trace; 5 % is several standard errors.
    fn check_net_radial(model: &MeasurementModel, seed: u64) {
        let volume = ReferenceVolume::paper();
        let half = volume.side_m / 2.0;
        let coordinate = Uniform::new(-half, half).unwrap();
        let mut rng = ChaCha12Rng::seed_from_u64(seed);
        let mut sum_m2 = 0.0;
        for _ in 0..SAMPLES {
            let offset = Vector3::from_fn(|_, _| coordinate.sample(&mut rng));
            let p = volume.centre_m + offset;
            let q = model.measure(&p, &mut rng).unwrap();
            sum_m2 += (q - p).norm_squared();
        }
        let rms_mm = (sum_m2 / SAMPLES as f64).sqrt() * 1e3;
        assert_relative_eq!(rms_mm, PAPER_NET_RADIAL_RMS_MM, max_relative = 0.05);
    }

    #[test]
    fn theodolite_net_radial_error_is_paper_value() {
        let (model, _) = MeasurementModel::paper_theodolites().unwrap();
        check_net_radial(&model, 1);
    }

    #[test]
    fn isotropic_net_radial_error_is_paper_value() {
        check_net_radial(&MeasurementModel::paper_isotropic(), 2);
    }

    /// Empirical covariance at one point agrees with the first-order `covariance_m2`.
    /// The variance estimate along a unit direction v has relative standard error
    /// sqrt(2/n); a covariance entry (i, j) has standard error sqrt((S_ii S_jj + S_ij^2)/n).
    /// Tolerance: 4 standard errors.
    fn check_covariance(model: &MeasurementModel, seed: u64) {
        let p = robot_base_m() + Vector3::new(0.3, -0.2, 0.8);
        let mut rng = ChaCha12Rng::seed_from_u64(seed);
        let errors: Vec<Vector3<f64>> = (0..SAMPLES).map(|_| model.measure(&p, &mut rng).unwrap() - p).collect();
        let n = SAMPLES as f64;
        let mean = errors.iter().sum::<Vector3<f64>>() / n;
        let empirical = errors
            .iter()
            .map(|e| (e - mean) * (e - mean).transpose())
            .sum::<Matrix3<f64>>()
            / (n - 1.0);
        let predicted = model.covariance_m2(&p).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let standard_error = ((predicted[(i, i)] * predicted[(j, j)] + predicted[(i, j)].powi(2)) / n).sqrt();
                let difference = (empirical[(i, j)] - predicted[(i, j)]).abs();
                assert!(
                    difference < 4.0 * standard_error,
                    "entry ({i},{j}): empirical {} vs predicted {} (se {standard_error})",
                    empirical[(i, j)],
                    predicted[(i, j)]
                );
            }
        }
    }

    #[test]
    fn theodolite_empirical_covariance_matches_first_order() {
        let (model, _) = MeasurementModel::paper_theodolites().unwrap();
        check_covariance(&model, 3);
    }

    #[test]
    fn isotropic_empirical_covariance_matches() {
        check_covariance(&MeasurementModel::paper_isotropic(), 4);
    }

    #[test]
    fn same_seed_gives_bit_identical_measurements() {
        let (model, _) = MeasurementModel::paper_theodolites().unwrap();
        let p = robot_base_m();
        let run = |seed| {
            let mut rng = ChaCha12Rng::seed_from_u64(seed);
            (0..10)
                .map(|_| model.measure(&p, &mut rng).unwrap().coords.map(f64::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(run(7), run(7));
    }

    #[test]
    fn model_round_trips_through_toml_and_rejects_unknown_keys() {
        let (model, _) = MeasurementModel::paper_theodolites().unwrap();
        let text = toml::to_string(&model).unwrap();
        let back: MeasurementModel = toml::from_str(&text).unwrap();
        assert_eq!(back, model);
        let iso: MeasurementModel = toml::from_str("kind = \"isotropic\"\nnet_radial_rms_mm = 0.19\n").unwrap();
        assert_eq!(iso, MeasurementModel::paper_isotropic());
        let typo = toml::from_str::<MeasurementModel>("kind = \"isotropic\"\nnet_radial_rms = 0.19\n");
        assert!(typo.is_err());
        assert_eq!(model.stations_m().len(), 2);
    }
}
