//! `--record FILE.rrd` (feature `viz`): rerun recordings of a campaign. `simulate` replays the
//! simulated campaign with the simulated robot ([`simulated`]); `calibrate` and `diagnose`
//! replay measured data, real or simulated, with the nominal and the calibrated robot side by
//! side ([`calibrated`]). Both draw the measured targets per experiment, the arcs and axes
//! fitted to them with their residual vectors, and send a default layout with the file.

#[cfg(feature = "viz")]
pub mod calibrated;
#[cfg(feature = "viz")]
pub mod simulated;

use super::output::Outputs;
#[cfg(feature = "viz")]
use anyhow::Context;
use anyhow::Result;
use std::path::Path;

/// `--record` was given to a build without the `viz` feature.
#[derive(Debug, thiserror::Error)]
#[error(
    "--record {0} needs the rerun recorder, which this build does not include: install it with \
     `cargo install --locked --path . --features viz` from the clone (another full build; `make run` \
     builds it as target/quick-release/axiscal)"
)]
pub struct RecordUnavailable(String);

/// Fails early, before any work, when `--record` was given but this build cannot record, or
/// when the recording may not be written: not an `.rrd` file (so never one of the command's own
/// outputs), an input of the command, or an existing file without `--force`
/// ([`Outputs::check`]).
pub fn ensure_recordable(path: Option<&Path>, outputs: &Outputs) -> Result<()> {
    let Some(path) = path else { return Ok(()) };
    if !cfg!(feature = "viz") {
        return Err(RecordUnavailable(path.display().to_string()).into());
    }
    if path.extension().is_none_or(|e| e != "rrd") {
        anyhow::bail!(
            "--record {}: a rerun recording is written to a file named `.rrd` (e.g. --record campaign.rrd), \
             which `axiscal view` and the viewer open",
            path.display()
        );
    }
    outputs.check(path)
}

/// Writes the recording `rrd` returns to `path` as every output is written (through a
/// temporary beside it, placed without replacing a file unless `--force`: [`Outputs::write`])
/// and says where it is.
#[cfg(feature = "viz")]
pub fn save(path: &Path, outputs: &Outputs, rrd: impl FnOnce() -> Result<Vec<u8>>) -> Result<()> {
    let bytes = rrd().with_context(|| format!("recording {}", path.display()))?;
    outputs.write(path, bytes)?;
    println!(
        "wrote {} (view it with `axiscal view {}`)",
        path.display(),
        path.display()
    );
    Ok(())
}

#[cfg(feature = "viz")]
mod arcs;
#[cfg(feature = "viz")]
pub use arcs::{ERROR_EXAGGERATION, log_arc_fits};
