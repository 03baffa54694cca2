use super::*;

fn table() -> JointCompTable {
    JointCompTable::new(vec![
        CompPoint {
            nominal_mm: 0.0,
            forward_trim_mm: 0.001,
            reverse_trim_mm: 0.0015,
        },
        CompPoint {
            nominal_mm: 100.0,
            forward_trim_mm: -0.002,
            reverse_trim_mm: -0.0015,
        },
        CompPoint {
            nominal_mm: 200.0,
            forward_trim_mm: 0.0,
            reverse_trim_mm: 0.0005,
        },
    ])
    .unwrap()
}

#[test]
fn a_type_1_file_holds_the_trims_with_six_decimals_and_nothing_else() {
    assert_eq!(
        table().to_comp_file(CompFileType::Trims),
        "0.000000 0.001000 0.001500\n\
         100.000000 -0.002000 -0.001500\n\
         200.000000 0.000000 0.000500\n"
    );
}

#[test]
fn a_type_0_file_holds_the_positions_the_loader_turns_back_into_the_trims() {
    // Trim = nominal − value: a trim of +1 µm means the joint fell 1 µm short.
    let text = table().to_comp_file(CompFileType::MeasuredPositions);
    assert_eq!(
        text,
        "0.000000 -0.001000 -0.001500\n\
         100.000000 100.002000 100.001500\n\
         200.000000 200.000000 199.999500\n"
    );
    let back = parse_comp_file(&text, CompFileType::MeasuredPositions).unwrap();
    for (a, b) in back.points().iter().zip(table().points()) {
        assert!((a.forward_trim_mm - b.forward_trim_mm).abs() < 1e-12);
        assert!((a.reverse_trim_mm - b.reverse_trim_mm).abs() < 1e-12);
    }
}

#[test]
fn the_trim_is_interpolated_on_the_commanded_position_and_held_beyond_the_ends() {
    let t = table();
    let fwd = |x| t.trim_mm(x, Direction::Positive);
    let rev = |x| t.trim_mm(x, Direction::Negative);
    assert!((fwd(50.0) - (-0.0005)).abs() < 1e-15);
    assert!((rev(150.0) - (-0.0005)).abs() < 1e-15);
    assert_eq!(fwd(-10.0), 0.001);
    assert_eq!(rev(999.0), 0.0005);
}

#[test]
fn a_header_line_is_refused_with_its_line_number() {
    let text = format!(
        "# X axis trims\n{}",
        table().to_comp_file(CompFileType::Trims)
    );
    let err = check_comp_file(&text).unwrap_err();
    assert_eq!(
        err,
        CompFileError::CommentLine {
            line: 1,
            text: "# X axis trims".into()
        }
    );
    assert!(err.to_string().contains("without a warning"), "{err}");
}

#[test]
fn a_comment_in_the_middle_is_refused_at_its_line() {
    let mut lines: Vec<String> = table()
        .to_comp_file(CompFileType::Trims)
        .lines()
        .map(String::from)
        .collect();
    lines.insert(2, "; measured 2026-11-28".into());
    let err = check_comp_file(&lines.join("\n")).unwrap_err();
    assert!(
        matches!(err, CompFileError::CommentLine { line: 3, .. }),
        "{err:?}"
    );
}

#[test]
fn non_ascending_nominal_positions_are_refused_at_the_offending_line() {
    let text = "0 0 0\n10 0 0\n10 0 0\n";
    assert_eq!(
        check_comp_file(text).unwrap_err(),
        CompFileError::NotAscending {
            line: 3,
            nominal_mm: 10.0,
            previous_mm: 10.0
        }
    );
    assert!(matches!(
        check_comp_file("5 0 0\n4 0 0\n").unwrap_err(),
        CompFileError::NotAscending { line: 2, .. }
    ));
}

#[test]
fn more_than_256_points_are_refused_at_line_257() {
    let text: String = (0..300).map(|i| format!("{i} 0 0\n")).collect();
    assert_eq!(
        check_comp_file(&text).unwrap_err(),
        CompFileError::TooManyPoints {
            count: 300,
            max: 256,
            line: 257
        }
    );
    let ok: String = (0..256).map(|i| format!("{i} 0 0\n")).collect();
    assert_eq!(check_comp_file(&ok).unwrap().points, 256);
}

#[test]
fn nan_and_infinities_are_refused_with_line_and_column() {
    assert_eq!(
        check_comp_file("0 0 0\n1 NaN 0\n").unwrap_err().to_string(),
        "line 2, column 2: NaN is not a usable value (finite, |value| ≤ 100000 mm)"
    );
    assert!(matches!(
        check_comp_file("0 0 0\n1 0 -inf\n").unwrap_err(),
        CompFileError::NotFinite {
            line: 2,
            column: 3,
            ..
        }
    ));
}

#[test]
fn a_wrong_column_count_is_refused_even_where_the_loader_would_ignore_the_extra() {
    // sscanf("%lf %lf %lf") reads the first three of four numbers: the checker is stricter,
    // since a fourth column means the file is not what the writer thinks it is.
    assert!(matches!(
        check_comp_file("0 0 0 7\n1 0 0\n").unwrap_err(),
        CompFileError::WrongColumnCount {
            line: 1,
            found: 4,
            ..
        }
    ));
    assert!(matches!(
        check_comp_file("0 0 0\n1 0\n").unwrap_err(),
        CompFileError::WrongColumnCount {
            line: 2,
            found: 2,
            ..
        }
    ));
    assert!(matches!(
        check_comp_file("0 0 0\n1 0 0.0.1\n").unwrap_err(),
        CompFileError::NotANumber {
            line: 2,
            column: 3,
            ..
        }
    ));
}

#[test]
fn an_empty_line_before_more_points_is_refused_and_trailing_ones_are_not() {
    assert_eq!(
        check_comp_file("0 0 0\n\n1 0 0\n").unwrap_err(),
        CompFileError::BlankLine { line: 2 }
    );
    assert_eq!(check_comp_file("0 0 0\r\n1 0 0\r\n\n\n").unwrap().points, 2);
}

#[test]
fn empty_and_single_point_files_are_refused() {
    assert_eq!(check_comp_file("").unwrap_err(), CompFileError::NoPoints);
    assert_eq!(
        check_comp_file("0 0 0\n").unwrap_err(),
        CompFileError::TooFewPoints { count: 1 }
    );
}

#[test]
fn a_type_0_file_read_as_type_1_is_refused_for_its_millimetre_trims() {
    let text = table().to_comp_file(CompFileType::MeasuredPositions);
    let err = parse_comp_file(&text, CompFileType::Trims).unwrap_err();
    assert!(
        matches!(err, CompFileError::TrimTooLarge { line: 2, .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("type-0 file"), "{err}");
}

#[test]
fn the_ini_lines_name_the_joint_the_file_and_its_type() {
    assert_eq!(
        ini_lines(2, "joint2-z.comp", CompFileType::Trims).unwrap(),
        "[JOINT_2]\nCOMP_FILE = joint2-z.comp\nCOMP_FILE_TYPE = 1\n"
    );
    assert_eq!(
        ini_lines(0, "x.comp", CompFileType::MeasuredPositions).unwrap(),
        "[JOINT_0]\nCOMP_FILE = x.comp\nCOMP_FILE_TYPE = 0\n"
    );
    for bad in ["", "a\nb", "x#1.comp", " x.comp"] {
        assert!(
            ini_lines(0, bad, CompFileType::Trims).is_err(),
            "{bad:?} accepted"
        );
    }
}

#[test]
fn the_file_type_numbers_are_0_and_1() {
    assert_eq!(
        CompFileType::from_number(0),
        Some(CompFileType::MeasuredPositions)
    );
    assert_eq!(CompFileType::from_number(1), Some(CompFileType::Trims));
    assert_eq!(CompFileType::from_number(2), None);
    assert_eq!(CompFileType::Trims.number(), 1);
}
