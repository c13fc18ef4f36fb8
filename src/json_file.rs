//! The JSON files axiscal writes (and reads back): every file carries the name and major
//! version of its layout and the version of axiscal that wrote it, as its first two fields
//! (`docs/formats.md#versioning`).

use serde::Serialize;
use serde::de::DeserializeOwned;

/// The version of axiscal that writes a file (the crate version).
pub const AXISCAL_VERSION: &str = env!("CARGO_PKG_VERSION");

/// The layout of one kind of JSON file: `axiscal.<name>/<major>`. A new major number means an
/// incompatible change (a field removed or renamed, a meaning or unit changed); fields may be
/// added within one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Schema {
    /// What the file holds, e.g. `calibration`.
    pub name: &'static str,
    /// Major version of its layout.
    pub major: u32,
}

impl Schema {
    /// `calibration.json`, `floor_calibration.json`.
    pub const CALIBRATION: Schema = Schema::v1("calibration");
    /// `report.json` of `calibrate` (findings under `findings`).
    pub const REPORT: Schema = Schema::v1("report");
    /// `diagnosis.json` (both modes).
    pub const DIAGNOSIS: Schema = Schema::v1("diagnosis");
    /// `summary.json` of a Monte-Carlo run.
    pub const SUMMARY: Schema = Schema::v1("summary");
    /// `evaluation.json` of `evaluate`.
    pub const EVALUATION: Schema = Schema::v1("evaluation");
    /// `floor_check.json` of `evaluate`.
    pub const FLOOR_CHECK: Schema = Schema::v1("floor_check");
    /// `summary.json` of `blind`.
    pub const BLIND_SUMMARY: Schema = Schema::v1("blind_summary");
    /// `cases.json` of `blind` (cases under `cases`).
    pub const BLIND_CASES: Schema = Schema::v1("blind_cases");
    /// `key.json` of a blind case.
    pub const BLIND_KEY: Schema = Schema::v1("blind_key");
    /// `budget.json` of `budget`.
    pub const BUDGET: Schema = Schema::v1("budget");
    /// `efficiency.json` of `study`.
    pub const STUDY: Schema = Schema::v1("study");
    /// `summary.json` of `validate`.
    pub const VALIDATION: Schema = Schema::v1("validation");

    const fn v1(name: &'static str) -> Schema {
        Schema { name, major: 1 }
    }

    /// The `schema` field's value, `axiscal.<name>/<major>`.
    pub fn id(&self) -> String {
        format!("axiscal.{}/{}", self.name, self.major)
    }
}

/// A JSON file of the wrong kind or of a layout this axiscal does not know.
#[derive(Debug, thiserror::Error)]
pub enum JsonFileError {
    /// Not JSON, or not the layout's fields.
    #[error(transparent)]
    Parse(#[from] serde_json::Error),
    /// The file says it holds something else, or an incompatible version of it.
    #[error(
        "the file's schema is `{found}`, expected `{expected}` (a different major version is an incompatible layout)"
    )]
    WrongSchema {
        /// The file's `schema`.
        found: String,
        /// The schema this reader knows.
        expected: String,
    },
}

#[derive(Serialize)]
struct Versioned<'a, T: Serialize + ?Sized> {
    schema: String,
    axiscal_version: &'static str,
    #[serde(flatten)]
    body: &'a T,
}

/// `value` (a struct or map) as pretty JSON with `schema` and `axiscal_version` first.
pub fn to_string<T: Serialize + ?Sized>(schema: Schema, value: &T) -> serde_json::Result<String> {
    serde_json::to_string_pretty(&Versioned {
        schema: schema.id(),
        axiscal_version: AXISCAL_VERSION,
        body: value,
    })
}

/// A list as pretty JSON: an object with `schema`, `axiscal_version` and the list under `key`.
pub fn list_to_string<T: Serialize>(schema: Schema, key: &str, items: &[T]) -> serde_json::Result<String> {
    let mut body = serde_json::Map::new();
    body.insert(key.to_owned(), serde_json::to_value(items)?);
    to_string(schema, &body)
}

/// Reads a file written by [`to_string`]: its `schema` must be `schema` (a file without one
/// predates versioning and is read as major version 1); `schema` and `axiscal_version` are
/// removed before the rest is parsed as `T`.
pub fn from_str<T: DeserializeOwned>(schema: Schema, text: &str) -> Result<T, JsonFileError> {
    let mut value: serde_json::Value = serde_json::from_str(text)?;
    if let Some(object) = value.as_object_mut() {
        let found = object.remove("schema");
        object.remove("axiscal_version");
        match found {
            Some(serde_json::Value::String(s)) if s == schema.id() => {}
            None if schema.major == 1 => {}
            other => {
                return Err(JsonFileError::WrongSchema {
                    found: other.map_or_else(|| "none".to_owned(), |v| v.to_string()),
                    expected: schema.id(),
                });
            }
        }
    }
    Ok(serde_json::from_value(value)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Body {
        zeta_mm: f64,
        alpha: Vec<u32>,
    }

    #[test]
    fn fields_come_first_and_the_body_keeps_its_order_and_reads_back() {
        let body = Body {
            zeta_mm: 1.5,
            alpha: vec![1, 2],
        };
        let text = to_string(Schema::CALIBRATION, &body).unwrap();
        let keys: Vec<&str> = text
            .lines()
            .filter_map(|l| l.trim().strip_prefix('"'))
            .filter_map(|l| l.split('"').next())
            .collect();
        assert_eq!(keys, ["schema", "axiscal_version", "zeta_mm", "alpha"]);
        assert!(text.contains("\"axiscal.calibration/1\""));
        assert_eq!(from_str::<Body>(Schema::CALIBRATION, &text).unwrap(), body);
        // Before versioning: no schema, same layout.
        assert_eq!(
            from_str::<Body>(Schema::CALIBRATION, r#"{"zeta_mm": 1.5, "alpha": [1, 2]}"#).unwrap(),
            body
        );
    }

    #[test]
    fn another_schema_or_major_version_is_refused() {
        let text = to_string(
            Schema::REPORT,
            &Body {
                zeta_mm: 0.0,
                alpha: vec![],
            },
        )
        .unwrap();
        let e = from_str::<Body>(Schema::CALIBRATION, &text).unwrap_err();
        assert!(e.to_string().contains("axiscal.report/1"), "{e}");
        let v2 = text.replace("axiscal.report/1", "axiscal.calibration/2");
        assert!(matches!(
            from_str::<Body>(Schema::CALIBRATION, &v2),
            Err(JsonFileError::WrongSchema { .. })
        ));
    }

    #[test]
    fn a_list_sits_under_its_key() {
        let text = list_to_string(Schema::BLIND_CASES, "cases", &[1, 2, 3]).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["schema"], "axiscal.blind_cases/1");
        assert_eq!(v["cases"], serde_json::json!([1, 2, 3]));
    }
}
