//! Gross errors among the sweeps' points, found before the procedure fits them: each sweep
//! whose held joints hold still is fitted alone (the ML arc through the transmission for a rotary joint, eqs. 1-8 and 14; the
//! ML line for a sliding one, eqs. 9-13), each point's 3-D residual is tested against a fence,
//! and the worst point beyond it is set aside and its sweep refitted until none is left.
//!
//! Each sweep has its own noise: the sweeps' noise differs (the swept joint's repeatability
//! turns into more error the farther its target is), and so does its shape: a theodolite
//! pair's depth error puts most of it along one direction. The points beyond 3.12 times the
//! median distance (`(Q3 + 3 IQR) / Q2` of Gaussian 3-D errors) are set aside first, worst
//! first: gross errors, so that several do not mask each other. A point's normalised residual
//! is `|r|` over the noise per axis of the sweep's other points kept, their residuals' sum of
//! squares over the degrees of freedom the fit leaves (an externally studentised residual). The
//! fence holds a family-wise false-alarm rate, [`SWEEP_POINTS_FALSE_ALARM`] over every point
//! the file's sweeps test: with the noise spread over `m` directions (1 to 3, from the
//! residuals' scatter matrix), `z^2 / 3` is about `F(m, m nu / 3)` (Satterthwaite), and the
//! fence is its `1 - rate / points` quantile. A corrupted reading, a swapped point id or a
//! point in other units lies far beyond it; the clean rate measured is in
//! `docs/validation.md`, "Outliers".
//!
//! Then the second targets of the sweeps that measure a coupling ([`second_target`]).

mod bump;
mod rounds;
mod second_target;

pub use bump::{SWEEP_BUMP_FALSE_ALARM, SweepBump, SweepEnd, bumps_undone};

use crate::numerics::stats::median;
use rounds::too_many_which;
pub use rounds::{OUTLIER_ROUNDS_MAX, OUTLIER_SHARE_MAX, without_poses};
pub use second_target::WorstSecondTarget;

use super::experiments::actuator_commands;
use super::outlier_point::{OutlierPoint, OutlierTest, row_of};
use super::{AxisExperiment, COMMAND_TOLERANCE, CalibrationOptions, ProcedureError, axis_experiments_with};
use crate::calibration::arc_model::{ArcModel, MeasurementNoise};
use crate::calibration::line_ml::{fit_line, predict_line};
use crate::calibration::{ArcFitOptions, CalibrationError, Studies, fit_arc_with_angle_noise_studies};
use crate::kinematics::{JointKind, centroid};
use crate::measurement::MeasurementSet;
use crate::numerics::stats::{chi3_far_out_over_median, f_upper_quantile, far_out_fence};
use crate::robot::TransmissionFitForm;
use crate::robot::{Controller, RobotDescription};
use nalgebra::{Point3, Vector3};

/// The outcome of the test: the points flagged and, when some were set aside, the set
/// without their poses (every target of a flagged point's step); and the sweeps whose points
/// shift part-way through ([`SweepBump`]).
#[derive(Clone, Debug)]
pub struct Screening {
    /// The points beyond the fence, in experiment and step order.
    pub outliers: Vec<OutlierPoint>,
    /// The set without the dropped points; `None` when none was dropped.
    pub set: Option<MeasurementSet>,
    /// The sweeps whose points from one step on sit off their earlier ones, in experiment order.
    pub bumps: Vec<SweepBump>,
}

/// A sweep's points lie within about twice their median distance from their median point
/// when evenly spread (a line's end at half its length against a quarter); a point beyond this
/// many times it is a gross error, left out of the first fit when the fit on every point fails.
pub const GROSS_DISTANCE_OVER_MEDIAN: f64 = 10.0;

/// A measure of each point from the residuals of a sweep's points ([`Sweep::peel`]).
type Measure<'a> = &'a dyn Fn(&[Vector3<f64>]) -> Vec<f64>;

/// The fence from the measures of the points kept ([`Sweep::peel`]).
type Fence<'a> = &'a dyn Fn(&[f64]) -> f64;

/// The residuals of the fit without the first point where [`Sweep::peel`] sets it aside first:
/// from the points kept, their fit's residuals and the measure it must exceed.
type Lead<'a> = &'a dyn Fn(&[usize], &[Vector3<f64>], f64) -> Option<Vec<Vector3<f64>>>;

/// One sweep's target-0 points and its joint's actuator command at each.
struct Sweep<'a> {
    experiment: &'a AxisExperiment,
    kind: JointKind,
    form: TransmissionFitForm,
    points: Vec<Point3<f64>>,
    u: Vec<f64>,
}

/// Tests the target-0 points of every sweep of `set` (module doc). With `keep` the points are
/// flagged as they would be dropped, but none is. A sweep whose fit fails is left to the
/// procedure, which says why; a sweep with more than [`OUTLIER_SHARE_MAX`] of its points, or
/// more than [`OUTLIER_ROUNDS_MAX`], beyond the fence is an error naming it.
pub fn screen_sweeps(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
    keep: bool,
) -> Result<Screening, ProcedureError> {
    let (experiments, _) = axis_experiments_with(set, desc, options.held_tolerance)?;
    let controller = Controller::from_description(desc);
    let sweeps: Vec<Sweep<'_>> = experiments.iter().map(|e| Sweep::new(e, desc, &controller)).collect();
    let sigma = options.noise_rms_3d_mm * 1e-3 / 3f64.sqrt();
    let max_iterations = options.max_iterations;
    let fits = FirstFits::of(&sweeps, Sweep::holds_still, (sigma, max_iterations));
    let pooled: Vec<f64> = fits
        .scales
        .iter()
        .flatten()
        .flat_map(|s| s.kept_z.iter().copied())
        .collect();
    if pooled.len() < 8 {
        return Ok(Screening {
            outliers: vec![],
            set: None,
            bumps: vec![],
        });
    }
    // The second targets keep their fence: Tukey's far-out fence of the sweeps' points.
    let second_fence = far_out_fence(&pooled);
    let mut outliers = Vec::new();
    let mut peeled = Vec::new();
    for index in 0..sweeps.len() {
        match fits.test(&sweeps, index, (set, keep), (sigma, max_iterations)) {
            None => {}
            Some(SweepTest::TooMany(e)) => return Err(e),
            Some(SweepTest::Tested(flagged, p)) => {
                outliers.extend(flagged);
                peeled.push(p);
            }
        }
    }
    let first_pass = without_poses(set, &outliers);
    let second = second_target::outliers(
        first_pass.as_ref().unwrap_or(set),
        set,
        desc,
        options,
        (second_fence, keep),
    )?;
    outliers.extend(second);
    let bumps = sweep_bumps(&sweeps, &peeled, set, (sigma, max_iterations));
    let set = without_poses(set, &outliers);
    Ok(Screening { outliers, set, bumps })
}

/// The test of the sweeps of `set` whose held joints wander, which [`screen_sweeps`] does not
/// test: their points moved to the design pose by the calibrated model of `cal` as the
/// procedure moves them (`held.rs`, `p' = W_L(q_design) W_L(q_recorded)^-1 p`), then tested as
/// [`screen_sweeps`] tests a still sweep's (the fence's family-wise rate over these sweeps'
/// points, their bumps' over these sweeps' blocks). A gross error moves its point as much once
/// moved; the wander the model leaves unexplained moves every point of the sweep a little, and
/// the fence is the sweep's own noise. A sweep with more points beyond the fence than a sweep
/// may lose is left to the procedure's misfit warning (the model, not its points, may be wrong
/// there). The bumps' shift is in the design pose's frame, which the wander turns from the
/// instrument's by the held joints' wander only (a tenth of a degree turns a 2 mm shift by
/// under 4 um). `set` of the screening is the rows kept: `set` less the poses of the points
/// dropped (none with `keep`).
pub fn screen_wandering_sweeps(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
    cal: &super::Calibration,
    keep: bool,
) -> Screening {
    let none = Screening {
        outliers: vec![],
        set: None,
        bumps: vec![],
    };
    let Ok((experiments, _)) = axis_experiments_with(set, desc, options.held_tolerance) else {
        return none;
    };
    let controller = Controller::from_description(desc);
    let corrector = super::held::Corrector {
        model: &cal.robot,
        controller: &controller,
        desc,
        reference_cmd: &cal.reference_cmd,
    };
    let sigma = options.noise_rms_3d_mm * 1e-3 / 3f64.sqrt();
    let sweeps: Vec<Sweep<'_>> = experiments
        .iter()
        .map(|e| {
            let mut s = Sweep::new(e, desc, &controller);
            s.points = match s.holds_still() {
                true => vec![],
                false => corrector.corrected(e, 0).unwrap_or_default(),
            };
            s
        })
        .collect();
    let fits = FirstFits::of(&sweeps, |s| !s.points.is_empty(), (sigma, options.max_iterations));
    let mut outliers = Vec::new();
    let mut peeled = Vec::new();
    for (index, s) in sweeps.iter().enumerate() {
        match fits.test(&sweeps, index, (set, keep), (sigma, options.max_iterations)) {
            Some(SweepTest::Tested(flagged, p)) => {
                outliers.extend(flagged.into_iter().map(|o| OutlierPoint {
                    test: OutlierTest::Moved,
                    ..o
                }));
                peeled.push(p);
            }
            // Untested, or the model rather than the points: the bumps read every point.
            Some(SweepTest::TooMany(_)) | None => {
                let Some(last) = fits.first[index].clone() else {
                    continue;
                };
                peeled.push(Peeled {
                    index,
                    kept: all(s),
                    last,
                });
            }
        }
    }
    let bumps = sweep_bumps(&sweeps, &peeled, set, (sigma, options.max_iterations));
    let set = without_poses(set, &outliers);
    Screening { outliers, set, bumps }
}

/// The bumps of [`screen_wandering_sweeps`] (its outliers not dropped).
pub fn wandering_sweep_bumps(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &CalibrationOptions,
    cal: &super::Calibration,
) -> Vec<SweepBump> {
    screen_wandering_sweeps(set, desc, options, cal, true).bumps
}

/// The first fits of the sweeps a screen tests: each one's residuals from the fit of every
/// point ([`Sweep::first_residuals`]) and its noise ([`Scale`]), `None` for a sweep not tested.
struct FirstFits {
    first: Vec<Option<Vec<Vector3<f64>>>>,
    scales: Vec<Option<Scale>>,
    /// The points of the sweeps with a scale: the family the fence's false-alarm rate covers.
    tested: usize,
}

/// What the test of one sweep found ([`FirstFits::test`]).
enum SweepTest {
    /// The points flagged and the sweep's points kept with the residuals of their fit.
    Tested(Vec<OutlierPoint>, Peeled),
    /// More points beyond the fence than a sweep may lose: the error naming them.
    TooMany(ProcedureError),
}

impl FirstFits {
    /// The first fits of the `sweeps` that pass `tested`.
    fn of<'a>(
        sweeps: &[Sweep<'a>],
        tested: impl Fn(&Sweep<'a>) -> bool,
        (sigma, max_iterations): (f64, usize),
    ) -> Self {
        let first: Vec<Option<Vec<Vector3<f64>>>> = sweeps
            .iter()
            .map(|s| tested(s).then(|| s.first_residuals(sigma, max_iterations)).flatten())
            .collect();
        let scales: Vec<Option<Scale>> = sweeps
            .iter()
            .zip(&first)
            .map(|(s, r)| Scale::of(s, r.as_ref()?, sigma, max_iterations))
            .collect();
        let tested = scales.iter().flatten().map(|t| t.points).sum();
        FirstFits { first, scales, tested }
    }

    /// The test of sweep `sweeps[index]`: its points beyond the fence set aside worst first
    /// ([`Sweep::peel`]), flagged as dropped unless `keep`, their lines read in `set`; `None`
    /// for a sweep untested or with too few degrees of freedom to test.
    fn test(
        &self,
        sweeps: &[Sweep<'_>],
        index: usize,
        (set, keep): (&MeasurementSet, bool),
        (sigma, max_iterations): (f64, usize),
    ) -> Option<SweepTest> {
        let (s, r, scale) = (
            &sweeps[index],
            self.first[index].as_ref()?,
            self.scales[index].as_ref()?,
        );
        let fence = scale.fence(self.tested)?;
        let z = |v: &[Vector3<f64>]| -> Vec<f64> { v.iter().enumerate().map(|(i, r)| scale.z(i, r)).collect() };
        let led = std::cell::Cell::new(false);
        let lead = |kept: &[usize], e: &[Vector3<f64>], bar: f64| {
            let d = s.first_point_lead((kept, e), &|v| scale.z(0, v), (fence, bar), (sigma, max_iterations));
            led.set(led.get() || d.is_some());
            d
        };
        let (kept, last) = s.peel(r, (&z, &|_| fence), &lead, sigma, max_iterations);
        let first_led = led.get();
        let mut is_kept = vec![false; s.points.len()];
        kept.iter().for_each(|&i| is_kept[i] = true);
        let flagged: Vec<usize> = (0..s.points.len()).filter(|&i| !is_kept[i]).collect();
        // Points still beyond the fence once the rounds are spent: as many more outliers.
        let beyond = kept.iter().filter(|&&i| scale.z(i, &last[i]) > fence).count();
        if beyond > 0 || flagged.len() as f64 > OUTLIER_SHARE_MAX * s.points.len() as f64 {
            let mut off: Vec<usize> = kept.iter().copied().filter(|&i| scale.z(i, &last[i]) > fence).collect();
            off.extend(&flagged);
            off.sort_unstable();
            let at = |i: usize| {
                let o = s.outlier(i, &last[i], scale.z(i, &last[i]), fence, false, set);
                (i, o.step, o.line)
            };
            return Some(SweepTest::TooMany(ProcedureError::TooManyOutliers {
                experiment: s.experiment.name.clone(),
                flagged: off.len(),
                points: s.points.len(),
                fence,
                which: too_many_which(&off.into_iter().map(at).collect::<Vec<_>>()),
            }));
        }
        let outliers = flagged
            .into_iter()
            .map(|i| {
                let mut o = s.outlier(i, &last[i], scale.z(i, &last[i]), fence, !keep, set);
                o.approach = match first_led && i == 0 {
                    true => s.lead(&last[0]),
                    false => s.approach(i, &last[i], &|r| scale.z(i, r), fence),
                };
                o
            })
            .collect();
        Some(SweepTest::Tested(outliers, Peeled { index, kept, last }))
    }
}

/// A tested sweep's points kept by the outlier test and every point's residual from their fit.
struct Peeled {
    /// The sweep's index.
    index: usize,
    kept: Vec<usize>,
    last: Vec<Vector3<f64>>,
}

/// The sweeps of `peeled` whose kept points shift part-way through ([`bump`]: a change point
/// of their residuals, confirmed by fitting the sweep again with the block moved back); a
/// sweep with none, whose first or last [`bump::END_BUMP_POINTS`] sit off its others
/// ([`bump::best_end`]), tested the same way over the ends tried in the file's sweeps.
fn sweep_bumps(
    sweeps: &[Sweep<'_>],
    peeled: &[Peeled],
    set: &MeasurementSet,
    (sigma, max_iterations): (f64, usize),
) -> Vec<SweepBump> {
    let refits_of = |p: &Peeled| {
        let s = &sweeps[p.index];
        let kept = p.kept.clone();
        move |blocks: &[(usize, Vector3<f64>)]| s.refit_moved(&kept, blocks, (sigma, max_iterations))
    };
    let refit_of = |p: &Peeled| {
        let refits = refits_of(p);
        move |start: usize, shift: &Vector3<f64>| refits(&[(start, *shift)])
    };
    let found: Vec<_> = peeled
        .iter()
        .map(|p| bump::best_start(&p.kept_residuals(), &refit_of(p)))
        .collect();
    let ends: Vec<_> = peeled
        .iter()
        .map(|p| bump::best_end(&p.kept_residuals(), &refit_of(p)))
        .collect();
    let tried: usize = found.iter().flatten().map(|c| c.1).sum();
    let ends_tried: usize = ends.iter().flatten().map(|c| c.1).sum();
    // Each sweep's residual variance as written and its degrees of freedom.
    let variances: Vec<(f64, f64)> = peeled
        .iter()
        .map(|p| {
            let dof = p.dof(&sweeps[p.index]);
            (
                p.kept_residuals().iter().map(|v| v.norm_squared()).sum::<f64>() / dof,
                dof,
            )
        })
        .collect();
    let mut bumps = Vec::new();
    for (p, i) in peeled.iter().zip(0..) {
        let (x, dof) = (p.kept_residuals(), p.dof(&sweeps[p.index]));
        let noisiest_other = (0..variances.len())
            .filter(|&j| j != i)
            .map(|j| variances[j])
            .max_by(|a, b| a.0.total_cmp(&b.0));
        // A change point that passes both tests, or else an end that does (over the ends).
        let passes = |candidate: &Option<(bump::Bumped, usize)>, tried: usize| {
            let (found, _) = candidate.as_ref()?;
            let p_value = bump::confirmed(&x, found, (dof, 1), tried)?;
            bump::explains(found, (dof, 1), noisiest_other, tried).then_some((*found, p_value, tried))
        };
        // Two change points, where none alone passes and the sweep as written misfits: both
        // tested together, over the pairs tried.
        let twice = || {
            let (first, _) = found[i].as_ref()?;
            let written = bump::Bumped {
                sum_sq: x.iter().map(|v| v.norm_squared()).sum(),
                ..*first
            };
            if bump::explains(&written, (dof, 0), noisiest_other, tried) {
                return None;
            }
            let ([first, second], more) = bump::second_start(&x, first, &refits_of(p))?;
            let pairs = tried * more;
            let p_value = bump::confirmed(&x, &second, (dof, 2), pairs)?;
            bump::explains(&second, (dof, 2), noisiest_other, pairs)
                .then_some([(first, p_value, pairs), (second, p_value, pairs)])
        };
        let (chosen, end) = match passes(&found[i], tried) {
            Some(c) => (c, false),
            None => match (twice(), passes(&ends[i], ends_tried)) {
                (Some(two), _) => {
                    bumps.extend(p.two_bumps(&sweeps[p.index], two, set));
                    continue;
                }
                (None, Some(c)) => (c, true),
                (None, None) => continue,
            },
        };
        bumps.push(p.bump(&sweeps[p.index], chosen, (end, 1), set));
    }
    bumps
}

impl Peeled {
    /// The residuals of the points kept.
    fn kept_residuals(&self) -> Vec<Vector3<f64>> {
        self.kept.iter().map(|&k| self.last[k]).collect()
    }

    /// The degrees of freedom of the fit of the points kept of sweep `s`.
    fn dof(&self, s: &Sweep<'_>) -> f64 {
        (3 * self.kept.len()) as f64 - s.parameters() as f64
    }

    /// The bumps of sweep `s` shifted at two steps (`two`: each change point with the pair's
    /// p-value and the pairs tried), in step order, each naming the other's step.
    fn two_bumps(&self, s: &Sweep<'_>, two: [(bump::Bumped, f64, usize); 2], set: &MeasurementSet) -> [SweepBump; 2] {
        let [a, b] = two.map(|found| self.bump(s, found, (false, 2), set));
        let (a_step, b_step) = (a.step, b.step);
        let mut two = [
            SweepBump {
                beside: Some(b_step),
                ..a
            },
            SweepBump {
                beside: Some(a_step),
                ..b
            },
        ];
        two.sort_by_key(|b| b.step);
        two
    }

    /// The bump of sweep `s` (these its points kept) at the change point `found` (its
    /// `sum_sq` with every block moved back), with its p-value and the blocks tried; with
    /// `end`, its block an end's ([`bump::SweepEnd`]); `blocks` moved back in the sweep (1, or
    /// 2 where it shifts twice).
    fn bump(
        &self,
        s: &Sweep<'_>,
        (found, p_value, tried): (bump::Bumped, f64, usize),
        (end, blocks): (bool, usize),
        set: &MeasurementSet,
    ) -> SweepBump {
        let (x, dof) = (self.kept_residuals(), self.dof(s));
        let (start, shift, undone) = (found.start, found.shift, found.sum_sq);
        let written: f64 = x.iter().map(|v| v.norm_squared()).sum();
        let sigma_m = found.unit_sigma * (undone / (dof - 3.0 * blocks as f64)).sqrt();
        let (step, line) = s.step_line(self.kept[start], set);
        let rms = |sum_sq: f64| (sum_sq / (3 * self.kept.len()) as f64).sqrt() * 1e3;
        let end = end.then(|| {
            let first = start < self.kept.len() - start;
            let which = if first {
                &self.kept[..start]
            } else {
                &self.kept[start..]
            };
            bump::SweepEnd {
                first,
                points: which.iter().map(|&k| s.step_line(k, set)).collect(),
            }
        });
        SweepBump {
            experiment: s.experiment.name.clone(),
            joint: s.experiment.joint,
            step,
            line,
            points: self.kept.len() - start,
            tested: self.kept.len(),
            shift_mm: [shift.x * 1e3, shift.y * 1e3, shift.z * 1e3],
            shift_sigma_mm: std::array::from_fn(|c| sigma_m[c] * 1e3),
            p_value,
            blocks_tried: tried,
            rms_mm: (rms(written), rms(undone)),
            beside: None,
            end,
        }
    }
}

/// Every point of `s`.
fn all(s: &Sweep<'_>) -> Vec<usize> {
    (0..s.points.len()).collect()
}

/// The family-wise false-alarm rate of the sweep points' test over a whole file: on clean data
/// about this share of files has a point flagged (`Scale::fence`; measured in
/// `docs/validation.md`, "Outliers").
pub const SWEEP_POINTS_FALSE_ALARM: f64 = 0.01;

/// A sweep's noise, from the residuals of its points within [`chi3_far_out_over_median`]
/// times their median (gross errors set aside, worst first, so that several in one sweep do
/// not mask each other).
struct Scale {
    /// Points tested.
    points: usize,
    /// The normalised residuals of the points kept, over their RMS per axis (the second
    /// targets' fence).
    kept_z: Vec<f64>,
    /// The sum of the kept points' squared residuals \[m^2\].
    sum_sq: f64,
    /// Its degrees of freedom: three per point kept, less the fit's parameters.
    dof: f64,
    /// Each point's squared residual in that sum (`None`: set aside) \[m^2\].
    own: Vec<Option<f64>>,
    /// The directions the noise spreads over (1 to 3): `tr(S)^2 / tr(S^2)` of the kept
    /// residuals' scatter matrix `S` (Satterthwaite's effective degrees of freedom).
    spread: f64,
}

impl Scale {
    /// The scale of sweep `s` from its residuals `first` (every point fitted).
    fn of(s: &Sweep<'_>, first: &[Vector3<f64>], sigma: f64, max_iterations: usize) -> Option<Scale> {
        let ratio = chi3_far_out_over_median();
        let norms = |v: &[Vector3<f64>]| -> Vec<f64> { v.iter().map(|r| r.norm()).collect() };
        let fence = |kept: &[f64]| ratio * median(kept);
        let (kept, last) = s.peel(first, (&norms, &fence), &|_, _, _| None, sigma, max_iterations);
        let mut own = vec![None; s.points.len()];
        kept.iter().for_each(|&i| own[i] = Some(last[i].norm_squared()));
        let sum_sq: f64 = own.iter().flatten().sum();
        let rms = (sum_sq / (3 * kept.len()).max(1) as f64).sqrt();
        let scatter: nalgebra::Matrix3<f64> = kept.iter().map(|&i| last[i] * last[i].transpose()).sum();
        let spread = (scatter.trace().powi(2) / scatter.norm_squared()).clamp(1.0, 3.0);
        (rms > 0.0).then(|| Scale {
            points: s.points.len(),
            kept_z: kept.iter().map(|&i| last[i].norm() / rms).collect(),
            sum_sq,
            dof: (3 * kept.len()) as f64 - s.parameters() as f64,
            own,
            spread,
        })
    }

    /// The normalised residual of point `i`: `|r|` over the noise per axis of the sweep's
    /// other points kept, their sum of squares over its degrees of freedom (an externally
    /// studentised residual; about `sqrt 3` for a point of the noise).
    fn z(&self, i: usize, r: &Vector3<f64>) -> f64 {
        let (sum, dof) = match self.own[i] {
            Some(own) => (self.sum_sq - own, self.dof - 3.0),
            None => (self.sum_sq, self.dof),
        };
        r.norm() / (sum.max(0.0) / dof).sqrt()
    }

    /// The fence for a file whose sweeps test `tested` points: a point of the noise passes it
    /// with probability `1 - SWEEP_POINTS_FALSE_ALARM / tested`. With the noise spread over
    /// `m` directions (`spread`), `z^2 / 3` is about `F(m, m nu / 3)` for the `nu` degrees of
    /// freedom of the other points (Satterthwaite): `m = 3` isotropic, `m = 1` all along one
    /// direction, the heaviest tail. `None`: too few degrees of freedom to test.
    fn fence(&self, tested: usize) -> Option<f64> {
        let nu = self.dof - 3.0;
        (nu >= 1.0).then(|| {
            let tail = SWEEP_POINTS_FALSE_ALARM / tested.max(1) as f64;
            (3.0 * f_upper_quantile(tail, self.spread, self.spread * nu / 3.0)).sqrt()
        })
    }
}

impl<'a> Sweep<'a> {
    fn new(e: &'a AxisExperiment, desc: &RobotDescription, controller: &Controller) -> Self {
        let k = e.joint - 1;
        Sweep {
            experiment: e,
            kind: desc.joints[k].kind,
            form: desc.joints[k].transmission_fit_form(),
            points: e.target0_m.clone(),
            u: e.target0_steps
                .iter()
                .map(|&i| actuator_commands(controller, desc, &e.commands[i])[k])
                .collect(),
        }
    }

    /// The parameters of its fit: an arc's centre, axis, radius and phase (7), a line's start
    /// and direction (5), and the transmission's coefficients.
    fn parameters(&self) -> usize {
        let path = match self.kind {
            JointKind::Revolute => 7,
            JointKind::Prismatic => 5,
        };
        path + self.form.n_coefficients()
    }

    /// Whether every held joint's reading stays within [`COMMAND_TOLERANCE`] through the sweep:
    /// else its points are not on one arc or line as measured (the procedure corrects them for
    /// the wander with the model it fits), and the sweep is not tested.
    fn holds_still(&self) -> bool {
        let e = self.experiment;
        let first = &e.commands[0];
        (0..first.len())
            .filter(|&j| e.holds_constant(j))
            .all(|j| e.commands.iter().all(|c| (c[j] - first[j]).abs() <= COMMAND_TOLERANCE))
    }

    /// The residual \[m\] of every point of the sweep against its fit on the points `kept`,
    /// with the transmission lowered as [`super::axis_fit`] lowers it when the description's
    /// order is not invertible over the sweep.
    fn residuals(
        &self,
        kept: &[usize],
        sigma: f64,
        max_iterations: usize,
    ) -> Result<Vec<Vector3<f64>>, CalibrationError> {
        let mut form = self.form;
        loop {
            match self.residuals_as(form, kept, sigma, max_iterations) {
                Err(CalibrationError::NotInvertible { .. }) if form.order() > 0 => {
                    form = form.one_order_lower().unwrap_or(form);
                }
                other => return other,
            }
        }
    }

    fn residuals_as(
        &self,
        form: TransmissionFitForm,
        kept: &[usize],
        sigma: f64,
        max_iterations: usize,
    ) -> Result<Vec<Vector3<f64>>, CalibrationError> {
        let points: Vec<Point3<f64>> = kept.iter().map(|&i| self.points[i]).collect();
        let u: Vec<f64> = kept.iter().map(|&i| self.u[i]).collect();
        if u.is_empty() {
            return Err(CalibrationError::TooFewPoints {
                fit: "outlier test",
                got: 0,
                needed: 1,
            });
        }
        // Every point's command after the first kept one: the fits measure motion from it.
        let mut commands = vec![u[0]];
        commands.extend_from_slice(&self.u);
        let predicted = match self.kind {
            JointKind::Revolute => {
                let noise = MeasurementNoise::Isotropic { sigma_per_axis: sigma };
                let options = ArcFitOptions {
                    form,
                    noise: noise.clone(),
                    reference_point: centroid(&points),
                    max_iterations,
                };
                let fit = fit_arc_with_angle_noise_studies(&points, &u, &options, 0.0, Studies::Skip)?;
                ArcModel::new(form, &commands, &noise)?.predict(&fit.params)?
            }
            JointKind::Prismatic => {
                let fit = fit_line(&points, &u, &form, sigma, 0.0, max_iterations)?;
                predict_line(&form, &fit.params, &commands)?
            }
        };
        Ok(self.points.iter().zip(&predicted[1..]).map(|(p, q)| p - q).collect())
    }

    /// The residuals of every point against the fit on all of them or, when that fit fails
    /// (a point kilometres off breaks it), on the points within [`GROSS_DISTANCE_OVER_MEDIAN`]
    /// times the median distance from the sweep's median point.
    fn first_residuals(&self, sigma: f64, max_iterations: usize) -> Option<Vec<Vector3<f64>>> {
        self.residuals(&all(self), sigma, max_iterations).ok().or_else(|| {
            let coordinate = |c: usize| median(&self.points.iter().map(|p| p[c]).collect::<Vec<_>>());
            let middle = Point3::new(coordinate(0), coordinate(1), coordinate(2));
            let distance: Vec<f64> = self.points.iter().map(|p| (p - middle).norm()).collect();
            let limit = GROSS_DISTANCE_OVER_MEDIAN * median(&distance);
            let near: Vec<usize> = (0..self.points.len()).filter(|&i| distance[i] <= limit).collect();
            (near.len() < self.points.len())
                .then(|| self.residuals(&near, sigma, max_iterations).ok())
                .flatten()
        })
    }

    /// Sets aside, worst first by `measure`, the points whose measure exceeds `fence(measures
    /// of the points kept)` and refits: the points kept and the residuals of the last fit
    /// (`first`: those of the fit with every point). Before each round `lead` (the points kept,
    /// their fit's residuals, the worst measure or the fence if larger) may set the sweep's
    /// first point aside instead, with the residuals of the fit without it
    /// ([`Self::first_point_lead`]).
    fn peel(
        &self,
        first: &[Vector3<f64>],
        (measure, fence): (Measure<'_>, Fence<'_>),
        lead: Lead<'_>,
        sigma: f64,
        max_iterations: usize,
    ) -> (Vec<usize>, Vec<Vector3<f64>>) {
        let mut kept = all(self);
        let mut residuals = first.to_vec();
        let most = ((OUTLIER_SHARE_MAX * self.points.len() as f64).floor() as usize + 1).min(OUTLIER_ROUNDS_MAX);
        for _ in 0..most {
            let m = measure(&residuals);
            let Some(&worst) = kept.iter().max_by(|&&a, &&b| m[a].total_cmp(&m[b])) else {
                break;
            };
            let kept_m: Vec<f64> = kept.iter().map(|&i| m[i]).collect();
            let bar = fence(&kept_m);
            if let Some(without_first) = lead(&kept, &residuals, m[worst].max(bar)) {
                kept.retain(|&i| i != 0);
                residuals = without_first;
                continue;
            }
            if m[worst] <= bar {
                break;
            }
            kept.retain(|&i| i != worst);
            match self.residuals(&kept, sigma, max_iterations) {
                Ok(r) => residuals = r,
                Err(_) => break,
            }
        }
        (kept, residuals)
    }

    /// The residuals of the fit without the sweep's first point, where that point (still among
    /// the points `kept`, `e` their fit's residuals), taken before its joint moved, runs ahead
    /// of the fit of the others along the motion (toward the second point,
    /// [`Self::first_motion`]), its studentised residual beyond `bar` (the fence, or the worst
    /// point's measure if larger: the point set aside is the worst) and its studentised part
    /// across the motion within `fence` (`z`: a residual over the noise of the other points);
    /// `None` otherwise. A backlash lead moves only the first point, but a transmission with a
    /// harmonic bends toward an end point (its leverage is large), so that its residual from
    /// the fit of every point shrinks and its neighbours' grow: tested that way, a clean
    /// neighbour is blamed and the first point kept. The studentised residual (Cook and
    /// Weisberg, *Residuals and Influence in Regression*, 1982, ch. 2) is
    /// `sqrt(e^T (I - H)^-1 e)` for the point's residual `e` from the fit with it and its
    /// leverage `H`; with its residual `d` from the fit without it, `e = (I - H) d`, so it is
    /// `sqrt(e . d)` and needs no Jacobian. A clean first point has the law the fence assumes.
    fn first_point_lead(
        &self,
        (kept, e): (&[usize], &[Vector3<f64>]),
        z: &dyn Fn(&Vector3<f64>) -> f64,
        (fence, bar): (f64, f64),
        (sigma, max_iterations): (f64, usize),
    ) -> Option<Vec<Vector3<f64>>> {
        let (t, _) = self.first_motion().filter(|_| kept.first() == Some(&0))?;
        let deleted = self.residuals(&kept[1..], sigma, max_iterations).ok()?;
        let (e, d) = (e[0], deleted[0]);
        let one = |x: f64| z(&Vector3::new(x.max(0.0).sqrt(), 0.0, 0.0));
        // Across the motion, studentised the same way: the fit of the others extrapolates to
        // the first point, and its circle's radius and plane are uncertain there.
        let across = (e - t * e.dot(&t)).dot(&(d - t * d.dot(&t)));
        let lead = one(e.dot(&d)) > bar && d.dot(&t) > 0.0 && one(across) <= fence;
        lead.then_some(deleted)
    }

    /// The unit direction from the sweep's first point to its second and the path's length per
    /// unit of command between them, where the first point is the experiment's first step (taken
    /// before its joint moved); `None` otherwise.
    fn first_motion(&self) -> Option<(Vector3<f64>, f64)> {
        let first = self.experiment.target0_steps.first() == Some(&0);
        if !first || self.points.len() < 2 {
            return None;
        }
        let chord = self.points[1] - self.points[0];
        let du = (self.u[1] - self.u[0]).abs();
        (du > 0.0).then_some((chord.try_normalize(1e-12)?, chord.norm() / du))
    }

    /// The joint's turn (a sliding joint's travel) that puts the first point where its residual
    /// `r` \[m\] says, ahead along the motion ([`Self::first_motion`]); `None` when behind.
    fn lead(&self, r: &Vector3<f64>) -> Option<f64> {
        let (t, per_unit) = self.first_motion()?;
        let along = r.dot(&t);
        (along > 0.0).then_some(along / per_unit)
    }

    /// Where point `i` (residual `r` \[m\]) is the sweep's first, taken before its joint moved
    /// (its step the experiment's first), and off its fit along the sweep's motion only (across
    /// it, `z` of what is left within `fence`), ahead toward the second point: the joint's turn
    /// (a sliding joint's travel) that puts it there, its chord's length over the commands'
    /// difference the path's length per unit. A joint with backlash sits anywhere in its band
    /// before the first move and lags on one side after it, so the first point alone runs ahead
    /// of the fit of the others by up to the band; a typo or a moved block sets it off in any
    /// direction.
    fn approach(&self, i: usize, r: &Vector3<f64>, z: &dyn Fn(&Vector3<f64>) -> f64, fence: f64) -> Option<f64> {
        let (t, _) = self.first_motion().filter(|_| i == 0)?;
        (z(&(r - t * r.dot(&t))) <= fence).then(|| self.lead(r)).flatten()
    }

    /// The residuals of the points `kept` fitted with those from `kept[start]` on moved back by
    /// `shift` \[m\], for each `(start, shift)` of `blocks`.
    fn refit_moved(
        &self,
        kept: &[usize],
        blocks: &[(usize, Vector3<f64>)],
        (sigma, max_iterations): (f64, usize),
    ) -> Option<Vec<Vector3<f64>>> {
        let mut points = self.points.clone();
        for (start, shift) in blocks {
            kept[*start..].iter().for_each(|&k| points[k] -= shift);
        }
        let moved = Sweep {
            points,
            u: self.u.clone(),
            ..*self
        };
        let r = moved.residuals(kept, sigma, max_iterations).ok()?;
        Some(kept.iter().map(|&k| r[k]).collect())
    }

    /// The step of point `i` and the line of its row in `set`, when known.
    fn step_line(&self, i: usize, set: &MeasurementSet) -> (usize, Option<u64>) {
        let e = self.experiment;
        let step = e.steps[e.target0_steps[i]];
        let row = set
            .rows()
            .iter()
            .position(|m| m.experiment == e.name && m.step == step && m.target == 0);
        (step, row.and_then(|r| set.line_of(r)))
    }

    fn outlier(
        &self,
        i: usize,
        residual_m: &Vector3<f64>,
        z: f64,
        fence: f64,
        dropped: bool,
        set: &MeasurementSet,
    ) -> OutlierPoint {
        let e = self.experiment;
        let mut o = OutlierPoint {
            experiment: e.name.clone(),
            joint: e.joint,
            step: e.steps[e.target0_steps[i]],
            target: 0,
            line: None,
            residual_mm: residual_m.norm() * 1e3,
            normalised_residual: z,
            fence,
            dropped,
            approach: None,
            test: OutlierTest::Screen,
        };
        o.line = row_of(set, &o).and_then(|row| set.line_of(row));
        o
    }
}

#[cfg(test)]
mod tests {
    use super::too_many_which;

    /// Points in one run of steps are the sweep's; points apart are single rows, named by line.
    #[test]
    fn a_run_is_the_sweep_and_rows_apart_are_named() {
        let run = too_many_which(&[(4, 5, Some(60)), (5, 6, Some(61)), (6, 7, Some(62)), (7, 8, Some(63))]);
        assert!(
            run.contains("one run of consecutive steps") && run.contains("the sweep, not single points"),
            "{run}"
        );
        let apart = too_many_which(&[
            (1, 1, Some(36)),
            (10, 11, Some(46)),
            (13, 14, Some(49)),
            (14, 15, Some(50)),
        ]);
        assert!(apart.contains("lines 36, 46, 49, 50, steps 1, 11, 14, 15"), "{apart}");
        assert!(
            apart.contains("single rows") && !apart.contains("not single points"),
            "{apart}"
        );
        let unread = too_many_which(&[(1, 1, None), (9, 9, None)]);
        assert!(unread.contains("(steps 1, 9)"), "{unread}");
    }
}
