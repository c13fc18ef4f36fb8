//! The allocator of the `axiscal` binary (`src/main.rs`), so that the benchmarks and the
//! profiling example time the work as the command line runs it.

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;
