//! `axiscal export ur-kinematics|xacro-yaml`: a calibration in the files a robot's software
//! loads (`docs/formats.md#exports`), each read back and checked against the calibrated model
//! at 1,000 random configurations; what a file cannot hold stops the export unless
//! `--approximate`, and is then named in the file and on the console with the error it leaves.

use super::output::Outputs;
use super::printer::Printer;
use anyhow::{Context, Result, bail};
use axiscal::calibration::export::{ChainDeviation, Unrepresented, origins_yaml, ur};
use axiscal::calibration::procedure::Calibration;
use axiscal::robot::RobotDescription;
use std::path::{Path, PathBuf};

/// Arguments of `axiscal export`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    what: What,
}

#[derive(Debug, clap::Subcommand)]
enum What {
    /// The UR ROS driver's `kinematics.yaml` (ur_description's kinematics parameters): joint
    /// origins with the zero offsets in them, the link frames and `hash` of the robot's current
    /// file (`--like`).
    UrKinematics(UrArgs),
    /// Per-joint URDF origins as YAML for a support package's xacro (`xacro.load_yaml`), zero
    /// offsets in the origins or as ros_control transmission offsets.
    XacroYaml(XacroArgs),
}

/// What every export reads and writes.
#[derive(Debug, clap::Args)]
struct Common {
    /// The calibration (`calibration.json` written by `axiscal calibrate`).
    #[arg(long)]
    calibration: PathBuf,
    /// Nominal robot description (TOML) the calibration was made with.
    #[arg(long, default_value = "asea-irb6l", value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// Go on even when the calibration records another robot description than `--robot`.
    #[arg(long)]
    allow_other_robot: bool,
    /// Write the file even when it cannot hold the whole calibration (harmonic transmissions,
    /// couplings, carried effects): what it leaves out is listed in it, with the tool error.
    #[arg(long)]
    approximate: bool,
    /// The file to write.
    #[arg(long)]
    out: PathBuf,
    /// Replace `--out` if it exists.
    #[arg(long)]
    force: bool,
}

#[derive(Debug, clap::Args)]
struct UrArgs {
    #[command(flatten)]
    common: Common,
    /// The robot's current `kinematics.yaml` (ur_description's `config/<ur_type>/default_kinematics.yaml`
    /// or the file `ur_calibration` extracted): its link frames and `hash` are kept.
    #[arg(long)]
    like: PathBuf,
    /// The `hash` to write instead of `--like`'s: the checksum of the controller calibration the
    /// driver should find on the robot (`calib_...`).
    #[arg(long)]
    hash: Option<String>,
}

#[derive(Debug, clap::Args)]
struct XacroArgs {
    #[command(flatten)]
    common: Common,
    /// Where the joints' zero offsets go: into the origins (the joint values are the readings)
    /// or into ros_control's simple transmission (`mechanical_reduction`, `offset` per joint).
    #[arg(long, value_enum, default_value = "origins")]
    offsets: Offsets,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum Offsets {
    Origins,
    Transmission,
}

/// Runs `axiscal export`.
pub fn run(args: Args, printer: Printer) -> Result<()> {
    match args.what {
        What::UrKinematics(a) => ur_kinematics(a, printer),
        What::XacroYaml(a) => xacro_yaml(a, printer),
    }
}

/// The description and calibration of `common`, and the outputs with every input registered.
fn inputs(common: &Common, extra: &[(&str, &Path)]) -> Result<(RobotDescription, Calibration, Outputs)> {
    let mut outputs = Outputs::new(common.force)
        .input("--calibration", &common.calibration)
        .input("--robot", &common.robot);
    for (what, path) in extra {
        outputs = outputs.input(what, path);
    }
    outputs.check(&common.out)?;
    let desc = RobotDescription::from_file(&common.robot)?;
    let cal = super::checks::read_calibration(&common.calibration, &desc, &common.robot, common.allow_other_robot)?
        .calibration;
    Ok((desc, cal, outputs))
}

/// Refuses an inexact export without `--approximate`, naming what it cannot hold.
fn refuse_inexact(left_out: &[Unrepresented], dev: &ChainDeviation, format: &str, approximate: bool) -> Result<()> {
    if left_out.is_empty() || approximate {
        return Ok(());
    }
    let items: Vec<&str> = left_out.iter().map(|u| u.what.as_str()).collect();
    let mut remedies: Vec<&str> = Vec::new();
    for u in left_out {
        if !remedies.contains(&u.remedy) {
            remedies.push(u.remedy);
        }
    }
    bail!(
        "{format} cannot hold this calibration: {}. Written without them the tool would be off by up to {:.3} mm and {:.3} mrad ({} configurations). Pass --approximate to write it so, or: {}",
        items.join("; "),
        dev.max_position_m * 1e3,
        dev.max_rotation_rad * 1e3,
        dev.poses,
        remedies.join("; ")
    )
}

/// The comment lines every export starts with.
fn header(common: &Common, left_out: &[Unrepresented], dev: &ChainDeviation) -> Vec<String> {
    let mut lines = vec![format!(
        "Written by axiscal {} from {} (robot description {}).",
        env!("CARGO_PKG_VERSION"),
        common.calibration.display(),
        common.robot.display()
    )];
    if left_out.is_empty() {
        lines.push(format!(
            "Read back, it reproduces the calibrated tool pose to {:.1e} m and {:.1e} rad at {} random configurations.",
            dev.max_position_m, dev.max_rotation_rad, dev.poses
        ));
    } else {
        lines.push("APPROXIMATE: this file does not hold".into());
        lines.extend(left_out.iter().map(|u| format!("  - {}", u.what)));
        lines.push(format!(
            "Read back, the tool is off the calibrated model by up to {:.3} mm and {:.3} mrad at {} random configurations.",
            dev.max_position_m * 1e3,
            dev.max_rotation_rad * 1e3,
            dev.poses
        ));
    }
    lines
}

fn ur_kinematics(a: UrArgs, printer: Printer) -> Result<()> {
    let (desc, cal, outputs) = inputs(&a.common, &[("--like", &a.like)])?;
    let text = axiscal::presets::read_text(&a.like).with_context(|| format!("{}: cannot read", a.like.display()))?;
    let reference = ur::UrKinematics::parse(&text, &a.like.display().to_string())?;
    let out = ur::export(&cal, &desc, &reference, a.hash.as_deref()).map_err(|e| match e {
        ur::UrError::Anchor(_) => anyhow::anyhow!("--like {}: {e}", a.like.display()),
        e => e.into(),
    })?;
    refuse_inexact(
        &out.left_out,
        &out.deviation,
        "a UR kinematics.yaml",
        a.common.approximate,
    )?;
    let mut comments = header(&a.common, &out.left_out, &out.deviation);
    comments.extend([
        format!(
            "Joint values are the controller's readings (zero offsets are in the origins); link frames as in {} (kept within {:.3} mm, {:.3} mrad).",
            a.like.display(),
            out.frames.largest_offset_m * 1e3,
            out.frames.largest_tilt_rad * 1e3
        ),
        format!(
            "The calibrated TCP in tool0 (set it on the controller): {}",
            ur::ur_pose(&out.tool0_from_tcp)
        ),
        format!("base_link in the instrument frame: {}", ur::ur_pose(&out.world_from_base_link)),
        "hash: the checksum of the controller's own calibration this file belongs to; the driver compares it with the robot's.".into(),
    ]);
    outputs.write(&a.common.out, out.kinematics.to_yaml(&comments))?;
    say!(
        printer,
        "wrote {} (UR kinematics, hash {}): {}",
        a.common.out.display(),
        out.kinematics.hash,
        summary(&out.left_out, &out.deviation)
    );
    say!(
        printer,
        "  calibrated TCP in tool0: {}",
        ur::ur_pose(&out.tool0_from_tcp)
    );
    Ok(())
}

fn xacro_yaml(a: XacroArgs, printer: Printer) -> Result<()> {
    let (desc, cal, outputs) = inputs(&a.common, &[])?;
    let offsets = match a.offsets {
        Offsets::Origins => origins_yaml::OffsetsIn::Origins,
        Offsets::Transmission => origins_yaml::OffsetsIn::Transmission,
    };
    let out = origins_yaml::export(&cal, &desc, offsets)?;
    refuse_inexact(&out.left_out, &out.deviation, "per-joint origins", a.common.approximate)?;
    let mut comments = header(&a.common, &out.left_out, &out.deviation);
    comments.push(match a.offsets {
        Offsets::Origins => "Joint values are the controller's readings: the zero offsets are in the origins.".into(),
        Offsets::Transmission => "Origins of the calibrated joint values; joint position = reading / mechanical_reduction + offset (ros_control simple transmission).".into(),
    });
    comments.push("URDF convention: x, y, z in m; roll, pitch, yaw in rad, R = Rz(yaw) Ry(pitch) Rx(roll); every joint moves along or about its +Z.".into());
    let text: String = comments
        .iter()
        .map(|c| format!("# {}\n", axiscal::csv_lines::one_line(c)))
        .collect::<String>()
        + &out.yaml;
    outputs.write(&a.common.out, text)?;
    say!(
        printer,
        "wrote {} (per-joint origins): {}",
        a.common.out.display(),
        summary(&out.left_out, &out.deviation)
    );
    Ok(())
}

/// One line on how well the written file holds the calibration.
fn summary(left_out: &[Unrepresented], dev: &ChainDeviation) -> String {
    if left_out.is_empty() {
        format!(
            "read back, it reproduces the calibrated tool pose to {:.1e} m, {:.1e} rad at {} configurations",
            dev.max_position_m, dev.max_rotation_rad, dev.poses
        )
    } else {
        format!(
            "APPROXIMATE ({} item(s) left out, listed in the file): tool off by up to {:.3} mm, {:.3} mrad at {} configurations",
            left_out.len(),
            dev.max_position_m * 1e3,
            dev.max_rotation_rad * 1e3,
            dev.poses
        )
    }
}
