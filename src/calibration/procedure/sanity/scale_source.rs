//! Several joints' transmissions departing at once from one instrument axis read long or
//! short (`calibrate` on sweeps): the transmission test ([`super::scale`]) reads each joint's
//! fitted mean slope against what a drive gives, and a scale of one coordinate column bends
//! every sweep's arc alike, which each joint's fitted transmission takes up as its share of
//! the scale. Each joint alone then looks like its command column scaled; one scale of one
//! column explains them all with one parameter.
//!
//! The attribution is a likelihood-ratio test between the two explanations of the departures
//! `d_k` (fitted over described slope less 1, variance `v_k` the fit's and a drive's combined):
//!
//! - **k command columns**: each departing joint's own factor, `k` parameters; what is left is
//!   the other joints' `sum d_j^2 / v_j`;
//! - **one column `c` scaled by `f`**: the sensitivity `g_k = d d_k / d f` of each joint's
//!   slope to the column undone about the data's centroid, by a finite difference of the
//!   calibration (`STEP`), gives `f` by weighted least squares (`f - 1 = -sum g d / v / sum
//!   g^2 / v`); the misfit, the chi-square of every joint's departure in the calibration re-run
//!   with the column undone plus the change of its residual sum of squares over the noise's
//!   variance (the profile's evidence, [`crate::measurement::unit_check::axis_scale`]), is then
//!   minimised over the factor by parabolas through the three best factors tried (the slopes
//!   follow a scale of several per cent only roughly linearly); the factor's sigma is the
//!   parabola's `a^(-1/2)` (the misfit is a chi-square: it grows by 1 at one sigma).
//!
//! The column is named when, with it undone, no joint departs beyond the transmission test's
//! [`DRIVE_SIGMAS`], the departures left pass the chi-square test at [`AXIS_SCALE_FALSE_ALARM`],
//! the points are not fitted significantly worse (the F test at that rate), and the ratio of
//! the two explanations' misfits (Wilks: chi-square with `k - 1` degrees of freedom, the
//! parameters one column saves) passes at that rate. With one departing joint both take one
//! parameter: the column alone is named when the misfits differ by more than the 1-dof
//! quantile in its favour, both are said when they differ by less, and the command column
//! alone (as before) otherwise. A genuine command column's scale departs in its joint only;
//! a column's scale that cancels it moves every other joint whose arcs it bends, which then
//! departs, so it does not pass.

use super::slope::{DRIVE_SIGMAS, JointSlope};
use crate::measurement::MeasurementSet;
use crate::measurement::unit_check::axis_scale::{AXIS_SCALE_FALSE_ALARM, COLUMNS, Fit};
use crate::numerics::stats::{chi_square_quantile, f_upper_quantile};

/// The relative step of the finite difference of the slopes: a thousandth, as the coordinate
/// profile's ([`crate::measurement::unit_check::axis_scale`]).
const STEP: f64 = 1e-3;

/// At most this many parabola steps after the linearised factor and its half: the misfit is
/// near a parabola in the factor over a few per cent, and each step is one calibration.
const ITERATIONS: usize = 4;

/// One calibration of a file, as the attribution reads it.
#[derive(Clone, Debug, PartialEq)]
pub struct Refit {
    /// Its swept joints' slopes ([`super::scale::joint_slopes`]).
    pub slopes: Vec<JointSlope>,
    /// Its residuals.
    pub fit: Fit,
}

/// One coordinate column's scale that explains the joints' departures (module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct ColumnSource {
    /// The column: 0 `x_mm`, 1 `y_mm`, 2 `z_mm`.
    pub column: usize,
    /// The factor it reads (the data divided by it about their centroid are explained).
    pub factor: f64,
    /// Its 1-sigma.
    pub sigma: f64,
    /// The joints the transmission test named: `(joint, how far it travels per command over
    /// the description's, its sigma, whether it slides, its sweep's experiment)`.
    pub joints: Vec<(usize, f64, f64, bool, String)>,
    /// The chi-square of every joint's departure with the column undone, and the joints.
    pub left: (f64, usize),
    /// The residual RMS per coordinate \[mm\] as read and with the column undone.
    pub rms_mm: [f64; 2],
    /// Whether a command column's scale explains the data alike (one joint departs, and the
    /// misfits do not tell them apart): both are said.
    pub alike: bool,
    /// Another column whose scale explains them within the test's reach of this one, and the
    /// factor it reads (a SCARA's links take a scale of x and y together).
    pub other: Option<(usize, f64)>,
}

/// The variance of a joint's departure: the fit's and a drive's combined.
fn variance(s: &JointSlope) -> f64 {
    s.sigma.powi(2) + s.drive.powi(2)
}

/// The chi-square of `slopes`' departures from 1.
fn chi_square<'a>(slopes: impl Iterator<Item = &'a JointSlope>) -> f64 {
    slopes.map(|s| (s.ratio - 1.0).powi(2) / variance(s)).sum()
}

/// The centroid of `set`'s coordinates \[mm\].
fn centroid(set: &MeasurementSet) -> [f64; 3] {
    let rows = set.rows();
    let n = rows.len().max(1) as f64;
    std::array::from_fn(|c| rows.iter().map(|m| m.position_mm[c]).sum::<f64>() / n)
}

/// `set` with column `c` divided by `factor` about `centre` \[mm\].
fn undone(set: &MeasurementSet, c: usize, factor: f64, centre: [f64; 3]) -> MeasurementSet {
    set.with_coordinate_scaled_about(c, 1.0 / factor, centre[c])
}

/// `at`'s slopes in `base`'s joints' order, `None` when a joint is missing or the fit kept
/// other parameters.
fn matched(base: &Refit, at: &Refit) -> Option<Vec<JointSlope>> {
    if at.fit.dof != base.fit.dof {
        return None;
    }
    base.slopes
        .iter()
        .map(|s| at.slopes.iter().find(|a| a.joint == s.joint).cloned())
        .collect()
}

/// The misfit of a calibration against `base`'s: the chi-square of its joints' departures
/// plus the change of its points' residual sum of squares over `noise` (module doc); `None`
/// where it kept other parameters or joints.
fn misfit(base: &Refit, at: &Refit, noise: f64) -> Option<f64> {
    let slopes = matched(base, at)?;
    Some(chi_square(slopes.iter()) + (at.fit.sum_squares_mm2 - base.fit.sum_squares_mm2) / noise)
}

/// The vertex of the parabola through three points `(f, misfit)` and its curvature `a` (the
/// misfit `a (f - vertex)^2 + c`), `None` where it opens downwards.
fn vertex(p: [(f64, f64); 3]) -> Option<(f64, f64)> {
    let [(x1, y1), (x2, y2), (x3, y3)] = p;
    let d = (x1 - x2) * (x1 - x3) * (x2 - x3);
    let a = (x3 * (y2 - y1) + x2 * (y1 - y3) + x1 * (y3 - y2)) / d;
    let b = (x3 * x3 * (y1 - y2) + x2 * x2 * (y3 - y1) + x1 * x1 * (y2 - y3)) / d;
    (a > 0.0 && a.is_finite() && b.is_finite()).then(|| (-b / (2.0 * a), a))
}

/// Column `c`'s factor, its sigma and the calibration with it undone (module doc): the
/// linearised factor from the slopes' finite difference, then the misfit's minimum by
/// parabolas through the three best factors tried (each a calibration re-run).
fn fitted_column(
    set: &MeasurementSet,
    c: usize,
    (base, noise): (&Refit, f64),
    refit: &dyn Fn(&MeasurementSet) -> Option<Refit>,
) -> Option<(f64, f64, Refit)> {
    let centre = centroid(set);
    let plus = matched(base, &refit(&undone(set, c, 1.0 + STEP, centre))?)?;
    let gains: Vec<f64> = base
        .slopes
        .iter()
        .zip(&plus)
        .map(|(s, p)| (p.ratio - s.ratio) / STEP)
        .collect();
    let information: f64 = base.slopes.iter().zip(&gains).map(|(s, g)| g * g / variance(s)).sum();
    if !(information.is_finite() && information > 0.0) {
        return None;
    }
    let pull: f64 = base
        .slopes
        .iter()
        .zip(&gains)
        .map(|(s, g)| g * (s.ratio - 1.0) / variance(s))
        .sum();
    let linear = 1.0 - pull / information;
    let mut sigma = information.sqrt().recip();
    let mut tried: Vec<(f64, f64, Refit)> = vec![(1.0, misfit(base, base, noise)?, base.clone())];
    for f in [(1.0 + linear) / 2.0, linear] {
        let at = refit(&undone(set, c, f, centre))?;
        tried.push((f, misfit(base, &at, noise)?, at));
    }
    for _ in 0..ITERATIONS {
        tried.sort_by(|a, b| a.1.total_cmp(&b.1));
        let best = tried[0].0;
        let Some((f, a)) = vertex([0, 1, 2].map(|i| (tried[i].0, tried[i].1))) else {
            break;
        };
        sigma = a.sqrt().recip();
        if (f - best).abs() < sigma / 10.0 || !f.is_finite() || f <= 0.0 {
            break;
        }
        let at = refit(&undone(set, c, f, centre))?;
        tried.push((f, misfit(base, &at, noise)?, at));
    }
    tried.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (factor, _, at) = tried.swap_remove(0);
    Some((factor, sigma, at))
}

/// The coordinate column whose scale explains the departures of the joints `named` (those the
/// transmission test names as their command columns scaled) in `set`, calibrated by `refit`
/// (module doc), or `None` where none does better than the command columns.
pub fn column_source(
    set: &MeasurementSet,
    named: &[usize],
    refit: &dyn Fn(&MeasurementSet) -> Option<Refit>,
) -> Option<ColumnSource> {
    if named.is_empty() {
        return None;
    }
    let base = refit(set)?;
    let dof = base.fit.dof as f64;
    if dof < 2.0 || base.fit.sum_squares_mm2 <= 0.0 {
        return None;
    }
    let rate = AXIS_SCALE_FALSE_ALARM;
    let noise = base.fit.sum_squares_mm2 / dof;
    let worse = f_upper_quantile(rate, 1.0, dof - 1.0);
    // What each column leaves: the joints' chi-square plus the points' change in noise units.
    let candidates = (0..3).filter_map(|c| {
        let (factor, sigma, at) = fitted_column(set, c, (&base, noise), refit)?;
        let slopes = matched(&base, &at)?;
        let left = chi_square(slopes.iter());
        let change = (at.fit.sum_squares_mm2 - base.fit.sum_squares_mm2) / noise;
        let explains = !slopes.iter().any(JointSlope::beyond)
            && left <= chi_square_quantile(1.0 - rate, slopes.len() as f64)
            && change < worse
            && (factor - 1.0).abs() > DRIVE_SIGMAS * sigma;
        explains.then_some((c, factor, sigma, left + change, (left, slopes.len()), at))
    });
    let mut candidates: Vec<_> = candidates.collect();
    candidates.sort_by(|a, b| a.3.total_cmp(&b.3));
    let apart = chi_square_quantile(1.0 - rate, 1.0);
    let other = candidates
        .get(1)
        .filter(|o| o.3 - candidates[0].3 < apart)
        .map(|o| (o.0, o.1));
    let (column, factor, sigma, misfit, left, at) = candidates.into_iter().next()?;
    let others = chi_square(base.slopes.iter().filter(|s| !named.contains(&s.joint)));
    let ratio = misfit - others;
    let alike = if named.len() >= 2 {
        if ratio > chi_square_quantile(1.0 - rate, (named.len() - 1) as f64) {
            return None;
        }
        false
    } else {
        if ratio > apart {
            return None;
        }
        ratio >= -apart
    };
    let joints = base
        .slopes
        .iter()
        .filter(|s| named.contains(&s.joint))
        .map(|s| {
            (
                s.joint,
                1.0 / s.ratio,
                s.sigma / s.ratio.powi(2),
                s.sliding,
                s.experiment.clone(),
            )
        })
        .collect();
    Some(ColumnSource {
        column,
        factor,
        sigma,
        joints,
        left,
        rms_mm: [noise.sqrt(), (at.fit.sum_squares_mm2 / dof).sqrt()],
        alike,
        other,
    })
}

impl ColumnSource {
    /// The column's name in backticks and its axis letter.
    fn names(&self) -> (String, &'static str) {
        (format!("`{}`", COLUMNS[self.column]), &COLUMNS[self.column][..1])
    }

    /// The joints' travels, in words: "joints 1, 2 turn 1.0343, 0.9722 times".
    fn travels(&self) -> String {
        let joints: Vec<String> = self.joints.iter().map(|j| j.0.to_string()).collect();
        let travels: Vec<String> = self.joints.iter().map(|j| format!("{:.4}", j.1)).collect();
        let moves = if self.joints.iter().all(|j| j.3) {
            "travel"
        } else {
            "turn"
        };
        match self.joints.len() {
            1 => format!(
                "joint {} ({}) {}s {} (+-{:.4}) times",
                joints[0], self.joints[0].4, moves, travels[0], self.joints[0].2
            ),
            _ => format!("joints {} {moves} {} times", joints.join(", "), travels.join(", ")),
        }
    }
}

impl std::fmt::Display for ColumnSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (name, axis) = self.names();
        let (factor, sigma) = (self.factor, self.sigma);
        let other = self.other.map_or_else(String::new, |(c, f)| {
            format!(
                " (or, alike for these data, `{}` reads {f:.5} times: the robot's links take a scale of both together)",
                COLUMNS[c]
            )
        });
        let undone = format!(
            "with {name} divided by {factor:.5} about the data's centroid no joint departs beyond what a drive gives \
             (chi-square {:.1} on {} joints, counting a drive's departure), and the calibration misses the points by \
             {:.4} mm RMS per coordinate against {:.4} mm as read",
            self.left.0, self.left.1, self.rms_mm[1], self.rms_mm[0]
        );
        let check = format!(
            "the instrument's scale along {axis} (its axis scale or compensation, a photogrammetry scale bar along it) \
             and the exporter (a column scaled or converted alone)"
        );
        if self.alike {
            let (joint, travel, _, sliding, _) = self.joints[0];
            let drive = match sliding {
                true => format!(
                    "lead (its screw's lead, a rack's or a scale's pitch) for joint {joint} is wrong, or the coordinates of \
                     {} alone are scaled by {travel:.4}",
                    self.joints[0].4
                ),
                false => format!("gear ratio for joint {joint} is wrong"),
            };
            return write!(
                f,
                "{} as far per command as the description's transmission says: the column `cmd_{joint}` looks scaled by \
                 {:.4} on export (or the description's {drive}), or {name}: the instrument's \
                 {axis} axis reads {factor:.5} times (+- {sigma:.5}){other}, which explains it alike ({undone}); these data \
                 cannot tell them apart: check cmd_{joint} against the controller's reading at two poses and {check}, \
                 then calibrate the corrected file again. The fit took the factor into joint {joint}'s transmission, so \
                 calibration.json is wrong for it",
                self.travels(),
                1.0 / travel
            );
        }
        let columns: Vec<String> = self.joints.iter().map(|j| format!("`cmd_{}`", j.0)).collect();
        write!(
            f,
            "{name}: the instrument's {axis} axis reads {factor:.5} times (+- {sigma:.5}, {:.0} sigma from 1){other}: {} \
             as far per command as {} transmission says, which one scale of {name} explains better ({undone}) than {} \
             scaled on export; each arc alone takes such a scale as a change of its joint's transmission, so \
             calibration.json has absorbed it into the transmissions and the geometry: check {check}, then calibrate \
             the corrected file again",
            (factor - 1.0).abs() / sigma,
            self.travels(),
            if self.joints.len() == 1 {
                "the description's"
            } else {
                "each description's"
            },
            match columns.len() {
                1 => format!("the column {}", columns[0]),
                _ => format!("the command columns {} each", columns.join(", ")),
            }
        )
    }
}
