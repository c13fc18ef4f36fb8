//! Scoring a blind suite: confusion matrix of the effect (expected vs diagnosed), accuracy on
//! the in-set cases above their detectable size, joint accuracy, `none` and `unexplained`
//! rates, and the gap shrinkage of correctly named effects; a per-case table.

use super::CaseKey;
use crate::diagnosis::Diagnosis;
use serde::{Deserialize, Serialize};
use std::fmt::Write;

/// One scored case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CaseResult {
    /// The hidden truth.
    pub key: CaseKey,
    /// The diagnosis of the CSV alone.
    pub diagnosis: Diagnosis,
    /// Trace of the effect after the refit over the smallest gap the diagnoser flags (>= 1:
    /// detectable; 0 when the refit absorbs the effect), `None` without an effect.
    pub size_ratio: Option<f64>,
    /// The magnitude at which that ratio is 1 (unit of the key's `magnitude_unit`); `None`
    /// without an effect or when the refit absorbs it (no magnitude is detectable).
    pub detectable_magnitude: Option<f64>,
}

/// Counts of (expected, diagnosed) effect names.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ConfusionMatrix {
    /// Row labels (expected answers).
    pub expected: Vec<String>,
    /// Column labels (diagnosed answers).
    pub diagnosed: Vec<String>,
    /// `counts[i][j]`: cases expecting `expected[i]` diagnosed as `diagnosed[j]`.
    pub counts: Vec<Vec<usize>>,
}

/// A held-out gap before and after the named effect is added.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct GapBeforeAfter {
    /// Before \[mm\].
    pub before_mm: f64,
    /// After \[mm\].
    pub after_mm: f64,
}

/// Before schema 2: `[before, after]`.
impl From<[f64; 2]> for GapBeforeAfter {
    fn from([before_mm, after_mm]: [f64; 2]) -> Self {
        GapBeforeAfter { before_mm, after_mm }
    }
}

/// The suite's score (fractions are NaN when their set is empty).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct BlindScore {
    /// Cases scored.
    pub cases: usize,
    /// Fraction of all cases with the expected effect name.
    pub effect_accuracy: f64,
    /// In-set effect cases above their detectable size (size ratio >= 1).
    pub detectable_in_set: usize,
    /// Among those, the fraction named right.
    pub detectable_in_set_accuracy: f64,
    /// Among correctly named per-joint effects, the fraction with the right joint.
    pub joint_accuracy: f64,
    /// In-set effect cases below their detectable size.
    pub undetectable_in_set: usize,
    /// Among those, the fraction read as `none` or named right (never a wrong name).
    pub undetectable_honest: f64,
    /// Fraction of no-effect cases read as `none`.
    pub none_accuracy: f64,
    /// Out-of-set cases above their detectable size.
    #[serde(default)]
    pub detectable_out_of_set: usize,
    /// Among those, the fraction read as `unexplained`.
    pub out_of_set_unexplained: f64,
    /// Out-of-set cases below their detectable size.
    #[serde(default)]
    pub undetectable_out_of_set: usize,
    /// Among those, the fraction read as `none` or `unexplained` (never a name).
    #[serde(default)]
    pub undetectable_out_of_set_honest: f64,
    /// Among cases with a named effect (not `none`/`unexplained`), the fraction correct.
    pub named_precision: f64,
    /// Among correctly named effects, the fraction whose held-out gap shrank by >= 70 %.
    pub shrunk_70: f64,
    /// Among correctly named effects whose gap before is large enough for a 70 % shrink to be
    /// resolved (`0.3 gap_before >= detectable_gap_mm`, the smallest gap the noise-only test
    /// flags), the fraction that shrank by >= 70 %.
    pub shrunk_70_resolvable: f64,
    /// Number of those resolvable cases.
    pub resolvable: usize,
    /// Among correctly named effects, the fraction that shrank by >= 70 % or whose remaining
    /// gap is below `detectable_gap_mm` (not distinguishable from noise).
    pub shrunk_70_or_at_noise: f64,
    /// Median of `gap_after / gap_before` over correctly named effects.
    pub median_gap_ratio: f64,
    /// Mean `gap_before` and `gap_after` over correctly named effects.
    #[serde(
        alias = "mean_gap_before_after_mm",
        deserialize_with = "crate::json_file::named_or_old::<_, GapBeforeAfter, [f64; 2]>"
    )]
    pub mean_gap: GapBeforeAfter,
    /// Two-effect cases.
    #[serde(default)]
    pub two_effect_cases: usize,
    /// Among those, the fraction with both effects named on their joints.
    #[serde(default)]
    pub two_effects_both_named: f64,
    /// Per drawn family member of the in-set cases above their detectable size: how many,
    /// and how many named right.
    #[serde(default)]
    pub shapes: Vec<ShapeRow>,
    /// The confusion matrix.
    pub confusion: ConfusionMatrix,
}

/// One family member's line of [`BlindScore::shapes`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct ShapeRow {
    /// The case's effect.
    pub effect: String,
    /// The drawn member (`CaseKey::shape`).
    pub shape: String,
    /// Cases above their detectable size.
    pub cases: usize,
    /// Of those, named right.
    pub named_right: usize,
}

/// The diagnosed answer as a case label: the sorted names of `effects` joined by `+` when two
/// effects are named, else the verdict's effect.
pub fn diagnosed_label(d: &Diagnosis) -> String {
    if d.effects.len() >= 2 {
        let mut names: Vec<&str> = d.effects.iter().map(|e| e.effect.as_str()).collect();
        names.sort_unstable();
        names.join("+")
    } else {
        d.outcome.effect.clone()
    }
}

/// Whether a two-effect case's both effects are named on their joints.
fn both_named(k: &CaseKey, d: &Diagnosis) -> bool {
    let on = |effect: &str, joint: Option<usize>| d.effects.iter().any(|e| e.effect == effect && e.joint == joint);
    k.second
        .as_ref()
        .is_some_and(|s| on(&s.effect, s.joint) && on("joint_compliance", k.joint))
}

/// The per-member rows of the in-set cases above their detectable size.
fn shape_rows(results: &[CaseResult]) -> Vec<ShapeRow> {
    let mut rows: Vec<ShapeRow> = Vec::new();
    for r in results {
        let k = &r.key;
        if k.expected == "unexplained" || k.effect == "none" || !r.size_ratio.is_some_and(|s| s >= 1.0) {
            continue;
        }
        let right = k.expected == diagnosed_label(&r.diagnosis);
        match rows.iter_mut().find(|x| x.effect == k.effect && x.shape == k.shape) {
            Some(x) => {
                x.cases += 1;
                x.named_right += usize::from(right);
            }
            None => rows.push(ShapeRow {
                effect: k.effect.clone(),
                shape: k.shape.clone(),
                cases: 1,
                named_right: usize::from(right),
            }),
        }
    }
    rows.sort_by(|a, b| (&a.effect, &a.shape).cmp(&(&b.effect, &b.shape)));
    rows
}

/// Case counts of [`score`], and the gaps of the correctly named effects.
#[derive(Default)]
struct Tally {
    /// Cases with the expected effect name.
    correct: usize,
    /// In-set effect cases above their detectable size.
    det: usize,
    /// Of those, named right.
    det_ok: usize,
    /// Correctly named per-joint effects.
    joint_total: usize,
    /// Of those, with the right joint.
    joint_ok: usize,
    /// In-set effect cases below their detectable size.
    undet: usize,
    /// Of those, read as `none` or named right.
    undet_ok: usize,
    /// No-effect cases.
    nones: usize,
    /// Of those, read as `none`.
    nones_ok: usize,
    /// Out-of-set cases above their detectable size.
    out: usize,
    /// Of those, read as `unexplained`.
    out_ok: usize,
    /// Out-of-set cases below their detectable size.
    out_undet: usize,
    /// Of those, not given a name.
    out_undet_ok: usize,
    /// Cases with a named effect.
    named: usize,
    /// Of those, correct.
    named_ok: usize,
    /// Correctly named effects whose gap shrank by >= 70 %.
    shrunk: usize,
    /// Correctly named effects whose 70 % shrink is resolvable.
    resolvable: usize,
    /// Of those, shrunk by >= 70 %.
    resolvable_shrunk: usize,
    /// Correctly named effects shrunk by >= 70 % or left at the noise level.
    shrunk_or_noise: usize,
    /// `gap_after / gap_before` of the correctly named effects with a gap before.
    gap_ratios: Vec<f64>,
    /// Sum of `gap_before` over the correctly named effects \[mm\].
    gap_before_sum_mm: f64,
    /// Sum of `gap_after` over the correctly named effects \[mm\].
    gap_after_sum_mm: f64,
    /// Two-effect cases.
    two: usize,
    /// Of those, both named on their joints.
    two_both: usize,
}

fn frac(a: usize, b: usize) -> f64 {
    if b == 0 { f64::NAN } else { a as f64 / b as f64 }
}

fn is_named(effect: &str) -> bool {
    effect != "none" && effect != "unexplained"
}

/// The confusion matrix of expected against diagnosed effect names (labels sorted).
fn confusion_matrix(results: &[CaseResult]) -> ConfusionMatrix {
    let mut labels: Vec<String> = Vec::new();
    for r in results {
        for l in [r.key.expected.clone(), diagnosed_label(&r.diagnosis)] {
            if !labels.contains(&l) {
                labels.push(l);
            }
        }
    }
    labels.sort();
    let mut counts = vec![vec![0; labels.len()]; labels.len()];
    let pos = |l: &String| labels.iter().position(|x| x == l).unwrap_or(0);
    for r in results {
        let (k, d) = (&r.key, &r.diagnosis);
        counts[pos(&k.expected)][pos(&diagnosed_label(d))] += 1;
    }
    ConfusionMatrix {
        expected: labels.clone(),
        diagnosed: labels,
        counts,
    }
}

impl Tally {
    /// Counts case `r` in its category (no effect, out-of-set or in-set, above or below its
    /// detectable size) and, when it is named right, its gap shrinkage and joint.
    fn add(&mut self, r: &CaseResult) {
        let n = self;
        let (k, d) = (&r.key, &r.diagnosis);
        let right = k.expected == diagnosed_label(d);
        n.correct += usize::from(right);
        n.named += usize::from(is_named(&d.outcome.effect));
        if k.second.is_some() {
            n.two += 1;
            n.two_both += usize::from(right && both_named(k, d));
            n.named_ok += usize::from(right);
            return;
        }
        if k.effect == "none" {
            n.nones += 1;
            n.nones_ok += usize::from(right);
        } else if k.expected == "unexplained" && r.size_ratio.is_none_or(|s| s >= 1.0) {
            n.out += 1;
            n.out_ok += usize::from(right);
        } else if k.expected == "unexplained" {
            n.out_undet += 1;
            n.out_undet_ok += usize::from(!is_named(&d.outcome.effect));
        } else if r.size_ratio.is_some_and(|s| s >= 1.0) {
            n.det += 1;
            n.det_ok += usize::from(right);
        } else {
            n.undet += 1;
            n.undet_ok += usize::from(right || d.outcome.effect == "none");
        }
        if right && is_named(&d.outcome.effect) {
            n.add_named_right(r);
        }
    }

    /// Counts a correctly named case `r`: its gap shrinkage and, for a per-joint effect, its
    /// joint.
    fn add_named_right(&mut self, r: &CaseResult) {
        let n = self;
        let (k, d) = (&r.key, &r.diagnosis);
        n.named_ok += 1;
        if d.outcome.gap_before_mm > 0.0 {
            n.gap_ratios.push(d.outcome.gap_after_mm / d.outcome.gap_before_mm);
            let shrunk = d.outcome.gap_after_mm <= 0.3 * d.outcome.gap_before_mm;
            n.shrunk += usize::from(shrunk);
            n.shrunk_or_noise += usize::from(shrunk || d.outcome.gap_after_mm < d.detectable_gap_mm);
            if 0.3 * d.outcome.gap_before_mm >= d.detectable_gap_mm {
                n.resolvable += 1;
                n.resolvable_shrunk += usize::from(shrunk);
            }
        }
        n.gap_before_sum_mm += d.outcome.gap_before_mm;
        n.gap_after_sum_mm += d.outcome.gap_after_mm;
        if k.joint.is_some() {
            n.joint_total += 1;
            n.joint_ok += usize::from(k.joint == d.outcome.joint);
        }
    }

    /// The score of `cases` cases from the counts (gap ratios sorted) and the confusion matrix.
    fn into_score(self, cases: usize, confusion: ConfusionMatrix, shapes: Vec<ShapeRow>) -> BlindScore {
        let n = self;
        let ratios = n.gap_ratios;
        BlindScore {
            cases,
            effect_accuracy: frac(n.correct, cases),
            detectable_in_set: n.det,
            detectable_in_set_accuracy: frac(n.det_ok, n.det),
            joint_accuracy: frac(n.joint_ok, n.joint_total),
            undetectable_in_set: n.undet,
            undetectable_honest: frac(n.undet_ok, n.undet),
            none_accuracy: frac(n.nones_ok, n.nones),
            detectable_out_of_set: n.out,
            out_of_set_unexplained: frac(n.out_ok, n.out),
            undetectable_out_of_set: n.out_undet,
            undetectable_out_of_set_honest: frac(n.out_undet_ok, n.out_undet),
            named_precision: frac(n.named_ok, n.named),
            shrunk_70: frac(n.shrunk, ratios.len()),
            shrunk_70_resolvable: frac(n.resolvable_shrunk, n.resolvable),
            resolvable: n.resolvable,
            shrunk_70_or_at_noise: frac(n.shrunk_or_noise, ratios.len()),
            median_gap_ratio: if ratios.is_empty() {
                f64::NAN
            } else {
                ratios[ratios.len() / 2]
            },
            mean_gap: GapBeforeAfter {
                before_mm: n.gap_before_sum_mm / n.named_ok.max(1) as f64,
                after_mm: n.gap_after_sum_mm / n.named_ok.max(1) as f64,
            },
            two_effect_cases: n.two,
            two_effects_both_named: frac(n.two_both, n.two),
            shapes,
            confusion,
        }
    }
}

/// `v` with `places` decimals, or `-` where it is undefined (a rate over no case).
fn decimals(v: f64, places: usize) -> String {
    if v.is_finite() {
        format!("{v:.places$}")
    } else {
        "-".into()
    }
}

/// Scores diagnoses against their keys.
pub fn score(results: &[CaseResult]) -> BlindScore {
    let confusion = confusion_matrix(results);
    let mut n = Tally::default();
    for r in results {
        n.add(r);
    }
    n.gap_ratios.sort_by(f64::total_cmp);
    n.into_score(results.len(), confusion, shape_rows(results))
}

impl BlindScore {
    /// Markdown summary.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let f = |v: f64| decimals(v, 2);
        let _ = writeln!(
            s,
            "{} cases: in-set effects above their detectable size named right {} ({} cases), right joint {}; \
             below it read `none` or right {} ({} cases); no-effect cases `none` {}; out-of-set effects above their \
             detectable size `unexplained` {} ({} cases), below it `none` or `unexplained` {} ({} cases); \
             named precision {}; gap shrunk >= 70 % in {} of the found cases ({} of the {} where the noise resolves it; \
             shrunk or left below the detectable gap {}; median after/before {}, mean {} -> {} mm); \
             all cases right {}\n",
            self.cases,
            f(self.detectable_in_set_accuracy),
            self.detectable_in_set,
            f(self.joint_accuracy),
            f(self.undetectable_honest),
            self.undetectable_in_set,
            f(self.none_accuracy),
            f(self.out_of_set_unexplained),
            self.detectable_out_of_set,
            f(self.undetectable_out_of_set_honest),
            self.undetectable_out_of_set,
            f(self.named_precision),
            f(self.shrunk_70),
            f(self.shrunk_70_resolvable),
            self.resolvable,
            f(self.shrunk_70_or_at_noise),
            f(self.median_gap_ratio),
            decimals(self.mean_gap.before_mm, 3),
            decimals(self.mean_gap.after_mm, 3),
            f(self.effect_accuracy),
        );
        let _ = writeln!(
            s,
            "two-effect cases (compliance and backlash): {}, both named on their joints {}\n",
            self.two_effect_cases,
            f(self.two_effects_both_named)
        );
        let _ = writeln!(
            s,
            "| effect | drawn member | cases above detectable | named right |\n|---|---|---|---|"
        );
        for r in &self.shapes {
            let _ = writeln!(s, "| {} | {} | {} | {} |", r.effect, r.shape, r.cases, r.named_right);
        }
        let _ = writeln!(s);
        let _ = writeln!(
            s,
            "| expected \\ diagnosed | {} |",
            self.confusion.diagnosed.join(" | ")
        );
        let _ = writeln!(s, "|---|{}", "---|".repeat(self.confusion.diagnosed.len()));
        for (l, row) in self.confusion.expected.iter().zip(&self.confusion.counts) {
            let cells: Vec<String> = row.iter().map(|c| c.to_string()).collect();
            let _ = writeln!(s, "| {l} | {} |", cells.join(" | "));
        }
        s
    }
}

/// Markdown table of every case: truth, size against the detectable size, verdict.
pub fn case_table(results: &[CaseResult]) -> String {
    let mut s = String::from(
        "| case | effect | joint | magnitude | unit | detectable size | size / detectable | diagnosed | joint | gap before -> after (mm) |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let opt = |x: Option<f64>, p: usize| x.map_or("-".to_owned(), |v| format!("{v:.p$e}"));
    for r in results {
        let (k, d) = (&r.key, &r.diagnosis);
        let _ = writeln!(
            s,
            "| {} | {} ({}) | {} | {} | {} | {} | {} | {} | {} | {:.3} -> {:.3} |",
            k.case,
            k.effect,
            k.shape,
            k.joint.map_or("-".into(), |j| j.to_string()),
            if k.effect == "none" {
                "-".into()
            } else {
                format!("{:.3e}", k.magnitude)
            },
            k.magnitude_unit,
            match (r.detectable_magnitude, r.size_ratio) {
                (None, Some(_)) => "absorbed".into(),
                (m, _) => opt(m, 2),
            },
            r.size_ratio.map_or("-".into(), |v| format!("{v:.2}")),
            diagnosed_label(d),
            d.outcome.joint.map_or("-".into(), |j| j.to_string()),
            d.outcome.gap_before_mm,
            d.outcome.gap_after_mm
        );
    }
    s
}
