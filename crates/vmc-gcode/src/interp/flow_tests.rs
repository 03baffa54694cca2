//! Tests of parameters, expressions and O-word control flow (values checked against
//! LinuxCNC's `rs274`).

use super::*;

fn xs(src: &str) -> Vec<f64> {
    run_program(src, &InterpConfig::default())
        .unwrap_or_else(|e| panic!("program rejected: {e}"))
        .into_iter()
        .filter_map(|m| match m.kind {
            CanonKind::Traverse { end_mm, .. } | CanonKind::Feed { end_mm, .. } => Some(end_mm[0]),
            _ => None,
        })
        .collect()
}

fn err(src: &str) -> GcodeError {
    run_program(src, &InterpConfig::default()).expect_err("program must be rejected")
}

#[test]
fn settings_take_effect_after_the_line_is_read() {
    assert_eq!(
        xs("#1=2\n#1=1 G0 X#1\nG0 X#1\n#1=5 #2=#1\nG0 X#2"),
        vec![2.0, 1.0, 1.0]
    );
}

#[test]
fn named_parameters_are_local_to_a_call_and_globals_are_shared() {
    let src = "#<a>=1 #<_g>=2\no10 sub\n#<a>=7\n#<_g>=[#1+#2+#3]\no10 endsub\n\
               o10 call [3] [4]\nG0 X#<a> Y#<_g>\nM2";
    let moves = run_program(src, &InterpConfig::default()).unwrap();
    assert_eq!(
        moves[0].kind,
        CanonKind::Traverse {
            end_mm: [1.0, 7.0, 0.0],
            end_abc_deg: [0.0; 3]
        }
    );
}

#[test]
fn call_arguments_are_restored_and_return_sets_value() {
    let src = "#1=2 #3=1\no1 sub\n#3=77\no1 return [#1*10]\no1 endsub\n\
               o1 call [11]\nG0 X#1 Y#3 Z#<_value>\nM2";
    let moves = run_program(src, &InterpConfig::default()).unwrap();
    assert_eq!(
        moves[0].kind,
        CanonKind::Traverse {
            end_mm: [2.0, 1.0, 110.0],
            end_abc_deg: [0.0; 3]
        }
    );
}

#[test]
fn if_elseif_else_take_one_branch() {
    let prog = |v: i32| {
        format!(
            "#1={v}\no1 if [#1 EQ 1]\nG0 X1\no1 elseif [#1 EQ 2]\nG0 X2\no1 else\nG0 X3\n\
             o1 endif\nG0 X9"
        )
    };
    assert_eq!(xs(&prog(1)), vec![1.0, 9.0]);
    assert_eq!(xs(&prog(2)), vec![2.0, 9.0]);
    assert_eq!(xs(&prog(5)), vec![3.0, 9.0]);
}

#[test]
fn loops_while_do_repeat_break_and_continue() {
    let w = "#1=0\no1 while [#1 LT 3]\n#1=[#1+1]\no2 if [#1 EQ 2]\no1 continue\no2 endif\n\
             G0 X#1\no1 endwhile";
    assert_eq!(xs(w), vec![1.0, 3.0]);
    let d = "#1=0\no1 do\n#1=[#1+1]\nG0 X#1\no2 if [#1 GE 2]\no1 break\no2 endif\no1 while [1]";
    assert_eq!(xs(d), vec![1.0, 2.0]);
    let r = "#1=0\no1 repeat [3]\n#1=[#1+1]\nG0 X#1\no1 endrepeat\nG0 X9";
    assert_eq!(xs(r), vec![1.0, 2.0, 3.0, 9.0]);
}

#[test]
fn endless_loops_and_recursion_are_refused_not_hung() {
    let e = err("o1 while [1]\no1 endwhile");
    assert!(e.is_unsupported() && e.line == 2, "{e}");
    let e = err("o1 sub\no1 call\no1 endsub\no1 call");
    assert!(e.is_unsupported(), "{e}");
}

#[test]
fn structure_errors_are_invalid_with_their_line() {
    for (src, line) in [
        ("G0 X1\no1 endif", 2),
        ("o1 if [1]\nG0 X1", 1),
        ("o1 if [1]\no2 endif", 2),
        ("o1 break", 1),
        ("o5 call", 1),
        ("G0 X#<nope>", 1),
        ("o1 sub\no2 sub\no2 endsub\no1 endsub", 2),
    ] {
        let e = err(src);
        assert_eq!(
            (e.line, e.kind),
            (line, GcodeErrorKind::Invalid),
            "{src}: {e}"
        );
    }
}

#[test]
fn block_delete_skips_only_when_switched_on() {
    assert_eq!(xs("/G0 X5\nG0 X1"), vec![5.0, 1.0]);
    let cfg = InterpConfig {
        block_delete: true,
        ..InterpConfig::default()
    };
    let moves = run_program("/G0 X5\nG0 X1", &cfg).unwrap();
    assert_eq!(moves.len(), 1);
}

fn kinds(src: &str) -> Vec<CanonKind> {
    run_program(src, &InterpConfig::default())
        .unwrap_or_else(|e| panic!("program rejected: {e}"))
        .into_iter()
        .map(|m| m.kind)
        .collect()
}

#[test]
fn g28_goes_through_the_intermediate_point_to_the_stored_position() {
    let k = kinds("G0 X5 Y5 Z5\n#5161=1 #5162=2 #5163=3\nG28 Z7\nG28\nG0 X4\nG30.1\nG0 X9\nG30");
    let t = |x, y, z| CanonKind::Traverse {
        end_mm: [x, y, z],
        end_abc_deg: [0.0; 3],
    };
    assert_eq!(
        k,
        vec![
            t(5.0, 5.0, 5.0),
            t(5.0, 5.0, 7.0),
            t(5.0, 5.0, 3.0),
            t(5.0, 5.0, 3.0),
            t(1.0, 2.0, 3.0),
            t(4.0, 2.0, 3.0),
            t(9.0, 2.0, 3.0),
            t(9.0, 2.0, 3.0),
            t(4.0, 2.0, 3.0),
        ]
    );
}

#[test]
fn g92_2_suspends_and_g92_3_restores_the_offset() {
    assert_eq!(
        xs("G0 X4\nG92 X1\nG0 X0\nG92.2\nG0 X0\nG92.3\nG0 X0\nG92.1\nG0 X0"),
        vec![4.0, 3.0, 0.0, 3.0, 0.0]
    );
}

#[test]
fn g10_l2_and_l20_set_work_offsets() {
    assert_eq!(
        xs("G10 L2 P1 X10\nG0 X0\nG10 L2 P2 X20\nG55 G0 X1"),
        vec![10.0, 21.0]
    );
    assert_eq!(
        xs("G0 X7\nG10 L20 P0 X2\nG0 X0\nG0 X2 (reads #5221)\nG0 X#5221"),
        vec![7.0, 5.0, 7.0, 10.0]
    );
    for src in [
        "G10 P1 X1",
        "G10 L2 X1",
        "G10 L3 P1 X1",
        "G10 L2 P1.5 X1",
        "G1 L2 X1 F1",
        "G0 Q1 X1",
    ] {
        assert_eq!(err(src).kind, GcodeErrorKind::Invalid, "{src}");
    }
    // G59.1…G59.3 are P7…P9.
    assert_eq!(xs("G10 L2 P7 X3\nG59.1 G0 X1"), vec![4.0]);
}

/// Machine end points (mm) of the straight moves of a program.
fn ends(src: &str) -> Vec<[f64; 3]> {
    run_program(src, &InterpConfig::default())
        .unwrap_or_else(|e| panic!("program rejected: {e}"))
        .into_iter()
        .filter_map(|m| match m.kind {
            CanonKind::Traverse { end_mm, .. } | CanonKind::Feed { end_mm, .. } => Some(end_mm),
            _ => None,
        })
        .collect()
}

fn assert_close(got: &[[f64; 3]], want: &[[f64; 3]]) {
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(want) {
        // 1e-9 mm: rounding of the rotation only.
        assert!(
            g.iter().zip(w).all(|(a, b)| (a - b).abs() < 1e-9),
            "{got:?} vs {want:?}"
        );
    }
}

#[test]
fn a_rotated_work_offset_turns_program_points_about_its_origin() {
    // X1 in a system at X10 turned 90°: machine (10, 1); G91 Y1 moves along program Y (-X).
    assert_close(
        &ends("G10 L2 P1 X10 R90\nG0 X1 Y0\nG91 G0 Y1"),
        &[[10.0, 1.0, 0.0], [9.0, 1.0, 0.0]],
    );
    // G92 shifts before the turn; L20 with a rotation sets X and Y of the offset.
    assert_close(
        &ends("G10 L2 P1 R90\nG92 X1\nG0 X2\nG10 L20 P1 X0\nG0 X1 Y0"),
        &[[0.0, 1.0, 0.0], [0.0, 2.0, 0.0]],
    );
    // A drilling cycle runs in the turned frame: hole at program (1, 0) = machine (0, 1).
    assert_close(
        &ends("G10 L2 P1 R90\nG0 Z5\nG81 X1 Y0 Z-1 R1 F100\nM2"),
        &[
            [0.0, 0.0, 5.0],
            [0.0, 1.0, 5.0],
            [0.0, 1.0, 1.0],
            [0.0, 1.0, -1.0],
            [0.0, 1.0, 1.0],
        ],
    );
    // An arc outside XY in a turned system has no canonical plane: refused, located.
    let e = err("G10 L2 P1 R30\nG18 G2 X2 Z0 R1 F100");
    assert!(e.is_unsupported() && e.line == 2, "{e}");
}

#[test]
fn coolant_pauses_and_path_control_make_no_motion() {
    assert_eq!(
        kinds("M8\nM7\nM9\nM0\nM1\nM60\nG64 P0.1 Q0.1\nG61\nG61.1"),
        vec![
            CanonKind::Coolant {
                mist: false,
                flood: true
            },
            CanonKind::Coolant {
                mist: true,
                flood: true
            },
            CanonKind::Coolant {
                mist: false,
                flood: false
            },
            CanonKind::Pause(PauseKind::Program),
            CanonKind::Pause(PauseKind::Optional),
            CanonKind::Pause(PauseKind::PalletShuttle),
        ]
    );
    assert_eq!(err("M8 M7").kind, GcodeErrorKind::Invalid);
}

#[test]
fn g43_shifts_absolute_z_by_the_tool_length_until_g49() {
    let cfg = InterpConfig {
        tool_lengths_mm: vec![(1, 100.0), (2, 50.0)],
        ..InterpConfig::default()
    };
    let zs = |src: &str| -> Vec<f64> {
        run_program(src, &cfg)
            .unwrap()
            .into_iter()
            .filter_map(|m| match m.kind {
                CanonKind::Traverse { end_mm, .. } => Some(end_mm[2]),
                _ => None,
            })
            .collect()
    };
    assert_eq!(
        zs("G43 H1 G0 Z5\nG91 G0 Z1\nG90 T2 M6\nG43\nG0 Z0\nG49 G0 Z0\nG43.1 Z2\nG0 Z0"),
        vec![105.0, 106.0, 50.0, 0.0, 2.0]
    );
    assert_eq!(
        run_program("G43 H3", &cfg).unwrap_err().kind,
        GcodeErrorKind::Invalid
    );
    assert_eq!(err("G0 X1 H1").kind, GcodeErrorKind::Invalid);
    // Without a table every tool has length 0.
    assert_eq!(xs("G43 H7 G0 X1 Z3"), vec![1.0]);
}

#[test]
fn fanuc_subroutines_repeat_share_parameters_and_nest() {
    let src = "#1=0\nG0 X1 M98 P2 L2\nG0 X#1\nM30\nO2\nM98 P1 L3\n#1=[FIX[#1]+1]\nM99\nO1\n#1=[#1+0.1]\nG0 X#1\nM99";
    let x = xs(src);
    assert_eq!(x.len(), 1 + 6 + 1);
    assert!(
        (x[6] - 1.3).abs() < 1e-9 && (x[7] - 2.0).abs() < 1e-9,
        "{x:?}"
    );
    // In the main flow an `O` line is a label, and M99 ends the program.
    assert_eq!(xs("O5\nG0 X1\nM99\nG0 X2"), vec![1.0]);
    assert_eq!(xs("O<main>\nG0 X1"), vec![1.0]);
    for src in ["M98", "M98 P7", "o1 sub\no1 endsub\nM98 P1"] {
        assert_eq!(err(src).kind, GcodeErrorKind::Invalid, "{src}");
    }
}

#[test]
fn io_and_override_m_codes_are_actions_without_motion() {
    let k = kinds("M64 P1\nM68 E0 Q2.5\nM66 P0 L0\nM50 P0\nM61 Q3 G0 X1");
    assert_eq!(k.len(), 5);
    assert_eq!(
        k[1],
        CanonKind::Io {
            m: 68,
            p: None,
            e: Some(0.0),
            l: None,
            q: Some(2.5)
        }
    );
    for src in ["M64", "M68 E1", "M61", "M62 P1 M63 P2"] {
        assert_eq!(err(src).kind, GcodeErrorKind::Invalid, "{src}");
    }
}

#[test]
fn a_call_runs_the_subroutine_file_of_that_name_from_the_subroutine_folders() {
    let dir = std::env::temp_dir().join(format!("vmc-subs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("hop.ngc"),
        "(before)\no<hop> sub\nG1 X#1 F100\no<step> call\no<hop> endsub\nG0 X99\nM2\n",
    )
    .unwrap();
    std::fs::write(dir.join("step.ngc"), "o<step> sub\nG1 Y1\no<step> endsub\n").unwrap();
    std::fs::write(dir.join("bare.ngc"), "G0 X1\n").unwrap();
    let cfg = InterpConfig {
        subroutine_dirs: vec![dir.join("missing"), dir.clone()],
        ..InterpConfig::default()
    };
    let moves = run_program("G21\no<hop> call [5]\nG0 Z1\nM2", &cfg).unwrap();
    let ends: Vec<[f64; 3]> = moves
        .iter()
        .filter_map(|m| match m.kind {
            CanonKind::Feed { end_mm, .. } | CanonKind::Traverse { end_mm, .. } => Some(end_mm),
            _ => None,
        })
        .collect();
    // Only the definition is taken from the file: its G0 X99 never runs.
    assert_eq!(ends, [[5.0, 0.0, 0.0], [5.0, 1.0, 0.0], [5.0, 1.0, 1.0]]);
    let e = run_program("G21\no<bare> call", &cfg).unwrap_err();
    assert!(e.msg.contains("has no o<bare> sub"), "{e}");
    assert_eq!((e.line, e.col), (2, 1));
    let e = run_program("G21\no<nowhere> call", &cfg).unwrap_err();
    assert!(e.is_unsupported(), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_call_may_compute_the_subroutine_number() {
    let src = "#2=10\nO[#2*10] call\n#<s>=200\nO#<s> call\nM2\n\
               O100 sub\nG0 X1\nO100 endsub\nO200 sub\nG0 X2\nO200 endsub";
    assert_eq!(xs(src), vec![1.0, 2.0]);
    assert_eq!(err("O[3] call\nM2").kind, GcodeErrorKind::Invalid);
    assert!(err("O[1] sub\nO[1] endsub").is_unsupported());
}

#[test]
fn g52_sets_the_g92_offset_to_its_values_whatever_the_distance_mode() {
    // G52 X2: program X0 is machine X2; G91 G52 X1 sets it to 1, not 3.
    assert_eq!(
        xs("G52 X2\nG0 X0\nG91 G52 X1\nG90 G0 X0\nG92.2\nG0 X0\nG92.3\nG0 X0"),
        vec![2.0, 1.0, 0.0, 1.0]
    );
}

#[test]
fn m19_orients_the_spindle_and_leaves_it_stopped() {
    let moves = run_program("S100 M3\nM19 R45 Q2 P1\nM2", &InterpConfig::default()).unwrap();
    assert!(moves.iter().any(|m| m.kind
        == CanonKind::SpindleOrient {
            angle_deg: 45.0,
            direction: OrientDirection::Clockwise,
            timeout_s: Some(2.0),
        }));
    // Stopped: right-hand tapping needs M3 again.
    assert_eq!(err("S100 M3\nM19\nG84 X1 Z-1 R1 F10").line, 3);
    for bad in ["M19 R-1", "M19 Q0", "M19 P3", "M3 M19"] {
        assert_eq!(err(bad).kind, GcodeErrorKind::Invalid, "{bad}");
    }
}

#[test]
fn g10_l1_l10_l11_write_tool_lengths_that_g43_then_uses() {
    let z = |src: &str| -> Vec<f64> {
        let cfg = InterpConfig {
            tool_lengths_mm: vec![(1, 50.0)],
            ..InterpConfig::default()
        };
        run_program(src, &cfg)
            .unwrap_or_else(|e| panic!("{src}: {e}"))
            .into_iter()
            .filter_map(|m| match m.kind {
                CanonKind::Traverse { end_mm, .. } => Some(end_mm[2]),
                _ => None,
            })
            .collect()
    };
    assert_eq!(z("G10 L1 P1 Z10\nG43 H1\nG0 Z0"), vec![10.0]);
    // At machine Z5, L10 Z1 makes the length 4 (with G92 Z shift 1: 3).
    assert_eq!(z("G0 Z5\nG10 L10 P1 Z1\nG43 H1\nG0 Z0"), vec![5.0, 4.0]);
    assert_eq!(
        z("G0 Z5\nG92 Z4\nG10 L10 P1 Z1\nG43 H1\nG0 Z0"),
        vec![5.0, 4.0]
    );
    // L11 measures in G59.3 (Z-2 here), without G92.
    assert_eq!(
        z("G10 L2 P9 Z-2\nG0 Z5\nG92 Z0\nG10 L11 P1 Z1\nG92.1\nG43 H1\nG0 Z0"),
        vec![5.0, 6.0]
    );
    let cfg = InterpConfig {
        tool_lengths_mm: vec![(1, 50.0)],
        ..InterpConfig::default()
    };
    let e = run_program("G10 L1 P7 Z1", &cfg).unwrap_err();
    assert!(e.msg.contains("tool 7 not found"), "{e}");
    assert!(err("G10 L1 P1 X1").is_unsupported());
    assert_eq!(err("G10 L1 P0 Z1").kind, GcodeErrorKind::Invalid);
}
