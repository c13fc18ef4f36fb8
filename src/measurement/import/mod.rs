//! Importers: measurement files written by other groups or exported by instruments, converted
//! to the measurement CSV of `docs/formats.md#measurement-csv`. One module per source format.

pub mod arrays;
pub mod boby_klimchik;
pub mod mat_v5;
pub mod points;
pub mod rct;
pub mod spatial_analyzer;
pub mod sscanss2;
pub mod table;
pub mod wide;
