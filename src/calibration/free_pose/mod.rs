//! Calibration from free poses: a robot measured at configurations anywhere in its workspace,
//! one or more targets on its last link, the joints read back (the "aggregate" family the paper
//! sets the independent-axis method against; `docs/method.md`, "Calibration from free poses").
//!
//! A pipeline of stages, each a typed, immutable value:
//! 1. [`FreePoses`]: the file's `moved_joint = 0` poses (commands, points by target);
//! 2. [`register`]: the instrument frame and the targets on the last link in closed form from
//!    the nominal kinematics, again without the gross poses (`gross.rs`: far beyond every other
//!    pose's misfit), which sit out the fits and are tested at the end as poses outside the fit;
//! 3. the nominal model registered: base and targets refined by least squares (the baseline
//!    every geometric calibration is compared with);
//! 4. [`identify`]: which parameters of [`model::layout`] the poses identify, the others named
//!    with the combination they are made of;
//! 5. the fit of the identified parameters (Levenberg-Marquardt, analytic Jacobian), refitted
//!    without the poses the outlier test flags, the harmonic order chosen by cross-validation;
//! 6. the plausibility check, the covariance, the noise estimate and, with a held-out split,
//!    the check on poses the fit did not see.
//!
//! Several setups (the instrument moved) share everything but the base.
//!
//! Pure maths: no files, no CLI, no simulator.

pub mod block;
mod effects;
mod error;
mod fit;
mod gross;
pub mod identify;
pub mod model;
pub mod poses;
pub mod register;
mod report;
mod scales;
pub mod slip;
mod summary;
#[cfg(test)]
mod tests;

pub use error::{FreePoseError, MIN_POSES};
pub use identify::{Identification, Unidentified};
pub use model::{FreePoseModel, layout};
pub use poses::{FreePose, FreePoses};
pub use report::markdown;
pub use scales::{ColumnScale, NamedScale};
pub use summary::{
    EffectJoint, EffectTrial, FreePoseCalibration, FreePoseSummary, Holdout, OutlierPose, ParameterEstimate,
    SetupPlacement, TargetEstimate,
};

use crate::calibration::refine::RefitParameter;
use crate::measurement::MeasurementSet;
use crate::numerics::lsq::LsqError;
use crate::robot::{Controller, RobotDescription, RobotModel};
use fit::{Fitted, Problem};
use nalgebra::{DMatrix, Isometry3};

// Outlier rounds at most (each refits without the poses flagged so far), and the fraction of
// the poses that may be dropped as outliers (beyond it the model, not the poses, is wrong):
// those of every outlier test.
use crate::numerics::outlier_rounds::{OUTLIER_ROUNDS, OUTLIER_SHARE_MAX};

/// Options of [`calibrate_free_poses`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreePoseOptions {
    /// Flag outliers but keep them in the fit.
    pub keep_outliers: bool,
    /// Fit on the even configurations only and report the odd ones as held out.
    pub holdout: bool,
    /// Take every row as a free pose, the axis experiments' too: for data whose every target
    /// sits on the last link (a sweep is then a set of poses like any other).
    pub all_rows: bool,
    /// Transmission harmonics tried up to this order (the order kept is the one that predicts
    /// held-out configurations best, [`CV_FOLDS`]-fold cross-validation).
    pub max_harmonic_order: usize,
    /// Try the non-geometric effects in the model (sag under gravity, backlash) and keep the
    /// set that predicts held-out configurations best ([`EffectTrial`]).
    pub effects: bool,
    /// Free poses fitted at most, evenly spaced through the file (the design's memory grows
    /// with them); [`FreePoseSummary::poses_left_out`] counts the others.
    pub max_poses: usize,
}

impl Default for FreePoseOptions {
    fn default() -> Self {
        FreePoseOptions {
            keep_outliers: false,
            holdout: false,
            all_rows: false,
            max_harmonic_order: 2,
            effects: true,
            max_poses: crate::measurement::bounded::FIT_MAX_POSES,
        }
    }
}

/// Calibrates the robot of `desc` from the free poses of `set` (module docs).
pub fn calibrate_free_poses(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &FreePoseOptions,
) -> Result<FreePoseCalibration, FreePoseError> {
    let poses = FreePoses::from_set_at_most(set, desc, options.all_rows, options.max_poses)?;
    let controller = Controller::from_description(desc);
    let nominal = RobotModel {
        name: format!("{} (calibrated from free poses)", desc.name),
        ..model::with_fit_forms(RobotModel::ideal(desc), desc)
    };
    let (train, test) = split(&poses, options.holdout);
    let unplaced = Problem {
        controller: &controller,
        poses: &poses,
        layout: &[],
        description_targets_m: desc.tool_targets_m(),
    };
    let (start, gross, train) = gross::registered_start_and_gross(&unplaced, &nominal, train, options)?;
    let layout = fitted_layout(&nominal, &poses, &train, options);
    let problem = Problem {
        controller: &controller,
        poses: &poses,
        layout: &layout,
        description_targets_m: desc.tool_targets_m(),
    };
    let frame_columns: Vec<usize> = (0..layout.len()).filter(|&c| frame_parameter(&layout[c])).collect();
    let registered = fit::fit(&problem, &start, &train, &frame_columns)?;
    let all: Vec<usize> = (0..layout.len()).collect();
    let (_, design) = registered
        .model
        .residuals_and_jacobian(&controller, &poses, &train, &layout, &all)
        .map_err(|u| u.error(&poses))?;
    let mut identification = identify::identify(&design, &layout, &registered.model.phi);
    let geometry = |id: &Identification| -> Vec<usize> {
        id.fitted
            .iter()
            .copied()
            .filter(|&c| model::harmonic_order(&layout[c]).is_none() && !identify::is_effect(&layout[c]))
            .collect()
    };
    // The column scales are tested before any pose is screened, and the screen runs on the
    // poses with the scales named undone (`scales` module doc): each on the geometric fit and
    // on the fit of every parameter the poses identify (the effects, the transmissions'
    // harmonics and the description's gear forms), whose residual is the noise: on the
    // geometry alone a drive's periodic error the model carries reads as a command scale.
    let full_fit = |here: &Problem<'_>, from: &FreePoseModel| {
        let mut id = identification.clone();
        converging(&mut id, &design, &layout, |id| fit::fit(here, from, &train, &id.fitted))
    };
    let with_more = identification.fitted.len() > geometry(&identification).len();
    let (found, undone) = scales::named_scales(
        &problem,
        &registered.model,
        &train,
        (
            &geometry(&identification),
            with_more.then_some(&full_fit as &scales::FullFit<'_>),
        ),
    );
    let screening = Problem {
        poses: undone.as_ref().unwrap_or(&poses),
        description_targets_m: problem.description_targets_m.clone(),
        ..problem
    };
    let screens = (&problem, &screening);
    // The outliers of the geometry pick the poses the harmonics are chosen on; the chosen
    // model's own test on every pose then decides which poses the calibration drops.
    let (fitted, kept, _) = converging(&mut identification, &design, &layout, |id| {
        screened(screens, &registered.model, &train, &geometry(id), options)
    })?;
    let Selected {
        fitted,
        harmonics_left_out,
        effects_left_out,
        effects_tried,
    } = select_harmonics_and_effects(&problem, fitted, &kept, &identification)?;
    identification.drop_insignificant(&harmonics_left_out, &layout);
    identification.fitted.retain(|c| !effects_left_out.contains(c));
    let screened_fit = converging(&mut identification, &design, &layout, |id| {
        screened(screens, &fitted.model, &train, &id.fitted, options)
    })?;
    let (fitted, kept, flags) = gross_tested(&problem, screened_fit, &gross, &identification.fitted)?;
    check_plausible(&fitted, &poses, &kept)?;
    let scales = found.into_iter().map(|f| f.named).collect();
    summary::summarise(summary::Stages {
        problem: &problem,
        start: &start,
        registered: &registered,
        identification: &identification,
        fitted,
        kept: &kept,
        flags: &flags,
        test: &test,
        keep_outliers: options.keep_outliers,
        effects_tried,
        scales,
    })
}

/// The parameters the fit may take ([`layout`]): the geometry, every setup's base, the targets,
/// the transmissions' harmonics up to `--harmonics` over the spans of the poses `train`, and
/// with `--effects` the effects' ([`effects::effect_layout`]).
fn fitted_layout(
    nominal: &RobotModel,
    poses: &FreePoses,
    train: &[usize],
    options: &FreePoseOptions,
) -> Vec<RefitParameter> {
    let mut layout = layout(
        nominal,
        &poses.target_ids,
        options.max_harmonic_order,
        &poses.spans(train),
        poses.setup_names.len(),
    );
    if options.effects {
        layout.extend(effects::effect_layout(nominal, poses, train));
    }
    layout
}

/// [`fit_without_outliers`] on the poses the outlier screen sees (`screening`: the file's, or
/// with the column scales named undone), then, where those differ from the file's (`problem`),
/// the fit of the file's poses it kept.
fn screened(
    (problem, screening): (&Problem<'_>, &Problem<'_>),
    start: &FreePoseModel,
    train: &[usize],
    columns: &[usize],
    options: &FreePoseOptions,
) -> Result<(Fitted, Vec<usize>, Vec<fit::Flag>), FreePoseError> {
    let (fitted, kept, flags) = fit_without_outliers(screening, start, train, columns, options)?;
    if std::ptr::eq(screening.poses, problem.poses) {
        return Ok((fitted, kept, flags));
    }
    Ok((fit::fit(problem, &fitted.model, &kept, columns)?, kept, flags))
}

/// The fit, the poses it kept and the flags, with the gross poses set aside before the fit
/// (`gross`, [`gross::registered_without_gross`]) tested against it as poses outside the fit
/// ([`fit::flag_outside`]): flagged, each joins the flags; not, it joins the fit again. A gross
/// pose the fitted model cannot execute keeps its flag from the registration.
fn gross_tested(
    problem: &Problem<'_>,
    (fitted, mut kept, mut flags): (Fitted, Vec<usize>, Vec<fit::Flag>),
    gross: &[fit::Flag],
    columns: &[usize],
) -> Result<(Fitted, Vec<usize>, Vec<fit::Flag>), FreePoseError> {
    if gross.is_empty() {
        return Ok((fitted, kept, flags));
    }
    let (executable, unexecutable): (Vec<&fit::Flag>, Vec<&fit::Flag>) = gross.iter().partition(|g| {
        fitted
            .model
            .residuals(problem.controller, problem.poses, &[g.pose])
            .is_ok()
    });
    let outside: Vec<usize> = executable.iter().map(|g| g.pose).collect();
    let confirmed = fit::flag_outside(problem, &fitted.model, &kept, &outside, columns)?;
    let back: Vec<usize> = outside
        .iter()
        .copied()
        .filter(|i| !confirmed.iter().any(|f| f.pose == *i))
        .collect();
    flags.extend(confirmed);
    flags.extend(unexecutable.into_iter().cloned());
    flags.sort_by_key(|f| f.pose);
    if back.is_empty() {
        return Ok((fitted, kept, flags));
    }
    kept.extend(back);
    kept.sort_unstable();
    let refitted = fit::fit(problem, &fitted.model, &kept, columns)?;
    Ok((refitted, kept, flags))
}

/// `attempt` with the parameters of `identification`; while its fit does not converge, again
/// without the parameter the design determines worst ([`Identification::drop_weakest`]).
fn converging<T>(
    identification: &mut Identification,
    design: &nalgebra::DMatrix<f64>,
    layout: &[RefitParameter],
    attempt: impl Fn(&Identification) -> Result<T, FreePoseError>,
) -> Result<T, FreePoseError> {
    loop {
        match attempt(identification) {
            Err(e @ FreePoseError::Fit(LsqError::NotConverged { .. })) => {
                if identification.drop_weakest(design, layout).is_none() {
                    return Err(e);
                }
            }
            other => return other,
        }
    }
}

/// The poses fitted and the poses held out: every pose, or the even and odd configurations.
fn split(poses: &FreePoses, holdout: bool) -> (Vec<usize>, Vec<usize>) {
    let configurations = poses.configurations();
    (0..poses.poses.len()).partition(|&i| !holdout || configurations[i].is_multiple_of(2))
}

/// The bases (of every setup) and the targets: the ones a registration of the nominal model
/// fits.
fn frame_parameter(p: &RefitParameter) -> bool {
    matches!(
        p,
        RefitParameter::Base(_) | RefitParameter::SetupBase { .. } | RefitParameter::Target { .. }
    )
}

/// The nominal model placed by the closed-form registration of the poses `which`.
fn registered_start(
    problem: &Problem<'_>,
    nominal: &RobotModel,
    which: &[usize],
) -> Result<FreePoseModel, FreePoseError> {
    let poses = problem.poses;
    let slots = poses.target_ids.len();
    let points: usize = which.iter().map(|&i| poses.poses[i].points_m.len()).sum();
    let parameters = 6 + 3 * slots;
    if 3 * points < parameters + 1 || which.len() < MIN_POSES {
        return Err(FreePoseError::TooFewPoints {
            poses: which.len(),
            points,
            parameters,
            needed: parameters.div_ceil(3) + 1,
        });
    }
    let unplaced = FreePoseModel::new(nominal, Isometry3::identity(), poses.target_ids.clone(), vec![]);
    let q = unplaced
        .joint_values(problem.controller, poses)
        .map_err(|u| u.error(poses))?;
    let fixed = unplaced.phi.fixed_frames();
    // The poses of one setup: their nominal tool frames in the base frame and their points.
    let of_setup = |setup: usize| {
        let mine: Vec<usize> = which
            .iter()
            .copied()
            .filter(|&i| poses.poses[i].setup == setup)
            .collect();
        let base_from_tool: Vec<Isometry3<f64>> = mine.iter().map(|&i| fixed.world_from_tool(&q[i])).collect();
        let observations: Vec<register::Observation> = mine
            .iter()
            .enumerate()
            .flat_map(|(k, &i)| {
                poses.poses[i]
                    .points_m
                    .iter()
                    .map(move |&(slot, measured_m)| register::Observation {
                        pose: k,
                        slot,
                        measured_m,
                    })
            })
            .collect();
        (base_from_tool, observations)
    };
    let (base_from_tool, observations) = of_setup(0);
    let reg = register::register(&base_from_tool, &observations, slots).ok_or(FreePoseError::Registration)?;
    let mut model = FreePoseModel::new(
        nominal,
        reg.world_from_base,
        poses.target_ids.clone(),
        reg.targets_in_tool_m,
    );
    // Every other setup: its base by the rigid fit of the registered targets onto its points.
    model.other_bases = (1..poses.setup_names.len())
        .map(|setup| {
            let (base_from_tool, observations) = of_setup(setup);
            register::fit_base(&base_from_tool, &observations, &model.targets_in_tool_m).ok_or_else(|| {
                FreePoseError::SetupUnplaced {
                    setup: poses.setup_names[setup].clone(),
                }
            })
        })
        .collect::<Result<_, _>>()?;
    Ok(model)
}

/// The fit of the parameters `columns` (the geometry), refitted without the poses the outlier
/// test flags (unless `keep_outliers`; [`fit::flag_outliers`]): the fit, the poses it kept,
/// every flag raised. Each round tests every pose against the fit of the poses kept so far, the
/// noise estimated from them (a gross error of the first fit inflates it and may mask a smaller
/// one, which the next round finds), and against the first fit's far-out fence; it ends when
/// the flags settle.
fn fit_without_outliers(
    problem: &Problem<'_>,
    start: &FreePoseModel,
    train: &[usize],
    columns: &[usize],
    options: &FreePoseOptions,
) -> Result<(Fitted, Vec<usize>, Vec<fit::Flag>), FreePoseError> {
    let mut fitted = fit::fit(problem, start, train, columns)?;
    // Tukey's fence is the first fit's and stays: re-computed on the poses left it would shrink
    // round by round and peel off the tail of clean data.
    let tukey = fit::outlier_fence(&fitted.residual, problem.poses, train);
    let mut flags = fit::flag_outliers(problem, &fitted.model, train, train, columns, tukey)?;
    let without = |flags: &[fit::Flag]| -> Vec<usize> {
        train
            .iter()
            .copied()
            .filter(|i| !flags.iter().any(|f| f.pose == *i))
            .collect()
    };
    for _ in 0..OUTLIER_ROUNDS {
        if flags.is_empty() || options.keep_outliers {
            break;
        }
        if flags.len() as f64 > OUTLIER_SHARE_MAX * train.len() as f64 {
            return Err(FreePoseError::TooManyOutliers {
                flagged: flags.len(),
                poses: train.len(),
            });
        }
        let kept = without(&flags);
        fitted = fit::fit(problem, &fitted.model, &kept, columns)?;
        let again = fit::flag_outliers(problem, &fitted.model, train, &kept, columns, tukey)?;
        let settled = again.iter().map(|f| f.pose).eq(flags.iter().map(|f| f.pose));
        flags = again;
        if settled {
            break;
        }
    }
    let kept: Vec<usize> = if options.keep_outliers {
        train.to_vec()
    } else {
        without(&flags)
    };
    if kept.len() != fitted.residual.len() / 3 && !options.keep_outliers {
        fitted = fit::fit(problem, &fitted.model, &kept, columns)?;
    }
    Ok((fitted, kept, flags))
}

/// The model selection's outcome: the fit of the chosen harmonic order and effects on the kept
/// poses, the columns left out, every set of effects tried.
struct Selected {
    fitted: Fitted,
    harmonics_left_out: Vec<usize>,
    effects_left_out: Vec<usize>,
    effects_tried: Vec<EffectTrial>,
}

/// The harmonic order, then the effects ([`effects::select_effects`]) at that order; when
/// effects are kept, the order again with them in every order's fit, and if it changes, the
/// effects again at the new order. The first order is judged without effects: an effect's
/// scatter (a backlash) can hide a harmonic the data resolve, and a sag then takes the
/// harmonic's place. A second round that does not converge leaves the first.
fn select_harmonics_and_effects(
    problem: &Problem<'_>,
    geometry: Fitted,
    kept: &[usize],
    identification: &Identification,
) -> Result<Selected, FreePoseError> {
    let without = |left_out: &[usize]| Identification {
        fitted: identification
            .fitted
            .iter()
            .copied()
            .filter(|c| !left_out.contains(c))
            .collect(),
        unidentified: vec![],
    };
    let (harmonic_fit, harmonics_left_out) = select_harmonics(problem, geometry.clone(), kept, identification, &[])?;
    let (fitted, effects_left_out, effects_tried) =
        effects::select_effects(problem, harmonic_fit, kept, &without(&harmonics_left_out))?;
    let first = Selected {
        fitted,
        harmonics_left_out,
        effects_left_out,
        effects_tried,
    };
    let kept_effects: Vec<usize> = identification
        .fitted
        .iter()
        .copied()
        .filter(|&c| identify::is_effect(&problem.layout[c]) && !first.effects_left_out.contains(&c))
        .collect();
    if kept_effects.is_empty() {
        return Ok(first);
    }
    let second = || -> Result<Option<Selected>, FreePoseError> {
        let geometry_columns: Vec<usize> = identification
            .fitted
            .iter()
            .copied()
            .filter(|&c| {
                let p = &problem.layout[c];
                model::harmonic_order(p).is_none() && !identify::is_effect(p)
            })
            .collect();
        let with_effects = fit::fit(
            problem,
            &geometry.model,
            kept,
            &[geometry_columns, kept_effects.clone()].concat(),
        )?;
        let (_, harmonics_left_out) = select_harmonics(problem, with_effects, kept, identification, &kept_effects)?;
        if harmonics_left_out == first.harmonics_left_out {
            return Ok(None);
        }
        let at_order = without(&harmonics_left_out);
        let columns: Vec<usize> = at_order
            .fitted
            .iter()
            .copied()
            .filter(|&c| !identify::is_effect(&problem.layout[c]))
            .collect();
        let harmonic_fit = fit::fit(problem, &geometry.model, kept, &columns)?;
        let (fitted, effects_left_out, effects_tried) =
            effects::select_effects(problem, harmonic_fit, kept, &at_order)?;
        Ok(Some(Selected {
            fitted,
            harmonics_left_out,
            effects_left_out,
            effects_tried,
        }))
    };
    match second() {
        Ok(Some(s)) => Ok(s),
        Ok(None) | Err(FreePoseError::Fit(LsqError::NotConverged { .. }) | FreePoseError::Unexecutable { .. }) => {
            Ok(first)
        }
        Err(e) => Err(e),
    }
}

/// The harmonic order the data resolve: the order (0 to the highest identified) whose fits
/// predict held-out configurations best, by cross-validation over [`CV_FOLDS`] folds of the
/// configurations (configuration `c` in fold `c mod folds`; repeated visits of one
/// configuration carry no new information about the model, so they are never split; each
/// fold's fit the Gauss-Newton step from the order's fit on every pose,
/// [`linearised_cv_errors`], refitted in full where a fold leaves a parameter undetermined);
/// an order replaces the one kept below it only when [`significantly_better`]. The effect
/// columns `effects` are in every order's fit (`geometry` is their fit at order 0). Returns
/// the fit of that order on every kept pose and the harmonic columns left out.
fn select_harmonics(
    problem: &Problem<'_>,
    geometry: Fitted,
    kept: &[usize],
    identification: &Identification,
    effects: &[usize],
) -> Result<(Fitted, Vec<usize>), FreePoseError> {
    let order_of = |c: usize| model::harmonic_order(&problem.layout[c]).unwrap_or(0);
    let max = identification.fitted.iter().map(|&c| order_of(c)).max().unwrap_or(0);
    let columns = |o: usize| -> Vec<usize> {
        identification
            .fitted
            .iter()
            .copied()
            .filter(|&c| order_of(c) <= o && (!identify::is_effect(&problem.layout[c]) || effects.contains(&c)))
            .collect()
    };
    let configurations = problem.poses.configurations();
    // Order 0 stands even when its own folds do not converge (then no order is tried above it).
    let mut best: (Option<Vec<f64>>, usize, Fitted) = (None, 0, geometry.clone());
    let mut previous = geometry;
    for order in 0..=max {
        // Each order starts from the one below (its new harmonics at 0), and its folds from
        // its fit on every pose. An order whose fit does not converge is more than the data
        // resolve: the orders above it are not tried.
        let fitted = if order == 0 {
            previous.clone()
        } else {
            match fit::fit(problem, &previous.model, kept, &columns(order)) {
                Ok(f) => f,
                Err(FreePoseError::Fit(LsqError::NotConverged { .. }) | FreePoseError::Unexecutable { .. }) => break,
                Err(e) => return Err(e),
            }
        };
        let errors = match cv_errors(problem, &fitted, kept, &configurations, &columns(order)) {
            Ok(errors) => errors,
            Err(FreePoseError::Fit(LsqError::NotConverged { .. }) | FreePoseError::Unexecutable { .. }) => break,
            Err(e) => return Err(e),
        };
        previous = fitted.clone();
        if best.0.as_ref().is_none_or(|b| significantly_better(&errors, b)) {
            best = (Some(errors), order, fitted);
        }
    }
    let (_, order, fitted) = best;
    let left_out = columns(max).into_iter().filter(|&c| order_of(c) > order).collect();
    Ok((fitted, left_out))
}

/// Folds of the harmonic order's cross-validation.
pub const CV_FOLDS: usize = 5;

/// Standard errors by which a larger model (a harmonic order, a set of effects) must lower the
/// cross-validated sum of squares of the model it would replace: a one-sided 2.3 % chance that
/// a model which does not predict better is taken for one that does (the paired differences'
/// sum is near normal over the tens to thousands of poses of a campaign).
const SIGNIFICANT_SE: f64 = 2.0;

/// Whether the per-pose held-out errors `errors` beat `best`'s: their paired differences
/// `d_i = best_i - errors_i` sum to more than [`SIGNIFICANT_SE`] standard errors of that sum,
/// `sqrt(n) sd(d)`. A larger model costs parameters; a gain within the folds' own scatter is
/// no evidence for it.
fn significantly_better(errors: &[f64], best: &[f64]) -> bool {
    let d: Vec<f64> = best.iter().zip(errors).map(|(b, e)| b - e).collect();
    let n = d.len() as f64;
    let sum: f64 = d.iter().sum();
    if !sum.is_finite() || d.len() < 2 {
        return sum > 0.0;
    }
    let mean = sum / n;
    let variance = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    sum > SIGNIFICANT_SE * (n * variance).sqrt()
}

/// Each pose's sum of squared held-out residuals \[m^2\] in the order of `kept`, over
/// [`CV_FOLDS`] folds of the configurations of the poses `kept` (each fold fitted on the
/// others); every entry infinite when a fold's model cannot execute one of its held-out
/// configurations.
fn cross_validated_errors(
    problem: &Problem<'_>,
    start: &FreePoseModel,
    kept: &[usize],
    configurations: &[usize],
    columns: &[usize],
) -> Result<Vec<f64>, FreePoseError> {
    let mut errors = vec![0.0; kept.len()];
    for fold in 0..CV_FOLDS {
        let in_fold = |i: usize| configurations[i] % CV_FOLDS == fold;
        let (held, train): (Vec<usize>, Vec<usize>) = kept.iter().partition(|&&i| in_fold(i));
        if held.is_empty() || train.is_empty() {
            continue;
        }
        let fitted = fit::fit(problem, start, &train, columns)?;
        // A model that cannot execute a held-out configuration (its harmonics make a
        // transmission non-monotonic there) does not generalise: infinitely bad.
        let Ok(r) = fitted.model.residuals(problem.controller, problem.poses, &held) else {
            return Ok(vec![f64::INFINITY; kept.len()]);
        };
        let mut row = 0;
        for (slot, &i) in kept.iter().enumerate().filter(|(_, i)| in_fold(**i)) {
            let coordinates = 3 * problem.poses.poses[i].points_m.len();
            errors[slot] = r.rows(row, coordinates).norm_squared();
            row += coordinates;
        }
    }
    Ok(errors)
}

/// Each pose's held-out squared residual over the folds, for the fit `fitted` of the
/// parameters `columns` on the poses `kept`: [`linearised_cv_errors`], or where a fold leaves a
/// parameter undetermined, [`cross_validated_errors`] (every fold refitted).
fn cv_errors(
    problem: &Problem<'_>,
    fitted: &Fitted,
    kept: &[usize],
    configurations: &[usize],
    columns: &[usize],
) -> Result<Vec<f64>, FreePoseError> {
    match linearised_cv_errors(problem, fitted, kept, configurations) {
        Some(errors) => Ok(errors),
        None => cross_validated_errors(problem, &fitted.model, kept, configurations, columns),
    }
}

/// Each pose's sum of squared held-out residuals \[m^2\] in the order of `kept` over the folds
/// of [`cross_validated_errors`], each fold's fit taken as one Gauss-Newton step from `fitted`
/// (the fit on every pose of `kept`, its residual and Jacobian in that order): with `A = J^T J`
/// and `J_k`, `r_k` the fold's rows, the fold's step `d = -(A - J_k^T J_k)^-1 (J^T r - J_k^T r_k)`
/// and its held-out residual `r_k + J_k d` (block deletion; exact for a linear model, Cook &
/// Weisberg, *Residuals and Influence in Regression*, 1982, sec. 3.6; here first order in the
/// fold's step, whose second-order part is the curvature of the residuals over a step within a
/// few sigmas). `None` when a fold's training rows leave a parameter undetermined.
fn linearised_cv_errors(
    problem: &Problem<'_>,
    fitted: &Fitted,
    kept: &[usize],
    configurations: &[usize],
) -> Option<Vec<f64>> {
    let (j, r) = (&fitted.jacobian, &fitted.residual);
    let scale = crate::numerics::lsq::column_scales(j);
    let scaled = DMatrix::from_fn(j.nrows(), j.ncols(), |row, c| j[(row, c)] / scale[c]);
    let normal = crate::numerics::lsq::gram(&scaled);
    let gradient = scaled.tr_mul(r);
    let mut first_row = Vec::with_capacity(kept.len());
    let mut row = 0;
    for &i in kept {
        first_row.push(row);
        row += 3 * problem.poses.poses[i].points_m.len();
    }
    let mut errors = vec![0.0; kept.len()];
    for fold in 0..CV_FOLDS {
        let held: Vec<usize> = (0..kept.len())
            .filter(|&s| configurations[kept[s]] % CV_FOLDS == fold)
            .collect();
        if held.is_empty() || held.len() == kept.len() {
            continue;
        }
        let rows: Vec<usize> = held
            .iter()
            .flat_map(|&s| first_row[s]..first_row[s] + 3 * problem.poses.poses[kept[s]].points_m.len())
            .collect();
        let j_k = scaled.select_rows(&rows);
        let r_k = r.select_rows(&rows);
        let train_normal = &normal - crate::numerics::lsq::gram(&j_k);
        let train_gradient = &gradient - j_k.tr_mul(&r_k);
        let step = -train_normal.cholesky()?.solve(&train_gradient);
        let held_residual = &r_k + &j_k * step;
        let mut at = 0;
        for &s in &held {
            let coordinates = 3 * problem.poses.poses[kept[s]].points_m.len();
            errors[s] = held_residual.rows(at, coordinates).norm_squared();
            at += coordinates;
        }
    }
    Some(errors)
}

/// Refuses a fit whose RMS is a good part of the points' own spread ([`crate::numerics::stats::ABSURD_SHARE`]).
fn check_plausible(fitted: &Fitted, poses: &FreePoses, kept: &[usize]) -> Result<(), FreePoseError> {
    let points: Vec<nalgebra::Point3<f64>> = kept
        .iter()
        .flat_map(|&i| poses.poses[i].points_m.iter().map(|(_, p)| *p))
        .collect();
    let spread = crate::numerics::stats::rms_spread(&points);
    let rms = fitted.rms_m();
    if rms > crate::numerics::stats::ABSURD_SHARE * spread {
        return Err(FreePoseError::Absurd {
            rms_mm: rms * 1e3,
            spread_mm: spread * 1e3,
            percent: 100.0 * rms / spread,
        });
    }
    Ok(())
}

/// `desc` with the tool targets a free-pose calibration fitted (its `summary`; `None` for
/// another calibration), where the description gives none and the calibration fitted targets
/// 0, 1 and 2 (in the description's tool frame): what `validate` needs to predict the points
/// of such a calibration's targets. Otherwise `desc`.
pub fn with_fitted_targets(desc: &RobotDescription, summary: Option<&FreePoseSummary>) -> RobotDescription {
    let Some(summary) = summary else {
        return desc.clone();
    };
    let ids: Vec<usize> = summary.targets.iter().map(|t| t.id).collect();
    if !desc.tool.targets_mm.is_empty() || ids != [0, 1, 2] {
        return desc.clone();
    }
    let mut with = desc.clone();
    with.tool.targets_mm = summary.targets.iter().map(|t| t.position_mm).collect();
    with
}
