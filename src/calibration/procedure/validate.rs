//! The checks of a calibration read back from a file (`docs/formats.md#calibration-json`):
//! every value the commands use is checked once, when the file is read, so a damaged or
//! hand-edited file is one error naming its field instead of a panic or a silently wrong
//! prediction later.

use super::Calibration;
use crate::calibration::model_parameters::{ModelCovariance, model_parameter_names};
use crate::measurement::format_f64;
use crate::measurement::unit_check::{MAX_ROW_LENGTH_M, row_slips};
use crate::robot::{
    CouplingFunction, MAX_HARMONIC_AMPLITUDE_RAD, MAX_INSTRUMENT_FRAME_MM, ModelError, Placement, RobotModel,
    Transmission, angle_deg_problem,
};
use nalgebra::DMatrix;

/// The largest noise level a calibration may record, 3-D RMS \[mm\]: beyond any instrument
/// that measures a robot (the range of `--noise-mm`).
pub const MAX_NOISE_RMS_3D_MM: f64 = 100.0;

/// The largest variance of one model parameter, in its name's unit squared: a 1-sigma of 1 m,
/// 1 rad or 1 (a dimensionless coefficient) is no calibration, and far larger values move the
/// propagation's models by more than they can hold (its steps are 1e-3 sigma).
pub const MAX_PARAMETER_VARIANCE: f64 = 1.0;

/// A value of a calibration file out of range or inconsistent with the rest.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("field `{field}`: {message}")]
pub struct InvalidCalibration {
    /// The key's path in the file, e.g. `model_covariance.covariance[3]`.
    pub field: String,
    /// What is wrong and what to write instead.
    pub message: String,
}

fn invalid(field: impl Into<String>, message: impl Into<String>) -> InvalidCalibration {
    InvalidCalibration {
        field: field.into(),
        message: message.into(),
    }
}

impl Calibration {
    /// Checks the values a command uses: one joint count across the fields that list the
    /// joints (`robot.joints`, `robot.rows`, `reference_cmd`), the robot model
    /// ([`RobotModel::validate`]) and its lengths and angles by the descriptions' rules
    /// ([`row_slips`]; no robot link is 20 m long, an angle lies within a turn), the
    /// fitted transmissions' and couplings' harmonics, one value per joint where a list is per
    /// joint (each joint's axis once), the noise levels and the model covariance
    /// ([`ModelCovariance::validate`]).
    pub fn validate(&self) -> Result<(), InvalidCalibration> {
        self.check_joint_count()?;
        self.robot.validate().map_err(in_robot)?;
        check_model_ranges(&self.robot)?;
        if let Some(slip) = row_slips(&self.robot.rows).into_iter().next() {
            return Err(invalid(
                format!("robot.{}", slip.field),
                format!(
                    "{}; recalibrate (or restore the value `axiscal calibrate` wrote)",
                    slip.message
                ),
            ));
        }
        check_fitted_harmonics(&self.robot)?;
        self.check_joint_lists()?;
        self.check_noise()?;
        match &self.model_covariance {
            Some(c) => c.validate(&self.robot),
            None => Ok(()),
        }
    }

    /// `robot.joints`, `robot.rows` (one fewer) and `reference_cmd` count the same joints: when
    /// two of them agree, the third is the field that was cut or extended (a deleted joint is
    /// said as `robot.joints`, not as the rows it no longer matches).
    fn check_joint_count(&self) -> Result<(), InvalidCalibration> {
        let (joints, by_rows, by_commands) = (
            self.robot.joints.len(),
            self.robot.rows.len() + 1,
            self.reference_cmd.len(),
        );
        if joints == by_rows || by_rows != by_commands {
            // Consistent, or no two fields agree against `robot.joints`: `RobotModel::validate`
            // and the joint lists say which field is off.
            return Ok(());
        }
        Err(invalid(
            "robot.joints",
            format!(
                "{joints} entries, where `robot.rows` ({} rows) and `reference_cmd` ({by_commands} values) say the \
                 robot has {by_rows} joints: a joint's entry was deleted or repeated; restore the file \
                 `axiscal calibrate` wrote (or recalibrate)",
                self.robot.rows.len()
            ),
        ))
    }

    /// `reference_cmd` has a finite value per joint; `row_sigma` one per row (or none, a
    /// free-pose calibration); joint numbers name joints of the robot.
    fn check_joint_lists(&self) -> Result<(), InvalidCalibration> {
        let n = self.robot.dof();
        if self.reference_cmd.len() != n || self.reference_cmd.iter().any(|c| !c.is_finite()) {
            return Err(invalid(
                "reference_cmd",
                format!(
                    "{:?}: the robot has {n} joints: one finite command per joint (deg or mm)",
                    self.reference_cmd
                ),
            ));
        }
        if !self.row_sigma.is_empty() && self.row_sigma.len() + 1 != n {
            return Err(invalid(
                "row_sigma",
                format!(
                    "{} entries: the robot has {} rows: one per row",
                    self.row_sigma.len(),
                    n - 1
                ),
            ));
        }
        let lists: [(&str, &str, Vec<usize>); 3] = [
            ("axes", "joint", self.axes.iter().map(|a| a.joint).collect()),
            (
                "zero_offset_sigma",
                "joint",
                self.zero_offset_sigma.iter().map(|z| z.joint).collect(),
            ),
            ("couplings", "to", self.couplings.iter().map(|c| c.to).collect()),
        ];
        for (list, key, joints) in lists {
            if let Some(i) = joints.iter().position(|&j| j == 0 || j > n) {
                return Err(invalid(
                    format!("{list}[{i}].{key}"),
                    format!("joint {}: the robot has joints 1..={n}", joints[i]),
                ));
            }
        }
        // One axis per joint: a repeated entry would be counted twice by the reports and the
        // certificate (and may differ from the first).
        for (i, a) in self.axes.iter().enumerate() {
            if let Some(first) = self.axes[..i].iter().position(|b| b.joint == a.joint) {
                return Err(invalid(
                    format!("axes[{i}].joint"),
                    format!(
                        "joint {} again (`axes[{first}]` is joint {} too): one entry per calibrated joint; the file was \
                         edited, restore the file `axiscal calibrate` wrote (or recalibrate)",
                        a.joint, a.joint
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Every propagated 1-sigma (`row_sigma`, `zero_offset_sigma`) is a finite number, at least
    /// 0: the reports, the certificate and the predicted errors read them.
    fn check_sigmas(&self) -> Result<(), InvalidCalibration> {
        let rows = self.row_sigma.iter().enumerate().flat_map(|(i, r)| {
            [
                ("a_mm", r.a_mm),
                ("b_mm", r.b_mm),
                ("alpha_deg", r.alpha_deg),
                ("beta_deg", r.beta_deg),
            ]
            .map(|(key, v)| (format!("row_sigma[{i}].{key}"), v))
        });
        let zeros = self.zero_offset_sigma.iter().enumerate().flat_map(|(i, z)| {
            [("sigma_rad", z.sigma_rad), ("sigma_mm", z.sigma_mm)]
                .into_iter()
                .filter_map(move |(key, v)| Some((format!("zero_offset_sigma[{i}].{key}"), v?)))
        });
        match rows.chain(zeros).find(|(_, v)| !(v.is_finite() && *v >= 0.0)) {
            Some((field, v)) => Err(invalid(
                field,
                format!(
                    "{}: a 1-sigma is a finite number, 0 or more; the file was damaged or edited: restore the value \
                     `axiscal calibrate` wrote (or recalibrate)",
                    format_f64(v)
                ),
            )),
            None => Ok(()),
        }
    }

    /// Checks that a calibration whose `robot` cannot be traced to `axiscal calibrate` (no
    /// `model_digest`, or one `robot` no longer matches) is one a calibration could be, for the
    /// description `desc` it is used with (the same joint count, checked before): each harmonic
    /// of a transmission or a coupling at most [`MAX_HARMONIC_AMPLITUDE_RAD`], every propagated
    /// 1-sigma finite and at least 0, and each joint's transmission turning one way (its slope
    /// above 0) and giving every command within the joint's limits one joint value (fig. 3
    /// inverts it; a harmonic transmission is checked for every angle by
    /// [`Transmission::problem`], a sliding joint's polynomial can turn back within its travel).
    /// A file `calibrate` wrote holds what it fitted, and `calibrate` warns of what it fits to a
    /// slip; an edited one holds what the editor wrote.
    pub fn plausible_for(&self, desc: &crate::robot::RobotDescription) -> Result<(), InvalidCalibration> {
        check_harmonic_amplitudes(&self.robot)?;
        self.check_sigmas()?;
        self.transmissions_within_limits(desc)
    }

    /// The transmissions of [`Calibration::plausible_for`] over the joints' limits.
    fn transmissions_within_limits(&self, desc: &crate::robot::RobotDescription) -> Result<(), InvalidCalibration> {
        for (k, j) in self.robot.joints.iter().enumerate().take(desc.dof()) {
            let [lo, hi] = desc.limits_internal(k);
            let within = (0..=LIMIT_SAMPLES).map(|i| lo + (hi - lo) * i as f64 / LIMIT_SAMPLES as f64);
            let turns_back = within
                .clone()
                .find(|&t| j.transmission.slope(t).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater));
            let uninvertible = within
                .into_iter()
                .find(|&t| j.transmission.actual_from_command(t).is_none());
            if let Some(t) = turns_back.or(uninvertible) {
                let unit = desc.joints[k].kind.file_unit();
                let shown = desc.joints[k].kind.to_file_units(t);
                return Err(invalid(
                    format!("robot.joints[{k}].transmission"),
                    format!(
                        "at {} {unit}, within joint {}'s limits [{}, {}] {unit}, the transmission turns back (its slope \
                         is not above 0): a command there has no single joint value; the file was edited: restore \
                         the value `axiscal calibrate` wrote (or recalibrate)",
                        format_f64((shown * 1e3).round() / 1e3),
                        k + 1,
                        format_f64(desc.joints[k].limits[0]),
                        format_f64(desc.joints[k].limits[1])
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Every noise level recorded is a finite number above 0 and at most
    /// [`MAX_NOISE_RMS_3D_MM`]: the fits were weighted with it, and `validate`, `report` and
    /// `iso9283 predict` divide by it.
    fn check_noise(&self) -> Result<(), InvalidCalibration> {
        let mut levels = vec![("options.noise_rms_3d_mm", self.options.noise_rms_3d_mm)];
        if let Some(noise) = &self.noise {
            levels.push(("noise.used_rms_3d_mm", noise.used_rms_3d_mm));
        }
        match levels
            .into_iter()
            .find(|(_, v)| !(v.is_finite() && *v > 0.0 && *v <= MAX_NOISE_RMS_3D_MM))
        {
            Some((field, v)) => Err(invalid(
                field,
                format!(
                    "{} mm: a noise level is a 3-D RMS above 0 and at most {MAX_NOISE_RMS_3D_MM} mm; recalibrate \
                     (or restore the value `axiscal calibrate` wrote)",
                    format_f64(v)
                ),
            )),
            None => Ok(()),
        }
    }
}

/// The calibrated model's lengths and angles by the rules a description's obey
/// (`docs/formats.md#robot-description`): the tool frame within [`MAX_ROW_LENGTH_M`] of its
/// link (as a description's tool and targets, no robot link is longer), the base within
/// [`MAX_INSTRUMENT_FRAME_MM`] of the instrument's origin, and every angle (phi, the rows',
/// the frames' roll, pitch and yaw) within a turn ([`angle_deg_problem`]). A calibration
/// fits values a few per cent from the description's; beyond these limits a value was edited
/// or damaged, and every prediction with it would be silently wrong.
fn check_model_ranges(robot: &RobotModel) -> Result<(), InvalidCalibration> {
    let restore = "; the file was damaged or edited: restore the value `axiscal calibrate` wrote (or recalibrate)";
    let tool_mm = nalgebra::Vector3::from(robot.tool_frame.translation_mm).norm();
    if !(tool_mm.is_finite() && tool_mm <= MAX_ROW_LENGTH_M * 1e3) {
        return Err(invalid(
            "robot.tool_frame.translation_mm",
            format!(
                "{} mm from the last link is beyond {MAX_ROW_LENGTH_M} m, further than any robot link is long (the \
                 values are in mm){restore}",
                format_f64(tool_mm)
            ),
        ));
    }
    if let Some(c) = robot
        .placement
        .translation_mm
        .iter()
        .find(|c| !(c.is_finite() && c.abs() <= MAX_INSTRUMENT_FRAME_MM))
    {
        return Err(invalid(
            "robot.placement.translation_mm",
            format!(
                "{} mm: the robot's base lies within 1 km of the instrument's origin (each coordinate within \
                 +-{MAX_INSTRUMENT_FRAME_MM:e} mm){restore}",
                format_f64(*c)
            ),
        ));
    }
    let frame_angles = |key: &'static str, p: &Placement| {
        p.rpy_deg
            .iter()
            .enumerate()
            .map(move |(i, v)| (format!("robot.{key}.rpy_deg[{i}]"), *v))
            .collect::<Vec<_>>()
    };
    let mut angles = frame_angles("tool_frame", &robot.tool_frame);
    angles.extend(frame_angles("placement", &robot.placement));
    for (k, j) in robot.joints.iter().enumerate() {
        angles.push((format!("robot.joints[{k}].phi_deg"), j.phi_deg));
    }
    for (k, r) in robot.rows.iter().enumerate() {
        for (key, v) in [
            ("alpha_deg", r.alpha_deg),
            ("beta_deg", r.beta_deg),
            ("gamma_deg", r.gamma_deg),
        ] {
            angles.push((format!("robot.rows[{k}].{key}"), v));
        }
    }
    match angles
        .into_iter()
        .find_map(|(field, v)| Some((field, angle_deg_problem(v)?)))
    {
        Some((field, why)) => Err(invalid(field, format!("{why}{restore}"))),
        None => Ok(()),
    }
}

/// A [`RobotModel::validate`] error as a field of the file's `robot`.
fn in_robot(e: ModelError) -> InvalidCalibration {
    match e {
        ModelError::Invalid { field, message } => invalid(format!("robot.{field}"), message),
        other => invalid("robot", other.to_string()),
    }
}

/// A fitted harmonic series has as many sine as cosine coefficients (one pair per order): a
/// file with another count was edited, and its covariance no longer names its parameters.
fn check_fitted_harmonics(robot: &RobotModel) -> Result<(), InvalidCalibration> {
    for (k, j) in robot.joints.iter().enumerate() {
        for (key, sin, cos) in harmonic_series(j) {
            if sin.len() != cos.len() {
                return Err(invalid(
                    format!("robot.joints[{k}].{key}"),
                    format!(
                        "`sin` has {} coefficients and `cos` {}: a fitted harmonic series has one of each per order",
                        sin.len(),
                        cos.len()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The harmonic series of joint `j` (its transmission's, a harmonic or a gear; its coupling's,
/// a gear), each with its key in the file and its `(sin, cos)` coefficients.
fn harmonic_series(j: &crate::robot::JointModel) -> Vec<Series<'_>> {
    let transmission = match &j.transmission {
        Transmission::Harmonic { sin, cos } | Transmission::Gear { sin, cos, .. } => Some((sin, cos)),
        Transmission::Polynomial { .. } => None,
    };
    let coupling = match &j.coupling_in {
        Some(CouplingFunction::Gear { sin, cos, .. }) => Some((sin, cos)),
        _ => None,
    };
    [("transmission", transmission), ("coupling_in", coupling)]
        .into_iter()
        .filter_map(|(key, pair)| pair.map(|(sin, cos)| (key, sin.as_slice(), cos.as_slice())))
        .collect()
}

/// A harmonic series of a joint: its key in the file, its sine and its cosine coefficients.
type Series<'a> = (&'static str, &'a [f64], &'a [f64]);

/// Points at which [`Calibration::plausible_for`] tests a transmission over a joint's limits: a
/// sliding joint's polynomial (a scale and a few orders) turns back over a fraction of its
/// travel, far wider than a thousandth.
const LIMIT_SAMPLES: usize = 1000;

/// Each harmonic of a transmission or a coupling (sine and cosine of one order) has an
/// amplitude of at most [`MAX_HARMONIC_AMPLITUDE_RAD`]: a larger one is an edited value
/// (`axiscal calibrate` keeps no such fit: the diagnosis calls it implausible), and every
/// command would be mapped to a joint value tens of degrees off.
fn check_harmonic_amplitudes(robot: &RobotModel) -> Result<(), InvalidCalibration> {
    for (k, j) in robot.joints.iter().enumerate() {
        for (key, sin, cos) in harmonic_series(j) {
            let amplitude = |o: usize| {
                sin.get(o)
                    .copied()
                    .unwrap_or(0.0)
                    .hypot(cos.get(o).copied().unwrap_or(0.0))
            };
            if let Some(o) = (0..sin.len().max(cos.len())).find(|&o| amplitude(o) > MAX_HARMONIC_AMPLITUDE_RAD) {
                return Err(invalid(
                    format!("robot.joints[{k}].{key}"),
                    format!(
                        "its order-{} harmonic (`sin[{o}]` {}, `cos[{o}]` {}) has an amplitude of {} rad ({} deg), \
                         beyond the {MAX_HARMONIC_AMPLITUDE_RAD} rad a joint's transmission error can be (a real \
                         gear's are a few mrad): every command would reach a joint value that far off; the file was \
                         edited: restore the value `axiscal calibrate` wrote (or recalibrate)",
                        o + 1,
                        format_f64(sin.get(o).copied().unwrap_or(0.0)),
                        format_f64(cos.get(o).copied().unwrap_or(0.0)),
                        format_f64((amplitude(o) * 1e4).round() / 1e4),
                        format_f64((amplitude(o).to_degrees() * 1e2).round() / 1e2)
                    ),
                ));
            }
        }
    }
    Ok(())
}

impl ModelCovariance {
    /// Checks that this is a covariance of `robot`'s parameters: its names are
    /// [`model_parameter_names`]`(robot)`, the matrix is square of that size, finite, each
    /// variance at most [`MAX_PARAMETER_VARIANCE`], symmetric to rounding and positive
    /// semi-definite to rounding (eigenvalues above `-100 n eps` times the largest).
    pub fn validate(&self, robot: &RobotModel) -> Result<(), InvalidCalibration> {
        self.check_names(&model_parameter_names(robot))?;
        self.check_shape()?;
        self.check_variances()?;
        let c = self.matrix();
        check_symmetric(&c)?;
        self.check_semi_definite(c)
    }

    /// The names are the model's parameters, in order.
    fn check_names(&self, expected: &[String]) -> Result<(), InvalidCalibration> {
        if self.names.len() != expected.len() {
            return Err(invalid(
                "model_covariance.names",
                format!(
                    "{} names, but `robot` has {} parameters: the covariance belongs to another model (recalibrate, or \
                     restore `robot` as `axiscal calibrate` wrote it)",
                    self.names.len(),
                    expected.len()
                ),
            ));
        }
        match self.names.iter().zip(expected).position(|(a, b)| a != b) {
            Some(i) => Err(invalid(
                format!("model_covariance.names[{i}]"),
                format!(
                    "`{}`, but parameter {i} of `robot` is `{}`: the covariance belongs to another model",
                    self.names[i], expected[i]
                ),
            )),
            None => Ok(()),
        }
    }

    /// One row per name, each with one value per name, all finite.
    fn check_shape(&self) -> Result<(), InvalidCalibration> {
        let n = self.names.len();
        if self.covariance.len() != n {
            return Err(invalid(
                "model_covariance.covariance",
                format!("{} rows for {n} names: one row per name", self.covariance.len()),
            ));
        }
        for (r, row) in self.covariance.iter().enumerate() {
            if row.len() != n {
                return Err(invalid(
                    format!("model_covariance.covariance[{r}]"),
                    format!("{} values for {n} names: one value per name", row.len()),
                ));
            }
            if let Some(c) = row.iter().position(|v| !v.is_finite()) {
                return Err(invalid(
                    format!("model_covariance.covariance[{r}][{c}]"),
                    "not a finite number",
                ));
            }
        }
        Ok(())
    }

    /// The first parameter `(index, name, variance)` whose variance is beyond
    /// [`MAX_PARAMETER_VARIANCE`] (or not finite): the data do not determine it.
    pub fn undetermined(&self) -> Option<(usize, &str, f64)> {
        (0..self.names.len().min(self.covariance.len()))
            .map(|k| {
                (
                    k,
                    self.names[k].as_str(),
                    self.covariance[k].get(k).copied().unwrap_or(f64::NAN),
                )
            })
            .find(|(_, _, v)| v.is_nan() || *v > MAX_PARAMETER_VARIANCE)
    }

    /// Each variance is at least 0 and at most [`MAX_PARAMETER_VARIANCE`].
    fn check_variances(&self) -> Result<(), InvalidCalibration> {
        for (k, name) in self.names.iter().enumerate() {
            let v = self.covariance[k][k];
            if !(0.0..=MAX_PARAMETER_VARIANCE).contains(&v) {
                return Err(invalid(
                    format!("model_covariance.covariance[{k}][{k}]"),
                    format!(
                        "the variance of `{name}` is {}: a variance is at least 0 and at most \
                         {MAX_PARAMETER_VARIANCE} (a 1-sigma of 1 in the name's unit); the file was damaged or edited, \
                         recalibrate",
                        format_f64(v)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// No eigenvalue below `-100 n eps` times the largest: a covariance with a negative
    /// variance along some direction gives no uncertainty (or a draw that panics).
    /// The parameters whose row is all zeros (kept nominal: joints without an experiment) are
    /// left out, exactly (each adds an eigenvalue 0), and the rest scaled to a largest entry of
    /// 1: the eigen-solver does not converge on a large block of exact zeros (it gave an
    /// eigenvalue of 1e-171 as the largest of a calibration of one joint).
    fn check_semi_definite(&self, c: DMatrix<f64>) -> Result<(), InvalidCalibration> {
        let kept: Vec<usize> = (0..c.nrows()).filter(|&r| c.row(r).iter().any(|v| *v != 0.0)).collect();
        let n = kept.len();
        let scale = c.amax();
        if n == 0 || scale == 0.0 {
            return Ok(());
        }
        let block = DMatrix::from_fn(n, n, |r, k| c[(kept[r], kept[k])] / scale);
        let eigen = block.symmetric_eigen();
        let eigenvalues = &eigen.eigenvalues * scale;
        let largest = eigenvalues.amax();
        let (k, lowest) = eigenvalues.argmin();
        if lowest >= -100.0 * n as f64 * f64::EPSILON * largest {
            return Ok(());
        }
        let along = kept[eigen.eigenvectors.column(k).iamax()];
        Err(invalid(
            "model_covariance.covariance",
            format!(
                "not positive semi-definite: an eigenvalue of {} (the largest is {}), mostly along `{}`: no \
                 covariance has a negative variance in any direction; the file was damaged or edited, recalibrate",
                format_f64(lowest),
                format_f64(largest),
                self.names[along]
            ),
        ))
    }
}

/// `c[r][c]` equals `c[c][r]` to rounding: within `1e-9` of `sqrt(c_rr c_cc)` and `n eps`
/// of the largest variance.
fn check_symmetric(c: &DMatrix<f64>) -> Result<(), InvalidCalibration> {
    let n = c.nrows();
    let floor = n as f64 * f64::EPSILON * c.diagonal().amax();
    for r in 0..n {
        for k in 0..r {
            let tolerance = 1e-9 * (c[(r, r)] * c[(k, k)]).sqrt() + floor;
            if (c[(r, k)] - c[(k, r)]).abs() > tolerance {
                return Err(invalid(
                    format!("model_covariance.covariance[{r}][{k}]"),
                    format!(
                        "{}, but `covariance[{k}][{r}]` is {}: a covariance is symmetric; the file was damaged or \
                         edited, recalibrate",
                        format_f64(c[(r, k)]),
                        format_f64(c[(k, r)])
                    ),
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn covariance(variances: &[f64]) -> ModelCovariance {
        let n = variances.len();
        ModelCovariance {
            names: (0..n).map(|k| format!("p{k}")).collect(),
            covariance: (0..n)
                .map(|r| (0..n).map(|c| if r == c { variances[r] } else { 0.0 }).collect())
                .collect(),
        }
    }

    /// The first variance beyond the largest a file may hold is named, as the file check
    /// refuses it; one at the bound is not.
    #[test]
    fn an_undetermined_parameter_is_the_one_the_file_check_refuses() {
        let at_bound = covariance(&[1e-6, MAX_PARAMETER_VARIANCE, 0.0]);
        assert_eq!(at_bound.undetermined(), None);
        assert!(at_bound.check_variances().is_ok());
        let beyond = covariance(&[1e-6, 34339.2, 2.0]);
        assert_eq!(beyond.undetermined(), Some((1, "p1", 34339.2)));
        assert!(beyond.check_variances().unwrap_err().field.ends_with("[1][1]"));
        assert_eq!(covariance(&[f64::NAN]).undetermined().map(|u| u.0), Some(0));
    }
}
