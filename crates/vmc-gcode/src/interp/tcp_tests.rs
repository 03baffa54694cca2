//! G43.4 tool centre point control: what the interpreter emits and what it refuses.

use super::*;

fn five_axis() -> InterpConfig {
    InterpConfig {
        tool_lengths_mm: vec![(1, 150.0), (2, 0.0)],
        tcp_axes: Some([false, true, true]),
        work_offsets_mm: {
            let mut w = [[0.0; 3]; WORK_OFFSETS];
            w[0] = [5.0, 0.0, 0.0];
            w
        },
        ..InterpConfig::default()
    }
}

fn error(src: &str, cfg: &InterpConfig) -> String {
    run_program_tcp(src, cfg).unwrap_err().to_string()
}

#[test]
fn moves_under_g43_4_carry_the_programmed_tip_unshifted_by_the_tool_length() {
    let src = "G0 X0 Y0 Z0\nG43.4 H1\nG0 X10 Y20 Z30 B-30 C90\nG1 X15 F500\nG2 X25 I5 J0\nG49\nG0 X0 Y0 Z0\nM2";
    let (moves, tcp) = run_program_tcp(src, &five_axis()).unwrap();
    assert_eq!(
        tcp,
        [None, Some(150.0), Some(150.0), Some(150.0), None, None]
    );
    // The work offset applies as to any program: the part frame's origin moves with it.
    assert_eq!(
        moves[1].kind,
        CanonKind::Traverse {
            end_mm: [15.0, 20.0, 30.0],
            end_abc_deg: [0.0, -30.0, 90.0]
        }
    );
    assert!(matches!(
        moves[2].kind,
        CanonKind::Feed {
            end_mm: [20.0, 20.0, 30.0],
            ..
        }
    ));
    assert!(matches!(
        moves[3].kind,
        CanonKind::Arc {
            end_mm: [30.0, 20.0, 30.0],
            ..
        }
    ));
    assert!(matches!(
        moves[4].kind,
        CanonKind::Traverse {
            end_mm: [5.0, 0.0, 0.0],
            ..
        }
    ));
}

#[test]
fn the_same_program_without_g43_4_is_unchanged_by_the_five_axis_configuration() {
    let src = "G0 X1 Y2 Z3 B-10\nG43 H1\nG1 Z-5 F100\nG49\nG0 Z0\nM2";
    let plain = run_program(
        src,
        &InterpConfig {
            tool_lengths_mm: vec![(1, 150.0), (2, 0.0)],
            ..five_axis()
        },
    )
    .unwrap();
    let (five, tcp) = run_program_tcp(src, &five_axis()).unwrap();
    assert_eq!(plain, five);
    assert!(tcp.iter().all(Option::is_none));
}

#[test]
fn g43_4_is_refused_on_a_machine_without_its_kinematics() {
    let cfg = InterpConfig {
        tool_lengths_mm: vec![(1, 150.0)],
        ..InterpConfig::default()
    };
    assert_eq!(
        error("G0 Z0\nG0 G43.4 H1 X0 Y0 Z0", &cfg),
        "line 2, column 4: G43.4 (tool centre point control) needs a five-axis machine's kinematics; this machine has none"
    );
}

#[test]
fn g43_4_without_a_tool_length_is_refused_with_its_column() {
    assert_eq!(
        error("G43.4 H3", &five_axis()),
        "line 1, column 1: G43.4 needs the tool's length: tool 3 has none in the tool table"
    );
    assert_eq!(
        error("G43.4 H2", &five_axis()),
        "line 1, column 1: G43.4 needs the tool's length: tool 2 has none in the tool table"
    );
    // No H: the spindle's tool, here tool 0.
    assert_eq!(
        error("G90\n  G43.4", &five_axis()),
        "line 2, column 3: G43.4 needs the tool's length: tool 0 has none in the tool table"
    );
}

#[test]
fn a_rotary_word_of_an_axis_the_machine_lacks_is_refused_under_g43_4() {
    assert_eq!(
        error("G43.4 H1\nG0 X0 Y0 Z0\nG1 X1 A10 F100", &five_axis()),
        "line 3, column 7: G43.4: this machine has no A axis"
    );
}

#[test]
fn the_first_move_after_a_frame_change_must_give_the_whole_tip_position() {
    assert_eq!(
        error("G43.4 H1\nG0 X0 Y0 B-10", &five_axis()),
        "line 2, column 1: the first move after G43.4 is switched on or off must give X, Y and Z in G90: the tool tip's place in the new frame"
    );
    assert!(error("G43.4 H1\nG91 G0 X0 Y0 Z0", &five_axis()).starts_with("line 2, column 5:"));
    assert!(
        error("G43.4 H1\nG0 X0 Y0 Z0\nG49\nG0 X5", &five_axis()).starts_with("line 4, column 1:")
    );
}

#[test]
fn machine_coordinates_cycles_and_tool_changes_are_refused_under_g43_4() {
    for (src, want) in [
        (
            "G43.4 H1\nG0 X0 Y0 Z0\nG53 G0 Z0",
            "line 3, column 1: G53 with G43.4",
        ),
        (
            "G43.4 H1\nG0 X0 Y0 Z0\nG28",
            "line 3, column 1: G28/G30 with G43.4",
        ),
        (
            "G43.4 H1\nG0 X0 Y0 Z0\nG81 X1 Y1 Z-1 R1 F100",
            "line 3, column 1: a canned cycle with G43.4",
        ),
        (
            "G43.4 H1\nG0 X0 Y0 Z0\nT2 M6",
            "line 3, column 4: M6 with G43.4",
        ),
    ] {
        let e = error(src, &five_axis());
        assert!(e.starts_with(want), "{src}: {e}");
    }
}
