//! `report.md` of a free-pose calibration.

use super::summary::{FreePoseSummary, OutlierPose};
use crate::calibration::noise::NoiseEstimate;
use crate::calibration::refine::ParameterUnit;
use crate::markdown;
use std::fmt::Write;

/// The report of a free-pose calibration of `robot` from `source`.
pub fn markdown(
    s: &FreePoseSummary,
    noise: Option<&NoiseEstimate>,
    (robot, source): (&str, &str),
    warnings: &[String],
) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# Calibration of {} from free poses\n", markdown::text(robot));
    let _ = writeln!(
        md,
        "Data: {}: {} poses, {} points fitted. Method: `docs/method.md`, \"Calibration from free poses\".\n",
        markdown::code(source),
        s.poses,
        s.points
    );
    if let Some(why) = &s.axis_rows_as_poses {
        let _ = writeln!(md, "The axis experiments' rows are fitted as free poses: {why}.\n");
    }
    md.push_str(&crate::calibration::procedure::warnings_section(warnings));
    residual_table(&mut md, s, noise);
    effects(&mut md, s);
    parameter_table(&mut md, s);
    unidentified(&mut md, s);
    targets(&mut md, s);
    outliers(&mut md, s);
    md
}

fn residual_table(md: &mut String, s: &FreePoseSummary, noise: Option<&NoiseEstimate>) {
    let _ = writeln!(md, "## Residuals\n\n| model | RMS (mm) |\n|---|---|");
    let _ = writeln!(
        md,
        "| nominal, closed-form registration | {:.4} |",
        s.closed_form_rms_mm
    );
    let _ = writeln!(md, "| nominal, base and targets fitted | {:.4} |", s.nominal_rms_mm);
    let _ = writeln!(md, "| calibrated | {:.4} |\n", s.calibrated_rms_mm);
    if let Some(n) = noise {
        let _ = writeln!(
            md,
            "Noise from the residuals: {:.4} mm 3-D RMS ({:.0} % interval {:.4}-{:.4} mm, {} dof). It contains \
             whatever the geometric model does not (compliance, backlash, thermal drift): the sigmas below are \
             scaled by it.\n",
            n.rms_3d_mm,
            n.confidence * 100.0,
            n.interval.low_mm,
            n.interval.high_mm,
            n.dof
        );
    }
    if let Some(h) = &s.holdout {
        let _ = writeln!(
            md,
            "Held out ({}): {} poses fitted, {} held out; held-out RMS nominal {:.4} mm, calibrated {:.4} mm (max {:.4} mm).\n",
            h.split, h.training_poses, h.heldout_poses, h.nominal_rms_mm, h.calibrated_rms_mm, h.calibrated_max_mm
        );
        if !h.outliers.is_empty() {
            let _ = writeln!(md, "Held-out outlier poses (left out of that RMS where dropped):\n");
            outlier_table(md, &h.outliers);
            md.push('\n');
        }
    }
}

fn unit_name(u: ParameterUnit) -> &'static str {
    match u {
        ParameterUnit::Mm => "mm",
        ParameterUnit::Mrad => "mrad",
        ParameterUnit::Coefficient => "",
        ParameterUnit::MradPerLoad => "mrad per load unit",
    }
}

/// The effects tried and the ones kept, joint by joint.
fn effects(md: &mut String, s: &FreePoseSummary) {
    if s.effects_tried.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "## Effects in the model

Each set fitted and scored by 5-fold cross-validation (`docs/method.md`, \"Effects in the model\"); the kept one is in `robot.effects`.\n\n| effects | parameters | cross-validated RMS (mm) | kept |\n|---|---|---|---|"
    );
    for t in &s.effects_tried {
        let _ = writeln!(
            md,
            "| {} | {} | {:.4} | {} |",
            t.effects,
            t.parameters,
            t.cross_validated_rms_mm,
            if t.chosen { "yes" } else { "" }
        );
    }
    if !s.effect_joints.is_empty() {
        let _ = writeln!(
            md,
            "\n| joint | effect | RMS (mrad) | largest (mrad) | 1-sigma (mrad) |\n|---|---|---|---|---|"
        );
        for e in &s.effect_joints {
            let sigma = e.sigma.map_or(String::new(), |v| format!("{v:.4}"));
            let _ = writeln!(
                md,
                "| {} | {} | {:.4} | {:.4} | {sigma} |",
                e.joint, e.effect, e.rms, e.max
            );
        }
    }
    let _ = writeln!(md);
}

fn parameter_table(md: &mut String, s: &FreePoseSummary) {
    let _ = writeln!(
        md,
        "## Fitted parameters ({}; condition number {:.3e})\n\n| parameter | value | change | 1-sigma | unit |\n|---|---|---|---|---|",
        s.parameters.len(),
        s.condition_number
    );
    for p in &s.parameters {
        let value = p.value.map_or("".to_string(), |v| format!("{v:.4}"));
        let _ = writeln!(
            md,
            "| `{}` | {value} | {:.4} | {:.4} | {} |",
            p.name,
            p.change,
            p.sigma,
            unit_name(p.unit)
        );
    }
    let _ = writeln!(md);
}

fn unidentified(md: &mut String, s: &FreePoseSummary) {
    if s.unidentified.is_empty() {
        let _ = writeln!(md, "Every parameter of the model is identified by these poses.\n");
        return;
    }
    let _ = writeln!(
        md,
        "## Not identified ({}, kept nominal)\n\n| parameter | why | same effect as |\n|---|---|---|",
        s.unidentified.len()
    );
    for u in &s.unidentified {
        let same: Vec<String> = u
            .same_as
            .iter()
            .map(|w| format!("{:+.4} `{}`", w.weight, w.name))
            .collect();
        let _ = writeln!(md, "| `{}` | {} | {} |", u.name, u.reason, same.join(" "));
    }
    let _ = writeln!(md);
}

fn targets(md: &mut String, s: &FreePoseSummary) {
    let _ = writeln!(
        md,
        "## Targets on the last link (nominal tool frame, mm)\n\n| target | in the file | x | y | z |\n|---|---|---|---|---|"
    );
    for t in &s.targets {
        let cell = |i: usize| match t.sigma_mm[i] {
            Some(sd) => format!("{:.3} +- {:.3}", t.position_mm[i], sd),
            None => format!("{:.3} (not identified)", t.position_mm[i]),
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} |",
            t.id,
            markdown::text(&t.name),
            cell(0),
            cell(1),
            cell(2)
        );
    }
    match s.tool_fit_rms_mm {
        Some(rms) => {
            let _ = writeln!(
                md,
                "\nTool frame: fitted to the description's `tool.targets_mm` (rigid fit RMS {rms:.4} mm).\n"
            );
        }
        None => {
            let _ = writeln!(
                md,
                "\nTool frame: nominal (the description gives no tool targets matching these target ids).\n"
            );
        }
    }
}

fn outliers(md: &mut String, s: &FreePoseSummary) {
    if s.outliers.is_empty() {
        let _ = writeln!(
            md,
            "No pose beyond the outlier fences (its residual studentised by its leverage against the noise of the poses near it, at a family-wise 1 % over the poses, and Tukey's far-out fence of the poses' RMS)."
        );
        return;
    }
    let _ = writeln!(md, "## Outlier poses ({})\n", s.outliers.len());
    outlier_table(md, &s.outliers);
}

/// The table of outlier poses.
fn outlier_table(md: &mut String, outliers: &[OutlierPose]) {
    let _ = writeln!(
        md,
        "| experiment | step | RMS (mm) | fence (mm) | dropped |\n|---|---|---|---|---|"
    );
    for o in outliers {
        let _ = writeln!(
            md,
            "| {} | {} | {:.4} | {:.4} | {} |",
            markdown::text(&o.experiment),
            o.step,
            o.rms_mm,
            o.fence_mm,
            o.dropped
        );
    }
}
