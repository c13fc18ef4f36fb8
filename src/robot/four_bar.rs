//! The planar four-bar that drives joint 3 of the ASEA IRB/L6 from an actuator near the base
//! (paper fig. 6; the passive motion 2->3 of section 4).
//!
//! All four bodies turn about axes parallel to joint axes 2 and 3, so the linkage is solved in
//! the plane normal to them, angles counted positive about the common axis direction:
//!
//! - the *arm* (link 2) from pivot `O2` on axis 2 to pivot `O3` on axis 3, length `L`; at
//!   `theta_2 = 0` it points along the planar x axis, so `O3 = L e(theta_2)`;
//! - the *crank*, pivoted on axis 2 and driven by actuator 3; while actuator 3 is held still
//!   (paper section 3.1) its tip is fixed in the base: `C = r_c e(psi_c)`;
//! - the *coupler rod* `C -> P`, length `r_r`;
//! - the *lever* on link 3 from `O3` to `P`, length `r_l`, at the fixed angle `psi_l` from
//!   link 3's reference direction: `P = O3 + r_l e(theta_2 + psi_l + g)`, where `g` is the
//!   relative rotation of link 3 on link 2 (the passive angle `theta_23`).
//!
//! Loop closure `|P - C| = r_r` gives `g(theta_2)` by circle-circle intersection. The nominal
//! mechanism is a parallelogram (`r_c = r_l`, `r_r = L`, `psi_l = psi_c`), for which link 3 keeps
//! its orientation in the base and `g = -theta_2` exactly, the controller's nominal model.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A four-bar that cannot be assembled at the requested input angle, or has bad dimensions.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FourBarError {
    /// A length is not finite and positive, or an angle is not finite.
    #[error("four-bar dimension `{field}` = {value} is invalid (lengths must be finite and > 0)")]
    BadDimension {
        /// The field name, e.g. `rod_m`.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// The rod cannot reach from the crank tip to a circle of the lever's radius about `O3`.
    #[error(
        "four-bar cannot close at theta_2 = {theta_2_rad} rad: crank tip is {distance_m} m from \
         axis 3, outside [{min_m}, {max_m}] m"
    )]
    CannotClose {
        /// The input angle \[rad\].
        theta_2_rad: f64,
        /// Distance from `O3` to the crank tip `C` \[m\].
        distance_m: f64,
        /// `|r_r - r_l|` \[m\].
        min_m: f64,
        /// `r_r + r_l` \[m\].
        max_m: f64,
    },
    /// The least-squares fit of the dimensions failed ([`crate::robot::fit_four_bar`]).
    #[error("fitting the four-bar's dimensions: {0}")]
    Fit(crate::numerics::lsq::LsqError),
}

/// Dimensions of the 2->3 four-bar (module docs give the planar construction).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FourBarGeometry {
    /// `L`: distance from axis 2 to axis 3 \[m\].
    pub arm_m: f64,
    /// `r_c`: crank length on axis 2 \[m\].
    pub crank_m: f64,
    /// `r_r`: coupler rod length \[m\].
    pub rod_m: f64,
    /// `r_l`: lever length on link 3 \[m\].
    pub lever_m: f64,
    /// `psi_c`: crank direction from the arm direction at `theta_2 = 0` \[rad\].
    pub crank_angle_rad: f64,
    /// `psi_l`: lever direction on link 3 from the arm direction, at zero relative angle \[rad\].
    pub lever_angle_rad: f64,
}

/// The assembled four-bar at one input angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FourBarState {
    /// The passive angle `g = theta_23` \[rad\].
    pub passive_rad: f64,
    /// `d g / d theta_2` \[-\].
    pub slope: f64,
    /// Loop-closure residual `|P - C| - r_r` \[m\] (zero up to rounding).
    pub closure_residual_m: f64,
}

fn unit(angle: f64) -> [f64; 2] {
    let (s, c) = angle.sin_cos();
    [c, s]
}

fn wrap_pi(x: f64) -> f64 {
    let y = (x + PI).rem_euclid(2.0 * PI) - PI;
    if y <= -PI { y + 2.0 * PI } else { y }
}

impl FourBarGeometry {
    /// The nominal parallelogram: crank and lever of length `crank_m` at `crank_angle_rad`,
    /// rod as long as the arm. Its passive angle is exactly `-theta_2`.
    pub fn parallelogram(arm_m: f64, crank_m: f64, crank_angle_rad: f64) -> Self {
        Self {
            arm_m,
            crank_m,
            rod_m: arm_m,
            lever_m: crank_m,
            crank_angle_rad,
            lever_angle_rad: crank_angle_rad,
        }
    }

    /// Checks that lengths are finite and positive and angles finite.
    pub fn validate(&self) -> Result<(), FourBarError> {
        let lengths = [
            ("arm_m", self.arm_m),
            ("crank_m", self.crank_m),
            ("rod_m", self.rod_m),
            ("lever_m", self.lever_m),
        ];
        for (field, value) in lengths {
            if !(value.is_finite() && value > 0.0) {
                return Err(FourBarError::BadDimension { field, value });
            }
        }
        for (field, value) in [
            ("crank_angle_rad", self.crank_angle_rad),
            ("lever_angle_rad", self.lever_angle_rad),
        ] {
            if !value.is_finite() {
                return Err(FourBarError::BadDimension { field, value });
            }
        }
        Ok(())
    }

    /// Absolute lever angle `phi` for branch `sign` at input `theta_2` (circle-circle
    /// intersection: `P` on the circle of radius `r_l` about `O3` and radius `r_r` about `C`).
    fn lever_direction(&self, theta_2: f64, sign: f64) -> Result<f64, FourBarError> {
        let o3 = unit(theta_2).map(|v| v * self.arm_m);
        let c = unit(self.crank_angle_rad).map(|v| v * self.crank_m);
        let dv = [c[0] - o3[0], c[1] - o3[1]];
        let d = dv[0].hypot(dv[1]);
        let (rl, rr) = (self.lever_m, self.rod_m);
        let (min_m, max_m) = ((rr - rl).abs(), rr + rl);
        if !(d > min_m && d < max_m) {
            return Err(FourBarError::CannotClose {
                theta_2_rad: theta_2,
                distance_m: d,
                min_m,
                max_m,
            });
        }
        // D . e(phi) = k with D = d e(delta): cos(phi - delta) = k / d.
        let k = (rl * rl + d * d - rr * rr) / (2.0 * rl);
        let delta = dv[1].atan2(dv[0]);
        let half = (d * d - k * k).max(0.0).sqrt().atan2(k);
        Ok(delta + sign * half)
    }

    /// The assembly branch continuous with the nominal (parallelogram) assembly: the one whose
    /// passive angle at `theta_2 = 0` is nearest zero.
    fn branch(&self) -> Result<f64, FourBarError> {
        let g_at = |sign| -> Result<f64, FourBarError> {
            Ok(wrap_pi(self.lever_direction(0.0, sign)? - self.lever_angle_rad).abs())
        };
        Ok(if g_at(1.0)? <= g_at(-1.0)? { 1.0 } else { -1.0 })
    }

    /// Solves the linkage at input angle `theta_2` \[rad\]: passive angle, its derivative (by
    /// implicit differentiation of the closure `F = |P - C|^2 - r_r^2 = 0`), and the closure
    /// residual.
    pub fn solve(&self, theta_2: f64) -> Result<FourBarState, FourBarError> {
        self.validate()?;
        let sign = self.branch()?;
        let phi = self.lever_direction(theta_2, sign)?;
        let passive_rad = wrap_pi(phi - theta_2 - self.lever_angle_rad);
        let o3 = unit(theta_2).map(|v| v * self.arm_m);
        let c = unit(self.crank_angle_rad).map(|v| v * self.crank_m);
        let e_phi = unit(phi);
        let r = [
            o3[0] + self.lever_m * e_phi[0] - c[0],
            o3[1] + self.lever_m * e_phi[1] - c[1],
        ];
        let perp = |a: f64| {
            let [x, y] = unit(a);
            [-y, x]
        };
        let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
        let dphi = -self.arm_m * dot(r, perp(theta_2)) / (self.lever_m * dot(r, perp(phi)));
        Ok(FourBarState {
            passive_rad,
            slope: dphi - 1.0,
            closure_residual_m: r[0].hypot(r[1]) - self.rod_m,
        })
    }

    /// The passive angle `theta_23(theta_2)` \[rad\].
    pub fn passive(&self, theta_2: f64) -> Result<f64, FourBarError> {
        self.solve(theta_2).map(|s| s.passive_rad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn skewed() -> FourBarGeometry {
        FourBarGeometry {
            arm_m: 0.6932,
            crank_m: 0.21,
            rod_m: 0.70,
            lever_m: 0.19,
            crank_angle_rad: 1.7,
            lever_angle_rad: 1.62,
        }
    }

    #[test]
    fn parallelogram_gives_minus_theta2() {
        let g = FourBarGeometry::parallelogram(0.69, 0.2, 1.3);
        for i in -45..=45 {
            let t = (i as f64).to_radians();
            let s = g.solve(t).unwrap();
            assert!((s.passive_rad + t).abs() < 1e-14, "t = {t}: {}", s.passive_rad + t);
            assert_relative_eq!(s.slope, -1.0, epsilon = 1e-12);
        }
    }

    #[test]
    fn slope_matches_central_differences_and_loop_closes() {
        let g = skewed();
        let h = 1e-6;
        for i in -8..=8 {
            let t = i as f64 * 0.1;
            let s = g.solve(t).unwrap();
            let fd = (g.passive(t + h).unwrap() - g.passive(t - h).unwrap()) / (2.0 * h);
            // central-difference truncation ~ h^2 g''' and rounding ~ 1e-16 / h.
            assert_relative_eq!(s.slope, fd, epsilon = 1e-8);
            assert!(s.closure_residual_m.abs() < 1e-14);
        }
    }

    proptest::proptest! {
        /// Near-parallelogram linkages (manufacturing errors up to a few mm and degrees):
        /// implicit-differentiation slope vs central differences, and loop closure.
        #[test]
        fn slope_and_closure_hold_for_perturbed_parallelograms(
            crank in 0.1f64..0.4,
            angle in 1.2f64..1.9,
            d in proptest::array::uniform4(-0.005f64..0.005),
            da in -0.05f64..0.05,
            t in -0.7f64..0.7,
        ) {
            let mut g = FourBarGeometry::parallelogram(0.69, crank, angle);
            g.arm_m += d[0];
            g.rod_m += d[1];
            g.lever_m += d[2];
            g.crank_m += d[3];
            g.lever_angle_rad += da;
            let h = 1e-6;
            // At least 0.1 rad from the ends of the linkage's range: a short crank with these
            // errors may not reach at the ends of `t`'s (the loop does not close: a clear
            // error, tested below), and next to such an end the passive angle goes as the
            // square root of the distance, whose third derivative (the central difference's
            // truncation) is unbounded.
            let closes = |x: f64| !matches!(g.solve(x), Err(FourBarError::CannotClose { .. }));
            proptest::prop_assume!((-4..=4).all(|k| closes(t + 0.025 * f64::from(k))));
            let s = g.solve(t).unwrap();
            let fd = (g.passive(t + h).unwrap() - g.passive(t - h).unwrap()) / (2.0 * h);
            // Truncation h^2 |g'''| / 6 plus rounding 1e-16 / h, both below 1e-8 here.
            proptest::prop_assert!((s.slope - fd).abs() < 1e-8, "{} vs {}", s.slope, fd);
            proptest::prop_assert!(s.closure_residual_m.abs() < 1e-14);
        }
    }

    #[test]
    fn unreachable_and_bad_dimensions_are_errors() {
        let mut g = skewed();
        g.rod_m = 0.1;
        assert!(matches!(g.solve(0.0), Err(FourBarError::CannotClose { .. })));
        g.rod_m = -1.0;
        assert!(matches!(
            g.solve(0.0),
            Err(FourBarError::BadDimension { field: "rod_m", .. })
        ));
    }
}
