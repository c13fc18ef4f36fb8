//! `axiscal simulate --record` and `axiscal view`: without the `viz` feature `--record` is a
//! clear error (exit 2); with it a recording is written; `view` without a viewer prints the
//! install command of the matching viewer and succeeds.

use crate::common;

use crate::common::axiscal;

/// The `rerun` crate version pinned in Cargo.toml (`rerun = { version = "=x.y.z", ... }`).
fn pinned_rerun_version() -> &'static str {
    include_str!("../../Cargo.toml")
        .lines()
        .find_map(|l| l.strip_prefix("rerun = { version = \"="))
        .and_then(|rest| rest.split('"').next())
        .expect("Cargo.toml pins rerun")
}

#[cfg(not(feature = "viz"))]
#[test]
fn record_without_the_viz_feature_is_an_error_with_exit_code_2() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = axiscal()
        .args([
            "simulate",
            "--instrument",
            "isotropic",
            "--validation-poses",
            "1",
            "--out",
        ])
        .arg(dir.path().join("c.csv"))
        .arg("--record")
        .arg(dir.path().join("c.rrd"))
        .assert()
        .code(2)
        .get_output()
        .clone();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("--features viz"), "{stderr}");
    assert!(!dir.path().join("c.csv").exists(), "fails before simulating");
}

#[cfg(feature = "viz")]
#[test]
fn record_writes_a_non_empty_recording() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rrd = dir.path().join("sub").join("c.rrd");
    axiscal()
        .args([
            "simulate",
            "--instrument",
            "isotropic",
            "--validation-poses",
            "5",
            "--out",
        ])
        .arg(dir.path().join("c.csv"))
        .arg("--record")
        .arg(&rrd)
        .assert()
        .success();
    let bytes = std::fs::read(&rrd).expect("recording written");
    assert!(bytes.len() > 10_000, "recording has {} bytes", bytes.len());
    assert_eq!(&bytes[..4], b"RRF2", "rrd magic");
}

#[cfg(not(feature = "viz"))]
#[test]
fn calibrate_and_diagnose_record_without_the_viz_feature_fail_before_any_work() {
    let (dir, data) = common::simulated_campaign_csv(3);
    for command in ["calibrate", "diagnose"] {
        let out = dir.path().join(command);
        let a = axiscal()
            .arg(command)
            .arg(&data)
            .arg("--out")
            .arg(&out)
            .arg("--record")
            .arg(dir.path().join("x.rrd"))
            .assert()
            .code(2);
        assert!(
            common::stderr(&a).contains("--features viz"),
            "{command}: {}",
            common::stderr(&a)
        );
        assert!(!out.exists(), "{command} wrote its outputs before failing");
    }
}

/// A recording of measured data through `calibrate --record` and `diagnose --record`: written,
/// non-empty, and not replaced without `--force`.
#[cfg(feature = "viz")]
#[test]
fn calibrate_and_diagnose_record_the_measured_data() {
    let (dir, data) = common::simulated_campaign_csv(3);
    for command in ["calibrate", "diagnose"] {
        let rrd = dir.path().join(format!("{command}.rrd"));
        let run = |force: bool| {
            let mut c = axiscal();
            c.arg(command)
                .arg(&data)
                .arg("--out")
                .arg(dir.path().join(command))
                .arg("--record")
                .arg(&rrd);
            if force {
                c.arg("--force");
            }
            c.assert()
        };
        run(false).success();
        let bytes = std::fs::read(&rrd).expect("recording written");
        assert!(bytes.len() > 10_000, "{command}: recording has {} bytes", bytes.len());
        assert_eq!(&bytes[..4], b"RRF2", "rrd magic");
        let again = run(false).code(2);
        assert!(common::stderr(&again).contains("--force"), "{}", common::stderr(&again));
        run(true).success();
    }
}

#[test]
fn view_without_a_viewer_prints_the_matching_install_command() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("x.rrd"), b"RRF2").expect("write");
    let out = axiscal()
        .current_dir(dir.path())
        .env("PATH", "")
        .env("AXISCAL_RERUN", dir.path().join("no-viewer-here"))
        .args(["view", "x.rrd"])
        .assert()
        .success()
        .get_output()
        .clone();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = format!("pip install rerun-sdk=={}", pinned_rerun_version());
    assert!(stdout.lines().any(|l| l.trim() == line), "{stdout}");
}

#[test]
fn view_of_a_missing_file_is_an_error() {
    let dir = tempfile::tempdir().expect("temp dir");
    axiscal()
        .current_dir(dir.path())
        .args(["view", "missing.rrd"])
        .assert()
        .code(2);
}
