//! `axiscal export`: every file read back by a reader and forward kinematics written here (plain
//! 4x4 arrays, URDF's `Rz(yaw) Ry(pitch) Rx(roll)` multiplied out by hand, a line reader for
//! the YAML), not by the exporter's own, and compared with the calibrated model at random
//! readings; and the nominal UR5e exported against UR's published `kinematics.yaml`.

use crate::common::{axiscal, number_after, read_calibration, stderr, stdout};
use axiscal::calibration::export::ur;
use axiscal::robot::{Controller, RobotDescription, RobotModel, commands_to_internal};
use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

type M4 = [[f64; 4]; 4];

fn mul(a: &M4, b: &M4) -> M4 {
    let mut c = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            c[i][j] = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// URDF `<origin>`: translation then `Rz(yaw) Ry(pitch) Rx(roll)`, multiplied out.
fn origin(x: f64, y: f64, z: f64, r: f64, p: f64, yaw: f64) -> M4 {
    let (sr, cr, sp, cp, sy, cy) = (r.sin(), r.cos(), p.sin(), p.cos(), yaw.sin(), yaw.cos());
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr, x],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr, y],
        [-sp, cp * sr, cp * cr, z],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// The motion of a joint along or about +Z.
fn motion(prismatic: bool, v: f64) -> M4 {
    if prismatic {
        origin(0.0, 0.0, v, 0.0, 0.0, 0.0)
    } else {
        origin(0.0, 0.0, 0.0, 0.0, 0.0, v)
    }
}

/// A rotation vector as a pose (Rodrigues), with a translation.
fn from_rotation_vector(v: [f64; 6]) -> M4 {
    let theta = (v[3] * v[3] + v[4] * v[4] + v[5] * v[5]).sqrt();
    let mut m = origin(v[0], v[1], v[2], 0.0, 0.0, 0.0);
    if theta > 0.0 {
        let k = [v[3] / theta, v[4] / theta, v[5] / theta];
        let (s, c) = (theta.sin(), theta.cos());
        for i in 0..3 {
            for j in 0..3 {
                let cross = match (i, j) {
                    (0, 1) => -k[2],
                    (0, 2) => k[1],
                    (1, 0) => k[2],
                    (1, 2) => -k[0],
                    (2, 0) => -k[1],
                    (2, 1) => k[0],
                    _ => 0.0,
                };
                m[i][j] = if i == j { c } else { 0.0 } + s * cross + (1.0 - c) * k[i] * k[j];
            }
        }
    }
    m
}

/// `key.sub.leaf -> value` of a block YAML file of nested mappings (comments skipped).
fn yaml_lines(text: &str) -> HashMap<String, String> {
    let mut path: Vec<(usize, String)> = Vec::new();
    let mut out = HashMap::new();
    for line in text
        .lines()
        .filter(|l| !l.trim_start().starts_with('#') && !l.trim().is_empty())
    {
        let indent = line.len() - line.trim_start().len();
        let (key, value) = line.trim().split_once(':').expect("key: value");
        path.retain(|(i, _)| *i < indent);
        let full: Vec<&str> = path.iter().map(|(_, k)| k.as_str()).chain([key]).collect();
        if value.trim().is_empty() {
            path.push((indent, key.to_string()));
        } else {
            out.insert(full.join("."), value.trim().to_string());
        }
    }
    out
}

fn num(map: &HashMap<String, String>, key: &str) -> f64 {
    map.get(key).unwrap_or_else(|| panic!("{key} missing")).parse().unwrap()
}

fn origin_of(map: &HashMap<String, String>, prefix: &str) -> M4 {
    let v: Vec<f64> = ["x", "y", "z", "roll", "pitch", "yaw"]
        .iter()
        .map(|k| num(map, &format!("{prefix}.{k}")))
        .collect();
    origin(v[0], v[1], v[2], v[3], v[4], v[5])
}

/// `p[x, y, z, rx, ry, rz]` after `label` in the file's comments.
fn ur_pose_in(text: &str, label: &str) -> M4 {
    let line = text
        .lines()
        .find(|l| l.contains(label))
        .unwrap_or_else(|| panic!("{label} missing"));
    let inside = &line[line.find("p[").unwrap() + 2..line.rfind(']').unwrap()];
    let v: Vec<f64> = inside.split(',').map(|t| t.trim().parse().unwrap()).collect();
    from_rotation_vector([v[0], v[1], v[2], v[3], v[4], v[5]])
}

/// A UR kinematics file's `base_link -> wrist_3_link (= tool0)` at readings `u` \[rad\].
fn ur_forward(map: &HashMap<String, String>, u: &[f64]) -> M4 {
    let mut t = origin(0.0, 0.0, 0.0, 0.0, 0.0, std::f64::consts::PI); // base_link_inertia
    for (segment, &v) in ur::SEGMENTS.iter().zip(u) {
        t = mul(
            &mul(&t, &origin_of(map, &format!("kinematics.{segment}"))),
            &motion(false, v),
        );
    }
    t
}

/// The largest position \[m\] and rotation-matrix entry difference of two poses.
fn difference(a: &M4, b: &M4) -> (f64, f64) {
    let d = ((0..3).map(|i| (a[i][3] - b[i][3]).powi(2)).sum::<f64>()).sqrt();
    let r = (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .map(|(i, j)| (a[i][j] - b[i][j]).abs())
        .fold(0.0, f64::max);
    (d, r)
}

fn as_m4(t: &nalgebra::Isometry3<f64>) -> M4 {
    let h = t.to_homogeneous();
    let mut m = [[0.0; 4]; 4];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = h[(i, j)];
        }
    }
    m
}

/// `n` readings (file units) drawn within the description's limits.
fn random_readings(desc: &RobotDescription, n: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            desc.joints
                .iter()
                .map(|j| rng.random_range(j.limits[0]..=j.limits[1]))
                .collect()
        })
        .collect()
}

/// A simulated campaign of `robot` (analytic arm, isotropic noise) calibrated with
/// `description` (a file in `dir`, or a shipped name): the calibration folder.
fn calibrated(dir: &Path, robot: &str, description: &str, seed: u64) -> PathBuf {
    let csv = dir.join("campaign.csv");
    axiscal()
        .args([
            "simulate",
            "--robot",
            robot,
            "--sim",
            "analytic",
            "--instrument",
            "isotropic",
        ])
        .args(["--seed", &seed.to_string(), "--validation-poses", "10", "--out"])
        .arg(&csv)
        .assert()
        .success();
    let out = dir.join("cal");
    axiscal()
        .args(["calibrate", "--allow-other-robot", "--robot", description])
        .arg(&csv)
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    out.join("calibration.json")
}

/// The shipped description `robot` with every revolute joint fitting a zero offset only (a
/// sliding joint keeps its default, a scale error), written in `dir`.
fn offsets_only(dir: &Path, robot: &str) -> PathBuf {
    let text =
        std::fs::read_to_string(format!("{}/scenarios/robots/{robot}.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let text = text.replace(
        "kind = \"revolute\"\n",
        "kind = \"revolute\"\ntransmission_fit = { form = \"harmonic\", order = 0 }\n",
    );
    let path = dir.join(format!("{robot}-offsets.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// `axiscal export <args> --calibration <cal> --out <out> <extra>`.
fn export_cmd(args: &[&str], cal: &Path, out: &Path, extra: &[&str]) -> assert_cmd::Command {
    let mut c = axiscal();
    c.arg("export")
        .args(args)
        .arg("--calibration")
        .arg(cal)
        .arg("--out")
        .arg(out)
        .args(extra);
    c
}

const UR5E_DEFAULT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/ur5e-default-kinematics.yaml");

#[test]
fn a_calibrated_ur5e_in_kinematics_yaml_reproduces_the_calibrated_tool_pose() {
    let dir = tempfile::tempdir().unwrap();
    let description = offsets_only(dir.path(), "ur5e-dh");
    let cal_path = calibrated(dir.path(), "ur5e-dh", description.to_str().unwrap(), 31);
    let out = dir.path().join("kinematics.yaml");
    let a = export_cmd(
        &[
            "ur-kinematics",
            "--robot",
            description.to_str().unwrap(),
            "--like",
            UR5E_DEFAULT,
        ],
        &cal_path,
        &out,
        &[],
    )
    .assert()
    .success();
    assert!(stdout(&a).contains("hash calib_12788084448423163542"), "{}", stdout(&a));
    let text = std::fs::read_to_string(&out).unwrap();
    let map = yaml_lines(&text);
    assert_eq!(map["kinematics.hash"], "calib_12788084448423163542");
    let (tcp, world_from_base_link) = (
        ur_pose_in(&text, "TCP in tool0"),
        ur_pose_in(&text, "base_link in the instrument frame"),
    );
    let desc = RobotDescription::from_file(&description).unwrap();
    let cal = read_calibration(dir.path().join("cal").as_path());
    let model = cal.robot.phi_model();
    let controller = Controller::from_description(&desc);
    let (mut worst_m, mut worst_r) = (0.0f64, 0.0f64);
    for cmd in random_readings(&desc, 1000, 5) {
        let u = commands_to_internal(&desc, &cmd);
        let want = as_m4(&model.world_from_tool(&cal.robot.joint_values(&controller, &u).unwrap()));
        let got = mul(&mul(&world_from_base_link, &ur_forward(&map, &u)), &tcp);
        let (d, r) = difference(&want, &got);
        (worst_m, worst_r) = (worst_m.max(d), worst_r.max(r));
    }
    println!("UR5e kinematics.yaml read here vs calibrated model: {worst_m:e} m, {worst_r:e} (rotation entries)");
    // The tool pose through a file of exact numbers: rounding of metres through six joints.
    assert!(worst_m < 1e-9 && worst_r < 1e-9, "{worst_m:e} m, {worst_r:e}");
}

#[test]
fn the_nominal_ur5e_exported_is_urs_published_kinematics() {
    let dir = tempfile::tempdir().unwrap();
    let description = offsets_only(dir.path(), "ur5e-dh");
    calibrated(dir.path(), "ur5e-dh", description.to_str().unwrap(), 32);
    let desc = RobotDescription::from_file(&description).unwrap();
    let mut cal = read_calibration(dir.path().join("cal").as_path());
    cal.robot = RobotModel::ideal(&desc);
    let reference = ur::UrKinematics::parse(&std::fs::read_to_string(UR5E_DEFAULT).unwrap(), "default").unwrap();
    let out = ur::export(&cal, &desc, &reference, None).unwrap();
    assert!(out.left_out.is_empty());
    let ours = yaml_lines(&out.kinematics.to_yaml(&[]));
    let theirs = yaml_lines(&std::fs::read_to_string(UR5E_DEFAULT).unwrap());
    let mut worst = (0.0f64, 0.0f64);
    for cmd in random_readings(&desc, 1000, 6) {
        let u: Vec<f64> = cmd.iter().map(|d| d.to_radians()).collect();
        let (d, r) = difference(&ur_forward(&ours, &u), &ur_forward(&theirs, &u));
        worst = (worst.0.max(d), worst.1.max(r));
    }
    println!(
        "nominal UR5e exported vs UR's file: {:e} m, {:e} (rotation entries)",
        worst.0, worst.1
    );
    // UR's own file rounds pi/2 to 1.570796327 (3.4e-10 rad off the DH table's alpha): a
    // 4e-10 m reach over its 0.9 m arm is the largest difference it allows.
    assert!(worst.0 < 1e-9 && worst.1 < 1e-9, "{worst:?}");
    for segment in ur::SEGMENTS {
        for key in ["x", "y", "z"] {
            let k = format!("kinematics.{segment}.{key}");
            assert!(
                (num(&ours, &k) - num(&theirs, &k)).abs() < 1e-9,
                "{k}: {} vs {}",
                ours[&k],
                theirs[&k]
            );
        }
    }
}

#[test]
fn a_ur_export_refuses_what_the_file_cannot_hold_and_a_robot_that_is_not_a_ur() {
    let dir = tempfile::tempdir().unwrap();
    // Harmonic transmissions (the description's default fit).
    let cal = calibrated(dir.path(), "ur5e-dh", "ur5e-dh", 33);
    let out = dir.path().join("k.yaml");
    let base = |extra: &[&str]| {
        export_cmd(
            &["ur-kinematics", "--robot", "ur5e-dh", "--like", UR5E_DEFAULT],
            &cal,
            &out,
            extra,
        )
    };
    let a = base(&[]).assert().code(2);
    assert!(
        stderr(&a).contains("harmonic transmission") && stderr(&a).contains("--approximate"),
        "{}",
        stderr(&a)
    );
    assert!(!out.exists());
    let a = base(&["--approximate"]).assert().success();
    assert!(stdout(&a).contains("APPROXIMATE"), "{}", stdout(&a));
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains("# APPROXIMATE: this file does not hold") && text.contains("joint 6's transmission"));
    // The header states the error it leaves.
    let stated = number_after(&text, "the tool is off the calibrated model by up to ");
    assert!(stated > 0.0);
    // Existing output without --force, a bad hash.
    assert!(stderr(&base(&["--approximate"]).assert().code(2)).contains("--force"));
    let like = std::fs::read_to_string(UR5E_DEFAULT).unwrap();
    // `like`'s text edited by `edit`, written as `name` and exported against: the command's outcome.
    let with_like = |name: &str, edit: &dyn Fn(&str) -> String| {
        let path = dir.path().join(name);
        std::fs::write(&path, edit(&like)).unwrap();
        let like_arg = ["--like", path.to_str().unwrap()];
        let args = [
            &["ur-kinematics", "--robot", "ur5e-dh", "--approximate"][..],
            &like_arg[..],
        ]
        .concat();
        (
            export_cmd(&args, &cal, &dir.path().join(format!("{name}.out")), &[]).assert(),
            path,
        )
    };
    let (a, no_hash) = with_like("no-hash.yaml", &|t| {
        t.replace("  hash: calib_12788084448423163542\n", "")
    });
    let a = a.code(2);
    assert!(
        stderr(&a).contains(&format!(
            "{}: `kinematics.hash`: missing: give --hash",
            no_hash.display()
        )),
        "{}",
        stderr(&a)
    );
    let a = base(&["--approximate", "--force", "--hash", "calib 1"])
        .assert()
        .code(2);
    assert!(stderr(&a).contains("--hash: the hash `calib 1`"), "{}", stderr(&a));
    // A hash of the reference file that is no plain word: the file and its key named, with the fix.
    let (a, bad_hash) = with_like("bad-hash.yaml", &|t| {
        t.replace("calib_12788084448423163542", "\"calib 1;x\"")
    });
    let a = a.code(2);
    assert!(
        stderr(&a).contains(&format!(
            "{}: `kinematics.hash`: the hash `calib 1;x`",
            bad_hash.display()
        )) && stderr(&a).contains("or give --hash"),
        "{}",
        stderr(&a)
    );
    // A byte-order mark before the reference's first key, as a Windows editor writes one.
    with_like("bom.yaml", &|t| format!("\u{feff}{t}")).0.success();
    // A SCARA is no UR.
    let scara = calibrated(&dir.path().join("scara"), "scara-rrpr", "scara-rrpr", 34);
    let a = export_cmd(
        &["ur-kinematics", "--robot", "scara-rrpr", "--like", UR5E_DEFAULT],
        &scara,
        &dir.path().join("scara.yaml"),
        &[],
    )
    .assert()
    .code(2);
    assert!(
        stderr(&a).contains("six revolute joints; the robot description has 4"),
        "{}",
        stderr(&a)
    );
}

/// An origins file's chain at readings `cmd` (file units), with its transmission maps when it
/// has them: `instrument -> tool0`.
fn origins_forward(map: &HashMap<String, String>, desc: &RobotDescription, cmd: &[f64]) -> M4 {
    let u = commands_to_internal(desc, cmd);
    let mut t = origin_of(map, "instrument-base_link");
    for (k, v) in u.iter().enumerate() {
        let name = format!("joint_{}", k + 1);
        let prismatic = map[&format!("{name}.type")] == "prismatic";
        let value = match map.get(&format!("{name}.offset")) {
            Some(_) => v / num(map, &format!("{name}.mechanical_reduction")) + num(map, &format!("{name}.offset")),
            None => *v,
        };
        t = mul(&mul(&t, &origin_of(map, &name)), &motion(prismatic, value));
    }
    mul(&t, &origin_of(map, "flange-tool0"))
}

/// The largest tool-position difference \[m\] between an origins file read here and the
/// calibrated model, at the readings the exporter checks (its seed and draw order: uniform
/// within the limits, internal units, 1000 configurations).
fn origins_worst(map: &HashMap<String, String>, desc: &RobotDescription, cal_dir: &Path) -> f64 {
    let cal = read_calibration(cal_dir);
    let (model, controller) = (cal.robot.phi_model(), Controller::from_description(desc));
    let mut rng = ChaCha12Rng::seed_from_u64(9283);
    let mut worst = 0.0f64;
    for _ in 0..1000 {
        let u: Vec<f64> = (0..desc.dof())
            .map(|k| {
                let [lo, hi] = desc.limits_internal(k);
                rng.random_range(lo..=hi)
            })
            .collect();
        let Ok(q) = cal.robot.joint_values(&controller, &u) else {
            continue;
        };
        let cmd = axiscal::robot::commands_to_file(desc, &u);
        worst = worst.max(difference(&as_m4(&model.world_from_tool(&q)), &origins_forward(map, desc, &cmd)).0);
    }
    worst
}

#[test]
fn origins_of_the_test_robots_read_back_as_the_calibrated_model() {
    for (robot, offsets) in [
        ("table-prpp", "transmission"),
        ("positioner-2axis", "origins"),
        ("scara-rrpr", "transmission"),
        ("arm6-dh", "origins"),
        ("ur5e-dh", "transmission"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let description = offsets_only(dir.path(), robot);
        let cal_path = calibrated(dir.path(), robot, description.to_str().unwrap(), 35);
        let out = dir.path().join("origins.yaml");
        export_cmd(
            &[
                "xacro-yaml",
                "--robot",
                description.to_str().unwrap(),
                "--offsets",
                offsets,
            ],
            &cal_path,
            &out,
            &[],
        )
        .assert()
        .success();
        let map = yaml_lines(&std::fs::read_to_string(&out).unwrap());
        let desc = RobotDescription::from_file(&description).unwrap();
        let worst = origins_worst(&map, &desc, &dir.path().join("cal"));
        println!("{robot} ({offsets}): origins read here vs calibrated model {worst:e} m");
        assert!(worst < 1e-9, "{robot}: {worst:e} m");
    }
}

#[test]
fn the_paper_robots_couplings_are_refused_and_their_approximation_stated_as_read() {
    let dir = tempfile::tempdir().unwrap();
    let cal_path = calibrated(dir.path(), "asea-irb6l", "asea-irb6l", 36);
    let out = dir.path().join("origins.yaml");
    let export = |extra: &[&str]| export_cmd(&["xacro-yaml"], &cal_path, &out, extra);
    let a = export(&[]).assert().code(2);
    for named in [
        "decoupled from joint 2",
        "moves passively with joint 4",
        "--approximate",
    ] {
        assert!(stderr(&a).contains(named), "{named}: {}", stderr(&a));
    }
    let a = export(&["--approximate"]).assert().success();
    let stated = number_after(&stdout(&a), "up to ");
    let map = yaml_lines(&std::fs::read_to_string(&out).unwrap());
    let worst = origins_worst(&map, &RobotDescription::asea_irb6l(), &dir.path().join("cal"));
    println!(
        "paper robot, --approximate: stated {stated} mm, read here {:.6} mm",
        worst * 1e3
    );
    // Printed to 1 um.
    assert!(
        (worst * 1e3 - stated).abs() <= 0.0005 + 1e-12,
        "read {worst:e} m, stated {stated} mm"
    );
    assert!(stated > 1.0, "the couplings matter: {stated} mm");
}
