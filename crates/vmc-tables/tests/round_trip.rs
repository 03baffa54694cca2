//! Round trips over random tables: write → check → read back gives the same values within the
//! printed precision, 1e-6 mm (1 nm): half of it from rounding to 6 decimals, plus float noise.
//! And the checker names the line of a comment or a disorder wherever it is put.

use proptest::prelude::*;
use vmc_tables::cec::{parse_cec_program, write_cec_program, CecDirection, CecProgram, CecTable};
use vmc_tables::linuxcnc::{
    check_comp_file, parse_comp_file, CompFileError, CompFileType, CompPoint, JointCompTable,
};

/// Half the 1 nm print resolution, plus what binary floating point adds to it.
const PRINT_TOL_MM: f64 = 0.5e-6 + 1e-9;

/// Random points: ascending nominal positions (gaps of at least 1 µm), trims within ±0.5 mm.
fn points() -> impl Strategy<Value = Vec<CompPoint>> {
    (
        -2000.0..2000.0f64,
        prop::collection::vec((0.001..50.0f64, -0.5..0.5f64, -0.5..0.5f64), 2..=256),
    )
        .prop_map(|(start, rows)| {
            let mut x = start;
            rows.into_iter()
                .map(|(gap, f, r)| {
                    x += gap;
                    CompPoint {
                        nominal_mm: x,
                        forward_trim_mm: f,
                        reverse_trim_mm: r,
                    }
                })
                .collect()
        })
}

fn file_type() -> impl Strategy<Value = CompFileType> {
    prop_oneof![
        Just(CompFileType::MeasuredPositions),
        Just(CompFileType::Trims)
    ]
}

proptest! {
    #[test]
    fn a_written_joint_table_checks_and_reads_back_within_a_nanometre(
        pts in points(),
        ty in file_type(),
    ) {
        let table = JointCompTable::new(pts.clone()).unwrap();
        let text = table.to_comp_file(ty);
        let summary = check_comp_file(&text).unwrap();
        prop_assert_eq!(summary.points, pts.len());
        let back = parse_comp_file(&text, ty).unwrap();
        for (b, p) in back.points().iter().zip(&pts) {
            prop_assert!((b.nominal_mm - p.nominal_mm).abs() <= PRINT_TOL_MM);
            prop_assert!((b.forward_trim_mm - p.forward_trim_mm).abs() <= PRINT_TOL_MM);
            prop_assert!((b.reverse_trim_mm - p.reverse_trim_mm).abs() <= PRINT_TOL_MM);
        }
        // What is read back is what was held in memory (already on the 1 nm grid).
        for (b, t) in back.points().iter().zip(table.points()) {
            prop_assert!((b.forward_trim_mm - t.forward_trim_mm).abs() <= 1e-9);
            prop_assert!((b.reverse_trim_mm - t.reverse_trim_mm).abs() <= 1e-9);
        }
    }

    #[test]
    fn a_comment_anywhere_is_refused_at_its_line(
        pts in points(),
        at in any::<prop::sample::Index>(),
        comment in prop_oneof![Just("# header"), Just("; note"), Just("nominal forward reverse")],
    ) {
        let text = JointCompTable::new(pts).unwrap().to_comp_file(CompFileType::Trims);
        let mut lines: Vec<&str> = text.lines().collect();
        let i = at.index(lines.len() + 1);
        lines.insert(i, comment);
        let err = check_comp_file(&lines.join("\n")).unwrap_err();
        prop_assert!(
            matches!(err, CompFileError::CommentLine { line, .. } if line == i + 1),
            "{:?}", err
        );
    }

    #[test]
    fn swapping_two_neighbouring_lines_is_refused_as_not_ascending(
        pts in points(),
        at in any::<prop::sample::Index>(),
    ) {
        let text = JointCompTable::new(pts).unwrap().to_comp_file(CompFileType::Trims);
        let mut lines: Vec<&str> = text.lines().collect();
        let i = at.index(lines.len() - 1);
        lines.swap(i, i + 1);
        let err = check_comp_file(&lines.join("\n")).unwrap_err();
        prop_assert!(
            matches!(err, CompFileError::NotAscending { line, .. } if line == i + 2),
            "{:?}", err
        );
    }
}

/// A random CEC table: 2 to 60 points, 1 µm to 50 mm apart, values within ±0.5 mm.
fn cec_table() -> impl Strategy<Value = (String, String, f64, f64, Vec<f64>, CecDirection)> {
    let axis = prop_oneof![Just("AX1"), Just("AX2"), Just("AX3"), Just("Z1")];
    let dir = prop_oneof![
        Just(CecDirection::Both),
        Just(CecDirection::Positive),
        Just(CecDirection::Negative)
    ];
    (
        axis.clone(),
        axis,
        -2000.0..2000.0f64,
        0.001..50.0f64,
        prop::collection::vec(-0.5..0.5f64, 2..60),
        dir,
    )
        .prop_map(|(i, o, min, step, v, d)| (i.to_string(), o.to_string(), min, step, v, d))
}

proptest! {
    #[test]
    fn a_written_cec_program_reads_back_within_a_nanometre(
        specs in prop::collection::vec(cec_table(), 1..5),
        channel in 1u32..10,
    ) {
        let tables: Vec<CecTable> = specs
            .iter()
            .map(|(i, o, min, step, v, d)| CecTable::new(i, o, *min, *step, v, *d).unwrap())
            .collect();
        let program = CecProgram { channel, comment_lines: vec!["round trip".into()], tables };
        let back = parse_cec_program(&write_cec_program(&program).unwrap()).unwrap();
        prop_assert_eq!(&back, &program);
        for (t, (_, _, min, step, v, _)) in back.tables.iter().zip(&specs) {
            prop_assert!((t.min_mm() - min).abs() <= PRINT_TOL_MM);
            prop_assert!((t.step_mm() - step).abs() <= PRINT_TOL_MM);
            for (a, b) in t.values_mm().iter().zip(v) {
                prop_assert!((a - b).abs() <= PRINT_TOL_MM);
            }
        }
    }
}
