//! Plots (placeholder).
use super::paper::PaperReport;
use std::path::Path;
/// Why a plot could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct PlotError(pub String);
/// Writes the plots.
pub fn write_plots(_r: &PaperReport, _dir: &Path) -> Result<Vec<std::path::PathBuf>, PlotError> { Ok(vec![]) }
