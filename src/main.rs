//! The `axiscal` command line: one module per subcommand under `src/cli/`; `main` only maps
//! errors to exit codes (0 success, 1 a threshold failed, 2 bad input or a failed run).

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
