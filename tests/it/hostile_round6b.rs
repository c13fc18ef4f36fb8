//! The sixth hostile run's importers: SScanSS-2's home column contradicted by the data, a
//! SScanSS-2 file read in the wrong length unit (the sliding sweeps' travel), one sliding joint's
//! values in metres, `;` separators, a mirrored file whose other unit the import must not advise,
//! and `import rct` in the wrong units (the unit check the other importers run).
//!
//! The SScanSS-2 files are written here by hand in the layout of SScanSS-2's example table (a z
//! stage, a rotation stage 53.6 mm from the measured point, a y and an x stage), not by
//! `axiscal simulate`; the rct files are a simulated positioner's sweeps rewritten as
//! robot_cal_tools' YAML.

use crate::common::axiscal;
use crate::common::hostile::{Case, case, clear_outputs, run_case};
use std::path::Path;

/// The shipped description of SScanSS-2's example table.
fn table_robot() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios/robots/real/sscanss2-table.toml")
        .display()
        .to_string()
}

/// A deterministic scatter of +-0.01 mm for the `i`-th coordinate.
fn scatter(i: usize) -> f64 {
    ((i * 7919 + 13) % 1000) as f64 / 1000.0 * 0.02 - 0.01
}

/// The table's rows: `(joint, [x, y, z] mm, value, type)`, every joint from its home 0.
fn table_rows() -> Vec<(usize, [f64; 3], f64, &'static str)> {
    let mut rows = Vec::new();
    let (centre, radius, at_zero) = ([-18.85, -50.16], 53.6, 69.4f64);
    for k in 0..=10 {
        let v = 50.0 * k as f64;
        rows.push((1, [0.0, 0.0, v], v, "prismatic"));
    }
    for k in 0..=10 {
        let v = -180.0 + 36.0 * k as f64;
        let a = (at_zero - v).to_radians();
        let p = [centre[0] + radius * a.cos(), centre[1] + radius * a.sin(), 0.0];
        rows.push((2, p, v, "revolute"));
    }
    for (joint, axis) in [(3, 1), (4, 0)] {
        for k in 0..=10 {
            let v = -200.0 + 40.0 * k as f64;
            let mut p = [0.0; 3];
            p[axis] = v;
            rows.push((joint, p, v, "prismatic"));
        }
    }
    for (i, r) in rows.iter_mut().enumerate() {
        for c in 0..3 {
            r.1[c] += scatter(3 * i + c);
        }
    }
    rows
}

/// The table as a SScanSS-2 file: points times `length`, joint `slid`'s values times
/// `slid_factor`, joint 2's home `home2`, x and y swapped when `swap_xy`, cells joined by `sep`.
struct Table {
    length: f64,
    slid: usize,
    slid_factor: f64,
    home2: f64,
    swap_xy: bool,
    sep: &'static str,
}

const CLEAN: Table = Table {
    length: 1.0,
    slid: 0,
    slid_factor: 1.0,
    home2: 0.0,
    swap_xy: false,
    sep: "\t",
};

fn write_table(dir: &Path, name: &str, t: &Table) {
    let text: String = table_rows()
        .into_iter()
        .map(|(joint, p, v, kind)| {
            let p = p.map(|c| c * t.length);
            let (x, y) = if t.swap_xy { (p[1], p[0]) } else { (p[0], p[1]) };
            let value = if joint == t.slid { v * t.slid_factor } else { v };
            let home = if joint == 2 { t.home2 } else { 0.0 };
            let cells = [
                joint.to_string(),
                x.to_string(),
                y.to_string(),
                p[2].to_string(),
                value.to_string(),
                kind.to_string(),
                home.to_string(),
            ];
            cells.join(t.sep) + "\n"
        })
        .collect();
    std::fs::write(dir.join(name), text).unwrap();
}

fn write_tables(dir: &Path) {
    write_table(dir, "clean.txt", &CLEAN);
    write_table(dir, "home10.txt", &Table { home2: 10.0, ..CLEAN });
    write_table(dir, "home03.txt", &Table { home2: 0.3, ..CLEAN });
    write_table(dir, "in_m.txt", &Table { length: 1e-3, ..CLEAN });
    write_table(
        dir,
        "j3_m.txt",
        &Table {
            slid: 3,
            slid_factor: 1e-3,
            ..CLEAN
        },
    );
    write_table(dir, "semicolon.txt", &Table { sep: ";", ..CLEAN });
    write_table(dir, "swap_xy.txt", &Table { swap_xy: true, ..CLEAN });
}

fn sscanss_cases() -> Vec<Case> {
    let robot = table_robot();
    let import = |file: &str, extra: &str| format!("import sscanss2 {file} --robot {robot} {extra} --out out.csv");
    let cases = [
        (
            "a clean table imports without a word",
            import("clean.txt", ""),
            0,
            vec![],
        ),
        (
            "joint 2's home written 10 deg where the sweeps stood at 0",
            import("home10.txt", ""),
            2,
            vec!["line 12, column home", "joint 2's home is 10 deg"],
        ),
        (
            "joint 2's home written 0.3 deg where the sweeps stood at 0",
            import("home03.txt", ""),
            2,
            vec!["line 12, column home", "joint 2's home is 0.3 deg"],
        ),
        (
            "a file in mm imported with --units m",
            import("clean.txt", "--units m"),
            2,
            vec![
                "sliding joints' sweeps move their points 99",
                "look like micrometres",
                "pass --units mm",
            ],
        ),
        (
            "a file in m imported with the default mm",
            import("in_m.txt", ""),
            2,
            vec![
                "sweeps move their points 0.001 times",
                "look like metres",
                "pass --units m",
            ],
        ),
        (
            "joint 3's values in m among joints in mm",
            import("j3_m.txt", ""),
            0,
            vec!["`cmd_3`", "joint 3's commands look like metres rather than millimetres"],
        ),
        (
            "cells separated by semicolons",
            import("semicolon.txt", ""),
            2,
            vec![
                "line 1: the cells are separated by `;`",
                "replace each `;` with a comma",
            ],
        ),
        (
            "a mirrored file imported with --units m",
            import("swap_xy.txt", "--units m"),
            2,
            vec!["read with --angles deg --units mm the data show", "mirror image"],
        ),
    ];
    cases
        .into_iter()
        .map(|(what, args, code, names)| case(what, &args, code, &names))
        .collect()
}

#[test]
fn sscanss2_homes_units_and_separators_are_named() {
    let dir = tempfile::tempdir().unwrap();
    write_tables(dir.path());
    for c in sscanss_cases() {
        let e = run_case(dir.path(), &c);
        if c.code == 0 && c.names.is_empty() {
            assert!(e.is_empty(), "{}: no warning: {e}", c.what);
        }
        assert!(
            !(c.code == 2 && c.what.contains("mirrored") && e.contains("pass --units")),
            "{}: {e}",
            c.what
        );
        clear_outputs(dir.path());
    }
}

/// The simulated positioner's sweeps (target 0) in `dir` as robot_cal_tools
/// YAML: positions times `length` (m: 1e-3 of the mm), joint values times `angle` (rad: the
/// degrees' `to_radians`).
fn write_rct(dir: &Path, name: &str, length: f64, angle: f64) {
    let csv = std::fs::read_to_string(dir.join("pos.csv")).unwrap();
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|c| *c == n).unwrap();
    let mut text = String::new();
    for (i, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        if cells[col("target")] != "0" || !cells[0].starts_with("axis") {
            continue;
        }
        let value = |n: &str| cells[col(n)].parse::<f64>().unwrap();
        text.push_str(&format!(
            "'{}':\n  camera_joints: []\n  pose:\n    qw: 1.0\n    qx: 0.0\n    qy: 0.0\n    qz: 0.0\n    x: {}\n    y: {}\n    z: {}\n  target_joints:\n  - {}\n  - {}\n",
            1_600_000_000 + i,
            value("x_mm") * length,
            value("y_mm") * length,
            value("z_mm") * length,
            value("cmd_1") * angle,
            value("cmd_2") * angle
        ));
    }
    std::fs::write(dir.join(name), text).unwrap();
}

#[test]
fn import_rct_checks_its_units_as_the_other_importers_do() {
    let dir = tempfile::tempdir().unwrap();
    axiscal()
        .current_dir(dir.path())
        .args([
            "simulate",
            "--robot",
            "positioner-2axis",
            "--sim",
            "analytic",
            "--seed",
            "11",
            "--out",
            "pos.csv",
        ])
        .assert()
        .success();
    let rad = 1f64.to_radians();
    write_rct(dir.path(), "good.yaml", 1e-3, rad);
    write_rct(dir.path(), "xyz_mm.yaml", 1.0, rad);
    write_rct(dir.path(), "joints_deg.yaml", 1e-3, 1.0);
    let import = |file: &str| format!("import rct {file} --robot positioner-2axis --out out.csv");
    let cases = [
        case("the positioner in m and rad", &import("good.yaml"), 0, &[]),
        case(
            "positions written in mm",
            &import("xyz_mm.yaml"),
            2,
            &["xyz_mm.yaml: read with --angles rad --units m", "pass --units mm"],
        ),
        case(
            "joint values written in degrees",
            &import("joints_deg.yaml"),
            2,
            &["joints_deg.yaml: read with --angles rad --units m", "pass --angles deg"],
        ),
    ];
    for c in cases {
        let e = run_case(dir.path(), &c);
        if c.code == 0 {
            assert!(!e.contains("warning"), "{}: no warning: {e}", c.what);
        }
        clear_outputs(dir.path());
    }
    // The advice followed, the file imports.
    axiscal()
        .current_dir(dir.path())
        .args([
            "import",
            "rct",
            "xyz_mm.yaml",
            "--robot",
            "positioner-2axis",
            "--units",
            "mm",
            "--out",
            "mm.csv",
        ])
        .assert()
        .success();
}
