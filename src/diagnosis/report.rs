//! `diagnosis.md`: the diagnosis in words and tables.

use super::{Diagnosis, WhereEntry};
use std::fmt::Write;

/// Markdown report of a diagnosis of the data in `source`.
pub fn markdown(d: &Diagnosis, source: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Sim-to-real gap diagnosis of {}\n", crate::markdown::code(source));
    let joint = match (d.outcome.joint, &d.member) {
        (Some(j), Some(m)) => format!(" (joint {j}, `{m}`)"),
        (Some(j), None) => format!(" (joint {j})"),
        (None, Some(m)) => format!(" (`{m}`)"),
        (None, None) => String::new(),
    };
    let _ = writeln!(
        s,
        "**{}**{joint}, confidence {:.2}: {}.\n",
        d.outcome.effect, d.outcome.confidence, d.verdict
    );
    let _ = writeln!(
        s,
        "Held-out gap {:.3} mm -> {:.3} mm (held-out RMS {:.3} mm, noise only {:.3} mm, smallest gap flagged {:.3} mm at false-alarm rate {}; {} training / {} held-out poses, noise {:.3} mm 3-D RMS; refit rank {} of {} parameters; {} noise-only samples).\n",
        d.outcome.gap_before_mm,
        d.outcome.gap_after_mm,
        d.heldout_rms_before_mm,
        d.noise_only_rms_mm,
        d.detectable_gap_mm,
        d.false_alarm,
        d.poses.training,
        d.poses.held_out,
        d.noise_rms_3d_mm,
        d.refit_rank.rank,
        d.refit_rank.parameters,
        d.null_samples
    );
    if d.poses.left_out > 0 {
        let _ = writeln!(
            s,
            "{} more validation poses of the file were left out: the diagnosis fits at most {} of them, evenly spaced through the file (`--max-poses`).\n",
            d.poses.left_out,
            d.poses.training + d.poses.held_out
        );
    }
    if !d.outliers.is_empty() {
        outliers_section(&mut s, &d.outliers);
    }
    if !d.parameters.is_empty() {
        let _ = writeln!(s, "| parameter | value | 1-sigma |\n|---|---|---|");
        for p in &d.parameters {
            let _ = writeln!(s, "| {} | {:.4e} | {:.2e} |", p.name, p.value, p.sigma);
        }
        s.push('\n');
    }
    if let Some(t) = &d.tool_targets {
        tool_targets_section(&mut s, t);
    }
    s.push_str("## Where\n\n");
    s.push_str(&where_table(&d.where_, &[], |_| Vec::new()));
    if !d.features.is_empty() {
        let _ = writeln!(
            s,
            "\n### Where, by workspace feature\n\nContrast: the feature's largest bin excess over its smallest (1: the gap is the same across the feature); threshold: the noise-only replicas' {} quantile of the same contrast.\n\n| feature | joint | contrast | noise-only threshold | beyond noise |\n|---|---|---|---|---|",
            1.0 - d.false_alarm
        );
        for f in &d.features {
            let _ = writeln!(
                s,
                "| {} | {} | {:.3} | {:.3} | {} |",
                f.feature,
                f.joint.map_or("-".into(), |j| j.to_string()),
                f.contrast,
                f.noise_only_threshold,
                if f.beyond_noise { "yes" } else { "no" }
            );
        }
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

/// Markdown table of `where` entries, with `extra` columns filled by `cells` per entry.
pub(super) fn where_table(
    entries: &[WhereEntry],
    extra: &[&str],
    cells: impl Fn(&WhereEntry) -> Vec<String>,
) -> String {
    let mut s = String::new();
    let mut header = vec!["experiment", "joint", "residual RMS (mm)", "noise only (mm)", "excess"];
    header.extend(extra);
    let _ = writeln!(s, "| {} |\n|{}", header.join(" | "), "---|".repeat(header.len()));
    for w in entries {
        let mut row = vec![
            crate::markdown::text(&w.experiment),
            w.joint.map_or("-".into(), |j| j.to_string()),
            format!("{:.4}", w.residual_rms_mm),
            format!("{:.4}", w.noise_only_rms_mm),
            format!("{:.2}", w.excess_ratio),
        ];
        row.extend(cells(w));
        let _ = writeln!(s, "| {} |", row.join(" | "));
    }
    s
}

/// The tool targets refined from the training poses against the description's.
fn tool_targets_section(s: &mut String, t: &super::ToolTargets) {
    if let Some(w) = t.warning() {
        let _ = writeln!(s, "**Warning**: {w}.\n");
    }
    if t.distances.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "Tool targets refined from the training poses (distances between targets; far off beyond {} sigma):\n\n| targets | nominal [mm] | refined [mm] | 1-sigma [mm] | sigmas off |\n|---|---|---|---|---|",
        super::FAR_SIGMAS
    );
    for d in &t.distances {
        let _ = writeln!(
            s,
            "| {}-{} | {:.3} | {:.3} | {:.3} | {:.1} |",
            d.first_target, d.second_target, d.nominal_mm, d.refined_mm, d.sigma_mm, d.sigmas_off
        );
    }
    s.push('\n');
}

/// The validation points the outlier test flagged.
fn outliers_section(s: &mut String, outliers: &[crate::calibration::procedure::OutlierPoint]) {
    let _ = writeln!(
        s,
        "Outliers (beyond the far-out fence and far from their pose's other targets; `docs/diagnosis.md`, \"Outliers\"):\n\n| line | experiment | step | target | residual [mm] | over the noise | fence | left out |\n|---|---|---|---|---|---|---|---|"
    );
    for o in outliers {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.3} | {:.1} | {:.1} | {} |",
            o.line.map_or_else(|| "-".to_string(), |l| l.to_string()),
            crate::markdown::text(&o.experiment),
            o.step,
            o.target,
            o.residual_mm,
            o.normalised_residual,
            o.fence,
            if o.dropped { "yes" } else { "no (--keep-outliers)" }
        );
    }
    s.push('\n');
}
