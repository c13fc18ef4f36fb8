//! `axiscal simulate --record`, `calibrate --record`, `diagnose --record` and `axiscal view`:
//! a build without the `viz` feature refuses `--record` with a clear error (exit 2) before any
//! work; a build with it writes the recording; `view` without a viewer prints the install
//! command of the matching viewer and succeeds.
//!
//! The recordings are made by the binary `make test` builds (`AXISCAL_TEST_BIN`, the
//! `quick-release` profile with the feature, as `make run` builds it), and the refusals by this
//! build's own binary when it has no recorder: a plain `cargo test` tests them, `make test`
//! (which builds the tests with the feature) leaves them out.

use crate::common;

use crate::common::axiscal;
use assert_cmd::Command;

/// This build's binary: without the `viz` feature when the tests are built without it.
#[cfg(not(feature = "viz"))]
fn this_build() -> Command {
    Command::cargo_bin("axiscal").expect("the axiscal binary is built")
}

/// The binary that makes the recordings: `AXISCAL_TEST_BIN` when set (`make test`'s; one built
/// without the feature fails these tests, its error naming the feature), else this build's when
/// the tests are built with the feature. `None` in a plain `cargo test` without the feature:
/// the recording tests say so and pass (`make test` runs them).
fn recording_binary() -> Option<Command> {
    if std::env::var_os("AXISCAL_TEST_BIN").is_some() || cfg!(feature = "viz") {
        return Some(axiscal());
    }
    eprintln!("no binary with the viz feature (set AXISCAL_TEST_BIN, or run `make test`): recording not tested");
    None
}

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
    let out = this_build()
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

#[test]
fn record_writes_a_non_empty_recording() {
    let Some(mut recorder) = recording_binary() else {
        return;
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let rrd = dir.path().join("sub").join("c.rrd");
    recorder
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
        let a = this_build()
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
#[test]
fn calibrate_and_diagnose_record_the_measured_data() {
    if recording_binary().is_none() {
        return;
    }
    let (dir, data) = common::simulated_campaign_csv(3);
    for command in ["calibrate", "diagnose"] {
        let rrd = dir.path().join(format!("{command}.rrd"));
        let run = |force: bool| {
            let mut c = recording_binary().expect("checked above");
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

/// A recording is written as every output is: through a temporary, so a link named by
/// `--record` is replaced and what it points at is left alone (it was overwritten through the
/// link); a `--record` that is not an `.rrd` file (one of the command's own outputs, e.g.
/// `calibration.json`) is refused before any work.
#[test]
fn a_recording_neither_writes_through_a_link_nor_replaces_an_output() {
    let Some(mut recorder) = recording_binary() else {
        return;
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let notes = dir.path().join("notes.txt");
    std::fs::write(&notes, "mine").unwrap();
    let link = dir.path().join("link.rrd");
    std::os::unix::fs::symlink(&notes, &link).unwrap();
    recorder
        .args([
            "simulate",
            "--instrument",
            "isotropic",
            "--validation-poses",
            "1",
            "--force",
            "--out",
        ])
        .arg(dir.path().join("c.csv"))
        .arg("--record")
        .arg(&link)
        .assert()
        .success();
    assert_eq!(std::fs::read_to_string(&notes).unwrap(), "mine");
    assert_eq!(&std::fs::read(&link).unwrap()[..4], b"RRF2", "rrd magic");
    let (data_dir, data) = common::simulated_campaign_csv(3);
    let out = data_dir.path().join("cal");
    let a = recording_binary()
        .expect("checked above")
        .arg("calibrate")
        .arg(&data)
        .arg("--out")
        .arg(&out)
        .arg("--record")
        .arg(out.join("calibration.json"))
        .assert()
        .code(2);
    assert!(common::stderr(&a).contains("`.rrd`"), "{}", common::stderr(&a));
    assert!(!out.exists(), "refused before any work");
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
