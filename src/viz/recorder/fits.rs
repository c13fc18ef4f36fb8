//! Fitted axes (arrows) and arcs (line strips) in a recording.

use super::{Recorder, VizError, vec3};
use crate::calibration::ArcFit;
use crate::kinematics::AxisLine;
use crate::viz::{LengthMismatch, arc_points, experiment_color};

/// Number of line-strip vertices of a drawn arc.
const ARC_SAMPLES: usize = 64;

impl Recorder {
    /// Logs a joint axis as an arrow at `world/fits/{experiment}/axis`: from `length_m / 2`
    /// behind the axis point to `length_m / 2` ahead, along `+Z` of the joint (line in metres).
    pub fn log_axis(&self, experiment: &str, axis: &AxisLine, length_m: f64) {
        let half = axis.direction.into_inner() * (length_m / 2.0);
        let start = axis.origin_m - half;
        let vector = 2.0 * half;
        let arrow = rerun::Arrows3D::from_vectors([[vector.x as f32, vector.y as f32, vector.z as f32]])
            .with_origins([vec3(&start)])
            .with_radii([0.003_f32])
            .with_colors([experiment_color(experiment)])
            .with_labels([format!("{experiment} axis")]);
        self.log(&format!("world/fits/{experiment}/axis"), &arrow);
    }

    /// Logs a fitted arc of experiment `experiment` at `world/fits/{experiment}/arc` (sampled
    /// by [`arc_points`] over the commands of the sweep) and its axis (see
    /// [`Recorder::log_axis`], as long as the arc's diameter). `unit_m` is the length of the
    /// fit's unit in metres (1e-3 for a fit in millimetres).
    pub fn log_arc_fit(
        &self,
        experiment: &str,
        fit: &ArcFit,
        commands_rad: &[f64],
        unit_m: f64,
    ) -> Result<(), VizError> {
        let points = arc_points(fit, commands_rad, ARC_SAMPLES).ok_or(LengthMismatch {
            what: "invertible sweep commands",
            expected: commands_rad.len(),
            found: 0,
        })?;
        let strip: Vec<[f32; 3]> = points.iter().map(|p| vec3(&(p * unit_m))).collect();
        let arc = rerun::LineStrips3D::new([strip])
            .with_radii([0.003_f32])
            .with_colors([experiment_color(experiment)]);
        self.log(&format!("world/fits/{experiment}/arc"), &arc);
        let axis = AxisLine {
            origin_m: fit.axis.origin_m * unit_m,
            direction: fit.axis.direction,
        };
        self.log_axis(experiment, &axis, (2.0 * fit.radius * unit_m).max(0.2));
        Ok(())
    }
}
