//! The pose and distance characteristics of ISO 9283:1998, section 7, from attained poses:
//! pose accuracy AP and repeatability RP (7.2.1, 7.2.2), multi-directional pose accuracy
//! variation vAP (7.2.3), distance accuracy AD and repeatability RD (7.3.1, 7.3.2).
//!
//! Positions are the tool point's (mm in the outputs, m inside); orientations are the angles
//! `a`, `b`, `c` about X, Y and Z of `R = Rz(c) Ry(b) Rx(a)`. An angle's mean is taken on the
//! differences from a reference angle wrapped to (-pi, pi] (the commanded angle for AP, the
//! first attained one otherwise), so that poses either side of +-pi average correctly.

use nalgebra::{Isometry3, Vector3};

/// `(a, b, c)` of a pose's orientation, `R = Rz(c) Ry(b) Rx(a)` \[rad\].
pub fn abc(pose: &Isometry3<f64>) -> [f64; 3] {
    crate::kinematics::roll_pitch_yaw(&pose.rotation)
}

/// `angle` wrapped to (-pi, pi].
fn wrap(angle: f64) -> f64 {
    let pi = std::f64::consts::PI;
    let w = angle.rem_euclid(2.0 * pi);
    if w > pi { w - 2.0 * pi } else { w }
}

/// The mean of `values` and their sample standard deviation (`n - 1`; 0 for one value).
fn mean_and_sd(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let ss: f64 = values.iter().map(|v| (v - mean).powi(2)).sum();
    (mean, if values.len() > 1 { (ss / (n - 1.0)).sqrt() } else { 0.0 })
}

/// The mean position of `poses` \[m\].
fn mean_position(poses: &[Isometry3<f64>]) -> Vector3<f64> {
    poses.iter().map(|p| p.translation.vector).sum::<Vector3<f64>>() / poses.len() as f64
}

/// Per angle `a, b, c`: the differences of `poses`' angles from `reference`'s, wrapped.
fn angle_differences(poses: &[Isometry3<f64>], reference: [f64; 3]) -> [Vec<f64>; 3] {
    std::array::from_fn(|i| poses.iter().map(|p| wrap(abc(p)[i] - reference[i])).collect())
}

/// Pose accuracy, ISO 9283 7.2.1: the mean attained pose against the commanded one.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct PoseAccuracy {
    /// `AP_P = sqrt((x_bar - x_c)^2 + (y_bar - y_c)^2 + (z_bar - z_c)^2)` \[mm\].
    pub ap_p_mm: f64,
    /// `AP_x = x_bar - x_c` \[mm\].
    pub ap_x_mm: f64,
    /// `AP_y = y_bar - y_c` \[mm\].
    pub ap_y_mm: f64,
    /// `AP_z = z_bar - z_c` \[mm\].
    pub ap_z_mm: f64,
    /// `AP_a = a_bar - a_c` \[mrad\].
    pub ap_a_mrad: f64,
    /// `AP_b = b_bar - b_c` \[mrad\].
    pub ap_b_mrad: f64,
    /// `AP_c = c_bar - c_c` \[mrad\].
    pub ap_c_mrad: f64,
}

/// [`PoseAccuracy`] of `attained` (at least one pose) against `commanded`.
pub fn pose_accuracy(commanded: &Isometry3<f64>, attained: &[Isometry3<f64>]) -> Option<PoseAccuracy> {
    if attained.is_empty() {
        return None;
    }
    let d = (mean_position(attained) - commanded.translation.vector) * 1e3;
    let angles = angle_differences(attained, abc(commanded));
    let [a, b, c]: [f64; 3] = std::array::from_fn(|i| mean_and_sd(&angles[i]).0 * 1e3);
    Some(PoseAccuracy {
        ap_p_mm: d.norm(),
        ap_x_mm: d.x,
        ap_y_mm: d.y,
        ap_z_mm: d.z,
        ap_a_mrad: a,
        ap_b_mrad: b,
        ap_c_mrad: c,
    })
}

/// Pose repeatability, ISO 9283 7.2.2: the spread of the attained poses about their mean.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct PoseRepeatability {
    /// `RP_l = l_bar + 3 S_l` \[mm\].
    pub rp_l_mm: f64,
    /// `l_bar`, the mean distance of the attained positions from their mean \[mm\].
    pub l_bar_mm: f64,
    /// `S_l = sqrt(sum (l_j - l_bar)^2 / (n - 1))` \[mm\].
    pub s_l_mm: f64,
    /// `RP_a = +-3 S_a`, `S_a = sqrt(sum (a_j - a_bar)^2 / (n - 1))`, the half-width \[mrad\].
    pub rp_a_mrad: f64,
    /// `RP_b = +-3 S_b` \[mrad\].
    pub rp_b_mrad: f64,
    /// `RP_c = +-3 S_c` \[mrad\].
    pub rp_c_mrad: f64,
}

/// [`PoseRepeatability`] of `attained` (at least two poses).
pub fn pose_repeatability(attained: &[Isometry3<f64>]) -> Option<PoseRepeatability> {
    if attained.len() < 2 {
        return None;
    }
    let mean = mean_position(attained);
    let l: Vec<f64> = attained
        .iter()
        .map(|p| (p.translation.vector - mean).norm() * 1e3)
        .collect();
    let (l_bar, s_l) = mean_and_sd(&l);
    let angles = angle_differences(attained, abc(&attained[0]));
    let [a, b, c]: [f64; 3] = std::array::from_fn(|i| 3.0 * mean_and_sd(&angles[i]).1 * 1e3);
    Some(PoseRepeatability {
        rp_l_mm: l_bar + 3.0 * s_l,
        l_bar_mm: l_bar,
        s_l_mm: s_l,
        rp_a_mrad: a,
        rp_b_mrad: b,
        rp_c_mrad: c,
    })
}

/// Multi-directional pose accuracy variation, ISO 9283 7.2.3: the largest distance between the
/// mean attained poses of the approach directions.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct DirectionalVariation {
    /// `vAP_P = max sqrt((x_bar_h - x_bar_k)^2 + ...)` over pairs of directions \[mm\].
    pub vap_p_mm: f64,
    /// `vAP_a = max |a_bar_h - a_bar_k|` \[mrad\].
    pub vap_a_mrad: f64,
    /// `vAP_b = max |b_bar_h - b_bar_k|` \[mrad\].
    pub vap_b_mrad: f64,
    /// `vAP_c = max |c_bar_h - c_bar_k|` \[mrad\].
    pub vap_c_mrad: f64,
}

/// [`DirectionalVariation`] of the attained poses of each approach direction (at least two
/// directions, each with a pose).
pub fn directional_variation(per_direction: &[Vec<Isometry3<f64>>]) -> Option<DirectionalVariation> {
    if per_direction.len() < 2 || per_direction.iter().any(Vec::is_empty) {
        return None;
    }
    let reference = abc(&per_direction[0][0]);
    let means: Vec<(Vector3<f64>, [f64; 3])> = per_direction
        .iter()
        .map(|poses| {
            let angles = angle_differences(poses, reference);
            (mean_position(poses), std::array::from_fn(|i| mean_and_sd(&angles[i]).0))
        })
        .collect();
    let (mut p, mut abc_max) = (0.0f64, [0.0f64; 3]);
    for (h, (ph, ah)) in means.iter().enumerate() {
        for (pk, ak) in &means[h + 1..] {
            p = p.max((ph - pk).norm() * 1e3);
            for i in 0..3 {
                abc_max[i] = abc_max[i].max((ah[i] - ak[i]).abs() * 1e3);
            }
        }
    }
    Some(DirectionalVariation {
        vap_p_mm: p,
        vap_a_mrad: abc_max[0],
        vap_b_mrad: abc_max[1],
        vap_c_mrad: abc_max[2],
    })
}

/// Distance accuracy and repeatability, ISO 9283 7.3.1 and 7.3.2, between two poses.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct DistanceFigures {
    /// `D_c`, the commanded distance \[mm\].
    pub commanded_mm: f64,
    /// `AD_P = D_bar - D_c`, `D_j = |P_1j - P_2j|` \[mm\].
    pub ad_p_mm: f64,
    /// `AD_x = D_bar_x - D_cx`, `D_xj = x_1j - x_2j` \[mm\].
    pub ad_x_mm: f64,
    /// `AD_y = D_bar_y - D_cy` \[mm\].
    pub ad_y_mm: f64,
    /// `AD_z = D_bar_z - D_cz` \[mm\].
    pub ad_z_mm: f64,
    /// `RD_P = +-3 S_D`, `S_D = sqrt(sum (D_j - D_bar)^2 / (n - 1))`, the half-width \[mm\].
    pub rd_p_mm: f64,
    /// `RD_x = +-3 S_Dx` \[mm\].
    pub rd_x_mm: f64,
    /// `RD_y = +-3 S_Dy` \[mm\].
    pub rd_y_mm: f64,
    /// `RD_z = +-3 S_Dz` \[mm\].
    pub rd_z_mm: f64,
}

/// [`DistanceFigures`] of pairs of attained poses (at least two pairs) against a commanded
/// pair.
pub fn distance_figures(
    commanded: (&Isometry3<f64>, &Isometry3<f64>),
    attained: &[(Isometry3<f64>, Isometry3<f64>)],
) -> Option<DistanceFigures> {
    if attained.len() < 2 {
        return None;
    }
    let dc = (commanded.0.translation.vector - commanded.1.translation.vector) * 1e3;
    let d: Vec<Vector3<f64>> = attained
        .iter()
        .map(|(p1, p2)| (p1.translation.vector - p2.translation.vector) * 1e3)
        .collect();
    let (d_bar, s_d) = mean_and_sd(&d.iter().map(Vector3::norm).collect::<Vec<_>>());
    let per_axis: [(f64, f64); 3] = std::array::from_fn(|i| mean_and_sd(&d.iter().map(|v| v[i]).collect::<Vec<_>>()));
    Some(DistanceFigures {
        commanded_mm: dc.norm(),
        ad_p_mm: d_bar - dc.norm(),
        ad_x_mm: per_axis[0].0 - dc.x,
        ad_y_mm: per_axis[1].0 - dc.y,
        ad_z_mm: per_axis[2].0 - dc.z,
        rd_p_mm: 3.0 * s_d,
        rd_x_mm: 3.0 * per_axis[0].1,
        rd_y_mm: 3.0 * per_axis[1].1,
        rd_z_mm: 3.0 * per_axis[2].1,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    fn pose(x_mm: f64, y_mm: f64, z_mm: f64, a_mrad: f64) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(x_mm * 1e-3, y_mm * 1e-3, z_mm * 1e-3),
            UnitQuaternion::from_euler_angles(a_mrad * 1e-3, 0.0, 0.0),
        )
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-9 * (1.0 + b.abs())
    }

    /// By hand: x = 1, 2, 3, 6 mm and a = 1, 2, 3, 6 mrad against a commanded origin:
    /// x_bar = 3, AP_P = 3; l = 2, 1, 0, 3, l_bar = 1.5, S_l = sqrt(5/3), RP_l = 1.5 + 3 sqrt(5/3)
    /// = 5.372983346; S_a = sqrt(14/3), RP_a = 3 sqrt(14/3) = 6.480740698.
    #[test]
    fn pose_accuracy_and_repeatability_match_a_hand_computed_example() {
        let attained: Vec<_> = [1.0, 2.0, 3.0, 6.0].iter().map(|&v| pose(v, 0.0, 0.0, v)).collect();
        let ap = pose_accuracy(&pose(0.0, 0.0, 0.0, 0.0), &attained).unwrap();
        assert!(
            close(ap.ap_p_mm, 3.0) && close(ap.ap_x_mm, 3.0) && close(ap.ap_a_mrad, 3.0),
            "{ap:?}"
        );
        let rp = pose_repeatability(&attained).unwrap();
        assert!(
            close(rp.l_bar_mm, 1.5) && close(rp.s_l_mm, (5.0f64 / 3.0).sqrt()),
            "{rp:?}"
        );
        assert!(close(rp.rp_l_mm, 5.372983346207417), "{rp:?}");
        assert!(close(rp.rp_a_mrad, 6.48074069840786), "{rp:?}");
        assert!(pose_repeatability(&attained[..1]).is_none() && pose_accuracy(&attained[0], &[]).is_none());
    }

    /// By hand: D = 100.5, 99, 101 mm against D_c = 100: D_bar = 100.1667, AD = 0.1667;
    /// S_D = sqrt(((1/3)^2 + (7/6)^2 + (5/6)^2) / 2) = sqrt(13/12), RD = 3 sqrt(13/12) = 3.122499.
    #[test]
    fn distance_figures_match_a_hand_computed_example() {
        let o = pose(0.0, 0.0, 0.0, 0.0);
        let pairs = [
            (pose(100.5, 0.0, 0.0, 0.0), o),
            (pose(100.0, 0.0, 0.0, 0.0), pose(1.0, 0.0, 0.0, 0.0)),
            (pose(101.0, 0.0, 0.0, 0.0), o),
        ];
        let d = distance_figures((&pose(100.0, 0.0, 0.0, 0.0), &o), &pairs).unwrap();
        assert!(close(d.commanded_mm, 100.0) && close(d.ad_p_mm, 1.0 / 6.0), "{d:?}");
        assert!(
            close(d.rd_p_mm, 3.0 * (13.0f64 / 12.0).sqrt()) && close(d.rd_x_mm, d.rd_p_mm),
            "{d:?}"
        );
    }

    /// By hand: direction means (0, 0, 0), (1, 0, 0), (0, 2, 0) mm: vAP_P = sqrt(5).
    #[test]
    fn directional_variation_is_the_largest_distance_between_direction_means() {
        let dirs = vec![
            vec![pose(-1.0, 0.0, 0.0, 1.0), pose(1.0, 0.0, 0.0, 3.0)],
            vec![pose(1.0, 0.0, 0.0, 2.0)],
            vec![pose(0.0, 2.0, 0.0, 2.0)],
        ];
        let v = directional_variation(&dirs).unwrap();
        assert!(close(v.vap_p_mm, 5f64.sqrt()) && close(v.vap_a_mrad, 0.0), "{v:?}");
    }

    /// Angles either side of +-pi average to pi, not 0.
    #[test]
    fn angles_across_pi_average_where_they_are() {
        let pi = std::f64::consts::PI;
        let attained = [
            pose(0.0, 0.0, 0.0, (pi - 0.001) * 1e3),
            pose(0.0, 0.0, 0.0, (-pi + 0.001) * 1e3),
        ];
        let ap = pose_accuracy(&pose(0.0, 0.0, 0.0, pi * 1e3), &attained).unwrap();
        assert!(ap.ap_a_mrad.abs() < 1e-9, "{ap:?}");
        let rp = pose_repeatability(&attained).unwrap();
        assert!(close(rp.rp_a_mrad, 3.0 * 2f64.sqrt()), "{rp:?}");
    }
}
