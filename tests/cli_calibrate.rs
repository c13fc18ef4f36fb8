//! `axiscal calibrate` end to end: simulate, calibrate, read the results back.

use assert_cmd::Command;
use axiscal::calibration::procedure::Calibration;

fn axiscal() -> Command {
    Command::cargo_bin("axiscal").unwrap()
}

#[test]
fn calibrate_writes_loadable_results_and_protects_them() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("campaign.csv");
    axiscal()
        .args(["simulate", "--seed", "5", "--out"])
        .arg(&data)
        .assert()
        .success();
    let out = dir.path().join("cal");
    axiscal()
        .arg("calibrate")
        .arg(&data)
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let cal: Calibration =
        serde_json::from_str(&std::fs::read_to_string(out.join("calibration.json")).unwrap()).unwrap();
    assert_eq!(cal.axes.len(), 6);
    assert_eq!(cal.couplings.len(), 2);
    assert!(
        std::fs::read_to_string(out.join("report.md"))
            .unwrap()
            .contains("## Findings")
    );
    assert!(
        std::fs::read_to_string(out.join("calibrated.urdf"))
            .unwrap()
            .contains("<joint name=\"joint6\"")
    );
    let findings: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert!(findings.as_array().is_some_and(|a| !a.is_empty()));

    // Nothing the user has is overwritten without --force.
    let a = axiscal()
        .arg("calibrate")
        .arg(&data)
        .arg("--out")
        .arg(&out)
        .assert()
        .code(2);
    assert!(String::from_utf8_lossy(&a.get_output().stderr).contains("--force"));
    axiscal()
        .arg("calibrate")
        .arg(&data)
        .arg("--out")
        .arg(&out)
        .arg("--force")
        .assert()
        .success();
    // The paper estimator runs as an option.
    axiscal()
        .arg("calibrate")
        .arg(&data)
        .args(["--estimator", "paper", "--out"])
        .arg(dir.path().join("paper"))
        .assert()
        .success();
}

#[test]
fn malformed_data_names_file_row_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("bad.csv");
    std::fs::write(
        &data,
        "experiment,moved_joint,step,target,x_mm,y_mm,z_mm,cmd_1,cmd_2,cmd_3,cmd_4,cmd_5,cmd_6\naxis6,6,0,0,1,2,abc,0,0,0,0,0,0\n",
    )
    .unwrap();
    let a = axiscal()
        .arg("calibrate")
        .arg(&data)
        .arg("--out")
        .arg(dir.path().join("o"))
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(
        err.contains("bad.csv") && err.contains(":2") && err.contains("z_mm"),
        "{err}"
    );
}
