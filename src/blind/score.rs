//! Scoring a blind suite: confusion matrix of the effect (expected vs diagnosed), joint
//! accuracy, and the gap shrinkage of correctly named effects.

use super::CaseKey;
use crate::diagnosis::Diagnosis;
use serde::{Deserialize, Serialize};
use std::fmt::Write;

/// Counts of (expected, diagnosed) effect names.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConfusionMatrix {
    /// Row labels (expected answers).
    pub expected: Vec<String>,
    /// Column labels (diagnosed answers).
    pub diagnosed: Vec<String>,
    /// `counts[i][j]`: cases expecting `expected[i]` diagnosed as `diagnosed[j]`.
    pub counts: Vec<Vec<usize>>,
}

/// The suite's score.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlindScore {
    /// Cases scored.
    pub cases: usize,
    /// Fraction with the expected effect name.
    pub effect_accuracy: f64,
    /// Among correctly named per-joint effects, the fraction with the right joint.
    pub joint_accuracy: f64,
    /// Among cases with a named effect (not `none`/`unexplained`), the fraction correct.
    pub named_precision: f64,
    /// Median of `gap_after / gap_before` over correctly named effects.
    pub median_gap_ratio: f64,
    /// Mean `gap_before` and `gap_after` over correctly named effects \[mm\].
    pub mean_gap_before_after_mm: [f64; 2],
    /// The confusion matrix.
    pub confusion: ConfusionMatrix,
}

/// Scores diagnoses against their keys.
pub fn score(results: &[(CaseKey, Diagnosis)]) -> BlindScore {
    let mut labels: Vec<String> = Vec::new();
    for (k, d) in results {
        for l in [&k.expected, &d.effect] {
            if !labels.contains(l) {
                labels.push(l.clone());
            }
        }
    }
    labels.sort();
    let mut counts = vec![vec![0; labels.len()]; labels.len()];
    let pos = |l: &String| labels.iter().position(|x| x == l).unwrap_or(0);
    let (mut correct, mut joint_total, mut joint_ok, mut named, mut named_ok) = (0, 0, 0, 0, 0);
    let mut ratios = Vec::new();
    let (mut before, mut after) = (0.0, 0.0);
    for (k, d) in results {
        counts[pos(&k.expected)][pos(&d.effect)] += 1;
        let is_named = d.effect != "none" && d.effect != "unexplained";
        if is_named {
            named += 1;
        }
        if k.expected == d.effect {
            correct += 1;
            if is_named {
                named_ok += 1;
                if d.gap_before_mm > 0.0 {
                    ratios.push(d.gap_after_mm / d.gap_before_mm);
                }
                before += d.gap_before_mm;
                after += d.gap_after_mm;
            }
            if k.joint.is_some() && is_named {
                joint_total += 1;
                if k.joint == d.joint {
                    joint_ok += 1;
                }
            }
        }
    }
    ratios.sort_by(f64::total_cmp);
    let frac = |a: usize, b: usize| if b == 0 { f64::NAN } else { a as f64 / b as f64 };
    BlindScore {
        cases: results.len(),
        effect_accuracy: frac(correct, results.len()),
        joint_accuracy: frac(joint_ok, joint_total),
        named_precision: frac(named_ok, named),
        median_gap_ratio: if ratios.is_empty() {
            f64::NAN
        } else {
            ratios[ratios.len() / 2]
        },
        mean_gap_before_after_mm: [before / named_ok.max(1) as f64, after / named_ok.max(1) as f64],
        confusion: ConfusionMatrix {
            expected: labels.clone(),
            diagnosed: labels,
            counts,
        },
    }
}

impl BlindScore {
    /// Markdown summary.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{} cases: effect accuracy {:.2}, joint accuracy {:.2}, named precision {:.2}, median gap after/before {:.2} (mean {:.3} -> {:.3} mm)\n",
            self.cases,
            self.effect_accuracy,
            self.joint_accuracy,
            self.named_precision,
            self.median_gap_ratio,
            self.mean_gap_before_after_mm[0],
            self.mean_gap_before_after_mm[1]
        );
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
