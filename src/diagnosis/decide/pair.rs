//! Two effects at once (`docs/diagnosis.md`, "Two effects"): forward selection over the
//! families. With the first effect `b` chosen, every candidate of another kind (another family
//! or joint) is fitted together with it on top of the refit, and its held-out improvement over
//! `b` alone is standardised against the same noise-only samples; the threshold is the
//! `1 - alpha` quantile of the noise-only maximum over those candidates that the refit and the
//! first do not absorb (family-wise, as for the first). Every fit is a Frisch-Waugh-Lovell
//! block on top of the refit and the first effect's block (the joint fit's residuals and
//! parameters, `calibration::refine::Block`). The best significant candidate with plausible parameters is the second effect.
//! Each effect's share of the closed gap is its Shapley value over the two orders of adding
//! them (Shapley, 1953; for two players the mean of the two marginal contributions).

use super::{
    Block, FitParams, LinearFit, Prepared, Residualised, Scored, absorbed_fraction, candidate_block, family_threshold,
    fitted_parameters, implausible_fit,
};
use crate::diagnosis::{Candidate, Parameter};
use crate::numerics::stats::{mean, std_dev};

/// The second effect and the pair's fit.
pub(super) struct Pair {
    /// The second candidate.
    pub(super) second: Candidate,
    /// Its fitted parameters (with the first's and the refit's).
    pub(super) parameters: Vec<Parameter>,
    /// Held-out chi-square of the pair, and of its noise-only samples.
    pub(super) chi2: f64,
    pub(super) chi2_null: Vec<f64>,
    /// The second's improvement over the first alone, in noise-only standard deviations, and
    /// the family-wise threshold it beat.
    pub(super) z: f64,
    pub(super) z_threshold: f64,
    /// Shares of the closed gap (first, second), summing to 1.
    pub(super) shares: [f64; 2],
}

/// One second candidate's held-out chi-square with the first, and its null samples.
struct Trial {
    candidate: Candidate,
    /// Its columns on top of the refit and the first.
    block: Block,
    chi2: f64,
    chi2_null: Vec<f64>,
    z: f64,
    z_null: Vec<f64>,
}

impl Trial {
    /// The refit and the first absorb it ([`absorbed_fraction`] of its block's outside
    /// fraction): neither tested nor in the family-wise maximum.
    fn absorbed(&self) -> bool {
        absorbed_fraction(self.block.outside_fraction)
    }
}

/// The second effect on top of `first` (module docs), if one is significant and plausible.
/// `g_obs` is the baseline's held-out chi-square (linear), `scored` every candidate alone;
/// every fit is a Frisch-Waugh-Lovell [`Block`] on top of the refit `base` and the first's.
pub(super) fn second_effect(
    prep: &Prepared,
    (base, after_base): (&LinearFit, &Residualised),
    scored: &[Scored],
    first: &Scored,
    (g_obs, sigma2, alpha): (f64, f64, f64),
) -> Option<Pair> {
    let x_first = &prep.x_candidates.iter().find(|(c, _)| *c == first.candidate)?.1;
    let b_first = candidate_block(prep, base, &[], x_first);
    let (chi2_first, null_first) = after_base.heldout_chi2(&b_first, sigma2);
    let after_first = after_base.after(&b_first);
    let (others, rows): (Vec<Candidate>, Vec<_>) = prep
        .x_candidates
        .iter()
        .filter(|(c, _)| !c.same_kind(&first.candidate))
        .map(|(c, x_c)| (*c, prep.rows(x_c)))
        .unzip();
    let blocks = base.blocks(&[&b_first], &rows);
    let chi2s = after_first.heldout_chi2_all(&blocks.iter().collect::<Vec<_>>(), sigma2);
    let mut trials: Vec<Trial> = others
        .into_iter()
        .zip(blocks)
        .zip(chi2s)
        .map(|((c, block), (chi2, chi2_null))| {
            let t_null: Vec<f64> = null_first.iter().zip(&chi2_null).map(|(a, b)| a - b).collect();
            let (mu, sd) = (mean(&t_null), std_dev(&t_null).max(1e-12));
            Trial {
                candidate: c,
                block,
                chi2,
                chi2_null,
                z: (chi2_first - chi2 - mu) / sd,
                z_null: t_null.iter().map(|t| (t - mu) / sd).collect(),
            }
        })
        .collect();
    let tested = trials.iter().filter(|t| !t.absorbed()).map(|t| &t.z_null[..]);
    let z_threshold = family_threshold(tested, null_first.len(), alpha);
    trials.retain(|t| t.z > z_threshold && !t.absorbed());
    trials.sort_by(|a, b| a.chi2.total_cmp(&b.chi2));
    let rank_below = base.rank + b_first.rank;
    trials.into_iter().find_map(|t| {
        let (p, left) = after_first.params(&t.block);
        let parameters = fitted_parameters(
            t.candidate,
            FitParams::of_block(&t.block, &p, rank_below),
            left,
            prep,
            sigma2,
        );
        if implausible_fit(prep, t.candidate, &parameters).is_some() {
            return None;
        }
        let alone = scored
            .iter()
            .find(|s| s.candidate == t.candidate)
            .map_or(g_obs, |s| s.chi2);
        let total = g_obs - t.chi2;
        let share_first = if total > 0.0 {
            (((g_obs - chi2_first) + (alone - t.chi2)) / 2.0 / total).clamp(0.0, 1.0)
        } else {
            0.5
        };
        Some(Pair {
            second: t.candidate,
            parameters,
            chi2: t.chi2,
            chi2_null: t.chi2_null,
            z: t.z,
            z_threshold,
            shares: [share_first, 1.0 - share_first],
        })
    })
}
