//! Fig. 5 compensation closed in the loop, library and CLI.

use crate::common;

use crate::common::pose_line;
use assert_cmd::Command;
use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
use axiscal::compensation::{CompensationError, Compensator};
use axiscal::harness::evaluation::{JointRanges, Region, random_poses};
use axiscal::kinematics::IkError;
use axiscal::measurement::MeasurementModel;
use axiscal::plan::{CalibrationPlan, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription};
use nalgebra::Isometry3;

/// A noisy calibration of the paper robot (its model differs from the truth by ~1 mm).
fn noisy_calibration() -> axiscal::calibration::procedure::Calibration {
    let desc = RobotDescription::asea_irb6l();
    let validation = ValidationPlan {
        poses: 0,
        ..ValidationPlan::workspace_default(6)
    };
    let set = common::analytic_campaign(
        &axiscal::sim::paper_robot(),
        &CalibrationPlan::table1(6),
        &validation,
        &MeasurementModel::paper_isotropic(),
        4,
    );
    calibrate(&set, &desc, &CalibrationOptions::default()).unwrap()
}

/// A robot whose truth IS the calibrated model reaches every compensated pose within 1 um
/// (IK tolerance 1e-12 m; the transmission inverse is a Newton iteration to rounding).
#[test]
fn compensation_of_a_robot_equal_to_its_calibrated_model_is_exact() {
    let desc = RobotDescription::asea_irb6l();
    let cal = noisy_calibration();
    let truth = cal.robot.clone();
    let comp = Compensator::new(&cal.robot, &desc).unwrap();
    let controller = Controller::from_description(&desc);
    let model = truth.phi_model();
    // Joint 5 within +-60 deg: near +-90 deg axes 4 and 6 line up (wrist singularity), where a
    // calibrated model can lose the pose entirely (a per-pose IK failure, tested below).
    let ranges = JointRanges::around_zero(&desc, &[40.0, 30.0, 35.0, 60.0, 60.0, 90.0]);
    let poses = random_poses(&desc.nominal_model(), &ranges, Region::Workspace, 40, 7);
    for p in &poses {
        let c = comp
            .compensate_from(&p.world_from_tool, &p.q_nominal)
            .unwrap_or_else(|e| panic!("{} q {:?}: {e}", p.id, p.q_nominal));
        let reached = model.world_from_tool(&truth.joint_values(&controller, &c.cmd).unwrap());
        let dp = (reached.translation.vector - p.world_from_tool.translation.vector).norm();
        assert!(dp < 1e-6, "{}: {dp:e} m", p.id);
        // The uncalibrated commands miss by the model error (mm), so the test is not vacuous.
        let nominal = model.world_from_tool(&truth.joint_values(&controller, &p.q_nominal).unwrap());
        assert!((nominal.translation.vector - p.world_from_tool.translation.vector).norm() > 1e-4);
    }
}

#[test]
fn unreachable_pose_is_an_ik_error_for_that_pose() {
    let desc = RobotDescription::asea_irb6l();
    let comp = Compensator::new(&axiscal::sim::paper_robot(), &desc).unwrap();
    let far = Isometry3::translation(10.0, 10.0, 10.0) * desc.nominal_model().world_from_base;
    let e = comp.compensate(&far).unwrap_err();
    assert!(matches!(e, CompensationError::Ik(IkError::NotConverged { .. })), "{e}");
}

fn write_calibration(dir: &std::path::Path) -> std::path::PathBuf {
    let path = dir.join("calibration.json");
    std::fs::write(
        &path,
        axiscal::json_file::to_string(axiscal::json_file::Schema::CALIBRATION, &noisy_calibration()).unwrap(),
    )
    .unwrap();
    path
}

#[test]
fn cli_batch_reports_a_failed_pose_and_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let cal = write_calibration(dir.path());
    let desc = RobotDescription::asea_irb6l();
    let model = desc.nominal_model();
    let mut csv = String::from("id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\n");
    csv += &pose_line("a", &model.world_from_tool(&[0.1, 0.1, -0.2, 0.3, 0.4, 0.5]));
    csv += &pose_line(
        "far",
        &(Isometry3::translation(10.0, 0.0, 0.0) * model.world_from_tool(&[0.0; 6])),
    );
    csv += &pose_line("b", &model.world_from_tool(&[-0.2, 0.05, 0.1, -0.3, 0.2, -0.5]));
    let poses = dir.path().join("poses.csv");
    std::fs::write(&poses, csv).unwrap();
    let out = dir.path().join("commands.csv");
    let assert = Command::cargo_bin("axiscal")
        .unwrap()
        .args(["compensate", "--calibration"])
        .arg(&cal)
        .arg("--poses")
        .arg(&poses)
        .arg("--out")
        .arg(&out)
        .assert()
        .code(2);
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    assert!(stderr.contains("pose far:"), "{stderr}");
    let text = std::fs::read_to_string(&out).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 4);
    assert!(lines[0].starts_with("id,status,cmd_1_deg"));
    assert!(lines[1].starts_with("a,ok,"));
    assert!(lines[2].starts_with("far,ik_failed,"));
    assert!(lines[3].starts_with("b,ok,"));
}

#[test]
fn cli_bad_pose_file_names_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let cal = write_calibration(dir.path());
    let poses = dir.path().join("poses.csv");
    std::fs::write(
        &poses,
        "id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\na,1,2,3,0,0,0\nb,1,oops,3,0,0,0\n",
    )
    .unwrap();
    let assert = Command::cargo_bin("axiscal")
        .unwrap()
        .args(["compensate", "--calibration"])
        .arg(&cal)
        .arg("--poses")
        .arg(&poses)
        .arg("--out")
        .arg(dir.path().join("c.csv"))
        .assert()
        .code(2);
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    assert!(stderr.contains("poses.csv: line 3, column y_mm"), "{stderr}");
}
