//! Axis wobble (bearing runout): a tilt of a joint's axis that turns with the joint.

use crate::kinematics::PhiModel;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

fn default_order() -> i32 {
    1
}

/// Axis wobble (bearing runout) of one joint: before the joint's motion, frame `k` is turned
/// by the small rotation vector `amplitude (cos(n q + phase), sin(n q + phase), 0)` (in frame
/// `k`, i.e. about an axis perpendicular to `Z_k` whose direction turns with the joint value `q`).
///
/// With `order = 1` the tilt turns with the link: the link sits tilted on its bearing, a point
/// at radius `r` leaves the nominal plane of its arc by `-amplitude r sin(phase)` and its path
/// is still a circle (about a tilted axis). Orders `n >= 3` (or `n <= -1`) bend the path out of
/// any plane by up to `amplitude r`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AxisWobble {
    /// The joint (1-based).
    pub joint: usize,
    /// Tilt amplitude \[rad\].
    pub amplitude_rad: f64,
    /// Phase of the tilt direction \[rad\].
    #[serde(default)]
    pub phase_rad: f64,
    /// How many times the tilt direction turns per joint turn; default 1.
    #[serde(default = "default_order")]
    pub order: i32,
}

/// Applies the axis wobbles to link poses computed without them (`links`, index `k` = link
/// `k + 1`), for joint values `q` of `model`: joint `k`'s tilt `W_k` (see [`AxisWobble`])
/// gives the world-frame correction `C_k = F_k W_k F_k^-1` (`F_k` = world_from_frame_k)
/// applied to every link from `k` on, joints processed from the last to the first so
/// each `F_k` is still the wobble-free one when used.
pub fn apply_wobble(wobble: &[AxisWobble], model: &PhiModel, q: &[f64], links: &mut [Isometry3<f64>]) {
    let mut wobbles: Vec<&AxisWobble> = wobble.iter().collect();
    wobbles.sort_by_key(|w| std::cmp::Reverse(w.joint));
    for w in wobbles {
        let k = w.joint - 1;
        if k >= links.len() || k >= q.len() {
            continue;
        }
        let frame = if k == 0 {
            model.world_from_base
        } else {
            links[k - 1] * model.link_from_next_frame(k - 1)
        };
        let angle = w.order as f64 * q[k] + w.phase_rad;
        let tilt = UnitQuaternion::from_scaled_axis(Vector3::new(angle.cos(), angle.sin(), 0.0) * w.amplitude_rad);
        let correction = frame * Isometry3::from_parts(Translation3::identity(), tilt) * frame.inverse();
        for link in &mut links[k..] {
            *link = correction * *link;
        }
    }
}
