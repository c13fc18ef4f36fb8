//! `calibration.json` (`docs/formats.md#calibration-json`): a calibration and the reports made
//! beside it, each a value of its own. The calibration ([`Calibration`]) is what the procedure
//! or the free-pose fit returns; the tool accuracy is predicted from it, the refinement
//! computed from it, the free-pose summary returned with it. The file holds them side by side:
//! the calibration's keys first, then the reports'.

use crate::calibration::free_pose::FreePoseSummary;
use crate::calibration::procedure::Calibration;
use crate::calibration::refine::Refinement;
use crate::calibration::tool_accuracy::ToolAccuracy;
use crate::json_file::{self, JsonFileError, Schema};
use serde::{Deserialize, Serialize};

/// The reports `axiscal calibrate` writes beside a calibration in `calibration.json`; each
/// absent when not made.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Reports {
    /// The predicted tool 1-sigma inside the calibrated spans and over the workspace
    /// ([`crate::calibration::tool_accuracy::predict`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool_accuracy: Option<ToolAccuracy>,
    /// Present when the calibration's robot was refined on the file's free poses
    /// (`calibrate --refine`): the refinement's summary. `axes`, `couplings` and the sigmas
    /// stay the axis experiments' (unrefined) estimates; `robot` is the refined model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refinement: Option<Refinement>,
    /// Present when the model was calibrated from free poses alone (no axis experiments,
    /// [`crate::calibration::free_pose`]): the fitted parameters with their sigmas, what the
    /// poses do not identify, the outliers and the held-out check. `axes` is then empty.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free_poses: Option<FreePoseSummary>,
    /// The warnings `axiscal calibrate` gave on these results when it wrote them (a result no
    /// robot of the description gives, a miss of the file's own validation poses), in words:
    /// every command that reads the file says them again. Absent when there were none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// What `calibration.json` holds: the calibration, and the reports beside it.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct CalibrationRecord {
    /// The calibration every command reads.
    #[serde(flatten)]
    pub calibration: Calibration,
    /// The reports made beside it.
    #[serde(flatten)]
    pub reports: Reports,
}

impl CalibrationRecord {
    /// A calibration without reports.
    pub fn new(calibration: Calibration) -> Self {
        CalibrationRecord {
            calibration,
            reports: Reports::default(),
        }
    }

    /// Reads the text of a `calibration.json`, parsed once ([`json_file::parse`]): the
    /// calibration and the reports each read from it, so that an error in either names its
    /// line, column and key.
    pub fn from_json(text: &str) -> Result<Self, JsonFileError> {
        let parsed = json_file::parse(Schema::CALIBRATION, text)?;
        Ok(CalibrationRecord {
            calibration: parsed.read()?,
            reports: parsed.read()?,
        })
    }

    /// The text of `calibration.json`.
    pub fn to_json(&self) -> serde_json::Result<String> {
        json_file::to_string(Schema::CALIBRATION, self)
    }
}
