//! The commands that run trials in parallel (`blind`, `study`, `evaluate`'s floor check,
//! `run`; `budget`'s pooled error: tests/it/gap_budget.rs) write the same bytes on 1 and on 2
//! worker threads: each trial's random
//! stream comes from (seed, trial index) alone and the results are gathered in trial order.
//! The thread count is set through `RAYON_NUM_THREADS` (the default of every command's pool);
//! each command writes into the same folder both times, so paths written into the outputs
//! match, and every file is compared byte for byte (the lock file, which holds the process
//! id, excepted).

use crate::common::axiscal;
use std::collections::BTreeMap;
use std::path::Path;

/// Every file under `dir` (relative path -> bytes), the lock file left out.
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.file_name().is_some_and(|n| n != ".axiscal.lock") {
                let rel = path.strip_prefix(dir).unwrap().display().to_string();
                out.insert(rel, std::fs::read(&path).unwrap());
            }
        }
    }
    out
}

/// Runs `args` (with `--out <dir> --force`) on 1 and on 2 threads and asserts the same files
/// with the same bytes and the same stdout.
fn assert_same_on_one_and_two_threads(args: &[&str]) {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let run = |threads: &str| {
        let a = axiscal()
            .args(args)
            .arg("--out")
            .arg(&out)
            .arg("--force")
            .env("RAYON_NUM_THREADS", threads)
            .assert()
            .code(0);
        (files(&out), a.get_output().stdout.clone())
    };
    let (one, one_stdout) = run("1");
    let (two, two_stdout) = run("2");
    assert!(!one.is_empty(), "{args:?} wrote nothing");
    assert_eq!(
        one.keys().collect::<Vec<_>>(),
        two.keys().collect::<Vec<_>>(),
        "{args:?}"
    );
    for (name, bytes) in &one {
        assert!(two[name] == *bytes, "{args:?}: {name} differs between 1 and 2 threads");
    }
    assert_eq!(
        String::from_utf8_lossy(&one_stdout),
        String::from_utf8_lossy(&two_stdout),
        "{args:?}: stdout"
    );
}

#[test]
fn blind_writes_the_same_bytes_on_one_and_two_threads() {
    assert_same_on_one_and_two_threads(&["blind", "--cases", "2", "--seed", "5", "--poses", "16"]);
}

#[test]
fn study_writes_the_same_bytes_on_one_and_two_threads() {
    assert_same_on_one_and_two_threads(&["study", "--trials", "6", "--seed", "9"]);
}

#[test]
fn evaluate_floor_check_writes_the_same_bytes_on_one_and_two_threads() {
    assert_same_on_one_and_two_threads(&["evaluate", "--seed", "4", "--floor-seeds", "3", "--random-poses", "10"]);
}

#[test]
fn run_writes_the_same_bytes_on_one_and_two_threads() {
    assert_same_on_one_and_two_threads(&["run", "scenarios/ci-smoke.toml", "--trials", "5"]);
}
