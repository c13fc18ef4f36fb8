//! Named per-trial metrics and trial records (pure data).

/// The metrics of one trial, in a stable order (the column order of `trials.csv`). Units are
/// in the names (`uncal_pos_rms_mm`); counts have none.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Metrics(Vec<(String, f64)>);

impl Metrics {
    /// No metrics yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends metric `name`.
    pub fn push(&mut self, name: &str, value: f64) {
        self.0.push((name.to_owned(), value));
    }

    /// Appends every metric of `other` (e.g. calibrated metrics after uncalibrated ones).
    pub fn extend(&mut self, other: Metrics) {
        self.0.extend(other.0);
    }

    /// The names in order.
    pub fn names(&self) -> Vec<String> {
        self.0.iter().map(|(n, _)| n.clone()).collect()
    }

    /// The values in order.
    pub fn values(&self) -> Vec<f64> {
        self.0.iter().map(|(_, v)| *v).collect()
    }

    /// The value of `name`, if present.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }
}

/// One finished trial: which case, which trial, its seed and its metric values (in the
/// order of the trial's `metric_names`), or why it failed.
#[derive(Clone, Debug, PartialEq)]
pub struct TrialRecord {
    /// Case index in the resolved scenario.
    pub case: usize,
    /// Trial index within the case (0-based).
    pub trial: usize,
    /// The trial's seed.
    pub seed: u64,
    /// Metric values (empty when the trial failed).
    pub values: Vec<f64>,
    /// Why the trial failed (one line); `None` when it succeeded.
    pub error: Option<String>,
}

impl TrialRecord {
    /// The record's unit index, `case * trials + trial`.
    pub fn unit(&self, trials: usize) -> usize {
        self.case * trials + self.trial
    }

    /// Whether the trial succeeded (then `values` holds every metric, all finite).
    pub fn succeeded(&self) -> bool {
        self.error.is_none()
    }
}
