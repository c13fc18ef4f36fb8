//! Hostile campaigns whose results were reported silently wrong, or whose errors named the
//! wrong cause: a singular phi-model row (written as a DH twist), coaxial axes, a copied sweep,
//! a mirrored frame seen by `diagnose`, a one-joint certificate, a coordinate kilometres off, a
//! turning joint's points on a line, and validation rows in metres beside a tool row in mm.
//! Each is checked against what its input makes true, not against a recorded output.

use crate::common::{altered_csv, axiscal, simulate_analytic, stderr, stdout};
use std::path::{Path, PathBuf};

fn shipped(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// The shipped robot `name` with `from` replaced by `to` (each must occur), written as `out`
/// in `dir`.
fn edited_robot(dir: &Path, name: &str, edits: &[(&str, &str)], out: &str) -> PathBuf {
    let mut text = std::fs::read_to_string(shipped(&format!("scenarios/robots/{name}.toml"))).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{name}: no {from:?}");
        text = text.replace(from, to);
    }
    let path = dir.join(out);
    std::fs::write(&path, text).unwrap();
    path
}

/// The file line (1-based) of the first row of `file` for which `is` holds.
fn line_of(file: &Path, is: impl Fn(&[&str]) -> bool) -> usize {
    let text = std::fs::read_to_string(file).unwrap();
    1 + text
        .lines()
        .position(|l| is(&l.split(',').collect::<Vec<_>>()))
        .expect("such a row")
}

#[test]
fn a_phi_row_written_with_the_dh_twist_is_refused_as_singular() {
    let dir = tempfile::tempdir().unwrap();
    // The hostile user's "every axis parallel": each row's alpha set to 0, as a DH twist.
    let robot = edited_robot(
        dir.path(),
        "asea-irb6l",
        &[("alpha_deg = 90.0", "alpha_deg = 0.0")],
        "parallel.toml",
    );
    let a = axiscal()
        .current_dir(dir.path())
        .args(["describe", "parallel.toml"])
        .assert()
        .code(2);
    let e = stderr(&a);
    for name in ["parallel.toml", "alpha_deg", "singular", "not the DH twist", "dh"] {
        assert!(e.contains(name), "no {name:?} in {e}");
    }
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(robot.exists());
}

#[test]
fn coaxial_axes_calibrate_without_a_unit_warning_and_validate() {
    let dir = tempfile::tempdir().unwrap();
    // Joint 2's table turns on joint 1's own axis: the rows' lengths are all zero.
    edited_robot(
        dir.path(),
        "positioner-2axis",
        &[("a_mm = 15.0, alpha_deg = 90.0", "a_mm = 0.0, alpha_deg = 0.0")],
        "coaxial.toml",
    );
    let run = |args: &[&str]| stderr(&axiscal().current_dir(dir.path()).args(args).assert().success());
    run(&[
        "simulate",
        "--robot",
        "coaxial.toml",
        "--sim",
        "analytic",
        "--seed",
        "3",
        "--out",
        "c.csv",
    ]);
    let e = run(&["calibrate", "c.csv", "--robot", "coaxial.toml", "--out", "cal"]);
    assert!(!e.contains("warning"), "the data are the description's robot: {e}");
    run(&[
        "validate",
        "--calibration",
        "cal/calibration.json",
        "c.csv",
        "--robot",
        "coaxial.toml",
        "--out",
        "v",
    ]);
}

#[test]
fn a_copied_sweep_is_refused_naming_both_copies() {
    let dir = tempfile::tempdir().unwrap();
    simulate_analytic(dir.path(), 0, 21, "good.csv");
    let good = std::fs::read_to_string(dir.path().join("good.csv")).unwrap();
    let copy: String = good
        .lines()
        .filter(|l| l.starts_with("axis3,"))
        .map(|l| format!("axis3copy{}\n", &l["axis3".len()..]))
        .collect();
    std::fs::write(dir.path().join("twice.csv"), good.clone() + &copy).unwrap();
    let points = good
        .lines()
        .filter(|l| l.starts_with("axis3,") && l.split(',').nth(3) == Some("0"))
        .count();
    let a = axiscal()
        .current_dir(dir.path())
        .args(["calibrate", "twice.csv", "--out", "out"])
        .assert()
        .code(2);
    let e = stderr(&a);
    let same = format!("both sweep joint 3 with the same {points} measured points");
    for name in ["twice.csv", "axis3 (lines", "axis3copy (lines", same.as_str()] {
        assert!(e.contains(name), "no {name:?} in {e}");
    }
    assert!(!dir.path().join("out").exists());
}

#[test]
fn diagnose_warns_of_a_mirrored_frame_as_calibrate_does() {
    let dir = tempfile::tempdir().unwrap();
    simulate_analytic(dir.path(), 12, 22, "good.csv");
    let mirrored = altered_csv(&dir.path().join("good.csv"), "mirrored.csv", |_| true, |f| f.swap(4, 5));
    // The data check refuses the left-handed frame before any fit ...
    let a = axiscal()
        .current_dir(dir.path())
        .arg("calibrate")
        .arg(&mirrored)
        .args(["--out", "refused"])
        .assert()
        .code(2);
    let e = stderr(&a);
    assert!(e.contains("the instrument frame is left-handed"), "{e}");
    // ... and past it (`--skip-unit-check`) the calibrated robot is said to be the mirror image.
    for command in ["calibrate", "diagnose"] {
        let a = axiscal()
            .current_dir(dir.path())
            .arg(command)
            .arg(&mirrored)
            .args(["--out", command, "--skip-unit-check"])
            .assert()
            .success();
        let e = stderr(&a);
        assert!(e.contains("mirror image of its description"), "{command}: {e}");
    }
}

#[test]
fn a_one_joint_certificate_counts_no_more_measured_parameters_than_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let joint2 = "[[joints]]   # 2: rotary table; its face 180 mm from the tilt axis\nkind = \"revolute\"\nlimits = [-360.0, 360.0]\ndh = { d_mm = 180.0, theta_deg = 0.0, a_mm = 0.0, alpha_deg = 0.0 }\n";
    let target2 = "[[axis_targets]]\njoint = 2\ntarget0 = { link = 2, position_mm = [150.0, 150.0, 180.0] }";
    edited_robot(
        dir.path(),
        "positioner-2axis",
        &[(joint2, ""), (target2, ""), ("link = 2", "link = 1")],
        "tilt.toml",
    );
    let run = |args: &[&str]| stdout(&axiscal().current_dir(dir.path()).args(args).assert().success());
    run(&[
        "simulate",
        "--robot",
        "tilt.toml",
        "--sim",
        "analytic",
        "--seed",
        "4",
        "--out",
        "t.csv",
    ]);
    run(&["calibrate", "t.csv", "--robot", "tilt.toml", "--out", "cal"]);
    let o = run(&[
        "report",
        "--calibration",
        "cal/calibration.json",
        "--robot",
        "tilt.toml",
        "--out",
        "r",
    ]);
    let parameters = crate::common::number_after(&o, "Two-axis positioner: ");
    let measured = crate::common::number_after(&o, "parameters (");
    assert!(measured >= 1.0 && measured <= parameters, "{o}");
    // The JSON holds as many parameters, and as many with an uncertainty.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("r/certificate.json")).unwrap()).unwrap();
    let list = json["parameters"].as_array().unwrap();
    assert_eq!(list.len() as f64, parameters);
    let with_u = list
        .iter()
        .filter(|p| p["standard_uncertainty"].as_f64() > Some(0.0))
        .count();
    assert_eq!(with_u as f64, measured);
}

#[test]
fn a_coordinate_kilometres_off_is_an_outlier_named_by_its_line() {
    let dir = tempfile::tempdir().unwrap();
    simulate_analytic(dir.path(), 0, 23, "good.csv");
    let is_it = |f: &[&str]| f.len() > 6 && f[0] == "axis6" && f[2] == "2" && f[3] == "0";
    for (z_mm, name) in [(9_999_999.0, "km.csv"), (99_999.0, "hundred-m.csv")] {
        let bad = altered_csv(
            &dir.path().join("good.csv"),
            name,
            |_| true,
            |f| {
                if is_it(&f.iter().map(String::as_str).collect::<Vec<_>>()) {
                    f[6] = format!("{z_mm}");
                }
            },
        );
        let line = line_of(&bad, is_it);
        let a = axiscal()
            .current_dir(dir.path())
            .args(["calibrate", name, "--out", &format!("{name}.out")])
            .assert()
            .success();
        let e = stderr(&a);
        assert!(
            e.contains(&format!("{name}:{line}: outlier: experiment axis6 step 2")),
            "{e}"
        );
    }
}

#[test]
fn a_turning_joints_points_on_a_line_are_said_to_be() {
    let dir = tempfile::tempdir().unwrap();
    simulate_analytic(dir.path(), 0, 24, "good.csv");
    // Target 0 of joint 6's sweep moved along a straight line, one step per millimetre.
    let straight = altered_csv(
        &dir.path().join("good.csv"),
        "straight.csv",
        |_| true,
        |f| {
            if f[0] == "axis6" && f[3] == "0" {
                let step: f64 = f[2].parse().unwrap();
                for (c, (start, per_step)) in [(-3100.0, 1.0), (5200.0, 2.0), (17.0, 0.5)].into_iter().enumerate() {
                    f[4 + c] = format!("{}", start + per_step * step);
                }
            }
        },
    );
    let a = axiscal()
        .current_dir(dir.path())
        .arg("calibrate")
        .arg(&straight)
        .args(["--out", "out"])
        .assert()
        .code(2);
    let e = stderr(&a);
    for name in [
        "straight.csv",
        "axis6 (joint 6)",
        "lie on a straight line",
        "target 0 sits on the swept link",
    ] {
        assert!(e.contains(name), "no {name:?} in {e}");
    }
}

#[test]
fn validation_rows_in_metres_beside_a_tool_row_in_millimetres_are_a_unit_slip() {
    let dir = tempfile::tempdir().unwrap();
    simulate_analytic(dir.path(), 30, 25, "good.csv");
    let mixed = altered_csv(
        &dir.path().join("good.csv"),
        "mixed.csv",
        |_| true,
        |f| {
            if f[0] == "validation" {
                crate::common::scale_fields(f, 4..7, 1e-3);
            }
        },
    );
    for command in ["calibrate", "diagnose"] {
        let a = axiscal()
            .current_dir(dir.path())
            .arg(command)
            .arg(&mixed)
            .args(["--out", "out"])
            .assert()
            .code(2);
        let e = stderr(&a);
        let ratio = crate::common::number_after(&e, "mm, ");
        // Printed to 4 decimals: 0.0010 or 0.0011 for metres; the median pose is not the tool row.
        assert!((ratio / 1e-3 - 1.0).abs() < 0.2, "{command}: the bulk's factor: {e}");
        assert!(e.contains("look like metres rather than millimetres"), "{command}: {e}");
    }
}

#[test]
fn tool_target_ids_swapped_turn_the_tool_frame_over_and_are_said() {
    let dir = tempfile::tempdir().unwrap();
    simulate_analytic(dir.path(), 0, 26, "good.csv");
    // The paper robot's tool targets form an isosceles right triangle at target 0: ids 1 and 2
    // swapped fit their mirror image exactly, turned over about the triangle's diagonal.
    let swapped = altered_csv(
        &dir.path().join("good.csv"),
        "swapped.csv",
        |_| true,
        |f| {
            if f[0] == "tool" && (f[3] == "1" || f[3] == "2") {
                f[3] = if f[3] == "1" { "2" } else { "1" }.into();
            }
        },
    );
    let a = axiscal()
        .current_dir(dir.path())
        .arg("calibrate")
        .arg(&swapped)
        .args(["--out", "out"])
        .assert()
        .success();
    let e = stderr(&a);
    let angle = crate::common::number_after(&e, "the tool frame fitted from the tool observation is turned ");
    // 180 deg less the fitted tool frame's few mrad of uncertainty.
    assert!(angle > 170.0, "{e}");
    assert!(e.contains("target ids swapped"), "{e}");
    let clean = axiscal()
        .current_dir(dir.path())
        .args(["calibrate", "good.csv", "--out", "clean"])
        .assert()
        .success();
    assert!(!stderr(&clean).contains("tool frame fitted"), "{}", stderr(&clean));
}

#[test]
fn a_repeatability_that_explains_all_the_scatter_is_said_and_the_noise_not_called_estimated() {
    let dir = tempfile::tempdir().unwrap();
    // 0.02 rad (1.1 deg) on the SCARA's shoulder: far more scatter than its sweeps show.
    edited_robot(
        dir.path(),
        "scara-rrpr",
        &[(
            "[[joints]]   # 1: shoulder, 400 mm column, 350 mm arm\n",
            "[[joints]]   # 1: shoulder, 400 mm column, 350 mm arm\nrepeatability_sigma = 0.02\n",
        )],
        "scara.toml",
    );
    let run = |args: &[&str]| stderr(&axiscal().current_dir(dir.path()).args(args).assert().success());
    run(&[
        "simulate",
        "--robot",
        "scara.toml",
        "--sim",
        "analytic",
        "--seed",
        "5",
        "--out",
        "s.csv",
    ]);
    let e = run(&["calibrate", "s.csv", "--robot", "scara.toml", "--out", "cal"]);
    assert!(
        e.contains("explains all of their scatter") && e.contains("joint 1: 0.02"),
        "{e}"
    );
    let cal = crate::common::read_calibration(&dir.path().join("cal"));
    let noise = cal.noise.expect("a noise report");
    assert_eq!(noise.source, "default");
    assert_eq!(noise.estimate.map(|e| e.rms_3d_mm), Some(0.0));
}

#[test]
fn a_one_joint_rail_is_referenced_at_its_tool_observation_and_validates() {
    let dir = tempfile::tempdir().unwrap();
    let rail = "name = \"Rail\"\ndh_convention = \"classic\"\n[placement]\ntranslation_mm = [2000.0, 300.0, -300.0]\n\
                [[joints]]\nkind = \"prismatic\"\nlimits = [-500.0, 500.0]\n\
                dh = { d_mm = 100.0, theta_deg = 0.0, a_mm = 0.0, alpha_deg = 0.0 }\n\
                [tool]\ntargets_mm = [[200.0, 0.0, 0.0], [0.0, 200.0, 0.0], [-150.0, -150.0, 20.0]]\n\
                [[axis_targets]]\njoint = 1\ntarget0 = { link = 1, position_mm = [150.0, 150.0, 0.0] }\n";
    std::fs::write(dir.path().join("rail.toml"), rail).unwrap();
    let run = |args: &[&str]| stderr(&axiscal().current_dir(dir.path()).args(args).assert().success());
    run(&[
        "simulate",
        "--robot",
        "rail.toml",
        "--sim",
        "analytic",
        "--validation-poses",
        "10",
        "--seed",
        "3",
        "--out",
        "r.csv",
    ]);
    run(&["calibrate", "r.csv", "--robot", "rail.toml", "--out", "cal"]);
    let cal = crate::common::read_calibration(&dir.path().join("cal"));
    // The tool observation is written at command 0: the tool frame is fitted there.
    assert_eq!(cal.reference_cmd, vec![0.0]);
    assert!(cal.tool.is_some(), "the tool frame fitted");
    run(&[
        "validate",
        "--calibration",
        "cal/calibration.json",
        "r.csv",
        "--robot",
        "rail.toml",
        "--out",
        "v",
    ]);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("v/summary.json")).unwrap()).unwrap();
    let verdict = summary["verdict"].as_str().unwrap();
    assert!(verdict.starts_with("consistent"), "{verdict}");
}

#[test]
fn pose_orientations_in_radians_are_said() {
    let dir = tempfile::tempdir().unwrap();
    simulate_analytic(dir.path(), 0, 27, "good.csv");
    axiscal()
        .current_dir(dir.path())
        .args(["calibrate", "good.csv", "--out", "cal"])
        .assert()
        .success();
    // The README's poses (reachable by the IRB/L6), their orientations as written and in radians.
    let poses_deg = [
        ("ref", [-3151.5, 5345.8, 167.8], [179.56, 0.23, -89.01]),
        ("low", [-2992.7, 5292.7, -544.2], [-152.04, -25.32, -70.69]),
    ];
    let file = |radians: bool| {
        let mut text = String::from("id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\n");
        for (id, p, rpy) in poses_deg {
            let a = rpy.map(|d: f64| if radians { d.to_radians() } else { d });
            text += &format!("{id},{},{},{},{},{},{}\n", p[0], p[1], p[2], a[0], a[1], a[2]);
        }
        text
    };
    for (radians, name) in [(false, "deg.csv"), (true, "rad.csv")] {
        std::fs::write(dir.path().join(name), file(radians)).unwrap();
        let out = axiscal()
            .current_dir(dir.path())
            .args([
                "compensate",
                "--calibration",
                "cal/calibration.json",
                "--poses",
                name,
                "--out",
            ])
            .arg(format!("{name}.out.csv"))
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&out.stderr);
        assert_eq!(e.contains("radians?"), radians, "{name}: {e}");
    }
}
