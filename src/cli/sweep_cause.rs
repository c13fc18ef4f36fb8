//! The words `calibrate` says of a sweep whose records, corrected, let the calibration fit the
//! file's own validation poses ([`axiscal::diagnosis::sweep_cause_of_misses`]): a held
//! command off through the sweep, the sweep's points drifting, or the whole file's.

use axiscal::diagnosis::{SWEEP_CAUSE_FALSE_ALARM, SweepCause, SweepFault, SweepShadow};

/// `(x, y, z)` with three decimals.
fn triple(v: &[f64; 3]) -> String {
    format!("({:.3}, {:.3}, {:.3})", v[0], v[1], v[2])
}

/// The directions along which a move changes nothing the validation poses show, after a move
/// given across them: empty where there are none.
fn free_words(free_along: &[[f64; 3]]) -> String {
    let directions: Vec<String> = free_along.iter().map(triple).collect();
    match directions.len() {
        0 => String::new(),
        1 => format!(" plus any amount along {}", directions[0]),
        _ => format!(" plus any amount in the span of {}", directions.join(" and ")),
    }
}

/// A 1-sigma with three decimals, or `undetermined` where it is infinite (the poses do not
/// show the correction).
fn one_sigma(sigma: f64) -> String {
    match sigma.is_finite() {
        true => format!("{sigma:.3}"),
        false => "undetermined".to_string(),
    }
}

/// What the records look off by, as said in a sentence (`whole`: the whole file's drift).
fn fault_words(fault: &SweepFault, whole: bool) -> String {
    match fault {
        SweepFault::HeldOffset {
            joint,
            offset,
            sigma,
            unit,
        } => format!(
            "the held `cmd_{joint}` looks offset by {offset:+.3} {unit} (1-sigma {}) from where the robot stood",
            one_sigma(*sigma)
        ),
        SweepFault::Drift {
            drift_mm,
            sigma_mm,
            free_along,
        } => format!(
            "its points look to drift by {} mm (1-sigma {} mm){} from its first {} to its last{}",
            triple(drift_mm),
            triple(sigma_mm),
            free_words(free_along),
            if whole { "row" } else { "step" },
            shown_words(free_along, "a drift"),
        ),
        SweepFault::Block {
            moved_mm,
            sigma_mm,
            free_along,
        } => format!(
            "its block looks moved by {} mm (1-sigma {} mm){}{}",
            triple(moved_mm),
            triple(sigma_mm),
            free_words(free_along),
            shown_words(free_along, "a block moved"),
        ),
    }
}

/// Why a move (`what`: `a block moved`, `a drift`) is given across some directions: empty
/// where it has none.
fn shown_words(free_along: &[[f64; 3]], what: &str) -> String {
    match free_along.is_empty() {
        true => String::new(),
        false => format!(
            " (these poses do not show a move along it: {what} along the axis its sweep turns about leaves that axis \
             where it is)"
        ),
    }
}

/// The correction that undoes `fault`, as said after "recalibrated with".
fn undone_words(fault: &SweepFault) -> String {
    match fault {
        SweepFault::HeldOffset {
            joint, offset, unit, ..
        } => {
            format!("`cmd_{joint}` in these rows moved by {:+.3} {unit}", -offset)
        }
        SweepFault::Drift { .. } => "that drift undone (each point moved back by its share of it)".to_string(),
        SweepFault::Block { .. } => "that move undone".to_string(),
    }
}

/// The records' owner: `experiment E` or `the whole file`.
fn owner(experiment: &Option<String>) -> String {
    experiment
        .as_ref()
        .map_or("the whole file".to_string(), |e| format!("experiment {e}"))
}

/// An alternative, after "or".
fn alternative_words((experiment, fault): &(Option<String>, SweepFault)) -> String {
    let who = owner(experiment);
    match fault {
        SweepFault::HeldOffset {
            joint, offset, unit, ..
        } => format!(", or the held `cmd_{joint}` of {who} by {offset:+.3} {unit}"),
        SweepFault::Drift {
            drift_mm, free_along, ..
        } => {
            format!(
                ", or {who}'s points drifting by {} mm{}",
                triple(drift_mm),
                free_words(free_along)
            )
        }
        SweepFault::Block {
            moved_mm, free_along, ..
        } => {
            format!(
                ", or {who}'s block moved by {} mm{}",
                triple(moved_mm),
                free_words(free_along)
            )
        }
    }
}

/// The clause for the miss's cause where the correction explains a part of it
/// ([`SweepCause::passes`] false), for the file `data` (its name).
pub(super) fn part_words(cause: &SweepCause, data: &str) -> String {
    let lines = cause
        .lines
        .map_or(String::new(), |(a, b)| format!(" ({data} lines {a}-{b})"));
    let check = match cause.fault {
        SweepFault::HeldOffset { joint, .. } => format!("check `cmd_{joint}` in these rows against the controller"),
        SweepFault::Drift { .. } | SweepFault::Block { .. } => {
            "check whether the instrument or the robot moved while these rows were measured".to_string()
        }
    };
    format!(
        "in {}{lines} {}: recalibrated with {} the model misses the poses by {:.3} mm RMS (chi2/dof {:.2}), a gain \
         beyond chance among the {} corrections of held commands and drifts tried (an F test at \
         {SWEEP_CAUSE_FALSE_ALARM:e}) though not within their test: {check}, and another cause besides: ",
        owner(&cause.experiment),
        fault_words(&cause.fault, cause.experiment.is_none()),
        undone_words(&cause.fault),
        cause.rms_mm.1,
        cause.per_dof.1,
        cause.tried,
    )
}

/// The clause naming how the reference-pose test reads the sweep, where the drift or the moved
/// block found there (`fault`) fits the poses best (`calibrate` then leaves out that test's own
/// warning of the sweep).
fn shadow_words(shadow: &Option<SweepShadow>, fault: &SweepFault) -> String {
    let named = match shadow {
        None => return String::new(),
        Some(SweepShadow::HeldOffset(joints)) => {
            let held: Vec<String> = joints.iter().map(|k| format!("`cmd_{k}`")).collect();
            format!("an offset of the held {}", held.join(" or "))
        }
        Some(SweepShadow::MovedBlock) => "a move of its block".to_string(),
    };
    let (found, which) = match fault {
        SweepFault::Block { .. } => ("a move of its block", "move"),
        _ => ("a drift through the sweep", "drift"),
    };
    format!(
        " (the reference-pose test, which compares the sweeps where each passes the pose with every joint at its held \
         value, reads this sweep as {named}: {found} moves its point there as that does, and over the validation poses \
         the {which} fits best)"
    )
}

/// Why the sweeps did not show the fault, and what to do.
fn why_words(fault: &SweepFault, whole: bool) -> String {
    match fault {
        SweepFault::HeldOffset { joint: j, .. } => format!(
            "the sweep's own axis fit takes such an offset in as a turn of its axis about joint {j}'s, which the sweeps \
             alone do not show: a value typed wrong for this experiment, or the joint re-mastered between the sweeps (or \
             the sweep's block moved between the sweeps, the instrument or the robot bumped, which moves its points much \
             alike where joint {j}'s axis is far from them); calibration.json is wrong for the robot: check `cmd_{j}` in \
             these rows against the controller, or measure the sweep again"
        ),
        SweepFault::Drift { .. } if whole => "each sweep's own axis fit takes its share of a slow drift in as a tilt or \
             shift of its axis, which the sweeps alone do not show: the instrument creeping through the campaign (warming \
             up, a settling stand or base); calibration.json is wrong for the robot: measure again once the instrument \
             and the robot have settled, with a reference point measured at intervals to show a drift"
            .to_string(),
        SweepFault::Drift { .. } => "the sweep's own axis fit takes a slow drift in as a tilt or shift of its axis, \
             which the sweeps alone do not show: the instrument or the robot's base creeping while the sweep ran \
             (warming up, a settling mount or stand); calibration.json is wrong for the robot: measure the sweep again \
             once the instrument and the robot have settled"
            .to_string(),
        SweepFault::Block { .. } => "the instrument or the robot bumped between the sweeps; calibration.json is wrong \
             for the robot: measure the sweep again"
            .to_string(),
    }
}

/// The warning, for the file `data` (its name) with `poses` validation poses.
pub(super) fn words(cause: &SweepCause, data: &str, poses: usize) -> String {
    let place = cause.lines.map_or(data.to_string(), |(l, _)| format!("{data}:{l}"));
    let lines = cause.lines.map_or(String::new(), |(a, b)| format!(" (lines {a}-{b})"));
    let or: String = cause.alternatives.iter().map(alternative_words).collect();
    let whole = cause.experiment.is_none();
    format!(
        "{place}: {}{lines}: {}{or}{}: the calibrated model misses this file's own {poses} validation poses (not \
         fitted) by {:.3} mm RMS (chi2/dof {:.2}), and recalibrated with {} it fits them (RMS {:.3} mm, chi2/dof \
         {:.2}); {}",
        owner(&cause.experiment),
        fault_words(&cause.fault, whole),
        shadow_words(&cause.shadows, &cause.fault),
        cause.rms_mm.0,
        cause.per_dof.0,
        undone_words(&cause.fault),
        cause.rms_mm.1,
        cause.per_dof.1,
        why_words(&cause.fault, whole),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_move_is_given_across_the_directions_the_poses_do_not_show_with_them() {
        let block = SweepFault::Block {
            moved_mm: [0.5124, -0.25, 0.0],
            sigma_mm: [0.0101, 0.02, 0.0],
            free_along: vec![[0.0, 0.0, 1.0]],
        };
        assert_eq!(
            fault_words(&block, false),
            "its block looks moved by (0.512, -0.250, 0.000) mm (1-sigma (0.010, 0.020, 0.000) mm) plus any amount \
             along (0.000, 0.000, 1.000) (these poses do not show a move along it: a block moved along the axis its \
             sweep turns about leaves that axis where it is)"
        );
        let alternative = alternative_words(&(Some("axis2".into()), block));
        assert_eq!(
            alternative,
            ", or experiment axis2's block moved by (0.512, -0.250, 0.000) mm plus any amount along (0.000, 0.000, 1.000)"
        );
        let held = SweepFault::HeldOffset {
            joint: 2,
            offset: 0.25,
            sigma: f64::INFINITY,
            unit: "deg",
        };
        assert!(fault_words(&held, false).contains("(1-sigma undetermined)"));
        let drift = SweepFault::Drift {
            drift_mm: [1.0, 2.0, 3.0],
            sigma_mm: [0.1, 0.2, 0.3],
            free_along: Vec::new(),
        };
        assert_eq!(
            fault_words(&drift, true),
            "its points look to drift by (1.000, 2.000, 3.000) mm (1-sigma (0.100, 0.200, 0.300) mm) from its first row to its last"
        );
    }
}
