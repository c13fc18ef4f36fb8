//! Progress of long library work, reported to whoever shows it (the command line's bar,
//! `cli/progress.rs`): the library counts units of work, it never draws. [`Silent`] when
//! nobody watches.

/// Receives the count of a long computation; called from worker threads.
pub trait Progress: Sync {
    /// `total` units of `unit` (e.g. `trials`) are to be done from now on.
    fn start(&self, total: usize, unit: &str);
    /// One more unit done.
    fn inc(&self);
}

/// Nobody watches.
pub struct Silent;

impl Progress for Silent {
    fn start(&self, _total: usize, _unit: &str) {}
    fn inc(&self) {}
}
