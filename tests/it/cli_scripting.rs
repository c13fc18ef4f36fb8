//! Scripts' view of the commands: `--json` puts the command's JSON document alone on stdout,
//! `--quiet` silences the rest, no progress display reaches a non-terminal stderr, and
//! `completions SHELL` prints a completion script.

use crate::common::{axiscal, simulated_campaign_csv, stderr, stdout};

fn json_of(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("stdout is not one JSON document ({e}): {text}"))
}

#[test]
fn calibrate_and_diagnose_json_is_the_whole_stdout() {
    let (dir, data) = simulated_campaign_csv(8);
    let a = axiscal()
        .arg("calibrate")
        .arg(&data)
        .arg("--json")
        .arg("--out")
        .arg(dir.path().join("cal"))
        .assert()
        .success();
    let v = json_of(&stdout(&a));
    assert_eq!(v["schema"], "axiscal.report/1");
    assert!(stderr(&a).contains("calibrated "), "the human lines go to stderr");
    let q = axiscal()
        .args(["--quiet", "calibrate"])
        .arg(&data)
        .args(["--json", "--force", "--out"])
        .arg(dir.path().join("cal"))
        .assert()
        .success();
    json_of(&stdout(&q));
    assert!(!stderr(&q).contains("calibrated "), "{}", stderr(&q));
    let d = axiscal()
        .arg("diagnose")
        .arg(&data)
        .args([
            "--json",
            "--noise-trials",
            "2",
            "--noise-draws",
            "1",
            "--axis-replicas",
            "2",
            "--out",
        ])
        .arg(dir.path().join("diag"))
        .assert()
        .success();
    assert_eq!(json_of(&stdout(&d))["schema"], "axiscal.diagnosis/2");
}

#[test]
fn run_json_and_no_progress_on_a_pipe() {
    let dir = tempfile::tempdir().unwrap();
    let a = axiscal()
        .args(["run", "ci-smoke", "--trials", "2", "--threads", "2", "--json", "--out"])
        .arg(dir.path().join("r"))
        .assert();
    let code = a.get_output().status.code();
    assert!(matches!(code, Some(0 | 1)), "{}", stderr(&a));
    assert_eq!(json_of(&stdout(&a))["schema"], "axiscal.summary/1");
    // stderr is a pipe here: the progress bar (`N/M trials ... elapsed`) is not drawn.
    assert!(!stderr(&a).contains("elapsed"), "{}", stderr(&a));
}

#[test]
fn completions_for_each_shell() {
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let a = axiscal().args(["completions", shell]).assert().success();
        let script = stdout(&a);
        assert!(script.contains("calibrate") && script.contains("import"), "{shell}");
    }
    axiscal().args(["completions", "tcsh"]).assert().code(2);
}

/// Every command's help is written for users: no Rust paths (`module::Type`) and no markdown
/// escapes (`\[mm\]`) from the doc comments it is made of.
#[test]
fn help_texts_name_no_rust_items() {
    let top = stdout(&axiscal().arg("--help").assert().success());
    let commands: Vec<String> = top
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_owned))
        .filter(|c| c != "help")
        .collect();
    assert!(commands.len() >= 15, "{commands:?}");
    for c in &commands {
        let help = stdout(&axiscal().args([c.as_str(), "--help"]).assert().success());
        for line in help.lines() {
            let rust_path = line
                .split(|ch: char| !(ch.is_alphanumeric() || ch == '_' || ch == ':'))
                .any(|w| w.contains("::") && !w.starts_with("::") && !w.ends_with("::"));
            assert!(!rust_path && !line.contains("\\["), "`axiscal {c} --help`: {line}");
        }
    }
}
