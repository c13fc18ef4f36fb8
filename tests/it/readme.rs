//! The README's tour and the own-robot guide (`docs/own-robot.md`), run as written: every
//! `$ ...` command of their `text` blocks, in order, in one fresh folder per document (with
//! `axiscal` the binary under test), its output compared with the lines the document shows.
//! Declared elisions: a line `...` stands for any number of lines; a line ending in `...` for
//! any line starting with what precedes it. A block after "Save as `NAME`" (any language but
//! `text`) is written to NAME first. Blocks with `--record` need the recorder (feature `viz`):
//! CI records and checks them in its own step.

use std::path::Path;

/// One command of a block (continuation lines and heredoc joined) and the output shown.
struct Step {
    command: String,
    shown: Vec<String>,
}

/// The blocks of `readme` in order: a file to write (`Save as` + a block) or commands to run.
enum Block {
    Save { name: String, text: String },
    Run(Vec<Step>),
}

/// The fenced blocks of `readme` (language, lines) with the text before each.
fn fenced(readme: &str) -> Vec<(String, Vec<String>, String)> {
    let mut out = Vec::new();
    let mut before = String::new();
    let mut lines = readme.lines();
    while let Some(line) = lines.next() {
        if let Some(lang) = line.strip_prefix("```") {
            let body: Vec<String> = lines
                .by_ref()
                .take_while(|l| !l.starts_with("```"))
                .map(str::to_owned)
                .collect();
            out.push((lang.to_owned(), body, std::mem::take(&mut before)));
        } else {
            before.push_str(line);
            before.push('\n');
        }
    }
    out
}

/// The steps of a `text` block: `$ ` lines with their continuations and heredocs, and the
/// output lines after each.
fn steps(body: &[String]) -> Vec<Step> {
    let mut steps: Vec<Step> = Vec::new();
    let mut i = 0;
    while i < body.len() {
        let line = &body[i];
        i += 1;
        let Some(first) = line.strip_prefix("$ ") else {
            if let Some(s) = steps.last_mut() {
                s.shown.push(line.clone());
            }
            continue;
        };
        let mut command = first.to_owned();
        while command.ends_with('\\') && i < body.len() {
            command.push('\n');
            command.push_str(&body[i]);
            i += 1;
        }
        if let Some(marker) = command.split("<<'").nth(1).and_then(|r| r.split('\'').next()) {
            let marker = marker.to_owned();
            while i < body.len() {
                command.push('\n');
                command.push_str(&body[i]);
                i += 1;
                if body[i - 1] == marker {
                    break;
                }
            }
        }
        steps.push(Step {
            command,
            shown: Vec::new(),
        });
    }
    steps
}

/// The tour's blocks: `text` blocks with commands, and the files they read.
fn blocks(readme: &str) -> Vec<Block> {
    let mut out = Vec::new();
    for (lang, body, before) in fenced(readme) {
        match lang.as_str() {
            "text" if body.iter().any(|l| l.starts_with("$ ")) => out.push(Block::Run(steps(&body))),
            "text" => {}
            _ => {
                if let Some(name) = before
                    .rsplit("Save as `")
                    .next()
                    .filter(|_| before.contains("Save as `"))
                {
                    out.push(Block::Save {
                        name: name.split('`').next().unwrap().to_owned(),
                        text: body.join("\n") + "\n",
                    });
                }
            }
        }
    }
    out
}

/// Whether `actual` shows `shown` with its elisions (module docs); the first mismatch.
fn matches(shown: &[String], actual: &[&str]) -> Result<(), String> {
    let (mut a, mut skipping) = (0, false);
    for s in shown {
        if s.trim() == "..." {
            skipping = true;
            continue;
        }
        let fits = |line: &str| match s.strip_suffix("...") {
            Some(prefix) => line.starts_with(prefix),
            None => line == s,
        };
        loop {
            match actual.get(a) {
                Some(line) if fits(line) => break,
                Some(_) if skipping => a += 1,
                Some(line) => return Err(format!("shown: {s}\nactual: {line}")),
                None => return Err(format!("shown: {s}\nactual: (no more output)")),
            }
        }
        a += 1;
        skipping = false;
    }
    match actual.get(a) {
        Some(line) if !skipping => Err(format!("shown: (no more output)\nactual: {line}")),
        _ => Ok(()),
    }
}

/// Runs `steps` in one shell in `dir`, `axiscal` on the PATH; each step's output (stdout and
/// stderr) separately.
fn run(dir: &Path, steps: &[Step]) -> Vec<String> {
    const SEPARATOR: &str = "@@readme-step@@";
    let script: String = steps
        .iter()
        .map(|s| format!("echo '{SEPARATOR}'\n(exit $status); {}\nstatus=$?\n", s.command))
        .collect();
    // The binary under test as `axiscal` on the PATH: the optimised one `make test` names
    // (AXISCAL_TEST_BIN, whatever its file name), else cargo's.
    let bin = std::env::var_os("AXISCAL_TEST_BIN")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| env!("CARGO_BIN_EXE_axiscal").into());
    let on_path = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(std::fs::canonicalize(&bin).unwrap(), on_path.path().join("axiscal")).unwrap();
    let path = format!(
        "{}:{}",
        on_path.path().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let out = std::process::Command::new("bash")
        .arg("-c")
        .arg(format!("exec 2>&1\nstatus=0\n{script}"))
        .current_dir(dir)
        .env("PATH", path)
        .output()
        .expect("bash runs");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    text.split(&format!("{SEPARATOR}\n"))
        .skip(1)
        .map(str::to_owned)
        .collect()
}

/// Runs the document `name` (relative to the clone) as the module docs say; the commands run.
fn run_document(name: &str) -> usize {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(name)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    let mut commands = 0;
    for block in blocks(&readme) {
        match block {
            Block::Save { name, text } => std::fs::write(dir.path().join(name), text).unwrap(),
            Block::Run(steps) if steps.iter().any(|s| s.command.contains("--record")) => {}
            Block::Run(steps) => {
                let outputs = run(dir.path(), &steps);
                assert_eq!(outputs.len(), steps.len(), "{outputs:?}");
                for (step, output) in steps.iter().zip(&outputs) {
                    commands += 1;
                    let actual: Vec<&str> = output.lines().collect();
                    if let Err(e) = matches(&step.shown, &actual) {
                        failures.push(format!("{name}: $ {}\n{e}\n--- whole output:\n{output}", step.command));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    commands
}

#[test]
fn the_tour_prints_what_the_readme_shows() {
    let commands = run_document("README.md");
    assert!(commands >= 10, "only {commands} commands found in the README's tour");
}

/// A three-joint DH arm, a URDF arm and a SCARA, each from its description through simulate,
/// calibrate, validate, diagnose and plan, by the guide's text alone.
#[test]
fn the_own_robot_guide_runs_as_written() {
    let commands = run_document("docs/own-robot.md");
    assert!(commands >= 15, "only {commands} commands found in docs/own-robot.md");
    for (robot, steps) in [("rrr3", 6), ("arm4", 6), ("scara", 5)] {
        let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/own-robot.md")).unwrap();
        let shown = text
            .lines()
            .filter(|l| l.starts_with("$ axiscal") && l.contains(&format!("{robot}.")))
            .count();
        assert_eq!(
            shown, steps,
            "{robot}: the guide runs describe/simulate/calibrate/validate/diagnose/plan"
        );
    }
}

/// The matcher's elisions, on made-up outputs.
#[test]
fn elisions_match_what_they_declare() {
    let shown = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert!(matches(&shown(&["a", "b"]), &["a", "b"]).is_ok());
    assert!(
        matches(&shown(&["a"]), &["a", "b"]).is_err(),
        "an unshown trailing line"
    );
    assert!(matches(&shown(&["a", "..."]), &["a", "b", "c"]).is_ok());
    assert!(matches(&shown(&["a", "...", "c"]), &["a", "b", "x", "c"]).is_ok());
    assert!(
        matches(&shown(&["a", "c"]), &["a", "b", "c"]).is_err(),
        "an undeclared gap"
    );
    assert!(matches(&shown(&["a b..."]), &["a b c d"]).is_ok());
    assert!(matches(&shown(&["a x..."]), &["a b c d"]).is_err());
    assert!(matches(&shown(&["a", "b"]), &["a"]).is_err(), "a missing line");
}
