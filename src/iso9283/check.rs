//! Whether figures read back from an `iso9283.json` are figures [`evaluate`](super::evaluate())
//! can have written: finite, distances and spreads not negative, each pose once, and the
//! figures that follow from others equal to them (`AP_P` from `AP_x, AP_y, AP_z`, `RP_l` from
//! `l_bar` and `S_l`, the worst from the poses'). A hand-edited or damaged file is said,
//! not put on a certificate.

use super::IsoFigures;

/// Relative difference within which a figure equals the one it follows from: a value written
/// and read back differs from the one computed by a few units in its last place (serde_json's
/// parser), far below this; an edit by far more.
const SAME_VALUE: f64 = 1e-9;

/// Whether `a` equals `b` within [`SAME_VALUE`].
fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= SAME_VALUE * a.abs().max(b.abs()).max(1e-12)
}

impl IsoFigures {
    /// The first value `evaluate` cannot have written, as `field = value: why` (the field as a
    /// JSON path); `None` when every value can be.
    pub fn impossible_value(&self) -> Option<String> {
        let mut seen = std::collections::BTreeSet::new();
        if self.poses.is_empty() {
            return Some("poses = []: no pose has figures".into());
        }
        for (i, p) in self.poses.iter().enumerate() {
            let at = |field: &str| format!("poses[{i}].{field}");
            if !(1..=5).contains(&p.pose) || !seen.insert(p.pose) {
                return Some(format!("{} = {}: each of the poses 1 to 5 once", at("pose"), p.pose));
            }
            if p.cycles == 0 {
                return Some(format!("{} = 0: a pose with figures has cycles", at("cycles")));
            }
            if let Some(why) = figures_for_cycles(p) {
                return Some(format!("{}{why}", at("")));
            }
            if let Some(why) = pose_values(p) {
                return Some(format!("{}{why}", at("")));
            }
        }
        self.campaign_values()
    }

    /// The worst figures, the registration and the distance figures (as
    /// [`IsoFigures::impossible_value`]).
    fn campaign_values(&self) -> Option<String> {
        let worst_ap = self.poses.iter().map(|p| p.accuracy.ap_p_mm).fold(0.0, f64::max);
        let worst_rp = self
            .poses
            .iter()
            .filter_map(|p| p.repeatability.map(|r| r.rp_l_mm))
            .fold(0.0, f64::max);
        let checks = [
            (
                "worst_ap_p_mm",
                self.worst_ap_p_mm,
                same(self.worst_ap_p_mm, worst_ap),
                "the largest poses[].accuracy.ap_p_mm",
            ),
            (
                "worst_rp_l_mm",
                self.worst_rp_l_mm,
                same(self.worst_rp_l_mm, worst_rp),
                "the largest poses[].repeatability.rp_l_mm",
            ),
        ];
        if let Some((field, value, _, why)) = checks.iter().find(|c| !c.2) {
            return Some(format!("{field} = {value}: it is {why}"));
        }
        let spreads = [
            ("registration_rms_mm", self.registration_rms_mm),
            (
                "distance_p2_p4.commanded_mm",
                self.distance_p2_p4.map(|d| d.commanded_mm),
            ),
            ("distance_p2_p4.rd_p_mm", self.distance_p2_p4.map(|d| d.rd_p_mm)),
        ];
        let signed = self.distance_p2_p4.map(|d| {
            [
                d.ad_p_mm, d.ad_x_mm, d.ad_y_mm, d.ad_z_mm, d.rd_x_mm, d.rd_y_mm, d.rd_z_mm,
            ]
        });
        if let Some(v) = signed.iter().flatten().find(|v| !v.is_finite()) {
            return Some(format!("distance_p2_p4 holds {v}: every figure is a finite number"));
        }
        spreads
            .iter()
            .find_map(|&(field, v)| v.filter(|v| !(v.is_finite() && *v >= 0.0)).map(|v| (field, v)))
            .map(|(field, v)| format!("{field} = {v}: a distance or spread is finite and not negative"))
    }
}

/// Whether one pose's figures are those its cycle count gives, as `field = value: why` after
/// the pose's path: repeatability with two cycles or more of the first direction (every cycle
/// without `directional`), none with one; `directional` with two directions, so two cycles.
fn figures_for_cycles(p: &super::PoseFigures) -> Option<String> {
    let one_direction = p.directional.is_none();
    if p.repeatability.is_none() && one_direction && p.cycles > 1 {
        return Some(format!(
            "repeatability = null: a pose of {} cycles in one direction has a repeatability",
            p.cycles
        ));
    }
    if p.cycles == 1 && (p.repeatability.is_some() || !one_direction) {
        let field = if one_direction { "repeatability" } else { "directional" };
        return Some(format!(
            "{field} is given: a pose of one cycle has neither repeatability nor directional figures"
        ));
    }
    None
}

/// The first impossible value of one pose's figures, as `field = value: why` after the pose's
/// path.
fn pose_values(p: &super::PoseFigures) -> Option<String> {
    let a = &p.accuracy;
    let signed = [
        ("accuracy.ap_x_mm", a.ap_x_mm),
        ("accuracy.ap_y_mm", a.ap_y_mm),
        ("accuracy.ap_z_mm", a.ap_z_mm),
        ("accuracy.ap_a_mrad", a.ap_a_mrad),
        ("accuracy.ap_b_mrad", a.ap_b_mrad),
        ("accuracy.ap_c_mrad", a.ap_c_mrad),
    ];
    if let Some((field, v)) = signed.into_iter().find(|(_, v)| !v.is_finite()) {
        return Some(format!("{field} = {v}: every figure is a finite number"));
    }
    let mut spreads = vec![("accuracy.ap_p_mm", a.ap_p_mm)];
    if let Some(r) = &p.repeatability {
        spreads.extend([
            ("repeatability.rp_l_mm", r.rp_l_mm),
            ("repeatability.l_bar_mm", r.l_bar_mm),
            ("repeatability.s_l_mm", r.s_l_mm),
            ("repeatability.rp_a_mrad", r.rp_a_mrad),
            ("repeatability.rp_b_mrad", r.rp_b_mrad),
            ("repeatability.rp_c_mrad", r.rp_c_mrad),
        ]);
    }
    if let Some(d) = &p.directional {
        spreads.extend([
            ("directional.vap_p_mm", d.vap_p_mm),
            ("directional.vap_a_mrad", d.vap_a_mrad),
            ("directional.vap_b_mrad", d.vap_b_mrad),
            ("directional.vap_c_mrad", d.vap_c_mrad),
        ]);
    }
    if let Some((field, v)) = spreads.iter().find(|(_, v)| !(v.is_finite() && *v >= 0.0)) {
        return Some(format!(
            "{field} = {v}: a distance or spread is finite and not negative"
        ));
    }
    let ap_p = (a.ap_x_mm.powi(2) + a.ap_y_mm.powi(2) + a.ap_z_mm.powi(2)).sqrt();
    if !same(a.ap_p_mm, ap_p) {
        return Some(format!(
            "accuracy.ap_p_mm = {}: it is sqrt(ap_x^2 + ap_y^2 + ap_z^2) = {ap_p} (ISO 9283 7.2.1)",
            a.ap_p_mm
        ));
    }
    let rp_l = p.repeatability.map(|r| (r.rp_l_mm, r.l_bar_mm + 3.0 * r.s_l_mm));
    match rp_l {
        Some((given, of)) if !same(given, of) => Some(format!(
            "repeatability.rp_l_mm = {given}: it is l_bar_mm + 3 s_l_mm = {of} (ISO 9283 7.2.2)"
        )),
        _ => None,
    }
}
