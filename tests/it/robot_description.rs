//! Robot description files: the shipped file loads; bad files name the file and the field.

use axiscal::robot::{DescriptionError, RobotDescription};
use std::path::Path;

const SHIPPED: &str = include_str!("../../scenarios/robots/asea-irb6l.toml");

fn parse(text: &str) -> Result<RobotDescription, DescriptionError> {
    RobotDescription::from_toml_str(text, Path::new("robot.toml"))
}

#[test]
fn shipped_description_round_trips_through_toml() {
    let d = RobotDescription::asea_irb6l();
    assert_eq!(d.dof(), 6);
    let text = toml::to_string(&d).unwrap();
    assert_eq!(parse(&text).unwrap(), d);
}

#[test]
fn unknown_key_is_rejected_with_file_and_line() {
    let text = SHIPPED.replacen("phi_deg = 90.0", "phi_deg = 90.0\nphy_deg = 1.0", 1);
    let e = parse(&text).unwrap_err().to_string();
    assert!(e.starts_with("robot.toml"), "{e}");
    assert!(e.contains("phy_deg") && e.contains("line"), "{e}");
}

#[test]
fn inconsistent_values_name_the_field() {
    let cases = [
        (
            SHIPPED.replacen("limits = [-40.0, 40.0]", "limits = [40.0, -40.0]", 1),
            "joints[1].limits",
        ),
        (
            SHIPPED.replacen("mass_kg = 22.0", "mass_kg = -1.0", 1),
            "joints[1].mass_kg",
        ),
        (
            SHIPPED.replacen(
                "com_mm = [-345.0, 0.0, 0.0]\nrepeatability_sigma = 1.1806e-4",
                "com_mm = [-345.0, 0.0, 0.0]\nrepeatability_sigma = -1e-4",
                1,
            ),
            "joints[1].repeatability_sigma",
        ),
        (
            SHIPPED.replacen("from = 3\nto = 4", "from = 3\nto = 5", 1),
            "couplings[1]",
        ),
        (
            SHIPPED.replacen(
                "[80.0, 0.0, 150.0], [0.0, 80.0, 150.0]]",
                "[0.0, 0.0, 250.0], [0.0, 0.0, 350.0]]",
                1,
            ),
            "tool.targets_mm",
        ),
        (
            SHIPPED.replacen("target0 = { link = 3,", "target0 = { link = 6,", 1),
            "axis_targets[3].target0.link",
        ),
    ];
    for (text, field) in cases {
        let e = parse(&text).unwrap_err();
        assert!(matches!(e, DescriptionError::Invalid { .. }), "{e}");
        let msg = e.to_string();
        assert!(
            msg.starts_with("robot.toml: field `") && msg.contains(field),
            "{field}: {msg}"
        );
    }
}

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let e = RobotDescription::from_file(Path::new("no/such/robot.toml")).unwrap_err();
    assert!(e.to_string().contains("no/such/robot.toml"));
}

/// The shipped FANUC URDF with one slip each, as a user's editor or exporter makes them: the
/// description is refused (exit 2) naming the URDF, the line and the joint or element, where
/// the URDF parser said "No elements found" or "custom: invalid float literal" with no place.
#[test]
fn urdf_slips_are_said_with_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/robots/real");
    let toml = std::fs::read_to_string(shipped.join("fanuc-r2000ic.toml")).unwrap();
    let urdf = std::fs::read_to_string(shipped.join("fanuc-r2000ic.urdf")).unwrap();
    let line_of = |needle: &str| urdf.lines().position(|l| l.contains(needle)).unwrap() + 1;
    let describe = |from: &str, to: &str| {
        assert_eq!(urdf.matches(from).count(), 1, "{from}");
        std::fs::write(dir.path().join("fanuc-r2000ic.urdf"), urdf.replace(from, to)).unwrap();
        std::fs::write(dir.path().join("fanuc.toml"), &toml).unwrap();
        let out = crate::common::axiscal()
            .arg("describe")
            .arg(dir.path().join("fanuc.toml"))
            .args(["--poses", "10"])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2));
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let err = describe("</robot>", "");
    assert!(
        err.contains("fanuc-r2000ic.urdf: `<robot>` of line") && err.contains("is never closed"),
        "{err}"
    );
    let err = describe("xyz=\"1.075 0 0\"", "xyz=\"1,075 0 0\"");
    assert!(
        err.contains(&format!(
            "line {}: joint `joint_3`: `<origin xyz=\"1,075 0 0\">`: `1,075` is not a number; a URDF writes a decimal point",
            line_of("xyz=\"1.075 0 0\"")
        )),
        "{err}"
    );
    let err = describe("lower=\"-2.5\"", "lower=\"-2.5 rad\"");
    assert!(
        err.contains(&format!(
            "line {}: joint `joint_3`: `<limit lower=\"-2.5 rad\">`",
            line_of("lower=\"-2.5\"")
        )),
        "{err}"
    );
    let err = describe(
        "<joint name=\"joint_4\" type=\"revolute\">",
        "<joint name=\"joint_4\" type=\"rotary\">",
    );
    assert!(
        err.contains(&format!(
            "line {}: joint `joint_4`: joint type `rotary`",
            line_of("name=\"joint_4\"")
        )),
        "{err}"
    );
    let err = describe("<joint name=\"joint_4\" type=\"revolute\">", "<joint name=\"joint_4\">");
    assert!(
        err.contains(&format!(
            "line {}: `<joint>` has no `type=\"...\"`",
            line_of("name=\"joint_4\"")
        )),
        "{err}"
    );
    let err = describe("<parent link=\"link_2\"/>", "<parent name=\"link_2\"/>");
    assert!(
        err.contains(&format!(
            "line {}: joint `joint_3`: `<parent>` has no `link=\"...\"`",
            line_of("<parent link=\"link_2\"/>")
        )),
        "{err}"
    );
    let err = describe("<robot name=", "<wrapper><robot name=");
    assert!(err.contains("line 7: the root element is `<wrapper>`"), "{err}");
    let err = describe(
        "<?xml version=\"1.0\"?>",
        "<?xml version=\"1.0\"?>\n<!DOCTYPE robot [\n  <!ENTITY l \"1.075\">\n  <!ELEMENT robot ANY>\n]>",
    );
    assert!(
        err.contains("Malformed XML; the document type declaration of line 2 holds an internal subset"),
        "{err}"
    );
    // A camera on link 3: the chain branches there, and the error names both ways on.
    let err = describe(
        "  <joint name=\"joint_4\"",
        "  <link name=\"camera\"/>\n  <joint name=\"camera_mount\" type=\"fixed\">\n    \
         <parent link=\"link_3\"/><child link=\"camera\"/>\n  </joint>\n  <joint name=\"joint_4\"",
    );
    assert!(
        err.contains("link `link_3` branches to `camera`, `link_4`: name the `tip_link`")
            && err.contains("(a leaf below it: `link_6`, `camera`)"),
        "{err}"
    );
}
