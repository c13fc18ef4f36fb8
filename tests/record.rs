//! The recorder's integration tests alone, for the build with the `viz` feature
//! (`cargo test --features viz --test record`): the `cli_record` module of `tests/it/` and its
//! helpers, so that the feature build compiles one module instead of the whole `it` binary.
//! Without the feature, `cargo test --test it cli_record::` runs the same module.

#[allow(dead_code)]
#[path = "it/common/mod.rs"]
mod common;

#[path = "it/cli_record.rs"]
mod cli_record;
