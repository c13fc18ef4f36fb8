//! The sanity checks' findings on an axis-experiment calibration, as warnings and notes:
//! implausible results, command-column scale doubts, sweeps out of place at the reference pose.

use super::Args;
use super::own_poses::OwnPosesWarning;
use crate::cli::checks;
use axiscal::calibration::procedure::{AxisEstimator, Calibration, Implausible, ScaleSlip, tool_spacing_scale};
use axiscal::measurement::{Measurement, MeasurementSet};
use axiscal::plan::TOOL_EXPERIMENT;
use axiscal::robot::RobotDescription;
use std::path::Path;

/// The file lines of the tool rows a [`Implausible::ToolMisfit`] is about (` (FILE lines
/// 3, 4, 5)`), empty for any other finding.
pub(super) fn tool_rows(found: &Implausible, set: &MeasurementSet, data: &Path) -> String {
    let Implausible::ToolMisfit { experiment, step, .. } = found else {
        return String::new();
    };
    let lines: Vec<String> = set
        .rows()
        .iter()
        .enumerate()
        .filter(|(_, m)| m.experiment == *experiment && m.step == *step)
        .filter_map(|(i, _)| set.line_of(i).map(|l| l.to_string()))
        .collect();
    if lines.is_empty() {
        return String::new();
    }
    format!(" ({} lines {})", data.display(), lines.join(", "))
}

/// For a [`Implausible::ToolMisfit`]: the scale the measured tool targets' spacings read
/// ([`tool_spacing_scale`]), in words, when one brings them all within their noise.
fn spacing_scale_words(found: &Implausible, set: &MeasurementSet, desc: &RobotDescription) -> String {
    let Implausible::ToolMisfit {
        experiment,
        step,
        noise_mm,
        ..
    } = found
    else {
        return String::new();
    };
    let measured: Vec<(usize, [f64; 3])> = set
        .rows()
        .iter()
        .filter(|m| m.experiment == *experiment && m.step == *step)
        .map(|m| (m.target, m.position_mm))
        .collect();
    let Some(s) = tool_spacing_scale(&measured, &desc.tool.targets_mm, *noise_mm) else {
        return String::new();
    };
    format!(
        "; the measured targets are {:.4} times as far apart as `[tool] targets_mm` (+- {:.4}), and with \
         that factor every spacing agrees within {:.3} mm: the coordinates are scaled (another unit, an instrument's \
         scale setting: check a known length) or `[tool] targets_mm` are drawn at another scale, rather than a point off",
        s.scale, s.sigma, s.worst_mm
    )
}

/// A joint's misfit with the file lines of the sweep that carries it (its first and last, and
/// its worst point's), from `set`.
pub(super) fn with_sweep_lines(mut found: Implausible, set: &MeasurementSet) -> Implausible {
    if let Implausible::Misfit { sweep: Some(s), .. } = &mut found {
        let lines: Vec<(u64, &Measurement)> = set
            .rows()
            .iter()
            .enumerate()
            .filter(|(_, m)| m.experiment == s.experiment)
            .filter_map(|(i, m)| set.line_of(i).map(|l| (l, m)))
            .collect();
        s.lines = lines.first().zip(lines.last()).map(|(a, b)| (a.0, b.0));
        s.worst_line = lines
            .iter()
            .find(|(_, m)| m.step == s.worst.0 && m.target == 0)
            .map(|(l, _)| *l);
    }
    found
}

/// The sanity checks' findings ([`axiscal::calibration::procedure::implausible`]) as warnings'
/// words, with the file lines they are about; a size off by a factor says that the
/// description, not only the coordinates, may be at fault when the data do not record this
/// very description ([`checks::description_suspect`]).
pub(super) fn implausible_warnings(
    found: &[Implausible],
    desc: &RobotDescription,
    set: &MeasurementSet,
    args: &Args,
) -> Vec<String> {
    found
        .iter()
        .map(|f| {
            let f = &with_sweep_lines(f.clone(), set);
            let rows = tool_rows(f, set, &args.data) + &spacing_scale_words(f, set, desc);
            let suspect = match f {
                Implausible::Size { .. } => {
                    let recorded = checks::data_identity(&args.data).ok().flatten();
                    checks::description_suspect(desc, &args.robot, recorded.as_ref())
                }
                _ => None,
            };
            match suspect {
                Some(s) => format!("{f}{rows}; {s}"),
                None => format!("{f}{rows}"),
            }
        })
        .collect()
}

/// The joints whose slope a gear's once-per-turn error and a scaled command column explain
/// alike ([`axiscal::calibration::procedure::scale_doubts`]) as notes; none beside a size or mirror finding, which explains the
/// slopes.
pub(super) fn print_scale_doubts(
    (cal, desc, rows): (&Calibration, &RobotDescription, &[Measurement]),
    found: &[Implausible],
    data: &Path,
) {
    if cal.options.estimator == AxisEstimator::Paper {
        eprintln!(
            "note: {}: the command-column scale test does not run on the paper's estimator: its transmission sigmas \
             (eq. 8, a-posteriori, given the fitted axis) leave out the axis's own error and would name scales a clean \
             file does not have; `--estimator ml` tests every column",
            data.display()
        );
        return;
    }
    if found
        .iter()
        .any(|f| matches!(f, Implausible::Size { .. } | Implausible::Mirrored { .. }))
    {
        return;
    }
    for doubt in axiscal::calibration::procedure::scale_doubts(cal, desc) {
        eprintln!("note: {}: {doubt}", data.display());
    }
    // The columns a warning named are said; the line bounds the others.
    let scaled: Vec<ScaleSlip> = found
        .iter()
        .filter_map(|f| match f {
            Implausible::Scaled(s) => Some(s.clone()),
            _ => None,
        })
        .collect();
    let named = axiscal::calibration::procedure::named_joints(&scaled);
    if let Some(reach) = axiscal::calibration::procedure::scale_reach(cal, desc, rows).and_then(|r| r.without(&named)) {
        eprintln!("note: {}: {reach}", data.display());
    }
}

/// The sweeps out of place among the sightings of their shared target at the reference pose
/// ([`axiscal::calibration::shared_target::moved_sweeps`], at the calibration's noise) as
/// warnings naming the file and the sweep's first line; where none is, the moves the test
/// lets pass ([`axiscal::calibration::shared_target::block_reach`]) as a note, and in a file
/// without validation poses the held joints' offsets it lets pass
/// ([`axiscal::calibration::shared_target::held_reach`]). The warning of a sweep whose drift the
/// file's own validation poses name (`own`: [`OwnPosesWarning::replaces`]) is left to that
/// warning, which says how the test read the sweep.
pub(super) fn print_moved_sweeps(
    cal: &Calibration,
    desc: &RobotDescription,
    set: &MeasurementSet,
    data: &Path,
    own: Option<&OwnPosesWarning>,
) {
    let noise = cal
        .noise
        .as_ref()
        .map_or(cal.options.noise_rms_3d_mm, |n| n.used_rms_3d_mm);
    let moved_sweeps = axiscal::calibration::shared_target::moved_sweeps(set, desc, noise);
    let replaced = own.and_then(|o| o.replaces.as_deref());
    for moved in moved_sweeps.iter().filter(|m| Some(m.experiment.as_str()) != replaced) {
        let place = moved.lines.map_or_else(
            || data.display().to_string(),
            |(l, _)| format!("{}:{l}", data.display()),
        );
        // Out of place by the held joints' backlash only: a note.
        let kind = if moved.backlash.is_empty() { "warning" } else { "note" };
        eprintln!("{kind}: {place}: {moved}");
    }
    if moved_sweeps.is_empty()
        && let Some(reach) = axiscal::calibration::shared_target::block_reach(set, desc, noise)
    {
        eprintln!("note: {}: {reach}", data.display());
    }
    // With validation poses, `misses_own_validation_poses` seeks a held offset the sweeps hide.
    let poses = set
        .rows()
        .iter()
        .any(|m| m.moved_joint == 0 && m.experiment != TOOL_EXPERIMENT);
    if moved_sweeps.is_empty()
        && !poses
        && let Some(reach) = axiscal::calibration::shared_target::held_reach(set, desc, noise)
    {
        eprintln!("note: {}: {reach}", data.display());
    }
}
