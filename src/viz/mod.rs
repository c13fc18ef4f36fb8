//! Rerun recordings of a campaign: an observer that the CLI drives; the maths never calls it.
//!
//! The shapes drawn and their colours are computed in every build (`shapes`, `colors`); the
//! recorder itself needs the cargo feature `viz` (the rerun crates). A `Recorder` buffers
//! everything in memory and `Recorder::save` writes one `.rrd` file (open it with `axiscal view
//! FILE.rrd`, i.e. the `rerun` viewer of the same version as the `rerun` crate). Everything is
//! in the world (instrument) frame, in metres, right-handed with Z up. Entity layout:
//!
//! | entity | archetype | what |
//! |---|---|---|
//! | `world/robot/link{k}` | `Transform3D` + `TransformAxes3D` | `world_from_link` of link `k` (1-based) |
//! | `world/robot/skeleton` | `LineStrips3D` | joint-frame origins, base to tool |
//! | `world/robot/links` | `Boxes3D` | one slim box per segment between joint origins |
//! | `world/robot/four_bar` | `LineStrips3D` | the closed four-bar loop, when given |
//! | `world/targets/{experiment}` | `Points3D` | measured targets, one colour per experiment |
//! | `world/fits/{experiment}/axis` | `Arrows3D` | a fitted joint axis |
//! | `world/fits/{experiment}/arc` | `LineStrips3D` | the fitted arc over the swept range |
//! | `world/errors/{name}` | `Arrows3D` | error vectors, coloured by [`error_color`] |
//! | `world/nominal`, `world/calibrated` | as `world/robot` | the nominal and the calibrated robot side by side (recordings of real data) |
//! | `world/residuals/{experiment}` | `Arrows3D` | measured minus fitted point of an axis experiment, exaggerated |
//! | `scalars/...` | `Scalars` | residuals and errors |
//! | `notes/{name}` | `TextDocument` | what the recording shows, verdicts (Markdown) |
//!
//! `Recorder::send_default_blueprint` stores a layout with the recording (3-D world,
//! scalars, notes), so it opens readable.
//!
//! Two sequence timelines: `step` (a pose counter running through the whole campaign) and
//! `trial` (a Monte-Carlo trial index); `STEP_TIMELINE`, `TRIAL_TIMELINE`.

mod colors;
#[cfg(feature = "viz")]
mod recorder;
mod shapes;

pub use colors::{ERROR_COLOR_STOPS, ROBOT_COLOR, error_color, experiment_color};
#[cfg(feature = "viz")]
pub use recorder::{Recorder, STEP_TIMELINE, TRIAL_TIMELINE, VizError};
pub use shapes::{LengthMismatch, arc_points, four_bar_loop_m, segment_boxes, vectors_between};
