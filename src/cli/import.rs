//! `axiscal import FORMAT ...`: converts measurement data written by other groups to the
//! measurement CSV of `docs/formats.md#measurement-csv`.

use anyhow::{Context, Result, bail};
use axiscal::measurement::import::boby_klimchik;
use axiscal::measurement::write_measurements_to;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `axiscal import`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    format: Format,
}

/// The source formats.
#[derive(Debug, clap::Subcommand)]
enum Format {
    /// Boby & Klimchik's laser-tracker data (folder with N1N2N3Jval.csv): six one-joint
    /// blocks of six poses, three SMRs each (targets 0,1,2 = SMRs 2,3,1). cmd_3 = J3 + J2 (the controller reads J3
    /// against the ground).
    BobyKlimchik(DirArgs),
}

/// A data-set folder and the output file.
#[derive(Debug, clap::Args)]
struct DirArgs {
    /// The data set's folder.
    dir: PathBuf,
    /// Output measurement CSV.
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing output file.
    #[arg(long)]
    force: bool,
}

fn write_csv(out: &Path, force: bool, comment: &str, set: &axiscal::measurement::MeasurementSet) -> Result<()> {
    if out.exists() && !force {
        bail!("{} exists; pass --force to replace it", out.display());
    }
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    }
    let file = std::fs::File::create(out).with_context(|| format!("creating {}", out.display()))?;
    let mut w = std::io::BufWriter::new(file);
    w.write_all(comment.as_bytes())
        .and_then(|_| write_measurements_to(&mut w, set))
        .and_then(|_| w.flush())
        .with_context(|| format!("writing {}", out.display()))
}

/// Runs `axiscal import`.
pub fn run(args: Args) -> Result<()> {
    match args.format {
        Format::BobyKlimchik(a) => {
            let set = boby_klimchik::import_dir(&a.dir)?;
            let source = a.dir.join(boby_klimchik::DATA_FILE);
            write_csv(&a.out, a.force, &boby_klimchik::provenance_comment(&source), &set)?;
            println!(
                "imported {} poses ({} experiments, {} targets each) from {} to {}",
                set.rows().len() / boby_klimchik::TARGETS,
                set.experiments().len(),
                boby_klimchik::TARGETS,
                source.display(),
                a.out.display()
            );
            Ok(())
        }
    }
}
