//! Gross poses set aside before the first fit: a pose whose points lie far beyond every other
//! pose's from the nominal model placed in closed form (one coordinate 1,000 m off, a point of
//! another file) would pull the least-squares registration and the first Levenberg-Marquardt
//! fit with it, so far that the fit leaves the robot's reach and the failure names a clean
//! pose. Such a pose is kept out of the fits and tested at the end by the outlier test as a
//! pose outside the fit ([`super::fit::flag_outside`]): flagged there, it is reported as an
//! outlier pose; not flagged, it joins the fit again.

use super::error::FreePoseError;
use super::fit::{Flag, Problem, pose_rms};
use super::model::FreePoseModel;
use crate::numerics::stats::median;
use crate::robot::RobotModel;

/// A pose this many times the median pose's RMS from the nominal model registered in closed
/// form is set aside before the first fit. The nominal model's own error moves every pose by a
/// like amount (a zero offset, a link length: smooth across the workspace, within a few times
/// the median at the workspace's edges), so only a gross error in a pose's rows reaches it.
pub const GROSS_OVER_MEDIAN: f64 = 20.0;

/// Registrations at most: each without the poses set aside so far (the first is pulled by the
/// gross poses themselves, the next ones are not).
const ROUNDS: usize = 3;

/// The nominal model registered in closed form, the gross poses of `train` and the others:
/// [`registered_without_gross`], or with `--keep-outliers` none set aside.
pub(super) fn registered_start_and_gross(
    problem: &Problem<'_>,
    nominal: &RobotModel,
    train: Vec<usize>,
    options: &super::FreePoseOptions,
) -> Result<(FreePoseModel, Vec<Flag>, Vec<usize>), FreePoseError> {
    if options.keep_outliers {
        return Ok((super::registered_start(problem, nominal, &train)?, vec![], train));
    }
    let (start, gross) = registered_without_gross(problem, nominal, &train, super::OUTLIER_SHARE_MAX)?;
    let rest = train
        .into_iter()
        .filter(|i| !gross.iter().any(|g| g.pose == *i))
        .collect();
    Ok((start, gross, rest))
}

/// The nominal model registered in closed form on the poses `train` but the gross ones, and
/// the gross ones (each with its RMS and the fence it passes, [`GROSS_OVER_MEDIAN`] times the
/// median, from that registration). Nothing is set aside where more than `share_max` of the poses would be:
/// the description, not single poses, misses such data, which the fit's own tests then say.
fn registered_without_gross(
    problem: &Problem<'_>,
    nominal: &RobotModel,
    train: &[usize],
    share_max: f64,
) -> Result<(FreePoseModel, Vec<Flag>), FreePoseError> {
    let mut gross: Vec<Flag> = vec![];
    let mut start = super::registered_start(problem, nominal, train)?;
    for _ in 0..ROUNDS {
        let Ok(r) = start.residuals(problem.controller, problem.poses, train) else {
            break;
        };
        let rms = pose_rms(&r, problem.poses, train);
        let fence = GROSS_OVER_MEDIAN * median(&rms);
        let found: Vec<Flag> = train
            .iter()
            .zip(&rms)
            .filter(|&(_, &x)| x > fence)
            .map(|(&pose, &rms_m)| Flag {
                pose,
                rms_m,
                fence_m: fence,
            })
            .collect();
        let same = found.iter().map(|f| f.pose).eq(gross.iter().map(|f| f.pose));
        if same || found.len() as f64 > share_max * train.len() as f64 {
            break;
        }
        gross = found;
        let rest: Vec<usize> = train
            .iter()
            .copied()
            .filter(|i| !gross.iter().any(|g| g.pose == *i))
            .collect();
        start = super::registered_start(problem, nominal, &rest)?;
    }
    Ok((start, gross))
}
