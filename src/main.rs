//! The `axiscal` command line: one module per subcommand under `src/cli/`; `main` only maps
//! errors to exit codes (0 success, 1 a threshold failed, 2 bad input or a failed run).

mod cli;

/// mimalloc instead of the system allocator: the trials allocate many small rows (`docs/performance.md`,
/// "The allocator"); it changes no number.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> std::process::ExitCode {
    cli::main()
}
