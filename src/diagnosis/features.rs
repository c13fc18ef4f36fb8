//! Per-feature `where` entries: the baseline's held-out residual in bins of a workspace
//! feature (reach, gravity torque, approach direction, joint angle, payload, temperature)
//! against the same bins of the noise-only replicas, so a gap that lives in one part of the
//! workspace shows there (module docs of [`crate::diagnosis`], step 5).

use super::{FeatureContrast, Pose, Prepared, WhereEntry, split};
use crate::numerics::stats::{QuantileMethod, mean, quantile};
use nalgebra::DMatrix;

/// Bins of a continuous feature: terciles of its held-out values.
const TERCILES: [&str; 3] = ["low", "mid", "high"];

/// Smallest number of held-out poses in a bin worth reporting.
const MIN_BIN_POSES: usize = 3;

/// One bin of a feature over the held-out poses.
struct Bin {
    label: &'static str,
    /// Observed SSR \[m^2\].
    observed: f64,
    /// SSR of every null sample \[m^2\].
    null: Vec<f64>,
    /// Targets in the bin.
    targets: f64,
}

/// One feature: its name, the joint it belongs to, and per held-out pose its bin label.
struct Feature {
    name: String,
    joint: Option<usize>,
    bins: Vec<Option<&'static str>>,
}

/// Tercile labels of `values` (`None` for a pose without a value); no bins when the values do
/// not vary.
fn terciles(values: &[Option<f64>]) -> Option<Vec<Option<&'static str>>> {
    let mut sorted: Vec<f64> = values.iter().flatten().copied().collect();
    sorted.sort_by(f64::total_cmp);
    let (first, last) = (*sorted.first()?, *sorted.last()?);
    if last - first <= 1e-9 * first.abs().max(last.abs()).max(1.0) {
        return None;
    }
    // The largest value of the lowest third and of the lowest two thirds.
    let n = sorted.len();
    let (a, b) = (sorted[n.div_ceil(3) - 1], sorted[(2 * n).div_ceil(3) - 1]);
    Some(
        values
            .iter()
            .map(|v| {
                v.map(|v| {
                    if v <= a {
                        TERCILES[0]
                    } else if v <= b {
                        TERCILES[1]
                    } else {
                        TERCILES[2]
                    }
                })
            })
            .collect(),
    )
}

fn features(prep: &Prepared, held: &[&Pose]) -> Vec<Feature> {
    let per_pose: Vec<_> = held.iter().map(|p| prep.predictor.pose_features(p)).collect();
    let dof = prep.predictor.dof();
    let mut out = Vec::new();
    let mut continuous = |name: String, joint: Option<usize>, values: Vec<Option<f64>>| {
        if let Some(bins) = terciles(&values) {
            out.push(Feature { name, joint, bins });
        }
    };
    continuous(
        "reach".into(),
        None,
        per_pose.iter().map(|f| f.as_ref().map(|f| f.reach_m)).collect(),
    );
    for k in 0..dof {
        continuous(
            format!("gravity_torque_{}", k + 1),
            Some(k + 1),
            per_pose
                .iter()
                .map(|f| f.as_ref().map(|f| f.gravity_torque_nm[k].abs()))
                .collect(),
        );
        continuous(
            format!("joint_angle_{}", k + 1),
            Some(k + 1),
            per_pose.iter().map(|f| f.as_ref().map(|f| f.q[k])).collect(),
        );
    }
    continuous(
        "payload".into(),
        None,
        held.iter().map(|p| Some(p.payload_kg)).collect(),
    );
    continuous(
        "temperature".into(),
        None,
        held.iter().map(|p| Some(p.temperature_c)).collect(),
    );
    for k in 0..dof {
        let bins: Vec<_> = held
            .iter()
            .map(|p| match p.approach[k] {
                a if a > 0.0 => Some("positive"),
                a if a < 0.0 => Some("negative"),
                _ => None,
            })
            .collect();
        if bins.contains(&Some("positive")) && bins.contains(&Some("negative")) {
            out.push(Feature {
                name: format!("approach_{}", k + 1),
                joint: Some(k + 1),
                bins,
            });
        }
    }
    out
}

/// Held-out residual excess per workspace-feature bin, and per feature the contrast between
/// its bins with its noise-only threshold. For every feature and bin with at least
/// [`MIN_BIN_POSES`] held-out poses: the baseline's held-out residual RMS over those poses
/// against the noise-only replicas' (mean over the null samples, in variance). A feature's
/// contrast is its largest bin ratio over its smallest (1 when the gap is the same
/// everywhere); the same contrast of every null sample (each bin against the null mean) gives
/// its `1 - false_alarm` quantile, so a gap that depends on the feature stands out even when
/// every bin exceeds noise.
/// `(r_obs, r_null)` are the observation's and the null samples' held-out residuals after the
/// baseline refit.
pub(super) fn feature_entries(
    prep: &Prepared,
    (r_obs, r_null): (&DMatrix<f64>, &DMatrix<f64>),
    false_alarm: f64,
) -> (Vec<WhereEntry>, Vec<FeatureContrast>) {
    let (_, held) = split(&prep.poses);
    // Residual rows of every held-out pose (3 per target, in pose order).
    let mut rows = Vec::with_capacity(held.len());
    let mut start = 0;
    for p in &held {
        let n = 3 * p.targets.len();
        rows.push(start..start + n);
        start += n;
    }
    let mut entries = Vec::new();
    let mut contrasts = Vec::new();
    for f in features(prep, &held) {
        let mut labels: Vec<&str> = f.bins.iter().flatten().copied().collect();
        labels.sort_unstable();
        labels.dedup();
        let mut bins: Vec<Bin> = Vec::new();
        for label in labels {
            let poses: Vec<usize> = (0..held.len()).filter(|&i| f.bins[i] == Some(label)).collect();
            if poses.len() < MIN_BIN_POSES {
                continue;
            }
            let ssr = |m: &DMatrix<f64>, c: usize| -> f64 {
                poses
                    .iter()
                    .flat_map(|&i| rows[i].clone())
                    .map(|r| m[(r, c)] * m[(r, c)])
                    .sum()
            };
            let targets = poses.iter().map(|&i| held[i].targets.len()).sum::<usize>().max(1) as f64;
            bins.push(Bin {
                label,
                observed: ssr(r_obs, 0),
                null: (0..r_null.ncols()).map(|c| ssr(r_null, c)).collect(),
                targets,
            });
        }
        for b in &bins {
            let obs = (b.observed / b.targets).sqrt() * 1e3;
            let noise = (mean(&b.null) / b.targets).sqrt() * 1e3;
            entries.push(WhereEntry {
                experiment: format!("feature:{}:{}", f.name, b.label),
                joint: f.joint,
                excess_ratio: obs / noise,
                residual_rms_mm: obs,
                noise_only_rms_mm: noise,
            });
        }
        if bins.len() < 2 {
            continue;
        }
        let contrast = |ssr: &dyn Fn(&Bin) -> f64| {
            let ratios: Vec<f64> = bins.iter().map(|b| (ssr(b) / mean(&b.null)).sqrt()).collect();
            ratios.iter().copied().fold(0.0, f64::max) / ratios.iter().copied().fold(f64::INFINITY, f64::min)
        };
        let observed = contrast(&|b| b.observed);
        let null_contrast: Vec<f64> = (0..r_null.ncols()).map(|c| contrast(&|b| b.null[c])).collect();
        let threshold = quantile(&null_contrast, 1.0 - false_alarm, QuantileMethod::InverseCdf);
        contrasts.push(FeatureContrast {
            feature: f.name,
            joint: f.joint,
            contrast: observed,
            noise_only_threshold: threshold,
            beyond_noise: observed > threshold,
        });
    }
    contrasts.sort_by(|a, b| (b.contrast / b.noise_only_threshold).total_cmp(&(a.contrast / a.noise_only_threshold)));
    (entries, contrasts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terciles_split_a_varying_feature_and_skip_a_constant_one() {
        let v: Vec<Option<f64>> = (0..9).map(|i| Some(i as f64)).chain([None]).collect();
        let b = terciles(&v).unwrap();
        assert_eq!(&b[..3], &[Some("low"); 3]);
        assert_eq!(&b[3..6], &[Some("mid"); 3]);
        assert_eq!(&b[6..9], &[Some("high"); 3]);
        assert_eq!(b[9], None);
        assert!(terciles(&[Some(20.0); 5]).is_none());
    }
}
