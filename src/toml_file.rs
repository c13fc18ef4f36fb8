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

/// Reads a whole file as text (a shipped file's virtual path serves its compiled-in text:
/// [`crate::presets`]).
pub fn read(path: &Path) -> Result<String, TomlFileError> {
    crate::presets::read_text(path).map_err(|source| TomlFileError::Io {
        path: path.to_owned(),
        source,
    })
}

/// Parses TOML text; `path` labels errors only. The message is one line: the 1-based line and
/// column, the parser's message and the offending line's text.
pub fn parse<T: DeserializeOwned>(text: &str, path: &Path) -> Result<T, TomlFileError> {
    toml::from_str(text).map_err(|e| TomlFileError::Parse {
        path: path.to_owned(),
        message: one_line_message(&e, text),
    })
}

/// `line L, column C: message (at `text of the line`)`, or the message alone without a span.
fn one_line_message(e: &toml::de::Error, text: &str) -> String {
    let message = e
        .message()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ");
    let Some(span) = e.span() else { return message };
    let start = span.start.min(text.len());
    let before = &text[..text.floor_char_boundary(start)];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    let source = text[line_start..].lines().next().unwrap_or("").trim();
    format!("line {line}, column {column}: {message} (at `{source}`)")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Small {
        mass_kg: f64,
    }

    #[test]
    fn a_parse_error_is_one_line_with_line_column_and_text() {
        let e = parse::<Small>("# c\nmass_kg = \"x\"\n", Path::new("r.toml"))
            .unwrap_err()
            .to_string();
        assert!(!e.contains('\n'), "{e}");
        assert!(e.starts_with("r.toml: line 2, column 11: "), "{e}");
        assert!(e.contains("(at `mass_kg = \"x\"`)"), "{e}");
        let e = parse::<Small>("mass_kgs = 1\n", Path::new("r.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown field `mass_kgs`") && e.contains("line 1"), "{e}");
    }
}
