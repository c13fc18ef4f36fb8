//! Hostile run 15, unclear messages 6 and 7: a Latin-1 byte in an extra column (which the
//! reading ignores) refused the file in the CSV library's words ("malformed CSV ... field: 15
//! ... invalid utf-8") with no fix; a data row pasted with `;` was blamed on column `target`
//! ("missing value"). Now the extra column is ignored (the calibration is the clean file's), a
//! non-UTF-8 byte in a column that is read names that column and says to save as UTF-8, and
//! the pasted row names its separator.

use crate::common::hostile::{case, run_case};
use crate::common::{axiscal, simulated_campaign_csv};

/// The clean campaign with its data line `line` (1-based, of the file) rewritten by `edit`.
fn edited(source: &std::path::Path, out: &std::path::Path, line: usize, edit: impl Fn(&[u8]) -> Vec<u8>) {
    let bytes = std::fs::read(source).unwrap();
    let mut lines: Vec<Vec<u8>> = bytes.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect();
    lines[line - 1] = edit(&lines[line - 1]);
    std::fs::write(out, lines.join(&b'\n')).unwrap();
}

#[test]
fn a_latin1_byte_is_ignored_in_an_extra_column_and_named_in_a_read_one() {
    let (dir, clean) = simulated_campaign_csv(1);
    let with_operator = dir.path().join("operator.csv");
    let text = std::fs::read_to_string(&clean).unwrap();
    let mut out = Vec::new();
    for (i, l) in text.lines().enumerate() {
        out.extend_from_slice(l.as_bytes());
        match () {
            _ if l.starts_with('#') => {}
            _ if l.starts_with("experiment,") => out.extend_from_slice(b",operator"),
            _ => out.extend_from_slice(if i % 2 == 0 { b",M\xfcller" } else { b",Smith" }),
        }
        out.push(b'\n');
    }
    std::fs::write(&with_operator, out).unwrap();
    for (file, name) in [(&clean, "c0"), (&with_operator, "c1")] {
        axiscal()
            .current_dir(dir.path())
            .arg("calibrate")
            .arg(file)
            .args(["--out", name, "-q"])
            .assert()
            .success();
    }
    let read = |name: &str| std::fs::read(dir.path().join(name).join("calibration.json")).unwrap();
    assert_eq!(read("c0"), read("c1"), "the extra column changed the calibration");
    let in_experiment = dir.path().join("experiment.csv");
    let header = text.lines().position(|l| l.starts_with("experiment,")).unwrap() + 1;
    edited(&clean, &in_experiment, header + 4, |l| {
        let mut l = l.to_vec();
        l.insert(l.iter().position(|&b| b == b',').unwrap(), 0xe9);
        l
    });
    let line = format!("experiment.csv:{}: column `experiment`", header + 4);
    run_case(
        dir.path(),
        &case(
            "a Latin-1 byte in a read column",
            "calibrate experiment.csv --out out",
            2,
            &[&line, "save the file as UTF-8"],
        ),
    );
}

#[test]
fn a_row_pasted_with_semicolons_names_its_separator() {
    let (dir, clean) = simulated_campaign_csv(1);
    let text = std::fs::read_to_string(&clean).unwrap();
    let header = text.lines().position(|l| l.starts_with("experiment,")).unwrap() + 1;
    edited(&clean, &dir.path().join("semi.csv"), header + 7, |l| {
        String::from_utf8_lossy(l).replace(',', ";").into_bytes()
    });
    let line = format!("semi.csv:{}: the row is a single field containing ';'", header + 7);
    run_case(
        dir.path(),
        &case(
            "a row with ;",
            "calibrate semi.csv --out out",
            2,
            &[&line, "type it again with commas"],
        ),
    );
}
