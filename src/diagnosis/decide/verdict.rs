//! The verdict of [`decide`](super::decide) (module docs of [`crate::diagnosis`], step 4): a
//! significant candidate is named when what it leaves is at the noise level or it closes
//! enough of the gap; otherwise the omnibus gap test decides `none` or `unexplained`.

use super::{GapTest, Scored};
use crate::diagnosis::Parameter;
use crate::numerics::stats::{QuantileMethod, quantile, upper_tail};

/// The outcome's fields as decided.
pub(super) struct Verdict {
    /// The named effect, `none` or `unexplained`.
    pub(super) effect: String,
    /// The named effect's joint, if any.
    pub(super) joint: Option<usize>,
    /// Confidence in the outcome.
    pub(super) confidence: f64,
    /// The gap (mm) left after the named effect.
    pub(super) gap_after_mm: f64,
    /// The named effect's fitted parameters.
    pub(super) parameters: Vec<Parameter>,
    /// The sentence explaining the outcome.
    pub(super) verdict: String,
}

/// What the verdict is decided from: the tests' results and the gap before any candidate.
pub(super) struct Evidence<'a> {
    /// The omnibus gap test.
    pub(super) gap: &'a GapTest,
    /// False-alarm rate.
    pub(super) alpha: f64,
    /// The family-wise z threshold.
    pub(super) z_threshold: f64,
    /// Held-out RMS (mm) of the baseline refit.
    pub(super) rms_before_mm: f64,
    /// Its noise-only RMS (mm).
    pub(super) noise_before_mm: f64,
    /// The gap (mm) before any candidate.
    pub(super) gap_before_mm: f64,
    /// Fraction of the gap's variance the best candidate closes.
    pub(super) fraction_closed: f64,
}

/// The name of a candidate with its joint, e.g. `backlash on joint 2`.
fn named(b: &Scored) -> String {
    format!(
        "{}{}",
        b.score.effect,
        b.score.joint.map_or(String::new(), |j| format!(" on joint {j}"))
    )
}

impl Evidence<'_> {
    /// A significant candidate is tested first (it is the more powerful, targeted test; its
    /// false-alarm rate is family-wise); the omnibus gap test decides `none` vs `unexplained`
    /// only when no candidate beats noise.
    pub(super) fn verdict(&self, best: Option<&Scored>, explained_fraction: f64) -> Verdict {
        match best {
            Some(b) => self.candidate_verdict(b, explained_fraction),
            None if self.gap.g_obs > self.gap.g_q => self.unexplained_gap(),
            None => self.at_noise_level(),
        }
    }

    /// The best significant candidate `b` is named when what it leaves is at the noise level
    /// or it closes `explained_fraction` of the gap's variance; else `unexplained`.
    fn candidate_verdict(&self, b: &Scored, explained_fraction: f64) -> Verdict {
        let (alpha, z_threshold, fraction_closed) = (self.alpha, self.z_threshold, self.fraction_closed);
        let (gap_before, gap_sigmas) = (self.gap_before_mm, self.gap.gap_sigmas);
        let remaining_ok = b.chi2 <= quantile(&b.chi2_null, 1.0 - alpha, QuantileMethod::InverseCdf);
        if remaining_ok || fraction_closed >= explained_fraction {
            Verdict {
                effect: b.score.effect.clone(),
                joint: b.candidate.joint(),
                confidence: b.kind_weight,
                gap_after_mm: b.score.gap_after_mm,
                parameters: b.score.parameters.clone(),
                verdict: format!(
                    "{} (z = {:.1} over the noise-only threshold {z_threshold:.1}) closes {:.0} % of the gap's variance ({gap_before:.3} -> {:.3} mm){}",
                    named(b),
                    b.score.z,
                    100.0 * fraction_closed.max(0.0),
                    b.score.gap_after_mm,
                    if remaining_ok {
                        "; what is left is at the noise level"
                    } else {
                        ""
                    }
                ),
            }
        } else {
            Verdict {
                effect: "unexplained".to_owned(),
                joint: None,
                confidence: 1.0 - upper_tail(&b.chi2_null, b.chi2),
                gap_after_mm: gap_before,
                parameters: vec![],
                verdict: format!(
                    "gap {gap_before:.3} mm ({gap_sigmas:.1} sigma); the best candidate, {}, closes only {:.0} % of its variance and leaves {:.3} mm above noise",
                    named(b),
                    100.0 * fraction_closed.max(0.0),
                    b.score.gap_after_mm
                ),
            }
        }
    }

    /// No candidate beats noise but the gap test flags the gap: `unexplained`.
    fn unexplained_gap(&self) -> Verdict {
        let (z_threshold, gap_before, gap_sigmas) = (self.z_threshold, self.gap_before_mm, self.gap.gap_sigmas);
        Verdict {
            effect: "unexplained".to_owned(),
            joint: None,
            confidence: 1.0 - self.gap.p_gap,
            gap_after_mm: gap_before,
            parameters: vec![],
            verdict: format!(
                "gap {gap_before:.3} mm ({gap_sigmas:.1} sigma) and no candidate beats noise (threshold z = {z_threshold:.1})"
            ),
        }
    }

    /// Neither a candidate nor the gap test beats noise: `none`.
    fn at_noise_level(&self) -> Verdict {
        let (alpha, z_threshold, gap_before) = (self.alpha, self.z_threshold, self.gap_before_mm);
        let (rms_before, noise_before) = (self.rms_before_mm, self.noise_before_mm);
        let detectable_gap_mm = self.gap.detectable_gap_mm;
        Verdict {
            effect: "none".to_owned(),
            joint: None,
            confidence: self.gap.p_gap,
            gap_after_mm: gap_before,
            parameters: vec![],
            verdict: format!(
                "held-out residual {rms_before:.3} mm is at the noise level (noise only {noise_before:.3} mm; gap {gap_before:.3} mm below the {detectable_gap_mm:.3} mm the test flags at false-alarm rate {alpha}) and no candidate beats noise (z threshold {z_threshold:.1})"
            ),
        }
    }
}
