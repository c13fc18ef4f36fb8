//! `axiscal compensate`: paper fig. 5 for a batch of required tool poses.
//!
//! Input `--poses` CSV (header required, columns by name, `#` lines are comments):
//! `id, x_mm, y_mm, z_mm, roll_deg, pitch_deg, yaw_deg`: the tool frame in the instrument
//! frame, rotation `Rz(yaw) Ry(pitch) Rx(roll)`.
//!
//! Output `--out` CSV, one row per pose: `id, status, cmd_1_deg..cmd_N_deg (`_mm` for a
//! sliding joint), converged,
//! iterations, position_error_mm, orientation_error_rad, send_x_mm, send_y_mm, send_z_mm,
//! send_roll_deg, send_pitch_deg, send_yaw_deg` (`send_*`: the nominal direct kinematics of
//! the commands, the pose to send to a controller that takes poses; `position_error_mm`,
//! `orientation_error_rad`: the IK residual on the calibrated model).
//!
//! Failure policy: a pose whose IK does not converge (out of reach, singular) gets
//! `status = ik_failed`, empty command and pose columns, and one line on stderr; the batch goes
//! on, and the command exits with code 2 at the end if any pose failed. A malformed input
//! file is one error naming the file, the line and the column (exit 2, nothing written).

use super::checks;
use super::output::{Outputs, commit_csv};
use anyhow::{Result, bail};
use axiscal::compensation::{CompensatedPose, CompensationError, Compensator};
use axiscal::kinematics::IkError;
use axiscal::measurement::import::table::Table;
use axiscal::robot::{Placement, RobotDescription, commands_to_file, file_unit};
use nalgebra::Isometry3;
use std::path::{Path, PathBuf};

/// Arguments of `axiscal compensate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The calibration (`serde_json` of `Calibration`, written by `axiscal calibrate`).
    #[arg(long)]
    calibration: PathBuf,
    /// Nominal robot description (the unchanged controller uses it).
    #[arg(long, default_value = "asea-irb6l", value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// Required tool poses (CSV, see module docs).
    #[arg(long)]
    poses: PathBuf,
    /// Output commands (CSV).
    #[arg(long)]
    out: PathBuf,
    /// Replace `--out` if it exists (never one of this command's inputs).
    #[arg(long)]
    force: bool,
    /// The payload the robot carries (kg): what the calibrated model's sag under a payload
    /// (`robot.effects`, payload terms) is evaluated with.
    #[arg(long, default_value_t = 0.0, value_parser = super::options::InRange::closed(0.0, 1e5, "kg"))]
    payload_kg: f64,
    #[command(flatten)]
    checks: checks::Overrides,
}

/// One required pose from the input file.
struct PoseRow {
    id: String,
    world_from_tool: Isometry3<f64>,
    /// Roll, pitch and yaw as written \[deg\].
    rpy_deg: [f64; 3],
}

const COLUMNS: [&str; 7] = ["id", "x_mm", "y_mm", "z_mm", "roll_deg", "pitch_deg", "yaw_deg"];

fn read_poses(path: &Path) -> Result<Vec<PoseRow>> {
    let table = Table::read(path)?;
    let index = table.required_all(&COLUMNS)?;
    let mut out = Vec::with_capacity(table.row_count());
    let mut lines: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    for row in table.rows() {
        let id = table.cell(&row, index[0])?;
        if id.is_empty() {
            bail!(table.row_error(
                row.line,
                index[0],
                "empty: give each pose an id (the output's rows are told apart by it)".into()
            ));
        }
        if let Some(first) = lines.insert(id.to_owned(), row.line) {
            bail!(table.row_error(
                row.line,
                index[0],
                format!(
                    "{:?} is the id of line {first} too: give each pose its own id (the output's rows are told apart by it)",
                    axiscal::csv_lines::shown_cell(id)
                )
            ));
        }
        let mut v = [0.0; 6];
        for (slot, &column) in v.iter_mut().zip(&index[1..]) {
            *slot = table.number(&row, column)?;
        }
        // The orientation columns (roll, pitch, yaw) are angles in degrees.
        if let Some((column, why)) = index[4..]
            .iter()
            .zip(&v[3..])
            .find_map(|(&column, &deg)| Some((column, axiscal::robot::angle_deg_problem(deg)?)))
        {
            return Err(table.row_error(row.line, column, why).into());
        }
        let placement = Placement {
            translation_mm: [v[0], v[1], v[2]],
            rpy_deg: [v[3], v[4], v[5]],
        };
        out.push(PoseRow {
            id: id.to_owned(),
            world_from_tool: placement.to_isometry(),
            rpy_deg: placement.rpy_deg,
        });
    }
    if out.is_empty() {
        bail!("{}: no pose rows after the header", path.display());
    }
    Ok(out)
}

/// The output CSV's header for the joints of `desc` (`cmd_k_deg` or, sliding, `cmd_k_mm`).
fn csv_header(desc: &RobotDescription) -> Vec<String> {
    let mut header: Vec<String> = vec!["id".into(), "status".into()];
    header.extend((0..desc.dof()).map(|k| format!("cmd_{}_{}", k + 1, file_unit(desc, k))));
    for h in [
        "converged",
        "iterations",
        "position_error_mm",
        "orientation_error_rad",
        "send_x_mm",
        "send_y_mm",
        "send_z_mm",
        "send_roll_deg",
        "send_pitch_deg",
        "send_yaw_deg",
    ] {
        header.push(h.into());
    }
    header
}

/// The columns after `id` of a compensated pose `c` whose status is `status`.
fn compensated_columns(row: &mut Vec<String>, c: &CompensatedPose, desc: &RobotDescription, status: &str) {
    row.push(status.into());
    row.extend(commands_to_file(desc, &c.cmd).iter().map(|v| format!("{v:.9}")));
    row.push("true".into());
    row.push(c.ik.iterations.to_string());
    row.push(format!("{:.3e}", c.ik.position_error_m * 1e3));
    row.push(format!("{:.3e}", c.ik.orientation_error_rad));
    let t = c.nominal_pose_to_send.translation.vector * 1e3;
    let [r, pi, y] = axiscal::kinematics::roll_pitch_yaw(&c.nominal_pose_to_send.rotation);
    row.extend([t.x, t.y, t.z].iter().map(|v| format!("{v:.6}")));
    row.extend([r, pi, y].iter().map(|v| format!("{:.9}", v.to_degrees())));
}

/// The columns after `id` of a pose that could not be compensated (`e`), `n` joints.
fn failed_columns(row: &mut Vec<String>, e: &CompensationError, n: usize) {
    let (status, iterations, pos, ori) = match e {
        CompensationError::Ik(IkError::NotConverged {
            iterations,
            position_error_m,
            orientation_error_rad,
        }) => (
            "ik_failed",
            iterations.to_string(),
            format!("{:.3e}", position_error_m * 1e3),
            format!("{orientation_error_rad:.3e}"),
        ),
        _ => ("failed", String::new(), String::new(), String::new()),
    };
    row.push(status.into());
    row.extend(std::iter::repeat_n(String::new(), n));
    row.extend(["false".into(), iterations, pos, ori]);
    row.extend(std::iter::repeat_n(String::new(), 6));
}

/// Runs `axiscal compensate`.
pub fn run(args: Args) -> Result<()> {
    let outputs = Outputs::new(args.force)
        .input("--calibration", &args.calibration)
        .input("--poses", &args.poses)
        .input("--robot", &args.robot);
    outputs.check(&args.out)?;
    let desc = RobotDescription::from_file(&args.robot)?;
    checks::description_units(&desc, &args.robot, args.checks.skip_unit_check)?;
    let cal =
        checks::read_calibration(&args.calibration, &desc, &args.robot, args.checks.allow_other_robot)?.calibration;
    if args.payload_kg > 0.0 && !cal.robot.effects.payload_sags() {
        eprintln!(
            "warning: --payload-kg {} has no effect: {} models no sag under a payload (no payload term in \
             `robot.effects`: a free-pose calibration fits one from poses measured at several `payload_kg`)",
            axiscal::measurement::format_f64(args.payload_kg),
            args.calibration.display()
        );
    }
    let comp = Compensator::new(&cal.robot, &desc)?.with_payload_kg(args.payload_kg);
    let poses = read_poses(&args.poses)?;
    if let Some(largest) = super::checks::within_a_radians_turn(poses.iter().flat_map(|p| p.rpy_deg)) {
        eprintln!(
            "warning: {}: every roll_deg, pitch_deg and yaw_deg lies within +-6.283 (the largest {}): radians? The \
             orientation columns are degrees (times 57.296 for radians); degrees that small keep the tool within 6 deg \
             of the base axes in every pose",
            args.poses.display(),
            axiscal::measurement::format_f64(largest)
        );
    }
    let positions: Vec<_> = poses
        .iter()
        .map(|p| p.world_from_tool.translation.vector.into())
        .collect();
    checks::pose_units(&positions, &desc, &args.poses, args.checks.skip_unit_check)?;
    let n = desc.dof();
    let mut w = axiscal::csv_lines::writer(outputs.create(&args.out)?);
    w.write_record(csv_header(&desc))?;
    let mut failed = 0;
    let required: Vec<_> = poses.iter().map(|p| p.world_from_tool).collect();
    for (p, compensated) in poses.iter().zip(comp.compensate_sequence(&required)) {
        let mut row = vec![p.id.clone()];
        match compensated {
            Ok(c) => match checks::outside_limits(&desc, &commands_to_file(&desc, &c.cmd)) {
                None => compensated_columns(&mut row, &c, &desc, "ok"),
                Some((joint, value, [lo, hi])) => {
                    failed += 1;
                    eprintln!(
                        "pose {}: cmd_{joint} = {value:.4} is outside the joint's limits [{lo}, {hi}] (deg or mm): not to be sent",
                        p.id
                    );
                    compensated_columns(&mut row, &c, &desc, "outside_limits");
                }
            },
            Err(e) => {
                failed += 1;
                eprintln!("pose {}: {e}", p.id);
                failed_columns(&mut row, &e, n);
            }
        }
        w.write_record(&row)?;
    }
    commit_csv(w)?;
    println!(
        "wrote {} ({} poses, {} failed)",
        args.out.display(),
        poses.len(),
        failed
    );
    if failed > 0 {
        bail!(
            "{failed} of {} poses could not be compensated (status column)",
            poses.len()
        );
    }
    Ok(())
}
