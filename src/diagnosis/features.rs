//! Per-feature `where` entries.

use super::{NullData, Prepared, WhereEntry};

/// Held-out residual excess per workspace-feature bin.
pub(super) fn feature_entries(_prep: &Prepared, _null: &NullData) -> Vec<WhereEntry> {
    Vec::new()
}
