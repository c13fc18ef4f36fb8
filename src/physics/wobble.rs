//! Axis wobble (bearing runout): a tilt of a joint's axis that varies periodically with the
//! joint, turning with it or about a fixed direction.

use crate::kinematics::PhiModel;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

fn default_order() -> i32 {
    1
}

/// Axis wobble (bearing runout) of one joint: before the joint's motion, frame `k` is turned
/// by a small rotation vector perpendicular to `Z_k` (in frame `k`) that varies with the joint
/// value `q` at `order` times its period:
///
/// - a **rotating** tilt (`fixed_direction_rad` absent): `amplitude (cos(n q + phase),
///   sin(n q + phase), 0)`, its direction turning `n` times per joint turn;
/// - a tilt about a **fixed direction** (`fixed_direction_rad = psi`, a swash):
///   `amplitude cos(n q + phase) (cos psi, sin psi, 0)`, rocking about one direction of frame
///   `k`.
///
/// A rotating tilt of order 1 turns with the link: the link sits tilted on its bearing, a point
/// at radius `r` leaves the nominal plane of its arc by `-amplitude r sin(phase)` and its path
/// is still a circle (about a tilted axis), which a calibration absorbs. Every other shape
/// (orders `n >= 2`, `n <= -1`, any fixed-direction tilt, which is half a rotating and half a
/// counter-rotating one) bends the path out of any plane by up to `amplitude r`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AxisWobble {
    /// The joint (1-based).
    pub joint: usize,
    /// Tilt amplitude \[rad\].
    pub amplitude_rad: f64,
    /// Phase of the tilt \[rad\].
    #[serde(default)]
    pub phase_rad: f64,
    /// How many times the tilt varies per joint turn; default 1.
    #[serde(default = "default_order")]
    pub order: i32,
    /// The fixed direction of a swash, as its angle from `X_k` in frame `k`'s xy-plane
    /// \[rad\]; absent: the tilt's direction turns with the joint.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed_direction_rad: Option<f64>,
}

/// The general tilt of order `n` of one joint's axis (frame `k`), the form the diagnosis fits:
/// the rotation vector `cos(n q) c + sin(n q) s`, `c` and `s` in frame `k`'s xy-plane. Every
/// [`AxisWobble`] of order `n` is one ([`AxisWobble::series`]): a rotating tilt has `s` equal
/// to `c` turned by 90 deg, a fixed-direction one `c` parallel to `s`; the general form also
/// holds the counter-rotating tilt (order `-n`) and any sum of these.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisTiltSeries {
    /// The joint (1-based).
    pub joint: usize,
    /// The order `n`.
    pub order: i32,
    /// `(c_x, c_y)` \[rad\].
    pub cos_rad: [f64; 2],
    /// `(s_x, s_y)` \[rad\].
    pub sin_rad: [f64; 2],
}

impl AxisTiltSeries {
    /// The rotation vector of the tilt at joint value `q` (in frame `k`) \[rad\].
    pub fn tilt_rad(&self, q: f64) -> Vector3<f64> {
        let (s, c) = (f64::from(self.order) * q).sin_cos();
        Vector3::new(
            c * self.cos_rad[0] + s * self.sin_rad[0],
            c * self.cos_rad[1] + s * self.sin_rad[1],
            0.0,
        )
    }
}

impl AxisWobble {
    /// The wobble as a general tilt series of its order (exact).
    pub fn series(&self) -> AxisTiltSeries {
        let (sp, cp) = self.phase_rad.sin_cos();
        let a = self.amplitude_rad;
        let (cos_rad, sin_rad) = match self.fixed_direction_rad {
            // a (cos(nq + p), sin(nq + p)) = cos(nq) a (cos p, sin p) + sin(nq) a (-sin p, cos p)
            None => ([a * cp, a * sp], [-a * sp, a * cp]),
            // a cos(nq + p) d = cos(nq) a cos p d - sin(nq) a sin p d
            Some(psi) => {
                let (sd, cd) = psi.sin_cos();
                ([a * cp * cd, a * cp * sd], [-a * sp * cd, -a * sp * sd])
            }
        };
        AxisTiltSeries {
            joint: self.joint,
            order: self.order,
            cos_rad,
            sin_rad,
        }
    }

    /// The rotation vector of the tilt at joint value `q` (in frame `k`) \[rad\].
    pub fn tilt_rad(&self, q: f64) -> Vector3<f64> {
        self.series().tilt_rad(q)
    }
}

/// Applies the axis wobbles to link poses computed without them ([`apply_axis_tilts`]).
pub fn apply_wobble(wobble: &[AxisWobble], model: &PhiModel, q: &[f64], links: &mut [Isometry3<f64>]) {
    let series: Vec<AxisTiltSeries> = wobble.iter().map(AxisWobble::series).collect();
    apply_axis_tilts(&series, model, q, links);
}

/// Applies axis tilts to link poses computed without them (`links`, index `k` = link
/// `k + 1`), for joint values `q` of `model`: joint `k`'s tilt `W_k` (the rotation of
/// [`AxisTiltSeries::tilt_rad`] in frame `k`) gives the world-frame correction
/// `C_k = F_k W_k F_k^-1` (`F_k` = world_from_frame_k) applied to every link from `k` on,
/// joints processed from the last to the first so each `F_k` is still the tilt-free one when
/// used.
pub fn apply_axis_tilts(tilts: &[AxisTiltSeries], model: &PhiModel, q: &[f64], links: &mut [Isometry3<f64>]) {
    let mut tilts: Vec<&AxisTiltSeries> = tilts.iter().collect();
    tilts.sort_by_key(|w| std::cmp::Reverse(w.joint));
    for w in tilts {
        let k = w.joint.wrapping_sub(1);
        if k >= links.len() || k >= q.len() {
            continue;
        }
        let frame = if k == 0 {
            model.world_from_base
        } else {
            links[k - 1] * model.link_from_next_frame(k - 1)
        };
        let tilt = UnitQuaternion::from_scaled_axis(w.tilt_rad(q[k]));
        let correction = frame * Isometry3::from_parts(Translation3::identity(), tilt) * frame.inverse();
        for link in &mut links[k..] {
            *link = correction * *link;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// The series of a rotating and of a fixed-direction wobble reproduce their defining
    /// formulas at any joint value (an independent evaluation of each form).
    #[test]
    fn the_series_of_each_wobble_shape_is_its_formula() {
        let (a, p, psi) = (3e-3, 0.7, -1.1);
        for order in [1, 2, -1, 3] {
            let rotating = AxisWobble {
                joint: 2,
                amplitude_rad: a,
                phase_rad: p,
                order,
                fixed_direction_rad: None,
            };
            let swash = AxisWobble {
                fixed_direction_rad: Some(psi),
                ..rotating
            };
            // Rounding: the angle-sum identity evaluates two products of size `a` and adds
            // them, a few ulps of `a` apart from the direct formula.
            let tol = 8.0 * f64::EPSILON * a;
            for q in [-2.0, -0.3, 0.0, 0.9, 2.5] {
                let angle = f64::from(order) * q + p;
                assert_relative_eq!(
                    rotating.tilt_rad(q),
                    Vector3::new(a * angle.cos(), a * angle.sin(), 0.0),
                    epsilon = tol
                );
                assert_relative_eq!(
                    swash.tilt_rad(q),
                    Vector3::new(psi.cos(), psi.sin(), 0.0) * a * angle.cos(),
                    epsilon = tol
                );
            }
        }
    }
}
