//! The instrument: the two-theodolite measurement model (triangulation, angular noise
//! calibrated to the paper's 0.19 mm net radial error) and the measurement data files
//! (`docs/formats.md#measurement-csv`).

pub mod bounded;
pub mod column_slips;
mod csv_io;
mod data;
pub mod description_check;
pub mod import;
mod model;
mod noise_calibration;
pub mod resolution;
pub mod target_ids;
mod theodolite;
pub mod unit_check;

pub use csv_io::{
    MeasurementFileError, format_f64, format_f64_converted, format_f64_list, read_measurements, read_measurements_from,
    write_measurements, write_measurements_to,
};
pub use data::{
    Experiment, LoneTarget, MAX_LABEL_CHARS, MAX_PAYLOAD_KG, Measurement, MeasurementSet, MeasurementSetError,
    POSE_COMMAND_TOLERANCE, RowProblem, TEMPERATURE_RANGE_C, TOOL_EXPERIMENT, is_format_char,
};
pub use model::{IsotropicNoise, MeasurementModel};
pub use noise_calibration::{
    Anisotropy, NoiseCalibration, PAPER_NET_RADIAL_RMS_MM, PAPER_RIGHT_STATION_MM, PAPER_ROBOT_BASE_MM,
    ReferenceVolume, paper_stations_around_m,
};
pub use theodolite::{StationAngles, TheodolitePair, TriangulationError};
