//! `diagnosis.md`: the diagnosis in words and tables.

use super::Diagnosis;
use std::fmt::Write;

/// Markdown report of a diagnosis of the data in `source`.
pub fn markdown(d: &Diagnosis, source: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Sim-to-real gap diagnosis of `{source}`\n");
    let joint = d.joint.map_or(String::new(), |j| format!(" (joint {j})"));
    let _ = writeln!(
        s,
        "**{}**{joint}, confidence {:.2}: {}.\n",
        d.effect, d.confidence, d.verdict
    );
    let _ = writeln!(
        s,
        "Held-out gap {:.3} mm -> {:.3} mm (held-out RMS {:.3} mm, noise only {:.3} mm, smallest gap flagged {:.3} mm at false-alarm rate {}; {} training / {} held-out poses, noise {:.3} mm 3-D RMS; refit rank {} of {} parameters; {} noise-only samples).\n",
        d.gap_before_mm,
        d.gap_after_mm,
        d.heldout_rms_before_mm,
        d.noise_only_rms_mm,
        d.detectable_gap_mm,
        d.false_alarm,
        d.poses[0],
        d.poses[1],
        d.noise_rms_3d_mm,
        d.refit_rank[0],
        d.refit_rank[1],
        d.null_samples
    );
    if !d.parameters.is_empty() {
        let _ = writeln!(s, "| parameter | value | 1-sigma |\n|---|---|---|");
        for p in &d.parameters {
            let _ = writeln!(s, "| {} | {:.4e} | {:.2e} |", p.name, p.value, p.sigma);
        }
        s.push('\n');
    }
    let _ = writeln!(
        s,
        "## Where\n\n| experiment | joint | residual RMS (mm) | noise only (mm) | excess |\n|---|---|---|---|---|"
    );
    for w in &d.where_ {
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} | {:.4} | {:.2} |",
            w.experiment,
            w.joint.map_or("-".into(), |j| j.to_string()),
            w.residual_rms_mm,
            w.noise_only_rms_mm,
            w.excess_ratio
        );
    }
    let _ = writeln!(
        s,
        "\n## Candidates (best first)\n\n| effect | joint | held-out RMS (mm) | gap after (mm) | improvement (chi2) | z | significant | outside refit | weight |\n|---|---|---|---|---|---|---|---|---|"
    );
    for c in &d.candidates {
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} | {:.4} | {:.1} | {:.1} | {} | {:.3} | {:.3} |",
            c.effect,
            c.joint.map_or("-".into(), |j| j.to_string()),
            c.heldout_rms_mm,
            c.gap_after_mm,
            c.improvement_chi2,
            c.z,
            if c.significant { "yes" } else { "no" },
            c.outside_refit_fraction,
            c.weight
        );
    }
    s
}
