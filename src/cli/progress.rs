//! The one progress display of every command that can take more than a second (`run`,
//! `blind`, `study`, `budget`, `evaluate`, `diagnose`): on stderr, hidden when stderr is not a
//! terminal (a pipe, a CI log) or with `--quiet`, cleared when done. Counted work shows a bar
//! with the count and ETA, also when the library does the counting (it reports through
//! `axiscal::progress::Progress`, a [`Progress::stage`] passed to it); until the library
//! knows the count, a spinner shows what runs and the elapsed time.

use super::printer::Printer;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::time::Duration;

/// A progress display; cleared when dropped.
pub struct Progress(ProgressBar);

fn bar(len: Option<u64>, printer: Printer) -> ProgressBar {
    let bar = match len {
        Some(n) => ProgressBar::new(n),
        None => ProgressBar::new_spinner(),
    };
    if !printer.shows_progress() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar
}

impl Progress {
    /// `len` units of work (`unit`: `trials`, `cases`, ...), counted with [`Self::inc`].
    pub fn counted(len: usize, unit: &str, printer: Printer) -> Self {
        let bar = bar(Some(len as u64), printer);
        let template = format!("{{bar:40}} {{pos}}/{{len}} {unit}  {{elapsed}} elapsed, ETA {{eta}}");
        if let Ok(style) = ProgressStyle::with_template(&template) {
            bar.set_style(style);
        }
        Progress(bar)
    }

    /// Work that cannot be counted from here: a spinner with `what` and the elapsed time.
    pub fn stage(what: &str, printer: Printer) -> Self {
        let bar = bar(None, printer);
        if let Ok(style) = ProgressStyle::with_template("{spinner} {msg}  {elapsed}") {
            bar.set_style(style);
        }
        bar.set_message(what.to_owned());
        bar.enable_steady_tick(Duration::from_millis(200));
        Progress(bar)
    }

    /// One more unit done.
    pub fn inc(&self) {
        self.0.inc(1);
    }
}

impl axiscal::progress::Progress for Progress {
    fn start(&self, total: usize, unit: &str) {
        let template = format!("{{msg}} {{bar:20}} {{pos}}/{{len}} {unit}, {{elapsed}}, ETA {{eta}}");
        if let Ok(style) = ProgressStyle::with_template(&template) {
            self.0.set_style(style);
        }
        self.0.set_length(total as u64);
        self.0.set_position(0);
    }

    fn inc(&self) {
        self.0.inc(1);
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}
