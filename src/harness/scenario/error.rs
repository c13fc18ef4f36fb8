//! Errors of scenario resolution and of runs.

use std::path::PathBuf;

/// A scenario could not be read or resolved.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read or parsed.
    #[error(transparent)]
    File(#[from] crate::toml_file::TomlFileError),
    /// A key has a value that parses but does not make sense.
    #[error("{path}: key `{key}`: {message}")]
    Invalid {
        /// The scenario file.
        path: PathBuf,
        /// The key, dotted (`sweep.spans`).
        key: String,
        /// What is wrong.
        message: String,
    },
}
