//! Interpreter tests: modal state, unit and offset arithmetic, arcs in all planes, errors.

use super::*;
use proptest::prelude::*;

/// 1e-9 mm = 1 pm: floating-point noise only; every expected value here is exact arithmetic.
const TOL_MM: f64 = 1e-9;

fn run(src: &str) -> Vec<CanonKind> {
    run_cfg(src, &InterpConfig::default())
}

fn run_cfg(src: &str, cfg: &InterpConfig) -> Vec<CanonKind> {
    run_program(src, cfg)
        .unwrap_or_else(|e| panic!("program rejected: {e}"))
        .into_iter()
        .map(|m| m.kind)
        .collect()
}

fn err(src: &str) -> GcodeError {
    run_program(src, &InterpConfig::default()).expect_err("program must be rejected")
}

fn ends(kinds: &[CanonKind]) -> Vec<[f64; 3]> {
    kinds
        .iter()
        .filter_map(|k| match k {
            CanonKind::Traverse { end_mm, .. }
            | CanonKind::Feed { end_mm, .. }
            | CanonKind::Arc { end_mm, .. } => Some(*end_mm),
            _ => None,
        })
        .collect()
}

fn assert_close(a: [f64; 3], b: [f64; 3]) {
    assert!(
        (0..3).all(|i| (a[i] - b[i]).abs() < TOL_MM),
        "{a:?} != {b:?}"
    );
}

/// The single arc of a program: (end, centre, plane, clockwise, extra turns).
fn the_arc(src: &str) -> ([f64; 3], [f64; 3], Plane, bool, u32) {
    let arcs: Vec<_> = run(src)
        .into_iter()
        .filter_map(|k| match k {
            CanonKind::Arc {
                end_mm,
                center_mm,
                plane,
                clockwise,
                extra_turns,
                ..
            } => Some((end_mm, center_mm, plane, clockwise, extra_turns)),
            _ => None,
        })
        .collect();
    assert_eq!(arcs.len(), 1, "{src}");
    arcs[0]
}

#[test]
fn rapid_and_feed_moves_land_where_programmed_with_their_line_numbers() {
    let moves = run_program("G0 X10 Y20\n\nG1 Z-5 F300\n", &InterpConfig::default()).unwrap();
    assert_eq!(
        moves[0],
        CanonMove {
            line: 1,
            kind: CanonKind::Traverse {
                end_mm: [10.0, 20.0, 0.0],
                end_abc_deg: [0.0; 3]
            }
        }
    );
    assert_eq!(
        moves[1],
        CanonMove {
            line: 3,
            kind: CanonKind::Feed {
                end_mm: [10.0, 20.0, -5.0],
                feed_mm_per_min: 300.0,
                end_abc_deg: [0.0; 3]
            }
        }
    );
}

#[test]
fn motion_mode_and_feed_are_modal() {
    let k = run("G1 X1 F100\nY2\nG0 Z3\nX4");
    assert!(
        matches!(k[1], CanonKind::Feed { end_mm: [1.0, 2.0, 0.0], feed_mm_per_min: f, .. } if f == 100.0)
    );
    assert!(matches!(
        k[3],
        CanonKind::Traverse {
            end_mm: [4.0, 2.0, 3.0],
            ..
        }
    ));
}

#[test]
fn g91_moves_are_relative_to_the_current_point() {
    let k = run("G0 X10 Y10\nG91 G1 X5 Y-2 F100\nX5\nG90 X0");
    assert_eq!(
        ends(&k),
        vec![
            [10.0, 10.0, 0.0],
            [15.0, 8.0, 0.0],
            [20.0, 8.0, 0.0],
            [0.0, 8.0, 0.0]
        ]
    );
}

#[test]
fn g20_coordinates_and_feeds_are_converted_to_mm() {
    let k = run("G20\nG1 X1 Y-0.5 F10\nG21 X1");
    assert!(
        matches!(k[0], CanonKind::Feed { end_mm: [25.4, -12.7, 0.0], feed_mm_per_min: f, .. } if (f - 254.0).abs() < TOL_MM)
    );
    assert!(matches!(
        k[1],
        CanonKind::Feed {
            end_mm: [1.0, -12.7, 0.0],
            ..
        }
    ));
}

#[test]
fn f_word_is_read_in_the_units_active_before_the_blocks_g20() {
    // RS274/NGC order: feed (step 3) before units (step 12).
    let k = run("G20 G1 X1 F10");
    assert!(
        matches!(k[0], CanonKind::Feed { end_mm: [25.4, 0.0, 0.0], feed_mm_per_min: f, .. } if f == 10.0)
    );
}

#[test]
fn work_offsets_shift_program_coordinates_and_g92_adds_on_top() {
    let mut cfg = InterpConfig::default();
    cfg.work_offsets_mm[0] = [100.0, 0.0, -50.0];
    cfg.work_offsets_mm[1] = [200.0, 10.0, 0.0];
    let k = run_cfg("G0 X1 Z1\nG55 X1\nG92 X0\nX5\nG92.1\nX5\nG54 X0", &cfg);
    // G92 X0 at machine X201 under G55: offset = 201 − 200 − 0 = 1 mm.
    assert_eq!(
        ends(&k),
        vec![
            [101.0, 0.0, -49.0],
            [201.0, 0.0, -49.0],
            [206.0, 0.0, -49.0],
            [205.0, 0.0, -49.0],
            [100.0, 0.0, -49.0]
        ]
    );
}

#[test]
fn g92_values_are_absolute_even_in_g91_and_scaled_in_g20() {
    let k = run("G0 X10\nG20 G91 G92 X1\nG90 X0");
    // Program X1 in = 25.4 mm at machine 10 → offset −15.4 mm; X0 → machine −15.4.
    assert_close(ends(&k)[1], [-15.4, 0.0, 0.0]);
}

#[test]
fn g53_moves_in_machine_coordinates_for_one_block_only() {
    let mut cfg = InterpConfig::default();
    cfg.work_offsets_mm[0] = [100.0, 100.0, 0.0];
    let k = run_cfg("G53 G0 X1 Y2\nG1 X1 F10\nG20 G53 X1", &cfg);
    assert_eq!(
        ends(&k),
        vec![[1.0, 2.0, 0.0], [101.0, 2.0, 0.0], [25.4, 2.0, 0.0]]
    );
}

#[test]
fn start_position_comes_from_the_config() {
    let cfg = InterpConfig {
        start_mm: [1.0, 2.0, 3.0],
        ..InterpConfig::default()
    };
    assert_eq!(ends(&run_cfg("G91 G0 X1", &cfg)), vec![[2.0, 2.0, 3.0]]);
}

#[test]
fn g17_g2_centre_form_gives_an_xy_arc_with_the_incremental_centre() {
    let (end, c, plane, cw, turns) = the_arc("G0 X10 Y0 Z-1\nG2 X0 Y10 I-10 J0 F100");
    assert_eq!(
        (end, plane, cw, turns),
        ([0.0, 10.0, -1.0], Plane::Xy, true, 0)
    );
    assert_close(c, [0.0, 0.0, -1.0]);
}

#[test]
fn g18_arc_uses_i_and_k_and_keeps_y_as_the_axis() {
    let (end, c, plane, cw, _) = the_arc("G0 X0 Y7 Z10\nG18 G3 X10 Z0 I0 K-10 F50");
    assert_eq!((end, plane, cw), ([10.0, 7.0, 0.0], Plane::Zx, false));
    assert_close(c, [0.0, 7.0, 0.0]);
}

#[test]
fn g19_arc_uses_j_and_k_and_keeps_x_as_the_axis() {
    let (end, c, plane, cw, _) = the_arc("G0 X3 Y0 Z5\nG19 G2 Y5 Z0 J0 K-5 F50");
    assert_eq!((end, plane, cw), ([3.0, 5.0, 0.0], Plane::Yz, true));
    assert_close(c, [3.0, 0.0, 0.0]);
}

#[test]
fn r_form_positive_gives_the_short_arc_and_negative_the_long_one() {
    let (_, c, ..) = the_arc("G2 X10 Y10 R10 F100");
    assert_close(c, [10.0, 0.0, 0.0]);
    let (_, c, ..) = the_arc("G2 X10 Y10 R-10 F100");
    assert_close(c, [0.0, 10.0, 0.0]);
    let (_, c, ..) = the_arc("G3 X10 Y10 R10 F100");
    assert_close(c, [0.0, 10.0, 0.0]);
}

#[test]
fn r_form_in_g18_places_the_centre_in_the_zx_plane() {
    // ZX plane: first axis Z, second X. G2 from (Z0,X0) to (Z10,X10), R10: centre (Z10, X0).
    let (_, c, plane, ..) = the_arc("G18 G2 X10 Z10 R10 F100");
    assert_eq!(plane, Plane::Zx);
    assert_close(c, [0.0, 0.0, 10.0]);
}

#[test]
fn full_circle_with_p_turns_and_helix_keeps_the_centre_at_the_start_height() {
    let (end, c, _, cw, turns) = the_arc("G0 X5\nG3 Z-3 I-5 P3 F100");
    assert_eq!((end, cw, turns), ([5.0, 0.0, -3.0], false, 2));
    assert_close(c, [0.0, 0.0, 0.0]);
}

#[test]
fn g90_1_takes_absolute_centres_through_the_work_offset() {
    let mut cfg = InterpConfig::default();
    cfg.work_offsets_mm[0] = [100.0, 0.0, 0.0];
    let k = run_cfg("G0 X10\nG90.1 G2 X-10 I0 J0 F100", &cfg);
    let CanonKind::Arc {
        center_mm, end_mm, ..
    } = k[1]
    else {
        panic!("{k:?}")
    };
    assert_close(center_mm, [100.0, 0.0, 0.0]);
    assert_close(end_mm, [90.0, 0.0, 0.0]);
}

#[test]
fn inch_arc_centres_are_scaled_too() {
    let (end, c, ..) = the_arc("G20 G2 X2 I1 F10");
    assert_close(end, [50.8, 0.0, 0.0]);
    assert_close(c, [25.4, 0.0, 0.0]);
}

#[test]
fn spindle_is_reported_once_per_change_and_m6_stops_it_first() {
    let k = run("S1000 M3\nM3\nS2000\nT5 M6\nM4\nM5\nS0");
    assert_eq!(
        k,
        vec![
            CanonKind::Spindle {
                dir: SpindleDir::Cw,
                rpm: 1000.0
            },
            CanonKind::Spindle {
                dir: SpindleDir::Cw,
                rpm: 2000.0
            },
            CanonKind::Spindle {
                dir: SpindleDir::Off,
                rpm: 2000.0
            },
            CanonKind::ToolChange { tool: 5 },
            CanonKind::Spindle {
                dir: SpindleDir::Ccw,
                rpm: 2000.0
            },
            CanonKind::Spindle {
                dir: SpindleDir::Off,
                rpm: 2000.0
            },
            CanonKind::Spindle {
                dir: SpindleDir::Off,
                rpm: 0.0
            },
        ]
    );
}

#[test]
fn a_block_executes_in_rs274_order_and_m2_ends_the_program() {
    let k = run("G1 X1 M2 G4 P2 F100 S500 M3\nthis line is never read ###");
    assert_eq!(
        k,
        vec![
            CanonKind::Spindle {
                dir: SpindleDir::Cw,
                rpm: 500.0
            },
            CanonKind::Dwell { duration_s: 2.0 },
            CanonKind::Feed {
                end_mm: [1.0, 0.0, 0.0],
                feed_mm_per_min: 100.0,
                end_abc_deg: [0.0; 3]
            },
            CanonKind::ProgramEnd,
        ]
    );
}

#[test]
fn preamble_codes_that_confirm_our_state_are_accepted() {
    assert!(run("%\nG17 G21 G40 G49 G54 G80 G90 G94\nM30\n%").ends_with(&[CanonKind::ProgramEnd]));
}

#[test]
fn g80_beside_a_motion_code_leaves_that_motion_mode_in_effect() {
    // Outputs of rs274 on the same programs: the safe-start line traverses to where the tool
    // is (G0 without axis words); the motion code, not G80, stays modal for the next block.
    let kinds = run("N1 G00 G17 G21 G40 G49 G80 G90\nX1\nM2");
    assert_eq!(ends(&kinds), vec![[0.0; 3], [1.0, 0.0, 0.0]]);
    assert!(matches!(kinds[0], CanonKind::Traverse { .. }));
    assert!(matches!(kinds[1], CanonKind::Traverse { .. }));
    let kinds = run("G1 G80 X1 F100\nX3\nM2");
    assert_eq!(ends(&kinds), vec![[1.0, 0.0, 0.0], [3.0, 0.0, 0.0]]);
    assert!(kinds[..2]
        .iter()
        .all(|k| matches!(k, CanonKind::Feed { .. })));
    let (end, centre, ..) = the_arc("G80 G2 X2 I1 F100\nM2");
    assert_close(end, [2.0, 0.0, 0.0]);
    assert_close(centre, [1.0, 0.0, 0.0]);
    // A cycle beside G80 drills: R plane, hole, retract (G99 to R).
    let kinds = run("G80 G81 G80 X1 Z-1 R1 F10\nM2");
    assert_eq!(
        ends(&kinds),
        vec![
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 0.0, -1.0],
            [1.0, 0.0, 1.0]
        ]
    );
    // G80 alone still cancels: axis words then have no motion to use them.
    assert!(err("G0 X1\nG80 X2")
        .msg
        .contains("G80 cancels the motion mode"));
}

#[test]
fn a_failed_block_leaves_the_interpreter_unchanged() {
    let mut it = Interpreter::new(InterpConfig::default());
    let mut out = Vec::new();
    let block = |s: &str| {
        crate::syntax::Block::from_literal_line(&crate::syntax::parse_line(1, s).unwrap().unwrap())
            .unwrap()
    };
    it.execute_block(&block("G0 X1"), &mut out).unwrap();
    // S and G20 would execute before the arc geometry fails.
    assert!(it
        .execute_block(&block("S100 M3 G20 G2 X3 I5 F1"), &mut out)
        .is_err());
    assert_eq!(out.len(), 1);
    it.execute_block(&block("G1 X2 F1"), &mut out).unwrap();
    assert_eq!(
        out[1].kind,
        CanonKind::Feed {
            end_mm: [2.0, 0.0, 0.0],
            feed_mm_per_min: 1.0,
            end_abc_deg: [0.0; 3]
        }
    );
    assert_eq!(it.position_mm(), [2.0, 0.0, 0.0]);
}

/// (program, line, column, kind, text the message must contain).
const ERROR_CASES: &[(&str, usize, usize, GcodeErrorKind, &str)] = &[
    (
        "G0 X1\nG1 X2",
        2,
        1,
        GcodeErrorKind::Invalid,
        "zero feed rate",
    ),
    ("F0 G1 X2", 1, 4, GcodeErrorKind::Invalid, "zero feed rate"),
    (
        "G0 X1\n  X2 G2 F100",
        2,
        6,
        GcodeErrorKind::Invalid,
        "G2 needs I/J/K or R",
    ),
    ("G2 X1 I1 R2 F1", 1, 10, GcodeErrorKind::Invalid, "mix R"),
    (
        "G2 X1 K1 F1",
        1,
        7,
        GcodeErrorKind::Invalid,
        "K word given for an arc in the XY plane",
    ),
    ("G18 G2 X1 J1 F1", 1, 11, GcodeErrorKind::Invalid, "J word"),
    ("G19 G3 Y1 I1 F1", 1, 11, GcodeErrorKind::Invalid, "I word"),
    (
        "G2 X10 I4 F1",
        1,
        1,
        GcodeErrorKind::Invalid,
        "radius to end of arc differs",
    ),
    ("G2 I0 J0 F1", 1, 1, GcodeErrorKind::Invalid, "zero-radius"),
    (
        "G2 Z1 R5 F1",
        1,
        1,
        GcodeErrorKind::Invalid,
        "with R needs X or Y",
    ),
    (
        "G0 X1\nG2 X1 Y0 R5 F1",
        2,
        1,
        GcodeErrorKind::Invalid,
        "ends where it starts",
    ),
    ("G2 X30 R10 F1", 1, 1, GcodeErrorKind::Invalid, "too small"),
    (
        "G90.1 G2 X2 I1 F1",
        1,
        7,
        GcodeErrorKind::Invalid,
        "J word missing",
    ),
    (
        "G2 X0 I1 P2.5 F1",
        1,
        10,
        GcodeErrorKind::Invalid,
        "whole number",
    ),
    (
        "G2 X0 I1 P0 F1",
        1,
        10,
        GcodeErrorKind::Invalid,
        "whole number",
    ),
    (
        "G2 X0 I1 P1000000 F1",
        1,
        10,
        GcodeErrorKind::Unsupported,
        "maximum",
    ),
    ("X1", 1, 1, GcodeErrorKind::Invalid, "no motion mode"),
    ("G0 X1\nG80 Y1", 2, 5, GcodeErrorKind::Invalid, "G80"),
    (
        "G1 X1 I1 F1",
        1,
        7,
        GcodeErrorKind::Invalid,
        "I word without G2/G3",
    ),
    ("G0 X1 P2", 1, 7, GcodeErrorKind::Invalid, "P word without"),
    ("G4", 1, 1, GcodeErrorKind::Invalid, "G4 needs a P word"),
    ("G4 P-1", 1, 4, GcodeErrorKind::Invalid, "negative"),
    (
        "G2 X0 I1 G4 P1 F1",
        1,
        13,
        GcodeErrorKind::Invalid,
        "claimed by both G4",
    ),
    (
        "G4 G53 P1",
        1,
        4,
        GcodeErrorKind::Invalid,
        "same modal group",
    ),
    ("G92", 1, 1, GcodeErrorKind::Invalid, "G92 needs"),
    (
        "G92 G1 X1",
        1,
        5,
        GcodeErrorKind::Invalid,
        "both use the axis words",
    ),
    (
        "G53 G2 X1 I1 F1",
        1,
        1,
        GcodeErrorKind::Invalid,
        "G53 needs G0 or G1",
    ),
    ("G91 G53 G0 X1", 1, 5, GcodeErrorKind::Invalid, "G91"),
    ("G1 X1 F-5", 1, 7, GcodeErrorKind::Invalid, "negative"),
    ("T1.5 M6", 1, 1, GcodeErrorKind::Invalid, "T word"),
    (
        "G0 X1\n(ok)\nG1 D1 X5 F9",
        3,
        4,
        GcodeErrorKind::Invalid,
        "D word without G41",
    ),
    (
        "G0 X1\nG41 D1\nG40 G2 X5 R3 F1",
        3,
        5,
        GcodeErrorKind::Invalid,
        "must be straight",
    ),
    (
        "G0 X1 H1",
        1,
        7,
        GcodeErrorKind::Invalid,
        "H word without G43",
    ),
    ("G1 G0 X1", 1, 4, GcodeErrorKind::Invalid, "G1 and G0"),
    (
        "M19 R400",
        1,
        5,
        GcodeErrorKind::Invalid,
        "R value must be within 0..360 with M19",
    ),
    (
        "G64 M19 R90",
        1,
        9,
        GcodeErrorKind::Invalid,
        "R word is ambiguous",
    ),
    (
        "G76 X1 Z-1",
        1,
        1,
        GcodeErrorKind::Unsupported,
        "G76 (lathe cycle)",
    ),
    (
        "G81 X1 Z-1 R1",
        1,
        1,
        GcodeErrorKind::Invalid,
        "G81 with zero feed rate",
    ),
    ("G0 X1e3", 1, 6, GcodeErrorKind::Invalid, "E word"),
    (
        "G0 Y12345678901",
        1,
        4,
        GcodeErrorKind::Invalid,
        "out of range",
    ),
];

#[test]
fn errors_name_the_word_line_column_and_kind() {
    for &(src, line, col, kind, text) in ERROR_CASES {
        let e = err(src);
        assert_eq!((e.line, e.col, e.kind), (line, col, kind), "{src:?}: {e}");
        assert!(
            e.msg.contains(text),
            "{src:?}: message {:?} lacks {text:?}",
            e.msg
        );
        assert!(e
            .to_string()
            .starts_with(&format!("line {line}, column {col}: ")));
    }
}

proptest! {
    // Fixed seed: the same cases on every run (determinism rule), no regression files.
    #![proptest_config(ProptestConfig {
        cases: 2000,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x696e_7470),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn arbitrary_bytes_never_panic_and_errors_have_a_position(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
        let src = String::from_utf8_lossy(&bytes);
        if let Err(e) = run_program(&src, &InterpConfig::default()) {
            prop_assert!(e.line >= 1 && e.col >= 1, "{e:?}");
        }
    }

    #[test]
    fn gcode_like_text_never_panics_and_errors_have_a_position(src in "([GMXYZIJKRPFSTN%();# .\n+-]|[0-9]){0,120}") {
        match run_program(&src, &InterpConfig::default()) {
            Err(e) => prop_assert!(e.line >= 1 && e.col >= 1 && !e.msg.is_empty(), "{e:?}"),
            Ok(moves) => prop_assert!(moves.iter().all(|m| m.line >= 1)),
        }
    }

    #[test]
    fn accepted_arcs_end_on_their_circle(
        x in -100.0f64..100.0, y in -100.0f64..100.0, r in -80.0f64..80.0, cw in any::<bool>(),
    ) {
        let g = if cw { "G2" } else { "G3" };
        let src = format!("G1 X1 Y2 F100\n{g} X{x:.4} Y{y:.4} R{r:.4}");
        if let Ok(moves) = run_program(&src, &InterpConfig::default()) {
            let CanonKind::Arc { end_mm, center_mm, .. } = moves[1].kind else { panic!("no arc") };
            let r1 = (1.0 - center_mm[0]).hypot(2.0 - center_mm[1]);
            let r2 = (end_mm[0] - center_mm[0]).hypot(end_mm[1] - center_mm[1]);
            // Both radii equal |R| up to LinuxCNC's 0.00127 mm snap tolerance.
            prop_assert!((r1 - r2).abs() < 2e-3 && (r1 - r.abs()).abs() < 2e-3, "r1 {r1} r2 {r2} R {r}");
        }
    }
}
