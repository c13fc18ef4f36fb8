//! The refinement's section of `report.md`.

use super::Refinement;
use std::fmt::Write;

/// At most this many parameter changes are listed (the largest in sigmas; all are in
/// `calibration.json`).
const LISTED_CHANGES: usize = 15;

/// The "Refinement on free poses" section.
pub fn markdown(r: &Refinement) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "## Refinement on free poses\n");
    let _ = writeln!(
        s,
        "The model (rows, zero offsets, transmission harmonics, couplings, base and tool frames) refined on {} free poses ({} points): {} parameters, rank {} ({}), {} directions dropped; {} Gauss-Newton steps{}.\n",
        r.poses,
        r.points,
        r.parameters,
        r.rank,
        r.rank_rule,
        r.dropped.len(),
        r.iterations,
        if r.converged {
            ""
        } else {
            " (step limit reached: not converged)"
        }
    );
    let _ = writeln!(
        s,
        "RMS distance of the points from the model: {:.4} mm before, {:.4} mm after (noise alone leaves {:.4} mm at {:.4} mm 3-D RMS noise).\n",
        r.rms_before_mm, r.rms_after_mm, r.expected_rms_after_mm, r.noise_rms_3d_mm
    );
    let _ = writeln!(
        s,
        "| fold | training poses | held-out poses | rank | held-out RMS before (mm) | after (mm) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for f in &r.folds {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.4} | {:.4} |",
            f.fold, f.training_poses, f.heldout_poses, f.rank, f.heldout_rms_before_mm, f.heldout_rms_after_mm
        );
    }
    let _ = writeln!(
        s,
        "| all | | | | {:.4} | {:.4} |\n",
        r.heldout_rms_before_mm, r.heldout_rms_after_mm
    );
    let mut changes: Vec<_> = r.changes.iter().collect();
    changes.sort_by(|a, b| {
        let key = |c: &&super::ParameterChange| c.change_sigmas.map_or(0.0, f64::abs);
        key(b).total_cmp(&key(a))
    });
    let _ = writeln!(
        s,
        "Largest changes in unrefined sigmas (all {} in `calibration.json`, `refinement.changes`; the axes, couplings and sigmas above are the unrefined estimates, the robot model written is the refined one):\n",
        r.changes.len()
    );
    let _ = writeln!(
        s,
        "| parameter | change | unrefined 1-sigma | refined 1-sigma | change / unrefined sigma |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    for c in changes.iter().take(LISTED_CHANGES) {
        let unit = serde_json::to_value(c.unit)
            .ok()
            .and_then(|v| v.as_str().map(String::from))
            .unwrap_or_default();
        let opt = |v: Option<f64>| v.map_or("-".to_owned(), |x| format!("{x:.4}"));
        let _ = writeln!(
            s,
            "| {} | {:.4} {unit} | {} | {:.4} | {} |",
            c.name,
            c.change,
            opt(c.unrefined_sigma),
            c.refined_sigma,
            opt(c.change_sigmas)
        );
    }
    if !r.dropped.is_empty() {
        let _ = writeln!(
            s,
            "\nDirections dropped (not identified by the free poses; the unrefined estimate stands):\n"
        );
        for d in &r.dropped {
            let parts: Vec<String> = d
                .leading
                .iter()
                .map(|w| format!("{:+.2} {}", w.weight, w.name))
                .collect();
            let _ = writeln!(
                s,
                "- s / noise = {:.3}: {}",
                d.singular_value_over_noise,
                parts.join(", ")
            );
        }
    }
    let _ = writeln!(s);
    s
}
