//! `axiscal evaluate` end to end: the paper scenario writes its report and plots and does not
//! overwrite them without `--force`.

use assert_cmd::Command;
use axiscal::harness::evaluation::{PLOT_FILES, PaperReport};

fn evaluate(out: &std::path::Path, force: bool) -> assert_cmd::assert::Assert {
    let mut cmd = Command::cargo_bin("axiscal").unwrap();
    cmd.args(["evaluate", "--seed", "2", "--random-poses", "5", "--out"])
        .arg(out);
    if force {
        cmd.arg("--force");
    }
    cmd.assert()
}

#[test]
fn evaluate_writes_the_report_and_protects_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("paper");
    evaluate(&out, false).success();
    let report: PaperReport =
        serde_json::from_str(&std::fs::read_to_string(out.join("evaluation.json")).unwrap()).unwrap();
    assert_eq!(report.scenario.seed, 2);
    assert_eq!(report.regions.len(), 2);
    for f in PLOT_FILES
        .iter()
        .chain(&["poses.csv", "calibration.json", "floor_calibration.json"])
    {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // Nothing is overwritten without --force: exit 2, naming the file.
    let again = evaluate(&out, false).code(2);
    let stderr = String::from_utf8_lossy(&again.get_output().stderr).into_owned();
    assert!(
        stderr.contains("evaluation.json") && stderr.contains("--force"),
        "{stderr}"
    );
    evaluate(&out, true).success();
}
