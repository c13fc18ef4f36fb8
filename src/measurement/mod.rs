//! The instrument: the two-theodolite measurement model (triangulation, angular noise
//! calibrated to the paper's 0.19 mm net radial error) and the measurement data files
//! (FORMATS.md section 1).

mod model;
mod noise_calibration;
mod theodolite;

pub use model::{IsotropicNoise, MeasurementModel};
pub use noise_calibration::{
    Anisotropy, NoiseCalibration, PAPER_NET_RADIAL_RMS_MM, PAPER_RIGHT_STATION_MM, PAPER_ROBOT_BASE_MM, ReferenceVolume,
};
pub use theodolite::{StationAngles, TheodolitePair, TriangulationError};
