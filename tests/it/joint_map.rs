//! From controller readings to calibrated joint values: the tabulated joint map, read the way
//! its documentation tells an outside tool to (nominal decoupling, then linear interpolation
//! in the two tables), agrees with the exact evaluation; the controller zero offsets recover
//! offsets put into a calibrated robot; `axiscal joints` prints the exact values.

use crate::common;

use axiscal::calibration::procedure::{
    Calibration, CalibrationOptions, JointMap, MapTable, calibrate, calibrated_joint_values, controller_zero_offsets,
    joint_map,
};
use axiscal::measurement::{IsotropicNoise, MeasurementModel};
use axiscal::plan::ValidationPlan;
use axiscal::robot::RobotDescription;
use rand::rngs::ChaCha12Rng;
use rand::{RngExt, SeedableRng};

/// A noise-free calibration of the paper robot (nontrivial transmissions and couplings).
fn paper_calibration(desc: &RobotDescription) -> Calibration {
    let set = common::axes_only_campaign_of(
        &common::paper_robot_without_jitter(),
        &MeasurementModel::Isotropic(IsotropicNoise { net_radial_rms_mm: 0.0 }),
        1,
    );
    calibrate(&set, desc, &CalibrationOptions::default()).expect("calibrates")
}

/// Linear interpolation of `table` for `joint` at `x` (inputs ascending).
fn lookup(map: &JointMap, table: MapTable, joint: usize, x: f64) -> Option<f64> {
    let rows: Vec<_> = map
        .rows
        .iter()
        .filter(|r| r.table == table && r.joint == joint)
        .collect();
    let i = rows.windows(2).position(|w| w[0].input <= x && x <= w[1].input)?;
    let (a, b) = (rows[i], rows[i + 1]);
    Some(a.output + (b.output - a.output) * (x - a.input) / (b.input - a.input))
}

/// The documented recipe: `u_1 = cmd_1`, `u_k = cmd_k - slope_k u_(k-1)`, then
/// `q_k = active_k(u_k) + passive_k(active_(k-1))` (all revolute here: degrees).
fn q_from_tables(map: &JointMap, cmd_deg: &[f64]) -> Vec<f64> {
    let mut u: Vec<f64> = Vec::new();
    for (k, c) in cmd_deg.iter().enumerate() {
        let below = if k == 0 { 0.0 } else { u[k - 1] };
        u.push(c - map.decoupling_slopes[k] * below);
    }
    let active: Vec<f64> = u
        .iter()
        .enumerate()
        .map(|(k, &uk)| lookup(map, MapTable::Active, k + 1, uk).expect("inside the table"))
        .collect();
    (0..cmd_deg.len())
        .map(|k| {
            let passive = (k > 0)
                .then(|| lookup(map, MapTable::Passive, k + 1, active[k - 1]))
                .flatten()
                .unwrap_or(0.0);
            active[k] + passive
        })
        .collect()
}

#[test]
fn the_tabulated_map_read_as_documented_agrees_with_the_exact_values() {
    let desc = RobotDescription::asea_irb6l();
    let cal = paper_calibration(&desc);
    let map = joint_map(&cal, &desc, 0.1);
    assert!(
        map.rows.iter().any(|r| r.table == MapTable::Passive),
        "couplings tabulated"
    );
    let mut rng = ChaCha12Rng::seed_from_u64(5);
    let mut worst: f64 = 0.0;
    for _ in 0..200 {
        let cmd: Vec<f64> = desc
            .joints
            .iter()
            .map(|j| rng.random_range(0.9 * j.limits[0]..0.9 * j.limits[1]))
            .collect();
        let exact: Vec<f64> = calibrated_joint_values(&cal, &desc, &cmd)
            .expect("executes")
            .iter()
            .map(|q| q.to_degrees())
            .collect();
        for (a, b) in q_from_tables(&map, &cmd).iter().zip(&exact) {
            worst = worst.max((a - b).abs());
        }
    }
    // Each joint value sums at most an active and a passive interpolation, each within the
    // reported bound (midpoints are where a smooth function's chord is furthest off), plus
    // rounding of the written values.
    assert!(
        worst <= 2.0 * map.max_interpolation_error + 1e-9,
        "worst {worst:e} deg against the reported {:e}",
        map.max_interpolation_error
    );
    assert!(
        map.max_interpolation_error < 1e-4,
        "0.1 deg steps: {:e}",
        map.max_interpolation_error
    );
}

#[test]
fn zero_offsets_put_into_a_calibrated_robot_are_recovered() {
    let desc = RobotDescription::asea_irb6l();
    let mut cal = paper_calibration(&desc);
    // Only offsets on top of a calibration of the ideal robot: the nominal kinematics with
    // the right offsets reproduce it exactly.
    cal.robot = axiscal::robot::RobotModel::ideal(&desc);
    let offsets_deg = [0.3, -0.2, 0.5, 0.1, -0.4, 0.25];
    for (j, o) in cal.robot.joints.iter_mut().zip(offsets_deg) {
        j.transducer_offset = f64::to_radians(o);
    }
    let commands = ValidationPlan::workspace_default(6).commands(&desc, &cal.reference_cmd);
    let fit = controller_zero_offsets(&cal, &desc, &commands).expect("converges");
    // theta_k = u_k - o_k and q_k = theta_k + slope_k theta_(k-1), cmd_k = u_k + slope_k u_(k-1):
    // q_k = cmd_k - o_k - slope_k o_(k-1), so the reading needs + (-o_k - slope_k o_(k-1)).
    for k in 0..6 {
        let slope = desc.nominal_coupling_into(k + 1).unwrap_or(0.0);
        let below = if k == 0 { 0.0 } else { offsets_deg[k - 1] };
        let expected = -offsets_deg[k] - slope * below;
        assert!(
            (fit.offsets[k] - expected).abs() < 1e-9,
            "joint {}: {} against {expected}",
            k + 1,
            fit.offsets[k]
        );
    }
    assert!(fit.rms_before_mm > 1.0, "the offsets matter: {} mm", fit.rms_before_mm);
    assert!(fit.rms_after_mm < 1e-8, "nothing left: {} mm", fit.rms_after_mm);
}

#[test]
fn joints_prints_the_exact_calibrated_joint_values() {
    let desc = RobotDescription::asea_irb6l();
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("calibration.json");
    let cal = paper_calibration(&desc);
    std::fs::write(
        &path,
        axiscal::json_file::to_string(axiscal::json_file::Schema::CALIBRATION, &cal).expect("json"),
    )
    .expect("write");
    let cmd = [10.0, -20.0, 30.0, 40.0, -50.0, 60.0];
    let a = common::axiscal()
        .args(["joints", "--calibration"])
        .arg(&path)
        .arg("--")
        .args(cmd.map(|c| c.to_string()))
        .assert()
        .success();
    let printed: Vec<f64> = common::stdout(&a)
        .split_whitespace()
        .map(|v| v.parse().expect("a number"))
        .collect();
    let exact = calibrated_joint_values(&cal, &desc, &cmd).expect("executes");
    for (p, e) in printed.iter().zip(&exact) {
        // Written as the shortest text that reads back to the same float.
        assert_eq!(p.to_bits(), e.to_degrees().to_bits());
    }
    // A batch: every row gets q_1 .. q_6 appended; a bad field names file, line and column.
    let csv = dir.path().join("readings.csv");
    let joints_csv = |text: &str| {
        std::fs::write(&csv, text).expect("write");
        common::axiscal()
            .args(["joints", "--calibration"])
            .arg(&path)
            .arg("--csv")
            .arg(&csv)
            .output()
            .expect("runs")
    };
    let header = "id,cmd_1,cmd_2,cmd_3,cmd_4,cmd_5,cmd_6\n";
    let o = joints_csv(&format!("{header}a,10,-20,30,40,-50,60\n"));
    assert!(o.status.success());
    let out = String::from_utf8_lossy(&o.stdout);
    let row: Vec<&str> = out.lines().nth(1).expect("a row").split(',').collect();
    assert_eq!(row.len(), 13);
    assert_eq!(
        row[7].parse::<f64>().expect("q_1").to_bits(),
        exact[0].to_degrees().to_bits()
    );
    // The comment lines before the header are copied; a bad row after good ones leaves stdout
    // empty (no table cut short at it).
    let comments = "# robot 17, 2026-12-05\n#  operator: A\n";
    let o = joints_csv(&format!(
        "{comments}{header}a,10,-20,30,40,-50,60\nb,10,-20,30,40,-50,60\nc,10,-20,x,40,-50,60\n"
    ));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(": line 6, column cmd_3"), "{err}");
    assert!(o.stdout.is_empty());
    let o = joints_csv(&format!("{comments}{header}a,10,-20,30,40,-50,60\n"));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success() && out.starts_with("# robot 17, 2026-12-05\n# operator: A\nid,cmd_1,"),
        "{out}"
    );
    assert!(!String::from_utf8_lossy(&o.stderr).contains("radians?"));
    // Readings in radians (every revolute command within +-2 pi, read as degrees) are converted
    // as degrees, with a warning naming the file.
    let radians: Vec<String> = cmd.iter().map(|c| c.to_radians().to_string()).collect();
    let o = joints_csv(&format!("{header}a,{}\nb,{}\n", radians.join(","), radians.join(",")));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("readings.csv: every revolute joint's command lies within +-6.283") && err.contains("radians?"),
        "{err}"
    );
}

/// A calibration whose robot lost a row (a damaged or hand-edited file, as the fuzzer found)
/// is one error naming the file and the field for `joints` and `compensate`, never a panic.
#[test]
fn a_damaged_calibration_robot_is_one_clear_error() {
    let desc = RobotDescription::asea_irb6l();
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("calibration.json");
    let text = axiscal::json_file::to_string(axiscal::json_file::Schema::CALIBRATION, &paper_calibration(&desc))
        .expect("json");
    let mut json: serde_json::Value = serde_json::from_str(&text).expect("parses");
    json["robot"]["rows"].as_array_mut().expect("rows").remove(2);
    std::fs::write(&path, serde_json::to_string(&json).expect("json")).expect("write");
    let poses = dir.path().join("poses.csv");
    std::fs::write(
        &poses,
        "id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\nref,-3151.5,5345.8,167.8,179.56,0.23,-89.01\n",
    )
    .expect("write");
    let joints = common::axiscal()
        .args(["joints", "--calibration"])
        .arg(&path)
        .args(["--", "0", "0", "0", "0", "0", "0"])
        .assert()
        .code(2);
    let compensate = common::axiscal()
        .args(["compensate", "--calibration"])
        .arg(&path)
        .arg("--poses")
        .arg(&poses)
        .arg("--out")
        .arg(dir.path().join("commands.csv"))
        .assert()
        .code(2);
    for a in [joints, compensate] {
        let err = common::stderr(&a);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains("calibration.json") && err.contains("rows"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}
