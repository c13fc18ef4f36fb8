//! One axis experiment's points out of place among the others': a coordinate column of its
//! rows in another length unit (`x_mm` in cm in the `axis2` rows), or its block of rows
//! shifted.
//!
//! Each revolute experiment's target 0 turns on a circle whose radius and centre the
//! description gives at the experiment's commands. The radius is the frame's own; the centres
//! are compared by their distances to the other experiments' centres, which no instrument
//! frame changes. An experiment whose radius is beyond [`SPREAD_WARNING`] of the description's
//! and beyond three of its standard errors (`Arc::radius_off`: a sweep whose held joints wander
//! scatters its radius), or whose centre's distance to every other experiment's centre is off the description's by
//! more than [`SPREAD_WARNING`]` - 1` (a quarter) of the robot's size (the largest distance
//! between the described centres) while the others agree among themselves, is out of place: a
//! robot within its drawing's tolerances is off by millimetres, a column in centimetres by
//! metres. Its column is named when one of its coordinate columns multiplied into millimetres
//! ([`LENGTH_UNITS`]) puts the experiment in place, or two of its columns exchanged do.

use super::arcs::{ExperimentArc, arc_of};
use super::{LENGTH_UNITS, MAX_SCATTER_GROWTH, SPREAD_WARNING, UnitSlip};
use crate::measurement::{Measurement, format_f64};
use nalgebra::Point3;

/// The coordinate columns, in order.
const COLUMNS: [&str; 3] = ["x_mm", "y_mm", "z_mm"];

/// The fewest experiments with a described centre for the centres to be compared: with two,
/// the one distance between them cannot say which is out of place.
const MIN_PLACED: usize = 3;

/// The largest distance \[mm\] between two experiments' described centres.
fn size_mm(arcs: &[ExperimentArc]) -> f64 {
    let centres: Vec<Point3<f64>> = arcs.iter().filter_map(|a| a.nominal_centre_mm).collect();
    centres
        .iter()
        .flat_map(|a| centres.iter().map(move |b| (a - b).norm()))
        .fold(0.0, f64::max)
}

/// The smallest difference \[mm\] between the measured distance from `centre` (experiment
/// `i`'s, as measured or converted) to another experiment's measured centre and the described
/// distance between their centres, over the other experiments: large only when experiment `i`
/// is off against every other one. `None` without a described centre.
fn centre_mismatch_mm(centre: &Point3<f64>, i: usize, arcs: &[ExperimentArc]) -> Option<f64> {
    let own = arcs[i].nominal_centre_mm?;
    arcs.iter()
        .enumerate()
        .filter(|(j, _)| *j != i)
        .filter_map(|(_, b)| Some(((centre - b.arc.centre).norm() - (own - b.nominal_centre_mm?).norm()).abs()))
        .min_by(f64::total_cmp)
}

/// Whether experiment `i`'s arc `arc` (as measured or converted) is in place: its radius
/// within [`SPREAD_WARNING`] of the description's or of its noise (`Arc::radius_off`) and its
/// centre within `tolerance_mm`.
fn in_place(arc: &super::arcs::Arc, i: usize, arcs: &[ExperimentArc], tolerance_mm: f64) -> bool {
    let radius = arcs[i].nominal_mm.is_none_or(|n| !arc.radius_off(n));
    radius && centre_mismatch_mm(&arc.centre, i, arcs).is_none_or(|d| d <= tolerance_mm)
}

/// Whether `arc`, experiment `i`'s points converted, fits them as their commands say: a unit
/// is named only when reading the column in it makes the data fit. The arc turns as far per
/// degree of the command as the description's robot turns it, within [`SPREAD_WARNING`], and
/// its point triples agree on one radius about as well as read ([`super::MAX_SCATTER_GROWTH`]: a
/// column in another unit draws an ellipse, which the conversion makes a circle; noise or another
/// target's readings do not become a circle by scaling a column). `growth`: how much more they
/// may scatter than as read, [`super::MAX_SCATTER_GROWTH`] for an arc out of place (its
/// conversion moves it, and may restore noise a coarser unit hid) and 1 for an arc in place but
/// of another radius, whose conversion must make its ellipse a circle: a noisy arc's radius is
/// off too, and flattening it by a column's factor fits it no better.
fn fits(arc: &super::arcs::Arc, i: usize, arcs: &[ExperimentArc], growth: f64) -> bool {
    let turn = arcs[i].nominal_turn.map_or(1.0, f64::abs);
    (arc.turn_ratio / turn).ln().abs() <= SPREAD_WARNING.ln()
        && arc.radius_scatter <= growth * arcs[i].arc.radius_scatter
}

/// Experiment `i`'s arc with each row's coordinates changed by `change`.
fn converted(i: usize, arcs: &[ExperimentArc], change: impl Fn(&mut [f64; 3])) -> Option<super::arcs::Arc> {
    let a = &arcs[i];
    let rows: Vec<Measurement> = a
        .rows
        .iter()
        .map(|m| {
            let mut m = m.clone();
            change(&mut m.position_mm);
            m
        })
        .collect();
    arc_of(&rows.iter().collect::<Vec<_>>(), a.joint - 1)
}

/// The column and length unit whose conversion of experiment `i`'s rows into millimetres puts
/// it in place ([`in_place`]).
fn column_in_other_unit(
    i: usize,
    arcs: &[ExperimentArc],
    tolerance_mm: f64,
    growth: f64,
) -> Option<(usize, f64, &'static str)> {
    (0..3)
        .flat_map(|c| LENGTH_UNITS.iter().map(move |(f, unit)| (c, *f, *unit)))
        .find(|&(c, f, _)| {
            converted(i, arcs, |p| p[c] /= f)
                .is_some_and(|arc| in_place(&arc, i, arcs, tolerance_mm) && fits(&arc, i, arcs, growth))
        })
}

/// The two coordinate columns whose exchange in experiment `i`'s rows puts it in place.
fn columns_swapped(i: usize, arcs: &[ExperimentArc], tolerance_mm: f64) -> Option<(usize, usize)> {
    [(0, 1), (0, 2), (1, 2)].into_iter().find(|&(a, b)| {
        converted(i, arcs, |p| p.swap(a, b))
            .is_some_and(|arc| in_place(&arc, i, arcs, tolerance_mm) && fits(&arc, i, arcs, MAX_SCATTER_GROWTH))
    })
}

/// What puts experiment `i` (out of place by `what`) in place: its coordinates or one of its
/// columns in another length unit, two of its columns exchanged, or (`centre_off`) a shift, said; `None` when nothing
/// explains an arc that is only of another radius.
fn explained(i: usize, arcs: &[ExperimentArc], tolerance_mm: f64, what: &str, centre_off: bool) -> Option<UnitSlip> {
    let name = &arcs[i].name;
    let every = LENGTH_UNITS.iter().find(|(f, _)| {
        converted(i, arcs, |p| p.iter_mut().for_each(|v| *v /= f))
            .is_some_and(|arc| in_place(&arc, i, arcs, tolerance_mm) && fits(&arc, i, arcs, MAX_SCATTER_GROWTH))
    });
    if let Some((f, unit)) = every {
        return Some(UnitSlip {
            field: COLUMNS.join(","),
            message: format!(
                "experiment {name}: {what}, and in place once its coordinates are multiplied by {}: this \
                 experiment's coordinates look like {unit} rather than millimetres, while the other experiments are \
                 millimetres",
                format_f64(1.0 / f)
            ),
        });
    }
    let growth = if centre_off { MAX_SCATTER_GROWTH } else { 1.0 };
    if let Some((c, f, unit)) = column_in_other_unit(i, arcs, tolerance_mm, growth) {
        return Some(UnitSlip {
            field: COLUMNS[c].into(),
            message: format!(
                "experiment {name}: {what}, and in place once its {} is multiplied by {}: this experiment's {} looks \
                 like {unit} rather than millimetres, while its other columns and the other experiments are \
                 millimetres",
                COLUMNS[c],
                format_f64(1.0 / f),
                COLUMNS[c]
            ),
        });
    }
    if let Some((p, q)) = columns_swapped(i, arcs, tolerance_mm) {
        let (p, q) = (COLUMNS[p], COLUMNS[q]);
        return Some(UnitSlip {
            field: format!("{p},{q}"),
            message: format!(
                "experiment {name}: {what}, and in place once its {p} and {q} are exchanged: this experiment's {p} and \
                 {q} look swapped"
            ),
        });
    }
    centre_off.then(|| UnitSlip {
        field: COLUMNS.join(","),
        message: format!(
            "experiment {name}: {what}: its block of rows is shifted (another instrument setup, an edit), or a column \
             of it is in other units"
        ),
    })
}

/// How far \[mm\] an experiment's centre may be off the described distances to the others' (a
/// quarter of the robot's size, module docs); unbounded with too few experiments to compare.
fn tolerance_mm(arcs: &[ExperimentArc]) -> f64 {
    let placed = arcs.iter().filter(|a| a.nominal_centre_mm.is_some()).count();
    if placed >= MIN_PLACED {
        (SPREAD_WARNING - 1.0) * size_mm(arcs)
    } else {
        f64::INFINITY
    }
}

/// Whether experiment `i`'s coordinates multiplied by `factor` put it in place among the others
/// and fit its commands ([`in_place`], [`fits`]): a scale is named only when applying it makes
/// the data fit.
pub(super) fn in_place_scaled(i: usize, arcs: &[ExperimentArc], factor: f64) -> bool {
    converted(i, arcs, |p| p.iter_mut().for_each(|v| *v *= factor))
        .is_some_and(|arc| in_place(&arc, i, arcs, tolerance_mm(arcs)) && fits(&arc, i, arcs, MAX_SCATTER_GROWTH))
}

/// The experiments out of place (module docs), each said once, and their indices into `arcs`.
/// `in_scale`: whether the file's radii as a whole match the description's (their median within
/// [`SPREAD_WARNING`]); else every experiment is off, which the whole file's check says.
pub(super) fn misplaced(arcs: &[ExperimentArc], in_scale: bool) -> (Vec<UnitSlip>, Vec<usize>) {
    if !in_scale {
        return (Vec::new(), Vec::new());
    }
    let tolerance_mm = tolerance_mm(arcs);
    let (mut slips, mut said) = (Vec::new(), Vec::new());
    for (i, a) in arcs.iter().enumerate() {
        let radius_off = !in_place(&a.arc, i, arcs, f64::INFINITY);
        let centre_off = centre_mismatch_mm(&a.arc.centre, i, arcs).filter(|d| *d > tolerance_mm);
        if !radius_off && centre_off.is_none() {
            continue;
        }
        let what = match centre_off {
            Some(d) => format!(
                "its arc's centre is {} mm off where the description puts it against every other experiment's \
                 (beyond a quarter of the robot's size, {} mm)",
                format_f64(d.round()),
                format_f64(tolerance_mm.round())
            ),
            None => format!(
                "target 0 turns on a radius of {:.4} where the description gives {:.1} mm",
                a.arc.radius,
                a.nominal_mm.unwrap_or(f64::NAN)
            ),
        };
        let Some(slip) = explained(i, arcs, tolerance_mm, &what, centre_off.is_some()) else {
            continue;
        };
        slips.push(slip);
        said.push(i);
    }
    (slips, said)
}
