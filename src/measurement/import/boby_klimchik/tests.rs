use super::*;
use approx::assert_relative_eq;

/// A well-formed file: pose `p` has SMR coordinates `p + t/10` and joint `p / 6 + 1` at `p`.
fn good_text() -> String {
    (0..LINES)
        .map(|p| {
            let mut v = [0.0; FIELDS_PER_LINE];
            for (c, x) in v.iter_mut().take(9).enumerate() {
                *x = p as f64 + c as f64 / 10.0;
            }
            let joint = p / POSES_PER_BLOCK;
            v[FIRST_JOINT_FIELD + joint] = p as f64;
            if joint == 1 {
                v[FIRST_JOINT_FIELD + 2] = -(p as f64);
            }
            v.iter().map(|x| format!("{x:.18e}")).collect::<Vec<_>>().join(" ")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn converts_blocks_to_axis_experiments() {
    let set = parse(&good_text(), Path::new("x.csv")).unwrap();
    assert_eq!(set.rows().len(), LINES * TARGETS);
    let experiments = set.experiments();
    assert_eq!(experiments.len(), JOINTS);
    for (k, e) in experiments.iter().enumerate() {
        assert_eq!(e.name, format!("axis{}", k + 1));
        assert_eq!(e.moved_joint, k + 1);
        assert_eq!(e.by_step().len(), POSES_PER_BLOCK);
    }
    let e1 = set.experiment("axis1").unwrap();
    let m = e1.get(2, 1).unwrap();
    // Target 1 is SMR 3: fields 7..=9.
    for (x, y) in m.position_mm.iter().zip([2.6, 2.7, 2.8]) {
        assert_relative_eq!(*x, y);
    }
    // The J2 block's J3 = -J2 reading is a constant relative joint 3.
    for m in set.experiment("axis2").unwrap().rows {
        assert_relative_eq!(m.cmd[2], 0.0);
        assert!(m.cmd[1] > 0.0);
    }
}

#[test]
fn wrong_field_count_names_the_line() {
    let mut lines: Vec<String> = good_text().lines().map(String::from).collect();
    lines[4].push_str(" 1.0");
    let e = parse(&lines.join("\n"), Path::new("d/N1N2N3Jval.csv")).unwrap_err();
    assert!(matches!(e, ImportError::FieldCount { line: 5, found: 22, .. }), "{e}");
    assert!(e.to_string().starts_with("d/N1N2N3Jval.csv:5: 22 fields"), "{e}");
}

#[test]
fn non_number_names_line_and_field() {
    for bad in ["abc", "nan", "inf"] {
        let mut lines: Vec<String> = good_text().lines().map(String::from).collect();
        let mut fields: Vec<String> = lines[7].split_whitespace().map(String::from).collect();
        fields[17] = bad.into();
        lines[7] = fields.join(" ");
        let e = parse(&lines.join("\n"), Path::new("f.csv")).unwrap_err();
        assert!(matches!(e, ImportError::NotANumber { line: 8, field: 18, .. }), "{e}");
        assert!(e.to_string().contains("field 18 (J3 deg)"), "{e}");
    }
}

#[test]
fn truncated_file_is_a_line_count_error() {
    let full = good_text();
    let text: Vec<&str> = full.lines().take(30).collect();
    let e = parse(&text.join("\n"), Path::new("f.csv")).unwrap_err();
    assert!(matches!(e, ImportError::LineCount { found: 30, .. }), "{e}");
}

#[test]
fn field_meanings() {
    assert_eq!(meaning(1), "SMR 1 x_mm");
    assert_eq!(meaning(9), "SMR 3 z_mm");
    assert_eq!(meaning(12), "zero");
    assert_eq!(meaning(21), "J6 deg");
}

/// `good_text` with its blocks in the order `order` (0-based block indices).
fn reordered(order: [usize; JOINTS]) -> String {
    let text = good_text();
    let lines: Vec<&str> = text.lines().collect();
    order
        .iter()
        .flat_map(|&b| lines[b * POSES_PER_BLOCK..(b + 1) * POSES_PER_BLOCK].to_vec())
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn reordered_blocks_are_named_by_the_joint_that_moves() {
    let set = parse(&reordered([2, 0, 1, 3, 5, 4]), Path::new("x.csv")).unwrap();
    let names: Vec<(&str, usize)> = set.experiments().iter().map(|e| (e.name, e.moved_joint)).collect();
    assert_eq!(
        names,
        [
            ("axis3", 3),
            ("axis1", 1),
            ("axis2", 2),
            ("axis4", 4),
            ("axis6", 6),
            ("axis5", 5)
        ]
    );
    let in_order = parse(&good_text(), Path::new("x.csv")).unwrap();
    for e in in_order.experiments() {
        assert_eq!(set.experiment(e.name).unwrap().rows, e.rows, "{}", e.name);
    }
}

#[test]
fn a_block_of_no_joint_or_of_a_joint_twice_names_its_lines() {
    let twice = reordered([0, 0, 2, 3, 4, 5]);
    let e = parse(&twice, Path::new("f.csv")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "f.csv: lines 7-12 (block 2): this block moves J1, as the block of lines 1-6 did: each joint has one block"
    );
    let mut lines: Vec<String> = good_text().lines().map(String::from).collect();
    for line in &mut lines[18..24] {
        let mut f: Vec<String> = line.split_whitespace().map(String::from).collect();
        f[FIRST_JOINT_FIELD + 3] = "0".into();
        *line = f.join(" ");
    }
    let e = parse(&lines.join("\n"), Path::new("f.csv")).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("f.csv: lines 19-24 (block 4): no joint moves"),
        "{e}"
    );
}
