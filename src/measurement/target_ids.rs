//! Tool target ids in the wrong order: the targets sit rigidly on the tool, so in every free
//! pose their mutual distances are the description's (`[tool] targets_mm`) up to the noise. A
//! pose whose distances miss the description's but match them with the ids in another order
//! has its ids swapped (a marker column or a MAT variable given in another order). The noise of
//! a distance is the poses' own scatter of it (1.4826 times the median absolute deviation, which
//! the swapped poses do not move while they are fewer than half), and each pose's test is the
//! chi-square of its distances' misses at [`TARGET_ID_FALSE_ALARM`] over the file's poses.
//!
//! Labellings a symmetric target set leaves with the same distances (two equal sides) are not
//! told apart here: the free-pose fit's tool frame does that
//! (`crate::calibration::free_pose::slip::mirrored_targets`).

use super::MeasurementSet;
use crate::numerics::stats::{chi_square_quantile, median_and_robust_sigma};
use std::collections::BTreeMap;

/// The false-alarm rate of the test over a clean file's poses (Bonferroni): once in ten
/// thousand files.
pub const TARGET_ID_FALSE_ALARM: f64 = 1e-4;

/// Tool targets tried in every order at most (24 orders).
const MAX_TARGETS: usize = 4;

/// The fewest poses whose scatter gives a distance's noise.
const MIN_POSES: usize = 3;

/// Free poses whose tool target ids are in another order than the description's.
#[derive(Clone, Debug, PartialEq)]
pub struct SwappedTargetIds {
    /// The data's target ids, ascending.
    pub ids: Vec<usize>,
    /// The orders the poses' distances match, best first (two when the targets' distances are
    /// symmetric: an order and its mirror image): `order[k]` the description's target the
    /// data's id `ids[k]` is.
    pub orders: Vec<Vec<usize>>,
    /// The file lines of the first row of each such pose (where known).
    pub lines: Vec<u64>,
    /// Poses in this order.
    pub poses: usize,
    /// Poses tested.
    pub tested: usize,
    /// The noise of a distance \[mm\] (the poses' scatter).
    pub sigma_mm: f64,
}

impl SwappedTargetIds {
    /// "0 is 1, 1 is 0": each id moved by `order` and the description's target it is.
    pub fn moved(&self, order: &[usize]) -> String {
        let moved: Vec<String> = self
            .ids
            .iter()
            .zip(order)
            .filter(|(a, b)| a != b)
            .map(|(a, b)| format!("{a} is {b}"))
            .collect();
        moved.join(", ")
    }
}

/// One pose's targets: id -> point \[mm\], and its first row.
type Pose = (BTreeMap<usize, [f64; 3]>, usize);

/// The free poses (`moved_joint = 0`) of `set` with at least two of the `described` targets.
fn poses(set: &MeasurementSet, described: usize) -> Vec<Pose> {
    let mut by_pose: BTreeMap<(&str, usize), Pose> = BTreeMap::new();
    for (i, m) in set.rows().iter().enumerate() {
        if m.moved_joint != 0 {
            continue;
        }
        let entry = by_pose
            .entry((m.experiment.as_str(), m.step))
            .or_insert_with(|| (BTreeMap::new(), i));
        entry.0.insert(m.target, m.position_mm);
    }
    let mut out: Vec<Pose> = by_pose
        .into_values()
        .filter(|(p, _)| p.len() >= 2 && p.keys().all(|&id| id < described))
        .collect();
    out.sort_by_key(|p| p.1);
    out
}

fn distance(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The noise of a distance \[mm\]: the root mean square over the pairs of ids of their
/// distances' scatter over the poses (module docs); `None` with fewer than [`MIN_POSES`] poses
/// of a pair.
fn distance_sigma(poses: &[Pose], ids: &[usize]) -> Option<f64> {
    let mut variances = Vec::new();
    for (k, a) in ids.iter().enumerate() {
        for b in &ids[k + 1..] {
            let d: Vec<f64> = poses
                .iter()
                .filter_map(|(p, _)| Some(distance(p.get(a)?, p.get(b)?)))
                .collect();
            if d.len() < MIN_POSES {
                continue;
            }
            variances.push(median_and_robust_sigma(&d).1.powi(2));
        }
    }
    (!variances.is_empty()).then(|| (variances.iter().sum::<f64>() / variances.len() as f64).sqrt())
}

/// Every order of `ids`.
fn orders(ids: &[usize]) -> Vec<Vec<usize>> {
    fn go(v: &mut Vec<usize>, from: usize, out: &mut Vec<Vec<usize>>) {
        if from == v.len() {
            out.push(v.clone());
            return;
        }
        for i in from..v.len() {
            v.swap(from, i);
            go(v, from + 1, out);
            v.swap(from, i);
        }
    }
    let mut out = Vec::new();
    go(&mut ids.to_vec(), 0, &mut out);
    out
}

/// The chi-square of a pose's distances against the description's `described` \[mm\] with the
/// data's ids `ids` read as `order`, and its degrees of freedom.
fn misfit(
    pose: &BTreeMap<usize, [f64; 3]>,
    ids: &[usize],
    order: &[usize],
    described: &[[f64; 3]],
    sigma: f64,
) -> (f64, usize) {
    let mut chi2 = 0.0;
    let mut dof = 0;
    for (k, a) in ids.iter().enumerate() {
        for (l, b) in ids.iter().enumerate().skip(k + 1) {
            let (Some(pa), Some(pb)) = (pose.get(a), pose.get(b)) else {
                continue;
            };
            let expected = distance(&described[order[k]], &described[order[l]]);
            chi2 += ((distance(pa, pb) - expected) / sigma).powi(2);
            dof += 1;
        }
    }
    (chi2, dof)
}

/// The free poses of `set` whose target ids are in another order than the description's
/// targets `described` \[mm\] (module docs), grouped by the order they are in.
pub fn swapped_target_ids(set: &MeasurementSet, described: &[[f64; 3]]) -> Vec<SwappedTargetIds> {
    let poses = poses(set, described.len());
    let mut ids: Vec<usize> = poses.iter().flat_map(|(p, _)| p.keys().copied()).collect();
    ids.sort_unstable();
    ids.dedup();
    if ids.len() < 3 || ids.len() > MAX_TARGETS || poses.len() < MIN_POSES {
        return Vec::new();
    }
    let Some(sigma) = distance_sigma(&poses, &ids).filter(|s| *s > 0.0) else {
        return Vec::new();
    };
    let alpha = TARGET_ID_FALSE_ALARM / poses.len() as f64;
    let all = orders(&ids);
    let mut found: BTreeMap<Vec<Vec<usize>>, Vec<usize>> = BTreeMap::new();
    for (pose, first) in &poses {
        let (written, dof) = misfit(pose, &ids, &ids, described, sigma);
        let bound = chi_square_quantile(1.0 - alpha, dof as f64);
        if written <= bound {
            continue;
        }
        let mut matching: Vec<(f64, &Vec<usize>)> = all
            .iter()
            .map(|o| (misfit(pose, &ids, o, described, sigma).0, o))
            .filter(|(chi2, o)| *chi2 <= bound && **o != ids)
            .collect();
        matching.sort_by(|a, b| a.0.total_cmp(&b.0).then_with(|| a.1.cmp(b.1)));
        if !matching.is_empty() {
            let mut orders: Vec<Vec<usize>> = matching.into_iter().map(|(_, o)| o.clone()).collect();
            orders.sort();
            found.entry(orders).or_default().push(*first);
        }
    }
    found
        .into_iter()
        .map(|(orders, rows)| SwappedTargetIds {
            ids: ids.clone(),
            orders,
            lines: rows.iter().filter_map(|&r| set.line_of(r)).collect(),
            poses: rows.len(),
            tested: poses.len(),
            sigma_mm: sigma,
        })
        .collect()
}
