//! Fuzzing of every reader of user files (stable Rust: proptest mutations of valid seed files
//! instead of `cargo fuzz`, which needs nightly): the measurement CSV, robot descriptions,
//! scenarios, effects files, a description's URDF, `calibration.json` and the importers' tables (a tracker's point
//! export, SpatialAnalyzer's ASCII export, a wide pose table). Each mutated file must give a value or one
//! error naming the file, never a panic; a value read is then used (calibrated, compensated,
//! hashed) and must not panic either.
//!
//! `make test` runs a short, fixed-seed pass; `make fuzz` runs
//! `fuzz_readers_for_a_set_time` for `FUZZ_SECONDS` (default 600) with fresh seeds, writing a
//! failing input (shrunk) to `target/fuzz-failures/`.

use crate::common;

use axiscal::calibration::procedure::{Calibration, CalibrationOptions, calibrate};
use axiscal::compensation::Compensator;
use axiscal::harness::scenario::{Overrides, ResolvedScenario, ScenarioFile};
use axiscal::json_file::{self, Schema};
use axiscal::kinematics::JointKind;
use axiscal::measurement::import::points::{LengthUnit, read_export};
use axiscal::measurement::import::spatial_analyzer;
use axiscal::measurement::import::table::Table;
use axiscal::measurement::import::wide::{WideOptions, import_wide};
use axiscal::measurement::{read_measurements_from, unit_check, write_measurements_to};
use axiscal::plan::{CalibrationPlan, ValidationPlan};
use axiscal::robot::RobotDescription;
use axiscal::sim::Effects;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::path::Path;
use std::time::{Duration, Instant};

/// The readers under test.
#[derive(Clone, Copy, Debug)]
enum Reader {
    MeasurementCsv,
    Description,
    Scenario,
    Effects,
    CalibrationJson,
    PointExport,
    SpatialAnalyzer,
    WideTable,
    Urdf,
}

const READERS: [Reader; 9] = [
    Reader::MeasurementCsv,
    Reader::Description,
    Reader::Scenario,
    Reader::Effects,
    Reader::CalibrationJson,
    Reader::PointExport,
    Reader::SpatialAnalyzer,
    Reader::WideTable,
    Reader::Urdf,
];

const POINT_EXPORT: &str = "id,x_mm,y_mm,z_mm,sigma_mm\n1,100.5,-20.25,300.125,0.02\n2,101.5,-19.75,\"300,5\",0.02\n\
P003,1e3,2.5e-1,-0.0,0.03\n";

const SPATIAL_ANALYZER: &str = "// SpatialAnalyzer 2023.1\n// Working frame: World, mm\nA Grp SMR_1 100.5 -20.25 300.125 0.01\n\
A Grp SMR_2 101.5 -19.75 300.5 0.01\nA Grp SMR_17 1000 0.25 -0.0 0.02\n";

const WIDE_TABLE: &str = "q1,q2,m1_x,m1_y,m1_z,m2_x,m2_y,m2_z\n0,0,1000,0,500,1100,0,500\n\
0.1,0,995,99.8,500,1094.5,109.8,500\n0.2,0,980.1,198.7,500,1078.1,218.5,500\n\
0.3,0,955.3,295.5,500,1050.9,325.1,nan\n0.3,0.2,950,290,520,,,\n";

/// A small valid campaign (fewer poses than Table 1, so a calibration of a mutant is quick).
fn campaign_csv() -> Vec<u8> {
    let plan = CalibrationPlan::table1(6);
    let validation = ValidationPlan {
        poses: 4,
        ..ValidationPlan::workspace_default(6)
    };
    let set = common::analytic_campaign(
        &common::paper_robot_without_jitter(),
        &plan,
        &validation,
        &axiscal::measurement::MeasurementModel::paper_isotropic(),
        3,
    );
    let mut out = b"# a comment line\n".to_vec();
    write_measurements_to(&mut out, &set).expect("in memory");
    out
}

const EFFECTS: &str = "[compliance]\nstiffness_nm_per_rad = [1e5, 1e5, 1e5, 1e5, 1e5, 1e5]\n\
[payload]\ncom_in_tool_mm = [0.0, 0.0, 50.0]\n[backlash]\nband_rad = [0.0, 1e-4, 0.0, 0.0, 0.0, 0.0]\n\
[thermal]\nalpha_per_k = 1.2e-5\n[[gear_harmonics]]\njoint = 5\norder = 2\nsin_rad = 1e-3\n\
[[wobble]]\njoint = 1\namplitude_rad = 1e-4\norder = -2\n[instrument_scale]\nppm = 20.0\n";

/// Valid files of each reader to mutate.
fn seeds(reader: Reader) -> Vec<Vec<u8>> {
    let file = |p: &str| std::fs::read(p).expect("a shipped file");
    match reader {
        Reader::MeasurementCsv => vec![campaign_csv()],
        Reader::Description => vec![
            file("scenarios/robots/asea-irb6l.toml"),
            file("scenarios/robots/boby-klimchik-arm.toml"),
        ],
        Reader::Scenario => vec![
            file("scenarios/ci-smoke.toml"),
            file("scenarios/perturbed-fleet.toml"),
            file("scenarios/noise-sweep.toml"),
        ],
        Reader::Effects => vec![EFFECTS.as_bytes().to_vec()],
        Reader::PointExport => vec![POINT_EXPORT.as_bytes().to_vec()],
        Reader::SpatialAnalyzer => vec![SPATIAL_ANALYZER.as_bytes().to_vec()],
        Reader::WideTable => vec![WIDE_TABLE.as_bytes().to_vec()],
        Reader::Urdf => vec![file("scenarios/robots/real/fanuc-r2000ic.urdf")],
        Reader::CalibrationJson => {
            let desc = RobotDescription::asea_irb6l();
            let set = read_measurements_from(campaign_csv().as_slice(), Path::new("seed.csv"), Some(6)).unwrap();
            let cal = calibrate(&set, &desc, &CalibrationOptions::default()).expect("the seed calibrates");
            vec![json_file::to_string(Schema::CALIBRATION, &cal).unwrap().into_bytes()]
        }
    }
}

/// Tokens that readers treat specially, spliced in by the mutator.
const TOKENS: [&str; 24] = [
    ",",
    "\n",
    "\r\n",
    "#",
    "\"",
    "NaN",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e-320",
    "-0",
    "0",
    "99999999999999999999999",
    "-1",
    "=",
    "[",
    "]",
    "{",
    "}",
    ";",
    "\t",
    "\u{feff}",
    "null",
];

/// One edit of a file.
#[derive(Clone, Debug)]
enum Edit {
    Flip(usize, u8),
    Insert(usize, Vec<u8>),
    Delete(usize, usize),
    Duplicate(usize, usize),
    Truncate(usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Flip(i, b)),
        (any::<usize>(), prop::sample::select(TOKENS.to_vec()))
            .prop_map(|(i, t)| Edit::Insert(i, t.as_bytes().to_vec())),
        (any::<usize>(), prop::collection::vec(any::<u8>(), 1..8)).prop_map(|(i, b)| Edit::Insert(i, b)),
        (any::<usize>(), 1usize..64).prop_map(|(i, n)| Edit::Delete(i, n)),
        (any::<usize>(), 1usize..256).prop_map(|(i, n)| Edit::Duplicate(i, n)),
        any::<usize>().prop_map(Edit::Truncate),
    ]
}

fn apply(mut bytes: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for e in edits {
        let at = |i: usize| if bytes.is_empty() { 0 } else { i % (bytes.len() + 1) };
        match e {
            Edit::Flip(i, b) if !bytes.is_empty() => {
                let i = i % bytes.len();
                bytes[i] ^= b | 1;
            }
            Edit::Flip(..) => {}
            Edit::Insert(i, t) => {
                let i = at(*i);
                bytes.splice(i..i, t.iter().copied());
            }
            Edit::Delete(i, n) => {
                let i = at(*i);
                let end = (i + n).min(bytes.len());
                bytes.drain(i..end);
            }
            Edit::Duplicate(i, n) => {
                let i = at(*i);
                let part: Vec<u8> = bytes[i..(i + n).min(bytes.len())].to_vec();
                bytes.splice(i..i, part);
            }
            Edit::Truncate(i) => {
                let i = at(*i);
                bytes.truncate(i);
            }
        }
    }
    bytes
}

/// Asserts an error names `label` and is one line.
fn check_error(label: &str, message: &str) -> Result<(), TestCaseError> {
    prop_assert!(message.contains(label), "error does not name {label}: {message}");
    Ok(())
}

/// Reads `bytes` with `reader`; uses what it reads. Panics propagate to the runner.
fn exercise(reader: Reader, bytes: &[u8]) -> Result<(), TestCaseError> {
    let desc = RobotDescription::asea_irb6l();
    let text = String::from_utf8_lossy(bytes);
    match reader {
        Reader::MeasurementCsv => match read_measurements_from(bytes, Path::new("fuzz.csv"), Some(6)) {
            Ok(set) => {
                let _ = unit_check::measurement_slips(&set, &desc);
                if let Err(e) = calibrate(&set, &desc, &CalibrationOptions::default()) {
                    prop_assert!(!e.to_string().is_empty());
                }
            }
            Err(e) => check_error("fuzz.csv", &e.to_string())?,
        },
        Reader::Description => match RobotDescription::from_toml_str(&text, Path::new("fuzz.toml")) {
            Ok(d) => {
                let _ = (d.geometry_hash(), unit_check::description_slips(&d), d.nominal_model());
            }
            Err(e) => check_error("fuzz.toml", &e.to_string())?,
        },
        Reader::Scenario => {
            let path = Path::new("scenarios/fuzz.toml");
            let parsed = axiscal::toml_file::parse::<ScenarioFile>(&text, path);
            match parsed
                .map_err(|e| e.to_string())
                .and_then(|f| ResolvedScenario::resolve(f, path, Overrides::default()).map_err(|e| e.to_string()))
            {
                Ok(s) => {
                    let _ = s.to_toml();
                }
                Err(e) => check_error("scenarios/fuzz.toml", &e)?,
            }
        }
        Reader::Effects => match Effects::from_toml_str(&text, Path::new("fuzz.toml"), 6) {
            Ok(_) => {}
            Err(e) => check_error("fuzz.toml", &e.to_string())?,
        },
        Reader::PointExport => match Table::parse(&*text, Path::new("fuzz.csv")).and_then(|t| read_export(&t)) {
            Ok(_) => {}
            Err(e) => check_error("fuzz.csv", &e.to_string())?,
        },
        Reader::SpatialAnalyzer => {
            match spatial_analyzer::to_table(&text, Path::new("fuzz.txt"), None).and_then(|t| read_export(&t)) {
                Ok(_) => {}
                Err(e) => check_error("fuzz.txt", &e.to_string())?,
            }
        }
        Reader::WideTable => {
            let options = WideOptions {
                kinds: vec![JointKind::Revolute, JointKind::Revolute],
                radians: true,
                lengths: LengthUnit::Mm,
                still_tolerance: 1e-6,
            };
            match Table::parse(&*text, Path::new("fuzz.csv")).and_then(|t| import_wide(&t, &options)) {
                Ok(set) => {
                    let _ = set.experiments();
                }
                Err(e) => check_error("fuzz.csv", &e.to_string())?,
            }
        }
        Reader::Urdf => {
            let dir = tempfile::tempdir().unwrap();
            let toml = std::fs::read("scenarios/robots/real/fanuc-r2000ic.toml").unwrap();
            std::fs::write(dir.path().join("fuzz.toml"), toml).unwrap();
            std::fs::write(dir.path().join("fanuc-r2000ic.urdf"), bytes).unwrap();
            match RobotDescription::from_file(&dir.path().join("fuzz.toml")) {
                Ok(d) => {
                    let _ = (d.geometry_hash(), unit_check::description_slips(&d), d.nominal_model());
                }
                Err(e) => check_error("fuzz.toml", &e.to_string())?,
            }
        }
        Reader::CalibrationJson => {
            if let Ok(cal) = json_file::from_str::<Calibration>(Schema::CALIBRATION, &text)
                && let Ok(comp) = Compensator::new(&cal.robot, &desc)
            {
                let pose = desc.nominal_model().world_from_tool(&[0.1, 0.2, -0.1, 0.3, 0.2, 0.1]);
                let _ = comp.compensate(&pose);
            }
        }
    }
    Ok(())
}

/// Runs `cases` mutants of `reader`'s seeds from `rng`; a failure is written to
/// `target/fuzz-failures/` and panics with it.
fn fuzz(reader: Reader, cases: u32, rng: TestRng) {
    let seeds = seeds(reader);
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    let mut runner = TestRunner::new_with_rng(config, rng);
    let strategy = (0..seeds.len(), prop::collection::vec(edit(), 1..6));
    let result = runner.run(&strategy, |(seed, edits)| {
        exercise(reader, &apply(seeds[seed].clone(), &edits))
    });
    if let Err(e) = result {
        let text = format!("{e}");
        let dir = Path::new("target/fuzz-failures");
        let _ = std::fs::create_dir_all(dir);
        let file = dir.join(format!("{reader:?}-{}.txt", std::process::id()));
        let _ = std::fs::write(&file, &text);
        panic!("{reader:?}: {text} (written to {})", file.display());
    }
}

#[test]
fn every_reader_survives_a_fixed_set_of_mutants() {
    for reader in READERS {
        let cases = match reader {
            Reader::MeasurementCsv | Reader::CalibrationJson => 24,
            _ => 96,
        };
        fuzz(reader, cases, TestRng::deterministic_rng(RngAlgorithm::ChaCha));
    }
}

#[test]
#[ignore = "long: `make fuzz` runs it for FUZZ_SECONDS (default 600)"]
fn fuzz_readers_for_a_set_time() {
    let seconds: u64 = std::env::var("FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(600);
    let deadline = Instant::now() + Duration::from_secs(seconds);
    let mut rounds = 0u64;
    let start_seed = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64);
    while Instant::now() < deadline {
        let reader = READERS[(rounds % READERS.len() as u64) as usize];
        let seed = start_seed.wrapping_add(rounds);
        let mut bytes = [0u8; 32];
        bytes[..8].copy_from_slice(&seed.to_le_bytes());
        eprintln!("round {rounds}: {reader:?}, seed {seed}");
        fuzz(reader, 64, TestRng::from_seed(RngAlgorithm::ChaCha, &bytes));
        rounds += 1;
    }
    eprintln!("{rounds} rounds of 64 mutants in {seconds} s without a failure");
}
