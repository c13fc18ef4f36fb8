//! The layout's rules, checked on the source itself (ARCHITECTURE.md):
//! - the truth boundary: the calibrator, the compensation and the diagnosis (and the maths
//!   they stand on) never reach the simulated robot (`sim`) or the harnesses that know its
//!   answers (`harness`), so no result can leak from the answer key;
//! - the maths never reach the viewer (`viz`);
//! - no function in `src/` is longer than 100 lines.
//!
//! Test modules (`#[cfg(test)] mod tests`) may use the simulator to make data: only the code
//! that ships is checked.

use std::path::{Path, PathBuf};

/// Modules that must never see the simulated truth, and what they may not name.
const BOUNDARY: &[(&str, &[&str])] = &[
    ("calibration", &["crate::sim", "crate::harness", "crate::viz"]),
    ("compensation", &["crate::sim", "crate::harness", "crate::viz"]),
    ("diagnosis", &["crate::sim", "crate::harness", "crate::viz"]),
    ("kinematics", &["crate::sim", "crate::harness", "crate::viz"]),
    ("measurement", &["crate::sim", "crate::harness", "crate::viz"]),
    ("numerics", &["crate::sim", "crate::harness", "crate::viz"]),
    ("physics", &["crate::sim", "crate::harness", "crate::viz"]),
    ("plan", &["crate::sim", "crate::harness", "crate::viz"]),
    ("robot", &["crate::sim", "crate::harness", "crate::viz"]),
];

/// Longest function allowed in `src/` \[lines, from the `fn` line to its closing brace\].
const MAX_FUNCTION_LINES: usize = 100;

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("reading {}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The lines of `path` that ship: a file that is itself a test module (`tests.rs`) has none;
/// otherwise every line but the file's test module (`#[cfg(test)]` at the start of a line, which
/// must open a `mod tests`, and that module's body).
fn shipped_lines(path: &Path) -> Vec<(usize, String)> {
    if path.file_name().is_some_and(|n| n == "tests.rs") {
        return vec![];
    }
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        if !lines[i].starts_with("#[cfg(test)]") {
            out.push((i + 1, lines[i].to_string()));
            i += 1;
            continue;
        }
        let next = lines.get(i + 1).map_or("", |l| l.trim_start());
        assert!(
            next.starts_with("mod tests") || next.starts_with("pub(crate) mod tests"),
            "{}:{}: `#[cfg(test)]` must open the file's `mod tests`",
            path.display(),
            i + 1
        );
        // Skip the module: a declaration, or a body up to its closing brace.
        i += 1;
        let mut depth = 0i64;
        while i < lines.len() {
            let code = code_of(lines[i]);
            depth += code.matches('{').count() as i64 - code.matches('}').count() as i64;
            i += 1;
            if depth == 0 && (code.contains('}') || code.trim_end().ends_with(';')) {
                break;
            }
        }
    }
    out
}

/// Code without its comments (`//` to the end of a line; doc comments included) and string
/// literals, so that a path named in prose or in a message does not count.
fn code_of(line: &str) -> String {
    let mut out = String::new();
    let mut chars = line.chars().peekable();
    let mut in_string = false;
    while let Some(c) = chars.next() {
        match (in_string, c) {
            (false, '/') if chars.peek() == Some(&'/') => break,
            (false, '"') => in_string = true,
            (true, '\\') => {
                chars.next();
            }
            (true, '"') => in_string = false,
            (false, _) => out.push(c),
            (true, _) => {}
        }
    }
    out
}

#[test]
fn the_calibrator_compensation_and_diagnosis_never_reach_the_simulated_truth() {
    let mut violations = Vec::new();
    for (module, forbidden) in BOUNDARY {
        let mut files = Vec::new();
        rust_files(&src().join(module), &mut files);
        assert!(!files.is_empty(), "no source files under src/{module}");
        for f in files {
            for (n, line) in shipped_lines(&f) {
                let code = code_of(&line);
                // `use crate::{sim, ..}` as well as `crate::sim::X`.
                let compact: String = code.chars().filter(|c| !c.is_whitespace()).collect();
                for path in *forbidden {
                    let leaf = path.trim_start_matches("crate::");
                    let grouped = format!("crate::{{{leaf},");
                    let grouped_last = format!(",{leaf}}}");
                    if compact.contains(path)
                        || compact.contains(&grouped)
                        || (compact.contains("crate::{") && compact.contains(&grouped_last))
                    {
                        violations.push(format!("{}:{n}: {} names {path}", f.display(), line.trim()));
                    }
                }
            }
        }
    }
    assert!(
        violations.is_empty(),
        "truth boundary crossed:\n{}",
        violations.join("\n")
    );
}

/// Lengths of the functions in `lines` (from the line of `fn` to the line of the brace that
/// closes its body), with their names and first lines; braces in comments and strings are
/// ignored.
fn function_lengths(lines: &[(usize, String)]) -> Vec<(usize, String, usize)> {
    let mut out = Vec::new();
    let code: Vec<String> = lines.iter().map(|(_, l)| code_of(l)).collect();
    for (i, c) in code.iter().enumerate() {
        let words: Vec<&str> = c.split(|ch: char| !(ch.is_alphanumeric() || ch == '_')).collect();
        let Some(pos) = words.iter().position(|w| *w == "fn") else {
            continue;
        };
        let Some(name) = words[pos + 1..].iter().find(|w| !w.is_empty()) else {
            continue;
        };
        let (mut depth, mut opened) = (0i64, false);
        for (j, cj) in code.iter().enumerate().skip(i) {
            for ch in cj.chars() {
                match ch {
                    '{' => {
                        depth += 1;
                        opened = true;
                    }
                    '}' => depth -= 1,
                    ';' if !opened && depth == 0 => break,
                    _ => {}
                }
            }
            if !opened && cj.contains(';') && depth == 0 {
                break;
            }
            if opened && depth == 0 {
                out.push((lines[j].0 - lines[i].0 + 1, name.to_string(), lines[i].0));
                break;
            }
        }
    }
    out
}

#[test]
fn no_function_is_longer_than_a_hundred_lines() {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let mut long = Vec::new();
    for f in files {
        let lines = shipped_lines(&f);
        for (len, name, line) in function_lengths(&lines) {
            if len > MAX_FUNCTION_LINES {
                long.push(format!("{}:{line}: fn {name} has {len} lines", f.display()));
            }
        }
    }
    assert!(
        long.is_empty(),
        "functions over {MAX_FUNCTION_LINES} lines (split them along their own comments):\n{}",
        long.join("\n")
    );
}

#[test]
fn the_length_check_measures_what_it_should() {
    let text = "fn short() {\n    let a = \"}\"; // }\n}\nfn decl();\nfn long() {\n    if x {\n    }\n}\n";
    let lines: Vec<(usize, String)> = text.lines().enumerate().map(|(i, l)| (i + 1, l.to_string())).collect();
    let found = function_lengths(&lines);
    assert_eq!(found, vec![(3, "short".into(), 1), (4, "long".into(), 5)]);
    assert_eq!(code_of("let p = \"crate::sim\"; // crate::sim"), "let p = ; ");
}
