//! A command column scaled on export, on sweeps: the transmission test names its joint, and
//! the coordinate-scale profile runs with that column undone by the joint's slope. Profiled as
//! read, the fits' share of the column's scale read as an instrument axis' (`cmd_2` x1.02 on
//! the UR5e as `z_mm` x1.0055 at 8 sigma, beside joint 2's own warning). An instrument axis
//! scaled beside the command column is still named.

use crate::common::{axiscal, column_scaled, stderr};
use crate::hostile_round15s::{robot, simulated};
use std::path::Path;

/// `calibrate` of `file` on robot `name`: exit code and stderr.
pub fn calibrate(dir: &Path, name: &str, file: &Path) -> (i32, String) {
    let a = axiscal()
        .current_dir(dir)
        .args(["calibrate", "--robot", &robot(name)])
        .arg(file)
        .args(["--out", "cal", "--force"])
        .assert();
    (a.get_output().status.code().unwrap_or(-1), stderr(&a))
}

/// The warnings of `stderr` that name a joint's command column scaled, and those that name an
/// instrument axis.
fn named(stderr: &str) -> (Vec<&str>, Vec<&str>) {
    let warnings = || stderr.lines().filter(|l| l.starts_with("warning:"));
    (
        warnings().filter(|l| l.contains("looks scaled")).collect(),
        warnings().filter(|l| l.contains("the instrument's")).collect(),
    )
}

#[test]
fn a_command_column_scaled_is_not_also_read_as_an_instrument_axis() {
    let dir = tempfile::tempdir().unwrap();
    for (name, column, factor) in [("ur5e-dh", 8, 1.02), ("ur5e-dh", 9, 0.98), ("arm6-dh", 8, 1.02)] {
        let clean = simulated(dir.path(), name, 5);
        let file = column_scaled(&clean, &format!("{name}_{column}.csv"), column, factor);
        let (code, e) = calibrate(dir.path(), name, &file);
        assert_eq!(code, 0, "{e}");
        let (commands, axes) = named(&e);
        let cmd = format!("`cmd_{}`", column - 6);
        assert!(commands.len() == 1 && commands[0].contains(&cmd), "{name} {cmd}: {e}");
        assert!(axes.is_empty(), "{name} {cmd}: an instrument axis named beside it: {e}");
    }
}

#[test]
fn an_instrument_axis_scaled_beside_a_command_column_is_still_named() {
    let dir = tempfile::tempdir().unwrap();
    let clean = simulated(dir.path(), "ur5e-dh", 5);
    let cmd = column_scaled(&clean, "cmd.csv", 8, 1.02);
    let both = column_scaled(&cmd, "both.csv", 5, 1.005);
    let (code, e) = calibrate(dir.path(), "ur5e-dh", &both);
    assert_eq!(code, 0, "{e}");
    let (commands, axes) = named(&e);
    assert!(commands.iter().any(|l| l.contains("`cmd_2`")), "{e}");
    assert!(axes.len() == 1 && axes[0].contains("`y_mm`"), "{e}");
}
