//! `--refine` and `--carry`: the calibration refined on the file's free poses, and its console
//! lines.

use super::Args;
use super::max_poses;
use crate::cli::checks;
use crate::cli::printer::Printer;
use anyhow::Context;
use anyhow::Result;
use axiscal::calibration::procedure::Calibration;
use axiscal::calibration::refine::{RefineOptions, Refinement, enough_free_poses};
use axiscal::calibration::refit_model::refine::refine_carrying;
use axiscal::calibration::refit_model::validation_poses_at_most;
use axiscal::diagnosis::{Candidate, Diagnosis, carried_candidates};
use axiscal::json_file::{self, Schema};
use axiscal::measurement::MeasurementSet;
use axiscal::robot::RobotDescription;
use std::path::Path;

/// With `--refine`, enough free poses in `set` for its folds, said before any calibration.
pub(super) fn check_refine_poses(args: &Args, set: &MeasurementSet, desc: &RobotDescription) -> Result<()> {
    if args.refine {
        let (poses, _) = validation_poses_at_most(set.rows(), desc, max_poses(args));
        enough_free_poses(poses.len(), args.refine_folds as usize)
            .map_err(|e| anyhow::anyhow!("--refine on {}: {e}", args.data.display()))?;
    }
    Ok(())
}

/// `cal` refined on the free poses of `set` (`--refine`) and the refinement, its summary
/// printed.
pub(super) fn refine(
    args: &Args,
    set: &MeasurementSet,
    desc: &RobotDescription,
    cal: &Calibration,
    printer: Printer,
) -> Result<(Calibration, Refinement)> {
    let options = RefineOptions {
        noise_rms_3d_mm: cal
            .noise
            .as_ref()
            .map_or(cal.options.noise_rms_3d_mm, |n| n.used_rms_3d_mm),
        folds: args.refine_folds as usize,
        max_poses: max_poses(args),
        keep_outliers: args.keep_outliers,
        ..RefineOptions::default()
    };
    let carried = match &args.carry {
        Some(path) => carried_effects(path, desc, set)?,
        None => Vec::new(),
    };
    let (refined, r) = refine_carrying(set, desc, cal, &options, &carried)
        .map_err(|e| anyhow::anyhow!("--refine on {}: {e}", args.data.display()))?;
    print_refinement(&r, (set, &args.data), &carried, printer)?;
    Ok((refined, r))
}

/// The console lines of a refinement `r` of the free poses of `set` (read from `data`); an
/// error when its result is implausible.
pub(super) fn print_refinement(
    r: &Refinement,
    (set, data): (&MeasurementSet, &Path),
    carried: &[Candidate],
    printer: Printer,
) -> Result<()> {
    say!(
        printer,
        "refined on {} free poses: rank {} of {} parameters ({} directions dropped), RMS {:.4} -> {:.4} mm (noise alone {:.4} mm); {}-fold held-out RMS {:.4} -> {:.4} mm",
        r.poses,
        r.rank,
        r.parameters,
        r.dropped.len(),
        r.rms_before_mm,
        r.rms_after_mm,
        r.expected_rms_after_mm,
        r.folds.len(),
        r.heldout_rms_before_mm,
        r.heldout_rms_after_mm
    );
    if r.poses_left_out > 0 {
        say!(
            printer,
            "  refined on {} of the file's {} free poses, evenly spaced through it (`--max-poses`; memory grows with them)",
            r.poses,
            r.poses + r.poses_left_out
        );
    }
    if !r.converged {
        eprintln!("warning: --refine: the Gauss-Newton steps reached their limit without converging");
    }
    checks::print_pose_outliers(&r.outliers, set, data, "refined");
    if let Some(why) = r.implausible() {
        anyhow::bail!(
            "--refine on {}: {why}; nothing written (without --refine the axis calibration stands)",
            data.display()
        );
    }
    print_carried(carried, r, printer);
    Ok(())
}

/// The effects the diagnosis in `path` names, as candidates a model carries (`--carry`).
pub(super) fn carried_effects(path: &Path, desc: &RobotDescription, set: &MeasurementSet) -> Result<Vec<Candidate>> {
    let text = axiscal::presets::read_text(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let mode: Option<serde_json::Value> = serde_json::from_str(&text).ok();
    if mode.as_ref().and_then(|v| v.get("mode")).and_then(|m| m.as_str()) == Some("axes_only") {
        anyhow::bail!(
            "--carry {}: an axes-only diagnosis (no validation poses) names no effect: nothing to carry",
            path.display()
        );
    }
    let d: Diagnosis = json_file::from_str(Schema::DIAGNOSIS, &text).with_context(|| {
        format!(
            "{}: not a diagnosis JSON (`axiscal diagnose` writes one)",
            path.display()
        )
    })?;
    carried_candidates(&d, desc, set).map_err(|e| anyhow::anyhow!("--carry {}: {e}", path.display()))
}

/// The console lines of the effects `--carry` fitted: each parameter with its sigma, and the
/// warning that only `calibration.json` carries them.
pub(super) fn print_carried(carried: &[Candidate], r: &Refinement, printer: Printer) {
    if carried.is_empty() {
        return;
    }
    let names: Vec<String> = carried
        .iter()
        .map(|c| match c.joint() {
            Some(j) => format!("{} on joint {j} ({})", c.effect_name(), c.member_name()),
            None => format!("{} ({})", c.effect_name(), c.member_name()),
        })
        .collect();
    say!(printer, "  carried: {}", names.join("; "));
    for p in r
        .changes
        .iter()
        .filter(|p| carried.iter().any(|c| p.name.contains(c.effect_name())))
    {
        say!(printer, "    {} = {:.4e} +- {:.2e}", p.name, p.change, p.refined_sigma);
    }
    eprintln!(
        "warning: the model carries {} (calibration.json robot.effects and transmissions, used by validate and compensate); calibrated.urdf and joint_map.csv hold the geometry only",
        names.join("; ")
    );
}
