//! The thirteenth hostile run's part B, classes D1-D3 (an input reached indirectly written
//! over), P1/H1 (a URDF nested thousands deep), U1 (a TOML nested 50,000 deep) and U9 (an
//! output on a read-only folder), as a table (as [`super::hostile`]):
//! - every file a command reads through another (a description's `[urdf] file`, a scenario's
//!   `robot`, `[truth] path`, `[sweep] plans`, simulate's `--plan`) is now one of its inputs:
//!   an output naming it, or a `run --force` that would replace or remove it in its folder, is
//!   refused with exit 2 naming both, and the file is left byte for byte;
//! - a URDF nested deeper than 100 elements is refused before parsing, naming the file and line
//!   (it aborted on a stack overflow from 6,000 levels, and ran for minutes at 100,000);
//! - a TOML error without a position (the parser's recursion limit) names the deepest key's
//!   line and what to write;
//! - an output whose temporary cannot be created names the output, not the temporary.

use crate::common::hostile::{Case, case, stderr_of_case};
use std::path::{Path, PathBuf};

/// The code block of `docs/own-robot.md` that follows the line `after`.
fn guide_block(after: &str) -> String {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/own-robot.md")).unwrap();
    let rest = &text[text.find(after).unwrap_or_else(|| panic!("no {after:?} in the guide"))..];
    let start = rest.find("```").unwrap();
    let body = &rest[start..];
    let body = &body[body.find('\n').unwrap() + 1..];
    body[..body.find("```").unwrap()].to_owned()
}

/// A folder holding the guide's four-axis URDF arm as `arm4.urdf` / `arm4.toml`, a copy
/// `u.urdf` / `r.toml`, a plan `pl.toml`, a simulated campaign `d.csv` and its calibration `c/`.
fn arm4_folder() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let urdf = guide_block("Save as `arm4.urdf`");
    let toml = guide_block("Save as `arm4.toml`");
    std::fs::write(dir.path().join("arm4.urdf"), &urdf).unwrap();
    std::fs::write(dir.path().join("arm4.toml"), &toml).unwrap();
    std::fs::write(dir.path().join("u.urdf"), &urdf).unwrap();
    std::fs::write(dir.path().join("r.toml"), toml.replace("arm4.urdf", "u.urdf")).unwrap();
    let plan = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/robots/asea-irb6l-table1-plan.toml");
    std::fs::copy(plan, dir.path().join("pl.toml")).unwrap();
    for args in [
        "simulate --robot r.toml --seed 3 --out d.csv -q",
        "calibrate d.csv --robot r.toml --out c -q",
    ] {
        crate::common::axiscal()
            .current_dir(dir.path())
            .args(args.split_whitespace())
            .assert()
            .success();
    }
    dir
}

/// Every file under `dir` (not in `skip`) with its bytes.
fn snapshot(dir: &Path, skip: &[&str]) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if skip.iter().any(|s| p.ends_with(s)) {
                continue;
            }
            if e.file_type().unwrap().is_dir() {
                stack.push(p);
            } else if e.file_type().unwrap().is_file() {
                files.push((p.clone(), std::fs::read(&p).unwrap()));
            }
        }
    }
    files.sort();
    files
}

/// Runs each case in `dir`: exit 2, one line naming what it must, and no file changed.
fn refused_leaving_all(dir: &Path, cases: &[Case]) {
    for c in cases {
        let before = snapshot(dir, &[]);
        let e = stderr_of_case(dir, c);
        assert_eq!(e.lines().count(), 1, "{}: one line: {e}", c.what);
        assert!(e.contains("refusing to write over it"), "{}: {e}", c.what);
        assert_eq!(snapshot(dir, &[]), before, "{}: a file changed: {e}", c.what);
    }
}

#[test]
fn an_output_naming_a_file_read_through_another_is_refused() {
    let dir = arm4_folder();
    let d = dir.path();
    std::fs::create_dir(d.join("sub")).unwrap();
    std::fs::copy(d.join("pl.toml"), d.join("sub/pl.toml")).unwrap();
    std::os::unix::fs::symlink("sub", d.join("lnk")).unwrap();
    std::fs::write(d.join("p.csv"), "id,c1,c2,c3,c4\n1,0,0,0,0\n").unwrap();
    let pwd = d.canonicalize().unwrap();
    let plan_abs = format!("simulate --plan ./pl.toml --out {}/pl.toml --force", pwd.display());
    let plan_abs: &'static str = Box::leak(plan_abs.into_boxed_str());
    let urdf = ["u.urdf", "--robot r.toml: `urdf.file`"];
    refused_leaving_all(
        d,
        &[
            case(
                "D1 simulate --plan",
                "simulate --plan pl.toml --out pl.toml --force",
                2,
                &["pl.toml", "--plan"],
            ),
            case("D1 through ./ and $PWD", plan_abs, 2, &["--plan ./pl.toml"]),
            case(
                "D1 through a linked folder",
                "simulate --plan sub/pl.toml --out lnk/pl.toml --force",
                2,
                &["lnk/pl.toml", "--plan sub/pl.toml"],
            ),
            case("D2 simulate", "simulate --robot r.toml --out u.urdf --force", 2, &urdf),
            case(
                "D2 simulate, the guide's names",
                "simulate --robot arm4.toml --out arm4.urdf --force",
                2,
                &["--robot arm4.toml: `urdf.file` arm4.urdf"],
            ),
            case("D2 plan", "plan --robot r.toml --out u.urdf --force", 2, &urdf),
            case(
                "D2 plan --plan-out",
                "plan --robot r.toml --optimize --max-rounds 0 --out q.csv --plan-out u.urdf --force",
                2,
                &urdf,
            ),
            case(
                "D2 compensate",
                "compensate --calibration c/calibration.json --robot r.toml --poses p.csv --out u.urdf --force",
                2,
                &urdf,
            ),
            case(
                "D2 export xacro-yaml",
                "export xacro-yaml --calibration c/calibration.json --robot r.toml --approximate --out u.urdf --force",
                2,
                &urdf,
            ),
        ],
    );
}

#[test]
fn a_folder_output_holding_the_descriptions_urdf_is_refused() {
    let dir = arm4_folder();
    let d = dir.path();
    let urdf = std::fs::read_to_string(d.join("u.urdf")).unwrap();
    for (name, command) in [("calibrated.urdf", "calibrate"), ("where.svg", "diagnose")] {
        std::fs::create_dir_all(d.join("o")).unwrap();
        std::fs::write(d.join("o").join(name), &urdf).unwrap();
        let toml = std::fs::read_to_string(d.join("r.toml")).unwrap();
        std::fs::write(d.join("ro.toml"), toml.replace("u.urdf", &format!("o/{name}"))).unwrap();
        let args = format!("{command} d.csv --robot ro.toml --out o --force");
        let args: &'static str = Box::leak(args.into_boxed_str());
        let needle: &'static str = Box::leak(format!("--robot ro.toml: `urdf.file` o/{name}").into_boxed_str());
        refused_leaving_all(d, &[case("D2 a folder output", args, 2, &[needle])]);
        std::fs::remove_dir_all(d.join("o")).unwrap();
    }
}

#[test]
fn run_force_keeps_the_files_its_scenario_reads_in_its_folder() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let smoke = std::fs::read_to_string(root.join("scenarios/ci-smoke.toml")).unwrap();
    let robot = std::fs::read_to_string(root.join("scenarios/robots/asea-irb6l.toml")).unwrap();
    let truth = crate::common::axiscal()
        .args(["describe", "asea-irb6l", "--truth-template"])
        .assert()
        .success();
    let truth = crate::common::stdout(&truth);
    let plan = std::fs::read_to_string(root.join("scenarios/robots/asea-irb6l-table1-plan.toml")).unwrap();
    let truth_at = |p: &str| smoke.replace("kind = \"paper\"", &format!("kind = \"file\"\npath = \"{p}\""));
    let tables = [
        (
            "robot",
            "summary.md",
            robot.as_str(),
            format!("robot = \"o/summary.md\"\n{smoke}"),
        ),
        ("truth.path", "summary.md", truth.as_str(), truth_at("o/summary.md")),
        (
            "truth.path",
            "hist-cal_pos_rms_mm.svg",
            truth.as_str(),
            truth_at("o/hist-cal_pos_rms_mm.svg"),
        ),
        (
            "sweep.plans[0]",
            "trials.csv",
            plan.as_str(),
            format!("{smoke}\n[sweep]\nplans = [\"o/trials.csv\"]\n"),
        ),
    ];
    for (key, name, content, scenario) in tables {
        std::fs::create_dir_all(d.join("o")).unwrap();
        std::fs::write(d.join("o").join(name), content).unwrap();
        // A histogram is an earlier run's where its metric is a column of the folder's trials.
        if name.starts_with("hist-") {
            std::fs::write(d.join("o/trials.csv"), "case,trial,seed,cal_pos_rms_mm,error\n").unwrap();
        }
        std::fs::write(d.join("s.toml"), &scenario).unwrap();
        let needle: &'static str = Box::leak(format!("SCENARIO s.toml: `{key}` o/{name}").into_boxed_str());
        let c = case(
            "D3 run --force",
            "run s.toml --trials 2 --out o --force -q",
            2,
            &[needle],
        );
        refused_leaving_all(d, &[c]);
        std::fs::remove_dir_all(d.join("o")).unwrap();
    }
    // Without that trials file the histogram is no run's: the run goes ahead and leaves it.
    std::fs::create_dir_all(d.join("o")).unwrap();
    std::fs::write(d.join("o/hist-cal_pos_rms_mm.svg"), &truth).unwrap();
    std::fs::write(d.join("s.toml"), truth_at("o/hist-cal_pos_rms_mm.svg")).unwrap();
    crate::common::axiscal()
        .current_dir(d)
        .args(["run", "s.toml", "--trials", "2", "--out", "o", "--force", "-q"])
        .assert()
        .success();
    assert_eq!(
        std::fs::read_to_string(d.join("o/hist-cal_pos_rms_mm.svg")).unwrap(),
        truth
    );
}

#[test]
fn a_urdf_nested_thousands_deep_is_refused_naming_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let toml = guide_block("Save as `arm4.toml`").replace("arm4.urdf", "u.urdf");
    std::fs::write(d.join("r.toml"), toml).unwrap();
    for depth in [101, 6000, 100_000] {
        let text = format!(
            "<robot name=\"x\">\n{}{}</robot>\n",
            "<a>".repeat(depth),
            "</a>".repeat(depth)
        );
        std::fs::write(d.join("u.urdf"), &text).unwrap();
        let before = snapshot(d, &[]);
        for args in ["describe r.toml --poses 10", "simulate --robot r.toml --out s.csv"] {
            let c = case(
                "P1/H1",
                args,
                2,
                &["u.urdf: line 2: elements nested 101 deep", "at most 100"],
            );
            let e = stderr_of_case(d, &c);
            assert_eq!(e.lines().count(), 1, "{e}");
        }
        assert_eq!(snapshot(d, &[]), before);
    }
    // Depth 100 (the robot element and 99 below it) is read: its error is the URDF's content.
    let text = format!("<robot name=\"x\">{}{}</robot>", "<a>".repeat(99), "</a>".repeat(99));
    std::fs::write(d.join("u.urdf"), &text).unwrap();
    let e = stderr_of_case(d, &case("depth 100", "describe r.toml", 2, &["u.urdf"]));
    assert!(!e.contains("nested"), "{e}");
}

#[test]
fn a_toml_nested_50000_deep_names_its_line_and_the_fix() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let dotted = format!("# deep\n\n{} = 1\n", vec!["a"; 50_000].join("."));
    let table = format!("name = \"x\"\n[{}]\nb = 1\n", vec!["a"; 50_000].join("."));
    for (what, text, line) in [("dotted", &dotted, "line 3"), ("table header", &table, "line 2")] {
        std::fs::write(d.join("r.toml"), text).unwrap();
        for args in ["describe r.toml", "run r.toml", "simulate --plan r.toml --out s.csv"] {
            let c = case(
                what,
                args,
                2,
                &["r.toml", line, "nested 50000 levels deep", "write the documented keys"],
            );
            let e = stderr_of_case(d, &c);
            assert_eq!(e.lines().count(), 1, "{e}");
            assert!(e.len() < 1000, "{e}");
        }
        assert_eq!(&std::fs::read_to_string(d.join("r.toml")).unwrap(), text);
    }
}

#[test]
fn an_output_in_a_folder_that_cannot_be_written_names_the_output() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // /proc takes no new file, whoever runs the test; a folder without write permission holds
    // only for a user who is not root.
    let mut outputs = vec![("/proc/s.csv".to_owned(), "/proc")];
    std::fs::create_dir(d.join("ro")).unwrap();
    std::fs::set_permissions(d.join("ro"), std::fs::Permissions::from_mode(0o555)).unwrap();
    if std::fs::write(d.join("ro/probe"), "").is_err() {
        outputs.push(("ro/s.csv".to_owned(), "ro"));
    }
    for (out, folder) in &outputs {
        let args: &'static str = Box::leak(format!("simulate --out {out}").into_boxed_str());
        let named: &'static str =
            Box::leak(format!("cannot write {out}: creating a file in {folder} fails").into_boxed_str());
        let e = stderr_of_case(d, &case("U9", args, 2, &[named]));
        assert_eq!(e.lines().count(), 1, "{e}");
        assert!(
            e.find(out.as_str()) < e.find(".axiscal-"),
            "the output before the temporary: {e}"
        );
        assert!(!Path::new(out).exists(), "{e}");
    }
    std::fs::set_permissions(d.join("ro"), std::fs::Permissions::from_mode(0o755)).unwrap();
}
