//! Independent-axis calibration of robot arms (Sultan & Wager), with a simulation-backed
//! validation harness.
//!
//! Each joint is moved alone while a target on the moving link is measured; each rotary axis is
//! fitted from its arc and each sliding axis from its line without trusting the joint readings,
//! then the transmission functions, passive couplings, joint offsets and tool frame; the result
//! is a phi-model of the actual robot, compensated through the unchanged controller. The user's
//! guide is `README.md`; the method is `docs/method.md`, the file formats `docs/formats.md`,
//! the layout and the truth boundary `ARCHITECTURE.md`.
//!
//! # Module map
//!
//! | module | what |
//! |---|---|
//! | [`kinematics`] | phi-model (appendix, eqs. A1-A4), forward kinematics, Jacobian, IK, DH |
//! | [`robot`] | the nominal description, [`robot::RobotModel`] (any robot: simulated, calibrated, ideal), transmissions, couplings, fig. 3 controller |
//! | [`plan`] | the campaign plan: Table-1 axis experiments, hold-still commands, validation poses |
//! | [`measurement`] | the instruments (theodolite pair, isotropic noise) and the measurement CSV |
//! | [`calibration`] | axis fits (eqs. 1-13), couplings (eqs. 14-15), the procedure and its report |
//! | [`certificate`] | the calibration certificate: parameters with GUM uncertainties, correlations, residuals, held-out poses (HTML and JSON) |
//! | [`compensation`] | fig. 5: commands for required tool poses |
//! | [`diagnosis`] | the sim-to-real gap diagnosis: where, which effect, how far it shrinks |
//! | [`iso9283`] | ISO 9283 pose and distance characteristics of measured cycles, and their prediction |
//! | [`physics`] | gravity, compliance and the unmodelled-effect forms (neutral ground) |
//! | [`numerics`] | the one least-squares loop and the statistics |
//! | [`sim`] | the simulated real robot (analytic and rapier arms): the answer key |
//! | [`harness`] | evaluation, Monte-Carlo scenarios, studies, the blind check |
//! | [`json_file`], [`json_schema`] | the versioned JSON outputs and their JSON Schemas (`docs/schemas/`) |
//! | [`progress`] | counts of long work, for whoever shows them |
//! | `viz` | rerun recordings: the shapes drawn, and the recorder (cargo feature `viz`) |
//!
//! `calibration`, `compensation` and `diagnosis` see only measurements and the nominal
//! description, never [`sim`] or [`harness`] (`tests/it/architecture.rs` enforces it).
//!
//! # Examples
//!
//! The nominal ASEA IRB/L6 at its zero pose (Table 2's nominal rows): the wrist frame 6 sits
//! 0.69 m up and 0.9025 m out along Y.
//!
//! ```
//! use axiscal::robot::RobotDescription;
//!
//! let desc = RobotDescription::asea_irb6l();
//! let model = desc.nominal_model();
//! let frame6 = model.world_from_base.inverse() * model.poses(&[0.0; 6]).world_from_link[5];
//! let p = frame6.translation.vector;
//! assert!((p.y - 0.9025).abs() < 1e-9 && (p.z - 0.69).abs() < 1e-9);
//! ```
//!
//! A whole calibration: simulate the paper's Table-1 campaign on the paper robot without any
//! noise, calibrate from the measurements and the nominal description alone, and compensate a
//! pose: the calibrated robot reproduces the truth.
//!
//! ```
//! use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
//! use axiscal::compensation::Compensator;
//! use axiscal::measurement::{IsotropicNoise, MeasurementModel, MeasurementSet};
//! use axiscal::plan::{CalibrationPlan, ValidationPlan};
//! use axiscal::robot::{Controller, RobotDescription};
//! use axiscal::sim::{AnalyticArm, paper_robot, simulate_campaign};
//! use rand::{SeedableRng, rngs::ChaCha12Rng};
//!
//! let desc = RobotDescription::asea_irb6l();
//! let mut truth = paper_robot();
//! for j in &mut truth.joints {
//!     j.repeatability_sigma = 0.0;
//! }
//! let mut arm = AnalyticArm::new(truth.clone(), Controller::from_description(&desc));
//! let no_validation = ValidationPlan { poses: 0, ..ValidationPlan::workspace_default(6) };
//! let campaign = simulate_campaign(
//!     &desc,
//!     &CalibrationPlan::table1(6),
//!     &no_validation,
//!     &mut arm,
//!     &MeasurementModel::Isotropic(IsotropicNoise { net_radial_rms_mm: 0.0 }),
//!     &mut ChaCha12Rng::seed_from_u64(1),
//! )?;
//! let data = MeasurementSet::new(6, campaign.rows)?;
//! let cal = calibrate(&data, &desc, &CalibrationOptions::default())?;
//! assert!(cal.axes.iter().all(|a| a.residual_rms_mm < 1e-6));
//!
//! // Fig. 5: commands that put the calibrated robot's tool where the truth's tool is at q.
//! let q = [0.1, -0.2, 0.3, 0.2, -0.4, 0.5];
//! let pose = truth.phi_model().world_from_tool(&q);
//! let commands = Compensator::new(&cal.robot, &desc)?.compensate(&pose)?;
//! let controller = Controller::from_description(&desc);
//! let reached = truth.phi_model().world_from_tool(&truth.joint_values(&controller, &commands.cmd)?);
//! assert!((reached.translation.vector - pose.translation.vector).norm() < 1e-6);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! The rotary-axis fit's first guess, a plane and circle through points of an arc:
//!
//! ```
//! use axiscal::calibration::fit_circle;
//! use nalgebra::Point3;
//!
//! let points: Vec<Point3<f64>> = (0..8)
//!     .map(|k| {
//!         let t = 0.1 * k as f64;
//!         Point3::new(1.0 + 0.5 * t.cos(), 2.0 + 0.5 * t.sin(), 0.3)
//!     })
//!     .collect();
//! let circle = fit_circle(&points)?;
//! assert!((circle.radius - 0.5).abs() < 1e-9);
//! assert!((circle.normal.z - 1.0).abs() < 1e-9);
//! # Ok::<(), axiscal::calibration::CalibrationError>(())
//! ```
#![warn(missing_docs)]
#![deny(clippy::float_cmp)]

pub mod calibration;
pub mod certificate;
pub mod compensation;
pub mod csv_lines;
pub mod diagnosis;
pub mod harness;
pub mod iso9283;
pub mod json_file;
pub mod json_schema;
pub mod kinematics;
pub mod markdown;
pub mod measurement;
pub mod numerics;
pub mod physics;
pub mod plan;
mod plotting;
pub mod presets;
pub mod progress;
pub mod robot;
pub mod sim;
pub mod toml_file;
pub mod viz;
pub mod yaml_file;
