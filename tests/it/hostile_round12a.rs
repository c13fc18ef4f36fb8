//! Helper h12a (hostile run 11, SB1 / SB2 / console noise): a command column scaled by 0.5 to
//! 0.6 % passed with no word, while the transmission test's note listed only the columns it
//! could not reach to 1 %; a sliding joint's column scaled 0.5 % passed in sweep files; and the
//! notes of what a file cannot show took several hundred characters each. Every file now says
//! each command column's own bound in one line (the words in report.md, "Detection limits"), a
//! slide's travel per command between 4 and 6 sigma of its lead is a note naming its column, and
//! the instrument-axis note is one line too; a one-axis scale the profile finds but cannot
//! confirm (a pose the model cannot fit remains with it undone) is a note naming it.

use crate::common::altered_csv;
use crate::common::hostile::{case, run_case};
use crate::hostile_round9b::{robot_path, simulated};
use std::path::Path;

/// The console line of the command-column bounds.
const COMMAND_BOUNDS: &str = "command-column scales this file cannot show: ";

/// `calibrate FILE --robot ROBOT --out OUT` in `dir`, its stderr.
fn calibrated(dir: &Path, file: &str, robot: &str, out: &str) -> String {
    let args = format!("calibrate {file} --robot {} --out {out}", robot_path(robot));
    run_case(dir, &case("calibrate", &args, 0, &[]))
}

/// `file` in `dir` with the field `field` of every row times `factor`, as `name`.
fn scaled(dir: &Path, file: &str, name: &str, field: usize, factor: f64) {
    altered_csv(
        &dir.join(file),
        name,
        |_| true,
        |f| crate::common::scale_fields(f, field..field + 1, factor),
    );
}

/// The bound the command-column line gives `column` (`cmd_4`), in per cent.
fn bound_of(stderr: &str, column: &str) -> Option<f64> {
    let line = stderr.lines().find(|l| l.contains(COMMAND_BOUNDS))?;
    let rest = &line[line.find(&format!("`{column}` below "))? + column.len() + 9..];
    rest.split_whitespace().next()?.parse().ok()
}

/// A column is named (a warning or a note with its factor) or covered by its bound.
fn named_or_bounded(stderr: &str, column: &str, joint: usize, scale_percent: f64) -> bool {
    let named = stderr.contains(&format!("the column `{column}` (joint {joint} slides) holds"))
        || stderr.contains(&format!("the column `{column}` looks scaled"))
        || stderr.contains(&format!("the column `{column}` was scaled by"))
        || stderr.contains(&format!("`{column}` scaled by"));
    named || bound_of(stderr, column).is_some_and(|b| b >= scale_percent)
}

#[test]
fn a_sweep_file_says_each_command_columns_bound_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulated(d, "arm6-dh", 1201, 0, "sw.csv");
    let e = calibrated(d, "sw.csv", "arm6-dh", "out");
    let lines: Vec<&str> = e.lines().filter(|l| l.contains(COMMAND_BOUNDS)).collect();
    assert_eq!(lines.len(), 1, "{e}");
    for j in 1..=6 {
        let b = bound_of(&e, &format!("cmd_{j}")).unwrap_or_else(|| panic!("cmd_{j}: {e}"));
        assert!(b > 0.0 && b < 100.0, "cmd_{j} {b}: {e}");
    }
    assert!(lines[0].len() < 400, "{}", lines[0]);
    assert!(!e.contains("warning:"), "{e}");
    let report = std::fs::read_to_string(d.join("out/report.md")).unwrap();
    assert!(report.contains("## Detection limits"), "{report}");
    assert!(report.contains("`cmd_6`: a scale below"), "{report}");
}

#[test]
fn a_wrist_column_scaled_half_a_per_cent_is_named_or_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulated(d, "ur5e-dh", 1202, 80, "all.csv");
    altered_csv(&d.join("all.csv"), "fp.csv", |f| f[1] == "0", |_| {});
    // cmd_5 is field 11 (cmd_1 is field 7).
    scaled(d, "fp.csv", "c5.csv", 11, 0.995);
    let e = calibrated(d, "c5.csv", "ur5e-dh", "out");
    assert!(named_or_bounded(&e, "cmd_5", 5, 0.5), "{e}");
    scaled(d, "all.csv", "sw5.csv", 11, 1.006);
    let e = calibrated(d, "sw5.csv", "ur5e-dh", "out2");
    assert!(named_or_bounded(&e, "cmd_5", 5, 0.6), "{e}");
}

#[test]
fn a_slides_column_scaled_half_a_per_cent_in_sweeps_is_named_or_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulated(d, "table-prpp", 1203, 0, "sw.csv");
    scaled(d, "sw.csv", "c1.csv", 7, 1.005);
    let e = calibrated(d, "c1.csv", "table-prpp", "out");
    assert!(named_or_bounded(&e, "cmd_1", 1, 0.5), "{e}");
    let e = calibrated(d, "sw.csv", "table-prpp", "clean");
    assert!(!e.contains("slides) holds") && !e.contains("warning:"), "{e}");
}

#[test]
fn the_instrument_axis_note_is_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulated(d, "asea-irb6l", 1204, 0, "sw.csv");
    let e = calibrated(d, "sw.csv", "asea-irb6l", "out");
    for l in e.lines().filter(|l| l.contains("cannot show")) {
        assert!(l.len() < 400, "{l}");
        assert!(l.ends_with("(report.md, \"Detection limits\")"), "{l}");
    }
    assert!(!e.contains("would pass the coordinate-scale test"), "{e}");
}

#[test]
fn an_axis_scale_the_profile_cannot_confirm_is_said() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Run 11's SB3 file: free poses of seed 404 with `x_mm` read 0.3 % short. With the column
    // undone a clean pose sits beyond the outlier fence, so the profile's finding is not
    // confirmed; the file said nothing and so claimed it would name 0.3 %.
    simulated(d, "ur5e-dh", 404, 60, "src.csv");
    altered_csv(&d.join("src.csv"), "fp.csv", |f| f[1] == "0", |_| {});
    scaled(d, "fp.csv", "x.csv", 4, 0.997);
    let e = calibrated(d, "x.csv", "ur5e-dh", "out");
    assert!(
        e.contains("`x_mm` reads 0.99") || e.contains("the instrument's x axis reads 0.99"),
        "{e}"
    );
}
