//! Shared by the benchmarks that print a ratio to an in-run baseline.

use std::time::Instant;

mod allocator;

/// Whether this is `cargo bench` (criterion's `--bench` flag) rather than `cargo test
/// --all-targets` (`make test`), which runs every benchmark once in a debug build as a smoke
/// test.
pub fn is_cargo_bench() -> bool {
    std::env::args().any(|a| a == "--bench")
}

/// Seconds per call of a baseline and of the measured work, each the median over `runs`
/// interleaved timings (a batch of `baseline_batch` baseline calls, then `measured_batch`
/// measured calls, and so on): interleaving makes a loaded machine slow both sides alike, so
/// their ratio moves far less than either time. Outside `cargo bench` one call of each, as a
/// smoke test.
pub fn interleaved_medians(
    runs: usize,
    (baseline_batch, baseline): (usize, &dyn Fn()),
    (measured_batch, measured): (usize, &dyn Fn()),
) -> (f64, f64) {
    let (runs, baseline_batch, measured_batch) = if is_cargo_bench() {
        (runs, baseline_batch, measured_batch)
    } else {
        (1, 1, 1)
    };
    let time = |f: &dyn Fn(), n: usize| {
        let start = Instant::now();
        for _ in 0..n {
            f();
        }
        start.elapsed().as_secs_f64() / n as f64
    };
    let (mut base, mut full) = (Vec::with_capacity(runs), Vec::with_capacity(runs));
    for _ in 0..runs {
        base.push(time(baseline, baseline_batch));
        full.push(time(measured, measured_batch));
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    (median(&mut base), median(&mut full))
}
