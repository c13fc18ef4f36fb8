//! Fits whose memory grows with the number of poses (the diagnosis, `calibrate --refine`, the
//! free-pose calibration) take at most a set number of a file's poses, evenly spaced through
//! it, so that a file of a million rows runs in bounded memory; the caller says how many it
//! left out. Every other row of the file is still read and used where the fit needs it (each
//! pose's approach directions come from the whole file's command history).

/// The poses the diagnosis fits at most by default (`diagnose --max-poses`): about 0.4 MB
/// each with the default noise-only replicas (16 x 32 draws), so ~400 MB.
pub const DIAGNOSIS_MAX_POSES: usize = 1000;

/// The free poses `calibrate --refine` and the free-pose calibration fit at most by default
/// (`calibrate --max-poses`).
pub const FIT_MAX_POSES: usize = 5000;

/// `items` (in their order) when there are at most `max` of them; else `max` of them, evenly
/// spaced: item `floor(i count / max)` for `i` in `0..max` (the first one always kept).
/// Deterministic: the same file gives the same selection.
pub fn evenly_spaced<T>(items: Vec<T>, max: usize) -> Vec<T> {
    let count = items.len();
    if count <= max {
        return items;
    }
    let mut keep = vec![false; count];
    for i in 0..max {
        // i < max < count: no overflow below 2^64 / count.
        keep[(i as u128 * count as u128 / max as u128) as usize] = true;
    }
    items
        .into_iter()
        .zip(keep)
        .filter_map(|(item, k)| k.then_some(item))
        .collect()
}

/// `max` of `items` (in their order; all of them when there are at most `max`) that visit as
/// many distinct configurations (`key` of an item) as `max` allows: the first visits of every
/// configuration first, then the second visits, and so on ([`evenly_spaced`] within the last
/// round that does not fit whole). A file that repeats a cycle of poses keeps every pose of
/// the cycle before any repeat of it, where evenly spaced items can fall on a few poses of the
/// cycle again and again (a stride of 13 over a cycle of 52 keeps 4); on distinct items it is
/// [`evenly_spaced`]. Deterministic: the same file gives the same selection.
pub fn spread_over_configurations<T, K: Eq + std::hash::Hash>(
    items: Vec<T>,
    max: usize,
    key: impl Fn(&T) -> K,
) -> Vec<T> {
    if items.len() <= max {
        return items;
    }
    // Each item's round: how many earlier items visit its configuration.
    let mut visits: std::collections::HashMap<K, usize> = std::collections::HashMap::new();
    let round: Vec<usize> = items
        .iter()
        .map(|item| {
            let seen = visits.entry(key(item)).or_insert(0);
            *seen += 1;
            *seen - 1
        })
        .collect();
    let mut per_round: Vec<usize> = Vec::new();
    for &r in &round {
        if per_round.len() <= r {
            per_round.resize(r + 1, 0);
        }
        per_round[r] += 1;
    }
    // The rounds kept whole, and how many of the next one fit.
    let mut left = max;
    let mut whole = 0;
    while whole < per_round.len() && per_round[whole] <= left {
        left -= per_round[whole];
        whole += 1;
    }
    let mut keep: Vec<bool> = round.iter().map(|&r| r < whole).collect();
    if whole < per_round.len() {
        let partial: Vec<usize> = (0..round.len()).filter(|&i| round[i] == whole).collect();
        for i in evenly_spaced(partial, left) {
            keep[i] = true;
        }
    }
    items
        .into_iter()
        .zip(keep)
        .filter_map(|(item, k)| k.then_some(item))
        .collect()
}

/// A pose's commands (file units) as its configuration's key: commands equal to 1e-6 are one
/// configuration (a revisit of a pose whose readings were rounded on export).
pub fn configuration_key(cmd: &[f64]) -> Vec<i64> {
    cmd.iter().map(|c| (c * 1e6).round() as i64).collect()
}

#[cfg(test)]
mod tests {
    use super::{evenly_spaced, spread_over_configurations};
    use proptest::prelude::*;
    use std::collections::HashSet;

    proptest! {
        /// The selection has `min(count, max)` items, in order, without repeats, the first
        /// kept; the gaps between kept items differ by at most one (a second path: the gap
        /// sizes counted, against `count / max` rounded both ways).
        #[test]
        fn evenly_spaced_keeps_max_items_with_even_gaps(count in 0usize..3000, max in 1usize..500) {
            let kept = evenly_spaced((0..count).collect::<Vec<_>>(), max);
            prop_assert_eq!(kept.len(), count.min(max));
            prop_assert!(kept.windows(2).all(|w| w[0] < w[1]));
            if count > 0 {
                prop_assert_eq!(kept[0], 0);
            }
            if count > max {
                let gaps: Vec<usize> = kept.windows(2).map(|w| w[1] - w[0]).collect();
                let (lo, hi) = (count / max, count.div_ceil(max));
                prop_assert!(gaps.iter().all(|&g| g == lo || g == hi), "gaps {:?} for {} of {}", gaps, max, count);
            }
        }

        /// The selection has `min(count, max)` items, in order, without repeats; it visits
        /// `min(configurations, max)` distinct configurations (a second path: counted on the
        /// selection); on distinct items it is `evenly_spaced`'s.
        #[test]
        fn spread_over_configurations_keeps_the_most_configurations(
            keys in proptest::collection::vec(0usize..40, 0..400),
            max in 1usize..120,
        ) {
            let items: Vec<(usize, usize)> = keys.iter().copied().enumerate().collect();
            let kept = spread_over_configurations(items.clone(), max, |&(_, k)| k);
            prop_assert_eq!(kept.len(), items.len().min(max));
            prop_assert!(kept.windows(2).all(|w| w[0].0 < w[1].0));
            let all: HashSet<usize> = keys.iter().copied().collect();
            let visited: HashSet<usize> = kept.iter().map(|&(_, k)| k).collect();
            prop_assert_eq!(visited.len(), all.len().min(max));
            let distinct: Vec<usize> = (0..keys.len()).collect();
            prop_assert_eq!(spread_over_configurations(distinct.clone(), max, |&i| i), evenly_spaced(distinct, max));
        }

        /// A cycle of 52 poses repeated: every pose of the cycle before any repeat.
        #[test]
        fn a_repeated_cycle_keeps_every_pose_of_it(cycles in 2usize..30, max in 52usize..200) {
            let items: Vec<usize> = (0..52 * cycles).collect();
            let kept = spread_over_configurations(items, max, |&i| i % 52);
            let visited: HashSet<usize> = kept.iter().map(|&i| i % 52).collect();
            prop_assert_eq!(visited.len(), 52);
        }
    }
}
