//! The checks that calibrate a file again on its data altered: the fits the coordinate-scale
//! profile compares ([`axes_profile_fit`], [`free_pose_profile_fit`]), the instrument axis whose
//! scale explains the joints the transmission test names ([`instrument_axis_source`], a
//! calibration per trial scale), and the data with the sweep screen's named bumps moved back,
//! calibrated ([`calibrated_with_bumps_undone`]); for free poses, the slip or moved block behind
//! the column scales the screen named ([`shift_behind_scales`]) and the poses with those scales
//! undone, calibrated ([`calibrated_with_scales_undone`]); the coordinate-scale profile weighed
//! against the joints' named column, with a second axis behind a named one
//! ([`coordinate_scale`]); a free-pose calibration's scale tests, with the poses calibrated
//! again with each scale said undone ([`free_pose_scale_checks`]). Each calibration is the procedure's own (`procedure::calibrate`, or
//! the free-pose fit); the checks' words are the callers'.

use crate::calibration::free_pose::block::{BlockShift, block_shift};
use crate::calibration::free_pose::slip::{ExplainingSlip, explaining_slip};
use crate::calibration::free_pose::{FreePoseOptions, FreePoseSummary, NamedScale, calibrate_free_poses};
use crate::calibration::noise::NOISE_TEST_LEVEL;
use crate::calibration::procedure::{
    Calibration, CalibrationOptions, ColumnSource, Implausible, Refit, ScaleDoubt, ScaleReach, ScaleSlip, SweepBump,
    bumps_undone, calibrate, column_source, free_pose_scale_doubts, free_pose_scale_reach, free_pose_scale_slips,
    implausible, joint_slopes, named_joints, simulated_sweeps, sweeps_agreement,
};
use crate::kinematics::JointKind;
use crate::measurement::MeasurementSet;
use crate::measurement::unit_check::axis_scale::{
    AxisScale, Fit, NullSpread, PROFILE_MAX_FREE_POSE_ROWS, Scaled, axis_scale, axis_scale_with_column_undone,
    factor_read, null_spread,
};
use crate::robot::RobotDescription;
use rand::SeedableRng;
use rand::rngs::ChaCha12Rng;
use rayon::prelude::*;

/// The axis fits' residuals of `cal` as the coordinate-scale profile reads them: the sum of
/// each axis's squared residual coordinates over the noise estimate's degrees of freedom, and
/// a misfit where the sweeps of the joints fitted from several disagree beyond their own
/// noise ([`sweeps_agreement`] below [`NOISE_TEST_LEVEL`]); `None` without a noise estimate.
pub fn axes_fit(cal: &Calibration) -> Option<Fit> {
    Some(Fit {
        sum_squares_mm2: cal
            .axes
            .iter()
            .map(|a| a.points as f64 * a.residual_rms_mm.powi(2))
            .sum(),
        dof: cal.noise.as_ref()?.estimate.as_ref()?.dof,
        misfits: usize::from(sweeps_agreement(cal).is_some_and(|a| a.p_value < NOISE_TEST_LEVEL)),
    })
}

/// The axis-experiment calibration of `set` with `options`, as the coordinate-scale profile
/// reads it ([`axes_fit`]); `None` where it fails.
pub fn axes_profile_fit(set: &MeasurementSet, desc: &RobotDescription, options: &CalibrationOptions) -> Option<Fit> {
    axes_fit(&calibrate(set, desc, options).ok()?)
}

/// The free-pose calibration of `set` with `options` (no held-out half, no effects: the
/// profile compares geometries), as the coordinate-scale profile reads it: the points' sum of
/// squares over their coordinates less the parameters, and the poses beyond the outlier fence
/// (a pose the model cannot fit stays flagged with a column undone); `None` where it fails.
pub fn free_pose_profile_fit(set: &MeasurementSet, desc: &RobotDescription, options: &FreePoseOptions) -> Option<Fit> {
    let profile = FreePoseOptions {
        holdout: false,
        effects: false,
        ..*options
    };
    let c = calibrate_free_poses(set, desc, &profile).ok()?;
    let points = c.summary.points as f64;
    Some(Fit {
        sum_squares_mm2: points * c.summary.calibrated_rms_mm.powi(2),
        dof: (3 * c.summary.points).saturating_sub(c.summary.parameters.len()),
        misfits: c.summary.outliers.len(),
    })
}

/// The instrument axis whose scale explains the departures of the joints in `slopes` (those
/// the transmission test names, [`command_slopes`]; [`column_source`]), the calibrations re-run
/// on `set` with `options`; `None` where `slopes` is empty.
pub fn instrument_axis_source(
    slopes: &[(usize, f64)],
    (set, desc): (&MeasurementSet, &RobotDescription),
    options: &CalibrationOptions,
) -> Option<ColumnSource> {
    let named: Vec<usize> = slopes.iter().map(|&(joint, _)| joint).collect();
    if named.is_empty() {
        return None;
    }
    let refit = |s: &MeasurementSet| {
        let c = calibrate(s, desc, options).ok()?;
        Some(Refit {
            slopes: joint_slopes(&c, desc),
            fit: axes_fit(&c)?,
        })
    };
    column_source(set, &named, &refit)
}

/// The joints the transmission test names as their command columns scaled in `cal`
/// ([`implausible`]): `(joint, 1-based; how far it travels per command over the description's)`.
pub fn command_slopes(cal: &Calibration, desc: &RobotDescription) -> Vec<(usize, f64)> {
    implausible(cal, desc)
        .iter()
        .filter_map(|f| match f {
            Implausible::Scaled(ScaleSlip::Command { joint, travel, .. }) => Some((*joint, *travel)),
            _ => None,
        })
        .collect()
}

/// `set` (screened) with the sweep screen's `bumps` moved back ([`bumps_undone`]) and its
/// calibration with `options`; `None` when no bump was named or that calibration fails (the
/// checks then read the data as written).
pub fn calibrated_with_bumps_undone(
    set: &MeasurementSet,
    bumps: &[SweepBump],
    desc: &RobotDescription,
    options: &CalibrationOptions,
) -> Option<(MeasurementSet, Calibration)> {
    let undone = bumps_undone(set, bumps)?;
    let cal = calibrate(&undone, desc, options).ok()?;
    Some((undone, cal))
}

/// A column slip or a block of free poses moved ([`explaining_slip`], [`block_shift`]).
#[derive(Clone, Debug)]
pub enum FreePoseShift {
    /// A column slip, or a block found by the nominal model's slip search.
    Slip(ExplainingSlip),
    /// A block found in the calibrated residuals.
    Block(BlockShift),
}

/// The slip ([`explaining_slip`]), else the shifted block (`block`, [`block_shift`] of the
/// calibration as read), the free poses `set` show, unless the column-scale screen named a
/// scale ([`FreePoseSummary::scales`]) that explains it: a scale moves the poses it reaches far
/// (a wrist's command at its extremes, a coordinate far from the centroid) by a pattern the
/// nominal model's slip search and the calibrated residuals' change-point test read as a step
/// in file order where those poses stand together (a KR's `cmd_5` x1.025 read as lines 474-482
/// moved; its `x_mm` x1.025 as the poses from line 780 on). The two explanations are compared
/// by their fit: the poses with the scales undone are calibrated again with the same options;
/// a block or slip whose undoing fits the poses better than the scales undone (calibrated RMS)
/// is returned (a `cmd_2`/`cmd_3` swap the screen reads as `cmd_2` x 1.31), as is a slip or
/// block that both tests still find on the undone poses (the scale may then be the shift's
/// shadow); where neither remains, the shift was the scale's and `None` is returned (the refit
/// with the first explanation undone, as the sweep side's `diagnosis/combined_slips.rs`). A
/// column slip of a column the screen named (`cmd_3` in gradians, read as `cmd_3` x 1.135 +-
/// 0.018) is returned: the two agree on the column, and the slip's exact factor names the cause.
pub fn shift_behind_scales(
    (set, desc): (&MeasurementSet, &RobotDescription),
    options: &FreePoseOptions,
    summary: &FreePoseSummary,
    block: Option<&BlockShift>,
) -> Option<FreePoseShift> {
    let as_read = explaining_slip(set, desc, options, Some(summary))
        .map(FreePoseShift::Slip)
        .or_else(|| block.cloned().map(FreePoseShift::Block))?;
    let same_column =
        matches!(&as_read, FreePoseShift::Slip(s) if summary.scales.iter().any(|n| n.scale.column == s.field));
    if summary.scales.is_empty() || same_column {
        return Some(as_read);
    }
    let undone = scales_undone(set, &summary.scales);
    let Ok(again) = calibrate_free_poses(&undone, desc, options) else {
        return Some(as_read);
    };
    // A shift that leaves less than the scales' refit does explains more than they do (a
    // column swap read as a scale that takes a twentieth of its misfit).
    let undone_rms_mm = match &as_read {
        FreePoseShift::Block(b) => b.undone_rms_mm,
        FreePoseShift::Slip(s) => s.undone_rms_mm,
    };
    if undone_rms_mm < again.summary.calibrated_rms_mm {
        return Some(as_read);
    }
    let remains = block_shift(&undone, desc, options, &again).is_some() || {
        let (_, summary_again) = again.into_calibration(desc);
        explaining_slip(&undone, desc, options, Some(&summary_again)).is_some()
    };
    remains.then_some(as_read)
}

/// `set` with the column scales `named` undone: each column divided by its factor (a
/// coordinate column about the origin: the centre a scale is read about moves only the base,
/// which the fit places).
pub fn scales_undone(set: &MeasurementSet, named: &[NamedScale]) -> MeasurementSet {
    named
        .iter()
        .fold(set.clone(), |s, n| match coordinate_index(&n.scale.column) {
            Some(c) => s.with_coordinate_scaled(c, 1.0 / n.scale.factor),
            None => {
                command_index(&n.scale.column).map_or(s.clone(), |j| s.with_command_scaled(j, 1.0 / n.scale.factor))
            }
        })
}

/// The free poses calibrated again with the column scales the screen named
/// ([`FreePoseSummary::scales`]) undone ([`scales_undone`]), with no held-out half and no
/// effects (the tests of the joints' transmissions read the geometry).
#[derive(Clone, Debug)]
pub struct ScalesUndone {
    /// The poses with the scales undone.
    pub set: MeasurementSet,
    /// Their calibration.
    pub cal: Calibration,
    /// Its free-pose summary.
    pub summary: FreePoseSummary,
}

/// [`ScalesUndone`] of `set` and the scales `named`; `None` without a named scale, or when the
/// calibration of the undone poses fails (the tests then run on the calibration as read).
pub fn calibrated_with_scales_undone(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &FreePoseOptions,
    named: &[NamedScale],
) -> Option<ScalesUndone> {
    if named.is_empty() {
        return None;
    }
    let undone = scales_undone(set, named);
    let (cal, summary) = geometry_calibration(&undone, desc, options)?;
    Some(ScalesUndone {
        set: undone,
        cal,
        summary,
    })
}

/// The free-pose calibration of `set` with `options` as the tests of the joints' transmissions
/// read it: no held-out half, no effects (they read the geometry); `None` where it fails.
fn geometry_calibration(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &FreePoseOptions,
) -> Option<(Calibration, FreePoseSummary)> {
    let geometry = FreePoseOptions {
        holdout: false,
        effects: false,
        ..*options
    };
    Some(calibrate_free_poses(set, desc, &geometry).ok()?.into_calibration(desc))
}

/// The 0-based coordinate of `x_mm`, `y_mm`, `z_mm`.
fn coordinate_index(column: &str) -> Option<usize> {
    ["x_mm", "y_mm", "z_mm"].iter().position(|c| *c == column)
}

/// The 0-based joint of `cmd_K`.
fn command_index(column: &str) -> Option<usize> {
    column.strip_prefix("cmd_")?.parse::<usize>().ok()?.checked_sub(1)
}

/// A calibration of a set as the coordinate-scale profile reads it ([`axes_profile_fit`],
/// [`free_pose_profile_fit`]).
pub type ProfileFit<'a> = &'a (dyn Fn(&MeasurementSet) -> Option<Fit> + Sync);

/// What the coordinate-scale profile ([`axis_scale`]) of a file reads, weighed against the
/// instrument column the joints' slopes named ([`instrument_axis_source`]).
#[derive(Clone, Debug)]
pub enum CoordinateScale {
    /// The profile could not run: its re-run calibrations did not keep the same poses and
    /// parameters, or failed.
    Untested,
    /// The column named from the joints' slopes (with the points' fit counted) explains what
    /// the profile reads, or the profile names nothing beside it: said with that column.
    SourceNamed,
    /// No scale the data determine beyond 1; the column that reads the most unlike the others.
    Within(AxisScale),
    /// Free poses whose column-scale screen, clustered by configuration, named none
    /// (`free_pose/scales.rs`): the profile's scale of one column, not named (the profile counts
    /// every point as independent, which repeated visits of one configuration are not).
    ScreenNamedNone(AxisScale),
    /// A scale the data determine beyond 1, and a second instrument axis behind it where the
    /// profile of the data with that column undone names another column.
    Named {
        /// The scale named.
        found: AxisScale,
        /// The second axis: the profile of the data with the named column divided by its factor
        /// about their centroid ([`axis_scale_with_column_undone`]), where it names another column.
        second: Option<AxisScale>,
        /// On sweeps the held joints' correction moved, what files simulated without any scale
        /// read ([`beyond_correction_error`]): the finding stands beyond it.
        null: Option<NullSpread>,
    },
    /// A scale the noise would name, on sweeps the held joints' correction moved, that files
    /// simulated from the calibration without any scale read as far from 1
    /// ([`beyond_correction_error`]): not named.
    WithinCorrectionError {
        /// The scale the profile reads.
        found: AxisScale,
        /// The spread the simulated files read.
        null: NullSpread,
    },
}

/// The files simulated from a calibration that [`beyond_correction_error`] profiles: with 20,
/// the prediction interval's threshold at the per-column false-alarm rate is 5.4 of their
/// standard deviations (Student's t, 19 degrees of freedom; 4.2 with the spread known), and
/// each file is a profile (three calibrations).
pub const NULL_FILES: usize = 20;

/// The seed of the first simulated file's noise (file `b` draws from `NULL_SEED + b`): a file
/// gets the same verdict on every run.
const NULL_SEED: u64 = 0x5ca1e;

/// `scale` weighed against the model error the held joints' correction carries
/// ([`NullSpread`]): a scale [`CoordinateScale::Named`] on sweeps that `cal` corrected (more
/// than one fit-and-correct pass) stands only beyond what files simulated from `cal` read
/// (`correction_null`: [`NULL_FILES`] files simulated with [`simulated_sweeps`]); otherwise
/// it is [`CoordinateScale::WithinCorrectionError`]. A second axis behind a named one is kept
/// only where it stands beyond them too. Other findings, and sweeps that needed no
/// correction, are returned as they are, as is a finding whose simulated files cannot be
/// made or calibrated.
pub fn beyond_correction_error(
    scale: CoordinateScale,
    (set, desc): (&MeasurementSet, &RobotDescription),
    (cal, fit): (&Calibration, ProfileFit<'_>),
    max_rows: usize,
) -> CoordinateScale {
    let CoordinateScale::Named { found, second, .. } = scale else {
        return scale;
    };
    let null_of = |found: &AxisScale| correction_null(found, (set, desc), (cal, fit), max_rows);
    match null_of(&found) {
        Some(null) if !null.passes() => CoordinateScale::WithinCorrectionError { found, null },
        null => CoordinateScale::Named {
            second: second.filter(|s| null_of(s).is_none_or(|n| n.passes())),
            found,
            null,
        },
    }
}

/// What [`NULL_FILES`] files simulated from `cal` at `set`'s commands without any scale read
/// of `found`'s column ([`simulated_sweeps`], with the noise of the sweeps' own fits; each
/// profiled with `fit`, thinned above `max_rows` rows), against `found` ([`null_spread`]);
/// `None` where `cal` needed no correction (one fit-and-correct pass), or the files cannot be
/// made or calibrated.
fn correction_null(
    found: &AxisScale,
    (set, desc): (&MeasurementSet, &RobotDescription),
    (cal, fit): (&Calibration, ProfileFit<'_>),
    max_rows: usize,
) -> Option<NullSpread> {
    if cal.held_passes <= 1 {
        return None;
    }
    let sigma_mm = sweeps_agreement(cal)
        .map(|a| a.rms_mm[0])
        .or_else(|| Some(cal.noise.as_ref()?.used_rms_3d_mm / 3f64.sqrt()))?;
    let reads: Vec<Option<f64>> = (0..NULL_FILES as u64)
        .into_par_iter()
        .map(|b| {
            let mut rng = ChaCha12Rng::seed_from_u64(NULL_SEED + b);
            let simulated = simulated_sweeps(set, (desc, &cal.robot), sigma_mm, &mut rng)?;
            factor_read(&simulated, found.scaled, fit, max_rows)
        })
        .collect::<Option<_>>()?;
    null_spread(found, &reads)
}

/// The coordinate-scale profile of `set` under the calibration `fit`, or of a slide's
/// commands read alike (the sliding joints of `desc`), weighed against `source`: a column named
/// from the joints' slopes that the profile's finding is, or that explains it once undone,
/// leaves nothing more to say. With `screened` (free poses whose column-scale screen named
/// none), a scale of one column is [`CoordinateScale::ScreenNamedNone`]; a scale of every
/// coordinate (a length scale) the screen leaves to the profile. Above `max_rows` rows the
/// profile thins the data ([`axis_scale`]).
pub fn coordinate_scale(
    (set, desc): (&MeasurementSet, &RobotDescription),
    (fit, source): (ProfileFit<'_>, Option<&ColumnSource>),
    (max_rows, screened): (usize, bool),
) -> CoordinateScale {
    let slides: Vec<usize> = (0..desc.joints.len())
        .filter(|&j| desc.joints[j].kind == JointKind::Prismatic)
        .collect();
    let Some(found) = axis_scale(set, fit, max_rows, &slides) else {
        return CoordinateScale::Untested;
    };
    let explained = |source: &ColumnSource| {
        axis_scale_with_column_undone(set, (source.column, source.factor), fit, max_rows, &slides)
            .is_some_and(|a| !a.significant)
    };
    if let Some(source) = source.filter(|s| !s.alike)
        && (!found.significant || found.scaled == Scaled::Column(source.column) || explained(source))
    {
        return CoordinateScale::SourceNamed;
    }
    if !found.significant {
        return CoordinateScale::Within(found);
    }
    if screened && found.scaled != Scaled::Every {
        return CoordinateScale::ScreenNamedNone(found);
    }
    let second = second_axis_scale(set, &found, fit, (max_rows, &slides));
    CoordinateScale::Named {
        found,
        second,
        null: None,
    }
}

/// A second instrument axis' scale behind the column `found` names: the coordinate-scale
/// profile of `set` with that column divided by its factor about the data's centroid
/// ([`axis_scale_with_column_undone`]), as the free-pose side calibrates again with a named
/// scale undone ([`calibrated_with_scales_undone`]): two axes scaled by different factors (x
/// long, z short) read as the first axis and, for the second's share, as the joints'
/// transmissions or the slides' leads. The second column the profile then names on its own
/// test (the same false-alarm rate); `None` where it names none, or the same column, or
/// `found` is no single column.
fn second_axis_scale(
    set: &MeasurementSet,
    found: &AxisScale,
    fit: ProfileFit<'_>,
    (max_rows, slides): (usize, &[usize]),
) -> Option<AxisScale> {
    let Scaled::Column(first) = found.scaled else {
        return None;
    };
    let second = axis_scale_with_column_undone(set, (first, found.factor), fit, max_rows, slides)?;
    let other = matches!(second.scaled, Scaled::Column(c) if c != first);
    (second.significant && other).then_some(second)
}

/// What the scale tests of a free-pose calibration found that the fit absorbed
/// ([`free_pose_scale_checks`]).
#[derive(Clone, Debug)]
pub enum FreePoseChecks {
    /// A column slip or a moved block of poses ([`shift_behind_scales`]): it misfits every test
    /// of a scale, which did not run.
    Shift(FreePoseShift),
    /// The scale tests.
    Scales(Box<FreePoseScales>),
}

/// The scale tests of a free-pose calibration, run on the poses calibrated again with the
/// column scales the screen named undone where it named any ([`calibrated_with_scales_undone`]),
/// so that a slope said is one the scales do not explain.
#[derive(Clone, Debug)]
pub struct FreePoseScales {
    /// The poses with the screen's scales undone, calibrated; `None` where it named none or
    /// that calibration failed (the tests then read the calibration as read).
    pub undone: Option<ScalesUndone>,
    /// The joints whose transmission departs beyond what a drive gives
    /// ([`free_pose_scale_slips`]).
    pub scaled: Vec<ScaleSlip>,
    /// The joints whose slope a gear's once-per-turn error and a scaled command column explain
    /// alike ([`free_pose_scale_doubts`]).
    pub doubts: Vec<ScaleDoubt>,
    /// The command columns the transmission test names once the joints said above are undone;
    /// `None` where none was said or that calibration failed.
    pub second: Option<SecondScales>,
    /// The coordinate-scale profile with the slopes' command columns undone, where every joint
    /// said is a command slope and the screen named no scale (one it named is the profile's
    /// finding already).
    pub profile: Option<CoordinateScale>,
    /// How large a scale of each other command column the transmission test lets pass
    /// ([`free_pose_scale_reach`] without the joints said).
    pub reach: Option<ScaleReach>,
}

/// The joints a free-pose calibration's transmission test said, and the command columns it
/// names once they are undone ([`second_command_scales`]).
#[derive(Clone, Debug)]
pub struct SecondScales {
    /// The joints said, `(joint, 1-based; its slope)`: scaled beyond a drive, then doubted.
    pub said: Vec<(usize, f64)>,
    /// What the test names with them undone.
    pub found: Vec<SecondCommandScale>,
}

/// The scale tests of the free-pose calibration `(cal, summary)` of `set` with `options`
/// ([`FreePoseChecks`]); `block` is [`block_shift`] of the calibration as read. A slip or a
/// shifted block misfits every test of a scale (a column's, the coordinates'): where one is
/// found ([`shift_behind_scales`]) the others do not run.
pub fn free_pose_scale_checks(
    (set, desc): (&MeasurementSet, &RobotDescription),
    options: &FreePoseOptions,
    (cal, summary): (&Calibration, &FreePoseSummary),
    block: Option<&BlockShift>,
) -> FreePoseChecks {
    if let Some(shift) = shift_behind_scales((set, desc), options, summary, block) {
        return FreePoseChecks::Shift(shift);
    }
    let undone = calibrated_with_scales_undone(set, desc, options, &summary.scales);
    let (set_u, (cal_u, summary_u)) = undone
        .as_ref()
        .map_or((set, (cal, summary)), |u| (&u.set, (&u.cal, &u.summary)));
    let scaled = free_pose_scale_slips((cal_u, summary_u), desc, set_u.rows());
    let doubts = free_pose_scale_doubts((cal_u, summary_u), desc, set_u.rows());
    // A joint's slope off its description's is a misfit the geometry carries; the
    // coordinate-scale profile would read it as an axis' scale, so it runs with the joints'
    // command columns undone by the slopes said: a second slip (a coordinate column scaled
    // too) is then tested, not hidden behind the first.
    let slopes: Vec<(usize, f64)> = scaled
        .iter()
        .filter_map(|s| match s {
            ScaleSlip::Command { joint, travel, .. } => Some((*joint, *travel)),
            _ => None,
        })
        .collect();
    let said: Vec<(usize, f64)> = slopes
        .iter()
        .copied()
        .chain(doubts.iter().map(|d| (d.joint, d.travel)))
        .collect();
    let second = second_command_scales((set_u, desc), options, &said).map(|found| SecondScales { said, found });
    let profile = (slopes.len() == scaled.len() && summary.scales.is_empty()).then(|| {
        let fit = |s: &MeasurementSet| free_pose_profile_fit(s, desc, options);
        let commands_undone = with_commands_scaled(set, &slopes);
        coordinate_scale(
            (&commands_undone, desc),
            (&fit, None),
            (PROFILE_MAX_FREE_POSE_ROWS, true),
        )
    });
    let reach =
        free_pose_scale_reach((cal_u, summary_u), desc, set_u.rows()).and_then(|r| r.without(&named_joints(&scaled)));
    FreePoseChecks::Scales(Box::new(FreePoseScales {
        undone,
        scaled,
        doubts,
        second,
        profile,
        reach,
    }))
}

/// A command column's scale the transmission test names once the joints said are undone
/// ([`second_command_scales`]).
#[derive(Clone, Debug)]
pub enum SecondCommandScale {
    /// A slope beyond what a drive gives ([`free_pose_scale_slips`]).
    Slip(ScaleSlip),
    /// A slope a gear's once-per-turn error and a scaled column explain alike
    /// ([`free_pose_scale_doubts`]).
    Doubt(ScaleDoubt),
}

/// The command columns behind the joints `said` (`(joint, 1-based; its slope)`): the poses
/// calibrated again with those joints' columns undone by their slopes (no held-out half, no
/// effects) and the transmission test run on that calibration, as `validate`'s two-slip search
/// refits with the first slip undone (`diagnosis/combined_slips.rs`): a one-per-cent column
/// scale beside another reads partly as the other's slope, and shows whole once the other is
/// undone. The joints not said that it names; `None` where none was said or the calibration
/// fails.
pub fn second_command_scales(
    (set, desc): (&MeasurementSet, &RobotDescription),
    options: &FreePoseOptions,
    said: &[(usize, f64)],
) -> Option<Vec<SecondCommandScale>> {
    if said.is_empty() {
        return None;
    }
    let undone = with_commands_scaled(set, said);
    let (again, again_summary) = geometry_calibration(&undone, desc, options)?;
    let again = (&again, &again_summary);
    let new = |joint: &usize| !said.iter().any(|(j, _)| j == joint);
    let slips = free_pose_scale_slips(again, desc, undone.rows())
        .into_iter()
        .filter(|s| matches!(s, ScaleSlip::Command { joint, .. } if new(joint)))
        .map(SecondCommandScale::Slip);
    let doubts = free_pose_scale_doubts(again, desc, undone.rows())
        .into_iter()
        .filter(|d| new(&d.joint))
        .map(SecondCommandScale::Doubt);
    Some(slips.chain(doubts).collect())
}

/// `set` with each joint's command column (`(joint, 1-based)`) multiplied by its factor: the
/// commands a joint that travels `factor` times the description's transmission per command
/// would have been given. Its lines kept.
pub fn with_commands_scaled(set: &MeasurementSet, factors: &[(usize, f64)]) -> MeasurementSet {
    factors
        .iter()
        .fold(set.clone(), |s, &(joint, f)| s.with_command_scaled(joint - 1, f))
}
