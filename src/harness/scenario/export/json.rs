//! `summary.json`.

use crate::harness::scenario::summary::Summary;

/// Pretty JSON of the summary, newline-terminated (NaN is written as `null`).
pub fn render(summary: &Summary) -> String {
    let mut s = serde_json::to_string_pretty(summary).expect("a summary has string keys only");
    s.push('\n');
    s
}
