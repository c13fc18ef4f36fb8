//! The JSON Schema of every JSON file axiscal writes (`docs/schemas/<name>.json`), generated
//! by schemars from the types the files are serialised from, for what the writer produces
//! (the serialisation contract). `tests/it/json_schemas.rs` checks that the committed files equal
//! these and that real outputs of each command validate against them.

use crate::calibration::procedure::Finding;
use crate::calibration::record::CalibrationRecord;
use crate::diagnosis::{AxesDiagnosis, Diagnosis, Validation};
use crate::harness::blind::{BlindScore, CaseKey, CaseResult};
use crate::harness::evaluation::{BudgetReport, FloorCheck, PaperReport};
use crate::harness::scenario::summary::Summary;
use crate::harness::studies::StudyReport;
use crate::json_file::Schema;
use schemars::JsonSchema;
use schemars::generate::SchemaSettings;
use serde_json::{Value, json};

/// `diagnosis.json` holds either mode's result.
#[derive(schemars::JsonSchema)]
#[serde(untagged)]
// Never built: it only describes the file's schema.
#[allow(dead_code, clippy::large_enum_variant)]
enum DiagnosisFile {
    /// With validation poses.
    Full(Diagnosis),
    /// Axis experiments only.
    AxesOnly(AxesDiagnosis),
}

/// The schema of `T` as the writer serialises it (draft 2020-12).
fn schema_of<T: JsonSchema>() -> Value {
    let generator = SchemaSettings::draft2020_12().for_serialize().into_generator();
    generator.into_root_schema_for::<T>().to_value()
}

/// Every `number` may also be `null`: NaN and infinities are written as `null`
/// (`docs/formats.md#units`).
fn numbers_nullable(v: &mut Value) {
    match v {
        Value::Object(o) => {
            match o.get_mut("type") {
                Some(t @ Value::String(_)) if t == "number" => *t = json!(["number", "null"]),
                Some(Value::Array(ts)) if ts.contains(&json!("number")) && !ts.contains(&json!("null")) => {
                    ts.push(json!("null"))
                }
                _ => {}
            }
            o.values_mut().for_each(numbers_nullable);
        }
        Value::Array(a) => a.iter_mut().for_each(numbers_nullable),
        _ => {}
    }
}

/// `body` (the schema of the file's content) with the two version fields of every file
/// (`json_file::to_string`) added as required properties.
fn versioned(schema: Schema, mut body: Value) -> Value {
    numbers_nullable(&mut body);
    let Some(root) = body.as_object_mut() else {
        return body;
    };
    root.insert("title".into(), json!(schema.id()));
    let properties = root.entry("properties").or_insert_with(|| json!({}));
    if let Some(p) = properties.as_object_mut() {
        p.insert(
            "schema".into(),
            json!({ "const": schema.id(), "description": "Layout name and major version." }),
        );
        p.insert(
            "axiscal_version".into(),
            json!({ "type": "string", "description": "Version of axiscal that wrote the file." }),
        );
    }
    let required = root.entry("required").or_insert_with(|| json!([]));
    if let Some(r) = required.as_array_mut() {
        r.insert(0, json!("axiscal_version"));
        r.insert(0, json!("schema"));
    }
    body
}

/// A file whose content is a list under `key` (`json_file::list_to_string`).
fn list_under<T: JsonSchema>(key: &str) -> Value {
    let mut items = schema_of::<Vec<T>>();
    let defs = items.as_object_mut().and_then(|o| o.remove("$defs"));
    if let Some(o) = items.as_object_mut() {
        o.remove("$schema");
        o.remove("title");
    }
    let mut root = json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "type": "object",
        "properties": { key: items },
        "required": [key],
    });
    if let Some(defs) = defs {
        root["$defs"] = defs;
    }
    root
}

/// Every JSON output: its [`Schema`], the file name of its schema under `docs/schemas/`, and
/// the schema, generated now.
pub fn schemas() -> Vec<(Schema, Value)> {
    [
        (Schema::CALIBRATION, schema_of::<CalibrationRecord>()),
        (Schema::REPORT, list_under::<Finding>("findings")),
        (Schema::DIAGNOSIS, schema_of::<DiagnosisFile>()),
        (Schema::SUMMARY, schema_of::<Summary>()),
        (Schema::EVALUATION, schema_of::<PaperReport>()),
        (Schema::FLOOR_CHECK, schema_of::<FloorCheck>()),
        (Schema::BLIND_SUMMARY, schema_of::<BlindScore>()),
        (Schema::BLIND_CASES, list_under::<CaseResult>("cases")),
        (Schema::BLIND_KEY, schema_of::<CaseKey>()),
        (Schema::BUDGET, schema_of::<BudgetReport>()),
        (Schema::STUDY, schema_of::<StudyReport>()),
        (Schema::VALIDATION, schema_of::<Validation>()),
        (Schema::ISO9283, schema_of::<crate::iso9283::IsoFigures>()),
        (Schema::ISO9283_PREDICTION, schema_of::<crate::iso9283::IsoPrediction>()),
        (Schema::CERTIFICATE, schema_of::<crate::certificate::Certificate>()),
    ]
    .into_iter()
    .map(|(schema, body)| (schema, versioned(schema, body)))
    .collect()
}

/// The file name of `schema`'s JSON Schema under `docs/schemas/`: `<name>.schema.json`.
pub fn file_name(schema: Schema) -> String {
    format!("{}.schema.json", schema.name)
}
