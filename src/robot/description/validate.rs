//! The checks of a description's values ([`RobotDescription::from_toml_str`]): the first
//! invalid field is reported with the file's path.

use super::{DescriptionError, RobotDescription};
use crate::measurement::{format_f64, format_f64_list};
use nalgebra::Point3;
use std::path::Path;

/// An invalid field of a description and what is wrong with it.
type Invalid = (String, String);

/// A revolute joint's limits lie within this \[deg\]: ten turns, beyond any cable-limited
/// joint; larger values are slips (radians read as degrees times 1e3, a dummy 1e300).
const MAX_REVOLUTE_LIMIT_DEG: f64 = 3600.0;

/// A sliding joint's limits lie within this \[mm\]: a 100 m gantry.
const MAX_PRISMATIC_LIMIT_MM: f64 = 1e5;

/// The heaviest link a description may give \[kg\]: 100 t, beyond a gantry's beam (the largest
/// arms' links weigh a few tonnes); more is a slip or a dummy (`1e30`) that makes every gravity
/// load absurd.
pub const MAX_LINK_MASS_KG: f64 = 1e5;

/// A joint's repeatability (1-sigma, rad or m) is at most this: 3 deg or 50 mm, a hundred
/// times the worst arm's; larger values are slips (degrees or micro-units read as rad or m).
pub const MAX_REPEATABILITY_SIGMA: f64 = 0.05;

/// A fitted gear's ratio (joint turns per gear turn) lies within `1/x..=x` of this: beyond,
/// the gear's harmonics turn too fast (or too slowly) for any sweep to resolve.
pub const MAX_GEAR_RATIO: f64 = 1e3;

/// Two stations of an instrument stand at least this far apart \[mm\]: closer, two
/// instruments would overlap (stations in metres read as mm), and their lines of sight meet
/// at angles too small to intersect.
pub const MIN_STATION_DISTANCE_MM: f64 = 100.0;

/// A row's `alpha` (the angle from `Z_phi_i` to axis `i+1`, eq. A3) stays this far \[deg\]
/// from 0 and 180: nearer, the next axis runs almost along `Z_phi_i`, and the row's `a` (where
/// the common normal leaves `Z_phi_i`) moves by the axis's length over `sin^2 alpha` times each
/// radian the fitted axis tilts: 33 times at 10 deg, kilometres as alpha goes to 0. The phi rule
/// of a DH table or URDF (`Z_phi` perpendicular to both axes) gives 90.
pub const MIN_ROW_ALPHA_DEG: f64 = 10.0;

/// An angle written in degrees (a placement's roll, pitch or yaw, a row's or a DH table's
/// angle, a phi angle, a pose's orientation) lies within a turn either way \[deg\]: beyond, it
/// is a slip (radians read as degrees, a dummy 1e9), and its sine and cosine would be round-off.
pub const MAX_ANGLE_DEG: f64 = 360.0;

/// The three tool targets spread at least this far \[mm\] (their largest distance): closer,
/// a theodolite pair (0.2 mm per point) or a laser tracker (0.02-0.05 mm) measures its noise,
/// not the tool's orientation; targets in metres read as mm (0.06 for 60 mm) lie within it.
pub const MIN_TOOL_TARGET_SPREAD_MM: f64 = 1.0;

/// A point of the instrument frame (a station, the robot's base) lies within this of its
/// origin \[mm\]: 1 km, beyond any instrument's reach (values in micrometres or a dummy).
pub const MAX_INSTRUMENT_FRAME_MM: f64 = 1e6;

/// The largest order of a harmonic series (a fitted transmission's or coupling's, a simulated
/// gear error's): turns of the term per turn of its angle; a gear's tooth-mesh error repeats a
/// few hundred times a turn at most. The order also sizes coefficient lists (one pair per order).
pub const MAX_HARMONIC_ORDER: usize = 1000;

/// Why `deg` is no angle of a file (beyond [`MAX_ANGLE_DEG`] or not finite), in words; `None`
/// for an angle within a turn.
pub fn angle_deg_problem(deg: f64) -> Option<String> {
    (deg.is_nan() || deg.abs() > MAX_ANGLE_DEG).then(|| {
        format!(
            "{} deg must be within +-{MAX_ANGLE_DEG} (an angle in degrees: beyond a turn it is a slip, radians or a dummy \
             value)",
            format_f64(deg)
        )
    })
}

impl RobotDescription {
    /// Checks the description's values; the first field found invalid is reported with `path`.
    pub(super) fn validate(&self, path: &Path) -> Result<(), DescriptionError> {
        self.check_name()
            .and_then(|()| self.check_counts())
            .and_then(|()| self.check_joints())
            .and_then(|()| self.check_transmission_fits())
            .and_then(|()| self.check_rows())
            .and_then(|()| self.check_couplings())
            .and_then(|()| self.check_frames())
            .and_then(|()| self.check_tool())
            .and_then(|()| self.check_axis_targets())
            .and_then(|()| self.check_instrument())
            .map_err(|(field, message)| DescriptionError::Invalid {
                path: path.to_owned(),
                field,
                message,
            })
    }

    /// At least one joint, and one row fewer than joints.
    fn check_counts(&self) -> Result<(), Invalid> {
        let n = self.joints.len();
        if n == 0 {
            return Err(("joints".into(), "at least one joint is required".into()));
        }
        if self.rows.len() + 1 != n {
            return Err((
                "rows".into(),
                format!("{} joints need {} rows, found {}", n, n - 1, self.rows.len()),
            ));
        }
        Ok(())
    }

    /// The name is written into the `#` comment lines of outputs and their headings: some text
    /// on one line, no control characters.
    fn check_name(&self) -> Result<(), Invalid> {
        if self.name.trim().is_empty() {
            return Err((
                "name".into(),
                format!(
                    "{:?} is empty: the name heads the outputs (\"calibrated <name> from ...\") and their comment \
                     lines; write the robot's name, e.g. name = \"ASEA IRB/L6\"",
                    self.name
                ),
            ));
        }
        match self.name.chars().find(|c| c.is_control()) {
            Some(c) => Err((
                "name".into(),
                format!(
                    "{:?} holds the control character {c:?}: a name is one line of text (it heads the outputs' comment \
                     lines)",
                    self.name
                ),
            )),
            None => Ok(()),
        }
    }

    /// Each joint's values are finite, its limits ordered, its mass and repeatability >= 0.
    fn check_joints(&self) -> Result<(), Invalid> {
        for (k, j) in self.joints.iter().enumerate() {
            let values: [(&str, &[f64]); 4] = [
                ("phi_deg", &[j.phi_deg]),
                ("limits", &j.limits),
                ("mass_kg", &[j.mass_kg]),
                ("com_mm", &j.com_mm),
            ];
            if let Some((key, _)) = values.iter().find(|(_, v)| v.iter().any(|x| !x.is_finite())) {
                return Err((format!("joints[{k}].{key}"), "values must be finite".into()));
            }
            if let Some(why) = angle_deg_problem(j.phi_deg) {
                return Err((format!("joints[{k}].phi_deg"), why));
            }
            let widest = match j.kind {
                crate::kinematics::JointKind::Revolute => MAX_REVOLUTE_LIMIT_DEG,
                crate::kinematics::JointKind::Prismatic => MAX_PRISMATIC_LIMIT_MM,
            };
            if j.limits.iter().any(|l| l.abs() > widest) {
                return Err((
                    format!("joints[{k}].limits"),
                    format!(
                        "limits beyond +-{widest} (deg or mm) are not a joint's: found [{:e}, {:e}]",
                        j.limits[0], j.limits[1]
                    ),
                ));
            }
            if j.limits[0] >= j.limits[1] {
                return Err((
                    format!("joints[{k}].limits"),
                    "lower limit must be below upper limit".into(),
                ));
            }
            if !(0.0..=MAX_LINK_MASS_KG).contains(&j.mass_kg) {
                return Err((
                    format!("joints[{k}].mass_kg"),
                    format!(
                        "{} kg is not a link's mass: from 0 to {MAX_LINK_MASS_KG} kg (the heaviest arms' links weigh tonnes; \
                         grams written as kg, or a dummy value?)",
                        format_f64(j.mass_kg)
                    ),
                ));
            }
            if !(0.0..=MAX_REPEATABILITY_SIGMA).contains(&j.repeatability_sigma) {
                return Err((
                    format!("joints[{k}].repeatability_sigma"),
                    format!(
                        "{} is not a joint's repeatability: a 1-sigma in rad (revolute) or m (prismatic) from 0 to \
                         {MAX_REPEATABILITY_SIGMA} (arms repeat to 1e-5..1e-3)",
                        format_f64(j.repeatability_sigma)
                    ),
                ));
            }
            for (key, value) in [("max_velocity", j.max_velocity), ("max_effort", j.max_effort)] {
                if let Some(v) = value
                    && !(v.is_finite() && v > 0.0)
                {
                    return Err((
                        format!("joints[{k}].{key}"),
                        format!("must be a positive number, got {}", format_f64(v)),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Each joint's `transmission_fit` gear ratio is finite and within [`MAX_GEAR_RATIO`] of
    /// 1 either way (the fit divides the joint angle by it); every fitted order, a joint's and
    /// a coupling's, at most [`MAX_HARMONIC_ORDER`].
    fn check_transmission_fits(&self) -> Result<(), Invalid> {
        let transmissions = self.joints.iter().enumerate().filter_map(|(k, j)| {
            let order = match j.transmission_fit? {
                super::TransmissionFitForm::Harmonic { order }
                | super::TransmissionFitForm::Gear { order, .. }
                | super::TransmissionFitForm::Polynomial { order } => order,
            };
            Some((format!("joints[{k}].transmission_fit.order"), order))
        });
        let couplings = self.couplings.iter().enumerate().filter_map(|(k, c)| match c.fit? {
            super::CouplingFitForm::Gear { order, .. } => Some((format!("couplings[{k}].fit.order"), order)),
            super::CouplingFitForm::Fractional => None,
        });
        if let Some((key, order)) = transmissions.chain(couplings).find(|(_, o)| *o > MAX_HARMONIC_ORDER) {
            return Err((
                key,
                format!(
                    "{order} is beyond the largest order {MAX_HARMONIC_ORDER} (a gear's error repeats at most a few \
                     hundred times a turn); the paper fits order 1, and each order adds two coefficients that every \
                     sweep of the joint must resolve"
                ),
            ));
        }
        for (k, j) in self.joints.iter().enumerate() {
            if let Some(super::TransmissionFitForm::Gear { ratio, .. }) = j.transmission_fit
                && !(1.0 / MAX_GEAR_RATIO..=MAX_GEAR_RATIO).contains(&ratio.abs())
            {
                return Err((
                    format!("joints[{k}].transmission_fit.ratio"),
                    format!(
                        "{} is not a gear's ratio: joint turns per gear turn, finite and from {} to {MAX_GEAR_RATIO} \
                         in size (negative for a reversing gear)",
                        format_f64(ratio),
                        1.0 / MAX_GEAR_RATIO
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The placement, the tool frame and the tool targets are finite; the frames' angles
    /// within [`MAX_ANGLE_DEG`]; the robot's base within [`MAX_INSTRUMENT_FRAME_MM`] of the
    /// instrument's origin.
    fn check_frames(&self) -> Result<(), Invalid> {
        let frames = [("placement", &self.placement), ("tool.frame", &self.tool.frame)];
        for (key, p) in frames {
            if p.translation_mm.iter().chain(&p.rpy_deg).any(|v| !v.is_finite()) {
                return Err((key.into(), "values must be finite".into()));
            }
            if let Some((i, why)) = p
                .rpy_deg
                .iter()
                .enumerate()
                .find_map(|(i, v)| Some((i, angle_deg_problem(*v)?)))
            {
                return Err((format!("{key}.rpy_deg[{i}]"), why));
            }
        }
        let base = self.placement.translation_mm;
        if base.iter().any(|c| c.abs() > MAX_INSTRUMENT_FRAME_MM) {
            return Err((
                "placement.translation_mm".into(),
                format!(
                    "{}: the robot's base (mm, in the instrument frame) must lie within 1 km of the instrument's origin \
                     (each coordinate within +-{MAX_INSTRUMENT_FRAME_MM:e} mm)",
                    format_f64_list(&base)
                ),
            ));
        }
        if self.tool.targets_mm.iter().flatten().any(|v| !v.is_finite()) {
            return Err(("tool.targets_mm".into(), "values must be finite".into()));
        }
        Ok(())
    }

    /// Each row's values are finite, and its `alpha` at least [`MIN_ROW_ALPHA_DEG`] from 0 and
    /// 180 deg.
    fn check_rows(&self) -> Result<(), Invalid> {
        for (k, r) in self.rows.iter().enumerate() {
            let values = [
                ("a_m", r.a_m),
                ("b_m", r.b_m),
                ("alpha_deg", r.alpha_deg),
                ("beta_deg", r.beta_deg),
                ("gamma_deg", r.gamma_deg),
                ("h_m", r.h_m),
            ];
            if let Some((key, _)) = values.iter().find(|(_, v)| !v.is_finite()) {
                return Err((format!("rows[{k}].{key}"), "must be finite".into()));
            }
            if let Some((key, why)) = values
                .iter()
                .filter(|(key, _)| key.ends_with("_deg"))
                .find_map(|(key, v)| Some((key, angle_deg_problem(*v)?)))
            {
                return Err((format!("rows[{k}].{key}"), why));
            }
            if r.alpha_deg.to_radians().sin().abs() < MIN_ROW_ALPHA_DEG.to_radians().sin() {
                return Err((
                    format!("rows[{k}].alpha_deg"),
                    format!(
                        "{}: within {MIN_ROW_ALPHA_DEG} deg of 0 or 180 the row is singular (axis {} along Z_phi_{}, eq. A3: \
                         its `a` is not determined by any measurement); a phi-model row's alpha is the angle from Z_phi to \
                         the next axis, not the DH twist between the axes: put Z_phi perpendicular to both axes (alpha_deg = \
                         90 or -90, the axes' angle in beta_deg), or give the geometry as a `dh` table (its conversion does so)",
                        format_f64(r.alpha_deg),
                        k + 2,
                        k + 1
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Each coupling drives joint `from + 1` from joint `from` within the robot, with a finite
    /// slope other than 0, and no joint is driven twice.
    fn check_couplings(&self) -> Result<(), Invalid> {
        let n = self.joints.len();
        for (k, c) in self.couplings.iter().enumerate() {
            if c.from == 0 || c.from >= n || c.to != c.from + 1 {
                return Err((
                    format!("couplings[{k}]"),
                    format!(
                        "a coupling drives joint from+1 from joint `from` in 1..{n}; found {} -> {}",
                        c.from, c.to
                    ),
                ));
            }
            if !c.slope.is_finite() || c.slope == 0.0 {
                return Err((
                    format!("couplings[{k}].slope"),
                    format!(
                        "must be finite and not 0 (a slope of 0 is no coupling: remove the entry), found {}",
                        c.slope
                    ),
                ));
            }
            if c.slope.abs() > MAX_GEAR_RATIO {
                return Err((
                    format!("couplings[{k}].slope"),
                    format!(
                        "{} is not a coupling's slope: the passive motion of joint {} per unit motion of joint {}, a \
                         gear between neighbouring joints, at most {MAX_GEAR_RATIO} in size (the IRB/L6's bevel gear: \
                         1.684)",
                        format_f64(c.slope),
                        c.to,
                        c.from
                    ),
                ));
            }
            if self.couplings[..k].iter().any(|d| d.to == c.to) {
                return Err((
                    format!("couplings[{k}]"),
                    format!(
                        "a second coupling into joint {}: one passive coupling drives a joint",
                        c.to
                    ),
                ));
            }
        }
        Ok(())
    }

    /// No tool targets (a robot whose targets a free-pose calibration fits), or exactly three,
    /// spread at least [`MIN_TOOL_TARGET_SPREAD_MM`], not collinear.
    fn check_tool(&self) -> Result<(), Invalid> {
        if self.tool.targets_mm.is_empty() {
            return Ok(());
        }
        if self.tool.targets_mm.len() != 3 {
            return Err((
                "tool.targets_mm".into(),
                format!(
                    "3 tool targets (or none) are required, found {}",
                    self.tool.targets_mm.len()
                ),
            ));
        }
        let t: Vec<Point3<f64>> = self.tool.targets_mm.iter().map(|p| Point3::from(*p)).collect();
        let spread_mm = [(0, 1), (0, 2), (1, 2)]
            .iter()
            .map(|&(a, b)| (t[a] - t[b]).norm())
            .fold(0.0_f64, f64::max);
        if spread_mm < MIN_TOOL_TARGET_SPREAD_MM {
            return Err((
                "tool.targets_mm".into(),
                format!(
                    "the three tool targets lie within {spread_mm:.3} mm of each other, closer than any instrument \
                     tells targets apart ({MIN_TOOL_TARGET_SPREAD_MM} mm): the values are in mm (metres where mm are \
                     expected? multiply by 1000)"
                ),
            ));
        }
        if (t[1] - t[0]).cross(&(t[2] - t[0])).norm() < 1.0 {
            return Err(("tool.targets_mm".into(), "the three tool targets are collinear".into()));
        }
        Ok(())
    }

    /// Given stations: at least one, each finite and within 1 km.
    fn check_instrument(&self) -> Result<(), Invalid> {
        let Some(entry) = &self.instrument else {
            return Ok(());
        };
        if entry.stations_mm.is_empty() {
            return Err((
                "instrument.stations_mm".into(),
                "at least one station is required (or leave out `[instrument]`)".into(),
            ));
        }
        if let Some((k, why)) = station_problem(&entry.stations_mm) {
            return Err((format!("instrument.stations_mm[{k}]"), why));
        }
        Ok(())
    }

    /// Each axis target's joint is in the robot and appears once; target 0 is moved by the
    /// joint (on the joint's own link when it drives a coupling) and target 1 beyond it.
    fn check_axis_targets(&self) -> Result<(), Invalid> {
        let n = self.joints.len();
        for (k, a) in self.axis_targets.iter().enumerate() {
            if a.joint == 0 || a.joint > n {
                return Err((format!("axis_targets[{k}].joint"), format!("must be in 1..={n}")));
            }
            if a.target0.link < a.joint || a.target0.link > n {
                return Err((
                    format!("axis_targets[{k}].target0.link"),
                    format!("must be in {}..={n} (moved by joint {})", a.joint, a.joint),
                ));
            }
            if self.couplings.iter().any(|c| c.from == a.joint) && a.target0.link != a.joint {
                return Err((
                    format!("axis_targets[{k}].target0.link"),
                    format!(
                        "joint {} drives a passive coupling into joint {}, so target 0 must sit on link {} itself \
                         (beyond it, the target would also move by the coupling's actual-vs-nominal error)",
                        a.joint,
                        a.joint + 1,
                        a.joint
                    ),
                ));
            }
            if let Some(t1) = a.target1
                && (t1.link <= a.joint || t1.link > n)
            {
                return Err((
                    format!("axis_targets[{k}].target1.link"),
                    format!("must be in {}..={n} (beyond the swept joint)", a.joint + 1),
                ));
            }
            if self.axis_targets[..k].iter().any(|b| b.joint == a.joint) {
                return Err((
                    format!("axis_targets[{k}].joint"),
                    format!("joint {} appears twice", a.joint),
                ));
            }
        }
        Ok(())
    }
}

/// The first of `stations_mm` that is not a finite point within 1 km, or stands closer than
/// [`MIN_STATION_DISTANCE_MM`] to an earlier one: its index and why.
pub fn station_problem(stations_mm: &[[f64; 3]]) -> Option<(usize, String)> {
    stations_mm.iter().enumerate().find_map(|(k, s)| {
        if !s.iter().all(|c| c.is_finite() && c.abs() <= MAX_INSTRUMENT_FRAME_MM) {
            return Some((
                k,
                format!("{s:?}: each coordinate must be a finite number of mm within 1 km"),
            ));
        }
        let near = stations_mm[..k]
            .iter()
            .position(|t| (Point3::from(*t) - Point3::from(*s)).norm() < MIN_STATION_DISTANCE_MM)?;
        Some((
            k,
            format!(
                "{s:?} is {:.1} mm from station {near}: two stations stand at least {MIN_STATION_DISTANCE_MM} mm \
                 apart (the coordinates are in mm, not m)",
                (Point3::from(stations_mm[near]) - Point3::from(*s)).norm()
            ),
        ))
    })
}
