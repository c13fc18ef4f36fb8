//! The layout's rules, checked on the source itself (ARCHITECTURE.md):
//! - the truth boundary: the calibrator, the compensation and the diagnosis (and the maths
//!   they stand on) never reach the simulated robot (`sim`) or the harnesses that know its
//!   answers (`harness`), so no result can leak from the answer key;
//! - the maths never reach the viewer (`viz`);
//! - no function in `src/` is longer than 100 lines;
//! - the calibration names neither the diagnosis nor the planner (they stand on it), and no two
//!   of its files import each other, directly or around a circle (`imports`);
//! - the planner names the calibration only in the file ARCHITECTURE.md says why of;
//! - every module is in ARCHITECTURE.md's layout.
//!
//! Test modules (`#[cfg(test)] mod tests`) may use the simulator to make data: only the code
//! that ships is checked.

mod imports;

use std::path::{Path, PathBuf};

/// Modules that must never see the simulated truth, and what they may not name.
const BOUNDARY: &[(&str, &[&str])] = &[
    (
        "calibration",
        &[
            "crate::sim",
            "crate::harness",
            "crate::viz",
            "crate::diagnosis",
            "crate::plan",
        ],
    ),
    ("compensation", &["crate::sim", "crate::harness", "crate::viz"]),
    ("diagnosis", &["crate::sim", "crate::harness", "crate::viz"]),
    ("kinematics", &["crate::sim", "crate::harness", "crate::viz"]),
    ("measurement", &["crate::sim", "crate::harness", "crate::viz"]),
    ("numerics", &["crate::sim", "crate::harness", "crate::viz"]),
    ("iso9283", &["crate::sim", "crate::harness", "crate::viz"]),
    ("certificate", &["crate::sim", "crate::harness", "crate::viz"]),
    ("physics", &["crate::sim", "crate::harness", "crate::viz"]),
    ("plan", &["crate::sim", "crate::harness", "crate::viz"]),
    ("robot", &["crate::sim", "crate::harness", "crate::viz"]),
];

/// Longest function allowed in `src/` \[lines, from the `fn` line to its closing brace\].
const MAX_FUNCTION_LINES: usize = 100;

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Every `*.rs` file of `src/`, relative to it.
fn src_files() -> Vec<PathBuf> {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    files
        .iter()
        .map(|f| f.strip_prefix(src()).expect("under src/").to_path_buf())
        .collect()
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
                for path in *forbidden {
                    if code_names(&code_of(&line), path) {
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

/// Whether the code `code` (no comments or strings) names the module `path` (`crate::sim`):
/// `crate::sim::X` as well as `use crate::{sim, ..}`.
fn code_names(code: &str, path: &str) -> bool {
    let compact: String = code.chars().filter(|c| !c.is_whitespace()).collect();
    let leaf = path.trim_start_matches("crate::");
    let grouped = format!("crate::{{{leaf},");
    let grouped_last = format!(",{leaf}}}");
    compact.contains(path)
        || compact.contains(&grouped)
        || (compact.contains("crate::{") && compact.contains(&grouped_last))
}

/// The files of `src/plan/` whose shipped code names `crate::calibration`, by name.
fn plan_files_naming_the_calibration() -> Vec<String> {
    let mut files = Vec::new();
    rust_files(&src().join("plan"), &mut files);
    let mut naming: Vec<String> = files
        .iter()
        .filter(|f| {
            shipped_lines(f)
                .iter()
                .any(|(_, line)| code_names(&code_of(line), "crate::calibration"))
        })
        .map(|f| f.strip_prefix(src()).unwrap_or(f).display().to_string())
        .collect();
    naming.sort();
    naming
}

#[test]
fn the_planner_reaches_the_calibration_only_where_the_architecture_says_why() {
    let architecture = std::fs::read_to_string(src().join("../ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let unexplained: Vec<String> = plan_files_naming_the_calibration()
        .into_iter()
        .filter(|f| {
            !architecture.contains(&format!(
                "One arrow goes from `plan/` up to `calibration/`, on purpose: `{f}`"
            ))
        })
        .collect();
    assert!(
        unexplained.is_empty(),
        "plan/ names calibration/ in files ARCHITECTURE.md does not explain: {unexplained:?}"
    );
}

#[test]
fn the_naming_check_sees_a_path_a_group_and_not_a_neighbour() {
    assert!(code_names(
        "use crate::calibration::procedure::calibrate;",
        "crate::calibration"
    ));
    assert!(code_names("use crate::{calibration, robot};", "crate::calibration"));
    assert!(code_names("use crate::{robot, calibration};", "crate::calibration"));
    assert!(!code_names("use crate::robot::Controller;", "crate::calibration"));
    assert!(!code_names(&code_of("// see crate::calibration"), "crate::calibration"));
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

/// The lines of the ```` ```text ```` block that follows the `## Layout` heading of
/// ARCHITECTURE.md.
fn layout_block() -> Vec<String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("ARCHITECTURE.md");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
    let mut lines = text
        .lines()
        .skip_while(|l| !(l.starts_with('#') && l.to_lowercase().contains("layout")))
        .skip_while(|l| !l.starts_with("```text"))
        .skip(1);
    let block: Vec<String> = lines
        .by_ref()
        .take_while(|l| !l.starts_with("```"))
        .map(String::from)
        .collect();
    assert!(
        !block.is_empty(),
        "no ```text block under a layout heading in ARCHITECTURE.md"
    );
    block
}

/// One top-level entry of the layout's `src/` part: the names in its first column (`cli/` and
/// `main.rs` for `  cli/ + main.rs   ...`), the rest of its text (`described`, continuation
/// lines included) and the two together (`text`).
struct LayoutEntry {
    heads: Vec<String>,
    described: String,
    text: String,
}

/// The entries of the `src/` part of the layout block: from the line `src/` to the next line
/// that is not indented; an entry starts at a line indented by exactly two spaces and runs
/// until the next such line. Its first column ends at the first run of two spaces.
fn layout_entries(block: &[String]) -> Vec<LayoutEntry> {
    let mut entries: Vec<LayoutEntry> = Vec::new();
    let src_part = block
        .iter()
        .skip_while(|l| l.trim_end() != "src/")
        .skip(1)
        .take_while(|l| l.starts_with(' ') || l.trim().is_empty());
    for line in src_part {
        let body = line.strip_prefix("  ").unwrap_or(line);
        if body.starts_with(' ') || body.trim().is_empty() {
            if let Some(last) = entries.last_mut() {
                for s in [&mut last.described, &mut last.text] {
                    s.push('\n');
                    s.push_str(line);
                }
            }
            continue;
        }
        let (head, described) = body.split_once("  ").unwrap_or((body, ""));
        let heads = head
            .split_whitespace()
            .filter(|w| *w != "+")
            .map(String::from)
            .collect();
        entries.push(LayoutEntry {
            heads,
            described: described.to_string(),
            text: body.to_string(),
        });
    }
    entries
}

/// Words of `text`: runs of letters, digits and `_` (so `chain.rs` and `chain/` give `chain`).
fn words(text: &str) -> Vec<&str> {
    text.split(|c: char| !(c.is_alphanumeric() || c == '_'))
        .filter(|w| !w.is_empty())
        .collect()
}

/// The module a file of `src/` defines, if the layout must list it: `a/b/mod.rs` defines the
/// folder `a/b`; test modules (`tests.rs`) and the crate roots (`main.rs`, `lib.rs`) are left
/// out.
fn listed_module(file: &Path) -> Option<&Path> {
    let name = file.file_name()?.to_str()?;
    if name == "tests.rs" || file == Path::new("main.rs") || file == Path::new("lib.rs") {
        return None;
    }
    Some(if name == "mod.rs" { file.parent()? } else { file })
}

/// What is wrong between the layout `block` and the source `files` (paths relative to `src/`):
/// the modules it leaves out and the names it gives that do not exist. See
/// [`every_module_is_in_the_architecture_map`] for the rule.
fn layout_problems(block: &[String], files: &[PathBuf]) -> Vec<String> {
    let entries = layout_entries(block);
    let mut problems = Vec::new();
    for file in files {
        let Some(module) = listed_module(file) else { continue };
        let first = module.iter().next().and_then(|p| p.to_str()).unwrap_or_default();
        let top = if module == file.as_path() && module.iter().count() == 1 {
            first.to_string()
        } else {
            format!("{first}/")
        };
        let stem = module.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
        match entries.iter().find(|e| e.heads.contains(&top)) {
            None => problems.push(format!("src/{}: no layout entry `{top}`", file.display())),
            Some(e) if !words(&e.text).contains(&stem) => problems.push(format!(
                "src/{}: `{stem}` is not in the layout entry `{top}`",
                file.display()
            )),
            Some(_) => {}
        }
    }
    for e in &entries {
        for head in &e.heads {
            let exists = match head.strip_suffix('/') {
                Some(dir) => files.iter().any(|f| f.starts_with(dir) && f != Path::new(dir)),
                None => files.iter().any(|f| f == Path::new(head)),
            };
            if !exists {
                problems.push(format!("layout entry `{head}`: src/{head} does not exist"));
            }
        }
        let folder = e.heads.first().filter(|h| h.ends_with('/')).map_or("", |h| h.as_str());
        let under = |f: &&PathBuf| f.starts_with(folder);
        for token in e
            .described
            .split(|c: char| !(c.is_alphanumeric() || matches!(c, '_' | '.' | '/')))
        {
            let token = token.trim_end_matches('.');
            let file = token.rsplit('/').next().filter(|n| n.ends_with(".rs"));
            let dir = token.strip_suffix('/').filter(|d| !d.contains('/'));
            let exists = match (file, dir) {
                (Some(n), _) => files
                    .iter()
                    .filter(under)
                    .any(|f| f.file_name().is_some_and(|x| x == n)),
                (None, Some(d)) => files
                    .iter()
                    .filter(under)
                    .any(|f| f.parent().is_some_and(|p| p.iter().any(|c| c == d))),
                (None, None) => true,
            };
            if !exists {
                problems.push(format!(
                    "layout entry `{}`: `{token}` is not under src/{folder}",
                    e.heads.join(" + ")
                ));
            }
        }
    }
    problems
}

/// ARCHITECTURE.md's layout lists every module of `src/`, and names no file that is not there.
///
/// The rule, kept simple: a module is a `*.rs` file or a folder with a `mod.rs`, except
/// `main.rs`, `lib.rs` and test modules (`tests.rs`). Its *entry* is the layout's line for its
/// top-level folder `a/` (the file itself for a file directly in `src/`) plus that line's
/// continuation lines, up to the next line indented by two spaces. A module `src/a/b/c.rs`
/// (or `src/a/b/c/mod.rs`) is listed when `c` appears in the entry for `a/` as a word, alone
/// or as `c.rs` or `c/`. Every `name.rs` and `name/` the layout gives must exist as a file or
/// folder of that name somewhere under the entry's folder (under `src/` for a file's entry),
/// and every first-column name (`kinematics/`, `json_file.rs`) must exist in `src/`. Bare words
/// (`procedure/ (experiments, frames)`) count for the first rule only: they are not checked
/// against the files, so a module named in prose passes.
#[test]
fn every_module_is_in_the_architecture_map() {
    let files = src_files();
    let problems = layout_problems(&layout_block(), &files);
    assert!(
        problems.is_empty(),
        "ARCHITECTURE.md's layout and src/ disagree (add each module with a few words):\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_layout_check_sees_a_missing_module_and_a_missing_file() {
    let block: Vec<String> = [
        "src/",
        "  a/   one.rs, two/ (x.rs)",
        "       three, y/",
        "  b.rs   the b",
        "tests/   four.rs",
    ]
    .map(String::from)
    .to_vec();
    let files: Vec<PathBuf> = [
        "a/mod.rs",
        "a/one.rs",
        "a/two/mod.rs",
        "a/three.rs",
        "a/three/tests.rs",
        "b.rs",
        "lib.rs",
    ]
    .map(PathBuf::from)
    .to_vec();
    assert_eq!(
        layout_problems(&block, &files),
        vec![
            "layout entry `a/`: `x.rs` is not under src/a/".to_string(),
            "layout entry `a/`: `y/` is not under src/a/".to_string(),
        ]
    );
    let files: Vec<PathBuf> = ["a/one.rs", "a/four.rs", "c.rs", "b.rs", "a/x.rs", "a/y/mod.rs"]
        .map(PathBuf::from)
        .to_vec();
    assert_eq!(
        layout_problems(&block, &files),
        vec![
            "src/a/four.rs: `four` is not in the layout entry `a/`".to_string(),
            "src/c.rs: no layout entry `c.rs`".to_string(),
            "layout entry `a/`: `two/` is not under src/a/".to_string(),
        ]
    );
}

/// The files of `files` (paths relative to `src/`) that break the one module-file convention: a
/// module with children is a folder with a `mod.rs`, so a `x.rs` beside a folder `x/` is one.
fn beside_their_folder(files: &[PathBuf]) -> Vec<String> {
    files
        .iter()
        .filter(|f| f.extension().is_some_and(|x| x == "rs"))
        .filter(|f| {
            let folder = f.with_extension("");
            files.iter().any(|g| g.starts_with(&folder))
        })
        .map(|f| {
            format!(
                "src/{}: move it to src/{}/mod.rs",
                f.display(),
                f.with_extension("").display()
            )
        })
        .collect()
}

/// One module-file convention: a module with child modules is `x/mod.rs`, never `x.rs` beside
/// `x/`.
#[test]
fn a_module_with_children_is_its_folders_mod_rs() {
    let files = src_files();
    let found = beside_their_folder(&files);
    assert!(found.is_empty(), "{}", found.join("\n"));
}

#[test]
fn the_convention_check_sees_a_file_beside_its_folder() {
    let files: Vec<PathBuf> = ["a/mod.rs", "a/one.rs", "b.rs", "b/tests.rs", "c.rs", "cd/x.rs"]
        .map(PathBuf::from)
        .to_vec();
    assert_eq!(
        beside_their_folder(&files),
        vec!["src/b.rs: move it to src/b/mod.rs".to_string()]
    );
}

/// Every shipped file of `src/` as its module path and code (comments and strings removed).
fn crate_code() -> imports::Crate {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let code = files
        .iter()
        .map(|f| {
            let module = imports::module_path(f.strip_prefix(src()).expect("under src/"));
            let lines = shipped_lines(f);
            let code: Vec<String> = lines.iter().map(|(_, l)| code_of(l)).collect();
            (module, code.join("\n"))
        })
        .collect();
    imports::Crate::new(code)
}

fn cycle_text(cycles: &[Vec<imports::ModulePath>]) -> Vec<String> {
    cycles
        .iter()
        .map(|c| c.iter().map(|m| m.join("::")).collect::<Vec<_>>().join(" <-> "))
        .collect()
}

/// Arrows of `calibration/` allowed to close a circle, each with why (none: the pipeline
/// refactor left none). The check fails on any other circle, and on an arrow listed here that
/// is gone (so the list only shrinks).
const KNOWN_BACK_ARROWS: &[(&str, &str, &str)] = &[];

#[test]
fn no_two_files_of_the_calibration_import_each_other() {
    let mut arrows = crate_code().arrows("calibration");
    let path = |m: &str| m.split("::").map(String::from).collect::<Vec<_>>();
    let mut gone = Vec::new();
    for (from, to, why) in KNOWN_BACK_ARROWS {
        let removed = arrows.get_mut(&path(from)).is_some_and(|t| t.remove(&path(to)));
        if !removed {
            gone.push(format!("{from} -> {to} ({why})"));
        }
    }
    assert!(
        gone.is_empty(),
        "listed back arrows no longer in the source (remove them from KNOWN_BACK_ARROWS):\n{}",
        gone.join("\n")
    );
    let cycles = imports::cycles(&arrows);
    assert!(
        cycles.is_empty(),
        "files of src/calibration import each other (move what both need to a file both import):\n{}",
        cycle_text(&cycles).join("\n")
    );
}

#[test]
fn the_cycle_check_sees_a_circle_through_a_facade_and_not_a_facade_alone() {
    let code = |files: &[(&str, &str)]| {
        imports::Crate::new(
            files
                .iter()
                .map(|(path, code)| (imports::module_path(Path::new(path)), code.to_string()))
                .collect(),
        )
    };
    // `a/mod.rs` re-exports `x`'s item and defines `D`, which `x` imports back: a circle.
    let circle = code(&[
        ("lib.rs", "mod a;"),
        ("a/mod.rs", "mod x; mod y; pub use x::{X, Other as O}; pub struct D;"),
        ("a/x.rs", "use super::{D, y::{self}};\npub struct X; pub struct Other;"),
        ("a/y.rs", "use crate::a::O; fn f() { let _ = super::X; }"),
    ]);
    let arrows = circle.arrows("a");
    let names = |m: &[&str]| m.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert!(arrows[&names(&["a", "y"])].contains(&names(&["a", "x"])), "{arrows:?}");
    assert_eq!(
        cycle_text(&imports::cycles(&arrows)),
        vec!["a <-> a::x <-> a::y".to_string()]
    );
    // The same facade with `D` in a file of its own: arrows into the facade's re-exports only.
    let facade = code(&[
        ("lib.rs", "mod a;"),
        ("a/mod.rs", "mod d; mod x; pub use d::D; pub use x::X;"),
        (
            "a/d.rs",
            "pub struct D;\nstruct H;\nmod serde_form {\n    use super::H;\n}",
        ),
        ("a/x.rs", "use super::D;\npub struct X;"),
    ]);
    let arrows = facade.arrows("a");
    assert_eq!(arrows[&names(&["a", "x"])], [names(&["a", "d"])].into_iter().collect());
    assert!(imports::cycles(&arrows).is_empty(), "{arrows:?}");
}

/// Every test ignored "run by `make test-real`" is in that target's filter: a real-data test
/// outside it never runs (two did not, in CI, before this check).
#[test]
fn every_real_data_test_is_run_by_make_test_real() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let makefile = std::fs::read_to_string(root.join("Makefile")).expect("reading the Makefile");
    let filter = makefile
        .lines()
        .skip_while(|l| !l.starts_with("test-real:"))
        .skip(1)
        .take_while(|l| l.starts_with('\t'))
        .find(|l| l.contains("--ignored"))
        .expect("the test-real target's test command");
    let mut missing = Vec::new();
    let mut tests: Vec<_> = std::fs::read_dir(root.join("tests/it"))
        .expect("reading tests/it")
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .collect();
    tests.sort();
    for file in tests {
        let text = std::fs::read_to_string(&file).expect("reading a test file");
        let module = file.file_stem().expect("a file name").to_string_lossy().into_owned();
        if text.contains("(run by `make test-real`)\"]") && !filter.contains(&format!(" {module}::")) {
            missing.push(module);
        }
    }
    assert!(
        missing.is_empty(),
        "modules with tests ignored for `make test-real` that its filter does not name: {missing:?}"
    );
}
