//! The plan's line of sight (closed-form distances to the nominal links' capsules) against the
//! rapier simulator's (parry ray casts on the simulated real robot, with its four-bar bodies):
//! a second, differently written path. The plan knows neither the real robot's errors nor the
//! four-bar bodies, so it is held to what a planning aid must do: predict at least 80 % of the
//! occlusions the simulator finds and call at most 10 % of its hidden points wrongly.

use crate::common::axiscal;
use std::collections::HashSet;
use std::path::Path;

fn data_rows(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<String> = lines.next().unwrap().split(',').map(str::to_owned).collect();
    (
        header,
        lines.map(|l| l.split(',').map(str::to_owned).collect()).collect(),
    )
}

fn key(h: &[String], r: &[String]) -> (String, String, String) {
    let c = |n: &str| r[h.iter().position(|x| x == n).unwrap()].clone();
    (c("experiment"), c("step"), c("target"))
}

#[test]
fn plan_sight_predicts_the_simulators_occlusions() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    axiscal()
        .args(["plan", "--validation-poses", "60", "--out"])
        .arg(d.join("plan.csv"))
        .assert()
        .success();
    axiscal()
        .args([
            "simulate",
            "--sim",
            "rapier",
            "--validation-poses",
            "60",
            "--seed",
            "2",
            "--out",
        ])
        .arg(d.join("sim.csv"))
        .assert()
        .success();
    let (sh, srows) = data_rows(&d.join("sim.csv"));
    let seen: HashSet<_> = srows.iter().map(|r| key(&sh, r)).collect();
    let (ph, prows) = data_rows(&d.join("plan.csv"));
    let sight: Vec<usize> = (0..ph.len()).filter(|&k| ph[k].starts_with("visible_")).collect();
    let (mut both, mut only_plan, mut only_sim) = (0usize, 0usize, 0usize);
    for r in &prows {
        let hidden = sight.iter().any(|&k| r[k] == "no");
        let occluded = !seen.contains(&key(&ph, r));
        match (hidden, occluded) {
            (true, true) => both += 1,
            (true, false) => only_plan += 1,
            (false, true) => only_sim += 1,
            (false, false) => {}
        }
    }
    eprintln!(
        "{} points: hidden in plan and simulator {both}, plan only {only_plan}, simulator only {only_sim}",
        prows.len()
    );
    assert!(both > 0, "the campaign has occlusions to predict");
    assert!(both as f64 >= 0.8 * (both + only_sim) as f64);
    assert!(only_plan as f64 <= 0.1 * (both + only_plan) as f64);
}
