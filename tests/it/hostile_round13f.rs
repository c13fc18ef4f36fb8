//! Hostile run 13, class "1 M rows of `diagnose` / `validate` / `report` above 1 GB and not
//! ending" (H2-H4): the per-pose central differences of the tool pose
//! ([`ToolSensitivity::jacobian`], two forward kinematics per parameter and pose) were most of
//! their time. Each moved model's chain now continues from the calibrated model's links below
//! the first frame it changes; kept here: that the Jacobian is still the full forward
//! kinematics' difference quotient bit for bit, computed by a second path (the public
//! [`tool_pose`] of each moved model), on robots of other shapes than the IRB/L6 (DH arms of six
//! and seven joints, a SCARA with a prismatic joint, a two-axis positioner).

use axiscal::calibration::model_parameters::model_parameter_names;
use axiscal::calibration::tool_accuracy::{ToolSensitivity, tool_pose};
use axiscal::robot::{Controller, RobotDescription, RobotModel, commands_to_internal};
use nalgebra::DMatrix;
use std::path::Path;

/// The robots: shipped descriptions of several shapes.
const ROBOTS: [&str; 5] = ["asea-irb6l", "arm6-dh", "arm7-dh", "scara-rrpr", "positioner-2axis"];

/// The difference quotient of the tool pose between the models moved by `+h` and `-h`, each
/// through its full forward kinematics ([`tool_pose`]): the columns of the Jacobian.
fn full_jacobian(s: &ToolSensitivity<'_>, controller: &Controller, cmd: &[f64]) -> DMatrix<f64> {
    let columns: Vec<_> = s.moved_models().collect();
    let mut j = DMatrix::zeros(6, columns.len());
    for (col, (plus, minus, step)) in columns.into_iter().enumerate() {
        let (a, b) = (
            tool_pose(plus, controller, cmd).unwrap(),
            tool_pose(minus, controller, cmd).unwrap(),
        );
        let dp = (a.translation.vector - b.translation.vector) / step;
        let dr = (a.rotation * b.rotation.inverse()).scaled_axis() / step;
        for r in 0..3 {
            j[(r, col)] = dp[r];
            j[(r + 3, col)] = dr[r];
        }
    }
    j
}

/// Every column of the Jacobian equals the full forward kinematics' quotient to the bit, at
/// several commands of every robot, with every model parameter moved (offsets non-zero so that
/// no joint's value is a round zero).
#[test]
fn jacobian_is_the_full_forward_kinematics_bit_for_bit() {
    let mut columns = 0;
    for name in ROBOTS {
        let path = Path::new("scenarios/robots").join(format!("{name}.toml"));
        let desc = RobotDescription::from_file(&path).unwrap();
        let mut robot = RobotModel::ideal(&desc);
        for (k, joint) in robot.joints.iter_mut().enumerate() {
            joint.transducer_offset = 1e-3 * (k as f64 + 1.0);
        }
        let controller = Controller::from_description(&desc);
        let n = model_parameter_names(&robot).len();
        let s = ToolSensitivity::new(&robot, &controller, &DMatrix::from_diagonal_element(n, n, 1e-8));
        for pose in 0..4 {
            let raw: Vec<f64> = (0..desc.dof())
                .map(|k| (pose as f64 - 1.5) * (k as f64 + 1.0) * 3.7)
                .collect();
            let cmd = commands_to_internal(&desc, &raw);
            let (fast, full) = (s.jacobian(&cmd).unwrap(), full_jacobian(&s, &controller, &cmd));
            assert_eq!(fast.shape(), full.shape(), "{name}");
            for (i, (a, b)) in fast.iter().zip(full.iter()).enumerate() {
                assert_eq!(a.to_bits(), b.to_bits(), "{name} pose {pose} entry {i}: {a} vs {b}");
            }
            columns += fast.ncols();
        }
    }
    // Not vacuous: every robot had parameters moved.
    assert!(columns >= ROBOTS.len() * 4 * 6, "{columns} columns compared");
}
