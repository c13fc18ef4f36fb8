//! The decision of [`diagnose`](super::diagnose): tests against the noise-only null
//! distribution (module docs of [`crate::diagnosis`], steps 3-5).

mod pair;
mod verdict;

use super::{
    Block, Candidate, CandidateScore, Diagnosis, DiagnosisOptions, FeatureContrast, LinearFit,
    NULL_DIRECTION_TOLERANCE, NamedEffect, NullData, Outcome, Parameter, Pose, Prepared, WhereEntry, implausible,
};
use crate::numerics::stats::{QuantileMethod, mean, quantile, std_dev, upper_tail};
use nalgebra::{DMatrix, DVector};
use verdict::Evidence;

/// A candidate's fit and its statistics.
struct Scored {
    candidate: Candidate,
    score: CandidateScore,
    /// Held-out chi-square of the observation and its null samples.
    chi2: f64,
    chi2_null: Vec<f64>,
    z_null: Vec<f64>,
    /// The summed weight of the nameable members of its family on its joint: the confidence
    /// in its effect when it is named.
    kind_weight: f64,
}

/// A fit's parameters with its `(X^T X)^+` and the directions it kept: the candidate's
/// parameters are the last of `p` (after the refit's and any other candidate's, or alone for
/// a [`Block`]).
struct FitParams<'a> {
    p: &'a DVector<f64>,
    normal_inverse: &'a DMatrix<f64>,
    rank: usize,
}

impl<'a> FitParams<'a> {
    fn of(fit: &'a LinearFit, p: &'a DVector<f64>) -> Self {
        FitParams {
            p,
            normal_inverse: &fit.normal_inverse,
            rank: fit.rank,
        }
    }

    /// A block's parameters `p` on top of a fit of rank `rank_below`.
    fn of_block(block: &'a Block, p: &'a DVector<f64>, rank_below: usize) -> Self {
        FitParams {
            p,
            normal_inverse: &block.normal_inverse,
            rank: rank_below + block.rank,
        }
    }
}

/// The candidate's parameters, the last of the fit's, with their standard deviations from the
/// fit's covariance, scaled by the training residual variance when it exceeds the noise's
/// (`ssr_train` the training SSR left by the fit).
fn fitted_parameters(c: Candidate, fit: FitParams, ssr_train: f64, prep: &Prepared, sigma2: f64) -> Vec<Parameter> {
    let (p, normal_inverse) = (fit.p, fit.normal_inverse);
    let dof = prep.train_rows.saturating_sub(fit.rank).max(1);
    let var = sigma2.max(ssr_train.max(0.0) / dof as f64);
    let names = c.parameter_names(prep.predictor.shape());
    let g = p.len() - names.len();
    let mut out: Vec<Parameter> = names
        .iter()
        .enumerate()
        .map(|(i, name)| Parameter {
            name: (*name).to_owned(),
            value: p[g + i],
            sigma: (normal_inverse[(g + i, g + i)] * var).max(0.0).sqrt(),
        })
        .collect();
    // The stiffness of a member with one compliance (the description's masses).
    if let (Candidate::JointCompliance { .. }, Some(c)) = (c, out.first().cloned())
        && c.name == "compliance_rad_per_nm"
        && c.value > 0.0
    {
        out.push(Parameter {
            name: "stiffness_nm_per_rad".into(),
            value: 1.0 / c.value,
            sigma: c.sigma / (c.value * c.value),
        });
    }
    out
}

/// The observation's and the noise-only samples' residuals after the baseline refit, training
/// and held-out rows: what every candidate's [`Block`] is fitted to.
struct Residualised {
    obs: (DMatrix<f64>, DMatrix<f64>),
    null: (DMatrix<f64>, DMatrix<f64>),
}

impl Residualised {
    fn new(prep: &Prepared, null: &NullData, base: &LinearFit) -> Self {
        let observed = DMatrix::from_column_slice(prep.residuals.len(), 1, prep.residuals.as_slice());
        Self::of(base, &prep.rows(&observed), (&null.train, &null.held))
    }

    /// The observation `(training, held-out)` rows and the noise-only samples' after `base`.
    fn of(base: &LinearFit, observed: &(DMatrix<f64>, DMatrix<f64>), null: (&DMatrix<f64>, &DMatrix<f64>)) -> Self {
        Residualised {
            obs: base.residualise(&observed.0, &observed.1),
            null: base.residualise(null.0, null.1),
        }
    }

    /// The same after `block` too.
    fn after(&self, block: &Block) -> Self {
        Residualised {
            obs: block.apply(&self.obs.0, &self.obs.1),
            null: block.apply(&self.null.0, &self.null.1),
        }
    }

    /// Held-out chi-square after `block` (on top of what these residuals are after): on the
    /// observation, and on every noise-only sample.
    fn heldout_chi2(&self, block: &Block, sigma2: f64) -> (f64, Vec<f64>) {
        self.heldout_chi2_all(&[block], sigma2).remove(0)
    }

    /// [`Residualised::heldout_chi2`] for each of `blocks`, computed together
    /// ([`Block::heldout_ssr_of`]).
    fn heldout_chi2_all(&self, blocks: &[&Block], sigma2: f64) -> Vec<(f64, Vec<f64>)> {
        // The observation first, then the null samples: one call for both.
        let both = |(o, n): (&DMatrix<f64>, &DMatrix<f64>)| {
            DMatrix::from_fn(
                o.nrows(),
                1 + n.ncols(),
                |r, c| if c == 0 { o[(r, 0)] } else { n[(r, c - 1)] },
            )
        };
        let ssr = Block::heldout_ssr_of(
            blocks,
            &both((&self.obs.0, &self.null.0)),
            &both((&self.obs.1, &self.null.1)),
        );
        ssr.into_iter()
            .map(|s| (s[0] / sigma2, s[1..].iter().map(|s| s / sigma2).collect()))
            .collect()
    }

    /// `block`'s fitted parameters for the observation and the training SSR they leave.
    fn params(&self, block: &Block) -> (DVector<f64>, f64) {
        let p = block.params(&self.obs.0);
        let left = (&self.obs.0 - &block.train * &p).norm_squared();
        (DVector::from_column_slice(p.as_slice()), left)
    }
}

/// A candidate's columns as a [`Block`] on top of the baseline refit and the blocks `below`.
fn candidate_block(prep: &Prepared, base: &LinearFit, below: &[&Block], x: &DMatrix<f64>) -> Block {
    let (t, h) = prep.rows(x);
    base.block(below, &t, &h)
}

/// Every candidate fitted on top of the baseline refit (the joint fit of both, by
/// Frisch-Waugh-Lovell: [`Block`]) and scored on the held-out rows.
fn score_candidates(
    prep: &Prepared,
    (base, after_base): (&LinearFit, &Residualised),
    g: (f64, &[f64]),
    sigma2: f64,
) -> Vec<Scored> {
    let to_rms_mm = |chi2: f64| (chi2.max(0.0) * sigma2 / prep.held_targets.max(1) as f64).sqrt() * 1e3;
    let rows: Vec<_> = prep.x_candidates.iter().map(|(_, x)| prep.rows(x)).collect();
    let blocks = base.blocks(&[], &rows);
    let chi2s = after_base.heldout_chi2_all(&blocks.iter().collect::<Vec<_>>(), sigma2);
    let mut out = Vec::new();
    for (((c, _), block), (chi2, chi2_null)) in prep.x_candidates.iter().zip(&blocks).zip(chi2s) {
        let t_null: Vec<f64> = g.1.iter().zip(&chi2_null).map(|(a, b)| a - b).collect();
        let (mu, sd) = (mean(&t_null), std_dev(&t_null).max(1e-12));
        let improvement = g.0 - chi2;
        let rms = to_rms_mm(chi2);
        let noise = to_rms_mm(mean(&chi2_null));
        let (p, left) = after_base.params(block);
        out.push(Scored {
            candidate: *c,
            score: CandidateScore {
                effect: c.effect_name().into(),
                member: c.member_name(),
                joint: c.joint(),
                heldout_rms_mm: rms,
                gap_after_mm: (rms * rms - noise * noise).max(0.0).sqrt(),
                improvement_chi2: improvement,
                z: (improvement - mu) / sd,
                significant: false,
                outside_refit_fraction: block.outside_fraction,
                weight: 0.0,
                parameters: fitted_parameters(*c, FitParams::of_block(block, &p, base.rank), left, prep, sigma2),
                implausible: None,
            },
            chi2,
            chi2_null,
            z_null: t_null.iter().map(|t| (t - mu) / sd).collect(),
            kind_weight: 0.0,
        });
    }
    out
}

fn where_entries(
    prep: &Prepared,
    (null, after_base): (&NullData, &Residualised),
    rms_before: f64,
    noise_before: f64,
    false_alarm: f64,
) -> (Vec<WhereEntry>, Vec<FeatureContrast>) {
    let mut out: Vec<WhereEntry> = prep
        .cal
        .axes
        .iter()
        .zip(&null.axis_rms2)
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
    let targets = (prep.residuals.len() / 3).max(1) as f64;
    let v = (prep.residuals.norm_squared() / targets).sqrt() * 1e3;
    let vn = (mean(&null.samples.column_iter().map(|c| c.norm_squared()).collect::<Vec<_>>()) / targets).sqrt() * 1e3;
    out.push(WhereEntry {
        experiment: "validation".into(),
        joint: None,
        excess_ratio: v / vn,
        residual_rms_mm: v,
        noise_only_rms_mm: vn,
    });
    out.push(WhereEntry {
        experiment: "validation_heldout_refit".into(),
        joint: None,
        excess_ratio: rms_before / noise_before,
        residual_rms_mm: rms_before,
        noise_only_rms_mm: noise_before,
    });
    let (features, contrasts) =
        super::features::feature_entries(prep, (&after_base.obs.1, &after_base.null.1), false_alarm);
    out.extend(features);
    out.sort_by(|a, b| b.excess_ratio.total_cmp(&a.excess_ratio));
    (out, contrasts)
}

/// The held-out RMS per held-out target in mm of a chi-square `chi2`, given the
/// per-coordinate noise variance `sigma2` (m^2).
fn chi2_to_rms_mm(chi2: f64, sigma2: f64, prep: &Prepared) -> f64 {
    (chi2.max(0.0) * sigma2 / prep.held_targets.max(1) as f64).sqrt() * 1e3
}

/// The omnibus gap test (step 4): the baseline refit's held-out chi-square against its
/// noise-only null distribution.
struct GapTest {
    /// Held-out chi-square of the observation under the baseline refit.
    g_obs: f64,
    /// The same chi-square for each null sample.
    g_null: Vec<f64>,
    /// Mean of `g_null`.
    g_mean: f64,
    /// The `1 - alpha` quantile of `g_null`.
    g_q: f64,
    /// How many null standard deviations `g_obs` lies above the null mean.
    gap_sigmas: f64,
    /// The smallest gap (mm) the test flags at the false-alarm rate.
    detectable_gap_mm: f64,
    /// Upper-tail probability of `g_obs` under the null.
    p_gap: f64,
}

/// Runs the gap test of the baseline refit at false-alarm rate `alpha` on the observation's
/// and the null samples' residuals after it (`after_base`).
fn gap_test(prep: &Prepared, after_base: &Residualised, sigma2: f64, alpha: f64) -> GapTest {
    let g_obs = super::column_ssr(&after_base.obs.1)[0] / sigma2;
    let g_null: Vec<f64> = super::column_ssr(&after_base.null.1)
        .iter()
        .map(|s| s / sigma2)
        .collect();
    let (g_mean, g_sd, g_q) = (
        mean(&g_null),
        std_dev(&g_null),
        quantile(&g_null, 1.0 - alpha, QuantileMethod::InverseCdf),
    );
    let gap_sigmas = (g_obs - g_mean) / g_sd.max(1e-12);
    let detectable_gap_mm = chi2_to_rms_mm(g_q - g_mean, sigma2, prep);
    let p_gap = upper_tail(&g_null, g_obs);
    GapTest {
        g_obs,
        g_null,
        g_mean,
        g_q,
        gap_sigmas,
        detectable_gap_mm,
        p_gap,
    }
}

/// Family-wise threshold: the `1 - alpha` quantile (over the `samples` null samples) of the
/// noise-only maximum of z over the candidates the refit does not absorb; marks those above
/// it significant and returns it.
fn mark_significant(scored: &mut [Scored], samples: usize, alpha: f64) -> f64 {
    let z_threshold = family_threshold(
        scored.iter().filter(|s| !s.absorbed()).map(|s| &s.z_null[..]),
        samples,
        alpha,
    );
    for s in scored.iter_mut() {
        s.score.significant = s.score.z > z_threshold && !s.absorbed();
    }
    z_threshold
}

/// The `1 - alpha` quantile over `samples` noise-only samples of the maximum of the tested
/// candidates' null z (`z_nulls`, one slice per candidate); `+inf` when none is tested.
fn family_threshold<'a>(z_nulls: impl Iterator<Item = &'a [f64]> + Clone, samples: usize, alpha: f64) -> f64 {
    if z_nulls.clone().next().is_none() {
        return f64::INFINITY;
    }
    let max_z: Vec<f64> = (0..samples)
        .map(|k| z_nulls.clone().map(|z| z[k]).fold(f64::NEG_INFINITY, f64::max))
        .collect();
    quantile(&max_z, 1.0 - alpha, QuantileMethod::InverseCdf)
}

/// Whether a candidate whose training columns have `outside_fraction` of their norm outside
/// what is fitted below it (the refit, and a first effect for a second) is absorbed by it:
/// below [`NULL_DIRECTION_TOLERANCE`] (e.g. a uniform instrument scale, which every refitted
/// length absorbs). Its improvement is then rounding and its z standardises rounding noise:
/// it is never significant and takes no part in the family-wise null maximum (with it, the
/// threshold moved with the rounding: 3.7 -> 4.1 on one blind case for a 1e-6-sigma change of
/// the calibration).
fn absorbed_fraction(outside_fraction: f64) -> bool {
    outside_fraction < NULL_DIRECTION_TOLERANCE
}

impl Scored {
    /// The refit absorbs the candidate ([`absorbed_fraction`]).
    fn absorbed(&self) -> bool {
        absorbed_fraction(self.score.outside_refit_fraction)
    }
}

/// Why `s`'s fitted parameters are implausible ([`implausible`]), with a compliance member's
/// largest sag over the validation poses.
fn implausibility(prep: &Prepared, s: &Scored) -> Option<String> {
    implausible_fit(prep, s.candidate, &s.score.parameters)
}

/// Why `candidate`'s fitted `parameters` are implausible ([`implausible`]).
fn implausible_fit(prep: &Prepared, candidate: Candidate, parameters: &[Parameter]) -> Option<String> {
    let n = candidate.parameter_names(prep.predictor.shape()).len();
    let effect: Vec<f64> = parameters.iter().take(n).map(|p| p.value).collect();
    let poses: Vec<&Pose> = prep.poses.iter().collect();
    let sag = prep.predictor.largest_sag_rad(candidate, &effect, &poses);
    implausible(candidate, parameters, sag)
}

/// Checks the significant candidates' parameters against their physical ranges.
fn check_plausibility(prep: &Prepared, scored: &mut [Scored]) {
    for s in scored.iter_mut().filter(|s| s.score.significant) {
        s.score.implausible = implausibility(prep, s);
    }
}

/// Whether `s` can be named: significant with plausible parameters.
fn nameable(s: &Scored) -> bool {
    s.score.significant && s.score.implausible.is_none()
}

/// Sorts the candidates by held-out chi-square.
fn rank(scored: &mut [Scored]) {
    scored.sort_by(|a, b| a.chi2.total_cmp(&b.chi2));
}

/// Moves ahead of the best nameable candidate the simplest nameable member of its family and
/// joint (fewer parameters) that it does not beat by more than two standard deviations of a
/// chi-square of the parameter difference, `2 sqrt(2 dk)` (a member nested in it, e.g. a
/// mechanism load path in the mixed one, leaves on held-out poses a chi-square larger by
/// about `dk` when the extra parameters are noise): the data must resolve the extra freedom
/// (a load path, a mass model) before it is named.
fn prefer_simpler_member(prep: &Prepared, scored: &mut [Scored]) {
    let Some(b) = scored.iter().position(nameable) else {
        return;
    };
    let count = |s: &Scored| s.candidate.parameter_names(prep.predictor.shape()).len();
    let (kb, chi2b) = (count(&scored[b]), scored[b].chi2);
    let simpler = scored
        .iter()
        .enumerate()
        .filter(|(_, s)| nameable(s) && s.candidate.same_kind(&scored[b].candidate))
        .filter(|(_, s)| {
            let k = count(s);
            k < kb && s.chi2 - chi2b < 2.0 * (2.0 * (kb - k) as f64).sqrt()
        })
        .min_by(|(_, x), (_, y)| count(x).cmp(&count(y)).then(x.chi2.total_cmp(&y.chi2)))
        .map(|(i, _)| i);
    if let Some(i) = simpler {
        scored[b..=i].rotate_right(1);
    }
}

/// Gives the nameable candidates (significant, plausible) their weights
/// `exp(-(chi2 - chi2_min) / 2)`, normalised over them, and each the sum over the nameable
/// members of its family on its joint.
fn weigh(scored: &mut [Scored]) {
    let chi2_min = scored
        .iter()
        .filter(|s| nameable(s))
        .map(|s| s.chi2)
        .fold(f64::INFINITY, f64::min);
    let z_sum: f64 = scored
        .iter()
        .filter(|s| nameable(s))
        .map(|s| (-(s.chi2 - chi2_min) / 2.0).exp())
        .sum();
    for s in scored.iter_mut().filter(|s| nameable(s)) {
        s.score.weight = (-(s.chi2 - chi2_min) / 2.0).exp() / z_sum;
    }
    let kinds: Vec<(Candidate, f64)> = scored
        .iter()
        .filter(|s| nameable(s))
        .map(|s| (s.candidate, s.score.weight))
        .collect();
    for s in scored.iter_mut() {
        s.kind_weight = kinds
            .iter()
            .filter(|(c, _)| c.same_kind(&s.candidate))
            .map(|(_, w)| w)
            .sum();
    }
}

/// The named candidate and the baseline it is compared with, refit beyond their
/// linearisation (the tests stay linear, as their null distributions). Updates the first
/// significant candidate's score and returns the baseline's held-out chi-square after the
/// refit (`g_obs` when there is nothing to refit).
fn refit_named(prep: &Prepared, scored: &mut [Scored], g_obs: f64, sigma2: f64) -> f64 {
    let mut g_fit = g_obs;
    if let Some(b) = scored.iter_mut().find(|s| nameable(s))
        && let Some((_, x)) = prep.x_candidates.iter().find(|(c, _)| *c == b.candidate)
        && let (Some(rb), Some(rc)) = (prep.refine(None, false), prep.refine(Some((b.candidate, x)), true))
    {
        g_fit = g_fit.min(rb.heldout_ssr / sigma2);
        b.chi2 = b.chi2.min(rc.heldout_ssr / sigma2);
        let (rms, noise) = (
            chi2_to_rms_mm(b.chi2, sigma2, prep),
            chi2_to_rms_mm(mean(&b.chi2_null), sigma2, prep),
        );
        b.score.heldout_rms_mm = rms;
        b.score.gap_after_mm = (rms * rms - noise * noise).max(0.0).sqrt();
        b.score.improvement_chi2 = g_fit - b.chi2;
        b.score.parameters = fitted_parameters(
            b.candidate,
            FitParams::of(&rc.fit, &rc.params),
            rc.r_train.norm_squared(),
            prep,
            sigma2,
        );
        b.score.implausible = implausibility(prep, b);
    }
    g_fit
}

/// The verdict on the first effect `b` with the second of `pair` (module docs of [`pair`]):
/// the pair is named when what it leaves is at the noise level or it closes enough of the
/// gap; `effect` and `joint` are then the one with the larger share, `effects` lists both.
fn two_effects(
    prep: &Prepared,
    evidence: &mut Evidence,
    b: &Scored,
    pair: pair::Pair,
    sigma2: f64,
    explained_fraction: f64,
) -> (verdict::Verdict, Vec<NamedEffect>) {
    let (rms, noise) = (
        chi2_to_rms_mm(pair.chi2, sigma2, prep),
        chi2_to_rms_mm(mean(&pair.chi2_null), sigma2, prep),
    );
    let gap_after = (rms * rms - noise * noise).max(0.0).sqrt();
    let duo = Scored {
        candidate: b.candidate,
        score: CandidateScore {
            heldout_rms_mm: rms,
            gap_after_mm: gap_after,
            ..b.score.clone()
        },
        chi2: pair.chi2,
        chi2_null: pair.chi2_null,
        z_null: Vec::new(),
        kind_weight: b.kind_weight,
    };
    if evidence.gap_before_mm > 0.0 {
        evidence.fraction_closed = 1.0 - (gap_after / evidence.gap_before_mm).powi(2);
    }
    let mut v = evidence.verdict(Some(&duo), explained_fraction);
    if v.effect == "unexplained" {
        return (v, Vec::new());
    }
    let second = NamedEffect {
        effect: pair.second.effect_name().into(),
        joint: pair.second.joint(),
        share: pair.shares[1],
    };
    v.verdict += &format!(
        "; together with {}{} (z = {:.1} over the threshold {:.1} on top of the first; shares of the closed gap {:.0} % and {:.0} %)",
        second.effect,
        second.joint.map_or(String::new(), |j| format!(" on joint {j}")),
        pair.z,
        pair.z_threshold,
        100.0 * pair.shares[0],
        100.0 * pair.shares[1]
    );
    let first = NamedEffect {
        effect: v.effect.clone(),
        joint: v.joint,
        share: pair.shares[0],
    };
    if second.share > first.share {
        v.effect = second.effect.clone();
        v.joint = second.joint;
        v.parameters = pair.parameters;
    }
    (v, vec![first, second])
}

/// Tests the observation against the null samples and names the effect.
pub(super) fn decide(prep: &Prepared, null: &NullData, options: &DiagnosisOptions) -> Diagnosis {
    let alpha = options.false_alarm;
    let sigma2 = (options.noise_rms_3d_mm * 1e-3).powi(2) / 3.0;
    let base = prep.baseline_fit();
    let after_base = Residualised::new(prep, null, base);
    let gap = gap_test(prep, &after_base, sigma2, alpha);
    let mut scored = score_candidates(prep, (base, &after_base), (gap.g_obs, &gap.g_null), sigma2);
    let samples = gap.g_null.len();
    let z_threshold = mark_significant(&mut scored, samples, alpha);
    rank(&mut scored);
    check_plausibility(prep, &mut scored);
    prefer_simpler_member(prep, &mut scored);
    weigh(&mut scored);
    let g_fit = refit_named(prep, &mut scored, gap.g_obs, sigma2);
    let rms_before = chi2_to_rms_mm(g_fit, sigma2, prep);
    let noise_before = chi2_to_rms_mm(gap.g_mean, sigma2, prep);
    let gap_before = (rms_before.powi(2) - noise_before.powi(2)).max(0.0).sqrt();
    let best = scored.iter().find(|s| nameable(s));
    let fraction_closed = match best {
        Some(b) if gap_before > 0.0 => 1.0 - (b.score.gap_after_mm / gap_before).powi(2),
        _ => 0.0,
    };
    let mut evidence = Evidence {
        gap: &gap,
        alpha,
        z_threshold,
        rms_before_mm: rms_before,
        noise_before_mm: noise_before,
        gap_before_mm: gap_before,
        fraction_closed,
    };
    let pair =
        best.and_then(|b| pair::second_effect(prep, (base, &after_base), &scored, b, (gap.g_obs, sigma2, alpha)));
    let (mut v, effects) = match (best, pair) {
        (Some(b), Some(pair)) => two_effects(prep, &mut evidence, b, pair, sigma2, options.explained_fraction),
        _ => (evidence.verdict(best, options.explained_fraction), Vec::new()),
    };
    let fraction_closed = evidence.fraction_closed;
    if best.is_none()
        && let Some(s) = scored.iter().find(|s| s.score.significant)
    {
        v.verdict += &format!(
            "; {}{} beats noise but is not named: {}",
            s.score.effect,
            s.score.joint.map_or(String::new(), |j| format!(" on joint {j}")),
            s.score.implausible.as_deref().unwrap_or("implausible")
        );
    }
    let base_params = prep.x_geometric.ncols();
    let member = scored
        .iter()
        .find(|s| nameable(s) && s.score.effect == v.effect && s.score.joint == v.joint)
        .map(|s| s.score.member.clone());
    let (where_, features) = where_entries(prep, (null, &after_base), rms_before, noise_before, alpha);
    Diagnosis {
        outcome: Outcome {
            effect: v.effect,
            joint: v.joint,
            confidence: v.confidence,
            gap_before_mm: gap_before,
            gap_after_mm: v.gap_after_mm,
        },
        where_,
        features,
        effects,
        candidates: scored.into_iter().map(|s| s.score).collect(),
        member,
        parameters: v.parameters,
        noise_rms_3d_mm: options.noise_rms_3d_mm,
        noise_source: "given".into(),
        tool_targets: None,
        poses: {
            let training = super::training_mask(&prep.poses).iter().filter(|t| **t).count();
            super::result::PoseSplit {
                training,
                held_out: prep.poses.len() - training,
                left_out: prep.poses_left_out,
            }
        },
        outliers: Vec::new(),
        warnings: Vec::new(),
        heldout_rms_before_mm: rms_before,
        noise_only_rms_mm: noise_before,
        gap_sigmas: gap.gap_sigmas,
        detectable_gap_mm: gap.detectable_gap_mm,
        false_alarm: alpha,
        null_samples: samples,
        refit_rank: super::result::RefitRank {
            rank: base.rank,
            parameters: base_params,
        },
        fraction_closed,
        verdict: v.verdict,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scored(candidate: Candidate, z_null: Vec<f64>, z: f64, outside: f64) -> Scored {
        Scored {
            candidate,
            score: CandidateScore {
                effect: candidate.effect_name().into(),
                member: candidate.member_name(),
                joint: candidate.joint(),
                heldout_rms_mm: 0.3,
                gap_after_mm: 0.0,
                improvement_chi2: 1.0,
                z,
                significant: false,
                outside_refit_fraction: outside,
                weight: 0.0,
                parameters: Vec::new(),
                implausible: None,
            },
            chi2: 0.0,
            chi2_null: Vec::new(),
            z_null,
            kind_weight: 0.0,
        }
    }

    /// A synthetic refit problem: 4 geometric columns and candidates of 2, 1 and 2 columns, of
    /// which the second lies wholly inside the geometric span (absorbed) and the third has one
    /// column inside it and one outside; an observation with an effect and noise, and 60
    /// noise-only samples (a deterministic pseudo-random sequence, no seed to tune).
    struct Synthetic {
        g: DMatrix<f64>,
        candidates: Vec<DMatrix<f64>>,
        observed: DMatrix<f64>,
        null: DMatrix<f64>,
        train_rows: usize,
    }

    fn synthetic() -> Synthetic {
        let rows = 120;
        let t = |r: usize| r as f64 / rows as f64 * 6.0;
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut noise = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let g = DMatrix::from_fn(rows, 4, |r, c| match c {
            0 => 1.0,
            1 => t(r),
            2 => t(r).sin(),
            _ => (0.5 * t(r)).cos(),
        });
        let x1 = DMatrix::from_fn(rows, 2, |r, c| if c == 0 { (3.0 * t(r)).sin() } else { t(r) * t(r) });
        let x2 = DMatrix::from_fn(rows, 1, |r, _| 2.0 * t(r) - 3.0 * t(r).sin());
        let x3 = DMatrix::from_fn(rows, 2, |r, c| if c == 0 { 1.0 + t(r) } else { (5.0 * t(r)).sin() });
        let observed = DMatrix::from_fn(rows, 1, |r, _| 0.3 * t(r) + 0.2 * (3.0 * t(r)).sin() + 0.05 * noise());
        let null = DMatrix::from_fn(rows, 60, |_, _| 0.05 * noise());
        Synthetic {
            g,
            candidates: vec![x1, x2, x3],
            observed,
            null,
            train_rows: rows / 2,
        }
    }

    /// The reference: one fit of all columns at once (`[G | below | X]`, a truncated SVD of
    /// the whole design, as the diagnosis computed it before the blocks): held-out chi-square
    /// of the observation and of the null samples, the last `k` parameters and their
    /// `(X^T X)^+` diagonal, the outside fraction of `X` against the fit of what is below.
    #[allow(clippy::type_complexity)]
    fn full_refit(
        s: &Synthetic,
        below: &[&DMatrix<f64>],
        x: &DMatrix<f64>,
    ) -> (f64, Vec<f64>, Vec<f64>, Vec<f64>, f64, usize) {
        let mut cols: Vec<_> = s.g.column_iter().map(|c| c.into_owned()).collect();
        for b in below {
            cols.extend(b.column_iter().map(|c| c.into_owned()));
        }
        let under = DMatrix::from_columns(&cols);
        cols.extend(x.column_iter().map(|c| c.into_owned()));
        let all = DMatrix::from_columns(&cols);
        let n = s.train_rows;
        let split = |m: &DMatrix<f64>| (m.rows(0, n).into_owned(), m.rows(n, m.nrows() - n).into_owned());
        let fit = LinearFit::new(&split(&all).0, &split(&all).1);
        let (ot, oh) = split(&s.observed);
        let (nt, nh) = split(&s.null);
        let chi2 = fit.heldout(&ot, &oh).norm_squared();
        let chi2_null = crate::diagnosis::column_ssr(&fit.heldout(&nt, &nh));
        let p = fit.params(&ot.column(0).into_owned());
        let k = x.ncols();
        let g = all.ncols() - k;
        let params = (0..k).map(|i| p[g + i]).collect();
        let diag = (0..k).map(|i| fit.normal_inverse[(g + i, g + i)]).collect();
        let outside = LinearFit::new(&split(&under).0, &split(&under).1).outside_fraction(&split(x).0);
        (chi2, chi2_null, params, diag, outside, fit.rank)
    }

    /// The Frisch-Waugh-Lovell blocks the diagnosis scores with give the full refit's held-out
    /// chi-squares (observation and every noise-only sample), parameters, their covariance
    /// diagonal and outside fractions, for single candidates and for a second one on top of a
    /// first, with and without absorbed columns; an absorbed candidate is absorbed on both
    /// paths. Tolerance: both are backward-stable orthogonal solves of the same problem; the
    /// column-scaled designs here have condition numbers below 1e3, so each result agrees to
    /// about `1e3 x 120 rows x eps = 3e-11` relative; `1e-8` leaves a factor 300 for the
    /// growth through the residualisation. An absorbed candidate's chi-square equals the
    /// refit's alone to the same relative rounding; its parameters are rounding on both paths
    /// (not compared).
    #[test]
    fn blocks_score_like_the_full_refit() {
        let s = synthetic();
        let n = s.train_rows;
        let split = |m: &DMatrix<f64>| (m.rows(0, n).into_owned(), m.rows(n, m.nrows() - n).into_owned());
        let base = LinearFit::new(&split(&s.g).0, &split(&s.g).1);
        let (nt, nh) = split(&s.null);
        let after_base = Residualised::of(&base, &split(&s.observed), (&nt, &nh));
        let close = |a: f64, b: f64, scale: f64| (a - b).abs() <= 1e-8 * scale.abs().max(b.abs());
        let check = |after: &Residualised, below: &[&DMatrix<f64>], blocks: &[&Block], x: &DMatrix<f64>| {
            let block = base.block(blocks, &split(x).0, &split(x).1);
            let (chi2, chi2_null) = after.heldout_chi2(&block, 1.0);
            let (p, _) = after.params(&block);
            let (r_chi2, r_null, r_p, r_diag, r_outside, r_rank) = full_refit(&s, below, x);
            let rank_below: usize = blocks.iter().map(|b| b.rank).sum();
            assert_eq!(base.rank + rank_below + block.rank, r_rank, "the same directions kept");
            assert!(close(chi2, r_chi2, r_chi2), "chi2 {chi2} against {r_chi2}");
            for (a, b) in chi2_null.iter().zip(&r_null) {
                assert!(close(*a, *b, *b), "null chi2 {a} against {b}");
            }
            assert_eq!(absorbed_fraction(block.outside_fraction), absorbed_fraction(r_outside));
            if !absorbed_fraction(r_outside) {
                assert!(close(block.outside_fraction, r_outside, 1.0));
                // With a direction dropped the two paths' minimum-norm conventions differ (the
                // whole design's column scaling against the block's): parameters compared only
                // when the block keeps every column.
                for i in 0..x.ncols() {
                    if block.rank == x.ncols() {
                        let scale = r_p.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                        assert!(close(p[i], r_p[i], scale), "parameter {i}: {} against {}", p[i], r_p[i]);
                        assert!(close(block.normal_inverse[(i, i)], r_diag[i], r_diag[i]));
                    }
                }
            }
            (block, r_outside)
        };
        let mut outside = Vec::new();
        for x in &s.candidates {
            outside.push(check(&after_base, &[], &[], x).1);
        }
        assert!(outside[0] > 0.05 && outside[2] > 0.05, "outside the refit: {outside:?}");
        assert!(
            absorbed_fraction(outside[1]),
            "the second candidate lies in the refit's span"
        );
        // A second effect on top of the first.
        let first = base.block(&[], &split(&s.candidates[0]).0, &split(&s.candidates[0]).1);
        let after_first = after_base.after(&first);
        for x in &s.candidates[1..] {
            check(&after_first, &[&s.candidates[0]], &[&first], x);
        }
    }

    /// A candidate the refit absorbs is never significant, whatever its z (rounding noise
    /// standardised by rounding noise), and takes no part in the family-wise maximum.
    #[test]
    fn an_absorbed_candidate_is_never_significant() {
        let null: Vec<f64> = (0..200).map(|k| (k as f64 / 199.0) * 3.0).collect();
        let harmonic = Candidate::GearHarmonic {
            joint: 5,
            order: 2,
            period: crate::physics::HarmonicPeriod::Transmission,
        };
        let mut s = vec![
            scored(Candidate::InstrumentScale, null.clone(), 10.0, 1e-11),
            scored(harmonic, vec![0.0; 200], 10.0, 0.5),
        ];
        let threshold = mark_significant(&mut s, 200, 0.05);
        assert_eq!(
            threshold.to_bits(),
            0f64.to_bits(),
            "the maximum is the other candidate's null z alone"
        );
        assert!(!s[0].score.significant);
        assert!(s[1].score.significant);
    }
}
