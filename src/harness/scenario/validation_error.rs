//! Position and orientation error of a model's prediction of the validation targets against
//! their measurements (pure: no truth, no I/O). The uncalibrated error uses the nominal
//! model; the calibrated one will use the calibrated model through the same function.

use crate::kinematics::rigid_fit;
use crate::measurement::Measurement;
use crate::plan::TOOL_EXPERIMENT;
use nalgebra::{Isometry3, Point3};
use std::collections::BTreeMap;

/// Errors over a set of validation poses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ValidationErrors {
    /// RMS over all measured targets of the radial (3-D) position error \[mm\].
    pub pos_rms_mm: f64,
    /// Largest radial position error \[mm\].
    pub pos_max_mm: f64,
    /// RMS over poses with every target measured of the tool-frame orientation error \[rad\].
    pub orient_rms_rad: f64,
    /// Largest orientation error \[rad\].
    pub orient_max_rad: f64,
    /// Targets compared.
    pub targets: usize,
    /// Poses whose orientation was compared.
    pub poses: usize,
}

/// Compares measured validation rows (`moved_joint == 0`) with a model.
///
/// `world_from_tool(row)` predicts the tool frame of a pose from its first row (its file-unit
/// commands `row.cmd`);
/// `tool_targets_m` are the targets in the tool frame. The position error of a target is
/// `|predicted - measured|`. The orientation error of a pose is the angle of the rotation of
/// the least-squares rigid fit ([`rigid_fit`]: Horn's unit quaternion, the rotation of
/// Kabsch's reflection-corrected SVD) that maps the predicted targets onto the
/// measured ones; poses with fewer than three measured targets give no orientation error.
/// With no row at all every field is NaN.
pub fn validation_errors<F>(
    rows: &[Measurement],
    tool_targets_m: &[Point3<f64>],
    world_from_tool: F,
) -> ValidationErrors
where
    F: Fn(&Measurement) -> Isometry3<f64>,
{
    // One group per pose: (experiment, step), in key order. The `tool` observation at the
    // reference pose trains the calibrator's tool frame, so it is not a validation pose.
    let poses: Vec<&Measurement> = rows
        .iter()
        .filter(|m| m.moved_joint == 0 && m.experiment != TOOL_EXPERIMENT)
        .collect();
    fn key(m: &Measurement) -> (&str, usize) {
        (m.experiment.as_str(), m.step)
    }
    let runs: Vec<&[&Measurement]> = poses.chunk_by(|a, b| key(a) == key(b)).collect();
    let mut sums = Sums::default();
    if runs.windows(2).all(|w| key(w[0][0]) < key(w[1][0])) {
        // A campaign's file: each pose's rows follow each other, the poses in key order, so
        // the runs are the groups in order (what the map below gives, without it).
        for group in runs {
            sums.add_pose(group, tool_targets_m, &world_from_tool);
        }
    } else {
        let mut by_step: BTreeMap<(&str, usize), Vec<&Measurement>> = BTreeMap::new();
        for m in poses {
            by_step.entry(key(m)).or_default().push(m);
        }
        for group in by_step.values() {
            sums.add_pose(group, tool_targets_m, &world_from_tool);
        }
    }
    let Sums {
        sum_pos_m2,
        max_pos_m,
        targets,
        sum_ang2,
        max_ang,
        poses,
        ..
    } = sums;
    let rms = |sum: f64, n: usize| if n == 0 { f64::NAN } else { (sum / n as f64).sqrt() };
    ValidationErrors {
        pos_rms_mm: rms(sum_pos_m2, targets) * 1e3,
        pos_max_mm: if targets == 0 { f64::NAN } else { max_pos_m * 1e3 },
        orient_rms_rad: rms(sum_ang2, poses),
        orient_max_rad: if poses == 0 { f64::NAN } else { max_ang },
        targets,
        poses,
    }
}

/// The running sums of [`validation_errors`], with the point buffers of a pose.
#[derive(Default)]
struct Sums {
    sum_pos_m2: f64,
    max_pos_m: f64,
    targets: usize,
    sum_ang2: f64,
    max_ang: f64,
    poses: usize,
    predicted: Vec<Point3<f64>>,
    measured: Vec<Point3<f64>>,
}

impl Sums {
    /// Adds the targets of one pose (its rows: `group`) and, with three or more, its
    /// orientation error.
    fn add_pose<F>(&mut self, group: &[&Measurement], tool_targets_m: &[Point3<f64>], world_from_tool: &F)
    where
        F: Fn(&Measurement) -> Isometry3<f64>,
    {
        let pose = world_from_tool(group[0]);
        self.predicted.clear();
        self.measured.clear();
        for m in group {
            let Some(t) = tool_targets_m.get(m.target) else {
                continue;
            };
            let predicted = pose * t;
            let measured = m.position_m();
            let e = (measured - predicted).norm();
            self.sum_pos_m2 += e * e;
            self.max_pos_m = self.max_pos_m.max(e);
            self.targets += 1;
            self.predicted.push(predicted);
            self.measured.push(measured);
        }
        if let Some((fit, _)) = rigid_fit(&self.predicted, &self.measured) {
            let angle = fit.rotation.angle();
            self.sum_ang2 += angle * angle;
            self.max_ang = self.max_ang.max(angle);
            self.poses += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Translation3, UnitQuaternion, Vector3};

    fn row(step: usize, target: usize, p_m: Point3<f64>) -> Measurement {
        Measurement {
            experiment: "validation".into(),
            moved_joint: 0,
            step,
            target,
            position_mm: [p_m.x * 1e3, p_m.y * 1e3, p_m.z * 1e3],
            cmd: vec![step as f64],
            payload_kg: 0.0,
            temperature_c: 20.0,
        }
    }

    /// Three targets on a tool, not collinear \[m\].
    fn tool_targets() -> [Point3<f64>; 3] {
        [
            Point3::new(0.1, 0.0, 0.0),
            Point3::new(-0.05, 0.08, 0.0),
            Point3::new(0.0, -0.06, 0.03),
        ]
    }

    #[test]
    fn recovers_a_known_rotation_and_offset() {
        let targets = tool_targets();
        let model = |cmd: &[f64]| Isometry3::translation(cmd[0], 1.0, 0.5);
        // The "real" tool is turned by 0.01 rad about z and shifted 1 mm along x.
        let err = Isometry3::from_parts(
            Translation3::new(0.001, 0.0, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.01),
        );
        let rows: Vec<Measurement> = (0..4)
            .flat_map(|s| {
                let real = model(&[s as f64]) * err;
                targets.iter().enumerate().map(move |(i, t)| row(s, i, real * t))
            })
            .collect();
        let e = validation_errors(&rows, &targets, |m| model(&m.cmd));
        assert_eq!((e.targets, e.poses), (12, 4));
        assert_relative_eq!(e.orient_rms_rad, 0.01, max_relative = 1e-9);
        assert_relative_eq!(e.orient_max_rad, 0.01, max_relative = 1e-9);
        assert!(e.pos_max_mm >= 1.0 && e.pos_rms_mm <= e.pos_max_mm);
        let exact = validation_errors(&rows, &targets, |m| model(&m.cmd) * err);
        assert!(exact.pos_max_mm < 1e-9 && exact.orient_max_rad < 1e-9);
    }

    #[test]
    fn poses_out_of_order_give_the_same_numbers_as_in_order() {
        let targets = tool_targets();
        let model = |m: &Measurement| Isometry3::translation(m.cmd[0], 1.0, 0.5);
        let measured = |s: usize, i: usize| {
            let wobble = Isometry3::rotation(Vector3::new(0.01 * s as f64, -0.003 * i as f64, 0.002));
            row(s, i, wobble * Isometry3::translation(s as f64, 1.0, 0.5) * targets[i])
        };
        let in_order: Vec<Measurement> = (0..5).flat_map(|s| (0..3).map(move |i| measured(s, i))).collect();
        // The same poses, last first, each pose's rows in their order: the groups by key.
        let reversed: Vec<Measurement> = (0..5).rev().flat_map(|s| (0..3).map(move |i| measured(s, i))).collect();
        let a = validation_errors(&in_order, &targets, model);
        assert_eq!(a, validation_errors(&reversed, &targets, model));
        assert_eq!((a.targets, a.poses), (15, 5));
        assert!(a.orient_max_rad > 0.03);
    }

    #[test]
    fn no_rows_is_nan() {
        let e = validation_errors(&[], &[], |_| Isometry3::identity());
        assert!(e.pos_rms_mm.is_nan() && e.orient_max_rad.is_nan());
    }
}
