//! Fits without their outlying groups (poses, each a few measured points): the group RMS of a
//! first fit sets Tukey's far-out fence ([`far_out_fence`]); the groups beyond it are left out
//! and the fit repeated, while the set beyond the (fixed) fence changes, at most
//! [`OUTLIER_ROUNDS`] times. The fence stays the first fit's: re-computed on the groups left
//! it would shrink round by round and peel off the tail of clean data.

use super::stats::far_out_fence;

/// Refits at most this many times.
pub const OUTLIER_ROUNDS: usize = 10;

/// At most this fraction of the groups may be left out: beyond it the model, not single
/// groups, is wrong.
pub const OUTLIER_SHARE_MAX: f64 = 0.2;

/// A group beyond the fence.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupFlag {
    /// The group (one of the caller's indices).
    pub group: usize,
    /// Its RMS residual (the caller's unit).
    pub rms: f64,
    /// The fence it exceeds (the same unit).
    pub fence: f64,
}

/// More groups beyond the fence than [`OUTLIER_SHARE_MAX`] allows.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error(
    "{flagged} of {groups} fail the outlier test (more than {:.0} %): the model, not single poses, misses these data",
    OUTLIER_SHARE_MAX * 100.0
)]
pub struct TooManyOutliers {
    /// Groups beyond the fence.
    pub flagged: usize,
    /// Groups fitted.
    pub groups: usize,
}

/// The fit on the groups kept, the groups kept and the flags (the last round's; every one
/// left out unless the caller kept them).
#[derive(Debug)]
pub struct Peeled<T> {
    /// The fit on `kept`.
    pub fitted: T,
    /// The groups the fit used.
    pub kept: Vec<usize>,
    /// The groups beyond the fence.
    pub flags: Vec<GroupFlag>,
}

/// The flags of `groups` whose RMS `rms` (in the order of `groups`) exceed `fence`.
fn flagged(groups: &[usize], rms: &[f64], fence: f64) -> Vec<GroupFlag> {
    groups
        .iter()
        .zip(rms)
        .filter(|(_, r)| **r > fence)
        .map(|(&group, &rms)| GroupFlag { group, rms, fence })
        .collect()
}

/// `groups` without the flagged ones.
fn without(groups: &[usize], flags: &[GroupFlag]) -> Vec<usize> {
    groups
        .iter()
        .copied()
        .filter(|g| !flags.iter().any(|f| f.group == *g))
        .collect()
}

/// The module's rounds: `first` is the first fit, on the groups `first_on` (every group of
/// `groups`, or those a caller already knows to leave out have been); `refit(previous, kept)`
/// fits the groups `kept` (from the previous fit); `rms_of(fit)` is the RMS residual of every
/// group of `groups` under a fit, in their order. With `keep_outliers` the groups beyond the
/// fence are flagged but kept.
pub fn fit_without_outliers<T, E>(
    groups: &[usize],
    keep_outliers: bool,
    (first, first_on): (T, Vec<usize>),
    mut refit: impl FnMut(&T, &[usize]) -> Result<T, E>,
    rms_of: impl Fn(&T) -> Result<Vec<f64>, E>,
) -> Result<Peeled<T>, E>
where
    E: From<TooManyOutliers>,
{
    let first_rms = rms_of(&first)?;
    let fence = far_out_fence(&first_rms);
    let mut flags = flagged(groups, &first_rms, fence);
    let (mut fitted, mut fitted_on) = (first, first_on);
    if keep_outliers && fitted_on == groups {
        return Ok(Peeled {
            fitted,
            kept: fitted_on,
            flags,
        });
    }
    for _ in 0..OUTLIER_ROUNDS {
        if flags.is_empty() || keep_outliers {
            break;
        }
        if flags.len() as f64 > OUTLIER_SHARE_MAX * groups.len() as f64 {
            return Err(TooManyOutliers {
                flagged: flags.len(),
                groups: groups.len(),
            }
            .into());
        }
        fitted_on = without(groups, &flags);
        fitted = refit(&fitted, &fitted_on)?;
        let again = flagged(groups, &rms_of(&fitted)?, fence);
        let settled = again.iter().map(|f| f.group).eq(flags.iter().map(|f| f.group));
        flags = again;
        if settled {
            break;
        }
    }
    let kept = if keep_outliers {
        groups.to_vec()
    } else {
        without(groups, &flags)
    };
    if kept != fitted_on {
        fitted = refit(&fitted, &kept)?;
    }
    Ok(Peeled { fitted, kept, flags })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fit of a constant to groups of values: their mean; a group's RMS is its distance.
    fn mean_of(values: &[f64], kept: &[usize]) -> f64 {
        kept.iter().map(|&i| values[i]).sum::<f64>() / kept.len() as f64
    }

    /// The median of the values `kept`: a fit no single gross error moves.
    fn median_of(values: &[f64], kept: &[usize]) -> f64 {
        let v: Vec<f64> = kept.iter().map(|&i| values[i]).collect();
        crate::numerics::stats::median(&v)
    }

    fn peel_by(values: &[f64], keep: bool, fit: fn(&[f64], &[usize]) -> f64) -> Result<Peeled<f64>, TooManyOutliers> {
        let groups: Vec<usize> = (0..values.len()).collect();
        fit_without_outliers(
            &groups,
            keep,
            (fit(values, &groups), groups.clone()),
            |_, kept| Ok(fit(values, kept)),
            |m| Ok(values.iter().map(|v| (v - m).abs()).collect()),
        )
    }

    fn peel(values: &[f64], keep: bool) -> Result<Peeled<f64>, TooManyOutliers> {
        peel_by(values, keep, mean_of)
    }

    /// Twenty values 1 +- 0.1 and one of 50: the 50 is left out, the mean is the others'.
    #[test]
    fn a_gross_error_is_left_out_and_the_fit_redone() {
        let mut values: Vec<f64> = (0..20).map(|i| 1.0 + 0.01 * (i as f64 - 9.5)).collect();
        values.push(50.0);
        let p = peel(&values, false).unwrap();
        assert_eq!(p.flags.iter().map(|f| f.group).collect::<Vec<_>>(), vec![20]);
        assert_eq!(p.kept, (0..20).collect::<Vec<_>>());
        assert_eq!(p.fitted.to_bits(), mean_of(&values, &p.kept).to_bits());
        let kept = peel(&values, true).unwrap();
        assert_eq!(kept.kept.len(), 21);
        assert_eq!(kept.flags.len(), 1);
    }

    /// Five of 21 values far off (fitted by their median; beyond a quarter the far-out fence
    /// itself moves out): the model, not the values, is wrong; five of thirty are left out.
    #[test]
    fn too_many_outliers_is_an_error() {
        let values = |n: usize| -> Vec<f64> {
            (0..n)
                .map(|i| {
                    if i % 3 == 0 && i < 15 {
                        100.0 + i as f64
                    } else {
                        1.0 + 1e-3 * i as f64
                    }
                })
                .collect()
        };
        let e = peel_by(&values(21), false, median_of).unwrap_err();
        assert_eq!((e.flagged, e.groups), (5, 21));
        assert_eq!(peel_by(&values(30), false, median_of).unwrap().kept.len(), 25);
    }

    /// Clean values: nothing flagged, the first fit stands.
    #[test]
    fn clean_groups_keep_the_first_fit() {
        let values: Vec<f64> = (0..30).map(|i| ((i * 7919) % 101) as f64 / 101.0).collect();
        let p = peel(&values, false).unwrap();
        assert!(p.flags.is_empty());
        assert_eq!(p.kept.len(), 30);
    }
}
