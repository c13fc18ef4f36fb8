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
/// at ten points of its run, leaves the whole old set or the whole new set; what it leaves beyond
/// that is only axiscal's named temporaries, which the next merge removes.
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
            // A SIGTERM removes the temporaries it knows of; one created in the instant before it
            // is tracked (a folder of plots) may stay, named as a SIGKILL's are.
            if !hidden.is_empty() {
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

/// A shipped description.
fn robot(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenarios/robots/{name}.toml"))
}

/// The free poses (`moved_joint` 0 rows) of `simulate --robot ROBOT --validation-poses 40
/// --seed SEED`, written to `dir/NAME.csv`.
fn free_poses(dir: &Path, name: &str, seed: u64) -> PathBuf {
    let all = dir.join(format!("{name}-{seed}-all.csv"));
    let path = robot(name);
    let args = ["simulate", "--sim", "analytic", "--robot", path.to_str().unwrap()];
    let mut c = axiscal(dir, &args);
    c.args([
        "--validation-poses",
        "40",
        "--seed",
        &seed.to_string(),
        "--out",
        all.to_str().unwrap(),
    ]);
    assert!(c.status().unwrap().success());
    let text = std::fs::read_to_string(&all).unwrap();
    let mut column = None;
    let kept: Vec<&str> = text
        .lines()
        .filter(|line| {
            if line.starts_with('#') {
                return true;
            }
            let fields: Vec<&str> = line.split(',').collect();
            match column {
                None => {
                    column = fields.iter().position(|f| *f == "moved_joint");
                    true
                }
                Some(k) => fields[k] == "0",
            }
        })
        .collect();
    let out = dir.join(format!("{name}-{seed}.csv"));
    std::fs::write(&out, kept.join("\n") + "\n").unwrap();
    out
}

/// Run 8's S6: another robot's free poses (the FANUC's read with a UR5e's description) were
/// imported without a word. The nominal robot placed at best misses them by a good part of
/// their spread; the free poses of every shipped test robot, read with its own description,
/// are not warned of (seeds not tuned on).
#[test]
fn another_robots_free_poses_are_named() {
    use axiscal::measurement::{read_measurements, unit_check::not_this_robot};
    use axiscal::robot::RobotDescription;
    let dir = tempfile::tempdir().unwrap();
    let robots = [
        "asea-irb6l",
        "scara-rrpr",
        "ur5e-dh",
        "arm7-dh",
        "table-prpp",
        "positioner-2axis",
    ];
    for name in robots {
        let desc = RobotDescription::from_file(&robot(name)).unwrap();
        for seed in [411, 412, 413] {
            let set = read_measurements(&free_poses(dir.path(), name, seed), Some(desc.dof())).unwrap();
            assert_eq!(not_this_robot(&set, &desc), None, "{name} seed {seed}");
        }
    }
    let irb = read_measurements(&free_poses(dir.path(), "asea-irb6l", 414), Some(6)).unwrap();
    let ur5e = RobotDescription::from_file(&robot("ur5e-dh")).unwrap();
    let slip = not_this_robot(&irb, &ur5e).expect("the IRB's poses read as a UR5e's");
    assert!(
        slip.message.contains("these data do not look like UR5e"),
        "{}",
        slip.message
    );
}

/// Run 8's S6 on the real file: the FANUC R-2000iC tracker data imported with the UR5e's
/// description are warned of; with the FANUC's own, not.
#[test]
#[ignore = "needs ../shared/data/real/fanuc-r2000ic-tracker (run by `make test-real`)"]
fn the_real_fanuc_data_imported_for_a_ur5e_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let mat = crate::common::real_data("fanuc-r2000ic-tracker/calibration_dataset.mat");
    for (name, warned) in [("ur5e-dh", true), ("real/fanuc-r2000ic", false)] {
        let path = robot(name);
        let args = [
            "import",
            "mat",
            mat.to_str().unwrap(),
            "--robot",
            path.to_str().unwrap(),
        ];
        let more: Vec<&str> = crate::common::REAL_FANUC_OPTIONS
            .into_iter()
            .chain(["--out", "m.csv", "--force"])
            .collect();
        let (ok, err) = stderr_of(dir.path(), &args, &more);
        assert!(ok, "{name}: {err}");
        assert_eq!(err.contains("these data do not look like"), warned, "{name}: {err}");
    }
}

/// `axiscal ARGS... MORE...` in `dir`: its exit status and stderr.
fn stderr_of(dir: &Path, args: &[&str], more: &[&str]) -> (bool, String) {
    let out = Command::new(assert_cmd::cargo::cargo_bin("axiscal"))
        .current_dir(dir)
        .args(args)
        .args(more)
        .output()
        .unwrap();
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}
