//! `axiscal import FORMAT ...`: converts measurement data written by other groups to the
//! measurement CSV of `docs/formats.md#measurement-csv`.

use super::output::Outputs;
use anyhow::{Context, Result};
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

/// Writes `comment` and `set` to `out`, never over `source` (the file imported).
fn write_csv(
    out: &Path,
    force: bool,
    source: &Path,
    comment: &str,
    set: &axiscal::measurement::MeasurementSet,
) -> Result<()> {
    let outputs = Outputs::new(force).input("DIR", source);
    let mut file = outputs.create(out)?;
    file.write_all(comment.as_bytes())
        .and_then(|_| write_measurements_to(&mut file, set))
        .with_context(|| format!("writing {}", out.display()))?;
    file.commit()
}

/// Runs `axiscal import`.
pub fn run(args: Args) -> Result<()> {
    match args.format {
        Format::BobyKlimchik(a) => {
            let source = a.dir.join(boby_klimchik::DATA_FILE);
            Outputs::new(a.force).input("DIR", &source).check(&a.out)?;
            let set = boby_klimchik::import_dir(&a.dir)?;
            write_csv(
                &a.out,
                a.force,
                &source,
                &boby_klimchik::provenance_comment(&source),
                &set,
            )?;
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
