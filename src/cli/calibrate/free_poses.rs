//! `axiscal calibrate` on a file of free poses only: the free-pose calibration
//! ([`axiscal::calibration::free_pose`]) and its console summary.

use super::Said;
use crate::cli::printer::Printer;
use anyhow::Result;
use axiscal::calibration::free_pose::block::{BlockShift, block_shift};
use axiscal::calibration::free_pose::poses::{configurations, minimal_geometry_parameters};
use axiscal::calibration::free_pose::slip::{
    ExplainingSlip, SLIP_FALSE_ALARM, explaining_slip, mirrored_targets, tool_turn_deg,
};
use axiscal::calibration::free_pose::{
    FreePoseError, FreePoseOptions, FreePoseSummary, NamedScale, calibrate_free_poses,
};
use axiscal::calibration::noise::NOISE_CONFIDENCE;
use axiscal::calibration::procedure::Calibration;
use axiscal::calibration::recalibrated::{
    FreePoseChecks, FreePoseScales, FreePoseShift, SecondCommandScale, free_pose_scale_checks,
};
use axiscal::calibration::record::CalibrationRecord;
use axiscal::measurement::MeasurementSet;
use axiscal::measurement::target_ids::{SwappedTargetIds, swapped_target_ids};
use axiscal::numerics::stats::chi_square_quantile;
use axiscal::robot::RobotDescription;
use std::path::Path;

/// The options of `calibrate` the free-pose path reads.
pub struct FreeArgs<'a> {
    /// The data file (messages).
    pub data: &'a Path,
    /// `--holdout`.
    pub holdout: bool,
    /// `--keep-outliers`.
    pub keep_outliers: bool,
    /// `--harmonics`.
    pub harmonics: usize,
    /// `--effects auto`.
    pub effects: bool,
    /// `--free-poses`: every row a free pose.
    pub all_rows: bool,
    /// `--refine` (refused: the free poses are the calibration's own data).
    pub refine: bool,
    /// `--max-poses`.
    pub max_poses: usize,
}

/// The free-pose calibration of `set`, its summary beside it.
pub fn calibrate(
    args: &FreeArgs<'_>,
    set: &MeasurementSet,
    desc: &RobotDescription,
    printer: Printer,
) -> Result<CalibrationRecord> {
    if args.refine {
        anyhow::bail!(
            "--refine refines an independent-axis calibration on free poses; {} has free poses only, which calibrate directly (drop --refine)",
            args.data.display()
        );
    }
    if args.all_rows
        && set.experiments().iter().any(|e| e.moved_joint > 0)
        && let Some(why_not) = axiscal::calibration::free_pose::poses::why_sweeps_are_not_poses(set, desc)
    {
        anyhow::bail!(
            "{}: --free-poses fits every row as a free pose, whose targets ride on the last link; the file's \
             sweeps measure other points: {why_not}; drop --free-poses to calibrate its axis experiments",
            args.data.display()
        );
    }
    let options = free_pose_options(args);
    let mut cal = calibrate_free_poses(set, desc, &options).map_err(|e| failure(e, args, (set, desc), &options))?;
    if args.all_rows && set.experiments().iter().any(|e| e.moved_joint > 0) {
        cal.summary.axis_rows_as_poses = Some("`--free-poses` asked for it".into());
    }
    let block = block_shift(set, desc, &options, &cal);
    let (cal, summary) = cal.into_calibration(desc);
    let mut said = Said::default();
    warn_few_degrees_of_freedom(args.data, &cal, &summary, &mut said);
    if let Some(words) = summary.predicts_no_better_than_nominal() {
        said.warn(format!(
            "{}: the calibrated model predicts {words}: it explains nothing the description does not, \
             and has fitted something no robot parameter is (a column's units, scale or sign; a block of poses \
             moved; target ids swapped; an effect it lacks): calibration.json is wrong for the robot; check the \
             columns the notes below name, or none named, each column against the controller at two poses",
            args.data.display()
        ));
    }
    warn_slips(
        args,
        (set, desc),
        &options,
        (&cal, &summary),
        block.as_ref(),
        (printer, &mut said),
    );
    let mut record = CalibrationRecord::new(cal);
    record.reports.free_poses = Some(summary);
    record.reports.warnings = said.into_warnings();
    Ok(record)
}

/// The free-pose fit's options from the command's arguments.
fn free_pose_options(args: &FreeArgs<'_>) -> FreePoseOptions {
    FreePoseOptions {
        keep_outliers: args.keep_outliers,
        holdout: args.holdout,
        max_harmonic_order: args.harmonics,
        all_rows: args.all_rows,
        effects: args.effects,
        max_poses: args.max_poses,
    }
}

/// The block of consecutive poses the free-pose calibration of `set` finds shifted off the
/// others ([`block_shift`]), computed without a word on the console; `None` when it finds
/// none or the calibration fails.
pub(super) fn quietly_shifted_block(
    args: &FreeArgs<'_>,
    set: &MeasurementSet,
    desc: &RobotDescription,
) -> Option<BlockShift> {
    let options = free_pose_options(args);
    let cal = calibrate_free_poses(set, desc, &options).ok()?;
    block_shift(set, desc, &options, &cal)
}

/// A failed free-pose calibration in words: its cause in the data when one is found (few
/// configurations, a column slip, target ids swapped), else the fit's own.
fn failure(
    e: FreePoseError,
    args: &FreeArgs<'_>,
    (set, desc): (&MeasurementSet, &RobotDescription),
    options: &FreePoseOptions,
) -> anyhow::Error {
    let data = args.data.display();
    // Few configurations leave the model free, whatever else the fit's failure suggests.
    if let Some(few) = few_configurations(set, minimal_parameters(desc), args.all_rows) {
        return anyhow::anyhow!(
            "calibrating {data} from its free poses: {few}; the fit fails ({})",
            first_clause(&e.to_string())
        );
    }
    if !matches!(e, FreePoseError::Absurd { .. } | FreePoseError::TooManyOutliers { .. }) {
        return anyhow::anyhow!("calibrating {data} from its free poses: {e}");
    }
    if let Some(s) = explaining_slip(set, desc, options, None) {
        return anyhow::anyhow!(
            "calibrating {data} from its free poses: {}; the fit fails ({})",
            slip_words(&s),
            first_clause(&e.to_string())
        );
    }
    match swapped_target_ids(set, &desc.tool.targets_mm).first() {
        Some(found) => anyhow::anyhow!(
            "calibrating {data} from its free poses{}; the fit fails ({})",
            target_ids_words(found, None, desc),
            first_clause(&e.to_string())
        ),
        None => anyhow::anyhow!("calibrating {data} from its free poses: {e}"),
    }
}

/// The console summary of a free-pose calibration.
pub fn print(s: &FreePoseSummary, desc: &RobotDescription, set: &MeasurementSet, data: &Path, printer: Printer) {
    let source = data.display();
    let what = match s.axis_rows_as_poses {
        Some(_) => "every row a free pose",
        None => "no axis experiment",
    };
    say!(
        printer,
        "calibrated {} from {} ({} free poses, {} points; {what}): {} parameters fitted, {} not identified (kept nominal, see report.md)",
        desc.name,
        source,
        s.poses,
        s.points,
        s.parameters.len(),
        s.unidentified.len()
    );
    if s.poses_left_out > 0 {
        say!(
            printer,
            "  fitted {} of the file's {} free poses, evenly spaced through it (`--max-poses`; memory grows with them)",
            s.poses,
            s.poses + s.poses_left_out
        );
    }
    say!(
        printer,
        "  RMS: nominal {:.4} mm (closed-form registration {:.4} mm) -> calibrated {:.4} mm; condition number {:.2e}",
        s.nominal_rms_mm,
        s.closed_form_rms_mm,
        s.calibrated_rms_mm,
        s.condition_number
    );
    if let Some(kept) = s.effects_tried.iter().find(|t| t.chosen) {
        let tried: Vec<String> = s
            .effects_tried
            .iter()
            .map(|t| format!("{} {:.4}", t.effects, t.cross_validated_rms_mm))
            .collect();
        say!(
            printer,
            "  effects in the model: {} ({} parameters), cross-validated RMS mm: {}",
            kept.effects,
            kept.parameters,
            tried.join(", ")
        );
        let parts: Vec<String> = s
            .effect_joints
            .iter()
            .map(|e| match e.sigma {
                Some(sigma) => format!("joint {} {} {:.4} +- {:.4}", e.joint, e.effect, e.rms, sigma),
                None => format!("joint {} {} {:.4} RMS (max {:.4})", e.joint, e.effect, e.rms, e.max),
            })
            .collect();
        if !parts.is_empty() {
            say!(printer, "  by joint (mrad; backlash: half band): {}", parts.join("; "));
        }
        if kept.effects != "none" {
            eprintln!(
                "warning: the model carries {} (calibration.json robot.effects, used by validate and compensate); calibrated.urdf and joint_map.csv hold the geometry only",
                kept.effects
            );
        }
    }
    if s.setups.len() > 1 {
        let labels: Vec<&str> = s.setups.iter().map(|p| p.setup.as_str()).collect();
        say!(
            printer,
            "  {} setups ({}): the base placed in each instrument frame (calibration.json: free_poses.setups)",
            s.setups.len(),
            labels.join(", ")
        );
    }
    if let Some(h) = &s.holdout {
        say!(
            printer,
            "  held out ({} poses, odd configurations): nominal {:.4} mm -> calibrated {:.4} mm RMS (max {:.4} mm)",
            h.heldout_poses,
            h.nominal_rms_mm,
            h.calibrated_rms_mm,
            h.calibrated_max_mm
        );
    }
    if let Some(h) = s.holdout.as_ref().filter(|h| h.unexecutable_poses > 0) {
        eprintln!(
            "warning: the calibrated model cannot execute {} held-out poses (a fitted transmission harmonic extrapolates beyond the fitted range; try --harmonics 0)",
            h.unexecutable_poses
        );
    }
    crate::cli::checks::print_pose_outliers(&s.outliers, set, data, "calibrated");
    if let Some(h) = &s.holdout {
        crate::cli::checks::print_pose_outliers(&h.outliers, set, data, "held out: the held-out RMS taken");
    }
    if s.tool_fit_rms_mm.is_none() {
        say!(
            printer,
            "  tool frame: nominal (the description's tool.targets_mm do not match the data's target ids)"
        );
    }
}

/// Where a [`BlockShift`] lies in the file: `of lines A-B` or `from line A on`.
pub(super) fn block_place(b: &BlockShift) -> String {
    let line = |l: Option<u64>| l.map_or_else(|| "?".to_owned(), |l| l.to_string());
    match b.to_end {
        true => format!("from line {} on", line(b.lines.0)),
        false => format!("of lines {}-{}", line(b.lines.0), line(b.lines.1)),
    }
}

/// A p-value as a block's warning gives it: `= 2.9e-57`, or `< 1e-99`.
pub(in crate::cli) fn p_value_words(p: f64) -> String {
    if p < 1e-99 {
        "< 1e-99".to_owned()
    } else {
        format!("= {p:.1e}")
    }
}

/// A [`BlockShift`] in words: where, by how much, how significant, what it did and the fix.
fn block_words(b: &BlockShift) -> String {
    let place = block_place(b);
    format!(
        "the free poses {place} ({} of the {} fitted) sit about ({:.2}, {:.2}, {:.2}) mm off the others: the calibrated \
         residuals step there in file order (p {} for the most significant of the {} blocks of consecutive poses \
         tried, against a false-alarm rate of {SLIP_FALSE_ALARM} shared by them); the instrument or the robot moved between \
         them (a bump, a re-setup). The free-pose fit took part of it into the geometry and the noise estimate \
         (calibrated RMS {:.3} mm as written, {:.3} mm with those poses moved back), so calibration.json is wrong for \
         the robot: give those rows their own `setup` label (or measure them again) and calibrate again",
        b.poses,
        b.tested,
        b.shift_mm[0],
        b.shift_mm[1],
        b.shift_mm[2],
        p_value_words(b.p_value),
        b.blocks_tried,
        b.written_rms_mm,
        b.undone_rms_mm
    )
}

/// The factor by which the noise estimate's [`NOISE_CONFIDENCE`] interval may reach above the
/// estimate before the prediction resting on it is said to be unreliable: a predicted
/// accuracy that may be more than twice as poor as printed tells the user little.
const NOISE_INTERVAL_FACTOR: f64 = 2.0;

/// The upper end of the noise estimate's two-sided `NOISE_CONFIDENCE` interval over the
/// estimate, for `dof` degrees of freedom: `sqrt(dof / chi2_{alpha/2}(dof))` (`s^2 dof /
/// sigma^2 ~ chi^2(dof)`).
fn noise_upper_factor(dof: f64) -> f64 {
    let alpha = 1.0 - NOISE_CONFIDENCE;
    (dof / chi_square_quantile(alpha / 2.0, dof)).sqrt()
}

/// Warns when the free-pose fit's noise estimate (its residual's sum of squares over
/// `3 points - parameters` degrees of freedom) is so uncertain that the upper end of its
/// [`NOISE_CONFIDENCE`] interval lies beyond [`NOISE_INTERVAL_FACTOR`] times the estimate: every
/// predicted accuracy (the tool 1-sigma, the sigmas, validate's test) scales with it. Says the
/// degrees of freedom, the interval and the poses that would bring it within the factor.
fn warn_few_degrees_of_freedom(data: &Path, cal: &Calibration, s: &FreePoseSummary, said: &mut Said) {
    let parameters = s.parameters.len();
    let dof = (3 * s.points).saturating_sub(parameters);
    let factor = noise_upper_factor(dof as f64);
    if dof > 0 && factor <= NOISE_INTERVAL_FACTOR {
        return;
    }
    let needed = (1..10_000)
        .find(|&d| noise_upper_factor(d as f64) <= NOISE_INTERVAL_FACTOR)
        .unwrap_or(1);
    let per_pose = 3.0 * s.points as f64 / s.poses.max(1) as f64;
    let poses = ((parameters + needed) as f64 / per_pose).ceil() as usize;
    let noise = cal.noise.as_ref().and_then(|n| n.estimate.as_ref());
    let estimate = match noise {
        Some(n) => format!(
            "the noise estimate {:.3} mm (3-D RMS) has the {:.0} % interval {:.3}-{:.3} mm, up to {factor:.1} times itself",
            n.rms_3d_mm,
            100.0 * NOISE_CONFIDENCE,
            n.interval.low_mm,
            n.interval.high_mm
        ),
        None => "no noise estimate is left".to_owned(),
    };
    said.warn(format!(
        "{}: the fit leaves {dof} degrees of freedom ({} points x 3 coordinates - {parameters} parameters fitted, \
         from {} free poses): {estimate}; every predicted accuracy (the tool 1-sigma, the sigmas in calibration.json, \
         validate's test) scales with it, and the model holds near these poses only; measure about {poses} free poses or \
         more across the workspace ({needed} degrees of freedom bring the interval's upper end within {NOISE_INTERVAL_FACTOR} \
         times the estimate)",
        data.display(),
        s.points,
        s.poses
    ));
}

/// The error's first clause (before its advice): "the calibrated model misses the points by ...".
fn first_clause(e: &str) -> &str {
    e.split(": the description").next().unwrap_or(e)
}

/// A column slip in words: the misfits and the fix.
fn slip_words(s: &ExplainingSlip) -> String {
    let fix = match s.field.as_str() {
        "setup" => "give those rows their own `setup` label (or measure them again)".to_owned(),
        field => format!("fix `{field}`"),
    };
    format!(
        "{}: the description's nominal model placed on the poses misses them by {:.3} mm RMS as written and by {:.3} mm \
         with that undone ({fix} and calibrate again)",
        s.claim, s.written_rms_mm, s.undone_rms_mm
    )
}

/// The warnings of a free-pose calibration the fit absorbed (module docs of
/// [`axiscal::calibration::free_pose::slip`]): a column slip; else tool target ids in another
/// order, by their distances ([`swapped_target_ids`]) or, for a symmetric set, by the fitted
/// tool frame's turn ([`mirrored_targets`]); and, without a column slip, the scale tests
/// ([`free_pose_scale_checks`]).
fn warn_slips(
    args: &FreeArgs<'_>,
    (set, desc): (&MeasurementSet, &RobotDescription),
    options: &FreePoseOptions,
    (cal, summary): (&Calibration, &FreePoseSummary),
    block: Option<&BlockShift>,
    (printer, said): (Printer, &mut Said),
) {
    let data = args.data.display();
    // Sweeps fitted as free poses (at their own configurations) count every row as a pose.
    let all_rows = summary.axis_rows_as_poses.is_some();
    if let Some(few) = few_configurations(set, Parameters(summary.parameters.len(), "parameters fitted"), all_rows) {
        // Repeated configurations determine no slip either: the search would name chance ones.
        said.warn(format!("{data}: {few}"));
        return;
    }
    match free_pose_scale_checks((set, desc), options, (cal, summary), block) {
        FreePoseChecks::Shift(FreePoseShift::Slip(s)) => said.warn(format!(
            "{data}: {}; the free-pose fit absorbed it into the geometry, so calibration.json is wrong for the robot",
            slip_words(&s)
        )),
        FreePoseChecks::Shift(FreePoseShift::Block(b)) => said.warn(format!("{data}: {}", block_words(&b))),
        FreePoseChecks::Scales(found) => {
            print_scales(&found, (set, &summary.scales), args.data, (printer, &mut *said));
            warn_target_ids(set, desc, summary, &data.to_string(), said);
        }
    }
}

/// The free-pose scale tests' findings ([`FreePoseScales`]) on `set` in words, after the
/// column scales the screen `named`: each test run with those undone says so.
fn print_scales(
    found: &FreePoseScales,
    (set, named): (&MeasurementSet, &[NamedScale]),
    data: &Path,
    (printer, said): (Printer, &mut Said),
) {
    let shown = data.display();
    for n in named {
        said.warn(format!("{shown}: {}", named_scale_words(n)));
    }
    let prefix = found
        .undone
        .as_ref()
        .map_or_else(String::new, |_| format!("{}: ", undone_words(named)));
    for s in &found.scaled {
        match s.free_pose_note() {
            Some(note) => eprintln!("note: {shown}: {prefix}{note}"),
            None => said.warn(format!("{shown}: {prefix}{s}")),
        }
    }
    for doubt in &found.doubts {
        eprintln!("note: {shown}: {prefix}{doubt}");
    }
    if let Some(second) = &found.second {
        print_second_scales(&second.said, &second.found, data, said);
    }
    if let Some(profile) = &found.profile {
        super::print_coordinate_scale(profile, set, data, (printer, said));
    }
    // The columns said above are named; the line bounds the others.
    if let Some(reach) = &found.reach {
        eprintln!("note: {shown}: {prefix}{reach}");
    }
}

/// The target ids swapped between rows, or mirrored as a whole against the description's
/// `[tool] targets_mm`, as warnings naming `data`.
fn warn_target_ids(
    set: &MeasurementSet,
    desc: &RobotDescription,
    summary: &FreePoseSummary,
    data: &str,
    said: &mut Said,
) {
    let swapped = swapped_target_ids(set, &desc.tool.targets_mm);
    for found in &swapped {
        said.warn(format!("{data}{}", target_ids_words(found, Some(summary), desc)));
    }
    if swapped.is_empty()
        && let Some(m) = mirrored_targets(summary, desc)
    {
        let moved: Vec<String> = m
            .ids
            .iter()
            .zip(&m.order)
            .filter(|(a, b)| a != b)
            .map(|(a, b)| format!("{a} is {b}"))
            .collect();
        said.warn(format!(
            "{data}: the tool frame fitted to the description's `[tool] targets_mm` turns {:.1} deg from the \
             description's, and {:.1} deg with the target ids read as {}: the targets' distances are symmetric, and the ids \
             are the mirror image of the description's (fix the `target` column and calibrate again)",
            m.written_deg,
            m.reordered_deg,
            moved.join(", ")
        ));
    }
}

/// The column scales `named` undone, in words (`with `x_mm` divided by 1.02510 (the scale
/// named above) the poses were calibrated again`).
fn undone_words(named: &[NamedScale]) -> String {
    let columns: Vec<String> = named
        .iter()
        .map(|n| format!("`{}` divided by {:.5}", n.scale.column, n.scale.factor))
        .collect();
    let scales = if named.len() == 1 { "the scale" } else { "the scales" };
    format!(
        "with {} ({scales} named above) the poses were calibrated again",
        columns.join(" and ")
    )
}

/// A column scale the free-pose fit named before screening the poses
/// ([`axiscal::calibration::free_pose::NamedScale`]), in words.
fn named_scale_words(n: &axiscal::calibration::free_pose::NamedScale) -> String {
    let reads = |c: &axiscal::calibration::free_pose::ColumnScale| {
        let what = if c.column.starts_with("cmd_") { "holds" } else { "reads" };
        format!(
            "`{}` {what} {:.5} (+- {:.5}) times what the model fits",
            c.column, c.factor, c.sigma
        )
    };
    let alike = match n.alike.as_slice() {
        [] => String::new(),
        others => {
            let words: Vec<String> = others.iter().map(reads).collect();
            format!(
                " (or, alike for these data, {}: their patterns over these poses are nearly the same, and the data cannot tell them apart)",
                words.join("; or ")
            )
        }
    };
    format!(
        "a column scale explains the poses' residuals: {}, {:.1} times its sigma over {} configurations{} (family-wise p {:.1e} over \
         the command and coordinate columns){alike}; the geometric fit misses the points by {:.4} mm RMS per coordinate as read and \
         by {:.4} mm with it undone. The outlier screen ran with it undone; calibration.json has absorbed it into the geometry: \
         check the column{} (the export's units or ratio, the instrument's axis scale) and calibrate the corrected file again",
        reads(&n.scale),
        n.t,
        n.configurations,
        if n.scale.column.starts_with("cmd_") {
            ", counting what a drive departs by (0.12 %: over a partial turn a gear's once-per-turn error reads as a scale)"
        } else {
            ""
        },
        n.p_value,
        n.rms_mm[0],
        n.rms_mm[1],
        if n.alike.is_empty() { "" } else { "s named" },
    )
}

/// The command columns the transmission test named with the joints `said` (`(joint, slope)`,
/// as a warning or a note) undone ([`axiscal::calibration::recalibrated::second_command_scales`]);
/// where it named none, that the test ran.
fn print_second_scales(undone: &[(usize, f64)], second: &[SecondCommandScale], data: &Path, said: &mut Said) {
    let columns: Vec<String> = undone
        .iter()
        .map(|(j, slope)| format!("`cmd_{j}` divided by {:.4}", 1.0 / slope))
        .collect();
    let undone_words = format!(
        "with {} (as said above) the poses were calibrated again and the transmission test run on them",
        columns.join(" and ")
    );
    let data = data.display();
    if second.is_empty() {
        eprintln!(
            "note: {data}: {undone_words}: it names no other command column (a scale within the file's \
             detection limits, the line on command-column scales, passes: over a partial turn it reads as a \
             gear's once-per-turn error)"
        );
    }
    for found in second {
        let (firm, text) = match found {
            SecondCommandScale::Slip(s) => s.free_pose_note().map_or((true, s.to_string()), |n| (false, n)),
            SecondCommandScale::Doubt(d) => (false, d.to_string()),
        };
        let words = format!("{data}: {undone_words}, and a second column shows: {text}");
        match firm {
            true => said.warn(words),
            false => eprintln!("note: {words}"),
        }
    }
}

/// A count of parameters and what they are, in words.
struct Parameters(usize, &'static str);

/// The geometry's minimal parameters ([`minimal_geometry_parameters`]), in words.
fn minimal_parameters(desc: &RobotDescription) -> Parameters {
    Parameters(
        minimal_geometry_parameters(desc),
        "parameters of the robot's geometry and placement (4 per turning joint, 2 per sliding one, 6 for the base)",
    )
}

/// [`few_configurations`] of the free poses of `set` against the geometry's minimal parameter
/// count ([`minimal_parameters`]).
pub(super) fn few_configurations_of(set: &MeasurementSet, desc: &RobotDescription, all_rows: bool) -> Option<String> {
    few_configurations(set, minimal_parameters(desc), all_rows)
}

/// The free poses' distinct configurations ([`configurations`]) in words, when they give fewer
/// independent values than the `fitted` parameters: repeated measurements of a few
/// configurations add noise averaging, no geometry, and the covariance then holds at those
/// configurations only. With `all_rows`, every row counts as a pose (the sweeps fitted as free
/// poses).
fn few_configurations(set: &MeasurementSet, Parameters(fitted, what): Parameters, all_rows: bool) -> Option<String> {
    let c = configurations(set, all_rows);
    (c.values < fitted).then(|| {
        format!(
            "its {} free poses stand at {} distinct configurations (commands), which give at most {} independent \
             values for the {fitted} {what}: repeated poses add no geometry, and the predicted accuracy holds \
             near those configurations only; measure the robot at more configurations across its workspace",
            c.poses, c.distinct, c.values
        )
    })
}

/// A [`SwappedTargetIds`] in words (after the file name): where, which order (the one whose
/// tool frame fitted in `summary` turns least, when the fit saw these ids in every pose) and
/// the fix.
fn target_ids_words(found: &SwappedTargetIds, summary: Option<&FreePoseSummary>, desc: &RobotDescription) -> String {
    let every = found.poses == found.tested;
    let orders: Vec<&Vec<usize>> = match summary.filter(|_| every) {
        Some(summary) => {
            let turns: Vec<Option<f64>> = found.orders.iter().map(|o| tool_turn_deg(summary, desc, o)).collect();
            match turns
                .iter()
                .enumerate()
                .filter_map(|(i, t)| Some((i, (*t)?)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
            {
                Some((i, _)) => vec![&found.orders[i]],
                None => found.orders.iter().collect(),
            }
        }
        None => found.orders.iter().collect(),
    };
    let read: Vec<String> = orders.iter().map(|o| format!("({})", found.moved(o))).collect();
    let lines: Vec<String> = found.lines.iter().take(10).map(u64::to_string).collect();
    let where_ = match every {
        true => format!(": in every one of its {} free poses", found.tested),
        false => format!(
            ": lines {}{} ({} of its {} free poses)",
            lines.join(", "),
            if found.lines.len() > lines.len() { ", ..." } else { "" },
            found.poses,
            found.tested
        ),
    };
    format!(
        "{where_}: the tool targets' mutual distances miss the description's `[tool] targets_mm` (noise {:.3} mm a distance) \
         and match them with the target ids read as {}: the `target` column (or the marker columns) is in another order; \
         the free-pose fit takes each id for one point on the tool (fix the ids and calibrate again)",
        found.sigma_mm,
        read.join(" or, mirrored, ")
    )
}
