//! Sim-to-real gap diagnosis (FORMATS.md section 3): from a measurement CSV and the nominal
//! description only, WHERE the calibrated model misses (axis experiments and validation poses
//! against what noise alone predicts), WHICH candidate effect explains the miss (each fitted
//! on training poses, scored on held-out ones), and HOW FAR the gap shrinks.
//!
//! Method:
//! 1. calibrate with the standard procedure; a noise-only Monte-Carlo (the same commands on
//!    the calibrated robot, [`replica`]) gives the residuals noise alone produces;
//! 2. validation poses split into training (even) and held-out (odd) halves; the baseline is
//!    the calibrated model refit on the training tool targets (rows `a`, `b`, `alpha`, joint
//!    offsets, order-1 transmission harmonics, coupling slopes, base and tool frames;
//!    Levenberg-Marquardt, [`levenberg_marquardt`]);
//! 3. each [`Candidate`] is fitted on the same training poses on top of the refit and scored
//!    on the held-out poses by a BIC-like criterion `chi2_heldout + p ln(n_heldout)` (Schwarz
//!    1978, with the held-out chi-square in place of the likelihood); the confidence is the
//!    softmax of `-score/2` over the baseline and the candidates (Akaike/Schwarz weights);
//! 4. gap = `sqrt(max(0, rms^2 - rms_noise^2))` on the held-out poses. `none` when the
//!    baseline gap is within `k` sigma of its noise-only spread; `unexplained` when the best
//!    candidate removes less than a set fraction of the gap (in variance).

mod fit;
mod model;
mod noise;
mod poses;
mod report;

pub use fit::{LsqFit, levenberg_marquardt};
pub use model::{Candidate, GRAVITY_M_S2, HARMONIC_ORDER, Predictor, WOBBLE_ORDER};
pub use noise::{clean_positions, replica};
pub use poses::{Pose, split, target_count, validation_poses};
pub use report::markdown;

use crate::calibration::procedure::{CalibrationOptions, ProcedureError, calibrate};
use crate::measurement::MeasurementSet;
use crate::robot::RobotDescription;
use rand::{SeedableRng, rngs::StdRng};
use serde::{Deserialize, Serialize};

/// Why a data set could not be diagnosed.
#[derive(Debug, thiserror::Error)]
pub enum DiagnosisError {
    /// The standard calibration failed.
    #[error("calibrating: {0}")]
    Calibration(#[from] ProcedureError),
    /// Too few validation poses to split.
    #[error("{found} validation poses (moved_joint = 0, not `tool`); at least {needed} needed")]
    TooFewPoses {
        /// Found.
        found: usize,
        /// Needed.
        needed: usize,
    },
    /// The model could not predict the data.
    #[error("{message}")]
    Model {
        /// What failed.
        message: String,
    },
}

/// Iteration cap of a candidate's fit (it starts from the converged refit).
pub const CANDIDATE_ITERATIONS: usize = 8;

/// Options of [`diagnose`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DiagnosisOptions {
    /// Measurement noise, 3-D RMS of a point \[mm\].
    pub noise_rms_3d_mm: f64,
    /// Noise-only Monte-Carlo replicas.
    pub noise_trials: usize,
    /// Seed of the replicas' noise.
    pub seed: u64,
    /// A gap counts when `rms^2 - rms_noise^2` exceeds this many sigma of its noise-only
    /// spread.
    pub significance_sigmas: f64,
    /// An effect is named when it removes at least this fraction of the gap's variance.
    pub explained_fraction: f64,
    /// Iteration cap of the refits.
    pub max_iterations: usize,
}

impl Default for DiagnosisOptions {
    fn default() -> Self {
        DiagnosisOptions {
            noise_rms_3d_mm: 0.19,
            noise_trials: 8,
            seed: 0,
            significance_sigmas: 3.0,
            explained_fraction: 0.5,
            max_iterations: 60,
        }
    }
}

/// One `where` entry: an experiment's residual against its noise-only prediction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WhereEntry {
    /// Experiment id (`validation` entries: the calibrated model on every validation pose;
    /// `validation_heldout_refit`: the baseline on the held-out poses).
    pub experiment: String,
    /// The moved joint, or `None` for validation poses.
    pub joint: Option<usize>,
    /// Residual RMS over the noise-only RMS.
    pub excess_ratio: f64,
    /// Residual RMS \[mm\].
    pub residual_rms_mm: f64,
    /// Noise-only RMS \[mm\] (mean over the replicas, in variance).
    pub noise_only_rms_mm: f64,
}

/// A fitted parameter with its 1-sigma.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Parameter {
    /// Name with unit.
    pub name: String,
    /// Value.
    pub value: f64,
    /// 1-sigma from the fit's covariance (noise variance the larger of the stated one and the
    /// fit's residual variance).
    pub sigma: f64,
}

/// One scored candidate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CandidateScore {
    /// Effect name.
    pub effect: String,
    /// Joint, or `None`.
    pub joint: Option<usize>,
    /// Held-out position RMS with the effect \[mm\].
    pub heldout_rms_mm: f64,
    /// Held-out gap with the effect \[mm\].
    pub gap_after_mm: f64,
    /// BIC-like score (lower is better).
    pub score: f64,
    /// Softmax weight of `-score/2` over the baseline and all candidates.
    pub weight: f64,
    /// Fitted effect parameters.
    pub parameters: Vec<Parameter>,
}

/// The diagnosis (FORMATS.md section 3 plus details).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Diagnosis {
    /// `none`, `unexplained`, or a candidate's effect name.
    pub effect: String,
    /// The effect's joint, or `None`.
    pub joint: Option<usize>,
    /// Confidence in `effect` (0..1).
    pub confidence: f64,
    /// Held-out gap of the baseline \[mm\].
    pub gap_before_mm: f64,
    /// Held-out gap with the named effect (the baseline's when none is named) \[mm\].
    pub gap_after_mm: f64,
    /// Experiments ranked by excess over noise.
    #[serde(rename = "where")]
    pub where_: Vec<WhereEntry>,
    /// Candidates, best first.
    pub candidates: Vec<CandidateScore>,
    /// The named effect's parameters.
    pub parameters: Vec<Parameter>,
    /// Noise assumed, 3-D RMS \[mm\].
    pub noise_rms_3d_mm: f64,
    /// Training and held-out pose counts.
    pub poses: [usize; 2],
    /// Baseline held-out RMS \[mm\].
    pub heldout_rms_before_mm: f64,
    /// Noise-only held-out RMS of the baseline \[mm\].
    pub noise_only_rms_mm: f64,
    /// Significance of the baseline gap: `(rms^2 - rms_noise^2) / spread` \[sigma\].
    pub gap_sigmas: f64,
    /// Fraction of the gap's variance the best candidate removes.
    pub fraction_closed: f64,
    /// One sentence.
    pub verdict: String,
}

/// The calibrated model refit on the training poses, and its residuals.
struct Baseline {
    cal: crate::calibration::procedure::Calibration,
    predictor: Predictor,
    fit: LsqFit,
    /// Held-out residuals of the refit \[m\].
    heldout: Vec<f64>,
    /// Validation residuals of the calibrated model on every pose \[m\].
    validation: Vec<f64>,
}

fn rms_3d_mm(r: &[f64]) -> f64 {
    (r.iter().map(|x| x * x).sum::<f64>() / (r.len() / 3).max(1) as f64).sqrt() * 1e3
}

fn baseline(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &DiagnosisOptions,
) -> Result<Baseline, DiagnosisError> {
    let cal = calibrate(
        set,
        desc,
        &CalibrationOptions {
            noise_rms_3d_mm: options.noise_rms_3d_mm,
            ..CalibrationOptions::default()
        },
    )?;
    let all = validation_poses(set.rows(), desc);
    if all.len() < 4 {
        return Err(DiagnosisError::TooFewPoses {
            found: all.len(),
            needed: 4,
        });
    }
    let axis_temps: Vec<f64> = set
        .rows()
        .iter()
        .filter(|m| m.moved_joint > 0)
        .map(|m| m.temperature_c)
        .collect();
    let reference_c = if axis_temps.is_empty() {
        20.0
    } else {
        axis_temps.iter().sum::<f64>() / axis_temps.len() as f64
    };
    let predictor = Predictor::new(&cal.robot, desc, reference_c, None);
    let (train, held) = split(&all);
    let zeros = vec![0.0; predictor.geometric_count()];
    let model_err = |what: &str| DiagnosisError::Model {
        message: format!("the calibrated model cannot execute a validation command ({what})"),
    };
    let every: Vec<&Pose> = all.iter().collect();
    let validation = predictor
        .residuals(&zeros, &every)
        .ok_or_else(|| model_err("all poses"))?;
    let fit = levenberg_marquardt(
        |p| predictor.residuals(p, &train),
        &zeros,
        &predictor.steps(),
        options.max_iterations,
    )
    .ok_or_else(|| model_err("training poses"))?;
    let heldout = predictor
        .residuals(&fit.params, &held)
        .ok_or_else(|| model_err("held-out poses"))?;
    Ok(Baseline {
        cal,
        predictor,
        fit,
        heldout,
        validation,
    })
}

/// Diagnoses `set` (module docs). Deterministic for given options.
pub fn diagnose(
    set: &MeasurementSet,
    desc: &RobotDescription,
    options: &DiagnosisOptions,
) -> Result<Diagnosis, DiagnosisError> {
    let base = baseline(set, desc, options)?;
    let noise_m = options.noise_rms_3d_mm * 1e-3;
    let sigma2 = noise_m * noise_m / 3.0;
    // Noise-only replicas of the whole pipeline (calibration + refit).
    let clean = clean_positions(set, &base.cal, desc)?;
    let mut rng = StdRng::seed_from_u64(options.seed);
    let mut mc_heldout2 = Vec::new();
    let mut mc_validation2 = Vec::new();
    let mut mc_axis2 = vec![Vec::new(); base.cal.axes.len()];
    for _ in 0..options.noise_trials {
        let r = replica(set, &clean, noise_m, &mut rng)?;
        let b = baseline(&r, desc, options)?;
        mc_heldout2.push(rms_3d_mm(&b.heldout).powi(2));
        mc_validation2.push(rms_3d_mm(&b.validation).powi(2));
        for (acc, a) in mc_axis2.iter_mut().zip(&b.cal.axes) {
            acc.push(a.residual_rms_mm.powi(2));
        }
    }
    let mean = |v: &[f64]| {
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let held_eq = base.heldout.len();
    let rms_before = rms_3d_mm(&base.heldout);
    let noise2 = if mc_heldout2.is_empty() {
        options.noise_rms_3d_mm.powi(2)
    } else {
        mean(&mc_heldout2)
    };
    let mc_spread = if mc_heldout2.len() > 1 {
        (mc_heldout2.iter().map(|x| (x - noise2).powi(2)).sum::<f64>() / (mc_heldout2.len() - 1) as f64).sqrt()
    } else {
        0.0
    };
    // Chi-square spread of a mean of held_eq squared coordinates (3 per target).
    let spread = mc_spread.max(noise2 * (2.0 / held_eq.max(1) as f64).sqrt());
    let gap = |rms2: f64, noise2: f64| (rms2 - noise2).max(0.0).sqrt();
    let gap_before = gap(rms_before.powi(2), noise2);
    let gap_sigmas = (rms_before.powi(2) - noise2) / spread;

    // Where.
    let mut where_: Vec<WhereEntry> = base
        .cal
        .axes
        .iter()
        .zip(&mc_axis2)
        .map(|(a, mc)| {
            let n = mean(mc).sqrt();
            WhereEntry {
                experiment: a.experiment.clone(),
                joint: Some(a.joint),
                excess_ratio: a.residual_rms_mm / n,
                residual_rms_mm: a.residual_rms_mm,
                noise_only_rms_mm: n,
            }
        })
        .collect();
    let v = rms_3d_mm(&base.validation);
    let vn = mean(&mc_validation2).sqrt();
    where_.push(WhereEntry {
        experiment: "validation".into(),
        joint: None,
        excess_ratio: v / vn,
        residual_rms_mm: v,
        noise_only_rms_mm: vn,
    });
    where_.push(WhereEntry {
        experiment: "validation_heldout_refit".into(),
        joint: None,
        excess_ratio: rms_before / noise2.sqrt(),
        residual_rms_mm: rms_before,
        noise_only_rms_mm: noise2.sqrt(),
    });
    where_.sort_by(|a, b| b.excess_ratio.total_cmp(&a.excess_ratio));

    // Which.
    let all = validation_poses(set.rows(), desc);
    let (train, held) = split(&all);
    let temps: Vec<f64> = all.iter().map(|p| p.temperature_c).collect();
    let t_mean = mean(&temps);
    let t_spread = (temps.iter().map(|t| (t - t_mean).powi(2)).sum::<f64>() / temps.len() as f64).sqrt();
    let train_eq = 3 * target_count(&train);
    let score_of = |ssr: f64, p: usize| ssr / sigma2 + p as f64 * (held_eq as f64).ln();
    let base_score = score_of(rms_before.powi(2) * 1e-6 * (held_eq / 3) as f64, 0);
    let mut scored: Vec<CandidateScore> = Vec::new();
    for c in Candidate::all(desc, &all, t_spread > 1.0) {
        let mut pred = base.predictor.clone();
        pred.candidate = Some(c);
        let mut p0 = base.fit.params.clone();
        p0.extend(std::iter::repeat_n(0.0, pred.effect_count()));
        let Some(fit) = levenberg_marquardt(|p| pred.residuals(p, &train), &p0, &pred.steps(), CANDIDATE_ITERATIONS)
        else {
            continue;
        };
        let Some(r) = pred.residuals(&fit.params, &held) else {
            continue;
        };
        let pe = pred.effect_count();
        let ssr_h: f64 = r.iter().map(|x| x * x).sum();
        let rms = rms_3d_mm(&r);
        // Noise-only held-out MSE grows by sigma_3d^2 p / n_train_equations (linear model).
        let noise2_c = noise2 + options.noise_rms_3d_mm.powi(2) * pe as f64 / train_eq as f64 * 3.0 / 3.0;
        let var = sigma2.max(fit.ssr_m2 / (fit.equations.saturating_sub(fit.params.len()).max(1)) as f64);
        let g = pred.geometric_count();
        let parameters = c
            .parameter_names()
            .iter()
            .enumerate()
            .map(|(i, name)| Parameter {
                name: (*name).to_owned(),
                value: fit.params[g + i],
                sigma: (fit.normal_inverse[(g + i, g + i)] * var).max(0.0).sqrt(),
            })
            .collect();
        scored.push(CandidateScore {
            effect: c.effect_name().into(),
            joint: c.joint(),
            heldout_rms_mm: rms,
            gap_after_mm: gap(rms * rms, noise2_c),
            score: score_of(ssr_h, pe),
            weight: 0.0,
            parameters,
        });
    }
    scored.sort_by(|a, b| a.score.total_cmp(&b.score));
    let best_score = scored.iter().map(|c| c.score).fold(base_score, f64::min);
    let z: f64 = scored
        .iter()
        .map(|c| (-(c.score - best_score) / 2.0).exp())
        .sum::<f64>()
        + (-(base_score - best_score) / 2.0).exp();
    for c in &mut scored {
        c.weight = (-(c.score - best_score) / 2.0).exp() / z;
    }
    let base_weight = (-(base_score - best_score) / 2.0).exp() / z;

    // Decision.
    let best = scored.first().filter(|c| c.score < base_score);
    let fraction_closed = match best {
        Some(b) if gap_before > 0.0 => 1.0 - (b.gap_after_mm / gap_before).powi(2),
        _ => 0.0,
    };
    let (effect, joint, confidence, gap_after, parameters, verdict) = if gap_sigmas < options.significance_sigmas {
        (
            "none".to_owned(),
            None,
            base_weight.max(1.0 - scored.first().map_or(0.0, |c| c.weight)),
            gap_before,
            vec![],
            format!(
                "held-out residual {rms_before:.3} mm is at the noise level ({:.3} mm; gap {gap_sigmas:.1} sigma < {})",
                noise2.sqrt(),
                options.significance_sigmas
            ),
        )
    } else {
        match best {
            Some(b) if fraction_closed >= options.explained_fraction => (
                b.effect.clone(),
                b.joint,
                b.weight,
                b.gap_after_mm,
                b.parameters.clone(),
                format!(
                    "{}{} closes {:.0} % of the gap's variance ({gap_before:.3} -> {:.3} mm)",
                    b.effect,
                    b.joint.map_or(String::new(), |j| format!(" on joint {j}")),
                    100.0 * fraction_closed,
                    b.gap_after_mm
                ),
            ),
            _ => (
                "unexplained".to_owned(),
                None,
                (1.0 - fraction_closed.max(0.0)).clamp(0.0, 1.0),
                gap_before,
                vec![],
                format!(
                    "gap {gap_before:.3} mm ({gap_sigmas:.1} sigma) that no candidate closes by {:.0} % (best: {:.0} %)",
                    100.0 * options.explained_fraction,
                    100.0 * fraction_closed.max(0.0)
                ),
            ),
        }
    };
    Ok(Diagnosis {
        effect,
        joint,
        confidence,
        gap_before_mm: gap_before,
        gap_after_mm: gap_after,
        where_,
        candidates: scored,
        parameters,
        noise_rms_3d_mm: options.noise_rms_3d_mm,
        poses: [train.len(), held.len()],
        heldout_rms_before_mm: rms_before,
        noise_only_rms_mm: noise2.sqrt(),
        gap_sigmas,
        fraction_closed,
        verdict,
    })
}
