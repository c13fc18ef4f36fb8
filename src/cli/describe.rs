//! `axiscal describe ROBOT.toml`: the phi-model of a robot description (rows, phi angles,
//! placement, tool, the joint axes at the zero pose) and, for a description given as a DH
//! table or a URDF, a check of its forward kinematics against the source at random poses.

use anyhow::{Context, Result, bail};
use axiscal::robot::{RobotDescription, RowEntry, commands_to_internal};
use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};
use std::path::PathBuf;

/// Arguments of `axiscal describe`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Robot description (TOML; phi rows, `dh` rows or a `urdf` file), or a shipped one's name.
    #[arg(value_parser = super::options::ROBOT_FILE)]
    robot: PathBuf,
    /// Random poses (uniform within the joint limits) for the forward-kinematics check (at most
    /// a million: a few seconds).
    #[arg(long, default_value_t = 1000, value_parser = super::options::InRange::closed(1usize, 1_000_000, ""))]
    poses: usize,
    /// Seed of the random poses.
    #[arg(long, value_parser = super::options::SEED, default_value_t = 1)]
    seed: u64,
    /// Print, instead, the description's nominal model as a truth model (TOML,
    /// `docs/formats.md#robot-model`): edit its rows, transmissions, couplings and offsets into
    /// the robot to simulate, then `simulate --robot ROBOT --truth FILE`.
    #[arg(long)]
    truth_template: bool,
    /// Skip the unit sanity check of the description's lengths (as `simulate` and `calibrate`
    /// run it).
    #[arg(long)]
    skip_unit_check: bool,
}

/// The nominal model of `desc` as a truth model file, read back before it is printed.
fn print_truth_template(desc: &RobotDescription, path: &std::path::Path) -> Result<()> {
    let model = axiscal::robot::RobotModel::ideal(desc);
    let text = toml::to_string(&model).context("writing the truth model as TOML")?;
    let back: axiscal::robot::RobotModel = toml::from_str(&text).context("reading the template back")?;
    if back != model {
        bail!("the truth template of {} does not read back as written", path.display());
    }
    // A shipped description by its name, a file by its path.
    let named = match path.strip_prefix(axiscal::presets::SHIPPED_ROOT) {
        Ok(_) => path
            .file_stem()
            .map_or(path.display().to_string(), |s| s.to_string_lossy().into_owned()),
        Err(_) => path.display().to_string(),
    };
    println!(
        "# The nominal model of {} as a truth model (docs/formats.md#robot-model): no manufacturing\n\
         # error. Edit rows, transmissions, couplings, transducer offsets, placement and tool frame\n\
         # into the robot to simulate, then: axiscal simulate --robot {} --truth THIS_FILE\n\
         # (angles in rad, lengths in m unless a key says otherwise).",
        desc.name, named
    );
    print!("{text}");
    Ok(())
}

/// The converted model must reproduce the source to this (m, rad): both are products of a
/// dozen unit-size rigid transforms, whose rounding is ~1e-15 per product; 1e-9 leaves six
/// orders for arms of a few metres.
const FK_TOLERANCE: f64 = 1e-9;

/// Runs `axiscal describe`.
pub fn run(args: Args) -> Result<()> {
    let text = axiscal::presets::read_text(&args.robot).with_context(|| format!("reading {}", args.robot.display()))?;
    let (desc, source) = RobotDescription::with_source(&text, &args.robot)?;
    super::checks::description_units(&desc, &args.robot, args.skip_unit_check)?;
    if args.truth_template {
        return print_truth_template(&desc, &args.robot);
    }
    let model = desc.nominal_model();
    println!(
        "# {} ({} joints): phi-model rows (paper Table 2 form), file units",
        desc.name,
        desc.dof()
    );
    for (k, j) in desc.joints.iter().enumerate() {
        println!(
            "joint {}: {:<9} phi_deg = {:>12.6}  limits = [{}, {}]",
            k + 1,
            format!("{:?}", j.kind).to_lowercase(),
            j.phi_deg,
            j.limits[0],
            j.limits[1]
        );
    }
    for (k, r) in desc.rows.iter().enumerate() {
        print_row(k, r);
    }
    let p = desc.placement;
    println!(
        "placement: translation_mm = {:?}, rpy_deg = {:?}",
        p.translation_mm, p.rpy_deg
    );
    println!(
        "tool.frame: translation_mm = {:?}, rpy_deg = {:?}",
        desc.tool.frame.translation_mm, desc.tool.frame.rpy_deg
    );
    let poses = model.poses(&vec![0.0; desc.dof()]);
    println!("axes at the zero pose (instrument frame):");
    for k in 0..desc.dof() {
        let a = poses.axis(k);
        let o = a.origin_m * 1e3;
        let d = a.direction;
        println!(
            "  axis {}: point ({:.3}, {:.3}, {:.3}) mm, direction ({:.6}, {:.6}, {:.6})",
            k + 1,
            o.x,
            o.y,
            o.z,
            d.x,
            d.y,
            d.z
        );
    }
    let Some((source, world_from_source)) = source else {
        println!("geometry given as phi rows: nothing to check");
        return Ok(());
    };
    let mut rng = ChaCha12Rng::seed_from_u64(args.seed);
    let (mut worst_m, mut worst_rad): (f64, f64) = (0.0, 0.0);
    for _ in 0..args.poses {
        let cmd: Vec<f64> = desc
            .joints
            .iter()
            .map(|j| rng.random_range(j.limits[0]..=j.limits[1]))
            .collect();
        let q = commands_to_internal(&desc, &cmd);
        let (a, b) = (world_from_source * source.base_from_tool(&q), model.world_from_tool(&q));
        worst_m = worst_m.max((a.translation.vector - b.translation.vector).norm());
        worst_rad = worst_rad.max(a.rotation.angle_to(&b.rotation));
    }
    println!(
        "forward kinematics against the source at {} random poses (seed {}): largest difference {:.3e} mm, {:.3e} rad",
        args.poses,
        args.seed,
        worst_m * 1e3,
        worst_rad
    );
    if worst_m > FK_TOLERANCE || worst_rad > FK_TOLERANCE {
        bail!(
            "the converted phi-model differs from the source by {worst_m:.3e} m, {worst_rad:.3e} rad (tolerance {FK_TOLERANCE:e})"
        );
    }
    Ok(())
}

fn print_row(k: usize, r: &RowEntry) {
    println!(
        "[[rows]]  # row {}: frame {} in the phi_{} frame\na_m = {:.9}\nb_m = {:.9}\nalpha_deg = {:.9}\nbeta_deg = {:.9}",
        k + 1,
        k + 2,
        k + 1,
        r.a_m,
        r.b_m,
        r.alpha_deg,
        r.beta_deg
    );
}
