//! `make test` builds its tests in `make run`'s profile with `make run`'s features, so that they
//! link the libraries `make run` compiled. That holds only while the dev-dependencies ask for no
//! feature of a normal dependency that the normal build does not: one more feature on a crate
//! deep in the tree (rustix through tempfile, approx's `default`) gives it and everything above
//! it a second compilation, which doubled the build of `make test`.

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;

/// Each package of `cargo tree` (with the recorder's feature) and the feature sets it is built
/// with; `dev` says whether the dev-dependencies are resolved too.
fn feature_sets(dev: bool) -> BTreeMap<String, BTreeSet<String>> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let mut command = Command::new(cargo);
    command
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["tree", "--offline", "--locked", "--features", "viz"])
        .args(["--prefix", "none", "--format", "{p} [{f}]"]);
    if !dev {
        command.args(["--edges", "no-dev"]);
    }
    let out = command.output().expect("cargo runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "cargo tree failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    parse_tree(&stdout)
}

/// `name vX.Y.Z [f1,f2]` lines (a ` (*)` or ` (proc-macro)` after them ignored) as package ->
/// the feature lists it appears with.
fn parse_tree(text: &str) -> BTreeMap<String, BTreeSet<String>> {
    let mut sets: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for line in text.lines() {
        let (Some(open), Some(close)) = (line.find(" ["), line.find(']')) else {
            continue;
        };
        let package = line[..open].trim().to_string();
        let features = line[open + 2..close].to_string();
        sets.entry(package).or_default().insert(features);
    }
    sets
}

/// The packages of the normal build whose features differ once the dev-dependencies are in.
fn changed_by_dev(
    normal: &BTreeMap<String, BTreeSet<String>>,
    with_dev: &BTreeMap<String, BTreeSet<String>>,
) -> Vec<String> {
    normal
        .iter()
        .filter(|(package, sets)| with_dev.get(*package) != Some(*sets))
        .map(|(package, sets)| format!("{package}: {sets:?} -> {:?}", with_dev.get(package)))
        .collect()
}

#[test]
fn the_dev_dependencies_change_no_feature_of_a_normal_dependency() {
    let normal = feature_sets(false);
    assert!(
        normal.keys().any(|package| package.starts_with("rerun v")),
        "the recorder is in the tree: {normal:?}"
    );
    let changed = changed_by_dev(&normal, &feature_sets(true));
    assert!(changed.is_empty(), "{}", changed.join("\n"));
}

#[test]
fn the_check_sees_a_feature_the_dev_dependencies_add() {
    let normal = parse_tree("rustix v1.1.6 [alloc,std]\napprox v0.5.1 [std] (*)\n");
    let with_dev =
        parse_tree("rustix v1.1.6 [alloc,fs,std]\napprox v0.5.1 [std]\nproptest v1.12.0 [std] (proc-macro)\n");
    let changed = changed_by_dev(&normal, &with_dev);
    assert_eq!(changed.len(), 1, "{changed:?}");
    assert!(changed[0].starts_with("rustix v1.1.6"), "{changed:?}");
}
