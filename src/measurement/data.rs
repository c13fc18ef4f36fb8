//! Measured target positions as read from (or written to) the measurement CSV of
//! `docs/formats.md#measurement-csv`, grouped by experiment and pose.

use crate::csv_lines::shown_cell;
use nalgebra::Point3;
use std::collections::{BTreeMap, HashMap};

/// Experiment id of the three tool targets observed at the reference pose (trains the
/// calibrator's tool frame; not a validation pose).
pub const TOOL_EXPERIMENT: &str = "tool";

/// An experiment id, a target's name or a setup's label longer than this \[characters\] is no
/// name (a cell holding a pasted file?): refused when read, so that no message or output
/// repeats it.
pub const MAX_LABEL_CHARS: usize = 200;

/// One observed target in one robot pose: one row of the measurement CSV.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// Text id of the experiment (one joint swept, or one set of validation poses).
    pub experiment: String,
    /// The joint whose actuator the experiment moves (1..=N), or 0 for validation poses.
    pub moved_joint: usize,
    /// 0-based order of the pose within the experiment.
    pub step: usize,
    /// Target id (axis experiments: 0 on the moved link, 1 on the next; validation: 0..=2).
    pub target: usize,
    /// Measured position in the instrument frame \[mm\].
    pub position_mm: [f64; 3],
    /// Controller commands `cmd_1..cmd_N` in file units: degrees (revolute) or millimetres
    /// (prismatic).
    pub cmd: Vec<f64>,
    /// Payload carried at the tool \[kg\] (default 0).
    pub payload_kg: f64,
    /// Ambient temperature \[deg C\] (default 20).
    pub temperature_c: f64,
}

impl Measurement {
    /// Default `payload_kg` when the column is absent.
    pub const DEFAULT_PAYLOAD_KG: f64 = 0.0;
    /// Default `temperature_c` when the column is absent.
    pub const DEFAULT_TEMPERATURE_C: f64 = 20.0;

    /// The measured position in metres.
    pub fn position_m(&self) -> Point3<f64> {
        Point3::from(self.position_mm.map(|c| c * 1e-3))
    }
}

/// What is wrong with one row of a measurement set (position given by the caller).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RowProblem {
    /// The experiment id is empty or has leading/trailing white space.
    #[error("experiment id {:?} is empty or has surrounding white space", shown_cell(experiment))]
    BadExperimentName {
        /// The id.
        experiment: String,
    },
    /// The experiment id is longer than [`MAX_LABEL_CHARS`].
    #[error(
        "experiment id {:?} is longer than {MAX_LABEL_CHARS} characters: an id names an experiment (`axis1`, \
         `validation`); shorten it",
        shown_cell(experiment)
    )]
    LongExperimentName {
        /// The id.
        experiment: String,
    },
    /// The row has a different number of joint commands from the set.
    #[error("{found} joint commands, expected {expected}")]
    JointCount {
        /// Commands in the row.
        found: usize,
        /// Joints of the robot.
        expected: usize,
    },
    /// A number is NaN or infinite.
    #[error("value {value} is not finite")]
    NotFinite {
        /// The column, e.g. `y_mm` or `cmd_3`.
        column: String,
        /// The value.
        value: f64,
    },
    /// A value outside its physical range (a negative payload, a temperature below absolute
    /// zero, a coordinate beyond 10 km, a command beyond 1e6).
    #[error("{} is outside {expected}", crate::measurement::format_f64(*value))]
    OutOfRange {
        /// The column.
        column: String,
        /// The value.
        value: f64,
        /// The range, in words.
        expected: &'static str,
    },
    /// `moved_joint` is not in `0..=N`.
    #[error("moved_joint {value} is outside 0..={joint_count}")]
    MovedJointOutOfRange {
        /// The value.
        value: usize,
        /// N.
        joint_count: usize,
    },
    /// The experiment's rows disagree on which joint it moves.
    #[error(
        "experiment {:?} moves joint {found} here but joint {first} earlier",
        shown_cell(experiment)
    )]
    InconsistentMovedJoint {
        /// The experiment.
        experiment: String,
        /// `moved_joint` of its first row.
        first: usize,
        /// `moved_joint` of this row.
        found: usize,
    },
    /// The experiment's id names a joint the robot does not have (`axis66` for a six-joint
    /// robot: a typo of `axis6`).
    #[error(
        "experiment {experiment:?} names joint {named}, but the robot has {joint_count} joints: a typo in the experiment id?{}",
        rename_hint(*moved_joint)
    )]
    NoSuchJoint {
        /// The experiment.
        experiment: String,
        /// The joint its id names.
        named: usize,
        /// N.
        joint_count: usize,
        /// The row's `moved_joint`.
        moved_joint: usize,
    },
    /// Two rows share (experiment, step, target).
    #[error(
        "duplicate (experiment, step, target) = ({:?}, {step}, {target}), first seen at {first_at}",
        shown_cell(experiment)
    )]
    DuplicateKey {
        /// The experiment.
        experiment: String,
        /// The step.
        step: usize,
        /// The target.
        target: usize,
        /// Where the key first appeared: 0-based row index in a [`MeasurementSet`], 1-based
        /// line in a file.
        first_at: u64,
    },
    /// Two rows of one pose (experiment and step) carry different commands: one pose has one
    /// reading of its commands, whichever targets were measured at it.
    #[error(
        "experiment {:?} step {step}: {} here but {} at {reading_at}, a row of the same pose: the targets of one pose \
         share its commands (within {POSE_COMMAND_TOLERANCE:e} deg or mm){}",
        shown_cell(experiment),
        crate::measurement::format_f64(*value),
        crate::measurement::format_f64(*reading),
        other_reading_hint(*value, *reading, *majority)
    )]
    PoseCommandsDiffer {
        /// The experiment.
        experiment: String,
        /// The step.
        step: usize,
        /// The joint whose command differs (1-based).
        joint: usize,
        /// This row's command.
        value: f64,
        /// The command most of the pose's rows carry.
        reading: f64,
        /// Where that reading is: 0-based row index in a [`MeasurementSet`], 1-based line in a
        /// file.
        reading_at: u64,
        /// Whether more than half of the pose's rows carry that reading; if not (two rows, one
        /// each), either row may be the wrong one.
        majority: bool,
    },
    /// An experiment whose id names a joint (`axis3`) holds free poses (`moved_joint = 0`).
    #[error(
        "experiment {:?} names joint {named}, but its moved_joint is 0 (free poses): set moved_joint to {named} if \
         its rows sweep joint {named}, or rename the experiment (`validation`, `poses`)",
        shown_cell(experiment)
    )]
    AxisIdOfFreePoses {
        /// The experiment.
        experiment: String,
        /// The joint its id names.
        named: usize,
    },
}

/// The commands of the rows of one pose must agree within this \[deg or mm\]: files written by
/// other programs round the commands they print, but one pose has one reading.
pub const POSE_COMMAND_TOLERANCE: f64 = 1e-6;

/// What a row's command `value` that differs from its pose's `reading` may be: the pose's
/// command in radians (degrees times pi/180, to the rounding of a printed value), or a row of
/// another pose; without a `majority` of the pose's rows for the reading, either row.
fn other_reading_hint(value: f64, reading: f64, majority: bool) -> &'static str {
    let radians = reading.abs() > 1e-3 && ((value.to_degrees() - reading) / reading).abs() < 1e-3;
    match (radians, majority) {
        (true, _) => ": this row's commands look like radians; write them in degrees as its pose's other rows",
        (false, true) => ": correct this row (a row of another pose?)",
        (false, false) => {
            ": no reading is most of the pose's rows, so either row may be the wrong one: correct the one that is \
             (a row of another pose?)"
        }
    }
}

impl RowProblem {
    /// The column the problem is in (for `DuplicateKey`, the key columns).
    pub fn column(&self) -> String {
        match self {
            Self::BadExperimentName { .. }
            | Self::LongExperimentName { .. }
            | Self::InconsistentMovedJoint { .. }
            | Self::NoSuchJoint { .. } => "experiment".into(),
            Self::AxisIdOfFreePoses { .. } => "moved_joint".into(),
            Self::PoseCommandsDiffer { joint, .. } => format!("cmd_{joint}"),
            Self::JointCount { .. } => "cmd_*".into(),
            Self::NotFinite { column, .. } | Self::OutOfRange { column, .. } => column.clone(),
            Self::MovedJointOutOfRange { .. } => "moved_joint".into(),
            Self::DuplicateKey { .. } => "experiment,step,target".into(),
        }
    }
}

/// The rename [`RowProblem::NoSuchJoint`] suggests: the joint the rows move.
fn rename_hint(moved_joint: usize) -> String {
    match moved_joint {
        0 => String::new(),
        k => format!(" (its rows move joint {k}: `axis{k}`)"),
    }
}

/// The joint an experiment id of the form `axis<k>` (case ignored) names, as `simulate` and the
/// importers write them; `usize::MAX` for digits beyond any number.
pub fn joint_named_by(experiment: &str) -> Option<usize> {
    let digits = experiment
        .get(..4)?
        .eq_ignore_ascii_case("axis")
        .then(|| &experiment[4..])?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some(digits.parse().unwrap_or(usize::MAX))
}

/// A row of a [`MeasurementSet`] is invalid.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("row {row}, column `{}`: {problem}", problem.column())]
pub struct MeasurementSetError {
    /// 0-based row index.
    pub row: usize,
    /// What is wrong.
    pub problem: RowProblem,
}

/// All rows of one measurement campaign, in file order, for a robot with N joints.
///
/// Invariants (checked by [`MeasurementSet::new`]): every row has N finite commands and a
/// finite position, `moved_joint` in `0..=N` and constant within an experiment, and
/// (experiment, step, target) is unique.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasurementSet {
    joint_count: usize,
    rows: Vec<Measurement>,
    /// The targets' names by id, when the file named them (`T1`, `SMR2`); empty for integer ids.
    target_names: Vec<String>,
    /// Each row's setup (the instrument's placement it was measured from), when the file has a
    /// `setup` column; empty: every row setup 0.
    row_setups: Vec<usize>,
    /// The setups' labels by id.
    setup_names: Vec<String>,
    /// The file line each row was read from, when a file was read.
    lines: SourceLines,
}

/// The file line of each row: where the rows came from, not what they are, so two sets with
/// the same rows are equal whatever their lines.
#[derive(Clone, Debug, Default)]
struct SourceLines(Vec<u64>);

impl PartialEq for SourceLines {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// The rows of one experiment, in file order.
#[derive(Clone, Debug, PartialEq)]
pub struct Experiment<'a> {
    /// Its id.
    pub name: &'a str,
    /// The joint it moves (0: validation poses).
    pub moved_joint: usize,
    /// Its rows in file order.
    pub rows: Vec<&'a Measurement>,
    /// The file lines of its first and last row, when the set was read from a file.
    pub lines: Option<(u64, u64)>,
}

impl<'a> Experiment<'a> {
    /// Rows keyed by (step, target).
    pub fn by_step_target(&self) -> BTreeMap<(usize, usize), &'a Measurement> {
        self.rows.iter().map(|m| ((m.step, m.target), *m)).collect()
    }

    /// Rows grouped by step (ascending), each group sorted by target.
    pub fn by_step(&self) -> BTreeMap<usize, Vec<&'a Measurement>> {
        let rows = self.rows_by_step();
        let mut steps: BTreeMap<usize, Vec<&'a Measurement>> = BTreeMap::new();
        for group in rows.chunk_by(|a, b| a.step == b.step) {
            steps.insert(group[0].step, group.to_vec());
        }
        steps
    }

    /// The rows ordered by (step, target): [`Self::by_step`]'s groups one after the other
    /// (`chunk_by` on the step gives them), without a map or a vector per step.
    pub fn rows_by_step(&self) -> Vec<&'a Measurement> {
        // (step, target) is unique in a set (`MeasurementSet::new` refuses duplicates), so a
        // sort orders the rows as `by_step_target` would.
        let mut rows = self.rows.clone();
        rows.sort_unstable_by_key(|m| (m.step, m.target));
        rows
    }

    /// The row for (step, target), if that target was observed.
    pub fn get(&self, step: usize, target: usize) -> Option<&'a Measurement> {
        self.rows.iter().copied().find(|m| m.step == step && m.target == target)
    }
}

impl MeasurementSet {
    /// Checks the invariants and builds the set.
    pub fn new(joint_count: usize, rows: Vec<Measurement>) -> Result<Self, MeasurementSetError> {
        validate(joint_count, &rows)?;
        Ok(Self {
            joint_count,
            rows,
            target_names: Vec::new(),
            row_setups: Vec::new(),
            setup_names: Vec::new(),
            lines: SourceLines::default(),
        })
    }

    /// The set with each row's file line (`lines`, one per row). Ignored unless there is one
    /// per row.
    pub fn with_lines(self, lines: Vec<u64>) -> Self {
        if lines.len() != self.rows.len() {
            return self;
        }
        Self {
            lines: SourceLines(lines),
            ..self
        }
    }

    /// The file line of row `row`, when the set was read from a file.
    pub fn line_of(&self, row: usize) -> Option<u64> {
        self.lines.0.get(row).copied()
    }

    /// The set without the rows `rows` (indices), its setups, target names and lines kept.
    pub fn without_rows(&self, rows: &[usize]) -> Self {
        let mut dropped = vec![false; self.rows.len()];
        for &r in rows {
            if let Some(d) = dropped.get_mut(r) {
                *d = true;
            }
        }
        let keep = |i: &usize| !dropped[*i];
        let pick = |v: &[usize]| -> Vec<usize> { (0..v.len()).filter(keep).map(|i| v[i]).collect() };
        Self {
            joint_count: self.joint_count,
            rows: (0..self.rows.len())
                .filter(keep)
                .map(|i| self.rows[i].clone())
                .collect(),
            target_names: self.target_names.clone(),
            row_setups: pick(&self.row_setups),
            setup_names: self.setup_names.clone(),
            lines: SourceLines((0..self.lines.0.len()).filter(keep).map(|i| self.lines.0[i]).collect()),
        }
    }

    /// The set with each row's setup (`row_setups`, one per row, ids into `names`): rows
    /// measured with the instrument placed elsewhere. Ignored unless there is one per row.
    pub fn with_setups(self, row_setups: Vec<usize>, names: Vec<String>) -> Self {
        if row_setups.len() != self.rows.len() {
            return self;
        }
        Self {
            row_setups,
            setup_names: names,
            ..self
        }
    }

    /// The set with every row a free pose (`moved_joint = 0`), its experiments, steps, setups
    /// and target names kept: sweeps the independent-axis procedure cannot use, taken as
    /// poses like any other (their targets on the last link).
    pub fn every_row_a_free_pose(&self) -> Self {
        let mut out = self.clone();
        for m in &mut out.rows {
            m.moved_joint = 0;
        }
        out
    }

    /// A digest of the measured rows, `fnv1a64:` and 16 hex digits: FNV-1a 64 over every row in
    /// order, its experiment id (byte length as u64 LE, then its UTF-8 bytes), `moved_joint`,
    /// `step` and `target` (u64 LE), then `x_mm`, `y_mm`, `z_mm`, `cmd_1..cmd_N`, `payload_kg`
    /// and `temperature_c` (IEEE-754 f64 bits, LE). Two files with the same rows in the same
    /// order have the same digest, whatever their formatting; another campaign has another.
    pub fn digest(&self) -> String {
        let mut hash = crate::robot::Fnv::new();
        for m in &self.rows {
            hash.bytes(&(m.experiment.len() as u64).to_le_bytes());
            hash.bytes(m.experiment.as_bytes());
            for v in [m.moved_joint, m.step, m.target] {
                hash.bytes(&(v as u64).to_le_bytes());
            }
            let numbers = m
                .position_mm
                .iter()
                .chain(&m.cmd)
                .chain([&m.payload_kg, &m.temperature_c]);
            numbers.for_each(|v| hash.bytes(&v.to_bits().to_le_bytes()));
        }
        hash.text()
    }

    /// The set with coordinate `column` (0: `x_mm`, 1: `y_mm`, 2: `z_mm`) of every row
    /// multiplied by `factor`: the rows as they would read in another unit of that column.
    pub fn with_coordinate_scaled(&self, column: usize, factor: f64) -> Self {
        let mut out = self.clone();
        for m in &mut out.rows {
            m.position_mm[column] *= factor;
        }
        out
    }

    /// The set with coordinate `column` of every row scaled by `factor` about `centre_mm`
    /// (`centre + factor (value - centre)`): one axis of the instrument reading long or short.
    pub fn with_coordinate_scaled_about(&self, column: usize, factor: f64, centre_mm: f64) -> Self {
        let mut out = self.clone();
        for m in &mut out.rows {
            m.position_mm[column] = centre_mm + factor * (m.position_mm[column] - centre_mm);
        }
        out
    }

    /// The set with each row `i` of `moves` moved by its `[x, y, z]` \[mm\] (its coordinates
    /// plus it): rows as they would read had the instrument not moved before them.
    pub fn with_rows_moved(&self, moves: &[(usize, [f64; 3])]) -> Self {
        let mut out = self.clone();
        for (i, by) in moves {
            if let Some(m) = out.rows.get_mut(*i) {
                (0..3).for_each(|c| m.position_mm[c] += by[c]);
            }
        }
        out
    }

    /// The set with command `joint` (0-based: `cmd_1` is 0) of every row multiplied by
    /// `factor`: a joint's readings on another scale (a slide's lead, an exporter's factor).
    pub fn with_command_scaled(&self, joint: usize, factor: f64) -> Self {
        let mut out = self.clone();
        for m in &mut out.rows {
            if let Some(c) = m.cmd.get_mut(joint) {
                *c *= factor;
            }
        }
        out
    }

    /// The set with command `joint` (0-based) of the rows of experiment `experiment` moved by
    /// `change` (file units): a held joint's recorded value in one sweep corrected.
    pub fn with_command_offset_in(&self, experiment: &str, joint: usize, change: f64) -> Self {
        let mut out = self.clone();
        for m in out.rows.iter_mut().filter(|m| m.experiment == experiment) {
            if let Some(c) = m.cmd.get_mut(joint) {
                *c += change;
            }
        }
        out
    }

    /// The set with the rows of experiment `experiment` moved by `-(block_mm + t drift_mm)`,
    /// `t` running linearly from 0 at its first step to 1 at its last: a move of the sweep's
    /// block and a drift through it undone.
    pub fn with_sweep_move_undone_in(&self, experiment: &str, block_mm: [f64; 3], drift_mm: [f64; 3]) -> Self {
        let steps = self.rows.iter().filter(|m| m.experiment == experiment).map(|m| m.step);
        let (first, last) = steps.fold((usize::MAX, 0), |(a, b), s| (a.min(s), b.max(s)));
        let span = last.saturating_sub(first).max(1) as f64;
        let mut out = self.clone();
        for m in out.rows.iter_mut().filter(|m| m.experiment == experiment) {
            let t = (m.step - first) as f64 / span;
            (0..3).for_each(|c| m.position_mm[c] -= block_mm[c] + t * drift_mm[c]);
        }
        out
    }

    /// The set with each row moved by `-t drift_mm`, `t` running linearly with its file line
    /// from 0 at line `lines.0` to 1 at line `lines.1`: a drift through the whole file undone
    /// (rows without a line are left as they are).
    pub fn with_file_drift_undone(&self, drift_mm: [f64; 3], lines: (u64, u64)) -> Self {
        let span = lines.1.saturating_sub(lines.0).max(1) as f64;
        let mut out = self.clone();
        for (i, m) in out.rows.iter_mut().enumerate() {
            if let Some(&line) = self.lines.0.get(i) {
                let t = line.saturating_sub(lines.0) as f64 / span;
                (0..3).for_each(|c| m.position_mm[c] -= t * drift_mm[c]);
            }
        }
        out
    }

    /// The first and last file lines of the rows, when the set was read from a file.
    pub fn line_span(&self) -> Option<(u64, u64)> {
        let first = self.lines.0.iter().min()?;
        let last = self.lines.0.iter().max()?;
        Some((*first, *last))
    }

    /// The setup of row `row` (0 without a `setup` column).
    pub fn setup_of(&self, row: usize) -> usize {
        self.row_setups.get(row).copied().unwrap_or(0)
    }

    /// The setups' labels by id (empty without a `setup` column).
    pub fn setup_names(&self) -> &[String] {
        &self.setup_names
    }

    /// The set with its targets named: `names[id]` is target `id`'s name (as a file wrote it).
    pub fn with_target_names(self, names: Vec<String>) -> Self {
        Self {
            target_names: names,
            ..self
        }
    }

    /// Target `id` as the file wrote it: its name, or the integer.
    pub fn target_name(&self, id: usize) -> String {
        self.target_names.get(id).cloned().unwrap_or_else(|| id.to_string())
    }

    /// N, the robot's number of joints (= number of `cmd_k` columns).
    pub fn joint_count(&self) -> usize {
        self.joint_count
    }

    /// All rows in file order.
    pub fn rows(&self) -> &[Measurement] {
        &self.rows
    }

    /// The rows, consuming the set.
    pub fn into_rows(self) -> Vec<Measurement> {
        self.rows
    }

    /// Experiments in order of first appearance, each with its rows in file order.
    pub fn experiments(&self) -> Vec<Experiment<'_>> {
        let mut index: HashMap<&str, usize> = HashMap::new();
        let mut experiments: Vec<Experiment<'_>> = Vec::new();
        for (row, m) in self.rows.iter().enumerate() {
            let line = self.line_of(row);
            // An experiment's rows usually follow each other: no lookup for those.
            let i = match experiments.last() {
                Some(last) if last.name == m.experiment => experiments.len() - 1,
                _ => *index.entry(&m.experiment).or_insert_with(|| {
                    experiments.push(Experiment {
                        name: &m.experiment,
                        moved_joint: m.moved_joint,
                        rows: Vec::new(),
                        lines: line.map(|l| (l, l)),
                    });
                    experiments.len() - 1
                }),
            };
            let e = &mut experiments[i];
            e.rows.push(m);
            if let (Some(l), Some((_, last))) = (line, e.lines.as_mut()) {
                *last = l;
            }
        }
        experiments
    }

    /// The experiment named `name`.
    pub fn experiment(&self, name: &str) -> Option<Experiment<'_>> {
        self.experiments().into_iter().find(|e| e.name == name)
    }
}

/// The first value of `m` that is NaN or infinite, with its column name (names are built
/// only then: this runs for every row of a file).
fn first_not_finite(m: &Measurement) -> Option<(String, f64)> {
    let all = m
        .position_mm
        .iter()
        .chain(&m.cmd)
        .chain([&m.payload_kg, &m.temperature_c]);
    let i = all.clone().position(|v| !v.is_finite())?;
    let value = all.copied().nth(i)?;
    let n = m.cmd.len();
    let column = match i {
        0..=2 => ["x_mm", "y_mm", "z_mm"][i].to_string(),
        _ if i < 3 + n => format!("cmd_{}", i - 2),
        _ if i == 3 + n => "payload_kg".into(),
        _ => "temperature_c".into(),
    };
    Some((column, value))
}

/// Checks the [`MeasurementSet`] invariants; the error carries the 0-based row index: the
/// first row, in order, that breaks one (a row's own fields are checked before its key).
fn validate(joint_count: usize, rows: &[Measurement]) -> Result<(), MeasurementSetError> {
    // Experiment name -> (index, moved joint); consecutive rows of one experiment reuse the
    // last lookup. The keys (experiment index, step, target, row) of the rows before the first
    // row with a problem of its own are sorted once for the duplicate check: no hashing per row.
    let mut moved: HashMap<&str, (usize, usize)> = HashMap::new();
    let mut last: Option<(&str, (usize, usize))> = None;
    let mut keys: Vec<(usize, usize, usize, usize)> = Vec::with_capacity(rows.len());
    let mut problem = None;
    for (row, m) in rows.iter().enumerate() {
        let (index, first) = match last {
            Some((name, entry)) if name == m.experiment => entry,
            _ => {
                let next = moved.len();
                let entry = *moved.entry(&m.experiment).or_insert((next, m.moved_joint));
                last = Some((&m.experiment, entry));
                entry
            }
        };
        if let Some(p) = row_problem(joint_count, m, first) {
            problem = Some(MeasurementSetError { row, problem: p });
            break;
        }
        keys.push((index, m.step, m.target, row));
    }
    keys.sort_unstable();
    // A key seen before: the error is at the earliest such row, naming the key's first row
    // (for three rows with one key, the window of the first two).
    let duplicate = keys
        .windows(2)
        .filter(|w| w[0].0 == w[1].0 && w[0].1 == w[1].1 && w[0].2 == w[1].2)
        .min_by_key(|w| w[1].3)
        .map(|w| MeasurementSetError {
            row: w[1].3,
            problem: RowProblem::DuplicateKey {
                experiment: rows[w[1].3].experiment.clone(),
                step: w[1].1,
                target: w[1].2,
                first_at: w[0].3 as u64,
            },
        });
    let differ = pose_commands_differ(rows, &keys);
    let earliest = [duplicate, differ].into_iter().flatten().min_by_key(|e| e.row);
    match earliest.or(problem) {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Row keys `(experiment index, step, target, row)` as [`validate`] sorts them.
type RowKey = (usize, usize, usize, usize);

/// The first row, in row order, whose commands differ from its pose's reading by more than
/// [`POSE_COMMAND_TOLERANCE`]; `keys` sorted, a pose's rows next to each other. A pose's reading
/// is the one most of its rows carry (the earliest row's on a tie), so the odd row is named.
fn pose_commands_differ(rows: &[Measurement], keys: &[RowKey]) -> Option<MeasurementSetError> {
    let differs = |a: usize, b: usize| {
        let (a, b) = (&rows[a].cmd, &rows[b].cmd);
        a.iter()
            .zip(b)
            .position(|(x, y)| (x - y).abs() > POSE_COMMAND_TOLERANCE)
    };
    keys.chunk_by(|a, b| a.0 == b.0 && a.1 == b.1)
        .filter(|pose| pose.len() > 1)
        .filter_map(|pose| {
            let agreeing = |r: usize| pose.iter().filter(|k| differs(r, k.3).is_none()).count();
            let reading = pose.iter().max_by_key(|k| (agreeing(k.3), std::cmp::Reverse(k.3)))?.3;
            let majority = 2 * agreeing(reading) > pose.len();
            let (row, k) = pose.iter().filter_map(|p| Some((p.3, differs(p.3, reading)?))).min()?;
            Some(MeasurementSetError {
                row,
                problem: RowProblem::PoseCommandsDiffer {
                    experiment: rows[row].experiment.clone(),
                    step: rows[row].step,
                    joint: k + 1,
                    value: rows[row].cmd[k],
                    reading: rows[reading].cmd[k],
                    reading_at: reading as u64,
                    majority,
                },
            })
        })
        .min_by_key(|e| e.row)
}

/// A target id seen in one row only of an experiment whose other steps (two or more) all see
/// one same set of targets, while the lone row's step sees that set but one: a mistyped id in
/// place of the missing one. A target seen at only some steps is normal (an instrument loses
/// sight of it); one seen once, exactly where another goes missing, is a typo.
#[derive(Clone, Debug, PartialEq)]
pub struct LoneTarget {
    /// The row (0-based, in the set).
    pub row: usize,
    /// Its experiment and step.
    pub experiment: String,
    /// Its step.
    pub step: usize,
    /// The lone id.
    pub target: usize,
    /// The targets every other step of the experiment sees.
    pub others: Vec<usize>,
    /// The one of them the lone row's step lacks.
    pub missing: usize,
}

impl MeasurementSet {
    /// The [`LoneTarget`]s of the set, in row order.
    pub fn lone_targets(&self) -> Vec<LoneTarget> {
        let mut by_experiment: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
        for (i, m) in self.rows.iter().enumerate() {
            by_experiment.entry(m.experiment.as_str()).or_default().push(i);
        }
        let mut out: Vec<LoneTarget> = by_experiment
            .values()
            .filter_map(|rows| self.lone_target_in(rows))
            .collect();
        out.sort_by_key(|l| l.row);
        out
    }

    /// The [`LoneTarget`] among `rows` (one experiment's), if any.
    fn lone_target_in(&self, rows: &[usize]) -> Option<LoneTarget> {
        let mut steps: BTreeMap<usize, std::collections::BTreeSet<usize>> = BTreeMap::new();
        let mut seen: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
        for &i in rows {
            let m = &self.rows[i];
            steps.entry(m.step).or_default().insert(m.target);
            seen.entry(m.target).or_default().push(i);
        }
        seen.values().filter(|r| r.len() == 1).find_map(|r| {
            let m = &self.rows[r[0]];
            let mut others = steps.iter().filter(|(s, _)| **s != m.step).map(|(_, t)| t);
            let first = others.next()?;
            let agree = steps.len() >= 3 && others.all(|t| t == first);
            let here: std::collections::BTreeSet<usize> =
                steps[&m.step].iter().copied().filter(|t| *t != m.target).collect();
            let missing: Vec<usize> = first.difference(&here).copied().collect();
            (agree && here.is_subset(first) && missing.len() == 1).then(|| LoneTarget {
                row: r[0],
                experiment: m.experiment.clone(),
                step: m.step,
                target: m.target,
                others: first.iter().copied().collect(),
                missing: missing[0],
            })
        })
    }
}

/// Whether `c` is a Unicode format character (general category Cf: the bidirectional
/// overrides and isolates such as U+202E, zero-width spaces and joiners, the byte-order mark,
/// the tag characters): invisible, and some reorder how the text around them is displayed, so
/// a label holding one does not read as it is written.
pub fn is_format_char(c: char) -> bool {
    matches!(
        c as u32,
        0xAD | 0x600..=0x605
            | 0x61C
            | 0x6DD
            | 0x70F
            | 0x890..=0x891
            | 0x8E2
            | 0x180E
            | 0x200B..=0x200F
            | 0x202A..=0x202E
            | 0x2060..=0x2064
            | 0x2066..=0x206F
            | 0xFEFF
            | 0xFFF9..=0xFFFB
            | 0x110BD
            | 0x110CD
            | 0x13430..=0x1343F
            | 0x1BCA0..=0x1BCA3
            | 0x1D173..=0x1D17A
            | 0xE0001
            | 0xE0020..=0xE007F
    )
}

/// Whether `label` is longer than [`MAX_LABEL_CHARS`] characters.
pub(crate) fn too_long(label: &str) -> bool {
    label.len() > MAX_LABEL_CHARS && label.chars().count() > MAX_LABEL_CHARS
}

/// A measured coordinate beyond this \[mm\] (10 km) is no instrument's.
const MAX_COORDINATE_MM: f64 = 1e7;

/// A command beyond this \[deg or mm\] is no joint's (2,800 turns, 1 km).
const MAX_COMMAND: f64 = 1e6;

/// A payload beyond this \[kg\] is no robot's: 10 t, over four times the heaviest industrial
/// arm's rated payload (2.3 t); larger values are slips (grams written as kg, a dummy).
pub const MAX_PAYLOAD_KG: f64 = 1e4;

/// The ambient temperatures a robot and its instrument are measured in \[deg C\]: -100 to 200,
/// beyond any workshop or climatic chamber (arms are rated for 0 to 45 deg C); outside, a value
/// is a slip (kelvin written as deg C reads 273 and more, a dummy).
pub const TEMPERATURE_RANGE_C: [f64; 2] = [-100.0, 200.0];

/// The range a measured coordinate `value_mm` is outside, in words; `None` within
/// [`MAX_COORDINATE_MM`].
pub(crate) fn coordinate_beyond(value_mm: f64) -> Option<&'static str> {
    (value_mm.abs() > MAX_COORDINATE_MM)
        .then_some("+-1e7 mm (10 km: farther than any instrument measures; coordinates in micrometres?)")
}

/// The range a command `value` (deg or mm) is outside, in words; `None` within
/// [`MAX_COMMAND`].
pub(crate) fn command_beyond(value: f64) -> Option<&'static str> {
    (value.abs() > MAX_COMMAND).then_some("+-1e6 (deg or mm: no joint turns or slides that far; a dummy value?)")
}

/// The first row of `rows` (a file's, as read) whose experiment id names a joint (`axis3`)
/// while its rows are free poses (`moved_joint = 0`), with the problem: a file's label and
/// its `moved_joint` disagree. Not a check of every set: a set made free poses on purpose
/// ([`MeasurementSet::every_row_a_free_pose`]) keeps its sweeps' names.
pub(crate) fn axis_id_of_free_poses(rows: &[Measurement]) -> Option<(usize, RowProblem)> {
    rows.iter().enumerate().find_map(|(row, m)| {
        let named = joint_named_by(&m.experiment).filter(|_| m.moved_joint == 0)?;
        Some((
            row,
            RowProblem::AxisIdOfFreePoses {
                experiment: m.experiment.clone(),
                named,
            },
        ))
    })
}

/// What is wrong with row `m` on its own (not its key), `first` being the joint its
/// experiment's first row moves.
fn row_problem(joint_count: usize, m: &Measurement, first: usize) -> Option<RowProblem> {
    if m.experiment.is_empty() || m.experiment.trim() != m.experiment {
        return Some(RowProblem::BadExperimentName {
            experiment: m.experiment.clone(),
        });
    }
    if too_long(&m.experiment) {
        return Some(RowProblem::LongExperimentName {
            experiment: m.experiment.clone(),
        });
    }
    if m.cmd.len() != joint_count {
        return Some(RowProblem::JointCount {
            found: m.cmd.len(),
            expected: joint_count,
        });
    }
    if let Some((column, value)) = first_not_finite(m) {
        return Some(RowProblem::NotFinite { column, value });
    }
    let axes = ["x_mm", "y_mm", "z_mm"];
    if let Some((axis, &value, expected)) = axes
        .iter()
        .zip(&m.position_mm)
        .find_map(|(axis, v)| Some((axis, v, coordinate_beyond(*v)?)))
    {
        return Some(RowProblem::OutOfRange {
            column: (*axis).into(),
            value,
            expected,
        });
    }
    if let Some((k, &value, expected)) = m
        .cmd
        .iter()
        .enumerate()
        .find_map(|(k, v)| Some((k, v, command_beyond(*v)?)))
    {
        return Some(RowProblem::OutOfRange {
            column: format!("cmd_{}", k + 1),
            value,
            expected,
        });
    }
    if let Some(p) = conditions_problem(m) {
        return Some(p);
    }
    if m.moved_joint > joint_count {
        return Some(RowProblem::MovedJointOutOfRange {
            value: m.moved_joint,
            joint_count,
        });
    }
    if let Some(named) = joint_named_by(&m.experiment).filter(|&k| !(1..=joint_count).contains(&k)) {
        return Some(RowProblem::NoSuchJoint {
            experiment: m.experiment.clone(),
            named,
            joint_count,
            moved_joint: m.moved_joint,
        });
    }
    (first != m.moved_joint).then(|| RowProblem::InconsistentMovedJoint {
        experiment: m.experiment.clone(),
        first,
        found: m.moved_joint,
    })
}

/// A payload or a temperature of `m` outside its physical range ([`MAX_PAYLOAD_KG`],
/// [`TEMPERATURE_RANGE_C`]).
fn conditions_problem(m: &Measurement) -> Option<RowProblem> {
    if m.payload_kg < 0.0 {
        return Some(RowProblem::OutOfRange {
            column: "payload_kg".into(),
            value: m.payload_kg,
            expected: "0 kg and above (a payload has no negative mass)",
        });
    }
    if m.payload_kg > MAX_PAYLOAD_KG {
        return Some(RowProblem::OutOfRange {
            column: "payload_kg".into(),
            value: m.payload_kg,
            expected: "0..=10000 kg (no robot carries more than 10 t; grams written as kg?)",
        });
    }
    let [coldest, hottest] = TEMPERATURE_RANGE_C;
    if !(coldest..=hottest).contains(&m.temperature_c) {
        return Some(RowProblem::OutOfRange {
            column: "temperature_c".into(),
            value: m.temperature_c,
            expected: "-100..=200 deg C (the ambient a robot is measured in; kelvin written as deg C?)",
        });
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(experiment: &str, moved_joint: usize, step: usize, target: usize) -> Measurement {
        Measurement {
            experiment: experiment.into(),
            moved_joint,
            step,
            target,
            position_mm: [1.0, 2.0, 3.0],
            cmd: vec![0.0; 2],
            payload_kg: 0.0,
            temperature_c: 20.0,
        }
    }

    #[test]
    fn groups_by_experiment_in_file_order() {
        let rows = vec![
            row("b", 2, 1, 0),
            row("a", 1, 0, 0),
            row("b", 2, 0, 1),
            row("b", 2, 0, 0),
        ];
        let set = MeasurementSet::new(2, rows).unwrap();
        let experiments = set.experiments();
        assert_eq!(experiments.iter().map(|e| e.name).collect::<Vec<_>>(), ["b", "a"]);
        let b = &experiments[0];
        assert_eq!(
            b.rows.iter().map(|m| (m.step, m.target)).collect::<Vec<_>>(),
            [(1, 0), (0, 1), (0, 0)]
        );
        assert_eq!(
            b.by_step_target().keys().copied().collect::<Vec<_>>(),
            [(0, 0), (0, 1), (1, 0)]
        );
        assert_eq!(b.by_step()[&0].iter().map(|m| m.target).collect::<Vec<_>>(), [0, 1]);
        assert_eq!(b.get(1, 0).map(|m| m.step), Some(1));
        assert!(b.get(1, 1).is_none());
    }

    /// A pose whose rows disagree on a command names the odd row when most rows agree, and says
    /// that either may be wrong when two rows disagree one against one.
    #[test]
    fn a_pose_without_a_majority_reading_does_not_blame_one_row() {
        let with_cmd = |target: usize, cmd: f64| Measurement {
            cmd: vec![cmd, 0.0],
            ..row("poses", 0, 0, target)
        };
        let e = MeasurementSet::new(2, vec![with_cmd(0, 7.5), with_cmd(1, -7.5)]).unwrap_err();
        assert!(matches!(
            e.problem,
            RowProblem::PoseCommandsDiffer { majority: false, .. }
        ));
        assert!(
            e.problem.to_string().contains("either row may be the wrong one"),
            "{}",
            e.problem
        );
        let e = MeasurementSet::new(2, vec![with_cmd(0, 7.5), with_cmd(1, -7.5), with_cmd(2, -7.5)]).unwrap_err();
        assert_eq!(e.row, 0);
        assert!(e.problem.to_string().contains("correct this row"), "{}", e.problem);
    }

    #[test]
    fn an_axis_id_names_its_joint_which_the_robot_must_have() {
        assert_eq!(joint_named_by("axis6"), Some(6));
        assert_eq!(joint_named_by("AXIS12"), Some(12));
        assert_eq!(joint_named_by("axis99999999999999999999999"), Some(usize::MAX));
        for other in ["axis", "axis6-2", "axis 6", "poses", "ax", "axis6b"] {
            assert_eq!(joint_named_by(other), None, "{other}");
        }
        let e = MeasurementSet::new(2, vec![row("a", 1, 0, 0), row("axis3", 2, 0, 0)]).unwrap_err();
        assert_eq!(e.row, 1);
        assert_eq!(
            e.problem,
            RowProblem::NoSuchJoint {
                experiment: "axis3".into(),
                named: 3,
                joint_count: 2,
                moved_joint: 2
            }
        );
        assert!(
            e.problem.to_string().ends_with("(its rows move joint 2: `axis2`)"),
            "{}",
            e.problem
        );
        assert!(MeasurementSet::new(2, vec![row("axis2", 2, 0, 0), row("axis0x", 1, 0, 0)]).is_ok());
    }

    #[test]
    fn set_rejects_duplicates_and_bad_joints() {
        let e = MeasurementSet::new(2, vec![row("a", 1, 0, 0), row("a", 1, 0, 0)]).unwrap_err();
        assert_eq!(e.row, 1);
        assert!(matches!(e.problem, RowProblem::DuplicateKey { first_at: 0, .. }));
        let e = MeasurementSet::new(2, vec![row("a", 3, 0, 0)]).unwrap_err();
        assert!(matches!(
            e.problem,
            RowProblem::MovedJointOutOfRange {
                value: 3,
                joint_count: 2
            }
        ));
        let e = MeasurementSet::new(2, vec![row("a", 1, 0, 0), row("a", 2, 1, 0)]).unwrap_err();
        assert!(matches!(
            e.problem,
            RowProblem::InconsistentMovedJoint { first: 1, found: 2, .. }
        ));
        let mut bad = row("a", 1, 0, 0);
        bad.position_mm[1] = f64::NAN;
        let e = MeasurementSet::new(2, vec![bad.clone()]).unwrap_err();
        assert_eq!(e.problem.column(), "y_mm");
        // The first row with a problem, in row order, whichever kind it is.
        let e = MeasurementSet::new(
            2,
            vec![row("a", 1, 0, 0), row("b", 1, 0, 0), row("a", 1, 0, 0), bad.clone()],
        )
        .unwrap_err();
        assert_eq!((e.row, e.problem.column().as_str()), (2, "experiment,step,target"));
        let e = MeasurementSet::new(2, vec![row("a", 1, 0, 0), bad, row("a", 1, 0, 0)]).unwrap_err();
        assert_eq!((e.row, e.problem.column().as_str()), (1, "y_mm"));
        let three = [1, 0, 1, 1].map(|target| row("a", 1, 0, target));
        let e = MeasurementSet::new(2, three.to_vec()).unwrap_err();
        assert_eq!(e.row, 2);
        assert!(matches!(
            e.problem,
            RowProblem::DuplicateKey {
                first_at: 0,
                target: 1,
                ..
            }
        ));
    }
}
