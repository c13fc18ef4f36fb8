//! Importers: measurement files written by other groups, converted to the measurement CSV of
//! FORMATS.md section 1. One module per source format.

pub mod boby_klimchik;
