//! The JSON files axiscal writes (and reads back): every file carries the name and major
//! version of its layout and the version of axiscal that wrote it, as its first two fields
//! (`docs/formats.md#versioning`).

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

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
    /// The oldest major version a reader of this axiscal still reads (older names through
    /// serde aliases); equal to `major` for files axiscal does not read back.
    pub oldest_read: u32,
}

impl Schema {
    /// `calibration.json`, `floor_calibration.json`. 2: named fields instead of pairs, the
    /// tool pose in mm, units in the names (`docs/formats.md#versioning`); 1 still reads.
    pub const CALIBRATION: Schema = Schema::new("calibration", 2, 1);
    /// `report.json` of `calibrate` (findings under `findings`).
    pub const REPORT: Schema = Schema::v1("report");
    /// `diagnosis.json` (both modes). 2: `poses`, `refit_rank` with named fields.
    pub const DIAGNOSIS: Schema = Schema::new("diagnosis", 2, 2);
    /// `summary.json` of a Monte-Carlo run.
    pub const SUMMARY: Schema = Schema::v1("summary");
    /// `evaluation.json` of `evaluate`. 2: named fields instead of positional arrays.
    pub const EVALUATION: Schema = Schema::new("evaluation", 2, 2);
    /// `floor_check.json` of `evaluate`. 2: named fields instead of positional arrays.
    pub const FLOOR_CHECK: Schema = Schema::new("floor_check", 2, 2);
    /// `summary.json` of `blind`. 2: `mean_gap` with named fields.
    pub const BLIND_SUMMARY: Schema = Schema::new("blind_summary", 2, 2);
    /// `cases.json` of `blind` (cases under `cases`). 2: each case's diagnosis at 2.
    pub const BLIND_CASES: Schema = Schema::new("blind_cases", 2, 2);
    /// `key.json` of a blind case.
    pub const BLIND_KEY: Schema = Schema::v1("blind_key");
    /// `budget.json` of `budget`.
    pub const BUDGET: Schema = Schema::v1("budget");
    /// `efficiency.json` of `study`. 2: units in the names of the sigmas.
    pub const STUDY: Schema = Schema::new("study", 2, 2);
    /// `summary.json` of `validate`. 2: the free poses tested against the noise and the
    /// calibration's predicted error, verdicts `consistent` / `exceeds` / `below`.
    pub const VALIDATION: Schema = Schema::new("validation", 2, 2);
    /// `iso9283.json` of `iso9283 evaluate`.
    pub const ISO9283: Schema = Schema::v1("iso9283");
    /// `iso9283-prediction.json` of `iso9283 predict`.
    pub const ISO9283_PREDICTION: Schema = Schema::v1("iso9283_prediction");
    /// `certificate.json` of `report`.
    pub const CERTIFICATE: Schema = Schema::v1("certificate");

    const fn v1(name: &'static str) -> Schema {
        Schema::new(name, 1, 1)
    }

    const fn new(name: &'static str, major: u32, oldest_read: u32) -> Schema {
        Schema {
            name,
            major,
            oldest_read,
        }
    }

    /// Whether a file whose `schema` is `id` is this layout in a version this axiscal reads.
    fn reads(&self, id: &str) -> bool {
        id.strip_prefix("axiscal.")
            .and_then(|rest| rest.split_once('/'))
            .is_some_and(|(name, major)| {
                name == self.name
                    && major
                        .parse::<u32>()
                        .is_ok_and(|m| (self.oldest_read..=self.major).contains(&m))
            })
    }

    /// The `schema` field's value, `axiscal.<name>/<major>`.
    pub fn id(&self) -> String {
        format!("axiscal.{}/{}", self.name, self.major)
    }
}

/// A JSON file of the wrong kind or of a layout this axiscal does not know.
#[derive(Debug, thiserror::Error)]
pub enum JsonFileError {
    /// Not JSON, or not the layout's fields: where, and what the parser said.
    #[error("line {line}, column {column}{}: {message}", key_of(key))]
    Parse {
        /// 1-based line of the text.
        line: usize,
        /// 1-based column (bytes) of the text.
        column: usize,
        /// The path of the key read there, e.g. `robot.rows[1].a_m` (empty at the top).
        key: String,
        /// The parser's message, with a hint for a `null` where a number belongs.
        message: String,
    },
    /// Not the layout's fields, where the text cannot say which.
    #[error("{0}")]
    Layout(String),
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

#[derive(Serialize, schemars::JsonSchema)]
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

/// Reads a file written by [`to_string`]: its `schema` must be `schema`'s name with a major
/// version from `schema.oldest_read` to `schema.major` (a file without one predates versioning
/// and is read as major version 1; older layouts read through serde aliases); `schema` and
/// `axiscal_version` are removed before the rest is parsed as `T`.
///
/// A leading byte-order mark is skipped (as the CSV readers do). An error names the line, the
/// column and the key's path there (`robot.rows[1].a_m`).
pub fn from_str<T: DeserializeOwned>(schema: Schema, text: &str) -> Result<T, JsonFileError> {
    parse(schema, text)?.read()
}

/// A file written by [`to_string`], parsed once and its schema checked ([`parse`]), to be read
/// as one or more types ([`Parsed::read`]: a file that holds several values side by side).
#[derive(Debug)]
pub struct Parsed<'a> {
    /// The text, for the line and column of an error.
    text: &'a str,
    /// The parsed text less `schema` and `axiscal_version`.
    value: serde_json::Value,
}

impl Parsed<'_> {
    /// The parsed file read as `T`; an error names the line, the column and the key's path.
    pub fn read<T: DeserializeOwned>(&self) -> Result<T, JsonFileError> {
        T::deserialize(&self.value).map_err(|e| placed::<T>(self.text, &e))
    }
}

/// The text of a file written by [`to_string`] parsed once, its schema checked as
/// [`from_str`] checks it.
pub fn parse(schema: Schema, text: &str) -> Result<Parsed<'_>, JsonFileError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut value = serde_json::from_str::<UniqueKeys>(text)
        .map_err(|e| located(text, &e))?
        .0;
    if let Some(object) = value.as_object_mut() {
        let found = object.remove("schema");
        object.remove("axiscal_version");
        match found {
            Some(serde_json::Value::String(s)) if schema.reads(&s) => {}
            None if schema.oldest_read == 1 => {}
            other => {
                return Err(JsonFileError::WrongSchema {
                    found: other.map_or_else(|| "none".to_owned(), |v| v.to_string()),
                    expected: schema.id(),
                });
            }
        }
    }
    Ok(Parsed { text, value })
}

/// A JSON value whose objects hold each key once: `serde_json::Value` keeps the last of a
/// repeated key silently, so that of a hand-edited file holding a value twice one would be
/// used without a word. The error is placed at the repeated key.
struct UniqueKeys(serde_json::Value);

impl<'de> Deserialize<'de> for UniqueKeys {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(UniqueKeysVisitor).map(UniqueKeys)
    }
}

/// Builds a [`UniqueKeys`] value as `serde_json::Value`'s own visitor does, refusing a key
/// repeated in one object.
struct UniqueKeysVisitor;

impl<'de> serde::de::Visitor<'de> for UniqueKeysVisitor {
    type Value = serde_json::Value;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<Self::Value, E> {
        Ok(v.into())
    }
    fn visit_i64<E>(self, v: i64) -> Result<Self::Value, E> {
        Ok(v.into())
    }
    fn visit_u64<E>(self, v: u64) -> Result<Self::Value, E> {
        Ok(v.into())
    }
    fn visit_f64<E>(self, v: f64) -> Result<Self::Value, E> {
        Ok(serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, serde_json::Value::Number))
    }
    fn visit_str<E>(self, v: &str) -> Result<Self::Value, E> {
        Ok(v.into())
    }
    fn visit_string<E>(self, v: String) -> Result<Self::Value, E> {
        Ok(v.into())
    }
    fn visit_unit<E>(self) -> Result<Self::Value, E> {
        Ok(serde_json::Value::Null)
    }
    fn visit_none<E>(self) -> Result<Self::Value, E> {
        Ok(serde_json::Value::Null)
    }
    fn visit_some<D: serde::Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        UniqueKeys::deserialize(d).map(|v| v.0)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut items = Vec::new();
        while let Some(UniqueKeys(v)) = seq.next_element()? {
            items.push(v);
        }
        Ok(serde_json::Value::Array(items))
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let mut object = serde_json::Map::new();
        // The key is checked before its value is read, so that the error stands at it.
        while let Some(key) = map.next_key::<String>()? {
            if object.contains_key(&key) {
                return Err(serde::de::Error::custom(format!(
                    "the key `{}` is given twice in one object: keep the one meant and delete the other",
                    crate::csv_lines::shown_message(&key)
                )));
            }
            let UniqueKeys(v) = map.next_value()?;
            object.insert(key, v);
        }
        Ok(serde_json::Value::Object(object))
    }
}

/// `e`, an error of reading the parsed value (which has no positions), placed in `text`: the
/// text is read again as `T` only to find where (the first error in the text's order: a
/// parsed object's keys are sorted); when that stops at a field the reader removed
/// (`schema`, `axiscal_version`), the message alone.
fn placed<T: DeserializeOwned>(text: &str, e: &serde_json::Error) -> JsonFileError {
    let removed = |m: &str| {
        ["schema", "axiscal_version"]
            .iter()
            .any(|f| m.starts_with(&format!("unknown field `{f}`")))
    };
    match serde_json::from_str::<T>(text) {
        Err(again) if !removed(&message_of(&again)) => located(text, &again),
        _ => JsonFileError::Layout(with_hint(message_of(e))),
    }
}

/// The parser's message without its " at line L column C".
fn message_of(e: &serde_json::Error) -> String {
    let text = e.to_string();
    let suffix = format!(" at line {} column {}", e.line(), e.column());
    crate::csv_lines::shown_message(text.strip_suffix(&suffix).unwrap_or(&text))
}

/// A `null` where a number belongs is how axiscal writes NaN: say what to write instead.
fn with_hint(message: String) -> String {
    if message.starts_with("invalid type: null") {
        format!("{message}: write a number (null stands for NaN, which has no meaning here)")
    } else {
        message
    }
}

/// `e` of reading `text` as [`JsonFileError::Parse`], with the key's path at its position.
fn located(text: &str, e: &serde_json::Error) -> JsonFileError {
    let (line, column) = (e.line(), e.column());
    let line_start: usize = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum();
    JsonFileError::Parse {
        line,
        column: column.max(1),
        key: key_at(text, line_start + column),
        message: with_hint(message_of(e)),
    }
}

/// `, key `PATH`` for a path, nothing at the top.
fn key_of(key: &str) -> String {
    if key.is_empty() {
        String::new()
    } else {
        format!(", key `{key}`")
    }
}

/// An object or array open at a point of a JSON text.
enum Open {
    /// An object, with the key whose value is being read (none between a comma and a key).
    Object(Option<String>),
    /// An array, with the index of the item being read.
    Array(usize),
}

/// The path (`robot.rows[1].a_m`) of the value being read at byte `offset` of the JSON
/// `text`: the keys and indices of the objects and arrays open there.
fn key_at(text: &str, offset: usize) -> String {
    let bytes = &text.as_bytes()[..offset.min(text.len())];
    let mut open: Vec<Open> = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'"' => {
                let end = string_end(bytes, i);
                if let Some(Open::Object(key @ None)) = open.last_mut() {
                    *key = Some(String::from_utf8_lossy(&bytes[i + 1..end.saturating_sub(1).max(i + 1)]).into());
                }
                i = end;
                continue;
            }
            b'{' => open.push(Open::Object(None)),
            b'[' => open.push(Open::Array(0)),
            b'}' | b']' => {
                open.pop();
            }
            b',' => match open.last_mut() {
                Some(Open::Array(n)) => *n += 1,
                Some(Open::Object(key)) => *key = None,
                None => {}
            },
            _ => {}
        }
        i += 1;
    }
    path_of(&open)
}

/// The index just past the string starting at the quote `bytes[start]` (or the end).
fn string_end(bytes: &[u8], start: usize) -> usize {
    let mut i = start + 1;
    while i < bytes.len() {
        match bytes[i] {
            b'\\' => i += 2,
            b'"' => return i + 1,
            _ => i += 1,
        }
    }
    bytes.len()
}

/// `a.b[2].c` of the open containers.
fn path_of(open: &[Open]) -> String {
    let mut path = String::new();
    for o in open {
        match o {
            Open::Object(Some(key)) if path.is_empty() => path.push_str(key),
            Open::Object(Some(key)) => {
                path.push('.');
                path.push_str(key);
            }
            Open::Object(None) => {}
            Open::Array(n) => path.push_str(&format!("[{n}]")),
        }
    }
    path
}

/// One value as it may appear in a file: the current layout (`T`, named fields) or the one
/// before it (`P`, e.g. a positional array), tried in that order.
#[derive(serde::Deserialize)]
#[serde(untagged)]
enum NamedOrOld<T, P> {
    Named(T),
    Old(P),
}

/// Reads a field that is `T` (named fields) now and was `P` (a positional array, a tuple)
/// before: `#[serde(deserialize_with = "json_file::named_or_old::<_, T, P>")]`, so files
/// written before the rename still read (`docs/formats.md#versioning`).
pub fn named_or_old<'de, D, T, P>(d: D) -> Result<T, D::Error>
where
    D: serde::Deserializer<'de>,
    T: serde::Deserialize<'de> + From<P>,
    P: serde::Deserialize<'de>,
{
    Ok(match NamedOrOld::<T, P>::deserialize(d)? {
        NamedOrOld::Named(t) => t,
        NamedOrOld::Old(p) => T::from(p),
    })
}

/// [`named_or_old`] for each element of a list.
pub fn each_named_or_old<'de, D, T, P>(d: D) -> Result<Vec<T>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: serde::Deserialize<'de> + From<P>,
    P: serde::Deserialize<'de>,
{
    let items = Vec::<NamedOrOld<T, P>>::deserialize(d)?;
    Ok(items
        .into_iter()
        .map(|i| match i {
            NamedOrOld::Named(t) => t,
            NamedOrOld::Old(p) => T::from(p),
        })
        .collect())
}

/// `skip_serializing_if` for a count that is absent from a file when zero.
pub fn is_zero_count(n: &usize) -> bool {
    *n == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
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
        assert!(text.contains("\"axiscal.calibration/2\""));
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
        let v3 = text.replace("axiscal.report/1", "axiscal.calibration/3");
        assert!(matches!(
            from_str::<Body>(Schema::CALIBRATION, &v3),
            Err(JsonFileError::WrongSchema { .. })
        ));
        // Version 1 still reads; an evaluation (not read back) reads its own major only.
        let v1 = text.replace("axiscal.report/1", "axiscal.calibration/1");
        assert!(from_str::<Body>(Schema::CALIBRATION, &v1).is_ok());
        let e1 = text.replace("axiscal.report/1", "axiscal.evaluation/1");
        assert!(from_str::<Body>(Schema::EVALUATION, &e1).is_err());
    }

    /// A key given twice in one object, at the top or nested, is refused at its line with its
    /// path, not read as the last one; a file without repeats parses to the value serde_json's
    /// own reader gives (a second path), numbers bit for bit.
    #[test]
    fn a_key_given_twice_is_refused_where_it_repeats() {
        let text = "{\n  \"zeta_mm\": 1.5,\n  \"alpha\": [1, 2],\n  \"zeta_mm\": 2.5\n}";
        let e = from_str::<Body>(Schema::CALIBRATION, text).unwrap_err().to_string();
        assert!(
            e.starts_with("line 4, ") && e.contains("`zeta_mm` is given twice"),
            "{e}"
        );
        let nested = r#"{"a": [{"b": {"c": 1, "d": 2, "c": 3}}]}"#;
        let e = parse(Schema::CALIBRATION, nested).unwrap_err().to_string();
        assert!(e.contains("key `a[0].b.c`") && e.contains("`c` is given twice"), "{e}");
        // The same key in sibling objects is no repeat.
        let siblings =
            r#"{"x": [{"k": 0.1}, {"k": -3e-300}], "y": {"k": null, "z": [true, "s", 18446744073709551615]}}"#;
        let own: serde_json::Value = serde_json::from_str(siblings).unwrap();
        assert_eq!(parse(Schema::CALIBRATION, siblings).unwrap().value, own);
        let k = |v: &serde_json::Value| v["x"][1]["k"].as_f64().unwrap().to_bits();
        assert_eq!(k(&parse(Schema::CALIBRATION, siblings).unwrap().value), k(&own));
    }

    /// A value of the wrong type is named by its key's path, line and column, a `null` for a
    /// number with what to write; a byte-order mark is skipped.
    #[test]
    fn an_error_names_the_keys_path_and_a_bom_is_skipped() {
        let text = "{\n  \"zeta_mm\": 1.5,\n  \"alpha\": [1, null]\n}";
        let e = from_str::<Body>(Schema::CALIBRATION, text).unwrap_err().to_string();
        assert!(
            e.starts_with("line 3, column 19, key `alpha[1]`: invalid type: null"),
            "{e}"
        );
        // The first in the text's order, not in the parsed object's (sorted) order.
        let e = from_str::<Body>(Schema::CALIBRATION, &text.replace("1.5", "null")).unwrap_err();
        assert!(
            e.to_string().contains("key `zeta_mm`") && e.to_string().contains("write a number"),
            "{e}"
        );
        // With `schema` (which the reader removes) and a type error after it.
        let versioned = text.replacen('{', "{\"schema\": \"axiscal.calibration/2\",", 1);
        let e = from_str::<Body>(Schema::CALIBRATION, &versioned)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("invalid type: null, expected a whole number from 0 to 4294967295"),
            "{e}"
        );
        let bom = format!("\u{feff}{}", text.replace("null", "2"));
        assert_eq!(from_str::<Body>(Schema::CALIBRATION, &bom).unwrap().alpha, [1, 2]);
    }

    #[test]
    fn the_path_at_a_point_counts_keys_and_items() {
        let text = r#"{"a": {"b": [1, {"c, ]": "x", "d": [0, 0, 9"#;
        assert_eq!(key_at(text, text.len()), "a.b[1].d[2]");
        assert_eq!(key_at(text, 5), "a");
        assert_eq!(key_at("", 0), "");
    }

    #[test]
    fn a_list_sits_under_its_key() {
        let text = list_to_string(Schema::BLIND_CASES, "cases", &[1, 2, 3]).unwrap();
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["schema"], "axiscal.blind_cases/2");
        assert_eq!(v["cases"], serde_json::json!([1, 2, 3]));
    }

    proptest::proptest! {
        /// A value written and read back is the same value to the bit (serde_json's
        /// `float_roundtrip`): a calibration read back compensates exactly as written.
        #[test]
        fn every_finite_number_reads_back_to_the_bit(bits in proptest::num::u64::ANY) {
            let x = f64::from_bits(bits);
            proptest::prop_assume!(x.is_finite());
            let body = Body { zeta_mm: x, alpha: vec![] };
            let text = to_string(Schema::CALIBRATION, &body).unwrap();
            let back: Body = from_str(Schema::CALIBRATION, &text).unwrap();
            proptest::prop_assert_eq!(back.zeta_mm.to_bits(), x.to_bits(), "{}", text);
        }
    }
}
