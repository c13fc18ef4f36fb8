//! Malformed-file tests: each error names the file, the line and the column.

use super::*;
use std::io::Write;

const HEADER: &str = "experiment,moved_joint,step,target,x_mm,y_mm,z_mm,cmd_1,cmd_2";

/// Writes `text` to a temporary file and reads it with N = `joint_count`.
fn read_text(
    text: &str,
    joint_count: Option<usize>,
) -> (tempfile::NamedTempFile, Result<MeasurementSet, MeasurementFileError>) {
    let mut file = tempfile::NamedTempFile::new().unwrap();
    file.write_all(text.as_bytes()).unwrap();
    file.flush().unwrap();
    let result = read_measurements(file.path(), joint_count);
    (file, result)
}

/// Reads `text`, expects an error, and checks its message names the file, `line` and `column`.
fn expect_error(text: &str, joint_count: Option<usize>, line: u64, column: &str) -> MeasurementFileError {
    let (file, result) = read_text(text, joint_count);
    let error = result.expect_err("malformed file must be rejected");
    let message = error.to_string();
    let path = file.path().display().to_string();
    assert!(message.contains(&path), "{message:?} does not name {path}");
    assert!(
        message.contains(&format!(":{line}:")),
        "{message:?} does not name line {line}"
    );
    assert!(
        message.contains(&format!("`{column}`")),
        "{message:?} does not name column {column}"
    );
    error
}

#[test]
fn reads_a_good_file_with_comments_extra_columns_and_any_order() {
    let text = "# produced by hand\n\
                cmd_2, note ,target,step,moved_joint,experiment,z_mm,y_mm,x_mm,cmd_1,temperature_c\n\
                # a comment between rows\n\
                2.5,hello,0,0,1,axis1,3,2,1,-10,21.5\n\
                2.5,,1,0,1,axis1,6,5,4,-10,\n";
    let (_file, result) = read_text(text, Some(2));
    let set = result.unwrap();
    assert_eq!(set.joint_count(), 2);
    let rows = set.rows();
    assert_eq!(rows.len(), 2);
    assert_eq!(
        rows[0].position_mm.map(f64::to_bits),
        [1.0f64, 2.0, 3.0].map(f64::to_bits)
    );
    assert_eq!(
        rows[0].cmd.iter().map(|c| c.to_bits()).collect::<Vec<_>>(),
        [(-10f64).to_bits(), 2.5f64.to_bits()]
    );
    assert_eq!(rows[0].temperature_c.to_bits(), 21.5f64.to_bits());
    assert_eq!(
        rows[1].temperature_c.to_bits(),
        Measurement::DEFAULT_TEMPERATURE_C.to_bits()
    );
    assert_eq!(rows[1].payload_kg.to_bits(), Measurement::DEFAULT_PAYLOAD_KG.to_bits());
    let (_file, inferred) = read_text(text, None);
    assert_eq!(inferred.unwrap(), set);
}

#[test]
fn missing_column() {
    let text = "experiment,moved_joint,step,target,x_mm,z_mm,cmd_1,cmd_2\naxis1,1,0,0,1,3,0,0\n";
    let e = expect_error(text, Some(2), 1, "y_mm");
    assert!(matches!(e, MeasurementFileError::MissingColumn { .. }));
}

/// Coordinates headed as other tools head them: the rename, and the conversion a unit needs;
/// a name that only starts with the letter (`xyz_id`) is no coordinate.
#[test]
fn a_coordinate_headed_with_its_unit_otherwise_is_named() {
    let row = "\naxis1,1,0,0,1,2,3,0,0\n";
    for (names, found, says) in [
        ("X [mm],Y [mm],Z [mm]", "X [mm]", "rename it `x_mm`"),
        ("x_mm,y (m),z (m)", "y (m)", "multiply it by 1000 to millimetres"),
        ("x_mm,y_mm,Z", "Z", "without a unit"),
        ("x_mm,y_mm,Z/in", "Z/in", "multiply it by 25.4"),
    ] {
        let text = format!("experiment,moved_joint,step,target,{names},cmd_1,cmd_2{row}");
        let column = format!("{}_mm", found[..1].to_ascii_lowercase());
        let e = expect_error(&text, Some(2), 1, &column);
        let message = e.to_string();
        assert!(
            matches!(e, MeasurementFileError::CoordinateSpelled { .. })
                && message.contains(&format!("\"{found}\""))
                && message.contains(says),
            "{names}: {message}"
        );
    }
    let text = format!("experiment,moved_joint,step,target,x_mm,xyz_id,z_mm,cmd_1,cmd_2{row}");
    let e = expect_error(&text, Some(2), 1, "y_mm");
    assert!(matches!(e, MeasurementFileError::MissingColumn { .. }), "{e}");
}

#[test]
fn line_numbers_count_comment_lines() {
    let text = format!("# one\n# two\n{HEADER}\naxis1,1,0,0,1,2,3,0,0\n# three\naxis1,1,1,0,1,oops,3,0,0\n");
    let e = expect_error(&text, Some(2), 6, "y_mm");
    assert!(matches!(e, MeasurementFileError::NotANumber { .. }));
}

/// A data row whose experiment id starts with `#` is refused naming its line, before or after
/// other rows, at the end of the file without a line end too; remarks with commas are not.
#[test]
fn a_commented_data_row_is_refused_and_remarks_are_not() {
    let row = "axis1,1,0,0,1,2,3,0,0";
    for (text, line) in [
        (format!("{HEADER}\n#{row}\n{row}\n"), 2),
        (
            format!(
                "# pre, 1, 2, 3, 4, 5, 6, 7, 8\n{HEADER}\n{row}\n# a, remark, of, nine, fields, in, words, it, is\n#x,1,1,0,1,2,3,0,0"
            ),
            5,
        ),
    ] {
        let (file, result) = read_text(&text, Some(2));
        let e = result.expect_err("a commented data row").to_string();
        assert!(e.starts_with(&format!("{}:{line}: ", file.path().display())), "{e}");
        assert!(e.contains("starts with `#` but has 9 fields"), "{e}");
    }
    let (_file, result) = read_text(
        &format!("{HEADER}\n{row}\n# measured 2024-01-05, by J. Smith, room 3\n"),
        Some(2),
    );
    assert_eq!(result.unwrap().rows().len(), 1);
    let (_file, result) = read_text(&format!("{HEADER}\n\"#axis1\",1,0,0,1,2,3,0,0\n"), Some(2));
    assert_eq!(result.unwrap().rows()[0].experiment, "#axis1");
}

/// A target's name or a setup's label beyond 200 characters is refused, shown by its start.
#[test]
fn a_label_of_a_megabyte_is_refused_by_its_start() {
    let name = "T".repeat(1_000_000);
    let text = format!("{HEADER}\naxis1,1,0,{name},1,2,3,0,0\n");
    let e = expect_error(&text, Some(2), 2, "target").to_string();
    assert!(
        e.contains("[1000000 characters]") && e.len() < 400,
        "{}",
        &e[..400.min(e.len())]
    );
}

#[test]
fn non_number() {
    let text = format!("{HEADER}\naxis1,1,0,0,1,2,3,0,zero\n");
    let e = expect_error(&text, Some(2), 2, "cmd_2");
    assert!(matches!(e, MeasurementFileError::NotANumber { .. }));
}

#[test]
fn nan_and_infinity() {
    let text = format!("{HEADER}\naxis1,1,0,0,NaN,2,3,0,0\n");
    let e = expect_error(&text, Some(2), 2, "x_mm");
    assert!(matches!(e, MeasurementFileError::NotFinite { .. }));
    let text = format!("{HEADER}\naxis1,1,0,0,1,2,3,0,0\naxis1,1,1,0,1,2,-inf,0,0\n");
    let e = expect_error(&text, Some(2), 3, "z_mm");
    assert!(matches!(e, MeasurementFileError::NotFinite { .. }));
}

#[test]
fn duplicated_experiment_step_target() {
    let text = format!("{HEADER}\naxis1,1,0,0,1,2,3,0,0\naxis1,1,0,1,1,2,3,0,0\naxis1,1,0,0,1,2,3,0,0\n");
    let e = expect_error(&text, Some(2), 4, "experiment,step,target");
    assert!(matches!(
        e,
        MeasurementFileError::InvalidRow {
            problem,
            ..
        } if matches!(*problem, RowProblem::DuplicateKey { first_at: 2, .. })
    ));
}

#[test]
fn moved_joint_out_of_range() {
    let text = format!("{HEADER}\naxis3,3,0,0,1,2,3,0,0\n");
    let e = expect_error(&text, Some(2), 2, "moved_joint");
    assert!(matches!(
        e,
        MeasurementFileError::InvalidRow {
            problem,
            ..
        } if matches!(*problem, RowProblem::MovedJointOutOfRange { .. })
    ));
}

#[test]
fn wrong_joint_count() {
    let text = format!("{HEADER}\naxis1,1,0,0,1,2,3,0,0\n");
    let e = expect_error(&text, Some(3), 1, "cmd_3");
    assert!(matches!(
        e,
        MeasurementFileError::JointCount {
            found: 2,
            expected: 3,
            ..
        }
    ));
    let e = expect_error(&text, Some(1), 1, "cmd_2");
    assert!(matches!(
        e,
        MeasurementFileError::JointCount {
            found: 2,
            expected: 1,
            ..
        }
    ));
    // Without an expected count the cmd columns must be contiguous.
    let text = "experiment,moved_joint,step,target,x_mm,y_mm,z_mm,cmd_1,cmd_3\naxis1,1,0,0,1,2,3,0,0\n";
    let e = expect_error(text, None, 1, "cmd_2");
    assert!(matches!(e, MeasurementFileError::MissingColumn { .. }));
}

#[test]
fn negative_step_and_target() {
    let text = format!("{HEADER}\naxis1,1,-1,0,1,2,3,0,0\n");
    let e = expect_error(&text, Some(2), 2, "step");
    assert!(matches!(e, MeasurementFileError::Negative { .. }));
    let text = format!("{HEADER}\naxis1,1,0,-2,1,2,3,0,0\n");
    let e = expect_error(&text, Some(2), 2, "target");
    assert!(matches!(e, MeasurementFileError::Negative { .. }));
    let text = format!("{HEADER}\naxis1,1,0.5,0,1,2,3,0,0\n");
    let e = expect_error(&text, Some(2), 2, "step");
    assert!(matches!(e, MeasurementFileError::NotAnInteger { .. }));
}

#[test]
fn short_row_and_duplicate_column() {
    let text = format!("{HEADER}\naxis1,1,0,0,1,2,3,0\n");
    let e = expect_error(&text, Some(2), 2, "cmd_2");
    assert!(matches!(e, MeasurementFileError::MissingField { .. }));
    let text = format!("{HEADER},x_mm\naxis1,1,0,0,1,2,3,0,0,1\n");
    let e = expect_error(&text, Some(2), 1, "x_mm");
    assert!(matches!(e, MeasurementFileError::DuplicateColumn { .. }));
}

#[test]
fn empty_file_and_header_only() {
    for text in ["", "# only a comment\n"] {
        let (file, result) = read_text(text, Some(2));
        let message = result.unwrap_err().to_string();
        assert!(
            message.contains(&file.path().display().to_string()) && message.contains("empty"),
            "{message}"
        );
    }
    let (_file, result) = read_text(&format!("# c\n{HEADER}\n"), Some(2));
    assert!(matches!(result, Err(MeasurementFileError::NoRows { line: 2, .. })));
}

#[test]
fn writer_refuses_to_overwrite() {
    let (file, result) = read_text(&format!("{HEADER}\naxis1,1,0,0,1,2,3,0,0\n"), Some(2));
    let set = result.unwrap();
    let e = write_measurements(file.path(), &set, false).unwrap_err();
    assert!(matches!(e, MeasurementFileError::Exists { .. }), "{e}");
    write_measurements(file.path(), &set, true).unwrap();
    assert_eq!(read_measurements(file.path(), Some(2)).unwrap(), set);
}

#[test]
fn byte_order_mark_is_ignored() {
    let (_file, result) = read_text(&format!("\u{feff}{HEADER}\naxis1,1,0,0,1,2,3,0,0\n"), Some(2));
    assert_eq!(result.unwrap().rows()[0].experiment, "axis1");
}

/// Target ids as trackers write them (`SMR2`, `T1`, `A`) are numbered 0, 1, ... in the order
/// they first appear and written back as names; a file mixing names and integers, or a
/// negative or fractional id among integers, is refused naming the line and the column.
#[test]
fn named_targets_are_numbered_in_order_and_round_trip() {
    let text = format!("{HEADER}\nposes,0,0,SMR2,1,2,3,0,0\nposes,0,0,T1,4,5,6,0,0\nposes,0,1,SMR2,7,8,9,10,20\n");
    let (_file, result) = read_text(&text, Some(2));
    let set = result.expect("named targets are read");
    let ids: Vec<usize> = set.rows().iter().map(|m| m.target).collect();
    assert_eq!(ids, [0, 1, 0]);
    assert_eq!(
        (set.target_name(0), set.target_name(1)),
        ("SMR2".to_string(), "T1".to_string())
    );
    let mut written = Vec::new();
    write_measurements_to(&mut written, &set).unwrap();
    let (_again, reread) = read_text(std::str::from_utf8(&written).unwrap(), Some(2));
    assert_eq!(reread.unwrap(), set);
    let mixed = format!("{HEADER}\nposes,0,0,SMR2,1,2,3,0,0\nposes,0,0,1,4,5,6,0,0\n");
    let error = expect_error(&mixed, Some(2), 3, "target");
    assert!(error.to_string().contains("all integers or all names"), "{error}");
    let mixed = format!("{HEADER}\nposes,0,0,0,1,2,3,0,0\nposes,0,0,A,4,5,6,0,0\n");
    expect_error(&mixed, Some(2), 3, "target");
    let negative = format!("{HEADER}\nposes,0,0,0,1,2,3,0,0\nposes,0,0,-1,4,5,6,0,0\n");
    assert!(
        expect_error(&negative, Some(2), 3, "target")
            .to_string()
            .contains("negative")
    );
}

/// A `setup` column: labels numbered in the order they first appear, written back (only a
/// file with two or more setups carries the column).
#[test]
fn setups_are_read_and_round_trip() {
    let text = format!(
        "{HEADER},setup\nposes,0,0,0,1,2,3,0,0,left\nposes,0,1,0,4,5,6,0,0,right\nposes,0,2,0,7,8,9,0,0,left\n"
    );
    let (_file, result) = read_text(&text, Some(2));
    let set = result.expect("setups are read");
    assert_eq!((0..3).map(|r| set.setup_of(r)).collect::<Vec<_>>(), [0, 1, 0]);
    assert_eq!(set.setup_names(), ["left", "right"]);
    let mut written = Vec::new();
    write_measurements_to(&mut written, &set).unwrap();
    let (_again, reread) = read_text(std::str::from_utf8(&written).unwrap(), Some(2));
    assert_eq!(reread.unwrap(), set);
    let one = format!("{HEADER},setup\nposes,0,0,0,1,2,3,0,0,only\n");
    let (_f, one) = read_text(&one, Some(2));
    let mut written = Vec::new();
    write_measurements_to(&mut written, &one.unwrap()).unwrap();
    assert!(!std::str::from_utf8(&written).unwrap().contains("setup"));
}

#[test]
fn a_row_longer_than_the_header_is_refused_and_trailing_empty_cells_are_not() {
    let (_file, result) = read_text(&format!("{HEADER}\naxis1,1,0,0,1,2,3,0,0,,\n"), Some(2));
    assert!(result.is_ok(), "{result:?}");
    let (file, result) = read_text(
        &format!("{HEADER}\naxis1,1,0,0,1,2,3,0,0\naxis1,1,1,0,1,2,3,0,0,5\n"),
        Some(2),
    );
    let message = result.unwrap_err().to_string();
    let place = format!("{}:3:", file.path().display());
    assert!(
        message.contains(&place) && message.contains("10 fields, the header 9"),
        "{message}"
    );
}

#[test]
fn json_xml_toml_binary_and_blank_files_are_named() {
    for (text, said) in [
        (&b"{\"schema\": 1}"[..], "looks like JSON"),
        (&[1u8, 2, 3, b'a', b',', b'b'][..], "binary"),
        (&b"  \n\n \n"[..], "empty file"),
        (
            &b"<?xml version=\"1.0\"?>\n<robot name=\"r\">\n"[..],
            "looks like a URDF",
        ),
        (&b"# a robot\nname = \"r\"\n[[joints]]\n"[..], "looks like a TOML file"),
        (&b"[placement]\nx = 1\n"[..], "looks like a TOML file"),
        (&b"description = \"a, b\"\n"[..], "looks like a TOML file"),
        (&b"[\n  {\"a\": 1}\n]\n"[..], "looks like JSON"),
    ] {
        let mut file = tempfile::NamedTempFile::new().unwrap();
        file.write_all(text).unwrap();
        file.flush().unwrap();
        let message = read_measurements(file.path(), Some(2)).unwrap_err().to_string();
        assert!(message.contains(said), "{message}");
    }
}

#[test]
fn a_converted_value_is_shown_without_the_conversions_last_bits() {
    // The products carry the multiplication's rounding: shown as the user would write them.
    assert_eq!(format_f64(1e-9 * 1e3), "1.0000000000000002e-6");
    assert_eq!(format_f64_converted(1e-9 * 1e3), "1e-6");
    assert_eq!(format_f64(0.0049 * 1e3), "4.8999999999999995");
    assert_eq!(format_f64_converted(0.0049 * 1e3), "4.9");
    assert_eq!(format_f64_converted(123.456), "123.456");
    // Twelve significant digits kept: a value the user wrote with many digits is not cut.
    assert_eq!(format_f64_converted(0.123456789012 * 1e3), "123.456789012");
}

#[test]
fn a_command_column_spelled_otherwise_is_refused_naming_it() {
    // `cmd_02` after `cmd_2` replaced joint 2's commands silently (the last one won).
    for (name, header) in [("cmd_02", "cmd_1,cmd_2,cmd_02"), ("cmd_+2", "cmd_1,cmd_+2")] {
        let header = HEADER.replace("cmd_1,cmd_2", header);
        let extra = if header.contains("cmd_02") { ",3" } else { "" };
        let (_f, r) = read_text(&format!("{header}\naxis1,1,0,0,1,2,3,0,0{extra}\n"), Some(2));
        let e = r.unwrap_err().to_string();
        assert!(
            e.contains(&format!("column `{name}`")) && e.contains("rename it `cmd_2`"),
            "{e}"
        );
    }
}

/// A number written with a typographic minus sign (U+2212) is named, with the ASCII number.
#[test]
fn a_typographic_minus_is_named() {
    let text = format!("{HEADER}\naxis1,1,0,0,\u{2212}3108.36,2,3,0,0\n");
    let e = expect_error(&text, Some(2), 2, "x_mm").to_string();
    assert!(
        e.contains("a typographic minus sign") && e.ends_with("write `-3108.36`"),
        "{e}"
    );
}
