//! Helper h11e (hostile run 10: ND1, run 5 S11, run 8 S6, run 6 S2/S4). `merge --force` into an
//! earlier result killed by SIGKILL left the new trials beside the old summary (the old files
//! deleted first, the new ones written one by one).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// `axiscal ARGS...` in `dir`, quiet.
fn axiscal(dir: &Path, args: &[&str]) -> Command {
    let mut c = Command::new(assert_cmd::cargo::cargo_bin("axiscal"));
    c.current_dir(dir)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    c
}

/// The visible files of `dir` with their bytes, and the names of its hidden files but the lock.
fn visible_and_hidden(dir: &Path) -> (Vec<(PathBuf, Vec<u8>)>, Vec<String>) {
    let mut visible = Vec::new();
    let mut hidden = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') {
            if name != ".axiscal.lock" {
                hidden.push(name);
            }
        } else {
            visible.push((entry.path(), std::fs::read(entry.path()).unwrap()));
        }
    }
    visible.sort();
    for file in &mut visible {
        file.0 = file.0.strip_prefix(dir).unwrap().to_path_buf();
    }
    (visible, hidden)
}

/// Run 10's ND1: `merge --force` into an earlier merged result, killed (SIGKILL, and SIGTERM)
/// at ten points of its run, leaves the whole old set or the whole new set; what a SIGKILL
/// leaves beyond that is only axiscal's named temporaries, which the next merge removes.
#[test]
fn a_killed_merge_leaves_one_whole_set() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (seed, shard) in [(1, 1), (1, 2), (2, 1), (2, 2)] {
        let (seed, split, out) = (seed.to_string(), format!("{shard}/2"), format!("sh{seed}_{shard}"));
        let args = [
            "run", "ci-smoke", "--trials", "200", "--seed", &seed, "--shard", &split, "--out", &out,
        ];
        assert!(axiscal(d, &args).status().unwrap().success());
    }
    assert!(
        axiscal(d, &["merge", "sh1_1", "sh1_2", "--out", "old"])
            .status()
            .unwrap()
            .success()
    );
    let start = Instant::now();
    assert!(
        axiscal(d, &["merge", "sh2_1", "sh2_2", "--out", "new"])
            .status()
            .unwrap()
            .success()
    );
    let whole = start.elapsed();
    let old = visible_and_hidden(&d.join("old")).0;
    let new = visible_and_hidden(&d.join("new")).0;
    let target = d.join("target");
    let merge = ["merge", "sh2_1", "sh2_2", "--out", "target", "--force"];
    for signal in [libc::SIGKILL, libc::SIGTERM] {
        for k in 0..10 {
            let _ = std::fs::remove_dir_all(&target);
            std::fs::create_dir(&target).unwrap();
            for (name, bytes) in &old {
                std::fs::write(target.join(name), bytes).unwrap();
            }
            let mut child = axiscal(d, &merge).spawn().unwrap();
            std::thread::sleep(whole.mul_f64(0.1 * k as f64) + Duration::from_micros(500));
            // SAFETY: a signal to the child this test started.
            unsafe { libc::kill(child.id() as i32, signal) };
            child.wait().unwrap();
            let (after, hidden) = visible_and_hidden(&target);
            let at = format!("signal {signal} at {k}/10 of the run");
            assert!(
                after == old || after == new,
                "{at}: a mixed set {:?}",
                after.iter().map(|f| &f.0).collect::<Vec<_>>()
            );
            if signal == libc::SIGTERM {
                assert!(hidden.is_empty(), "{at}: {hidden:?} left");
            } else if !hidden.is_empty() {
                assert!(
                    hidden
                        .iter()
                        .all(|n| n.contains(".axiscal-") || n.starts_with(".axiscal-")),
                    "{at}: {hidden:?}"
                );
                assert!(axiscal(d, &merge).status().unwrap().success());
                let (again, hidden) = visible_and_hidden(&target);
                assert!(
                    again == new && hidden.is_empty(),
                    "{at}: the next merge left {hidden:?}"
                );
            }
        }
    }
}

