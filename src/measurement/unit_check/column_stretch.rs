//! One coordinate column scaled by a factor that is no length unit (an exporter's or a
//! hand-edited column: `x_mm` doubled, `z_mm` read 30 % long): beyond the [`MIN_STRETCH`] the
//! profile test of [`super::axis_scale`] and the free-pose screen warn of, within the unit slips
//! of [`super::SLIP_FACTOR`]. Such a column draws each arc as an ellipse and spreads the free
//! poses along one instrument axis; every other check then names whichever row, sweep or
//! transmission bends furthest to absorb it.
//!
//! A search over the factor, written apart from the calibration: each column in turn (and the
//! three together, the links' own length, which this check leaves to the others) divided by a
//! factor on a logarithmic grid, and the file's shape misfit at each: the median distance of
//! the measured points whose targets the description places (the handedness check's points:
//! `handedness::nominal_point`, sweeps and free poses alike) from the nominal robot's
//! at their commands, after the rigid registration of each setup
//! ([`crate::kinematics::rigid_fit`]), over the nominal points' spread. A file of free poses
//! alone whose description places no tool target has the targets' places on the tool fitted
//! with the registration, as the handedness check fits them
//! (`handedness::fitted_targets`): taken at the tool frame's origin, the targets'
//! offsets (a tool's size) would blur the misfit and bias the factor. A gross row (beyond
//! [`GROSS_OVER_MEDIAN`] as read) is left out first.
//!
//! A column is named when dividing it by one factor shrinks the misfit by [`IMPROVEMENT`] (a
//! shape error that large is the column's, not the robot's, whose deviations from its
//! description no scale of one instrument axis mends) and the three columns together do not do
//! as well.

use super::handedness::{FreePosePoints, fitted_targets, free_pose_points, nominal_point};
use super::{SLIP_FACTOR, UnitSlip};
use crate::measurement::{MeasurementSet, format_f64};
use crate::numerics::stats::rms_spread;
use crate::robot::{Controller, RobotDescription, RobotModel};
use nalgebra::{Isometry3, Point3};

/// Dividing the column by the factor found must shrink the misfit by at least this: the
/// nominal robot's own deviations from the measured one (per cent of its size, targets placed
/// to centimetres) keep the misfit of a clean file where no column's scale moves it.
pub const IMPROVEMENT: f64 = 4.0;

/// A factor within this of 1 is left to the profile test ([`super::axis_scale`]) and the
/// free-pose screen, which name a column's scale to per mille with the calibration itself and
/// warn; beyond it the calibration that absorbs the scale misses its own validation poses by
/// tens of millimetres (the IRB/L6's `y_mm` x1.10: 51 mm against 4.9 predicted), so the file
/// is refused instead.
pub const MIN_STRETCH: f64 = 1.10;

/// The grid's ratio between neighbouring factors: 2 %, refined by the parabola through the
/// best point and its neighbours.
pub const GRID_STEP: f64 = 1.02;

/// At most this many points are judged (every n-th row of more): a column's stretch shows in a
/// few thousand points as in a million, and the search judges them about 650 times.
const MAX_POINTS: usize = 4_000;

/// Fewer placed points than this in a setup leave it out (a rigid fit of 6 parameters).
const MIN_SETUP_POINTS: usize = 6;

/// The coordinate columns by index.
const COLUMNS: [&str; 3] = ["x_mm", "y_mm", "z_mm"];

/// What the search scales: one column, or the three together.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scaled {
    Column(usize),
    All,
}

impl Scaled {
    fn divide(self, p: &Point3<f64>, factor: f64) -> Point3<f64> {
        match self {
            Scaled::Column(c) => {
                let mut q = *p;
                q[c] /= factor;
                q
            }
            Scaled::All => p / factor,
        }
    }
}

/// One setup's placed points: measured and nominal \[m\].
type SetupPoints = (Vec<Point3<f64>>, Vec<Point3<f64>>);

/// The points the misfit is judged on.
enum Points {
    /// The placed points of each setup.
    Placed(Vec<SetupPoints>),
    /// Free poses whose targets' places on the tool are fitted: the nominal tool frames, the
    /// target ids and the measured points \[m\].
    Unplaced(FreePosePoints),
}

/// A point farther than this many times the median from where the registration puts it, as
/// read, is a gross row (a kilometre typed for a metre) the search leaves out: a least-squares
/// registration follows it, and any scale that shrinks it would seem to mend the file.
pub const GROSS_OVER_MEDIAN: f64 = 20.0;

/// The file's points and the nominal spread \[m\] the misfit is measured in.
struct Shapes {
    points: Points,
    nominal_spread_m: f64,
}

impl Shapes {
    fn of(set: &MeasurementSet, desc: &RobotDescription) -> Option<Self> {
        let shapes = match desc.tool_targets_m().is_empty() {
            true => free_pose_points(set.rows(), desc).map_or_else(|| Self::placed(set, desc), Self::unplaced),
            false => Self::placed(set, desc),
        }?;
        Some(shapes.without_gross_points().without_gross_points())
    }

    /// Free poses, their targets unplaced (module docs), every n-th of more than [`MAX_POINTS`].
    fn unplaced((tools, targets, measured): FreePosePoints) -> Option<Self> {
        let every = measured.len().div_ceil(MAX_POINTS).max(1);
        let tools: Vec<Isometry3<f64>> = tools.into_iter().step_by(every).collect();
        let targets: Vec<usize> = targets.into_iter().step_by(every).collect();
        let measured: Vec<Point3<f64>> = measured.into_iter().step_by(every).collect();
        let origins: Vec<Point3<f64>> = tools.iter().map(|t| Point3::from(t.translation.vector)).collect();
        let nominal_spread_m = rms_spread(&origins);
        (nominal_spread_m > 0.0).then_some(Shapes {
            points: Points::Unplaced((tools, targets, measured)),
            nominal_spread_m,
        })
    }

    fn placed(set: &MeasurementSet, desc: &RobotDescription) -> Option<Self> {
        let ideal = RobotModel::ideal(desc);
        let controller = Controller::from_description(desc);
        let rows = set.rows();
        let every = rows.len().div_ceil(MAX_POINTS).max(1);
        let mut by_setup: std::collections::BTreeMap<usize, SetupPoints> = std::collections::BTreeMap::new();
        for (i, m) in rows.iter().enumerate().step_by(every) {
            if let Some(nominal) = nominal_point(desc, &ideal, &controller, m) {
                let entry = by_setup.entry(set.setup_of(i)).or_default();
                entry.0.push(m.position_m());
                entry.1.push(nominal);
            }
        }
        let setups: Vec<_> = by_setup
            .into_values()
            .filter(|(measured, _)| measured.len() >= MIN_SETUP_POINTS)
            .collect();
        let (sum, count) = setups.iter().fold((0.0, 0), |(sum, count), (_, nominal)| {
            let s = rms_spread(nominal);
            (sum + s * s * nominal.len() as f64, count + nominal.len())
        });
        let nominal_spread_m = (sum / count.max(1) as f64).sqrt();
        (count > 0 && nominal_spread_m > 0.0).then_some(Shapes {
            points: Points::Placed(setups),
            nominal_spread_m,
        })
    }

    /// The points without those [`GROSS_OVER_MEDIAN`] beyond the median residual as read.
    fn without_gross_points(self) -> Self {
        let residuals = self.residuals_m(Scaled::All, 1.0);
        let fence = GROSS_OVER_MEDIAN * super::median(residuals.clone());
        let mut kept = residuals.iter().map(|r| *r <= fence);
        let points = match self.points {
            Points::Placed(setups) => Points::Placed(
                setups
                    .into_iter()
                    .map(|(measured, nominal)| {
                        measured
                            .into_iter()
                            .zip(nominal)
                            .filter(|_| kept.next() == Some(true))
                            .unzip()
                    })
                    .filter(|(measured, _): &(Vec<_>, Vec<_>)| measured.len() >= MIN_SETUP_POINTS)
                    .collect(),
            ),
            Points::Unplaced((tools, targets, measured)) => {
                let keep: Vec<bool> = kept.collect();
                let pick = |i: &usize| keep.get(*i) == Some(&true);
                Points::Unplaced((
                    (0..tools.len()).filter(pick).map(|i| tools[i]).collect(),
                    (0..targets.len()).filter(pick).map(|i| targets[i]).collect(),
                    (0..measured.len()).filter(pick).map(|i| measured[i]).collect(),
                ))
            }
        };
        Shapes { points, ..self }
    }

    /// Each point's distance \[m\] from where the registration (module docs) puts its nominal
    /// one, with `scaled` divided by `factor`; infinite for the points of a setup that does not
    /// register.
    fn residuals_m(&self, scaled: Scaled, factor: f64) -> Vec<f64> {
        let distances = |measured: &[Point3<f64>], placed: Option<Vec<Point3<f64>>>| -> Vec<f64> {
            match placed {
                Some(placed) => measured.iter().zip(&placed).map(|(m, n)| (m - n).norm()).collect(),
                None => vec![f64::INFINITY; measured.len()],
            }
        };
        match &self.points {
            Points::Placed(setups) => setups
                .iter()
                .flat_map(|(measured, nominal)| {
                    let measured: Vec<Point3<f64>> = measured.iter().map(|p| scaled.divide(p, factor)).collect();
                    let placed = crate::kinematics::rigid_fit(nominal, &measured)
                        .map(|(measured_from_nominal, _)| nominal.iter().map(|n| measured_from_nominal * n).collect());
                    distances(&measured, placed)
                })
                .collect(),
            Points::Unplaced((tools, targets, measured)) => {
                let measured: Vec<Point3<f64>> = measured.iter().map(|p| scaled.divide(p, factor)).collect();
                let placed = fitted_targets(tools, targets, &measured, false).map(|(placed, _)| placed);
                distances(&measured, placed)
            }
        }
    }

    /// The misfit (module docs) with `scaled` divided by `factor`: the median residual over
    /// the nominal spread.
    fn misfit(&self, scaled: Scaled, factor: f64) -> f64 {
        super::median(self.residuals_m(scaled, factor)) / self.nominal_spread_m
    }

    /// The factor on the grid over `[1 / SLIP_FACTOR, SLIP_FACTOR]` that minimises the
    /// misfit, refined by the parabola through its neighbours (in the factor's logarithm), and
    /// the misfit there.
    /// `None` where the best is the grid's end: a factor beyond the search's reach, a unit
    /// the other checks name (a column in inches, or in centimetres in a block of rows).
    fn best_factor(&self, scaled: Scaled) -> Option<(f64, f64)> {
        let steps = (SLIP_FACTOR.ln() / GRID_STEP.ln()).ceil() as i32;
        let h = GRID_STEP.ln();
        let cost = |ln_factor: f64| self.misfit(scaled, ln_factor.exp());
        let grid: Vec<(f64, f64)> = (-steps..=steps)
            .map(|i| (f64::from(i) * h, cost(f64::from(i) * h)))
            .collect();
        let best = (0..grid.len())
            .min_by(|&a, &b| grid[a].1.total_cmp(&grid[b].1))
            .unwrap_or(0);
        let (ln_best, cost_best) = grid[best];
        let (Some(before), Some(after)) = (best.checked_sub(1).map(|i| grid[i]), grid.get(best + 1)) else {
            return None;
        };
        // The vertex of the parabola through three equally spaced points.
        let curvature = before.1 - 2.0 * cost_best + after.1;
        let ln_vertex = match curvature > 0.0 {
            true => ln_best + 0.5 * h * (before.1 - after.1) / curvature,
            false => ln_best,
        };
        let refined = cost(ln_vertex);
        Some(match refined < cost_best {
            true => (ln_vertex.exp(), refined),
            false => (ln_best.exp(), cost_best),
        })
    }
}

/// The coordinate column that reads a factor long or short (module docs), as a slip naming the
/// column and the factor.
pub(super) fn one_column_stretched(set: &MeasurementSet, desc: &RobotDescription) -> Option<UnitSlip> {
    let shapes = Shapes::of(set, desc)?;
    let as_read = shapes.misfit(Scaled::All, 1.0);
    if !(as_read.is_finite() && as_read > 0.0) {
        return None;
    }
    let uniform = shapes
        .best_factor(Scaled::All)
        .map_or(f64::INFINITY, |(_, misfit)| misfit);
    let (column, factor, misfit) = (0..3)
        .filter_map(|c| {
            let (factor, misfit) = shapes.best_factor(Scaled::Column(c))?;
            Some((c, factor, misfit))
        })
        .min_by(|a, b| a.2.total_cmp(&b.2))?;
    let stretched = factor.ln().abs() >= MIN_STRETCH.ln();
    let mended = misfit * IMPROVEMENT <= as_read;
    if !stretched || !mended || uniform <= misfit {
        return None;
    }
    Some(UnitSlip {
        field: COLUMNS[column].into(),
        message: format!(
            "its values are {} times what the description and the other two columns make them: this column alone \
             divided by that factor brings the measured points {:.1} times closer to the nominal robot's at their \
             commands (a typical distance of {:.1} mm against {:.1} mm as read, after the best rigid placement of each setup), while \
             no other column and no scale of all three does; undo the scale this column was written with (an \
             exporter's or an edit's factor)",
            format_f64((factor * 1000.0).round() / 1000.0),
            as_read / misfit,
            misfit * shapes.nominal_spread_m * 1e3,
            as_read * shapes.nominal_spread_m * 1e3
        ),
    })
}
