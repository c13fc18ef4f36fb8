//! Helpers shared by the integration tests (`crate::common` in a test module).

pub mod hostile;

use assert_cmd::Command;
use axiscal::measurement::{IsotropicNoise, MeasurementModel, MeasurementSet};
use axiscal::plan::{CalibrationPlan, ValidationPlan};
use axiscal::robot::{Controller, RobotDescription, RobotModel};
use axiscal::sim::{AnalyticArm, Effects, simulate_campaign};
use nalgebra::Isometry3;
use rand::{RngExt, SeedableRng, rngs::ChaCha12Rng};

/// The `axiscal` binary of this build, or the one `AXISCAL_TEST_BIN` names (`make test-real`
/// runs the tests on real data with the optimised build of the same source: its debug build
/// takes ~8x the CPU on the real FANUC file's calibrations).
pub fn axiscal() -> Command {
    match std::env::var_os("AXISCAL_TEST_BIN") {
        Some(bin) => Command::new(bin),
        None => Command::cargo_bin("axiscal").expect("the axiscal binary is built"),
    }
}

/// What a finished command wrote to stderr.
pub fn stderr(a: &assert_cmd::assert::Assert) -> String {
    String::from_utf8_lossy(&a.get_output().stderr).into_owned()
}

/// What a finished command wrote to stdout.
pub fn stdout(a: &assert_cmd::assert::Assert) -> String {
    String::from_utf8_lossy(&a.get_output().stdout).into_owned()
}

/// The paper robot with its repeatability jitter switched off (noise-free executions).
pub fn paper_robot_without_jitter() -> RobotModel {
    let mut truth = axiscal::sim::paper_robot();
    for j in &mut truth.joints {
        j.repeatability_sigma = 0.0;
    }
    truth
}

/// The measurements of `plan` then `validation` on `truth` (the analytic arm behind the
/// IRB/L6 controller) by `instrument`, random stream from `seed`.
pub fn analytic_campaign(
    truth: &RobotModel,
    plan: &CalibrationPlan,
    validation: &ValidationPlan,
    instrument: &MeasurementModel,
    seed: u64,
) -> MeasurementSet {
    analytic_campaign_with_effects(truth, Effects::default(), plan, validation, instrument, seed)
}

/// [`analytic_campaign`] on a truth with unmodelled `effects`.
pub fn analytic_campaign_with_effects(
    truth: &RobotModel,
    effects: Effects,
    plan: &CalibrationPlan,
    validation: &ValidationPlan,
    instrument: &MeasurementModel,
    seed: u64,
) -> MeasurementSet {
    let desc = RobotDescription::asea_irb6l();
    let mut arm = AnalyticArm::new(truth.clone(), Controller::from_description(&desc)).with_effects(effects, &desc);
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    let out = simulate_campaign(&desc, plan, validation, &mut arm, instrument, &mut rng).expect("the campaign runs");
    MeasurementSet::new(desc.dof(), out.rows).expect("a simulated campaign is a valid measurement set")
}

/// A campaign of the jitter-free paper robot: Table 1 and `poses` validation poses, measured
/// with isotropic noise of 3-D RMS `noise_mm`, random stream from `seed`.
pub fn jitter_free_campaign(noise_mm: f64, poses: usize, seed: u64) -> MeasurementSet {
    analytic_campaign(
        &paper_robot_without_jitter(),
        &CalibrationPlan::table1(6),
        &ValidationPlan {
            poses,
            ..ValidationPlan::workspace_default(6)
        },
        &MeasurementModel::Isotropic(IsotropicNoise {
            net_radial_rms_mm: noise_mm,
        }),
        seed,
    )
}

/// The Table-1 axis experiments alone (no validation poses) of the paper robot, with its
/// jitter, through the paper's isotropic instrument, random stream from `seed`.
pub fn axes_only_campaign(seed: u64) -> MeasurementSet {
    axes_only_campaign_of(&axiscal::sim::paper_robot(), &MeasurementModel::paper_isotropic(), seed)
}

/// The Table-1 axis experiments alone (no validation poses) of `robot` through `instrument`,
/// random stream from `seed`.
pub fn axes_only_campaign_of(robot: &RobotModel, instrument: &MeasurementModel, seed: u64) -> MeasurementSet {
    analytic_campaign(
        robot,
        &CalibrationPlan::table1(6),
        &ValidationPlan {
            poses: 0,
            ..ValidationPlan::workspace_default(6)
        },
        instrument,
        seed,
    )
}

/// `axiscal simulate --sim analytic --validation-poses POSES --seed SEED --out OUT`, run in
/// `dir`.
pub fn simulate_analytic(dir: &std::path::Path, poses: usize, seed: u64, out: &str) {
    simulate_analytic_of(dir, "asea-irb6l", (poses, seed), out);
}

/// [`simulate_analytic`] of the robot `robot` (a shipped name or a description file in `dir`).
pub fn simulate_analytic_of(dir: &std::path::Path, robot: &str, (poses, seed): (usize, u64), out: &str) {
    axiscal()
        .current_dir(dir)
        .args(["simulate", "--sim", "analytic", "--robot", robot, "--validation-poses"])
        .arg(poses.to_string())
        .arg("--seed")
        .arg(seed.to_string())
        .args(["--out", out])
        .assert()
        .success();
}

/// A temporary folder holding `campaign.csv`, written by `axiscal simulate --seed SEED`.
pub fn simulated_campaign_csv(seed: u64) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let data = dir.path().join("campaign.csv");
    axiscal()
        .args(["simulate", "--seed", &seed.to_string(), "--out"])
        .arg(&data)
        .assert()
        .success();
    (dir, data)
}

/// Random commands (file units) uniformly within each swept joint's span around the plan's
/// reference (joints not swept stay at the reference).
pub fn commands_in_spans(plan: &CalibrationPlan, rng: &mut ChaCha12Rng) -> Vec<f64> {
    plan.reference
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let half = plan
                .sweeps
                .iter()
                .find(|s| s.joint == k + 1)
                .map_or(0.0, |s| s.span / 2.0);
            r + rng.random_range(-half..=half)
        })
        .collect()
}

/// One row of a `compensate --poses` CSV: `id` and the pose `p` in mm and deg.
pub fn pose_line(id: &str, p: &Isometry3<f64>) -> String {
    let t = p.translation.vector * 1e3;
    let (r, pi, y) = p.rotation.euler_angles();
    format!(
        "{id},{},{},{},{},{},{}\n",
        t.x,
        t.y,
        t.z,
        r.to_degrees(),
        pi.to_degrees(),
        y.to_degrees()
    )
}

/// A path under the shared folder's `data/real/`: `../shared/` beside the repository (as in
/// CI), or the folder named by `AXISCAL_SHARED_DIR`; a clear failure when it is missing.
pub fn real_data(relative: &str) -> std::path::PathBuf {
    let shared = std::env::var_os("AXISCAL_SHARED_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    let path = shared.join("data/real").join(relative);
    assert!(
        path.exists(),
        "the real data set is missing: expected {} (set AXISCAL_SHARED_DIR to use another shared folder)",
        path.display()
    );
    path
}

/// The `calibration.json` in the folder `out`, read through its schema.
pub fn read_calibration(out: &std::path::Path) -> axiscal::calibration::procedure::Calibration {
    let path = out.join("calibration.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    axiscal::json_file::from_str(axiscal::json_file::Schema::CALIBRATION, &text).expect("a calibration")
}

/// The `calibration.json` in the folder `out` with the reports beside the calibration.
pub fn read_record(out: &std::path::Path) -> axiscal::calibration::record::CalibrationRecord {
    let path = out.join("calibration.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    axiscal::calibration::record::CalibrationRecord::from_json(&text).expect("a calibration")
}

/// The points' centroid and the eigenvectors of their scatter matrix, the largest eigenvalue's
/// first (a second, model-free estimate of a line's direction or a circle's plane).
pub fn principal_axes(points: &[nalgebra::Point3<f64>]) -> (nalgebra::Point3<f64>, [nalgebra::Vector3<f64>; 3]) {
    let n = points.len() as f64;
    let centroid = nalgebra::Point3::from(points.iter().map(|p| p.coords).sum::<nalgebra::Vector3<f64>>() / n);
    let scatter: nalgebra::Matrix3<f64> = points.iter().map(|p| (p - centroid) * (p - centroid).transpose()).sum();
    let eigen = scatter.symmetric_eigen();
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
    (centroid, order.map(|k| eigen.eigenvectors.column(k).into_owned()))
}

/// The number written right after the first `label` in `text` (up to the next space).
pub fn number_after(text: &str, label: &str) -> f64 {
    let rest = text
        .split(label)
        .nth(1)
        .unwrap_or_else(|| panic!("`{label}` not in: {text}"));
    let word = rest.split(' ').next().unwrap();
    word.parse()
        .unwrap_or_else(|_| panic!("`{word}` after `{label}` is not a number"))
}

/// `file` with `change` applied to the rows of experiment `experiment`, as `name` beside it.
pub fn altered_experiment(
    file: &std::path::Path,
    name: &str,
    experiment: &str,
    change: impl Fn(&mut Vec<String>),
) -> std::path::PathBuf {
    altered_csv(
        file,
        name,
        |_| true,
        |f| {
            if f[0] == experiment {
                change(f)
            }
        },
    )
}

/// The measurement CSV `file` with `change` applied to the fields of every data row
/// (`experiment, moved_joint, step, target, x_mm, y_mm, z_mm, cmd_1, ..`) and the rows `keep`
/// refuses left out, written as `name` beside it: a campaign made wrong in a known way.
pub fn altered_csv(
    file: &std::path::Path,
    name: &str,
    keep: impl Fn(&[String]) -> bool,
    change: impl Fn(&mut Vec<String>),
) -> std::path::PathBuf {
    let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let mut out = String::new();
    for line in text.lines() {
        if line.starts_with('#') || line.starts_with("experiment,") {
            out.push_str(line);
        } else {
            let mut f: Vec<String> = line.split(',').map(String::from).collect();
            if !keep(&f) {
                continue;
            }
            change(&mut f);
            out.push_str(&f.join(","));
        }
        out.push('\n');
    }
    let path = file.with_file_name(name);
    std::fs::write(&path, out).unwrap();
    path
}

/// Multiplies the fields `range` of a row of [`altered_csv`] by `factor`.
pub fn scale_fields(f: &mut [String], range: std::ops::Range<usize>, factor: f64) {
    for v in &mut f[range] {
        *v = (v.parse::<f64>().expect("a number") * factor).to_string();
    }
}

/// `file` with field `column` (0-based) of every data row (neither a `#` comment nor the
/// header) multiplied by `factor`, as `name` in its folder.
pub fn column_scaled(file: &std::path::Path, name: &str, column: usize, factor: f64) -> std::path::PathBuf {
    let text = std::fs::read_to_string(file).unwrap();
    let lines: Vec<String> = text
        .lines()
        .map(|l| {
            if l.starts_with('#') || l.starts_with("experiment,") {
                return l.to_string();
            }
            let mut f: Vec<String> = l.split(',').map(String::from).collect();
            scale_fields(&mut f, column..column + 1, factor);
            f.join(",")
        })
        .collect();
    let out = file.with_file_name(name);
    std::fs::write(&out, lines.join("\n") + "\n").unwrap();
    out
}

/// The options of the README's command importing the real FANUC R-2000iC tracker file.
pub const REAL_FANUC_OPTIONS: [&str; 8] = [
    "--joints",
    "q",
    "--targets",
    "mA,mB,mC",
    "--angles",
    "rad",
    "--units",
    "m",
];

/// The real FANUC R-2000iC tracker file (`../shared`), imported with its README's command to
/// `out`; returns the description it was imported with.
pub fn import_real_fanuc(out: &std::path::Path) -> std::path::PathBuf {
    let robot = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/robots/real/fanuc-r2000ic.toml");
    axiscal()
        .args(["import", "mat"])
        .arg(real_data("fanuc-r2000ic-tracker/calibration_dataset.mat"))
        .arg("--robot")
        .arg(&robot)
        .args(REAL_FANUC_OPTIONS)
        .arg("--out")
        .arg(out)
        .assert()
        .success();
    robot
}
