//! Colours of a recording: one per experiment, the robot's, and a colour map for error
//! magnitudes.

/// Colour of the simulated robot in a recording (`world/robot`), and of the nominal one beside
/// a calibrated robot.
pub const ROBOT_COLOR: [u8; 4] = [150, 150, 160, 255];

/// The colour map of [`error_color`]: `(fraction of full scale, RGB)` stops, linearly
/// interpolated in sRGB: green (no error) -> yellow (half scale) -> red (full scale and above).
pub const ERROR_COLOR_STOPS: [(f64, [u8; 3]); 3] = [(0.0, [0, 170, 60]), (0.5, [240, 200, 0]), (1.0, [215, 25, 28])];

/// The colour of an error of length `magnitude` on the scale `0..=full_scale` (same unit):
/// `t = clamp(magnitude / full_scale, 0, 1)` mapped through [`ERROR_COLOR_STOPS`]. A
/// non-positive or non-finite scale, or a non-finite magnitude, gives full-scale red.
pub fn error_color(magnitude: f64, full_scale: f64) -> [u8; 4] {
    let t = if full_scale > 0.0 && full_scale.is_finite() && magnitude.is_finite() {
        (magnitude.abs() / full_scale).clamp(0.0, 1.0)
    } else {
        1.0
    };
    let stops = &ERROR_COLOR_STOPS;
    let k = stops
        .iter()
        .rposition(|(at, _)| *at <= t)
        .unwrap_or(0)
        .min(stops.len() - 2);
    let (t0, c0) = stops[k];
    let (t1, c1) = stops[k + 1];
    let w = ((t - t0) / (t1 - t0)).clamp(0.0, 1.0);
    let mix = |a: u8, b: u8| (f64::from(a) + w * (f64::from(b) - f64::from(a))).round() as u8;
    [mix(c0[0], c1[0]), mix(c0[1], c1[1]), mix(c0[2], c1[2]), 255]
}

/// Ten well separated colours (Tableau 10).
const PALETTE: [[u8; 3]; 10] = [
    [78, 121, 167],
    [242, 142, 43],
    [225, 87, 89],
    [118, 183, 178],
    [89, 161, 79],
    [237, 201, 72],
    [176, 122, 161],
    [255, 157, 167],
    [156, 117, 95],
    [186, 176, 172],
];

/// A stable colour per experiment id (the part before any `/`, so `axis2/target1` is coloured
/// as `axis2`): `axis{k}` takes palette entry `k - 1`, `validation` grey, anything else an
/// entry chosen by an FNV-1a hash of the name.
pub fn experiment_color(experiment: &str) -> [u8; 4] {
    let experiment = experiment.split('/').next().unwrap_or(experiment);
    let index = if experiment == "validation" {
        PALETTE.len() - 1
    } else if let Some(k) = experiment.strip_prefix("axis").and_then(|k| k.parse::<usize>().ok()) {
        k.saturating_sub(1) % (PALETTE.len() - 1)
    } else {
        let hash = experiment.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        });
        (hash % (PALETTE.len() as u64 - 1)) as usize
    };
    let [r, g, b] = PALETTE[index];
    [r, g, b, 255]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_colours_follow_the_documented_stops() {
        for (at, rgb) in ERROR_COLOR_STOPS {
            let c = error_color(at * 2.0, 2.0);
            assert_eq!(&c[..3], &rgb[..], "stop at {at}");
        }
        assert_eq!(error_color(5.0, 1.0), error_color(1.0, 1.0), "clamped above full scale");
        assert_eq!(error_color(1.0, 0.0), error_color(1.0, 1.0), "bad scale is red");
        let quarter = error_color(0.25, 1.0);
        assert_eq!(quarter, [120, 185, 30, 255], "halfway between green and yellow");
    }

    #[test]
    fn experiments_get_distinct_stable_colours() {
        let axes: Vec<_> = (1..=6).map(|k| experiment_color(&format!("axis{k}"))).collect();
        for (i, a) in axes.iter().enumerate() {
            for b in &axes[i + 1..] {
                assert_ne!(a, b);
            }
        }
        assert_eq!(experiment_color("custom"), experiment_color("custom"));
        assert_eq!(experiment_color("axis2/target1"), axes[1]);
        assert_ne!(experiment_color("validation"), axes[0]);
    }
}
