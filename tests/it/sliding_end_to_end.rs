//! Robots with sliding joints and fewer than six joints end to end (issue 15): simulated,
//! calibrated, compensated (fig. 5) and evaluated against the truth, from the library and from
//! the command line, with descriptions written as DH tables and no edits of the data.

use crate::common;

use crate::common::{axiscal, stderr, stdout};
use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
use axiscal::compensation::Compensator;
use axiscal::kinematics::REDUCED_POSITION_TOLERANCE_M;
use axiscal::measurement::{IsotropicNoise, MeasurementModel, MeasurementSet};
use axiscal::plan::{CalibrationPlan, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription, RobotModel, commands_to_internal};
use axiscal::sim::{AnalyticArm, PerturbationSpec, perturb, simulate_campaign};
use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};
use std::path::Path;

/// Measurement noise of the campaigns, 3-D RMS \[mm\].
const NOISE_MM: f64 = 0.1;

fn description(name: &str) -> RobotDescription {
    RobotDescription::from_file(Path::new(&format!("scenarios/robots/{name}.toml"))).unwrap()
}

/// A robot drawn around `desc` (tests/data/test-robot-spec.toml) with stream `seed`.
fn truth(desc: &RobotDescription, seed: u64) -> RobotModel {
    let spec = PerturbationSpec::from_toml_str(include_str!("../data/test-robot-spec.toml"), "spec").unwrap();
    perturb(desc, &spec, &mut ChaCha12Rng::seed_from_u64(seed)).unwrap()
}

/// The generalised Table 1 of `desc` on `truth`, measured with [`NOISE_MM`].
fn campaign(desc: &RobotDescription, truth: &RobotModel, seed: u64) -> MeasurementSet {
    let mut arm = AnalyticArm::new(truth.clone(), Controller::from_description(desc));
    let validation = ValidationPlan {
        poses: 0,
        ..ValidationPlan::workspace_default(desc.dof())
    };
    let instrument = MeasurementModel::Isotropic(IsotropicNoise {
        net_radial_rms_mm: NOISE_MM,
    });
    let out = simulate_campaign(
        desc,
        &CalibrationPlan::for_robot(desc),
        &validation,
        &mut arm,
        &instrument,
        &mut ChaCha12Rng::seed_from_u64(seed),
    )
    .unwrap();
    MeasurementSet::new(desc.dof(), out.rows).unwrap()
}

/// Random commands (file units) within the plan's spans around its reference. A SCARA's elbow
/// (joint 2) is kept bent by at least 20 deg: stretched, the nominal arm reaches points up to
/// the link-length errors (~1 mm) beyond the real arm's reach, which no compensation reaches.
fn random_commands(desc: &RobotDescription, rng: &mut ChaCha12Rng) -> Vec<f64> {
    let mut cmd = common::commands_in_spans(&CalibrationPlan::for_robot(desc), rng);
    if desc.name.starts_with("SCARA") && cmd[1].abs() < 20.0 {
        cmd[1] = 20f64.copysign(cmd[1]);
    }
    cmd
}

/// Where `robot` puts the tool frame's origin for internal-unit commands `cmd` \[m\].
fn tool_point(robot: &RobotModel, controller: &Controller, cmd: &[f64]) -> nalgebra::Vector3<f64> {
    let q = robot.joint_values(controller, cmd).unwrap();
    robot.phi_model().world_from_tool(&q).translation.vector
}

/// `(uncompensated, compensated)` RMS tool-point error \[mm\] of `truth` asked for the poses
/// the nominal model reaches at 40 random commands, compensated with `calibrated`.
fn compensation_errors(desc: &RobotDescription, truth: &RobotModel, calibrated: &RobotModel) -> (f64, f64) {
    let controller = Controller::from_description(desc);
    let nominal = desc.nominal_model();
    let ideal = RobotModel::ideal(desc);
    let comp = Compensator::new(calibrated, desc).unwrap();
    let mut rng = ChaCha12Rng::seed_from_u64(5);
    let (mut before, mut after) = (0.0, 0.0);
    let n = 40;
    for _ in 0..n {
        let cmd = commands_to_internal(desc, &random_commands(desc, &mut rng));
        let required = nominal.world_from_tool(&ideal.joint_values(&controller, &cmd).unwrap());
        let c = comp.compensate(&required).expect("a reachable pose is compensated");
        before += (tool_point(truth, &controller, &cmd) - required.translation.vector).norm_squared();
        after += (tool_point(truth, &controller, &c.cmd) - required.translation.vector).norm_squared();
    }
    ((before / n as f64).sqrt() * 1e3, (after / n as f64).sqrt() * 1e3)
}

/// Compensation with the truth itself as the calibration reaches the required points to the
/// IK's position tolerance: fig. 5 inverts sliding joints' scale errors and zero offsets
/// exactly, and reaches with four joints what four joints can.
#[test]
fn compensation_with_the_true_model_is_exact_for_sliding_robots() {
    for name in ["table-prpp", "scara-rrpr"] {
        let desc = description(name);
        let truth = truth(&desc, 7);
        let (before, after) = compensation_errors(&desc, &truth, &truth);
        println!("{name}: truth as calibration: uncompensated {before:.3} mm, compensated {after:.2e} mm");
        // The IK tolerance plus rounding (1e-9 mm of a metre-sized pose).
        assert!(after <= REDUCED_POSITION_TOLERANCE_M * 1e3 + 1e-9, "{name}: {after} mm");
        assert!(before > 100.0 * after.max(1e-6), "{name}: the perturbation is visible");
    }
}

/// Simulated, calibrated from 0.1 mm measurements, compensated and evaluated against the truth
/// at 40 random poses: the compensated tool point is far closer than the uncompensated one, and
/// within twice one measurement's noise: the tool frame rests on three points measured at one
/// pose (each [`NOISE_MM`] 3-D RMS), so its origin alone is uncertain by about
/// `NOISE_MM / sqrt(3)` before its orientation's lever and the axes' errors add.
#[test]
fn sliding_robots_are_calibrated_compensated_and_evaluated() {
    for (name, seed) in [("table-prpp", 41), ("scara-rrpr", 42)] {
        let desc = description(name);
        let truth = truth(&desc, 8);
        let options = CalibrationOptions {
            noise_rms_3d_mm: NOISE_MM,
            ..CalibrationOptions::default()
        };
        let cal = calibrate(&campaign(&desc, &truth, seed), &desc, &options).unwrap();
        let (before, after) = compensation_errors(&desc, &truth, &cal.robot);
        println!("{name}: uncompensated {before:.3} mm, compensated {after:.3} mm RMS");
        assert!(after < 2.0 * NOISE_MM, "{name}: compensated {after} mm");
        assert!(after < before / 5.0, "{name}: {after} vs {before} mm");
    }
}

/// `axiscal simulate` then `axiscal calibrate` of `robot` with `plan` (if any) from the DH-table
/// descriptions in `scenarios/robots/`, nothing edited in between; returns the folder, the
/// calibration folder and calibrate's stdout.
fn simulate_and_calibrate(robot: &str, plan: Option<&str>) -> (tempfile::TempDir, std::path::PathBuf, String) {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("campaign.csv");
    let desc = format!("scenarios/robots/{robot}.toml");
    let mut sim = axiscal();
    sim.args([
        "simulate",
        "--sim",
        "analytic",
        "--instrument",
        "isotropic",
        "--seed",
        "3",
    ])
    .args([
        "--robot",
        &desc,
        "--truth",
        &format!("scenarios/robots/{robot}-truth.toml"),
    ])
    .args(["--validation-poses", "10", "--out"])
    .arg(&data);
    if let Some(p) = plan {
        sim.args(["--plan", p]);
    }
    sim.assert().success();
    let out = dir.path().join("cal");
    let a = axiscal()
        .args(["calibrate", "--robot", &desc, "--out"])
        .arg(&out)
        .arg(&data)
        .assert();
    let text = format!("{}{}", stdout(&a), stderr(&a));
    a.success();
    (dir, out, text)
}

/// The three campaigns of the issue from the command line: a P-R-P-P table, a two-axis
/// positioner and one joint of a six-axis arm, each described by a DH table.
#[test]
fn cli_calibrates_the_table_the_positioner_and_a_one_joint_campaign() {
    let (_d, out, text) = simulate_and_calibrate("table-prpp", Some("scenarios/robots/table-prpp-plan.toml"));
    assert!(text.contains("(4 axes)"), "{text}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("sliding joint 1 travels"), "{report}");
    assert!(report.contains("Base frame:"), "{report}");
    let residuals = std::fs::read_to_string(out.join("residuals.csv")).unwrap();
    assert!(residuals.lines().count() > 60, "one row per point");

    let (_d, _out, text) = simulate_and_calibrate("positioner-2axis", None);
    assert!(text.contains("(2 axes)"), "{text}");

    let (_d, out, text) = simulate_and_calibrate("arm6-dh", Some("scenarios/robots/arm6-joint1-plan.toml"));
    assert!(text.contains("(1 axes)") || text.contains("(1 axis)"), "{text}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("Not calibrated (no axis experiment): joint(s) 2, 3, 4, 5, 6"),
        "{report}"
    );
}

/// `axiscal compensate` on the calibrated table: the sliding joints' commands come in mm
/// (`cmd_k_mm`), and every reachable pose is compensated.
#[test]
fn cli_compensates_a_sliding_robot_in_mm() {
    let (dir, out, _) = simulate_and_calibrate("table-prpp", Some("scenarios/robots/table-prpp-plan.toml"));
    let desc = description("table-prpp");
    let nominal = desc.nominal_model();
    let ideal = RobotModel::ideal(&desc);
    let controller = Controller::from_description(&desc);
    let mut rng = ChaCha12Rng::seed_from_u64(9);
    let mut poses = String::from("id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\n");
    for i in 0..5 {
        let cmd = commands_to_internal(&desc, &random_commands(&desc, &mut rng));
        let p = nominal.world_from_tool(&ideal.joint_values(&controller, &cmd).unwrap());
        poses.push_str(&common::pose_line(&format!("p{i}"), &p));
    }
    let poses_file = dir.path().join("poses.csv");
    std::fs::write(&poses_file, poses).unwrap();
    let commands = dir.path().join("commands.csv");
    axiscal()
        .args([
            "compensate",
            "--robot",
            "scenarios/robots/table-prpp.toml",
            "--calibration",
        ])
        .arg(out.join("calibration.json"))
        .arg("--poses")
        .arg(&poses_file)
        .arg("--out")
        .arg(&commands)
        .assert()
        .success();
    let text = std::fs::read_to_string(&commands).unwrap();
    let header = text.lines().next().unwrap();
    assert!(
        header.starts_with("id,status,cmd_1_mm,cmd_2_deg,cmd_3_mm,cmd_4_mm,"),
        "{header}"
    );
    assert_eq!(text.lines().filter(|l| l.contains(",ok,")).count(), 5, "{text}");
}

/// The rapier multibody (prismatic joints as rapier's prismatic joints) reproduces the analytic
/// arm's link frames on the sliding robots, a second and differently written forward model:
/// same truth, same commands, within a micrometre at a 1 m lever (rounding is ~1e-13 m).
#[test]
fn rapier_sliding_joints_agree_with_the_analytic_arm() {
    use axiscal::sim::{ArmExecutor, Effects, RapierArm, RapierArmOptions};
    for name in ["table-prpp", "scara-rrpr"] {
        let desc = description(name);
        let mut truth = truth(&desc, 9);
        for j in &mut truth.joints {
            j.repeatability_sigma = 0.0;
        }
        let controller = Controller::from_description(&desc);
        let mut analytic = AnalyticArm::new(truth.clone(), controller);
        let mut rapier = RapierArm::new(truth, &desc, Effects::default(), RapierArmOptions::new(desc.dof()));
        let conditions = axiscal::plan::PoseConditions::default();
        let mut draw = ChaCha12Rng::seed_from_u64(12);
        let mut rng = ChaCha12Rng::seed_from_u64(0);
        let mut worst_m = 0.0_f64;
        for _ in 0..200 {
            let cmd: Vec<f64> = (0..desc.dof())
                .map(|k| {
                    let [lo, hi] = desc.limits_internal(k);
                    draw.random_range(lo..hi)
                })
                .collect();
            let a = analytic.execute(&cmd, &conditions, &mut rng).unwrap();
            let r = rapier.execute(&cmd, &conditions, &mut rng).unwrap();
            for (fa, fr) in a.iter().zip(&r) {
                let d = fa.to_homogeneous() - fr.to_homogeneous();
                worst_m = worst_m.max(d.fixed_view::<3, 4>(0, 0).abs().max());
            }
        }
        println!("{name}: worst link-frame disagreement {worst_m:e} m");
        assert!(worst_m < 1e-6, "{name}: {worst_m:e} m");
    }
}

/// A measurement file cut to fewer joints than the description (a reduced robot's columns) is
/// one error naming the file, the line and the missing column, exit code 2, nothing written.
#[test]
fn a_file_with_fewer_command_columns_than_joints_is_one_clear_error() {
    let (dir, _out, _) = simulate_and_calibrate("table-prpp", Some("scenarios/robots/table-prpp-plan.toml"));
    let full = std::fs::read_to_string(dir.path().join("campaign.csv")).unwrap();
    // Drop the last command column (cmd_4, the 11th field) from every data line.
    let reduced: String = full
        .lines()
        .map(|l| match l.starts_with('#') {
            true => format!("{l}\n"),
            false => {
                let mut f: Vec<&str> = l.split(',').collect();
                f.remove(10);
                format!("{}\n", f.join(","))
            }
        })
        .collect();
    let data = dir.path().join("reduced.csv");
    std::fs::write(&data, reduced).unwrap();
    let out = dir.path().join("reduced-cal");
    let a = axiscal()
        .args(["calibrate", "--robot", "scenarios/robots/table-prpp.toml", "--out"])
        .arg(&out)
        .arg(&data)
        .assert()
        .code(2);
    let err = stderr(&a);
    assert!(
        err.contains("reduced.csv:2: column `cmd_4`: the file has 3 joint command columns, expected 4"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!out.exists(), "nothing written");
}
