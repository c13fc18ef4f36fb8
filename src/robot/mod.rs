//! The robot as the program knows it: the nominal description a user writes
//! ([`RobotDescription`]), the kinematic-plus-transmission [`RobotModel`] that describes any
//! robot (the simulated truth and the calibrated robot alike), its transmission and coupling
//! functions, four-bar geometry, and the fig. 3 controller.

mod compliance;
mod controller;
mod description;
mod effects;
mod four_bar;
mod four_bar_fit;
mod functions;
mod model;
mod model_error;

pub use compliance::{ComplianceTerm, LoadProduct, SpringLoad, SpringSite};
pub use controller::Controller;
pub(crate) use description::Fnv;
pub use description::{
    AxisTargets, CouplingFitForm, DescriptionError, DescriptionIdentity, DhConventionEntry, DhEntry, InstrumentEntry,
    JointEntry, LinkTarget, MAX_ANGLE_DEG, MAX_HARMONIC_ORDER, MAX_INSTRUMENT_FRAME_MM, MAX_REPEATABILITY_SIGMA,
    MIN_STATION_DISTANCE_MM, NominalCoupling, Placement, RobotDescription, RowEntry, ToolEntry, TransmissionFitForm,
    UrdfEntry, angle_deg_problem, commands_to_file, commands_to_internal, file_unit, station_problem,
};
pub use effects::{BacklashTerm, LoadTerm, ModelEffects, PoseLoad, SagTerm, gravity_direction, sag_regressor};
pub use four_bar::{FourBarError, FourBarGeometry, FourBarState};
pub use four_bar_fit::{FourBarFit, fit_four_bar};
pub use functions::{CouplingFunction, MAX_HARMONIC_AMPLITUDE_RAD, Transmission};
pub use model::{FourBarLinkage, JointModel, RobotModel};
pub use model_error::ModelError;
