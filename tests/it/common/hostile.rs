//! The table of the hostile-input tests: a case is a command line run in a folder of inputs,
//! the exit code it must give and what its stderr must name.

use std::path::Path;
use std::time::Duration;

/// One hostile try: the arguments (run in the case folder), the exit code, and what stderr
/// must hold.
pub struct Case {
    /// What the case tries, in words (the failure's label).
    pub what: &'static str,
    /// The command line, split at white space.
    pub args: Vec<String>,
    /// The exit code.
    pub code: i32,
    /// What stderr must contain.
    pub names: Vec<String>,
}

/// A [`Case`] of the command line `args` (split at white space).
pub fn case(what: &'static str, args: &str, code: i32, names: &[&str]) -> Case {
    Case {
        what,
        args: args.split_whitespace().map(str::to_owned).collect(),
        code,
        names: names.iter().map(|n| n.to_string()).collect(),
    }
}

/// Runs `c` in `dir` and returns its stderr: the exit code and the names checked, and a bad
/// input (exit 2) said in one line of less than a screenful, with nothing written as `out` or
/// `out.csv` ([`clear_outputs`] removes what a case did write, before the next).
pub fn run_case(dir: &Path, c: &Case) -> String {
    let e = stderr_of_case(dir, c);
    if c.code == 2 {
        assert_eq!(e.lines().count(), 1, "{}: one line: {e}", c.what);
        assert!(e.len() < 1000, "{}: a long value echoed: {} bytes", c.what, e.len());
        let written = ["out", "out.csv"].map(|n| dir.join(n));
        assert!(written.iter().all(|p| !p.exists()), "{}: nothing written", c.what);
    }
    e
}

/// Runs `c` in `dir` and returns its stderr, with the exit code and the names checked.
pub fn stderr_of_case(dir: &Path, c: &Case) -> String {
    let a = crate::common::axiscal()
        .current_dir(dir)
        .args(&c.args)
        .timeout(Duration::from_secs(120))
        .assert()
        .code(c.code);
    let e = crate::common::stderr(&a);
    for name in &c.names {
        assert!(e.contains(name.as_str()), "{}: no {name:?} in {e}", c.what);
    }
    e
}

/// `cal/calibration.json` of `dir` with `edit` applied to its JSON value, as `name`.
pub fn edited_calibration(dir: &Path, name: &str, edit: impl FnOnce(&mut serde_json::Value)) {
    let text = std::fs::read_to_string(dir.join("cal/calibration.json")).unwrap();
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    edit(&mut value);
    std::fs::write(dir.join(name), serde_json::to_string(&value).unwrap()).unwrap();
}

/// `calibrate DATA --out out --force` run in `dir`, which must succeed: its stderr.
pub fn calibrate_stderr(dir: &Path, data: &Path) -> String {
    let a = crate::common::axiscal()
        .current_dir(dir)
        .arg("calibrate")
        .arg(data)
        .args(["--out", "out", "--force"])
        .assert()
        .success();
    crate::common::stderr(&a)
}

/// Removes what a case wrote as `out` or `out.csv` in `dir`.
pub fn clear_outputs(dir: &Path) {
    let _ = std::fs::remove_dir_all(dir.join("out"));
    let _ = std::fs::remove_file(dir.join("out.csv"));
}

/// `campaign.csv` (`simulate --sim analytic --validation-poses 40 --seed SEED`) and its
/// calibration `cal/` in `dir`: the inputs most cases alter.
pub fn calibrated_campaign(dir: &Path, seed: u64) {
    crate::common::simulate_analytic(dir, 40, seed, "campaign.csv");
    crate::common::axiscal()
        .current_dir(dir)
        .args(["calibrate", "campaign.csv", "--out", "cal"])
        .assert()
        .success();
}

/// The second path of the held-offset tests: an offset named once (`(value, sigma)`) and
/// named again with twice the offset written differ by the one written, `delta`, within 4 of
/// their combined sigmas (the clean file's own miss cancels); `what` names the case.
pub fn assert_twice_less_once(what: &str, once: (f64, f64), twice: (f64, f64), delta: f64) {
    let sigma = once.1.hypot(twice.1);
    assert!(
        (twice.0 - once.0 - delta).abs() < 4.0 * sigma,
        "{what}: {} - {} against {delta} +- {sigma}",
        twice.0,
        once.0
    );
}

/// [`assert_twice_less_once`] on each axis of a vector named once and with twice the vector
/// written (`(value, sigma)` per axis).
pub fn assert_twice_less_once_3(what: &str, once: ([f64; 3], [f64; 3]), twice: ([f64; 3], [f64; 3]), delta: [f64; 3]) {
    for (c, &d) in delta.iter().enumerate() {
        assert_twice_less_once(
            &format!("axis {c}: {what}"),
            (once.0[c], once.1[c]),
            (twice.0[c], twice.1[c]),
            d,
        );
    }
}

/// The first and last file line of experiment `experiment`'s rows in `file`, as `a-b`.
pub fn lines_of(file: &std::path::Path, experiment: &str) -> String {
    let text = std::fs::read_to_string(file).unwrap();
    let rows: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.split(',').next() == Some(experiment))
        .map(|(i, _)| i + 1)
        .collect();
    format!("{}-{}", rows[0], rows[rows.len() - 1])
}
