//! `axiscal run` and `axiscal merge` end to end: exit codes 0/1/2, results files, shards
//! merged equal a single run bit for bit, no silent overwrite.

use crate::common::{axiscal, stderr};
use std::path::Path;

/// `ci-smoke.toml` with `from` replaced by `to` and `extra` appended, written into `dir`.
fn smoke_variant(dir: &Path, name: &str, (from, to): (&str, &str), extra: &str) -> std::path::PathBuf {
    let text = std::fs::read_to_string("scenarios/ci-smoke.toml").unwrap();
    assert!(text.contains(from));
    let path = dir.join(name);
    std::fs::write(&path, format!("{}\n{extra}", text.replacen(from, to, 1))).unwrap();
    path
}

#[test]
fn ci_smoke_passes_and_writes_every_result() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("smoke");
    axiscal()
        .args(["run", "scenarios/ci-smoke.toml", "--out"])
        .arg(&out)
        .assert()
        .code(0);
    for f in [
        "scenario.resolved.toml",
        "trials.csv",
        "summary.json",
        "summary.md",
        "hist-uncal_pos_rms_mm.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let csv = std::fs::read_to_string(out.join("trials.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 4);
    assert!(csv.starts_with("case,trial,seed,uncal_pos_rms_mm,"));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["schema"], "axiscal.summary/1");
    assert_eq!(summary["all_hold"], true);
    assert!(summary["cases"][0]["metrics"][0]["p95"].is_f64());

    // A second run into the same folder is refused without --force, accepted with it.
    let a = axiscal()
        .args(["run", "scenarios/ci-smoke.toml", "--out"])
        .arg(&out)
        .assert()
        .code(2);
    assert!(stderr(&a).contains("--force"));
    // With --force the earlier run's histogram goes; a user's `hist-*.svg` (no metric of the
    // run's) stays.
    std::fs::write(out.join("hist-mine.svg"), "<svg/>").unwrap();
    std::fs::write(out.join("hist-uncal_pos_rms_mm.svg"), "old").unwrap();
    axiscal()
        .args(["run", "scenarios/ci-smoke.toml", "--force", "--out"])
        .arg(&out)
        .assert()
        .code(0);
    assert_eq!(std::fs::read_to_string(out.join("hist-mine.svg")).unwrap(), "<svg/>");
    assert_ne!(
        std::fs::read_to_string(out.join("hist-uncal_pos_rms_mm.svg")).unwrap(),
        "old"
    );
}

#[test]
fn an_impossible_threshold_exits_1_and_says_by_how_much() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = smoke_variant(
        dir.path(),
        "impossible.toml",
        ("", ""),
        "[[thresholds]]\nmetric = \"uncal_pos_rms_mm\"\nstat = \"max\"\nop = \"<=\"\nvalue = 0.001\n",
    );
    let a = axiscal()
        .arg("run")
        .arg(&scenario)
        .arg("--out")
        .arg(dir.path().join("out"))
        .assert()
        .code(1);
    let err = stderr(&a);
    assert!(err.contains("max(uncal_pos_rms_mm) <= 0.001"), "{err}");
    assert!(err.contains("over the bound by"), "{err}");
    assert!(err.contains("1 threshold(s) failed"), "{err}");
}

/// Every trial fails (the simulated robot stands 900 m from the theodolites, whose lines of
/// sight meet there nearly parallel): the console says why (the first trial's error and how
/// many failed alike), `summary.json` records it, and the verdicts say there is no value
/// rather than `NaN`.
#[test]
fn a_case_whose_trials_all_fail_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let truth = std::fs::read_to_string("scenarios/robots/asea-irb6l-paper-truth.toml").unwrap();
    let base = "translation_mm = [-3142.3, 4439.4, -526.123]";
    assert!(truth.contains(base));
    let far = truth.replacen(base, "translation_mm = [-3142.3, 900000.0, -526.123]", 1);
    std::fs::write(dir.path().join("far-truth.toml"), far).unwrap();
    let scenario = smoke_variant(
        dir.path(),
        "far.toml",
        ("kind = \"paper\"", "kind = \"file\"\npath = \"far-truth.toml\""),
        "",
    );
    let out = dir.path().join("out");
    let a = axiscal()
        .arg("run")
        .arg(&scenario)
        .arg("--out")
        .arg(&out)
        .assert()
        .code(1);
    let (err, text) = (stderr(&a), crate::common::stdout(&a));
    assert!(
        err.contains("warning: case base: trial 0 failed: simulating the campaign"),
        "{err}"
    );
    assert!(
        !text.contains("NaN") && text.contains("no value (no trial of the case succeeded)"),
        "{text}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let case = &summary["cases"][0];
    assert_eq!(case["failed"], 4);
    let first = &case["first_error"];
    assert_eq!(first["trial"], 0);
    assert!(first["error"].as_str().unwrap().starts_with("simulating the campaign"));
    let same = first["same"].as_u64().unwrap();
    assert!((1..=4).contains(&same), "{first}");
}

#[test]
fn bad_scenarios_exit_2_naming_file_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let threshold = |metric: &str, op: &str| {
        format!("[[thresholds]]\nmetric = \"{metric}\"\nstat = \"p95\"\nop = \"{op}\"\nvalue = 1\n")
    };
    let cases = [
        (
            "typo.toml",
            ("trials = 4", "trails = 4"),
            String::new(),
            "unknown field `trails`",
        ),
        ("zero.toml", ("trials = 4", "trials = 0"), String::new(), "key `trials`"),
        (
            "noise.toml",
            ("net_radial_rms_mm = 0.19", "net_radial_rms_mm = -1"),
            String::new(),
            "key `measurement.net_radial_rms_mm`",
        ),
        (
            "metric.toml",
            ("", ""),
            threshold("no_such_mm", "<="),
            "key `thresholds[2].metric`",
        ),
        ("op.toml", ("", ""), threshold("occluded", "<"), "unknown variant `<`"),
        (
            "no-sweep.toml",
            (
                "[truth]",
                "[plan]\nreference = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\nsweeps = []\n\n[truth]",
            ),
            String::new(),
            "key `plan.sweeps`: case `base`: the plan has no sweep",
        ),
    ];
    for (name, replace, extra, key) in cases {
        let path = smoke_variant(dir.path(), name, replace, &extra);
        let a = axiscal()
            .arg("run")
            .arg(&path)
            .arg("--out")
            .arg(dir.path().join(format!("out-{name}")))
            .assert()
            .code(2);
        let err = stderr(&a);
        assert!(err.contains(name) && err.contains(key), "{name}: {err}");
    }
}

#[test]
fn four_shards_merged_equal_one_run_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    axiscal()
        .args(["run", "scenarios/ci-smoke.toml", "--trials", "7", "--out"])
        .arg(d.join("single"))
        .assert()
        .code(0);
    let mut merge = axiscal();
    merge.arg("merge");
    for k in 1..=4 {
        let shard = d.join(format!("shard{k}"));
        axiscal()
            .args(["run", "scenarios/ci-smoke.toml", "--trials", "7", "--threads", "1"])
            .arg("--shard")
            .arg(format!("{k}/4"))
            .arg("--out")
            .arg(&shard)
            .assert()
            .code(0);
        merge.arg(&shard);
    }
    merge.arg("--out").arg(d.join("merged")).assert().code(0);
    for f in ["trials.csv", "summary.json", "summary.md", "scenario.resolved.toml"] {
        let single = std::fs::read(d.join("single").join(f)).unwrap();
        let merged = std::fs::read(d.join("merged").join(f)).unwrap();
        assert!(single == merged, "{f} differs between one run and four merged shards");
    }
    // Missing shards are refused.
    let a = axiscal()
        .arg("merge")
        .arg(d.join("shard1"))
        .arg(d.join("shard3"))
        .arg("--out")
        .arg(d.join("partial"))
        .assert()
        .code(2);
    assert!(stderr(&a).contains("missing"));
}

/// A scenario named `.` or `..` is refused at load: `results/..` is the working folder, whose
/// files `run --force` replaced (a user's `summary.md`).
#[test]
fn a_scenario_named_dot_or_dot_dot_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("summary.md"), "mine").unwrap();
    for (i, name) in [".", ".."].into_iter().enumerate() {
        let text = std::fs::read_to_string("scenarios/ci-smoke.toml").unwrap();
        let scenario = dir.path().join(format!("s{i}.toml"));
        std::fs::write(&scenario, format!("name = \"{name}\"\n{text}")).unwrap();
        let a = axiscal()
            .current_dir(dir.path())
            .arg("run")
            .arg(&scenario)
            .arg("--force")
            .assert()
            .code(2);
        assert!(stderr(&a).contains("not a folder name of its own"), "{}", stderr(&a));
    }
    assert_eq!(std::fs::read_to_string(dir.path().join("summary.md")).unwrap(), "mine");
    assert!(!dir.path().join("results").exists());
}

/// A lock file that is a link is refused, never written through (the run wrote its process id
/// over the scenario file the link pointed at).
#[test]
fn a_lock_file_that_is_a_link_is_not_written_through() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = dir.path().join("my.toml");
    std::fs::copy("scenarios/ci-smoke.toml", &scenario).unwrap();
    let before = std::fs::read_to_string(&scenario).unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::os::unix::fs::symlink(&scenario, out.join(".axiscal.lock")).unwrap();
    let a = axiscal()
        .arg("run")
        .arg(&scenario)
        .arg("--out")
        .arg(&out)
        .assert()
        .code(2);
    assert!(stderr(&a).contains("the lock file is a link"), "{}", stderr(&a));
    assert_eq!(std::fs::read_to_string(&scenario).unwrap(), before);
}

/// Hostile run 70: a scenario whose truth is another robot's (another joint count, another
/// joint kind) or whose ISO 9283 cube is centred outside the joint limits ran every trial into
/// a failure and exited 1; each is now refused at load, naming the file and the key, exit 2,
/// nothing run.
#[test]
fn a_truth_of_another_robot_or_a_centre_beyond_the_limits_is_refused_at_load() {
    let dir = tempfile::tempdir().unwrap();
    let robots = std::fs::canonicalize("scenarios/robots").unwrap();
    let at = |name: &str| robots.join(name).display().to_string();
    let scara = format!("robot = \"{}\"\n", at("scara-rrpr.toml"));
    let cases = [
        (
            "count.toml",
            ("description", format!("{scara}description")),
            String::new(),
            "key `truth`: the truth has 6 joints, the robot",
        ),
        (
            "kind.toml",
            (
                "kind = \"paper\"",
                format!(
                    "{scara}[truth]\nkind = \"file\"\npath = \"{}\"",
                    at("table-prpp-truth.toml")
                ),
            ),
            String::new(),
            "key `truth.path`: the truth's joint 1 is prismatic",
        ),
        (
            "centre.toml",
            ("description", "description".to_string()),
            "[iso9283]\ncycles = 3\ncentre_cmd = [0.0, 0.0, 0.0, 0.0, 0.0, 500.0]\n".to_string(),
            "key `iso9283.centre_cmd`: joint 6's 500 deg is outside its limits",
        ),
    ];
    for (name, replace, extra, expected) in cases {
        let text = std::fs::read_to_string("scenarios/ci-smoke.toml").unwrap();
        let text = match replace.0 {
            "kind = \"paper\"" => text.replacen("[truth]\nkind = \"paper\"", &replace.1, 1),
            from => text.replacen(from, &replace.1, 1),
        };
        let path = dir.path().join(name);
        std::fs::write(&path, format!("{text}\n{extra}")).unwrap();
        let out = dir.path().join(format!("out-{name}"));
        let a = axiscal().arg("run").arg(&path).arg("--out").arg(&out).assert().code(2);
        let e = stderr(&a);
        assert!(e.contains(name) && e.contains(expected), "{name}: {e}");
        assert!(!out.join("trials.csv").exists(), "{name}: no trial run");
    }
}
