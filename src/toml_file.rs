//! Reading TOML input files (robot descriptions, truth models, effects, scenarios): one error
//! type naming the file, with the parser's line, column and key in the message.

use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

/// A TOML input file could not be read or parsed.
#[derive(Debug, thiserror::Error)]
pub enum TomlFileError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// Malformed TOML, an unknown or missing key, or a value of the wrong type.
    #[error("{path}: {message}")]
    Parse {
        /// The file (or a label for text not read from a file).
        path: PathBuf,
        /// What the parser said, with line and column.
        message: String,
    },
}

/// Reads a whole file as text.
pub fn read(path: &Path) -> Result<String, TomlFileError> {
    std::fs::read_to_string(path).map_err(|source| TomlFileError::Io {
        path: path.to_owned(),
        source,
    })
}

/// Parses TOML text; `path` labels errors only.
pub fn parse<T: DeserializeOwned>(text: &str, path: &Path) -> Result<T, TomlFileError> {
    toml::from_str(text).map_err(|e| TomlFileError::Parse {
        path: path.to_owned(),
        message: e.to_string().trim_end().to_owned(),
    })
}
