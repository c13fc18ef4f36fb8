//! Writing a measurement set and reading it back is the identity, bit for bit.

use axiscal::measurement::{Measurement, MeasurementSet, read_measurements, write_measurements};
use proptest::prelude::*;
use std::collections::{HashMap, HashSet};

/// Any finite f64, including subnormals and signed zeros.
fn finite() -> impl Strategy<Value = f64> {
    use proptest::num::f64::{NEGATIVE, NORMAL, POSITIVE, SUBNORMAL, ZERO};
    POSITIVE | NEGATIVE | NORMAL | SUBNORMAL | ZERO
}

/// Any finite f64 within `+-max` (the reader's range for coordinates and commands), by the
/// remainder, which keeps every bit pattern's variety: subnormals, signed zeros, long mantissas.
fn finite_within(max: f64) -> impl Strategy<Value = f64> {
    finite().prop_map(move |v| v % max)
}

/// Experiment ids that need quoting (commas, quotes, new lines, a leading `#`).
fn experiment_name() -> impl Strategy<Value = String> {
    "[#a-z\",][a-zA-Z0-9_#,\" \n-]{0,8}[a-z#]"
}

type RowSeed = (usize, usize, usize, [f64; 3], Vec<f64>, f64, f64);

fn measurement_set() -> impl Strategy<Value = MeasurementSet> {
    (1usize..=7).prop_flat_map(|n| {
        let row = (
            0usize..4,
            0usize..6,
            0usize..3,
            // Coordinates within +-1e7 mm, commands within +-1e6 (both checked).
            [finite_within(1e7), finite_within(1e7), finite_within(1e7)],
            prop::collection::vec(finite_within(1e6), n),
            // Payloads and temperatures within their physical ranges (both checked).
            finite_within(axiscal::measurement::MAX_PAYLOAD_KG).prop_map(f64::abs),
            {
                let [coldest, hottest] = axiscal::measurement::TEMPERATURE_RANGE_C;
                finite_within((hottest - coldest) / 2.0).prop_map(move |t| t + (hottest + coldest) / 2.0)
            },
        );
        (
            Just(n),
            prop::collection::vec(experiment_name(), 4),
            prop::collection::vec(0..=n, 4),
            prop::collection::vec(row, 1..24),
        )
            .prop_map(
                |(n, names, moved, seeds): (usize, Vec<String>, Vec<usize>, Vec<RowSeed>)| {
                    let mut seen = HashSet::new();
                    // One pose's rows share its commands (the first row's).
                    let mut pose_cmd: HashMap<(String, usize), Vec<f64>> = HashMap::new();
                    let rows = seeds
                        .into_iter()
                        .filter(|(e, step, target, ..)| seen.insert((names[*e].clone(), *step, *target)))
                        .map(|(e, step, target, position_mm, cmd, payload_kg, temperature_c)| {
                            let cmd = pose_cmd.entry((names[e].clone(), step)).or_insert(cmd).clone();
                            (e, step, target, position_mm, cmd, payload_kg, temperature_c)
                        })
                        .map(
                            |(e, step, target, position_mm, cmd, payload_kg, temperature_c)| Measurement {
                                experiment: names[e].clone(),
                                // Ids may coincide: the first index of the id fixes the moved joint.
                                moved_joint: moved[names.iter().position(|m| *m == names[e]).unwrap_or(e)],
                                step,
                                target,
                                position_mm,
                                cmd,
                                payload_kg,
                                temperature_c,
                            },
                        )
                        .collect();
                    MeasurementSet::new(n, rows).expect("generated set is valid")
                },
            )
    })
}

fn bits(m: &Measurement) -> Vec<u64> {
    m.position_mm
        .iter()
        .chain(&m.cmd)
        .chain([&m.payload_kg, &m.temperature_c])
        .map(|v| v.to_bits())
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn write_then_read_is_the_identity(set in measurement_set()) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("measurements.csv");
        write_measurements(&path, &set, false).unwrap();
        let back = read_measurements(&path, Some(set.joint_count())).unwrap();
        prop_assert_eq!(back.joint_count(), set.joint_count());
        prop_assert_eq!(back.rows().len(), set.rows().len());
        for (a, b) in set.rows().iter().zip(back.rows()) {
            prop_assert_eq!(&a.experiment, &b.experiment);
            prop_assert_eq!((a.moved_joint, a.step, a.target), (b.moved_joint, b.step, b.target));
            prop_assert_eq!(bits(a), bits(b));
        }
        let inferred = read_measurements(&path, None).unwrap();
        prop_assert_eq!(inferred.joint_count(), set.joint_count());
    }
}
