//! `axiscal joints --calibration CAL.json CMD...`: the calibrated joint values of controller
//! commands (what a URDF, a ROS `joint_states` publisher or any kinematic-chain tool must be
//! fed), for one pose on the command line or every row of a CSV.

use anyhow::{Context, Result, bail};
use axiscal::calibration::procedure::{Calibration, calibrated_joint_values};
use axiscal::measurement::format_f64;
use axiscal::measurement::import::table::Table;
use axiscal::robot::{RobotDescription, commands_to_file};
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// Arguments of `axiscal joints`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The calibration (`calibration.json` written by `axiscal calibrate`).
    #[arg(long)]
    calibration: PathBuf,
    /// Nominal robot description (TOML) the calibration was made with.
    #[arg(long, default_value = "asea-irb6l", value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// One pose's commands as the controller reads them, `cmd_1 .. cmd_N` (deg or mm), e.g.
    /// `10 -20.5 30 0 45 90`.
    #[arg(allow_negative_numbers = true, value_parser = command_value)]
    commands: Vec<f64>,
    /// A CSV with columns `cmd_1 .. cmd_N` (any other columns are copied): every row gets
    /// `q_1 .. q_N` appended. Written to stdout.
    #[arg(long, conflicts_with = "commands")]
    csv: Option<PathBuf>,
    /// Go on even when the calibration records another robot description than `--robot` (a
    /// different geometry hash).
    #[arg(long)]
    allow_other_robot: bool,
}

/// One command given on the command line; a list in one argument (`10,10,10`) is told to be
/// given as separate arguments.
fn command_value(text: &str) -> Result<f64, String> {
    let shown = axiscal::csv_lines::shown_cell(text.trim());
    if text.contains([',', ';']) || text.trim().contains(char::is_whitespace) {
        return Err(format!(
            "`{shown}` holds several values; give each command as its own argument (`10 -20.5 30 ...`, cmd_1 .. cmd_N)"
        ));
    }
    // A NaN or infinity parses: the limits check names its joint.
    text.trim()
        .parse::<f64>()
        .map_err(|_| format!("`{shown}` is not a number (a command in deg or mm)"))
}

/// Refuses commands (file units) outside the description's limits: a reading no pose of the
/// robot gives (a unit slip, a dummy value), where the calibrated model would extrapolate.
fn within_limits(desc: &RobotDescription, cmd_file: &[f64], what: &str) -> Result<()> {
    if let Some(k) = cmd_file.iter().position(|c| !c.is_finite()) {
        let what_it_is = if cmd_file[k].is_nan() {
            "not a number"
        } else {
            "not a finite number"
        };
        bail!(
            "{what}: cmd_{} = {} is {what_it_is}: give each command as a finite number (deg or mm), as the controller \
             reads it",
            k + 1,
            cmd_file[k]
        );
    }
    match super::checks::outside_limits(desc, cmd_file) {
        Some((joint, value, [lo, hi])) => bail!(
            "{what}: cmd_{joint} = {} is outside the joint's limits [{lo}, {hi}] (deg or mm; the description's `limits`)",
            format_f64(value)
        ),
        None => Ok(()),
    }
}

/// Runs `axiscal joints`.
pub fn run(args: Args) -> Result<()> {
    let desc = RobotDescription::from_file(&args.robot)?;
    let cal =
        super::checks::read_calibration(&args.calibration, &desc, &args.robot, args.allow_other_robot)?.calibration;
    match &args.csv {
        Some(path) => convert_csv(&cal, &desc, path, &args.calibration),
        None => {
            if args.commands.len() != desc.dof() {
                bail!(
                    "give {} commands (cmd_1 .. cmd_{}), got {}",
                    desc.dof(),
                    desc.dof(),
                    args.commands.len()
                );
            }
            within_limits(&desc, &args.commands, "the commands")?;
            let q = calibrated_joint_values(&cal, &desc, &args.commands).with_context(|| {
                format!(
                    "the calibrated robot of {} cannot execute these commands",
                    args.calibration.display()
                )
            })?;
            let q = commands_to_file(&desc, &q);
            println!("{}", q.iter().map(|v| format_f64(*v)).collect::<Vec<_>>().join(" "));
            Ok(())
        }
    }
}

/// Appends `q_1 .. q_N` to every row of the CSV at `path`, to stdout, after its comment lines
/// before the header. `cal` was read from `cal_path`.
fn convert_csv(cal: &Calibration, desc: &RobotDescription, path: &Path, cal_path: &Path) -> Result<()> {
    let table = Table::read(path)?;
    let names: Vec<String> = (1..=desc.dof()).map(|k| format!("cmd_{k}")).collect();
    let columns = table.required_all(&names.iter().map(String::as_str).collect::<Vec<_>>())?;
    let added: Vec<String> = (1..=desc.dof()).map(|k| format!("q_{k}")).collect();
    if let Some(q) = added.iter().find(|q| table.column(&[q]).is_some()) {
        bail!(
            "{}: column `{q}`: the file already has the calibrated joint values' columns; remove them (the output appends `q_1 .. q_{}`)",
            path.display(),
            desc.dof()
        );
    }
    // Every row is converted, into the table's text, before any is written: a bad row leaves
    // stdout empty, not a table cut short at it.
    let mut text = axiscal::csv_lines::writer(Vec::new());
    text.write_record(table.header_as_written.iter().chain(&added))?;
    let mut revolute_deg: Vec<f64> = Vec::new();
    for row in table.rows() {
        let cmd: Vec<f64> = columns
            .iter()
            .map(|&c| table.number(&row, c))
            .collect::<Result<_, _>>()?;
        revolute_deg.extend(
            desc.joints
                .iter()
                .zip(&cmd)
                .filter(|(j, _)| j.kind == axiscal::kinematics::JointKind::Revolute)
                .map(|(_, c)| *c),
        );
        let place = format!("{}:{}", path.display(), row.line);
        within_limits(desc, &cmd, &place)?;
        let q = calibrated_joint_values(cal, desc, &cmd).with_context(|| {
            format!(
                "{place}: the calibrated robot of {} cannot execute these commands",
                cal_path.display()
            )
        })?;
        let values = commands_to_file(desc, &q);
        let mut cells: Vec<String> = row.cells().map(str::to_owned).collect();
        cells.resize(table.header.len(), String::new());
        cells.extend(values.iter().map(|v| format_f64(*v)));
        text.write_record(&cells)?;
    }
    let text = text.into_inner().map_err(|e| e.into_error())?;
    if let Some(largest) = super::checks::within_a_radians_turn(revolute_deg) {
        eprintln!(
            "warning: {}: every revolute joint's command lies within +-6.283 (the largest {}): radians? The cmd_k \
             columns are degrees as the controller reads them (times 57.296 for radians); degrees that small keep \
             every joint within 6.3 deg of zero in every row",
            path.display(),
            format_f64(largest)
        );
    }
    let mut stdout = std::io::stdout().lock();
    for comment in &table.comments {
        writeln!(stdout, "# {comment}")?;
    }
    stdout.write_all(&text)?;
    stdout.flush()?;
    Ok(())
}
