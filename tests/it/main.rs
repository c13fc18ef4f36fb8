//! The integration tests, one binary (as ripgrep does): a one-line library change relinks one
//! test executable, not one per file. Each module is one subject; `common` holds the helpers
//! they share. Run a subject alone with its module path: `cargo test --test it cli_calibrate::`.

mod common;

mod anywhere;
mod architecture;
mod calibration_procedure;
mod calibration_study;
mod campaign_plan;
mod certificate;
mod cli_calibrate;
mod cli_evaluate;
mod cli_record;
mod cli_run;
mod cli_safety;
mod cli_scripting;
mod cli_simulate;
mod compensation;
mod diagnosis;
mod effect_shapes;
mod effects;
mod export;
mod fuzz_readers;
mod gap_budget;
mod iso9283;
mod joint_map;
mod json_schemas;
mod kinematics_props;
mod lean_calibration;
mod measurement_csv_roundtrip;
mod noise_and_held;
mod nominal_frames;
mod outliers;
mod paper_scenario;
mod plan_import;
mod plan_optimize;
mod plan_sight;
mod progress_counts;
mod rapier_arm;
mod readme;
mod real_boby_klimchik;
mod real_fanuc;
mod real_rct;
mod real_sscanss2;
mod refine;
mod reproducible_streams;
mod robot_description;
mod scenario_run;
mod seven_joints;
mod sliding_end_to_end;
mod test_robots;
mod thread_determinism;
mod tool_accuracy;
mod truth_model;
mod urdf_parser;
mod validate;
