//! Every key of every TOML input file is documented: the keys the readers accept (the JSON
//! Schema schemars derives from the deserialised types, serde's renames and flattening
//! included) each appear, quoted as a key, in the file's section of `docs/formats.md`.

use axiscal::harness::scenario::ScenarioFile;
use axiscal::plan::CalibrationPlan;
use axiscal::robot::{RobotDescription, RobotModel};
use axiscal::sim::{Effects, PerturbationSpec};
use schemars::JsonSchema;
use serde_json::Value;
use std::collections::BTreeSet;
use std::path::Path;

/// The property names of a schema, through `$ref`s, combinators, items and maps.
fn keys(v: &Value, root: &Value, seen: &mut BTreeSet<String>, out: &mut BTreeSet<String>) {
    match v {
        Value::Object(o) => {
            if let Some(Value::String(r)) = o.get("$ref")
                && seen.insert(r.clone())
                && let Some(def) = root.get("$defs").and_then(|d| d.get(r.rsplit('/').next().unwrap()))
            {
                keys(def, root, seen, out);
            }
            if let Some(Value::Object(p)) = o.get("properties") {
                for (k, sub) in p {
                    out.insert(k.clone());
                    keys(sub, root, seen, out);
                }
            }
            for (k, sub) in o {
                if k != "properties" && k != "$defs" {
                    keys(sub, root, seen, out);
                }
            }
        }
        Value::Array(a) => a.iter().for_each(|x| keys(x, root, seen, out)),
        _ => {}
    }
}

/// The keys `T`'s reader accepts.
fn accepted<T: JsonSchema>() -> BTreeSet<String> {
    let generator = schemars::generate::SchemaSettings::draft2020_12()
        .for_deserialize()
        .into_generator();
    let schema = generator.into_root_schema_for::<T>().to_value();
    let mut out = BTreeSet::new();
    keys(&schema, &schema, &mut BTreeSet::new(), &mut out);
    out
}

/// The text of `docs/formats.md` from the anchor `from` to the next anchor of `until`.
fn section(doc: &str, from: &str, until: &str) -> String {
    let start = doc
        .find(&format!("<a id=\"{from}\"></a>"))
        .unwrap_or_else(|| panic!("no anchor {from}"));
    let end = doc[start..]
        .find(&format!("<a id=\"{until}\"></a>"))
        .unwrap_or_else(|| panic!("no anchor {until}"));
    doc[start..start + end].to_owned()
}

/// Whether `text` names `key` as a key: quoted or in a table's name (after a backtick, `[` or
/// `.`; before a backtick, `]`, `[`, `.` or `=`), or in an inline table's list of keys (after
/// `{ ` or `, `; before `,`, ` }` or ` =`).
fn documents(text: &str, key: &str) -> bool {
    text.match_indices(key).any(|(i, _)| {
        let (head, next) = (&text[..i], &text[i + key.len()..]);
        let quoted = head.ends_with(['`', '[', '.']) && next.starts_with(['`', ']', '[', '.', '=', ' ']);
        let quoted = quoted && (!next.starts_with(' ') || next.starts_with(" ="));
        let listed = (head.ends_with("{ ") || head.ends_with(", "))
            && (next.starts_with(',') || next.starts_with(" }") || next.starts_with(" ="));
        quoted || listed
    })
}

/// A file's name, the keys its reader accepts and its sections of `docs/formats.md` (from
/// anchor, to anchor).
type InputFile<'a> = (&'a str, BTreeSet<String>, &'a [(&'a str, &'a str)]);

#[test]
fn every_input_key_is_in_the_formats_doc() {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/formats.md")).unwrap();
    // Each file's sections: (from anchor, to anchor). A scenario holds an effects file's
    // tables and may hold a plan's sweeps.
    let files: [InputFile; 6] = [
        (
            "robot description",
            accepted::<RobotDescription>(),
            &[("robot-description", "robot-model")],
        ),
        (
            "robot model",
            accepted::<RobotModel>(),
            &[("robot-model", "effects-file")],
        ),
        (
            "effects file",
            accepted::<Effects>(),
            &[("effects-file", "scenario-file")],
        ),
        (
            "scenario file",
            accepted::<ScenarioFile>(),
            &[
                ("scenario-file", "calibration-json"),
                ("effects-file", "scenario-file"),
                ("plan-file", "point-export"),
            ],
        ),
        (
            "perturbation",
            accepted::<PerturbationSpec>(),
            &[("perturbation", "sweep")],
        ),
        (
            "plan file",
            accepted::<CalibrationPlan>(),
            &[("plan-file", "point-export")],
        ),
    ];
    let mut missing = Vec::new();
    for (file, keys, sections) in &files {
        assert!(keys.len() >= 3, "{file}: only {keys:?} found in its schema");
        let text: String = sections
            .iter()
            .map(|(from, until)| section(&doc, from, until))
            .collect();
        let from = sections[0].0;
        missing.extend(
            keys.iter()
                .filter(|k| !documents(&text, k))
                .map(|k| format!("{file}: `{k}` (docs/formats.md#{from})")),
        );
    }
    assert!(
        missing.is_empty(),
        "keys read but not documented:\n{}",
        missing.join("\n")
    );
}

/// The matcher: a key quoted, in a table's name or an assignment counts; a word in prose or
/// inside another key does not.
#[test]
fn a_key_counts_only_where_it_is_named_as_one() {
    assert!(documents("| `span` | deg |", "span"));
    assert!(documents("`[[sweeps]]` in run order", "sweeps"));
    assert!(documents("`[effects.compliance]`", "compliance"));
    assert!(documents("`held_jitter = [min, max]`", "held_jitter"));
    assert!(documents("`{ d_mm, theta_deg, a_mm, alpha_deg }`", "a_mm"));
    assert!(documents("`sag[].joint`", "sag"));
    assert!(!documents("`span of a sweep`", "span"));
    assert!(!documents("the span of a sweep", "span"));
    assert!(!documents("`second_target`", "target"));
}
