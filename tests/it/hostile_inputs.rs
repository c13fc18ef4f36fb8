//! Hostile values inside well-formed inputs, as a table: numbers a file or an option holds that
//! parse but mean nothing (a zero offset of 100 rad, a roll of 1e300 deg, a payload of 1e9 kg,
//! a placement in metres, a coupling slope of 1e300, a validation half-range wider than the
//! joint), lists left empty, a CSV where a TOML plan belongs, and an output folder that is
//! another run's. A bad input is one error line naming the file and the key or column, exit 2,
//! nothing written; a plausible but suspicious one a `warning:` line.

use crate::common::altered_csv;
use crate::common::hostile::{Case, case, clear_outputs, run_case};
use std::path::Path;

fn shipped(relative: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)).unwrap()
}

/// `text` with `from` replaced once by `to`, which must be there.
fn edited(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "no {from:?} to replace");
    text.replacen(from, to, 1)
}

/// The descriptions and scenarios of the table, each a shipped file with one value changed.
fn write_edited_files(dir: &Path) {
    let irb = shipped("scenarios/robots/asea-irb6l.toml");
    let smoke = shipped("scenarios/ci-smoke.toml");
    let positioner = shipped("scenarios/robots/positioner-2axis.toml");
    let placement = "translation_mm = [-3142.3, 4439.4, -526.1]";
    let gear = "transmission_fit = { form = \"gear\", ratio = 1.6842105263157894, order = 1 }";
    let third_joint = "[[joints]]\nkind = \"revolute\"\nlimits = [-90.0, 90.0]\n\
                       dh = { d_mm = 50.0, theta_deg = 0.0, a_mm = 0.0, alpha_deg = 0.0 }\n\n[tool]";
    let files = [
        (
            "no-tool.toml",
            edited(
                &irb,
                "targets_mm = [[0.0, 0.0, 150.0], [80.0, 0.0, 150.0], [0.0, 80.0, 150.0]]",
                "targets_mm = []",
            ),
        ),
        (
            "rpy.toml",
            edited(&irb, "rpy_deg = [0.0, 0.0, 0.0]", "rpy_deg = [1e9, 0, 0]"),
        ),
        (
            "slope.toml",
            edited(&irb, "slope = 1.0     # identity", "slope = 1e300"),
        ),
        (
            "metres.toml",
            edited(&irb, placement, "translation_mm = [-3.1423, 4.4394, -0.5261]"),
        ),
        (
            "far.toml",
            edited(&irb, placement, "translation_mm = [-3.1e12, 4439.4, -526.1]"),
        ),
        (
            "order99.toml",
            edited(&irb, gear, &gear.replace("order = 1", "order = 99")),
        ),
        (
            "order5000.toml",
            edited(&irb, gear, &gear.replace("order = 1", "order = 5000")),
        ),
        ("three-joints.toml", edited(&positioner, "[tool]", third_joint)),
        (
            "half-range.toml",
            edited(&smoke, "half_range = [40.0,", "half_range = [4000.0,"),
        ),
        (
            "noisy.toml",
            edited(&smoke, "net_radial_rms_mm = 0.19", "net_radial_rms_mm = 1e6"),
        ),
    ];
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
}

/// Writes every input of the table into `dir`: one simulated campaign and its calibration,
/// and files made from them or from shipped files with one value changed.
fn write_inputs(dir: &Path) {
    crate::common::hostile::calibrated_campaign(dir, 5);
    let campaign = dir.join("campaign.csv");
    // Row fields: experiment, moved_joint, step, target, x, y, z, cmd_1..cmd_6, payload, temperature.
    for (name, field, value) in [("payload.csv", 13, "1e9"), ("hot.csv", 14, "2000")] {
        let first = std::cell::Cell::new(true);
        altered_csv(
            &campaign,
            name,
            |_| true,
            |f| {
                if first.replace(false) {
                    f[field] = value.into();
                }
            },
        );
    }
    let text = std::fs::read_to_string(dir.join("cal/calibration.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["robot"]["joints"][0]["transducer_offset_rad_or_m"] = 100.0.into();
    std::fs::write(dir.join("offset.json"), json.to_string()).unwrap();
    // A calibration's folder whose residuals.csv is the one `validate` writes (its header).
    std::fs::create_dir(dir.join("mixed")).unwrap();
    std::fs::write(dir.join("mixed/calibration.json"), &text).unwrap();
    std::fs::write(
        dir.join("mixed/residuals.csv"),
        "experiment,kind,moved_joint,step,target,x_mm,y_mm,z_mm,predicted_x_mm,predicted_y_mm,predicted_z_mm,\
         dx_mm,dy_mm,dz_mm,error_mm\n",
    )
    .unwrap();
    let files = [
        (
            "roll.csv",
            "id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\np1,-3142.3,5341.9,-26.1,1e300,0,0\n",
        ),
        (
            "rxyz.csv",
            "x_mm,y_mm,z_mm,rx_deg,ry_deg,rz_deg\n-3142.3,5341.9,-26.1,180,0,0\n",
        ),
        ("headless.csv", "1,-3142.3,5341.9,-26.1,180,0,0\n"),
        ("three.csv", "cmd_1,cmd_2,cmd_3\n0,0,0\n"),
        (
            "sheet.csv",
            "# axiscal measurement plan\npoint,pose,experiment,moved_joint,step,target,cmd_1,cmd_2\n1,1,axis2,2,0,0,0,-25\n",
        ),
    ];
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    write_edited_files(dir);
}

/// The cases of the descriptions and scenarios of [`write_edited_files`].
fn description_cases() -> Vec<Case> {
    vec![
        case(
            "validation poses of a robot without tool targets",
            "simulate --robot no-tool.toml --validation-poses 10 --out out.csv",
            2,
            &["--validation-poses 10", "no-tool.toml", "`tool.targets_mm` is empty"],
        ),
        case(
            "a placement roll of 1e9 deg",
            "describe rpy.toml",
            2,
            &["rpy.toml", "field `placement.rpy_deg[0]`", "within +-360"],
        ),
        case(
            "a coupling slope of 1e300",
            "simulate --robot slope.toml --out out.csv",
            2,
            &["slope.toml", "field `couplings[1].slope`", "at most 1000"],
        ),
        case(
            "a placement in metres",
            "simulate --robot metres.toml --out out.csv",
            2,
            &["metres.toml", "field `placement.translation_mm`", "in metres?"],
        ),
        case(
            "a placement 3e12 mm away",
            "simulate --robot far.toml --out out.csv",
            2,
            &["far.toml", "field `placement.translation_mm`", "within 1 km"],
        ),
        case(
            "a third joint without axis targets",
            "simulate --robot three-joints.toml --out out.csv",
            2,
            &["three-joints.toml", "field `axis_targets`", "no entry for joint 3"],
        ),
        case(
            "a transmission order of 5000",
            "describe order5000.toml",
            2,
            &["order5000.toml", "field `joints[4].transmission_fit.order`", "1000"],
        ),
        case(
            "a transmission order of 99 for 16 points",
            "calibrate campaign.csv --robot order99.toml --allow-other-robot --out out",
            2,
            &[
                "experiment axis5",
                "`joints[4].transmission_fit.order` = 99",
                "16 points given",
            ],
        ),
        case(
            "a validation half-range beyond the joint's limits",
            "run half-range.toml --trials 1 --out out",
            2,
            &[
                "half-range.toml",
                "key `validation.half_range`",
                "joint 1",
                "[-170, 170]",
            ],
        ),
        case(
            "a scenario noise of 1e6 mm",
            "run noisy.toml --trials 1 --out out",
            2,
            &["noisy.toml", "key `measurement.net_radial_rms_mm`", "at most 100 mm"],
        ),
    ]
}

fn cases() -> Vec<Case> {
    let cal = "--calibration cal/calibration.json";
    let mut cases = description_cases();
    cases.extend([
        case(
            "a transducer offset of 100 rad",
            "joints --calibration offset.json -- 10 10 10 10 10 10",
            2,
            &[
                "offset.json",
                "field `robot.joints[0].transducer_offset_rad_or_m`",
                "beyond a turn",
            ],
        ),
        case(
            "a command that is not a number",
            &format!("joints {cal} -- nan 10 10 10 10 10"),
            2,
            &["cmd_1 = NaN is not a number"],
        ),
        case(
            "a pose's roll of 1e300 deg",
            &format!("compensate {cal} --poses roll.csv --out out.csv"),
            2,
            &["roll.csv", "line 2", "roll_deg", "within +-360"],
        ),
        case(
            "a payload of 1e9 kg",
            "calibrate payload.csv --out out",
            2,
            &["payload.csv:3", "column `payload_kg`", "0..=10000 kg"],
        ),
        case(
            "a temperature of 2000 deg C",
            "diagnose hot.csv --out out",
            2,
            &["hot.csv:3", "column `temperature_c`", "-100..=200 deg C"],
        ),
        case(
            "a plan sheet given to simulate --plan",
            "simulate --plan sheet.csv --out out.csv",
            2,
            &["sheet.csv", "--plan takes a TOML plan file", "CSV"],
        ),
        case(
            "a plan sheet given to plan --plan",
            "plan --plan sheet.csv --out out.csv",
            2,
            &["sheet.csv", "--plan takes a TOML plan file", "import points"],
        ),
        case(
            "validate into the calibration's own folder",
            &format!("validate {cal} campaign.csv --out cal --force"),
            2,
            &["--out `cal`", "folder of --calibration", "choose another folder"],
        ),
        case(
            "report on a residuals.csv that validate wrote",
            "report --calibration mixed/calibration.json --out out",
            2,
            &[
                "mixed/residuals.csv",
                "no column `radial_mm`",
                "`axiscal validate` writes",
            ],
        ),
        case(
            "tool poses with another tool's column names",
            &format!("compensate {cal} --poses rxyz.csv --out out.csv"),
            2,
            &[
                "rxyz.csv",
                "no columns id, roll_deg, pitch_deg, yaw_deg",
                "the header needs id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg",
            ],
        ),
        case(
            "tool poses without a header (its numbers repeat)",
            &format!("compensate {cal} --poses headless.csv --out out.csv"),
            2,
            &[
                "headless.csv",
                "is data, not a header",
                "id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg",
            ],
        ),
        case(
            "three command columns for a six-joint robot",
            &format!("joints {cal} --csv three.csv"),
            2,
            &[
                "three.csv",
                "no columns cmd_4, cmd_5, cmd_6",
                "the header needs cmd_1,cmd_2,cmd_3,cmd_4,cmd_5,cmd_6",
            ],
        ),
        case(
            "a span in radians",
            "plan --span 1=0.8 --out out.csv",
            0,
            &["warning: --span 1=0.8", "too short", "0.8 rad would be 45.8 deg"],
        ),
    ]);
    cases
}

#[test]
fn every_hostile_value_is_one_clear_error_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    write_inputs(dir.path());
    let residuals = std::fs::read(dir.path().join("cal/residuals.csv")).unwrap();
    for c in cases() {
        run_case(dir.path(), &c);
        clear_outputs(dir.path());
    }
    let after = std::fs::read(dir.path().join("cal/residuals.csv")).unwrap();
    assert!(after == residuals, "the calibration's residuals.csv was replaced");
}
