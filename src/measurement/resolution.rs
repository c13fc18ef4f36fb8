//! The resolution coordinates are written with: the step every value is a multiple of (a file
//! rounded to 0.01 mm) and the finest an instrument resolves, below which scatter is not
//! judged.

/// The finest step \[mm\] an instrument writes: a laser tracker's resolution. Scatter below it
/// is rounding of noise-free data, not the instrument's noise.
pub const INSTRUMENT_RESOLUTION_MM: f64 = 1e-3;

/// Steps \[mm\] values may be written rounded to, coarsest first: 1, 2 and 5 times the powers of
/// ten from 100 mm to 1 nm, and the inch's decimal fractions (25.4 mm to 0.254 um).
fn steps_mm() -> Vec<f64> {
    let decimal = (-6..=2).flat_map(|e| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(e)));
    let inch = (-5..=0).map(|e| 25.4 * 10f64.powi(e));
    let mut steps: Vec<f64> = decimal.chain(inch).filter(|&q| q <= 100.0).collect();
    steps.sort_by(|a, b| b.total_cmp(a));
    steps
}

/// Whether `value` is a multiple of `step` but for the error of reading and converting it
/// (a relative 1e-12, far below the finest step at a robot's size).
fn is_multiple(value: f64, step: f64) -> bool {
    ((value / step).round() * step - value).abs() <= 1e-12 * value.abs().max(1.0)
}

/// The coarsest step of `steps_mm` every one of `values_mm` is a multiple of: the step they
/// were written rounded to; `None` for values written finer than 1 nm (or none, or not finite).
pub fn written_step_mm(values_mm: impl Iterator<Item = f64> + Clone) -> Option<f64> {
    steps_mm()
        .into_iter()
        .find(|&q| values_mm.clone().all(|v| v.is_finite() && is_multiple(v, q)))
        .filter(|_| values_mm.clone().next().is_some())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values written with `printf`-style precision give that precision (one of them ends in 1
    /// at every precision, so that no coarser step of 2 or 5 fits); the same values in
    /// metres read back as millimetres (a conversion's rounding) still do; whole inches give
    /// 25.4 mm; values at full precision give none.
    #[test]
    fn written_steps_are_found_from_the_values() {
        let written = |decimals: usize, values: &[f64]| -> Vec<f64> {
            values
                .iter()
                .map(|v| format!("{v:.decimals$}").parse().unwrap())
                .collect()
        };
        let raw = [-3_142.298_731_4, 5_341.901_177_3, 1_111.111_111_1, 0.003_141_59, 811.5];
        for (decimals, step) in [(0, 1.0), (1, 0.1), (2, 0.01), (3, 1e-3), (4, 1e-4)] {
            let values = written(decimals, &raw);
            let found = written_step_mm(values.iter().copied()).unwrap();
            assert!((found / step - 1.0).abs() < 1e-12, "{decimals}: {found}");
            let via_metres: Vec<f64> = values.iter().map(|v| (v * 1e-3) * 1e3).collect();
            assert_eq!(written_step_mm(via_metres.iter().copied()), Some(found), "{decimals}");
        }
        let inches: Vec<f64> = [-124.0, 210.0, 3.0].iter().map(|i| i * 25.4).collect();
        assert_eq!(written_step_mm(inches.iter().copied()), Some(25.4));
        assert_eq!(written_step_mm(raw.iter().copied()), None);
        assert_eq!(written_step_mm(std::iter::empty()), None);
        assert_eq!(written_step_mm([1.0, f64::NAN].iter().copied()), None);
    }
}
