//! Reading TOML input files (robot descriptions, truth models, effects, scenarios): one error
//! type naming the file, with the parser's line, column and key in the message.

use crate::csv_lines::{shown_cell, shown_message};
use serde::Serialize;
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

/// A TOML input file could not be read or parsed.
#[derive(Debug, thiserror::Error)]
pub enum TomlFileError {
    /// The file could not be read.
    #[error("{path}: cannot read: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        cause: std::io::Error,
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
        cause: source,
    })
}

/// Parses TOML text; `path` labels errors only. The message is one line: the 1-based line and
/// column, the parser's message and the offending line's text.
///
/// A `nan` or `inf` is an error naming its key: no key of axiscal's TOML files takes one.
///
/// A fixed-length list written longer (`limits = [-40, 0, 40]` for two numbers) is an error
/// naming its key: the parser reads the first values and drops the rest, so the value read
/// back is compared with the text, list by list, where both have a list at one key.
///
/// Text that does not parse and is a CSV table ([`looks_like_csv`]) is an error saying so, not
/// the parser's message about its first line.
pub fn parse<T: DeserializeOwned + Serialize>(text: &str, path: &Path) -> Result<T, TomlFileError> {
    let parse_error = |e: toml::de::Error| TomlFileError::Parse {
        path: path.to_owned(),
        message: one_line_message(&e, text),
    };
    let value: T = toml::from_str(text).map_err(|e| match foreign_format(text, path) {
        Some(message) => TomlFileError::Parse {
            path: path.to_owned(),
            message,
        },
        None => match top_level_key_in_table::<T>(&e, text) {
            Some(hint) => TomlFileError::Parse {
                path: path.to_owned(),
                message: format!("{}; {hint}", one_line_message(&e, text)),
            },
            None => parse_error(e),
        },
    })?;
    let written: toml::Table = toml::from_str(text).map_err(parse_error)?;
    if let Some((key, v)) = non_finite_in(&written, "") {
        return Err(TomlFileError::Parse {
            path: path.to_owned(),
            message: format!("key `{key}`: {v} is not a number any key of this file takes: write a finite number"),
        });
    }
    if let Ok(toml::Value::Table(read)) = toml::Value::try_from(&value)
        && let Some((key, written_len, read_len)) = longer_list(&written, &read, "")
    {
        return Err(TomlFileError::Parse {
            path: path.to_owned(),
            message: format!("key `{key}`: {written_len} values, but it holds {read_len}"),
        });
    }
    Ok(value)
}

/// The kinds of axiscal's own TOML files, told apart by their top-level keys ([`Self::of`]), so
/// that one given where another is read is named, not met with the parser's first unknown key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OwnToml {
    /// A robot description (`joints`, `urdf` or `rows`, with its `tool` or `axis_targets`):
    /// `--robot`, `describe`.
    Description,
    /// A robot model, a simulated truth (`tool_frame`, `four_bars`, joints with their
    /// `transmission`): `--truth`.
    Model,
    /// A scenario (`measurement`, `truth`, `thresholds` or `trials`): `axiscal run`.
    Scenario,
    /// A calibration plan (`sweeps`, no `joints`): `--plan`.
    Plan,
}

impl OwnToml {
    /// The kind of `text`, when it is TOML with one kind's keys.
    pub fn of(text: &str) -> Option<Self> {
        let table: toml::Table = toml::from_str(text).ok()?;
        let has = |key: &str| table.contains_key(key);
        let any = |keys: &[&str]| keys.iter().any(|k| has(k));
        // A model's joints carry their errors; a description's their limits.
        let model_joints = table
            .get("joints")
            .and_then(|j| j.as_array()?.first()?.as_table().cloned())
            .is_some_and(|j| j.contains_key("transmission") || j.contains_key("transducer_offset"));
        let description_only = [
            "tool",
            "axis_targets",
            "dh_convention",
            "urdf",
            "couplings",
            "instrument",
        ];
        if any(&["measurement", "truth", "thresholds", "trials"]) {
            Some(Self::Scenario)
        } else if !any(&description_only) && (any(&["tool_frame", "four_bars", "effects"]) || model_joints) {
            Some(Self::Model)
        } else if any(&["joints", "urdf", "rows"]) {
            Some(Self::Description)
        } else if has("sweeps") {
            Some(Self::Plan)
        } else {
            None
        }
    }

    /// The kind in words, where it is given, and its section of docs/formats.md.
    fn said(self) -> (&'static str, &'static str, &'static str) {
        match self {
            Self::Description => (
                "a robot description",
                "with --robot or to `describe`",
                "robot-description",
            ),
            Self::Model => ("a robot model (a simulated truth)", "with --truth", "robot-model"),
            Self::Scenario => ("a scenario file", "to `axiscal run`", "scenario-file"),
            Self::Plan => ("a calibration plan", "with --plan", "plan-file"),
        }
    }
}

/// [`parse`] for one of axiscal's own kinds of TOML file: text of another own kind
/// ([`OwnToml::of`]) that does not parse as `expected` is an error naming both kinds.
pub fn parse_own<T: DeserializeOwned + Serialize>(
    text: &str,
    path: &Path,
    expected: OwnToml,
) -> Result<T, TomlFileError> {
    parse(text, path).map_err(|e| match OwnToml::of(text).filter(|k| *k != expected) {
        Some(kind) => TomlFileError::Parse {
            path: path.to_owned(),
            message: {
                let ((kind, given, doc), (wanted, _, wanted_doc)) = (kind.said(), expected.said());
                format!(
                    "this is {kind}, not {wanted} (docs/formats.md#{wanted_doc}): {kind} is given {given} \
                     (docs/formats.md#{doc})"
                )
            },
        },
        None => e,
    })
}

/// What `text`, which is not the XML of a URDF, is instead, for a message: a CSV table, one
/// of axiscal's own TOML files, other TOML or JSON; `None` when it starts as XML (a URDF with a
/// fault the parser names) or is none of these.
pub fn not_xml(text: &str, path: &Path) -> Option<String> {
    let (_, first) = first_content_line(text)?;
    if first.starts_with('<') {
        return None;
    }
    if csv_first_line(text, path).is_some() {
        return Some("a CSV table".into());
    }
    if let Some(kind) = OwnToml::of(text) {
        return Some(format!("a TOML file, {}", kind.said().0));
    }
    if toml::from_str::<toml::Table>(text).is_ok() {
        return Some("a TOML file".into());
    }
    first.starts_with('{').then(|| "JSON".into())
}

/// What `text`, which does not parse as TOML, is instead, when its first content line tells: a
/// CSV table, a URDF or other XML, a JSON object; `None` for text that is meant as TOML.
fn foreign_format(text: &str, path: &Path) -> Option<String> {
    const GIVE_TOML: &str =
        "give the TOML file of `key = value` lines (docs/formats.md) that this option or command reads";
    if let Some((line, first)) = csv_first_line(text, path) {
        return Some(format!(
            "line {line}: this is a CSV table (`{}`), not a TOML file: {GIVE_TOML}; a measurement CSV is the DATA of \
             `calibrate`, `diagnose` or `validate`",
            shown_cell(first)
        ));
    }
    let (line, first) = first_content_line(text)?;
    if first.starts_with('<') {
        let urdf = text.contains("<robot");
        return Some(if urdf {
            format!(
                "line {line}: this is a URDF (XML), not a TOML file: a robot description TOML points at it with \
                 `[urdf]` `file = \"{}\"` (docs/formats.md, robot description); {GIVE_TOML}",
                shown_cell(
                    &path
                        .file_name()
                        .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
                )
            )
        } else {
            format!("line {line}: this is XML, not a TOML file: {GIVE_TOML}")
        });
    }
    first
        .starts_with('{')
        .then(|| format!("line {line}: this is JSON, not a TOML file: {GIVE_TOML}"))
}

/// Whether `text` is a CSV table rather than TOML: its first line that is neither blank nor a
/// `#` comment has a comma and neither a `=` nor a `[` at its start (a TOML key or table).
pub fn looks_like_csv(text: &str) -> bool {
    first_content_line(text).is_some_and(|(_, l)| l.contains(',') && !l.contains('=') && !l.starts_with('['))
}

/// The first line of `text` that is neither blank nor a `#` comment: its 1-based number and
/// its trimmed text.
fn first_content_line(text: &str) -> Option<(usize, &str)> {
    text.lines()
        .map(str::trim)
        .enumerate()
        .find(|(_, l)| !l.is_empty() && !l.starts_with('#'))
        .map(|(i, l)| (i + 1, l))
}

/// The first content line of `text` read from `path` when it is a CSV table (by its text, or
/// by a `.csv` name).
fn csv_first_line<'a>(text: &'a str, path: &Path) -> Option<(usize, &'a str)> {
    let named_csv = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    (named_csv || looks_like_csv(text)).then(|| first_content_line(text).unwrap_or((1, "")))
}

/// The first `nan` or `inf` of `table` (TOML allows them; no key of axiscal's files does):
/// its dotted key and value.
fn non_finite_in(table: &toml::Table, prefix: &str) -> Option<(String, f64)> {
    table.iter().find_map(|(k, v)| {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        non_finite_value(v, &key)
    })
}

/// [`non_finite_in`] for one value.
fn non_finite_value(value: &toml::Value, key: &str) -> Option<(String, f64)> {
    match value {
        toml::Value::Float(f) if !f.is_finite() => Some((key.to_string(), *f)),
        toml::Value::Array(items) => items
            .iter()
            .enumerate()
            .find_map(|(i, v)| non_finite_value(v, &format!("{key}[{i}]"))),
        toml::Value::Table(t) => non_finite_in(t, key),
        _ => None,
    }
}

/// The first list of `written` longer than the list at the same key of `read` (the value as
/// deserialised and written back): its dotted key and both lengths.
fn longer_list(written: &toml::Table, read: &toml::Table, prefix: &str) -> Option<(String, usize, usize)> {
    written.iter().find_map(|(k, w)| {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        longer_value(w, read.get(k)?, &key)
    })
}

/// [`longer_list`] for one value.
fn longer_value(written: &toml::Value, read: &toml::Value, key: &str) -> Option<(String, usize, usize)> {
    match (written, read) {
        (toml::Value::Array(w), toml::Value::Array(r)) if w.len() > r.len() => {
            Some((key.to_string(), w.len(), r.len()))
        }
        (toml::Value::Array(w), toml::Value::Array(r)) => w
            .iter()
            .zip(r)
            .enumerate()
            .find_map(|(i, (w, r))| longer_value(w, r, &format!("{key}[{i}]"))),
        (toml::Value::Table(w), toml::Value::Table(r)) => longer_list(w, r, key),
        _ => None,
    }
}

/// The line whose key (`a.b.c = ...`, `[a.b.c]`, `[[a.b]]`) has the most dotted parts, with
/// that count and the key: where a parser error without a position (its recursion limit)
/// comes from.
fn deepest_key(text: &str) -> Option<(usize, usize, String)> {
    let key_of = |line: &str| {
        let line = line.trim();
        let key = match line.strip_prefix('[') {
            Some(rest) => rest.trim_start_matches('[').split(']').next().unwrap_or(""),
            None => line.split('=').next().unwrap_or(""),
        };
        key.trim().to_owned()
    };
    text.lines()
        .enumerate()
        .map(|(i, line)| {
            let key = key_of(line);
            (i + 1, key.matches('.').count() + 1, key)
        })
        .max_by_key(|&(line, depth, _)| (depth, std::cmp::Reverse(line)))
}

/// `line L, column C: message (at `text of the line`)`, or the message alone without a span.
/// When `e` is an unknown key below a table header that the file reads as a top-level key
/// (moved to the top of `text`, the key is no longer refused): where the key belongs, in words.
/// TOML reads every key after `[table]` as that table's, so a top-level key written at the end
/// of a file is refused as an unknown key of its last table.
fn top_level_key_in_table<T: DeserializeOwned>(e: &toml::de::Error, text: &str) -> Option<String> {
    let key = e.message().strip_prefix("unknown field `")?.split('`').next()?;
    let start = text.floor_char_boundary(e.span()?.start.min(text.len()));
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[start..].find('\n').map_or(text.len(), |i| start + i + 1);
    let number = |at: usize| text[..at].matches('\n').count() + 1;
    let header_at = |at: usize| {
        text[at..]
            .lines()
            .next()
            .is_some_and(|l| l.trim_start().starts_with('['))
    };
    let starts = || {
        std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .filter(|&i| i < text.len())
    };
    let table = starts().rfind(|&i| i < line_start && header_at(i))?;
    let first = starts().find(|&i| header_at(i))?;
    let line = &text[line_start..line_end];
    let moved = format!(
        "{}\n{}{}",
        line.trim_end_matches(['\r', '\n']),
        &text[..line_start],
        &text[line_end..]
    );
    toml::from_str::<toml::Table>(&moved).ok()?;
    let still_unknown = toml::from_str::<T>(&moved)
        .err()
        .is_some_and(|e| e.message().starts_with(&format!("unknown field `{key}`")));
    (!still_unknown).then(|| {
        format!(
            "`{}` is a top-level key, and after the header `{}` (line {}) it is read as that table's: move it above the \
             first table header (line {})",
            shown_cell(key),
            shown_cell(text[table..].lines().next().unwrap_or("").trim()),
            number(table),
            number(first)
        )
    })
}

fn one_line_message(e: &toml::de::Error, text: &str) -> String {
    let message = e
        .message()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ");
    let mut message = shown_message(&message);
    if message.ends_with("value was too large") {
        message.push_str(": a TOML file holds whole numbers up to 9223372036854775807 (64-bit signed)");
    }
    let Some(span) = e.span() else {
        return match deepest_key(text) {
            Some((line, depth, key)) if message.contains("recursion") => format!(
                "line {line}: key `{}` is nested {depth} levels deep: {message}; axiscal's files nest their keys a \
                 few levels at most (docs/formats.md): write the documented keys",
                shown_cell(&key)
            ),
            _ => message,
        };
    };
    let start = span.start.min(text.len());
    let before = &text[..text.floor_char_boundary(start)];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    let source = shown_cell(text[line_start..].lines().next().unwrap_or("").trim());
    format!("line {line}, column {column}: {message} (at `{source}`)")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, serde::Deserialize, serde::Serialize)]
    #[serde(deny_unknown_fields)]
    struct Small {
        mass_kg: f64,
    }

    #[derive(Debug, serde::Deserialize, serde::Serialize)]
    #[serde(deny_unknown_fields)]
    struct Nested {
        name: String,
        rate: Option<f64>,
        table: Small,
    }

    #[test]
    fn a_top_level_key_written_below_a_table_is_said_to_belong_above_it() {
        let path = Path::new("s.toml");
        let text = "name = \"a\"\n\n[table]\nmass_kg = 1.0\nrate = 0.5\n";
        let message = parse::<Nested>(text, path).unwrap_err().to_string();
        assert!(
            message.contains(
                "`rate` is a top-level key, and after the header `[table]` (line 3) it is read as that table's: move it \
                 above the first table header (line 3)"
            ),
            "{message}"
        );
        assert!(message.contains("line 5, column 1: unknown field `rate`"), "{message}");
        // A key unknown anywhere gets the parser's message alone.
        let message = parse::<Nested>("name = \"a\"\n[table]\nmass_kg = 1.0\nmas_kg = 2.0\n", path)
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("unknown field `mas_kg`") && !message.contains("top-level"),
            "{message}"
        );
        // Above the table it is read.
        let read = parse::<Nested>("name = \"a\"\nrate = 0.5\n[table]\nmass_kg = 1.0\n", path).unwrap();
        assert_eq!(read.rate, Some(0.5));
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

    /// A whole number a TOML file cannot hold, or a type serde names in Rust, is said as what
    /// to write.
    #[test]
    fn numbers_out_of_range_say_the_range() {
        #[derive(Debug, serde::Deserialize, serde::Serialize)]
        struct Seeded {
            seed: u64,
        }
        let e = parse::<Seeded>("seed = 18446744073709551615\n", Path::new("s.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("whole numbers up to 9223372036854775807"), "{e}");
        let e = parse::<Seeded>("seed = -1\n", Path::new("s.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("expected a whole number from 0 to 18446744073709551615"),
            "{e}"
        );
    }

    #[test]
    fn a_plan_sheet_is_a_csv_and_a_plan_file_is_not() {
        assert!(looks_like_csv("# axiscal plan\npoint,pose,experiment\n1,1,axis6\n"));
        assert!(!looks_like_csv("# a plan\nreference = [0, 0]\n[[sweeps]]\njoint = 1\n"));
        assert!(!looks_like_csv("[[sweeps]]\njoint = 1\nspan = 40.0\n"));
        assert!(!looks_like_csv(""));
    }

    /// A CSV given for TOML is said to be one, with its first line, not the parser's message.
    #[test]
    fn a_csv_is_refused_as_a_csv() {
        let e = parse::<Small>(
            "# axiscal\nexperiment,moved_joint,step\naxis1,1,0\n",
            Path::new("g.txt"),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("g.txt: line 2: this is a CSV table (`experiment,moved_joint,step`)"),
            "{e}"
        );
    }

    #[derive(Debug, serde::Deserialize, serde::Serialize)]
    #[serde(deny_unknown_fields)]
    struct Pair {
        limits: [f64; 2],
        nested: Vec<Small>,
    }

    /// A `nan` or `inf` anywhere is an error naming its key, in a list or a table of a list.
    #[test]
    fn a_non_finite_number_is_an_error_naming_its_key() {
        let e = parse::<Pair>("limits = [1.0, inf]\nnested = []\n", Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("key `limits[1]`: inf"), "{e}");
        let e = parse::<Pair>("limits = [1.0, 2.0]\n[[nested]]\nmass_kg = nan\n", Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("p.toml: key `nested[0].mass_kg`: NaN"), "{e}");
    }

    /// A list longer than its key holds is an error naming the key, nested lists too; the
    /// right lengths parse.
    #[test]
    fn a_list_longer_than_its_key_is_an_error() {
        let ok = "limits = [1.0, 2.0]\nnested = [{ mass_kg = 1.0 }]\n";
        assert!(parse::<Pair>(ok, Path::new("p.toml")).is_ok());
        let e = parse::<Pair>("limits = [1.0, 2.0, 3.0]\nnested = []\n", Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("key `limits`: 3 values, but it holds 2"), "{e}");
    }
}
