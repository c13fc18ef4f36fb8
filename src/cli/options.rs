//! Numeric options: a value parser that refuses a number outside its range and says the range,
//! and the worker-thread option shared by the commands that run in parallel.

use anyhow::{Context, Result, bail};
use axiscal::presets::Kind;
use clap::builder::TypedValueParser;
use std::ffi::OsStr;
use std::fmt::Display;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// A number in `min..=max` (or `min < x` when `min_open`), as a clap value parser whose error
/// states the range and what the option means.
#[derive(Clone, Copy, Debug)]
pub struct InRange<T: 'static> {
    /// The smallest value (excluded when `min_open`).
    pub min: T,
    /// The largest value.
    pub max: T,
    /// Whether `min` itself is refused (e.g. a noise level must be above 0).
    pub min_open: bool,
    /// The unit, for the message (`mm`, `rad`, or empty).
    pub unit: &'static str,
}

impl<T: Copy> InRange<T> {
    /// `min..=max`.
    pub const fn closed(min: T, max: T, unit: &'static str) -> Self {
        InRange {
            min,
            max,
            min_open: false,
            unit,
        }
    }

    /// `min < x <= max`.
    pub const fn above(min: T, max: T, unit: &'static str) -> Self {
        InRange {
            min,
            max,
            min_open: true,
            unit,
        }
    }
}

impl<T: Display + Copy> InRange<T> {
    /// The range in words, e.g. `in 1..=100000` or `above 0 and at most 100 mm`.
    pub fn describe(&self) -> String {
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        if self.min_open {
            format!("above {} and at most {}{unit}", self.min, self.max)
        } else {
            format!("in {}..={}{unit}", self.min, self.max)
        }
    }
}

impl<T> InRange<T>
where
    T: FromStr + PartialOrd + Display + Copy,
{
    /// Why `text` does not parse as a `T`: a number of another kind (negative or fractional for a
    /// count) is out of range or not whole; anything else is not a number.
    fn not_parsed(&self, text: &str) -> String {
        let written = axiscal::csv_lines::shown_cell(text.trim());
        let why = match text.trim().parse::<f64>() {
            Ok(v) if v.is_finite() && v.fract() == 0.0 => "is out of range",
            Ok(v) if v.is_finite() => "is not a whole number",
            _ => "is not a number",
        };
        format!("`{written}` {why}; must be {}", self.describe())
    }

    /// Parses `text` and checks the range; the error states the range.
    pub fn check(&self, text: &str) -> Result<T, String> {
        let value: T = text.trim().parse().map_err(|_| self.not_parsed(text))?;
        let low_ok = if self.min_open {
            value > self.min
        } else {
            value >= self.min
        };
        // NaN fails both comparisons.
        if !(low_ok && value <= self.max) {
            let written = axiscal::csv_lines::shown_cell(text.trim());
            return Err(format!("{written} is out of range; must be {}", self.describe()));
        }
        Ok(value)
    }
}

impl<T> TypedValueParser for InRange<T>
where
    T: FromStr + PartialOrd + Display + Copy + Send + Sync + 'static,
{
    type Value = T;

    fn parse_ref(&self, cmd: &clap::Command, arg: Option<&clap::Arg>, value: &OsStr) -> Result<T, clap::Error> {
        let text = value.to_string_lossy();
        self.check(&text).map_err(|reason| {
            let name = arg.map_or_else(|| "value".to_owned(), |a| format!("--{}", a.get_id()));
            clap::Error::raw(
                clap::error::ErrorKind::ValueValidation,
                format!("invalid value for {}: {reason}\n", name.replace('_', "-")),
            )
            .with_cmd(cmd)
        })
    }
}

/// A random seed: any whole number from 0 to 2^64 - 1.
pub const SEED: InRange<u64> = InRange::closed(0, u64::MAX, "");

/// A measurement noise level, 3-D RMS (mm): in range, and no finer than an instrument
/// ([`axiscal::harness::scenario::units::noise_slip`], the scenario file's check: a noise in metres).
pub const NOISE_MM: NoiseMm = NoiseMm(InRange::above(
    0.0,
    axiscal::calibration::procedure::MAX_NOISE_RMS_3D_MM,
    "mm",
));

/// The value parser of [`NOISE_MM`].
#[derive(Clone, Copy, Debug)]
pub struct NoiseMm(pub InRange<f64>);

impl TypedValueParser for NoiseMm {
    type Value = f64;

    fn parse_ref(&self, cmd: &clap::Command, arg: Option<&clap::Arg>, value: &OsStr) -> Result<f64, clap::Error> {
        let mm = self.0.parse_ref(cmd, arg, value)?;
        let Some(why) = axiscal::harness::scenario::units::noise_slip(mm) else {
            return Ok(mm);
        };
        let name = arg.map_or_else(|| "value".to_owned(), |a| format!("--{}", a.get_id()));
        Err(clap::Error::raw(
            clap::error::ErrorKind::ValueValidation,
            format!("invalid value for {}: {why}\n", name.replace('_', "-")),
        )
        .with_cmd(cmd))
    }
}

/// A joint's repeatability, 1-sigma (rad), as the description's `repeatability_sigma`.
pub const REPEATABILITY_RAD: InRange<f64> = InRange::closed(0.0, axiscal::robot::MAX_REPEATABILITY_SIGMA, "rad");

/// Joint values within this of each other hold a joint still (deg or mm).
pub const STILL_TOLERANCE: InRange<f64> = InRange::closed(0.0, 10.0, "deg or mm");

/// Worker threads: 1 to this many.
pub const MAX_THREADS: usize = 1024;
/// `--threads`' range.
pub const THREADS: InRange<usize> = InRange::closed(1, MAX_THREADS, "");

/// Caps `RAYON_NUM_THREADS` (which rayon reads for every pool built without a count) at
/// [`MAX_THREADS`], as `--threads` is, with `--threads`' warning beyond 4 threads per core: a
/// count of 20,000 held a four-trial run for more than a minute and a gigabyte. Called at the
/// start of `main`, before any thread exists (setting the environment is sound only then).
pub fn cap_rayon_threads_from_environment() {
    let Some(n) = std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|v| v.trim().parse::<usize>().ok())
    else {
        return;
    };
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    if n > MAX_THREADS {
        eprintln!("warning: RAYON_NUM_THREADS={n}: capped at {MAX_THREADS} worker threads, the most `--threads` takes");
        // SAFETY: no other thread exists yet (`main` has only set its panic hook), so nothing
        // reads the environment while it changes.
        unsafe { std::env::set_var("RAYON_NUM_THREADS", MAX_THREADS.to_string()) };
    } else if n > 4 * cores {
        eprintln!(
            "warning: RAYON_NUM_THREADS={n} on {cores} core(s): more than 4 threads per core only costs start-up time \
             and memory (results are the same for any count)"
        );
    }
}

/// A rayon pool of `threads` workers (default: one per core), with a warning when the count is
/// far beyond the cores (it only adds start-up time and memory; results do not depend on it).
pub fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if let Some(n) = threads {
        if n == 0 || n > MAX_THREADS {
            bail!("--threads {n}: must be {}", THREADS.describe());
        }
        if n > 4 * cores {
            eprintln!(
                "warning: --threads {n} on {cores} core(s): more than 4 threads per core only costs start-up time and \
                 memory (results are the same for any count)"
            );
        }
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .context("building the thread pool")
}

/// A file on the command line: an existing file, or the name of a shipped one of the
/// `accepted` kinds (`axiscal::presets`). The error lists those kinds' shipped names.
pub fn shipped_or_file(text: &str, accepted: &[Kind]) -> Result<PathBuf, String> {
    axiscal::presets::resolve(Path::new(text), accepted).map_err(|e| e.to_string())
}

/// A URDF robot name as ROS takes it: a letter or `_`, then letters, digits, `_` and `/` (at
/// most 100): written into XML attributes unescaped, so nothing that would break them.
pub fn ros_robot_name(text: &str) -> Result<String, String> {
    let mut chars = text.chars();
    let first_ok = chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_');
    if first_ok && text.len() <= 100 && chars.all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '/') {
        return Ok(text.to_string());
    }
    Err(format!(
        "`{}` is not a ROS name: a letter or `_`, then letters, digits, `_` and `/` (at most 100), e.g. `my_robot`",
        axiscal::csv_lines::shown_cell(text)
    ))
}

/// The value parser of a file on the command line that may also be a shipped file's name
/// ([`shipped_or_file`]) of the kinds it holds. A path that is not UTF-8 (a Latin-1 file name)
/// is taken as the system gives it: it can only name a file, since every shipped name is ASCII.
#[derive(Clone, Copy, Debug)]
pub struct ShippedOrFile(pub &'static [Kind]);

impl TypedValueParser for ShippedOrFile {
    type Value = PathBuf;

    fn parse_ref(&self, cmd: &clap::Command, arg: Option<&clap::Arg>, value: &OsStr) -> Result<PathBuf, clap::Error> {
        let kinds = self.0;
        if value.to_str().is_some() {
            return (move |text: &str| shipped_or_file(text, kinds)).parse_ref(cmd, arg, value);
        }
        axiscal::presets::resolve(Path::new(value), kinds).map_err(|e| {
            let name = arg.map_or_else(|| "value".to_owned(), ToString::to_string);
            clap::Error::raw(
                clap::error::ErrorKind::ValueValidation,
                format!("invalid value '{}' for '{name}': {e}\n", value.to_string_lossy()),
            )
            .with_cmd(cmd)
        })
    }
}

/// A robot description on the command line (`asea-irb6l`).
pub const ROBOT_FILE: ShippedOrFile = ShippedOrFile(&[Kind::Description]);

/// A simulated robot's truth: a truth model, or a description (its nominal model).
pub const TRUTH_FILE: ShippedOrFile = ShippedOrFile(&[Kind::Truth, Kind::Description]);

/// An axis-experiment plan (`asea-irb6l-table1-plan`).
pub const PLAN_FILE: ShippedOrFile = ShippedOrFile(&[Kind::Plan]);

/// The shipped manufacturing errors a default truth is drawn with.
pub const PERTURBATION_FILE: ShippedOrFile = ShippedOrFile(&[Kind::Perturbation]);

/// A scenario on the command line: an existing file or a shipped scenario's name (`paper`).
pub const SCENARIO_FILE: ShippedOrFile = ShippedOrFile(&[Kind::Scenario]);

/// Human-readable duration of `seconds` (`45 s`, `3.2 h`, `12 years`).
pub fn duration_words(seconds: f64) -> String {
    const HOUR: f64 = 3600.0;
    const DAY: f64 = 24.0 * HOUR;
    const YEAR: f64 = 365.25 * DAY;
    if seconds < 120.0 {
        format!("{seconds:.0} s")
    } else if seconds < 2.0 * HOUR {
        format!("{:.0} min", seconds / 60.0)
    } else if seconds < 2.0 * DAY {
        format!("{:.1} h", seconds / HOUR)
    } else if seconds < YEAR {
        format!("{:.0} days", seconds / DAY)
    } else {
        format!("{:.3e} years", seconds / YEAR)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_refuse_outside_values_and_say_the_range() {
        let p = InRange::above(0.0, 0.5, "");
        assert!(p.check("0").unwrap_err().contains("above 0 and at most 0.5"));
        assert!(p.check("NaN").is_err());
        assert!(p.check("1.5").is_err());
        assert!(p.check("x").unwrap_err().contains("not a number"));
        assert_eq!(p.check("0.01"), Ok(0.01));
        let n = InRange::closed(1usize, 10, "");
        assert!(n.check("0").unwrap_err().contains("in 1..=10"));
        assert_eq!(n.check("10"), Ok(10));
    }

    #[test]
    fn durations_read_naturally() {
        assert_eq!(duration_words(5.0), "5 s");
        assert_eq!(duration_words(600.0), "10 min");
        assert_eq!(duration_words(36000.0), "10.0 h");
        assert!(duration_words(1e12).ends_with("years"));
    }
}
