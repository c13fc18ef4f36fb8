//! `axiscal view FILE.rrd`: opens a recording in the rerun viewer of the version the recording
//! was written with, or says how to install it.

use anyhow::{Result, bail};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The version of the `rerun` crate pinned in Cargo.toml: recordings are read by the viewer of
/// the same version (checked against Cargo.toml and Cargo.lock by a test).
pub const RERUN_VERSION: &str = "0.36.3";

/// The command that installs the matching viewer (the `rerun-sdk` wheel ships the `rerun`
/// binary).
pub fn install_command() -> String {
    format!("pip install rerun-sdk=={RERUN_VERSION}")
}

/// Arguments of `axiscal view`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The recording (`.rrd`, e.g. written by `axiscal simulate --record FILE.rrd`).
    file: PathBuf,
}

/// Where the viewer is looked for: the file `AXISCAL_RERUN` names, if set (alone); else, in
/// order, `.venv/bin/rerun` of the current folder, the one `make setup-viewer` installs in the
/// clone this binary was built from (so `axiscal view` finds it from any folder, also after
/// `cargo install --path .`), then `rerun` on `PATH`.
fn viewer_candidates() -> Vec<PathBuf> {
    if let Some(viewer) = std::env::var_os("AXISCAL_RERUN") {
        return vec![PathBuf::from(viewer)];
    }
    let venv = |root: &Path| root.join(".venv").join("bin").join("rerun");
    let mut out = vec![venv(Path::new(".")), venv(Path::new(env!("CARGO_MANIFEST_DIR")))];
    if let Some(path) = std::env::var_os("PATH") {
        out.extend(std::env::split_paths(&path).map(|dir| dir.join("rerun")));
    }
    out
}

/// The first viewer of [`viewer_candidates`] that exists.
fn find_viewer() -> Option<PathBuf> {
    viewer_candidates().into_iter().find(|candidate| candidate.is_file())
}

/// The first bytes of every rerun recording: `RRF` and the framing version (`RRF2` for rerun
/// 0.36, `RRF0`/`RRF1` for older files the viewer still reads).
const RRD_MAGIC: &[u8] = b"RRF";

/// Refuses a file that is not a rerun recording (a measurement CSV, a calibration) before any
/// word about the viewer, which could not open it either.
fn check_recording(file: &Path) -> Result<()> {
    use std::io::Read;
    let mut head = Vec::with_capacity(RRD_MAGIC.len());
    std::fs::File::open(file)
        .and_then(|f| f.take(RRD_MAGIC.len() as u64).read_to_end(&mut head))
        .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
    if head != RRD_MAGIC {
        bail!(
            "{}: not a rerun recording (.rrd: it does not start with `RRF`); write one with `--record FILE.rrd` \
             (simulate, calibrate or diagnose) and view that",
            file.display()
        );
    }
    Ok(())
}

/// Runs `axiscal view`. A missing or failing viewer is not an error (exit 0): the recording is
/// still valid, and this prints what to do.
pub fn run(args: Args) -> Result<()> {
    if args.file.is_dir() {
        bail!(
            "{} is a folder; give the recording file (`.rrd`) in it",
            args.file.display()
        );
    }
    if args.file.exists() && !args.file.is_file() {
        bail!(
            "{} is not a regular file (a device or a pipe); give a recording file (`.rrd`)",
            args.file.display()
        );
    }
    if !args.file.is_file() {
        bail!("no recording at {}", args.file.display());
    }
    check_recording(&args.file)?;
    let Some(viewer) = find_viewer() else {
        println!(
            "The rerun viewer was not found ({}). Install the viewer matching this recording \
             with\n\n    {}\n\n(`make setup-viewer` in the clone installs it into its .venv, where \
             `axiscal view` finds it from any folder), then run `axiscal view {}` again.",
            match std::env::var_os("AXISCAL_RERUN") {
                Some(v) => format!("AXISCAL_RERUN names {}, which is not a file", Path::new(&v).display()),
                None => format!(
                    "looked in ./.venv/bin/, {}/.venv/bin/ and on PATH",
                    env!("CARGO_MANIFEST_DIR")
                ),
            },
            install_command(),
            args.file.display()
        );
        return Ok(());
    };
    if let Ok(out) = Command::new(&viewer).arg("--version").output() {
        let version = String::from_utf8_lossy(&out.stdout);
        if !version.contains(RERUN_VERSION) {
            eprintln!(
                "warning: {} reports `{}`; recordings are written by rerun {RERUN_VERSION} \
                 (install the match with `{}`)",
                viewer.display(),
                version.trim(),
                install_command()
            );
        }
    }
    eprintln!("opening {} with {}", args.file.display(), viewer.display());
    match Command::new(&viewer).arg(&args.file).status() {
        Ok(status) if status.success() => {}
        Ok(status) => eprintln!(
            "warning: the viewer exited with {status} (no display?); the recording is unaffected \
             (check it with `{} rrd verify {}`)",
            viewer.display(),
            args.file.display()
        ),
        Err(e) => eprintln!("warning: could not start {}: {e}", viewer.display()),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viewer_version_matches_the_pinned_crate() {
        let manifest = include_str!("../../Cargo.toml");
        let line = manifest
            .lines()
            .find(|l| l.starts_with("rerun = "))
            .expect("Cargo.toml declares rerun");
        assert!(line.contains(&format!("version = \"={RERUN_VERSION}\"")), "{line}");
        let lock = include_str!("../../Cargo.lock");
        assert!(
            lock.contains(&format!("name = \"rerun\"\nversion = \"{RERUN_VERSION}\"")),
            "Cargo.lock pins rerun {RERUN_VERSION}"
        );
        assert_eq!(install_command(), "pip install rerun-sdk==0.36.3");
    }

    /// From any folder, the clone's `.venv` (where `make setup-viewer` installs) is looked in,
    /// after the current folder's and before `PATH`.
    #[test]
    fn the_clones_viewer_is_found_from_any_folder() {
        if std::env::var_os("AXISCAL_RERUN").is_some() {
            return;
        }
        let candidates = viewer_candidates();
        let clone = Path::new(env!("CARGO_MANIFEST_DIR")).join(".venv/bin/rerun");
        assert_eq!(candidates[0], Path::new("./.venv/bin/rerun"));
        assert_eq!(candidates[1], clone);
    }
}
