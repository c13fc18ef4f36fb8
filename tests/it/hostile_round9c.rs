//! Helper h9c (hostile run 8: S5, S6, U3, Part A): the importers and wrong files. Another
//! command's output given as the data is named as that file; a Boby-Klimchik file written with
//! commas names its separator; a revolute-only SScanSS-2 file read in metres is refused; a MAT
//! target variable in millimetres among metres is named; joints in radians read as degrees, with
//! one column also scaled, still get "pass --angles rad"; a `--still-tolerance` below a joint's
//! jitter names the tolerance, not the units.

use crate::common::hostile::{case, clear_outputs, run_case};
use crate::hostile_round5c::{mat_file, write_mats};
use std::path::Path;

/// A shipped robot description's path.
fn shipped_robot(name: &str) -> String {
    format!("{}/scenarios/robots/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

/// calibrate's, compensate's and a study's files, and a pose list, given as the data: each is
/// named as the file it is (they used to get "the file has 0 joint command columns").
#[test]
fn another_commands_output_is_named_as_such() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    crate::common::hostile::calibrated_campaign(d, 9);
    std::fs::write(
        d.join("comp.csv"),
        "id,status,cmd_1_deg,cmd_2_deg,cmd_3_deg,cmd_4_deg,cmd_5_deg,cmd_6_deg,converged,iterations,\
         position_error_mm,orientation_error_rad,send_x_mm,send_y_mm,send_z_mm,send_roll_deg,send_pitch_deg,\
         send_yaw_deg\np1,ok,1,2,3,4,5,6,true,4,0,0,1,2,3,4,5,6\n",
    )
    .unwrap();
    std::fs::write(
        d.join("poses.csv"),
        "id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\np1,100,200,300,0,0,0\n",
    )
    .unwrap();
    let cases = [
        case(
            "residuals",
            "calibrate cal/residuals.csv --out out",
            2,
            &["residuals table"],
        ),
        case(
            "joint map",
            "calibrate cal/joint_map.csv --out out",
            2,
            &["joint map (joint_map.csv)"],
        ),
        case(
            "zero offsets",
            "calibrate cal/zero_offsets.csv --out out",
            2,
            &["zero offsets"],
        ),
        case(
            "pose list",
            "calibrate poses.csv --out out",
            2,
            &["pose list for `compensate --poses`"],
        ),
        case(
            "compensate's table",
            "validate comp.csv --calibration cal/calibration.json --out out",
            2,
            &["`compensate`'s table of corrected commands", "not a measurement CSV"],
        ),
    ];
    for c in &cases {
        let e = run_case(d, c);
        assert!(!e.contains("joint command columns"), "{}: {e}", c.what);
        clear_outputs(d);
    }
}

/// `N1N2N3Jval.csv` written back with commas: the separator is named.
#[test]
fn a_comma_separated_boby_klimchik_file_names_its_separator() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("bk");
    std::fs::create_dir(&data).unwrap();
    let line = (1..=21).map(|i| format!("{i}.5")).collect::<Vec<_>>().join(",");
    std::fs::write(data.join("N1N2N3Jval.csv"), format!("{line}\n").repeat(36)).unwrap();
    let c = case(
        "bk commas",
        "import boby-klimchik bk --out out.csv",
        2,
        &["N1N2N3Jval.csv:1: 1 fields, expected 21", "separated by `,`"],
    );
    run_case(dir.path(), &c);
}

/// A two-link SScanSS-2 file (1 mm links, as the shipped example robot), written here: joint
/// 1 swept with joint 2 at 0 (radius 2 mm), then joint 2 with joint 1 at 0 (radius 1 mm).
fn two_link_file() -> String {
    let (cx, z) = (10.0, 1.5);
    let mut text = String::new();
    for k in 1..=2 {
        for step in 0..11 {
            let deg = -150.0 + 30.0 * step as f64;
            let t = f64::to_radians(deg);
            let (x, y) = match k {
                1 => (cx + 2.0 * t.cos(), 2.0 * t.sin()),
                _ => (cx + 1.0 + t.cos(), t.sin()),
            };
            text.push_str(&format!("{k},{x:.6},{y:.6},{z:.6},{deg},revolute,0\n"));
        }
    }
    text
}

/// S5: a revolute-only SScanSS-2 file read with `--units m` (its 2 mm arcs become 2 m ones)
/// is refused with "pass --units mm"; read in millimetres it imports without a word.
#[test]
fn a_revolute_sscanss2_file_in_the_wrong_length_unit_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("two_link.csv"), two_link_file()).unwrap();
    let import = format!(
        "import sscanss2 two_link.csv --robot {} --out out.csv",
        shipped_robot("real/sscanss2-two-link")
    );
    let clean = run_case(dir.path(), &case("mm", &import, 0, &[]));
    assert!(clean.is_empty(), "{clean}");
    clear_outputs(dir.path());
    let c = case(
        "m",
        &format!("{import} --units m"),
        2,
        &["revolute sweeps' arcs are 1000 times", "pass --units mm"],
    );
    run_case(dir.path(), &c);
}

/// Run 8 K-S8: one MAT target variable in millimetres, the others in metres: the variable is
/// named (it used to be "coordinates scaled by 339 ... another robot?"); the file with every
/// target in metres imports.
#[test]
fn a_mat_target_in_another_unit_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    crate::common::simulate_analytic(d, 40, 23, "campaign.csv");
    write_mats(d);
    edited_mat(&d.join("good.mat"), d, "mc_mm.mat", mc_in_mm);
    let mat = "import mat --robot asea-irb6l --joints q --targets mA,mB,mC --angles rad --units m --out out.csv";
    let clean = run_case(d, &case("good", &format!("{mat} good.mat"), 0, &[]));
    assert!(clean.is_empty(), "{clean}");
    clear_outputs(d);
    let c = case(
        "mC in mm",
        &format!("{mat} mc_mm.mat"),
        2,
        &[
            "variable `mC`",
            "other targets' (`mA`, `mB`)",
            "millimetres among metres",
        ],
    );
    let e = run_case(d, &c);
    assert!(!e.contains("another robot"), "{e}");
}

/// The MAT file `source` with `edit` applied to its variables `q`, `mA`, `mB`, `mC`, written
/// as `name` in `dir` (a hand-edited copy).
fn edited_mat(source: &Path, dir: &Path, name: &str, edit: impl Fn(&str, &mut [Vec<f64>])) {
    let file = axiscal::measurement::import::mat_v5::read(&std::fs::read(source).unwrap()).unwrap();
    let vars: Vec<(&str, Vec<Vec<f64>>)> = ["q", "mA", "mB", "mC"]
        .into_iter()
        .map(|n| {
            let a = file.array(n).unwrap();
            let mut m: Vec<Vec<f64>> = (0..a.rows)
                .map(|r| (0..a.cols).map(|c| a.get(r, c)).collect())
                .collect();
            edit(n, &mut m);
            (n, m)
        })
        .collect();
    std::fs::write(dir.join(name), mat_file(&vars)).unwrap();
}

/// Target `mC` in millimetres (the file's metres times 1000).
fn mc_in_mm(name: &str, m: &mut [Vec<f64>]) {
    if name == "mC" {
        m.iter_mut().flatten().for_each(|v| *v *= 1e3);
    }
}

/// Run 8 N2 on the real FANUC file: joints in radians read as degrees, with `q`'s joint 2 also
/// scaled by 1.05 (so some rows leave the limits in either unit): "pass --angles rad" and the
/// rows outside the limits, not "coordinates scaled by 40.9 ... another robot?"; the target
/// `mC` in millimetres is named.
#[test]
#[ignore = "needs ../shared/data/real/fanuc-r2000ic-tracker (run by `make test-real`)"]
fn real_fanuc_mat_with_a_scaled_column_read_in_degrees_says_pass_angles_rad() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fanuc = crate::common::real_data("fanuc-r2000ic-tracker/calibration_dataset.mat");
    edited_mat(&fanuc, d, "q2.mat", |n, m| {
        if n == "q" {
            m.iter_mut().for_each(|r| r[1] *= 1.05);
        }
    });
    edited_mat(&fanuc, d, "mc.mat", mc_in_mm);
    let mat = format!(
        "import mat --robot {} --joints q --targets mA,mB,mC --units m --out out.csv",
        shipped_robot("real/fanuc-r2000ic")
    );
    let e = run_case(
        d,
        &case(
            "q2 x1.05 in deg",
            &format!("{mat} q2.mat --angles deg"),
            2,
            &[
                "read with --angles rad --units m its units fit",
                "pass --angles rad",
                "`cmd_2`",
            ],
        ),
    );
    assert!(!e.contains("another robot"), "{e}");
    run_case(
        d,
        &case("mC in mm", &format!("{mat} mc.mat --angles rad"), 2, &["variable `mC`"]),
    );
}

/// Run 8 U3 on the real rct file: a `--still-tolerance` below joint 1's jitter (1e-9 deg)
/// makes joint 2's turns read as joint-1 sweeps; the warning names the still tolerance and a
/// value that works, not "the commands look scaled by 0 against degrees". With the value it
/// gives, the 13 turns of joint 2 come back.
#[test]
#[ignore = "needs ../shared/data/real/rct-two-axis-positioner (run by `make test-real`)"]
fn real_rct_with_a_tiny_still_tolerance_names_the_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    let yaml = crate::common::real_data("rct-two-axis-positioner/positioner_kinematic_measurements.yaml");
    let import = format!(
        "import rct {} --robot {} --out out.csv",
        yaml.display(),
        shipped_robot("positioner-2axis")
    );
    let e = run_case(
        dir.path(),
        &case(
            "1e-9",
            &format!("{import} --still-tolerance 0.000000001"),
            0,
            &["sweeps of joint 1", "are joint 2's", "pass --still-tolerance"],
        ),
    );
    assert!(!e.contains("scaled by 0"), "{e}");
    let suggested = e
        .split("pass --still-tolerance ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap();
    clear_outputs(dir.path());
    let again = run_case(
        dir.path(),
        &case("suggested", &format!("{import} --still-tolerance {suggested}"), 0, &[]),
    );
    assert!(!again.contains("warning"), "{again}");
    let text = std::fs::read_to_string(dir.path().join("out.csv")).unwrap();
    let turns: std::collections::BTreeSet<&str> = text
        .lines()
        .filter(|l| l.starts_with("axis2"))
        .filter_map(|l| l.split(',').next())
        .collect();
    assert_eq!(turns.len(), 13, "{turns:?}");
}

/// Run 8 U3 on SScanSS-2's real table file, x + 2 mm on every joint-1 row: the sweep of joint
/// 1 is named as shifted (it used to be refused as a wrong home column, the home being right).
#[test]
#[ignore = "needs ../shared/data/real/sscanss2-cpa (run by `make test-real`)"]
fn real_sscanss2_table_with_joint_1_shifted_names_the_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(crate::common::real_data("sscanss2-cpa/table.txt")).unwrap();
    let shifted: String = text
        .lines()
        .map(|l| {
            let mut f: Vec<String> = l.split('\t').map(str::to_owned).collect();
            if f.len() == 7 && f[0].trim() == "1" {
                f[1] = format!("{}", f[1].trim().parse::<f64>().unwrap() + 2.0);
            }
            f.join("\t") + "\n"
        })
        .collect();
    std::fs::write(dir.path().join("shifted.txt"), shifted).unwrap();
    let c = case(
        "joint 1 + 2 mm",
        &format!(
            "import sscanss2 shifted.txt --robot {} --out out.csv",
            shipped_robot("real/sscanss2-table")
        ),
        2,
        &["joint 1's sweep (lines 1-11)", "rows' coordinates are shifted"],
    );
    let e = run_case(dir.path(), &c);
    assert!(!e.contains("column home"), "{e}");
}
