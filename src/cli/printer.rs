//! How a command prints, decided once from the command line (`--verbose`, `--quiet`, the
//! command's own `--json`) and passed down as a value to whatever prints.

use anyhow::Context;
use std::fmt;
use std::io::IsTerminal;
use std::path::Path;

/// The output settings of the running command.
#[derive(Clone, Copy, Debug, Default)]
pub struct Printer {
    /// `--verbose`: details (e.g. the instrument's calibration) on stderr.
    pub verbose: bool,
    /// `--quiet`: no progress display; with `--json`, no human-readable lines either.
    pub quiet: bool,
    /// `--json`: stdout holds the command's JSON document alone.
    pub json: bool,
}

impl Printer {
    /// The same settings for a command given `--json` (`json` true) or not.
    pub fn with_json(self, json: bool) -> Self {
        Printer { json, ..self }
    }

    /// A human-readable line: on stdout normally; with `--json` on stderr, or nowhere with
    /// `--quiet`.
    pub fn say(&self, line: fmt::Arguments) {
        if !self.json {
            println!("{line}");
        } else if !self.quiet {
            eprintln!("{line}");
        }
    }

    /// With `--json`, prints the JSON document the command wrote at `path` on stdout.
    pub fn emit_json(&self, path: &Path) -> anyhow::Result<()> {
        if self.json {
            let text = std::fs::read_to_string(path).with_context(|| format!("reading back {}", path.display()))?;
            println!("{}", text.trim_end());
        }
        Ok(())
    }

    /// Whether a progress display is drawn: stderr is a terminal and `--quiet` was not given.
    pub fn shows_progress(&self) -> bool {
        !self.quiet && std::io::stderr().is_terminal()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_keeps_the_global_flags() {
        let p = Printer {
            verbose: true,
            quiet: true,
            json: false,
        }
        .with_json(true);
        assert!(p.verbose && p.quiet && p.json);
        assert!(!p.with_json(false).json);
    }
}
