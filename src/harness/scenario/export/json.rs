//! `summary.json`.

use crate::harness::scenario::summary::Summary;

/// Pretty JSON of the summary, newline-terminated (NaN is written as `null`).
pub fn render(summary: &Summary) -> String {
    let mut s = crate::json_file::to_string(crate::json_file::Schema::SUMMARY, summary)
        .expect("a summary has string keys only");
    s.push('\n');
    s
}
