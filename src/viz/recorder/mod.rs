//! The recorder (cargo feature `viz`): a buffered rerun recording stream, its timelines and
//! the log calls of the entity layout in [`crate::viz`]'s docs.

mod fits;
mod robot;

use super::{LengthMismatch, error_color, experiment_color, vectors_between};
use nalgebra::Point3;

/// The timeline of poses: one tick per commanded pose, through the whole campaign.
pub const STEP_TIMELINE: &str = "step";
/// The timeline of Monte-Carlo trials.
pub const TRIAL_TIMELINE: &str = "trial";

/// A recording could not be made or written.
#[derive(Debug, thiserror::Error)]
pub enum VizError {
    /// The recording stream could not be created.
    #[error("creating the rerun recording: {cause}")]
    Stream {
        /// Why.
        cause: rerun::RecordingStreamError,
    },
    /// The recording could not be encoded as an `.rrd` file.
    #[error("encoding the rerun recording: {cause}")]
    Encode {
        /// Why.
        cause: String,
    },
    /// Some log calls failed (serialisation); the rest of the recording was written.
    #[error("{count} rerun log call(s) failed, the first: {first}")]
    Log {
        /// Number of failed calls.
        count: usize,
        /// The first failure.
        first: String,
    },
    /// Two inputs that must match in length do not.
    #[error(transparent)]
    LengthMismatch(#[from] LengthMismatch),
}

/// Observer that logs a campaign to a rerun recording (see the module docs for the layout).
#[derive(Debug)]
pub struct Recorder {
    stream: rerun::RecordingStream,
    /// Log calls that failed, and the first failure (reported by [`Recorder::into_rrd`]).
    failures: std::cell::RefCell<(usize, Option<String>)>,
}

pub(crate) fn vec3(p: &Point3<f64>) -> [f32; 3] {
    [p.x as f32, p.y as f32, p.z as f32]
}

impl Recorder {
    /// A recording buffered in memory under application id `application_id` (e.g. `axiscal`),
    /// with the world frame declared right-handed, Z up.
    pub fn new(application_id: &'static str) -> Result<Self, VizError> {
        let stream = rerun::RecordingStreamBuilder::new(application_id)
            .buffered()
            .map_err(|source| VizError::Stream { cause: source })?;
        let rec = Recorder {
            stream,
            failures: Default::default(),
        };
        let result = rec
            .stream
            .log_static("world", &rerun::ViewCoordinates::RIGHT_HAND_Z_UP());
        rec.note(result);
        Ok(rec)
    }

    /// Remembers a failed log call for [`Recorder::into_rrd`].
    fn note(&self, result: rerun::RecordingStreamResult<()>) {
        if let Err(e) = result {
            let mut f = self.failures.borrow_mut();
            f.0 += 1;
            f.1.get_or_insert_with(|| e.to_string());
        }
    }

    /// Logs `what` at `entity` on the current timelines.
    pub(crate) fn log<A: rerun::AsComponents + ?Sized>(&self, entity: &str, what: &A) {
        self.note(self.stream.log(entity, what));
    }

    /// The underlying stream, for logging anything this type has no method for.
    pub fn stream(&self) -> &rerun::RecordingStream {
        &self.stream
    }

    /// Sets the `step` timeline for everything logged next.
    pub fn set_step(&self, step: i64) {
        self.stream.set_time_sequence(STEP_TIMELINE, step);
    }

    /// Sets the `trial` timeline for everything logged next.
    pub fn set_trial(&self, trial: i64) {
        self.stream.set_time_sequence(TRIAL_TIMELINE, trial);
    }

    /// Clears both timelines: what is logged next is timeless for them (latest-at everywhere).
    pub fn reset_time(&self) {
        self.stream.reset_time();
    }

    /// Logs a scalar at `scalars/{name}` on the current timelines (`name` may contain `/`).
    pub fn log_scalar(&self, name: &str, value: f64) {
        self.log(&format!("scalars/{name}"), &rerun::Scalars::single(value));
    }

    /// Logs measured target positions \[m\] of one experiment at `world/targets/{experiment}`,
    /// coloured by [`experiment_color`].
    pub fn log_targets(&self, experiment: &str, points_m: &[Point3<f64>]) {
        let points = rerun::Points3D::new(points_m.iter().map(vec3))
            .with_radii([0.006_f32])
            .with_colors([experiment_color(experiment)]);
        self.log(&format!("world/targets/{experiment}"), &points);
    }

    /// Logs error vectors as arrows at `world/errors/{name}`, from `from_m[i]` (commanded or
    /// predicted point) towards `to_m[i]` (measured point), drawn `exaggeration` times their
    /// length (1 = true scale; millimetre errors on a metre-sized arm need ~100), each
    /// coloured by its true length with [`error_color`] on the scale `0..=full_scale_m`.
    /// Returns the true lengths \[m\].
    pub fn log_error_vectors(
        &self,
        name: &str,
        from_m: &[Point3<f64>],
        to_m: &[Point3<f64>],
        full_scale_m: f64,
        exaggeration: f64,
    ) -> Result<Vec<f64>, VizError> {
        self.log_vectors(
            &format!("world/errors/{name}"),
            from_m,
            to_m,
            full_scale_m,
            exaggeration,
        )
    }

    /// Logs vectors `from_m[i] -> to_m[i]` as arrows at the entity `entity`, drawn
    /// `exaggeration` times their length and coloured by their true length with
    /// [`error_color`] on `0..=full_scale_m` (see [`Recorder::log_error_vectors`]). Returns
    /// the true lengths \[m\].
    pub fn log_vectors(
        &self,
        entity: &str,
        from_m: &[Point3<f64>],
        to_m: &[Point3<f64>],
        full_scale_m: f64,
        exaggeration: f64,
    ) -> Result<Vec<f64>, VizError> {
        let vectors = vectors_between(from_m, to_m)?;
        let lengths: Vec<f64> = vectors.iter().map(|v| v.norm()).collect();
        let arrows = rerun::Arrows3D::from_vectors(vectors.iter().map(|v| {
            let v = v * exaggeration;
            [v.x as f32, v.y as f32, v.z as f32]
        }))
        .with_origins(from_m.iter().map(vec3))
        .with_radii([0.002_f32])
        .with_colors(lengths.iter().map(|&l| error_color(l, full_scale_m)));
        self.log(entity, &arrows);
        Ok(lengths)
    }

    /// Logs a Markdown note at `notes/{name}` (timeless for the timelines in use when logged
    /// with [`Recorder::reset_time`] first): what the recording shows, a verdict.
    pub fn log_note(&self, name: &str, markdown: &str) {
        self.log(
            &format!("notes/{name}"),
            &rerun::TextDocument::new(markdown).with_media_type(rerun::MediaType::markdown()),
        );
    }

    /// Sends the default layout with the recording, so that it opens readable: the 3-D world
    /// (robots, targets, fits, residual and error vectors) on the left, the scalars and the
    /// notes stacked on the right, the time panel on the `step` timeline.
    pub fn send_default_blueprint(&self) {
        use rerun::blueprint::{
            Blueprint, BlueprintActivation, Horizontal, Spatial3DView, TextDocumentView, TimePanel, TimeSeriesView,
            Vertical,
        };
        let layout = Horizontal::new([
            Spatial3DView::new("3D").with_origin("/world").into(),
            Vertical::new([
                TimeSeriesView::new("residuals and errors")
                    .with_origin("/scalars")
                    .into(),
                TextDocumentView::new("notes").with_origin("/notes").into(),
            ])
            .with_row_shares([0.6, 0.4])
            .into(),
        ])
        .with_column_shares([0.68, 0.32]);
        let blueprint = Blueprint::new(layout).with_time_panel(TimePanel::new().with_timeline(STEP_TIMELINE));
        self.note(blueprint.send(&self.stream, BlueprintActivation::default()));
    }

    /// Everything logged, as the bytes of an `.rrd` file (the stream moved to a memory sink and
    /// encoded): the caller writes them as it writes any output (through a temporary, never
    /// through a link). Fails if any log call failed.
    pub fn into_rrd(self) -> Result<Vec<u8>, VizError> {
        let storage = self.stream.memory();
        let bytes = storage.drain_as_bytes().map_err(|cause| VizError::Encode {
            cause: cause.to_string(),
        })?;
        match self.failures.take() {
            (0, _) => Ok(bytes),
            (count, first) => Err(VizError::Log {
                count,
                first: first.unwrap_or_default(),
            }),
        }
    }
}
