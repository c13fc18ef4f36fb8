//! The files an input names inside it, which the command reads too: a robot description's
//! `[urdf] file`; a scenario's `robot`, `[truth] path` (with `kind = "file"`) and
//! `[sweep] plans`, and the URDF of the scenario's robot. [`super::output::Outputs::input`]
//! registers them as inputs, so that no output replaces a file the command reads only
//! through another one (docs/formats.md#errors-and-exit-codes).
//!
//! The keys and their resolution are those of the readers: a description's URDF is relative to
//! the description (`RobotDescription::convert_source`), a scenario's paths to the scenario
//! (`ResolvedScenario::resolve`). A file that is not a regular file, not TOML, or larger than
//! [`MAX_BYTES`] names nothing here (its reader reports what is wrong with it).

use std::path::{Path, PathBuf};

/// The largest file read for references: axiscal's TOML files are a few KiB; a measurement
/// CSV given as an input is not read twice.
const MAX_BYTES: u64 = 4 << 20;

/// How deep references are followed (scenario -> description -> URDF).
const MAX_DEPTH: usize = 3;

/// The files `path` (named by `what`, e.g. `--robot`) names, each with the chain that names
/// it (`` --robot r.toml: `urdf.file` ``), and those they name in turn.
pub fn referenced_files(what: &str, path: &Path) -> Vec<(String, PathBuf)> {
    let mut found = Vec::new();
    follow(what, path, 0, &mut found);
    found
}

fn follow(what: &str, path: &Path, depth: usize, found: &mut Vec<(String, PathBuf)>) {
    if depth >= MAX_DEPTH {
        return;
    }
    let Some(table) = toml_table(path) else { return };
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut named = Vec::new();
    if let Some(file) = table
        .get("urdf")
        .and_then(|u| u.get("file"))
        .and_then(toml::Value::as_str)
    {
        named.push(("urdf.file".to_owned(), dir.join(file)));
    }
    if table.contains_key("trials") || table.contains_key("measurement") || table.contains_key("thresholds") {
        named.extend(scenario_files(&table, dir));
    }
    for (key, file) in named {
        let label = format!("{what} {}: `{key}`", path.display());
        follow(&label, &file, depth + 1, found);
        found.push((label, file));
    }
}

/// The files a scenario table names (docs/formats.md#scenario-file), resolved against `dir`.
fn scenario_files(table: &toml::Table, dir: &Path) -> Vec<(String, PathBuf)> {
    let mut named = Vec::new();
    if let Some(robot) = table.get("robot").and_then(toml::Value::as_str) {
        named.push(("robot".to_owned(), dir.join(robot)));
    }
    let truth = table.get("truth");
    if truth.and_then(|t| t.get("kind")).and_then(toml::Value::as_str) == Some("file")
        && let Some(p) = truth.and_then(|t| t.get("path")).and_then(toml::Value::as_str)
    {
        named.push(("truth.path".to_owned(), dir.join(p)));
    }
    let plans = table
        .get("sweep")
        .and_then(|s| s.get("plans"))
        .and_then(toml::Value::as_array);
    for (i, p) in plans.into_iter().flatten().enumerate() {
        if let Some(p) = p.as_str() {
            named.push((format!("sweep.plans[{i}]"), dir.join(p)));
        }
    }
    named
}

/// `path` read as a TOML table, if it is a regular file of at most [`MAX_BYTES`] that parses.
fn toml_table(path: &Path) -> Option<toml::Table> {
    let meta = std::fs::metadata(path).ok()?;
    if !meta.is_file() || meta.len() > MAX_BYTES {
        return None;
    }
    let text = std::fs::read_to_string(path).ok()?;
    toml::from_str(&text).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scenario_names_its_robot_its_urdf_its_truth_and_its_plans() {
        let dir = std::env::temp_dir().join(format!("axiscal-referenced-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("r")).unwrap();
        std::fs::write(dir.join("r/d.toml"), "name = \"x\"\n[urdf]\nfile = \"u.urdf\"\n").unwrap();
        std::fs::write(
            dir.join("s.toml"),
            "trials = 1\nrobot = \"r/d.toml\"\n[truth]\nkind = \"file\"\npath = \"t.toml\"\n[sweep]\nplans = [\"p.toml\"]\n",
        )
        .unwrap();
        let found = referenced_files("SCENARIO", &dir.join("s.toml"));
        let files: Vec<_> = found
            .iter()
            .map(|(_, p)| p.strip_prefix(&dir).unwrap().to_owned())
            .collect();
        let expected = ["r/u.urdf", "r/d.toml", "t.toml", "p.toml"].map(PathBuf::from);
        assert_eq!(files, expected, "{found:?}");
        assert!(
            found[0].0.starts_with("SCENARIO ")
                && found[0].0.contains("s.toml: `robot` ")
                && found[0].0.ends_with("d.toml: `urdf.file`"),
            "{found:?}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
