//! Everything `calibrate` writes into its output folder, rendered as text before anything is
//! written (the binary places the files as one set): the calibration, its two reports, the
//! URDF, the joint map, the residuals and, when their fit converges, the controller zero
//! offsets (`docs/formats.md`).

use super::free_pose;
use super::procedure::{
    Calibration, ColumnSource, Implausible, JointMap, MapTable, RawReadingDeviation, UrdfOptions,
    controller_zero_offsets, findings, implausible, joint_map, joints_without_speed_limits, markdown,
    raw_reading_deviation, residuals_csv, urdf, with_column_source,
};
use super::record::CalibrationRecord;
use crate::json_file::{self, Schema};
use crate::measurement::format_f64;
use crate::numerics::lsq::LsqError;
use crate::robot::RobotDescription;
use std::fmt::Write as _;

/// The files `calibrate` writes into its output folder, in this order.
pub const OUTPUT_FILES: [&str; 7] = [
    "calibration.json",
    "report.md",
    "report.json",
    "calibrated.urdf",
    "joint_map.csv",
    "residuals.csv",
    "zero_offsets.csv",
];

/// How the outputs are written.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputOptions {
    /// The URDF's name and root.
    pub urdf: UrdfOptions,
    /// Step of the tabulated joint map (deg or mm).
    pub joint_map_step: f64,
}

/// The sanity checks' findings ([`implausible`]) on the calibration of `record`: none on a
/// free-pose calibration (its own tests judge it); `bumps_undone`, the findings on the
/// calibration of the data with the sweep screen's named bumps moved back
/// (`procedure::bumps_undone`), in place of this calibration's, whose fits took each bump into
/// its joint; the joints' scales that `column_source` (the instrument axis whose scale explains
/// them, `calibration::procedure::column_source`) explains said as that axis.
pub fn sanity_findings(
    record: &CalibrationRecord,
    desc: &RobotDescription,
    column_source: Option<&ColumnSource>,
    bumps_undone: Option<Vec<Implausible>>,
) -> Vec<Implausible> {
    match record.reports.free_poses {
        None => with_column_source(
            bumps_undone.unwrap_or_else(|| implausible(&record.calibration, desc)),
            column_source,
        ),
        Some(_) => vec![],
    }
}

/// The rendered outputs of a calibration.
#[derive(Clone, Debug)]
pub struct CalibrationOutputs {
    /// The files of [`OUTPUT_FILES`] that are written, by name, in order.
    pub files: Vec<(&'static str, String)>,
    /// Outputs left out, with the reason.
    pub left_out: Vec<String>,
    /// How far a URDF fed raw controller readings puts the tool.
    pub deviation: RawReadingDeviation,
    /// Joints whose URDF speed and effort limits are unknown.
    pub missing_speed_limits: Vec<usize>,
}

/// The calibration could not be written as JSON.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {cause}")]
pub struct OutputError {
    /// The file being rendered.
    pub file: &'static str,
    /// Why.
    pub cause: serde_json::Error,
}

/// Renders every output of `record` (see [`OUTPUT_FILES`]); `poses` (file units) are the
/// commands the raw-reading deviation and the zero offsets are computed over, `source` names
/// the data.
pub fn render(
    record: &CalibrationRecord,
    desc: &RobotDescription,
    source: &str,
    poses: &[Vec<f64>],
    options: &OutputOptions,
) -> Result<CalibrationOutputs, OutputError> {
    let json = |file: &'static str, r: serde_json::Result<String>| r.map_err(|cause| OutputError { file, cause });
    let cal = &record.calibration;
    let deviation = raw_reading_deviation(cal, desc, poses);
    let mut report_findings = findings(cal, desc);
    report_findings.extend(deviation.findings());
    let map = joint_map(cal, desc, options.joint_map_step);
    let mut files = vec![
        (OUTPUT_FILES[0], json(OUTPUT_FILES[0], record.to_json())?),
        (
            OUTPUT_FILES[1],
            report_markdown(record, desc, source) + &deviation.markdown(),
        ),
        (
            OUTPUT_FILES[2],
            json(
                OUTPUT_FILES[2],
                json_file::list_to_string(Schema::REPORT, "findings", &report_findings),
            )?,
        ),
        (OUTPUT_FILES[3], urdf(&cal.robot.phi_model(), desc, &options.urdf)),
        (OUTPUT_FILES[4], joint_map_csv(&map, &desc.name)),
        (OUTPUT_FILES[5], residuals_csv(cal)),
    ];
    // The zero offsets are a convenience for controllers that take nothing else: when their
    // fit fails, the calibration stands and the file is left out with the reason.
    let mut left_out = Vec::new();
    let fitted = free_pose::with_fitted_targets(desc, record.reports.free_poses.as_ref());
    match zero_offsets_csv(cal, (desc, &fitted), poses) {
        Ok(text) => files.push((OUTPUT_FILES[6], text)),
        Err(e) => left_out.push(format!(
            "{} not written: fitting the controller zero offsets: {e}",
            OUTPUT_FILES[6]
        )),
    }
    Ok(CalibrationOutputs {
        files,
        left_out,
        deviation,
        missing_speed_limits: joints_without_speed_limits(desc),
    })
}

/// Whether the turn of `joint` (1-based) moves any tool target of `desc` at any of the first
/// poses of `commands` (file units) on the nominal model: its column of the point Jacobian
/// ([`crate::kinematics::point_jacobian`]) beyond rounding (`1e-8` of the largest column, as
/// the zero-offset fit's test).
fn turn_moves_targets(desc: &RobotDescription, commands: &[Vec<f64>], joint: usize) -> bool {
    let nominal = desc.nominal_model();
    let n = desc.dof();
    commands.iter().take(10).any(|cmd| {
        let q = crate::robot::commands_to_internal(desc, cmd);
        desc.tool_targets_m().iter().any(|t| {
            let j = crate::kinematics::point_jacobian(&nominal, &q, n - 1, &(nominal.last_link_from_tool * t));
            let largest = (0..n).map(|k| j.column(k).norm()).fold(0.0, f64::max);
            j.column(joint - 1).norm() > 1e-8 * largest
        })
    })
}

/// `report.md`: the free-pose report or the independent-axis one.
fn report_markdown(record: &CalibrationRecord, desc: &RobotDescription, source: &str) -> String {
    match &record.reports.free_poses {
        Some(summary) => free_pose::markdown(
            summary,
            record.calibration.noise.as_ref().and_then(|n| n.estimate.as_ref()),
            (&desc.name, source),
            &record.reports.warnings,
        ),
        None => markdown(record, desc, source),
    }
}

/// `joint_map.csv` (`docs/formats.md#joint-map`).
pub fn joint_map_csv(map: &JointMap, robot_name: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# axiscal joint map of {robot_name}: calibrated joint values from controller commands"
    );
    let _ = writeln!(
        s,
        "# q_k = active_k(u_k) + passive_k(active_(k-1)); u_1 = cmd_1, u_k = cmd_k - slope_k u_(k-1), slope_k: {}",
        map.decoupling_slopes
            .iter()
            .enumerate()
            .map(|(k, s)| format!("{}={}", k + 1, format_f64(*s)))
            .collect::<Vec<_>>()
            .join(" ")
    );
    let _ = writeln!(
        s,
        "# linear interpolation in this table is within {:.3e} (deg or mm) of the exact values",
        map.max_interpolation_error
    );
    let _ = writeln!(s, "table,joint,input,output,input_unit,output_unit");
    for r in &map.rows {
        let table = match r.table {
            MapTable::Active => "active",
            MapTable::Passive => "passive",
        };
        let _ = writeln!(
            s,
            "{table},{},{},{},{},{}",
            r.joint,
            format_f64(r.input),
            format_f64(r.output),
            r.input_unit,
            r.output_unit
        );
    }
    s
}

/// `zero_offsets.csv` (`docs/formats.md#zero-offsets`): the zero offsets a controller that
/// takes nothing else can use, fitted over `commands` (file units) on `desc`'s tool targets.
/// A joint the fit cannot see is named with its reason: its turn moves no target of `desc`
/// (they lie on its axis), or, `desc` giving none and `fitted` holding the targets a free-pose
/// calibration fitted ([`free_pose::with_fitted_targets`]) off its axis, its offset is
/// confounded with their positions (a turn of the last joint is a turn of the targets about
/// its axis).
pub fn zero_offsets_csv(
    cal: &Calibration,
    (desc, fitted): (&RobotDescription, &RobotDescription),
    commands: &[Vec<f64>],
) -> Result<String, LsqError> {
    let fit = controller_zero_offsets(cal, desc, commands)?;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# zero offsets for a controller that takes nothing else: ADD `offset` to a joint reading (subtract it from a command) and the nominal kinematics reproduce the calibrated robot best"
    );
    let _ = writeln!(
        s,
        "# tool-target RMS, nominal vs calibrated, over {} poses: {:.3} mm without offsets, {:.3} mm with them (what offsets alone cannot take)",
        fit.poses, fit.rms_before_mm, fit.rms_after_mm
    );
    let (confounded, on_axis): (Vec<usize>, Vec<usize>) = fit
        .undetermined
        .iter()
        .partition(|&&j| desc.tool.targets_mm.is_empty() && turn_moves_targets(fitted, commands, j));
    let list = |joints: &[usize]| joints.iter().map(usize::to_string).collect::<Vec<_>>().join(", ");
    if !on_axis.is_empty() {
        let _ = writeln!(
            s,
            "# joint {}: its turn moves none of the tool targets (they lie on its axis): no offset of it is seen, 0 written",
            list(&on_axis)
        );
    }
    if !confounded.is_empty() {
        let _ = writeln!(
            s,
            "# joint {}: its offset is confounded with the tool targets' positions the free-pose calibration fitted (calibration.json free_poses.targets, off its axis): turning it moves them as turning the targets about its axis would, so the data cannot tell it; the description gives no targets to fit it on, 0 written",
            list(&confounded)
        );
    }
    s.push_str("joint,offset,unit\n");
    for (k, (offset, unit)) in fit.offsets.iter().zip(&fit.units).enumerate() {
        let _ = writeln!(s, "{},{},{unit}", k + 1, format_f64(*offset));
    }
    Ok(s)
}
