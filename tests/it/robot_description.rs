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
