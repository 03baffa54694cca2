use super::*;

fn program() -> CecProgram {
    CecProgram {
        channel: 1,
        comment_lines: vec!["made for a test".into()],
        tables: vec![
            CecTable::new(
                "AX1",
                "AX2",
                0.0,
                100.0,
                &[0.0, 0.0021, -0.0013],
                CecDirection::Both,
            )
            .unwrap(),
            CecTable::new(
                "AX1",
                "AX1",
                0.0,
                100.0,
                &[0.001, 0.002, 0.0],
                CecDirection::Negative,
            )
            .unwrap(),
        ],
    }
}

#[test]
fn a_program_is_written_in_the_manuals_layout() {
    let text = write_cec_program(&program()).unwrap();
    let expected = "%_N_NC_CEC_INI
CHANDATA(1)
; made for a test
$AN_CEC[0,0]=0
$AN_CEC[0,1]=0.0021
$AN_CEC[0,2]=-0.0013
$AN_CEC_INPUT_AXIS[0]=(AX1)
$AN_CEC_OUTPUT_AXIS[0]=(AX2)
$AN_CEC_STEP[0]=100.0
$AN_CEC_MIN[0]=0.0
$AN_CEC_MAX[0]=200.0
$AN_CEC_DIRECTION[0]=0
$AN_CEC_MULT_BY_TABLE[0]=0
$AN_CEC_IS_MODULO[0]=0
$AN_CEC[1,0]=0.001
$AN_CEC[1,1]=0.002
$AN_CEC[1,2]=0
$AN_CEC_INPUT_AXIS[1]=(AX1)
$AN_CEC_OUTPUT_AXIS[1]=(AX1)
$AN_CEC_STEP[1]=100.0
$AN_CEC_MIN[1]=0.0
$AN_CEC_MAX[1]=200.0
$AN_CEC_DIRECTION[1]=-1
$AN_CEC_MULT_BY_TABLE[1]=0
$AN_CEC_IS_MODULO[1]=0
M17
";
    assert_eq!(text, expected);
}

#[test]
fn a_written_program_reads_back_to_the_same_tables() {
    let p = program();
    let back = parse_cec_program(&write_cec_program(&p).unwrap()).unwrap();
    assert_eq!(back, p);
}

#[test]
fn the_compensation_follows_the_direction_setting_and_sums_per_output_axis() {
    let p = program();
    let at = |_: &str| 50.0;
    let neg = |_: &str| Direction::Negative;
    let pos = |_: &str| Direction::Positive;
    // Table 1 (AX1 on AX1) applies only in the negative direction.
    assert!((p.total_compensation_mm("AX1", at, neg) - 0.0015).abs() < 1e-15);
    assert_eq!(p.total_compensation_mm("AX1", at, pos), 0.0);
    assert!((p.total_compensation_mm("AX2", at, pos) - 0.00105).abs() < 1e-15);
    // End values held beyond MAX.
    assert!((p.tables[0].compensation_mm(500.0, Direction::Positive) + 0.0013).abs() < 1e-15);
}

fn with_line(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "{from} not in the program");
    text.replacen(from, to, 1)
}

#[test]
fn a_missing_parameter_is_refused_since_the_controller_would_keep_an_old_value() {
    let text = write_cec_program(&program()).unwrap();
    let cut = with_line(&text, "$AN_CEC_DIRECTION[1]=-1\n", "");
    assert_eq!(
        parse_cec_program(&cut).unwrap_err(),
        CecError::MissingParameter {
            table: 1,
            parameter: "$AN_CEC_DIRECTION"
        }
    );
}

#[test]
fn a_gap_in_the_points_is_refused() {
    let text = write_cec_program(&program()).unwrap();
    let cut = with_line(&text, "$AN_CEC[0,1]=0.0021\n", "");
    assert_eq!(
        parse_cec_program(&cut).unwrap_err(),
        CecError::MissingValue { table: 0, point: 1 }
    );
}

#[test]
fn an_end_position_that_is_not_min_plus_step_times_points_is_refused() {
    let text = write_cec_program(&program()).unwrap();
    let wrong = with_line(&text, "$AN_CEC_MAX[0]=200.0", "$AN_CEC_MAX[0]=250.0");
    let err = parse_cec_program(&wrong).unwrap_err();
    assert!(
        matches!(
            err,
            CecError::EndPositionMismatch {
                table: 0,
                points: 3,
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn unknown_unsupported_and_duplicate_statements_are_refused_with_their_line() {
    let text = write_cec_program(&program()).unwrap();
    let ncu = with_line(&text, "M17", "$AN_CEC_INPUT_NCU[0]=1\nM17");
    assert!(matches!(
        parse_cec_program(&ncu).unwrap_err(),
        CecError::Unsupported { line: 26, .. }
    ));
    let mult = with_line(
        &text,
        "$AN_CEC_MULT_BY_TABLE[0]=0",
        "$AN_CEC_MULT_BY_TABLE[0]=2",
    );
    assert!(matches!(
        parse_cec_program(&mult).unwrap_err(),
        CecError::Unsupported { line: 13, .. }
    ));
    let modulo = with_line(&text, "$AN_CEC_IS_MODULO[1]=0", "$AN_CEC_IS_MODULO[1]=1");
    assert!(matches!(
        parse_cec_program(&modulo).unwrap_err(),
        CecError::Unsupported { line: 25, .. }
    ));
    let dup = with_line(&text, "M17", "$AN_CEC[0,2]=0\nM17");
    assert_eq!(
        parse_cec_program(&dup).unwrap_err(),
        CecError::Duplicate {
            line: 26,
            what: "$AN_CEC[0,2]".into(),
            first_line: 6
        }
    );
    let junk = with_line(&text, "M17", "G01 X10\nM17");
    assert!(matches!(
        parse_cec_program(&junk).unwrap_err(),
        CecError::UnknownStatement { line: 26, .. }
    ));
    let after = format!("{text}G0 X0\n");
    assert!(matches!(
        parse_cec_program(&after).unwrap_err(),
        CecError::AfterEnd { line: 27, .. }
    ));
}

#[test]
fn the_program_frame_is_required() {
    let text = write_cec_program(&program()).unwrap();
    assert!(matches!(
        parse_cec_program(&with_line(&text, "%_N_NC_CEC_INI", "%_N_OTHER_INI")).unwrap_err(),
        CecError::MissingProgramName { line: 1, .. }
    ));
    assert!(matches!(
        parse_cec_program(&with_line(&text, "CHANDATA(1)", "CHANDATA(0)")).unwrap_err(),
        CecError::BadValue { line: 2, .. }
    ));
    assert_eq!(
        parse_cec_program(&with_line(&text, "M17\n", "")).unwrap_err(),
        CecError::MissingEnd
    );
    assert!(matches!(
        parse_cec_program(&with_line(&text, "(AX2)", "(AX2")).unwrap_err(),
        CecError::BadValue { line: 8, .. }
    ));
    assert!(matches!(
        parse_cec_program(&with_line(&text, "=0.0021", "=NaN")).unwrap_err(),
        CecError::BadValue { line: 5, .. }
    ));
}

#[test]
fn spaces_around_the_equals_sign_and_trailing_comments_are_read() {
    let text = write_cec_program(&program())
        .unwrap()
        .replace("]=", "] = ")
        .replace(
            "$AN_CEC_MIN[0] = 0.0",
            "$AN_CEC_MIN[0] = 0.0 ; compensation starts at 0 mm",
        );
    assert_eq!(parse_cec_program(&text).unwrap(), program());
}

#[test]
fn invalid_tables_and_programs_are_not_written() {
    let t = |name: &str, step: f64, values: &[f64]| {
        CecTable::new(name, "AX1", 0.0, step, values, CecDirection::Both)
    };
    assert!(t("AX 1", 1.0, &[0.0, 0.0]).is_err());
    assert!(t("AX1", 0.0, &[0.0, 0.0]).is_err());
    assert!(t("AX1", 1.0, &[0.0]).is_err());
    assert!(t("AX1", 1.0, &[0.0, f64::NAN]).is_err());
    let mut p = program();
    p.channel = 0;
    assert!(write_cec_program(&p).is_err());
    let mut p = program();
    p.comment_lines = vec!["two\nlines".into()];
    assert!(write_cec_program(&p).is_err());
}
