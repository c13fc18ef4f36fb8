//! Importers: measurement files written by other groups, converted to the measurement CSV of
//! `docs/formats.md#measurement-csv`. One module per source format.

pub mod boby_klimchik;
