//! A pair of theodolite stations: angle measurement, triangulation and its first-order
//! covariance.
//!
//! The instrument frame is the frame of the LEFT station: origin at its centre, z up. Each
//! station reads the azimuth (angle in the horizontal plane from +x towards +y) and the
//! elevation (angle above the horizontal plane) of the line of sight to a target. A point is
//! triangulated as the midpoint of the common perpendicular of the two lines of sight, which
//! is the least-squares intersection of the two rays (the paper's instrument, section 4:
//! "two theodolites, net radial error 0.19 mm").

use nalgebra::{Matrix3, Matrix3x4, Point3, Vector3, Vector4};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// Why a point could not be measured or triangulated.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TriangulationError {
    /// The target lies on the vertical through a station, where azimuth is undefined.
    #[error("target is on the vertical through station {station} (horizontal distance {horizontal_distance_m} m)")]
    OnStationVertical {
        /// 0 = left, 1 = right.
        station: usize,
        /// Horizontal distance from the station to the target \[m\].
        horizontal_distance_m: f64,
    },
    /// The closest point of the two sight lines lies behind a station.
    #[error(
        "closest point of the sight lines lies behind station {station} (distance along its sight line {distance_m} m)"
    )]
    BehindStation {
        /// 0 = left, 1 = right.
        station: usize,
        /// Signed distance along that station's line of sight \[m\].
        distance_m: f64,
    },
    /// The two lines of sight are (nearly) parallel: their intersection is ill-conditioned.
    #[error(
        "lines of sight are nearly parallel: intersection angle {intersection_angle_rad} rad \
         is below the minimum {min_intersection_angle_rad} rad"
    )]
    NearParallel {
        /// The angle between the two lines of sight \[rad\].
        intersection_angle_rad: f64,
        /// The configured minimum \[rad\].
        min_intersection_angle_rad: f64,
    },
}

/// Azimuth and elevation of a line of sight from one station \[rad\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StationAngles {
    /// Angle in the horizontal plane from +x towards +y \[rad\].
    pub azimuth_rad: f64,
    /// Angle above the horizontal plane \[rad\].
    pub elevation_rad: f64,
}

impl StationAngles {
    /// Unit direction of the line of sight in the instrument frame.
    pub fn direction(&self) -> Vector3<f64> {
        let (sa, ca) = self.azimuth_rad.sin_cos();
        let (se, ce) = self.elevation_rad.sin_cos();
        Vector3::new(ce * ca, ce * sa, se)
    }

    /// Derivatives of [`Self::direction`] with respect to azimuth and elevation.
    fn direction_derivatives(&self) -> [Vector3<f64>; 2] {
        let (sa, ca) = self.azimuth_rad.sin_cos();
        let (se, ce) = self.elevation_rad.sin_cos();
        [
            Vector3::new(-ce * sa, ce * ca, 0.0),
            Vector3::new(-se * ca, -se * sa, ce),
        ]
    }
}

/// Two theodolite stations with Gaussian angular reading noise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TheodolitePair {
    /// Centre of the left station in the instrument frame \[m\] (normally the origin).
    #[schemars(with = "[f64; 3]")]
    pub left_station_m: Point3<f64>,
    /// Centre of the right station in the instrument frame \[m\].
    #[schemars(with = "[f64; 3]")]
    pub right_station_m: Point3<f64>,
    /// Standard deviation of one azimuth reading \[rad\].
    pub sigma_az_rad: f64,
    /// Standard deviation of one elevation reading \[rad\].
    pub sigma_el_rad: f64,
    /// Lines of sight meeting at a smaller angle than this are rejected \[rad\].
    #[serde(default = "default_min_intersection_angle_rad")]
    pub min_intersection_angle_rad: f64,
}

fn default_min_intersection_angle_rad() -> f64 {
    // About 0.6 deg: the noise gain of the intersection grows as 1/sin(angle), so below this
    // the point is meaningless at any realistic angular accuracy.
    0.01
}

/// Horizontal distance below which a target counts as on a station's vertical \[m\].
const MIN_HORIZONTAL_DISTANCE_M: f64 = 1e-9;

impl TheodolitePair {
    /// A pair with the given stations and angular noise, default minimum intersection angle.
    pub fn new(
        left_station_m: Point3<f64>,
        right_station_m: Point3<f64>,
        sigma_az_rad: f64,
        sigma_el_rad: f64,
    ) -> Self {
        Self {
            left_station_m,
            right_station_m,
            sigma_az_rad,
            sigma_el_rad,
            min_intersection_angle_rad: default_min_intersection_angle_rad(),
        }
    }

    /// The two station centres `[left, right]` in the instrument frame \[m\], e.g. as ray
    /// origins for line-of-sight checks.
    pub fn stations_m(&self) -> [Point3<f64>; 2] {
        [self.left_station_m, self.right_station_m]
    }

    /// Exact (noise-free) azimuth and elevation of `p_m` seen from station `station` (0 or 1).
    pub fn angles(&self, station: usize, p_m: &Point3<f64>) -> Result<StationAngles, TriangulationError> {
        let d = p_m - self.stations_m()[station];
        let horizontal_distance_m = d.x.hypot(d.y);
        if horizontal_distance_m < MIN_HORIZONTAL_DISTANCE_M {
            return Err(TriangulationError::OnStationVertical {
                station,
                horizontal_distance_m,
            });
        }
        Ok(StationAngles {
            azimuth_rad: d.y.atan2(d.x),
            elevation_rad: d.z.atan2(horizontal_distance_m),
        })
    }

    /// Triangulates the point seen at `left` from the left station and `right` from the
    /// right: the midpoint of the common perpendicular of the two lines of sight.
    pub fn triangulate(&self, left: StationAngles, right: StationAngles) -> Result<Point3<f64>, TriangulationError> {
        let rays = self.rays(left, right)?;
        Ok(rays.midpoint())
    }

    /// Simulates one measurement of `p_m`: exact angles plus Gaussian reading noise at both
    /// stations, then [`Self::triangulate`].
    pub fn measure<R: Rng + ?Sized>(&self, p_m: &Point3<f64>, rng: &mut R) -> Result<Point3<f64>, TriangulationError> {
        let mut noisy = |a: StationAngles| {
            let daz: f64 = StandardNormal.sample(rng);
            let del: f64 = StandardNormal.sample(rng);
            StationAngles {
                azimuth_rad: a.azimuth_rad + self.sigma_az_rad * daz,
                elevation_rad: a.elevation_rad + self.sigma_el_rad * del,
            }
        };
        let left = noisy(self.angles(0, p_m)?);
        let right = noisy(self.angles(1, p_m)?);
        self.triangulate(left, right)
    }

    /// Jacobian of the triangulated point at `p_m` with respect to the four readings
    /// `(az_left, el_left, az_right, el_right)` \[m/rad\].
    ///
    /// Implicit differentiation of the closest-point conditions `u1 . r = u2 . r = 0`,
    /// `r = p1 + s u1 - p2 - t u2`, at an exact intersection (`r = 0`):
    /// `ds - b dt = t u1.du2`, `b ds - dt = -s u2.du1` with `b = u1.u2`, and
    /// `dm = (ds u1 + s du1 + dt u2 + t du2) / 2`.
    pub fn triangulation_jacobian(&self, p_m: &Point3<f64>) -> Result<Matrix3x4<f64>, TriangulationError> {
        let angles = [self.angles(0, p_m)?, self.angles(1, p_m)?];
        let rays = self.rays(angles[0], angles[1])?;
        let (u1, u2, s, t) = (rays.u1, rays.u2, rays.s, rays.t);
        let b = u1.dot(&u2);
        let one_minus_b2 = 1.0 - b * b;
        let mut jacobian = Matrix3x4::zeros();
        for (k, du1) in angles[0].direction_derivatives().iter().enumerate() {
            let dt = s * u2.dot(du1) / one_minus_b2;
            let ds = b * dt;
            jacobian.set_column(k, &((u1 * ds + du1 * s + u2 * dt) * 0.5));
        }
        for (k, du2) in angles[1].direction_derivatives().iter().enumerate() {
            let c = t * u1.dot(du2) / one_minus_b2;
            let (ds, dt) = (c, b * c);
            jacobian.set_column(2 + k, &((u1 * ds + u2 * dt + du2 * t) * 0.5));
        }
        Ok(jacobian)
    }

    /// First-order covariance of a measurement of `p_m` \[m^2\]: `J diag(sigma^2) J^T` with
    /// `J` from [`Self::triangulation_jacobian`].
    pub fn covariance_m2(&self, p_m: &Point3<f64>) -> Result<Matrix3<f64>, TriangulationError> {
        let j = self.triangulation_jacobian(p_m)?;
        let variances = Vector4::new(
            self.sigma_az_rad.powi(2),
            self.sigma_el_rad.powi(2),
            self.sigma_az_rad.powi(2),
            self.sigma_el_rad.powi(2),
        );
        Ok(j * Matrix3x4::from_fn(|r, c| j[(r, c)] * variances[c]).transpose())
    }

    /// The angle between the lines (not rays: antiparallel sight lines are as degenerate) of
    /// unit directions `u1`, `u2` (`b = u1 . u2`), `atan2(|u1 x u2|, |b|)`, when it is below
    /// the minimum; `None` when it is not. Where `|u1 x u2| > 2 min |b|` (every measurement
    /// of a usable pair) the angle exceeds `atan(2 min) >= min` (`tan x <= 2x` for
    /// `0 <= x <= 1`), a margin far beyond rounding, and the `atan2` is skipped: the answer is
    /// that of the comparison in every case.
    fn narrow_angle(&self, u1: &Vector3<f64>, u2: &Vector3<f64>, b: f64) -> Option<f64> {
        let sine = u1.cross(u2).norm();
        let min = self.min_intersection_angle_rad;
        if min <= 1.0 && sine > 2.0 * min * b.abs() {
            return None;
        }
        let angle = sine.atan2(b.abs());
        (angle < min).then_some(angle)
    }

    fn rays(&self, left: StationAngles, right: StationAngles) -> Result<Rays, TriangulationError> {
        let (p1, p2) = (self.left_station_m, self.right_station_m);
        let (u1, u2) = (left.direction(), right.direction());
        let b = u1.dot(&u2);
        if let Some(intersection_angle_rad) = self.narrow_angle(&u1, &u2, b) {
            return Err(TriangulationError::NearParallel {
                intersection_angle_rad,
                min_intersection_angle_rad: self.min_intersection_angle_rad,
            });
        }
        // Normal equations of min |p1 + s u1 - p2 - t u2|^2 with |u1| = |u2| = 1.
        let w = p1 - p2;
        let (d, e) = (u1.dot(&w), u2.dot(&w));
        let denominator = 1.0 - b * b;
        let s = (b * e - d) / denominator;
        let t = (e - b * d) / denominator;
        // A sight line is a half-line: a closest point behind a station is not a measurement.
        if let Some(station) = [s, t].iter().position(|&distance_m| distance_m <= 0.0) {
            return Err(TriangulationError::BehindStation {
                station,
                distance_m: [s, t][station],
            });
        }
        Ok(Rays { p1, p2, u1, u2, s, t })
    }
}

/// Two lines of sight and the parameters of their closest points.
struct Rays {
    p1: Point3<f64>,
    p2: Point3<f64>,
    u1: Vector3<f64>,
    u2: Vector3<f64>,
    s: f64,
    t: f64,
}

impl Rays {
    fn midpoint(&self) -> Point3<f64> {
        let a = self.p1 + self.u1 * self.s;
        let b = self.p2 + self.u2 * self.t;
        nalgebra::center(&a, &b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    fn pair() -> TheodolitePair {
        TheodolitePair::new(Point3::origin(), Point3::new(-6.2846, 0.0, 0.0), 3e-5, 2e-5)
    }

    fn point_near_robot() -> impl Strategy<Value = Point3<f64>> {
        (-4.2..-2.1f64, 3.4..5.4f64, -1.0..1.0f64).prop_map(|(x, y, z)| Point3::new(x, y, z))
    }

    proptest! {
        #[test]
        fn exact_rays_reproduce_the_point(p in point_near_robot()) {
            let pair = pair();
            let q = pair.triangulate(pair.angles(0, &p).unwrap(), pair.angles(1, &p).unwrap()).unwrap();
            // Pure rounding: a few ulps of the 5 m lever arm.
            prop_assert!((q - p).norm() < 1e-12, "error {} m", (q - p).norm());
        }

        #[test]
        fn jacobian_matches_central_differences(p in point_near_robot()) {
            let pair = pair();
            let analytic = pair.triangulation_jacobian(&p).unwrap();
            let base = [pair.angles(0, &p).unwrap(), pair.angles(1, &p).unwrap()];
            let h = 1e-6;
            for k in 0..4 {
                let shifted = |sign: f64| {
                    let mut a = base;
                    let st = &mut a[k / 2];
                    if k % 2 == 0 { st.azimuth_rad += sign * h } else { st.elevation_rad += sign * h }
                    pair.triangulate(a[0], a[1]).unwrap()
                };
                let numeric = (shifted(1.0) - shifted(-1.0)) / (2.0 * h);
                // Central-difference truncation error ~ h^2 |d3p/da3| ~ 1e-12 * (5 m)*10,
                // plus rounding 1e-16 * 5 m / 1e-6.
                assert_relative_eq!(analytic.column(k).into_owned(), numeric, epsilon = 1e-8);
            }
        }
    }

    /// The skipped `atan2` never changes the answer: lines at angles from half to twice the
    /// minimum (and antiparallel ones), for minima up to and beyond the 1-rad bound, give the
    /// comparison's answer and angle.
    #[test]
    fn narrow_angle_is_the_comparison_of_the_angle() {
        for min in [0.0, 0.01, 0.3, 1.0, 1.2, -0.1] {
            let pair = TheodolitePair {
                min_intersection_angle_rad: min,
                ..pair()
            };
            let u1 = Vector3::new(0.3, -0.5, 0.8).normalize();
            let across = u1.cross(&Vector3::z()).normalize();
            for k in 0..=200 {
                let angle = (0.5 + 1.5 * k as f64 / 200.0) * min.abs().max(1e-3);
                for sign in [1.0, -1.0] {
                    let u2 = (u1 * angle.cos() + across * angle.sin()) * sign;
                    let b = u1.dot(&u2);
                    let reference = u1.cross(&u2).norm().atan2(b.abs());
                    let expected = (reference < min).then_some(reference);
                    assert_eq!(pair.narrow_angle(&u1, &u2, b), expected, "min {min}, angle {angle}");
                }
            }
        }
    }

    #[test]
    fn parallel_rays_are_rejected() {
        let pair = pair();
        let a = StationAngles {
            azimuth_rad: 1.0,
            elevation_rad: 0.1,
        };
        assert!(matches!(
            pair.triangulate(a, a),
            Err(TriangulationError::NearParallel { .. })
        ));
        // Sight lines meet at (-6.28, -6.28, 0): in front of the left station, behind the right.
        let left = StationAngles {
            azimuth_rad: -3.0 * std::f64::consts::FRAC_PI_4,
            elevation_rad: 0.0,
        };
        let right = StationAngles {
            azimuth_rad: std::f64::consts::FRAC_PI_2,
            elevation_rad: 0.0,
        };
        assert!(matches!(
            pair.triangulate(left, right),
            Err(TriangulationError::BehindStation { station: 1, .. })
        ));
        let above = Point3::new(0.0, 0.0, 3.0);
        assert!(matches!(
            pair.angles(0, &above),
            Err(TriangulationError::OnStationVertical { station: 0, .. })
        ));
    }
}
