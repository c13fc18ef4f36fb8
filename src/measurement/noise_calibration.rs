//! Calibrating the theodolites' angular noise to a quoted net radial error, and describing
//! the resulting anisotropy.
//!
//! The paper quotes one number for its instrument, "net radial error 0.19 mm" (section 4),
//! read as the 3-D RMS of the error vector. Angular noise maps into position through the
//! triangulation Jacobian, so the error is larger along the lines of sight (depth) than
//! across them. The angular sigma is chosen so the mean of `trace(covariance)` over a
//! reference volume around the robot equals `0.19^2 mm^2`; since the first-order covariance
//! scales with `sigma^2`, this is one closed-form scaling.

use super::theodolite::{TheodolitePair, TriangulationError};
use nalgebra::{Point3, SymmetricEigen, Unit, Vector3};
use serde::{Deserialize, Serialize};
use std::fmt;

/// The paper's net radial error of the instrument \[mm\] (section 4).
pub const PAPER_NET_RADIAL_RMS_MM: f64 = 0.19;
/// Robot base placement in the instrument frame \[mm\] (paper's measured axis 1).
pub const PAPER_ROBOT_BASE_MM: [f64; 3] = [-3142.3, 4439.4, -526.1];
/// Default right-station position \[mm\]: on the x axis, so the robot sees a symmetric pair.
pub const PAPER_RIGHT_STATION_MM: [f64; 3] = [-6284.6, 0.0, 0.0];

/// A cube of points over which the net radial error is averaged.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ReferenceVolume {
    /// Centre of the cube in the instrument frame \[m\].
    #[schemars(with = "[f64; 3]")]
    pub centre_m: Point3<f64>,
    /// Edge length \[m\].
    pub side_m: f64,
    /// Grid points along each edge (at least 1; 1 means the centre only).
    pub points_per_side: usize,
}

impl ReferenceVolume {
    /// A 2 m cube centred 0.5 m above the robot base placement `base_m`, 9 points per edge.
    pub fn around_robot_base(base_m: &Point3<f64>) -> Self {
        Self {
            centre_m: base_m + Vector3::new(0.0, 0.0, 0.5),
            side_m: 2.0,
            points_per_side: 9,
        }
    }

    /// [`Self::around_robot_base`] at the paper's robot placement.
    pub fn paper() -> Self {
        Self::around_robot_base(&(Point3::from(Vector3::from(PAPER_ROBOT_BASE_MM)) * 1e-3))
    }

    /// The grid points (regular, including the faces of the cube).
    pub fn grid_points(&self) -> Vec<Point3<f64>> {
        let n = self.points_per_side.max(1);
        let coordinate = |i: usize| {
            if n == 1 {
                0.0
            } else {
                self.side_m * (i as f64 / (n - 1) as f64 - 0.5)
            }
        };
        let mut points = Vec::with_capacity(n * n * n);
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    points.push(self.centre_m + Vector3::new(coordinate(i), coordinate(j), coordinate(k)));
                }
            }
        }
        points
    }
}

/// The shape of the measurement covariance at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Anisotropy {
    /// Where \[m\].
    pub point_m: Point3<f64>,
    /// Principal standard deviations, largest first \[m\].
    pub principal_sigmas_m: [f64; 3],
    /// The matching principal directions.
    pub principal_axes: [Unit<Vector3<f64>>; 3],
}

impl Anisotropy {
    /// The principal axes of `covariance_m2` at `p_m`.
    pub fn of(pair: &TheodolitePair, p_m: &Point3<f64>) -> Result<Self, TriangulationError> {
        let eigen = SymmetricEigen::new(pair.covariance_m2(p_m)?);
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
        Ok(Self {
            point_m: *p_m,
            principal_sigmas_m: order.map(|i| eigen.eigenvalues[i].max(0.0).sqrt()),
            principal_axes: order.map(|i| Unit::new_normalize(eigen.eigenvectors.column(i).into_owned())),
        })
    }

    /// Largest over smallest principal standard deviation (depth over lateral).
    pub fn ratio(&self) -> f64 {
        self.principal_sigmas_m[0] / self.principal_sigmas_m[2]
    }

    /// 3-D RMS of the error vector at this point \[m\].
    pub fn radial_rms_m(&self) -> f64 {
        self.principal_sigmas_m.iter().map(|s| s * s).sum::<f64>().sqrt()
    }
}

impl fmt::Display for Anisotropy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [a, b, c] = self.principal_sigmas_m.map(|s| s * 1e3);
        let axis = self.principal_axes[0];
        let p = self.point_m * 1e3;
        write!(
            f,
            "at ({:.1}, {:.1}, {:.1}) mm: principal sigmas {a:.4}, {b:.4}, {c:.4} mm \
             (largest along ({:.3}, {:.3}, {:.3})), ratio {:.2}, radial RMS {:.4} mm",
            p.x,
            p.y,
            p.z,
            axis.x,
            axis.y,
            axis.z,
            self.ratio(),
            self.radial_rms_m() * 1e3
        )
    }
}

/// The outcome of [`TheodolitePair::calibrated`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseCalibration {
    /// Calibrated azimuth reading sigma \[rad\].
    pub sigma_az_rad: f64,
    /// Calibrated elevation reading sigma \[rad\].
    pub sigma_el_rad: f64,
    /// The net radial error it reproduces over the volume \[m\].
    pub net_radial_rms_m: f64,
    /// The volume it was averaged over.
    pub volume: ReferenceVolume,
    /// Covariance shape at the centre of the volume.
    pub at_centre: Anisotropy,
}

impl fmt::Display for NoiseCalibration {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "theodolite noise: sigma_az {:.3} urad, sigma_el {:.3} urad for net radial RMS {:.4} mm over a \
             {:.2} m cube; {}",
            self.sigma_az_rad * 1e6,
            self.sigma_el_rad * 1e6,
            self.net_radial_rms_m * 1e3,
            self.volume.side_m,
            self.at_centre
        )
    }
}

impl TheodolitePair {
    /// Net radial error over `volume`: `sqrt(mean trace(covariance))` \[m\] (first order).
    pub fn net_radial_rms_m(&self, volume: &ReferenceVolume) -> Result<f64, TriangulationError> {
        let points = volume.grid_points();
        let mut sum_m2 = 0.0;
        for p in &points {
            sum_m2 += self.covariance_m2(p)?.trace();
        }
        Ok((sum_m2 / points.len() as f64).sqrt())
    }

    /// Stations at `left_m`, `right_m` with angular noise scaled so the net radial error over
    /// `volume` is `net_radial_rms_m`; `el_over_az` is the ratio sigma_el / sigma_az.
    pub fn calibrated(
        left_m: Point3<f64>,
        right_m: Point3<f64>,
        el_over_az: f64,
        net_radial_rms_m: f64,
        volume: &ReferenceVolume,
    ) -> Result<(Self, NoiseCalibration), TriangulationError> {
        let unit = Self::new(left_m, right_m, 1.0, el_over_az);
        let scale = net_radial_rms_m / unit.net_radial_rms_m(volume)?;
        let pair = Self::new(left_m, right_m, scale, scale * el_over_az);
        let calibration = NoiseCalibration {
            sigma_az_rad: pair.sigma_az_rad,
            sigma_el_rad: pair.sigma_el_rad,
            net_radial_rms_m,
            volume: *volume,
            at_centre: Anisotropy::of(&pair, &volume.centre_m)?,
        };
        Ok((pair, calibration))
    }

    /// The paper's set-up: left station at the origin, right station at
    /// [`PAPER_RIGHT_STATION_MM`], equal azimuth and elevation noise, 0.19 mm net radial
    /// error over [`ReferenceVolume::paper`].
    pub fn paper() -> Result<(Self, NoiseCalibration), TriangulationError> {
        let right_m = Point3::from(Vector3::from(PAPER_RIGHT_STATION_MM)) * 1e-3;
        Self::around_robot_base(
            [Point3::origin(), right_m],
            &paper_robot_base_m(),
            PAPER_NET_RADIAL_RMS_MM * 1e-3,
        )
    }

    /// Stations `[left, right]` (instrument frame \[m\]) with equal azimuth and elevation noise
    /// scaled to `net_radial_rms_m` over the 2 m cube around a robot base at `base_m`
    /// ([`ReferenceVolume::around_robot_base`]).
    pub fn around_robot_base(
        stations_m: [Point3<f64>; 2],
        base_m: &Point3<f64>,
        net_radial_rms_m: f64,
    ) -> Result<(Self, NoiseCalibration), TriangulationError> {
        let [left_m, right_m] = stations_m;
        Self::calibrated(
            left_m,
            right_m,
            1.0,
            net_radial_rms_m,
            &ReferenceVolume::around_robot_base(base_m),
        )
    }
}

/// [`PAPER_ROBOT_BASE_MM`] in metres.
fn paper_robot_base_m() -> Point3<f64> {
    Point3::from(Vector3::from(PAPER_ROBOT_BASE_MM)) * 1e-3
}

/// The paper's two theodolite stations as seen from a robot base at `base_m` (instrument frame
/// \[m\]) turned by `yaw_rad` about the vertical: each station keeps the offset from the base it
/// had from the paper's IRB/L6 (the origin and [`PAPER_RIGHT_STATION_MM`] against
/// [`PAPER_ROBOT_BASE_MM`], yaw 0), turned by `yaw_rad`. At the paper's base and yaw 0 these are
/// the paper's stations exactly.
pub fn paper_stations_around_m(base_m: &Point3<f64>, yaw_rad: f64) -> [Point3<f64>; 2] {
    let paper_base_m = paper_robot_base_m();
    let turn = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), yaw_rad);
    [
        Point3::origin(),
        Point3::from(Vector3::from(PAPER_RIGHT_STATION_MM)) * 1e-3,
    ]
    .map(|station_m| base_m + turn * (station_m - paper_base_m))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn the_paper_stations_are_the_paper_set_up_exactly_and_move_with_the_base() {
        let paper_base_m = paper_robot_base_m();
        let right_m = Point3::from(Vector3::from(PAPER_RIGHT_STATION_MM)) * 1e-3;
        assert_eq!(paper_stations_around_m(&paper_base_m, 0.0), [Point3::origin(), right_m]);
        // Another base, turned a quarter turn: each station's offset from the base is the
        // paper's, turned by 90 deg about z ((x, y, z) -> (-y, x, z)), written out here.
        let base_m = Point3::new(1.6, 0.5, -0.7);
        let turned = paper_stations_around_m(&base_m, std::f64::consts::FRAC_PI_2);
        for (station_m, paper_m) in turned.iter().zip([Point3::origin(), right_m]) {
            let d = paper_m - paper_base_m;
            assert_relative_eq!(station_m - base_m, Vector3::new(-d.y, d.x, d.z), epsilon = 1e-12);
        }
    }

    #[test]
    fn paper_calibration_reproduces_the_radial_error() {
        let (pair, calibration) = TheodolitePair::paper().unwrap();
        let rms_m = pair.net_radial_rms_m(&ReferenceVolume::paper()).unwrap();
        assert_relative_eq!(rms_m, PAPER_NET_RADIAL_RMS_MM * 1e-3, max_relative = 1e-12);
        // Symmetric stations: one principal axis is horizontal-depth, the ratio exceeds 1.
        assert!(calibration.at_centre.ratio() > 1.0);
        println!("{calibration}");
    }
}
