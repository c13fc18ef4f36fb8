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

#[cfg(test)]
mod tests {
    use super::evenly_spaced;
    use proptest::prelude::*;

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
    }
}
