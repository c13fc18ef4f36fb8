//! The eleventh hostile run's two slips at once with one kept silent (SB5): a free-pose file
//! with two command columns scaled (`cmd_4` x 0.995 and `cmd_6` x 1.006 on a UR5e's free poses)
//! said one joint's slope as a note (a doubt: the gear or the column) and nothing of the other.
//! Now, once a joint's slope is said, the poses are calibrated again with its column undone by
//! that slope and the transmission test runs on them, as `validate`'s two-slip search refits with
//! the first slip undone: a second column it then names is said, and where it names none the
//! note says that the test ran and the scale it would have named.

use crate::common::altered_csv;
use crate::common::hostile::{case, stderr_of_case};
use crate::hostile_round11d::{robot, simulated};

/// Field `i` (0-based, of `experiment, moved_joint, step, target, x_mm, y_mm, z_mm, cmd_1, ..`)
/// of a row `f`, multiplied by `factor`.
fn scale(f: &mut [String], i: usize, factor: f64) {
    f[i] = (f[i].parse::<f64>().unwrap() * factor).to_string();
}

#[test]
fn a_second_command_scale_is_tested_with_the_first_joints_slope_undone() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    simulated(d, "ur5e-dh", 60, 404, "src.csv");
    // The free poses only (the validation poses), `cmd_4` x 0.995 and `cmd_6` x 1.006.
    altered_csv(
        &d.join("src.csv"),
        "two.csv",
        |f| f[1] == "0",
        |f| {
            scale(f, 7 + 3, 0.995);
            scale(f, 7 + 5, 1.006);
        },
    );
    let e = stderr_of_case(
        d,
        &case(
            "UR5e free poses, cmd_4 x0.995 and cmd_6 x1.006 (run 11 SB5: one joint's slope a note, the other unsaid)",
            &format!("calibrate two.csv {} --out out", robot("ur5e-dh")),
            0,
            &[
                "joint 4 (free poses) turns 1.00",
                "with `cmd_4` divided by 0.99",
                "the poses were calibrated again and the transmission test run on them",
            ],
        ),
    );
    assert!(
        e.contains("it names no other command column (a scale within the file's detection limits")
            || e.contains("a second column shows"),
        "the second test's outcome said: {e}"
    );
}
