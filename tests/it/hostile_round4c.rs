//! The fourth hostile run's descriptions and options that passed silently wrong: `dh` twists
//! in radians, every link length 0, lengths in centimetres or inches (a warning on every
//! command that reads the description, and data refused as a unit slip then name the
//! description too), a payload heavier than the robot, `import wide` with the wrong `--angles`
//! or `--units`, and `--free-poses` on sweeps whose targets are not one tool target each. No
//! shipped description draws a warning.

use crate::common::hostile::{Case, calibrated_campaign, case, clear_outputs, run_case};
use crate::common::{axiscal, stderr};
use axiscal::measurement::description_check::description_warnings;
use axiscal::robot::RobotDescription;
use std::path::Path;

fn shipped(relative: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)).unwrap()
}

/// `text` with each `dh = { ... }` row's `key = value` cells for `keys` mapped by `f`.
fn dh_mapped(text: &str, keys: &[&str], f: impl Fn(f64) -> f64) -> String {
    let mut out = String::new();
    for line in text.lines() {
        let mut line = line.to_owned();
        if line.trim_start().starts_with("dh = {") {
            for key in keys {
                let start = line.find(&format!("{key} = ")).expect("the key") + key.len() + 3;
                let end = start + line[start..].find([',', ' ', '}']).expect("the value's end");
                let value: f64 = line[start..end].parse().unwrap();
                line.replace_range(start..end, &format!("{:.6}", f(value)));
            }
        }
        out.push_str(&line);
        out.push('\n');
    }
    out
}

/// The description variants of the run: `(file, text)`, from the shipped `robot`.
fn variants(robot: &str) -> Vec<(String, String)> {
    let text = shipped(&format!("scenarios/robots/{robot}.toml"));
    let lengths = ["d_mm", "a_mm"];
    vec![
        (
            format!("{robot}-rad.toml"),
            dh_mapped(&text, &["alpha_deg"], f64::to_radians),
        ),
        (format!("{robot}-zero.toml"), dh_mapped(&text, &lengths, |_| 0.0)),
        (format!("{robot}-cm.toml"), dh_mapped(&text, &lengths, |v| v / 10.0)),
        (format!("{robot}-inch.toml"), dh_mapped(&text, &lengths, |v| v / 25.4)),
    ]
}

/// Every shipped description (`scenarios/robots/`, `real/`) reads with no warning, from its
/// file or inlined in a scenario.
#[test]
fn no_shipped_description_draws_a_warning() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/robots");
    let mut read = 0;
    for dir in [root.clone(), root.join("real")] {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "toml") {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let Ok((desc, source)) = RobotDescription::with_source(&text, &path) else {
                continue;
            };
            let warnings = description_warnings(&desc, source.as_ref().map(|(chain, _)| chain));
            assert_eq!(warnings, vec![], "{}", path.display());
            // As a scenario inlines it: the converted rows only.
            assert_eq!(description_warnings(&desc, None), vec![], "{} inlined", path.display());
            read += 1;
        }
    }
    assert!(read >= 11, "{read} descriptions read");
}

/// S6: `describe` of a description in radians, with every length 0, or in cm or inches warns,
/// naming the file and what the values look like.
#[test]
fn describe_warns_of_twists_in_radians_zero_lengths_and_lengths_in_cm_or_inches() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut cases: Vec<Case> = Vec::new();
    for robot in ["scara-rrpr", "ur5e-dh", "arm7-dh", "positioner-2axis", "table-prpp"] {
        for (name, text) in variants(robot) {
            std::fs::write(d.join(&name), text).unwrap();
            let expected: &[&str] = match name.rsplit('-').next().unwrap() {
                "rad.toml" => &["`joints[].dh.alpha_deg`", "looks like radians", " deg?)"],
                // A table of one revolute joint and three slides may have every offset 0; the
                // SCARA's three revolute axes are one line then, which only turntables are.
                "zero.toml" if robot == "table-prpp" => continue,
                "zero.toml" => &["every link length is 0"],
                // The positioner's lengths in cm or inches are refused already (its targets
                // beyond 100 times its rows).
                _ if robot == "positioner-2axis" => continue,
                _ => &["lengths in centimetres", "or inches"],
            };
            let mut names = vec![name.as_str()];
            names.extend(expected);
            cases.push(case("a wrong description", &format!("describe {name}"), 0, &names));
        }
    }
    assert_eq!(cases.len(), 17);
    for c in &cases {
        let e = run_case(d, c);
        assert!(e.contains("--skip-unit-check silences this"), "{}: {e}", c.what);
        let skipped = axiscal()
            .current_dir(d)
            .args(&c.args)
            .arg("--skip-unit-check")
            .assert()
            .success();
        assert_eq!(stderr(&skipped), "", "{}", c.what);
    }
}

/// U2: data refused as a unit slip against a wrong description, with no description recorded
/// in the file, name the description too.
#[test]
fn a_slip_against_a_description_in_cm_names_the_description() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    axiscal()
        .current_dir(d)
        .args(["simulate", "--robot", "scara-rrpr", "--sim", "analytic", "--seed", "3"])
        .args(["--validation-poses", "20", "--out", "scara.csv"])
        .assert()
        .success();
    let text = std::fs::read_to_string(d.join("scara.csv")).unwrap();
    let unrecorded: String = text
        .lines()
        .filter(|l| !l.starts_with("# axiscal.description"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(d.join("bare.csv"), unrecorded).unwrap();
    for (name, text) in variants("scara-rrpr") {
        std::fs::write(d.join(name), text).unwrap();
    }
    let cases = [
        case(
            "SCARA in cm",
            "calibrate bare.csv --robot scara-rrpr-cm.toml --out out",
            2,
            &[
                "bare.csv",
                "or the description scara-rrpr-cm.toml is not this robot's",
                "centimetres",
            ],
        ),
        case(
            "SCARA with no lengths",
            "calibrate bare.csv --robot scara-rrpr-zero.toml --out out",
            2,
            &[
                "is not this robot's",
                "every link length is 0: the 3 revolute axes are one line",
            ],
        ),
    ];
    for c in &cases {
        // The description's own warning comes first, the refusal last.
        let e = crate::common::axiscal()
            .current_dir(d)
            .args(&c.args)
            .assert()
            .code(c.code);
        let e = stderr(&e);
        for name in &c.names {
            assert!(e.contains(name.as_str()), "{}: no {name:?} in {e}", c.what);
        }
        let last = e.lines().last().unwrap();
        assert!(
            last.starts_with("error: ") && last.contains("is not this robot's"),
            "{}: {e}",
            c.what
        );
        clear_outputs(d);
    }
    // The same data with their record, of the shipped SCARA: the record says the description differs.
    let c = case(
        "recorded",
        "calibrate scara.csv --robot scara-rrpr-cm.toml --allow-other-robot --out out",
        2,
        &["the data record another, "],
    );
    let e = stderr(&axiscal().current_dir(d).args(&c.args).assert().code(2));
    assert!(e.contains(c.names[0].as_str()), "{e}");
}

/// The rows of `text` (a measurement CSV) with `payload_kg` set to `kg`.
fn with_payload(text: &str, kg: &str) -> String {
    let mut lines = text.lines();
    let mut out = String::new();
    let mut column = None;
    for line in lines.by_ref() {
        out.push_str(line);
        out.push('\n');
        if !line.starts_with('#') {
            column = line.split(',').position(|c| c == "payload_kg");
            break;
        }
    }
    let column = column.expect("a payload_kg column");
    for line in lines {
        let mut cells: Vec<&str> = line.split(',').collect();
        cells[column] = kg;
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    out
}

/// S12, S13, U7 on the IRB/L6's campaign: a payload of 2.5 t on a 6 kg robot warns; `import
/// wide` with the wrong `--angles` or `--units` is refused naming the value that fits;
/// `--free-poses` on sweeps whose targets sit on inner links is refused naming the cause.
#[test]
fn payload_wide_units_and_free_poses_on_sweeps_are_said() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    calibrated_campaign(d, 7);
    let campaign = std::fs::read_to_string(d.join("campaign.csv")).unwrap();
    std::fs::write(d.join("heavy.csv"), with_payload(&campaign, "2500")).unwrap();
    std::fs::write(d.join("wide.csv"), wide_table(&campaign)).unwrap();
    // Marker 1's y and z headers swapped: the warning names the table's lines.
    let swapped = wide_table(&campaign).replacen("m1_y,m1_z", "m1_z,m1_y", 1);
    std::fs::write(d.join("wide-yz.csv"), swapped).unwrap();
    let cases = [
        case(
            "a payload of 2.5 t",
            "calibrate heavy.csv --out out",
            0,
            &["heavy.csv:3: payload_kg = 2500 kg is more than the robot's own moving mass (88.5 kg"],
        ),
        case(
            "validate with it",
            "validate heavy.csv --calibration cal/calibration.json --out out",
            0,
            &["payload_kg = 2500 kg"],
        ),
        case(
            "degrees read as radians",
            "import wide wide.csv --angles rad --units mm --out out.csv",
            2,
            &[
                "wide.csv",
                "read with --angles deg --units mm it does: pass --angles deg",
            ],
        ),
        case(
            "millimetres read as metres",
            "import wide wide.csv --angles deg --units m --out out.csv",
            2,
            &["wide.csv", "pass --units mm"],
        ),
        case(
            "both",
            "import wide wide.csv --angles rad --units m --out out.csv",
            2,
            &["pass --angles deg --units mm"],
        ),
        case(
            "a marker's y and z headers swapped",
            "import wide wide-yz.csv --angles deg --units mm --out out.csv",
            0,
            &["the farthest off: line "],
        ),
        case(
            "sweeps as free poses",
            "calibrate campaign.csv --free-poses --out out",
            2,
            &[
                "--free-poses fits every row as a free pose",
                "not on the last link",
                "drop --free-poses",
            ],
        ),
    ];
    for c in &cases {
        run_case(d, c);
        clear_outputs(d);
    }
    let right = axiscal()
        .current_dir(d)
        .args([
            "import", "wide", "wide.csv", "--angles", "deg", "--units", "mm", "--out", "out.csv",
        ])
        .assert()
        .success();
    assert_eq!(stderr(&right), "");
}

/// One pose of a wide table: its `(experiment, step)`, joint values and markers.
type WidePose = ((String, String), Vec<String>, [Option<String>; 3]);

/// The campaign's rows as a wide table (`q1..q6`, markers `m1`-`m3` for targets 0-2), one row
/// per `(experiment, step)` in file order.
fn wide_table(campaign: &str) -> String {
    let mut lines = campaign.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let mut poses: Vec<WidePose> = Vec::new();
    for line in lines {
        let r: Vec<&str> = line.split(',').collect();
        let key = (r[col("experiment")].to_owned(), r[col("step")].to_owned());
        if poses.last().is_none_or(|p| p.0 != key) {
            let q = (1..=6).map(|k| r[col(&format!("cmd_{k}"))].to_owned()).collect();
            poses.push((key, q, [None, None, None]));
        }
        let target: usize = r[col("target")].parse().unwrap();
        let xyz = [r[col("x_mm")], r[col("y_mm")], r[col("z_mm")]].join(",");
        poses.last_mut().unwrap().2[target] = Some(xyz);
    }
    let mut text = String::from("q1,q2,q3,q4,q5,q6,m1_x,m1_y,m1_z,m2_x,m2_y,m2_z,m3_x,m3_y,m3_z\n");
    for (_, q, markers) in poses {
        let cells: Vec<String> = markers.into_iter().map(|m| m.unwrap_or_else(|| ",,".into())).collect();
        text.push_str(&format!("{},{}\n", q.join(","), cells.join(",")));
    }
    text
}
