//! Cutter radius compensation against LinuxCNC: every expected path is the output of
//! `rs274 -g -t tool.tbl prog.ngc` (LinuxCNC's stand-alone interpreter) for the program shown,
//! with `tool.tbl` = `T1 P1 D0.472441 Z5.905512 ;` and `T2 P2 D0.118110 Z3.937008 ;` (Ø12 mm
//! and Ø3 mm, in inches as `rs274` reads a table without an INI file). Only the motion calls
//! are kept (trailing A, B, C arguments dropped).

use super::*;

/// LinuxCNC prints 4 decimals.
const TOL: f64 = 1e-4;

fn cfg() -> InterpConfig {
    InterpConfig {
        tool_diameters_mm: vec![(1, 12.0), (2, 3.0)],
        ..InterpConfig::default()
    }
}

fn run_comp(src: &str) -> Result<Vec<CanonMove>, GcodeError> {
    run_program(&format!("G21 G17 G90 F100 T1 M6\n{src}\nM2"), &cfg())
}

/// Plane coordinates of a reference call: (kind, numbers).
fn parse_ref(text: &str) -> Vec<(String, Vec<f64>)> {
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .map(|l| {
            let (name, rest) = l.split_once('(').expect("call");
            let nums = rest
                .trim_end_matches(')')
                .split(',')
                .filter(|a| !a.trim().is_empty())
                .map(|a| a.trim().parse().expect("number"))
                .collect();
            (name.to_string(), nums)
        })
        .collect()
}

fn as_ref_calls(moves: &[CanonMove]) -> Vec<(String, Vec<f64>)> {
    moves
        .iter()
        .filter_map(|m| match &m.kind {
            CanonKind::Traverse { end_mm, .. } => {
                Some(("STRAIGHT_TRAVERSE".to_string(), end_mm.to_vec()))
            }
            CanonKind::Feed { end_mm, .. } => Some(("STRAIGHT_FEED".to_string(), end_mm.to_vec())),
            CanonKind::Arc {
                end_mm,
                center_mm,
                plane,
                clockwise,
                ..
            } => {
                let (a1, a2, ax) = match plane {
                    Plane::Xy => (0, 1, 2),
                    Plane::Zx => (2, 0, 1),
                    Plane::Yz => (1, 2, 0),
                };
                let rot = if *clockwise { -1.0 } else { 1.0 };
                Some((
                    "ARC_FEED".to_string(),
                    vec![
                        end_mm[a1],
                        end_mm[a2],
                        center_mm[a1],
                        center_mm[a2],
                        rot,
                        end_mm[ax],
                    ],
                ))
            }
            CanonKind::Coolant { flood: true, .. } => Some(("FLOOD_ON".to_string(), vec![])),
            CanonKind::Coolant { flood: false, .. } => Some(("FLOOD_OFF".to_string(), vec![])),
            CanonKind::Dwell { duration_s } => Some(("DWELL".to_string(), vec![*duration_s])),
            CanonKind::Spindle {
                dir: SpindleDir::Cw,
                ..
            } => Some(("START_SPINDLE_CLOCKWISE".to_string(), vec![0.0])),
            _ => None,
        })
        .collect()
}

fn assert_path(src: &str, reference: &str) {
    let ours = as_ref_calls(&run_comp(src).unwrap_or_else(|e| panic!("{src}: {e}")));
    let expected = parse_ref(reference);
    assert_eq!(ours.len(), expected.len(), "{src}\nours {ours:?}");
    for (i, (o, r)) in ours.iter().zip(&expected).enumerate() {
        let close =
            o.1.len() == r.1.len() && o.1.iter().zip(&r.1).all(|(a, b)| (a - b).abs() <= TOL);
        assert!(
            o.0 == r.0 && close,
            "{src}\nmove {i}: ours {o:?}, rs274 {r:?}"
        );
    }
}

fn comp_err(src: &str) -> GcodeError {
    run_comp(src).expect_err("must be rejected")
}

#[test]
fn inside_corners_are_trimmed_and_the_exit_goes_straight() {
    assert_path(
        "G0 X0 Y0\nG41 D1\nG1 X20 Y0\nG1 X20 Y20\nG1 X0 Y20\nG40\nG1 X-10 Y30",
        "STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000)
         STRAIGHT_FEED(14.0000, 6.0000, 0.0000)
         STRAIGHT_FEED(14.0000, 14.0000, 0.0000)
         STRAIGHT_FEED(-0.0000, 14.0000, 0.0000)
         STRAIGHT_FEED(-10.0000, 30.0000, 0.0000)",
    );
}

#[test]
fn outside_corners_get_an_arc_of_the_tool_radius() {
    assert_path(
        "G0 X0 Y0\nG41 D1\nG1 X20 Y0\nG1 X20 Y-20\nG1 X0 Y-20\nG40\nG1 X-10 Y-30",
        "STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000)
         STRAIGHT_FEED(20.0000, 6.0000, 0.0000)
         ARC_FEED(26.0000, 0.0000, 20.0000, 0.0000, -1, 0.0000)
         STRAIGHT_FEED(26.0000, -20.0000, 0.0000)
         ARC_FEED(20.0000, -26.0000, 20.0000, -20.0000, -1, 0.0000)
         STRAIGHT_FEED(-0.0000, -26.0000, 0.0000)
         STRAIGHT_FEED(-10.0000, -30.0000, 0.0000)",
    );
}

#[test]
fn the_entry_move_ends_offset_perpendicular_to_itself() {
    assert_path(
        "G0 X0 Y0\nG41 D1\nG1 X20 Y10\nG1 X40 Y10\nG40 G1 X50 Y0",
        "STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000)
         STRAIGHT_FEED(17.3167, 15.3666, 0.0000)
         ARC_FEED(20.0000, 16.0000, 20.0000, 10.0000, -1, 0.0000)
         STRAIGHT_FEED(40.0000, 16.0000, 0.0000)
         STRAIGHT_FEED(50.0000, 0.0000, 0.0000)",
    );
}

#[test]
fn a_z_move_between_is_held_and_trimmed_with_the_corner() {
    assert_path(
        "G0 X0 Y0\nG41 D1\nG1 X20 Y10\nG1 Z-5\nG1 X20 Y30\nG40 G1 X50 Y0",
        "STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000)
         STRAIGHT_FEED(14.0000, 13.7082, 0.0000)
         STRAIGHT_FEED(14.0000, 13.7082, -5.0000)
         STRAIGHT_FEED(14.0000, 30.0000, -5.0000)
         STRAIGHT_FEED(50.0000, 0.0000, -5.0000)",
    );
}

#[test]
fn line_to_arc_and_arc_to_line_inside_corners_meet_on_the_offset_circle() {
    assert_path(
        "G0 X0 Y0\nG41 D1\nG1 X20 Y0\nG2 X40 Y0 R10\nG1 X60 Y0",
        "STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000)
         STRAIGHT_FEED(15.1676, 6.0000, 0.0000)
         ARC_FEED(44.8324, 6.0000, 30.0000, -0.0000, -1, 0.0000)
         STRAIGHT_FEED(60.0000, 6.0000, 0.0000)",
    );
}

#[test]
fn a_negative_g41_1_diameter_puts_the_tool_on_the_right() {
    let reference = "STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000)
         STRAIGHT_FEED(20.0000, -1.0000, 0.0000)
         ARC_FEED(21.0000, 0.0000, 20.0000, 0.0000, 1, 0.0000)
         STRAIGHT_FEED(21.0000, 20.0000, 0.0000)";
    assert_path("G0 X0 Y0\nG41.1 D-2\nG1 X20 Y0\nG1 Y20", reference);
    assert_path("G0 X0 Y0\nG42.1 D2\nG1 X20 Y0\nG1 Y20", reference);
}

#[test]
fn g18_compensates_in_the_zx_plane() {
    assert_path(
        "G0 X0 Y0\nG18 G41 D1\nG1 X20 Z0\nG1 X20 Z20\nG1 X40 Z20\nG40 G1 X50 Z50",
        "STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000)
         STRAIGHT_FEED(20.0000, 0.0000, -6.0000)
         ARC_FEED(0.0000, 26.0000, 0.0000, 20.0000, -1, 0.0000)
         STRAIGHT_FEED(26.0000, 0.0000, 14.0000)
         STRAIGHT_FEED(40.0000, 0.0000, 14.0000)
         STRAIGHT_FEED(50.0000, 0.0000, 50.0000)",
    );
}

#[test]
fn rapid_outside_corners_go_straight() {
    assert_path(
        "G0 X0 Y0\nG41 D1\nG0 X20 Y0\nG0 X20 Y-20\nG1 X0 Y-20\nG40 G0 X-10 Y-30",
        "STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000)
         STRAIGHT_TRAVERSE(20.0000, 6.0000, 0.0000)
         STRAIGHT_TRAVERSE(26.0000, 0.0000, 0.0000)
         STRAIGHT_TRAVERSE(26.0000, -20.0000, 0.0000)
         ARC_FEED(20.0000, -26.0000, 20.0000, -20.0000, -1, 0.0000)
         STRAIGHT_FEED(-0.0000, -26.0000, 0.0000)
         STRAIGHT_TRAVERSE(-10.0000, -30.0000, 0.0000)",
    );
}

#[test]
fn actions_between_held_moves_keep_their_order() {
    assert_path(
        "G0 X0 Y0\nG41 D1\nG1 X20 Y0\nM8\nG4 P1\nF200\nS100 M3\nG1 Y20\nM9\nG1 X0",
        "STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000)
         STRAIGHT_FEED(14.0000, 6.0000, 0.0000)
         FLOOD_ON()
         DWELL(1.0000)
         START_SPINDLE_CLOCKWISE(0)
         STRAIGHT_FEED(14.0000, 14.0000, 0.0000)
         FLOOD_OFF()
         STRAIGHT_FEED(-0.0000, 14.0000, 0.0000)",
    );
}

#[test]
fn arc_to_arc_near_reversal_is_an_inside_corner_where_the_offset_circles_meet() {
    // From LinuxCNC's `crazy-paths` test (radius 0.5 mm left).
    let src = "G0 X0 Y-100\nG41.1 D.5\nG1 Y-102\nG1 X15 Y-101\n\
               G3 I-3.939915 J-6.381776 X6.571635 Y-113.390421\n\
               G2 I1.555996 J2.082997 X7.390034 Y-108.814243\n\
               G1 X5.390034 Y-105.814243\nG40\nG1 X15.390034 Y-99.814243";
    assert_path(
        src,
        "STRAIGHT_TRAVERSE(0.0000, -100.0000, 0.0000)
         STRAIGHT_FEED(0.2500, -101.7328, 0.0000)
         STRAIGHT_FEED(14.1180, -100.8082, 0.0000)
         ARC_FEED(5.3231, -111.8146, 11.0601, -107.3818, 1, 0.0000)
         ARC_FEED(7.0052, -108.6877, 8.1276, -111.3074, -1, 0.0000)
         STRAIGHT_FEED(5.1820, -105.9529, 0.0000)
         STRAIGHT_FEED(15.3900, -99.8142, 0.0000)",
    );
}

#[test]
fn a_tool_change_after_g40_makes_the_compensated_point_the_programmed_one() {
    assert_path(
        "G0 X0 Y0\nG41 D1\nG1 X20 Y0\nG1 X20 Y20\nG40\nT2 M6\nG0 Z10\nG1 X0 Y0",
        "STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000)
         STRAIGHT_FEED(14.0000, 6.0000, 0.0000)
         STRAIGHT_FEED(14.0000, 20.0000, 0.0000)
         STRAIGHT_TRAVERSE(14.0000, 20.0000, 10.0000)
         STRAIGHT_FEED(0.0000, 0.0000, 10.0000)",
    );
}

#[test]
fn held_moves_are_released_at_the_end_of_the_text_and_keep_their_lines() {
    let moves = run_program("G0 X0 Y0\nG41.1 D2 F100\nG1 X20\nG1 Y-20", &cfg()).unwrap();
    let lines: Vec<usize> = moves.iter().map(|m| m.line).collect();
    assert_eq!(lines, vec![1, 3, 4, 4]);
}

#[test]
fn errors_follow_linuxcnc() {
    // (program, line, column, rs274's message)
    let cases = [
        (
            "G0 X0 Y0\nG41 D1\nG1 X5",
            4,
            1,
            "Length of cutter compensation entry move",
        ),
        (
            "G0 X0 Y0\nG41 D1\nG1 Z-1\nG1 X20",
            4,
            1,
            "entry move is not greater",
        ),
        (
            "G0 X0 Y0\nG41 D1\nG1 X20 Y0\nG1 X30 Y0\nG1 X30 Y1\nG1 X20 Y1",
            7,
            1,
            "Straight feed in concave corner cannot be reached by the tool without gouging",
        ),
        (
            "G0 X0 Y0\nG41 D1\nG1 X20 Y0\nG1 X30 Y0\nG1 X30 Y1\nG40\nG1 X0 Y0",
            7,
            1,
            "Straight feed in concave corner cannot be reached by the tool without gouging",
        ),
        (
            "G0 X0 Y-5\nG41 D1\nG1 X20 Y-5\nG3 X25 Y0 R5",
            5,
            1,
            "Tool radius not less than arc radius with comp",
        ),
        (
            "G0 X0 Y0\nG41 D1\nG1 X20\nG42 D1",
            5,
            1,
            "Cannot turn cutter radius comp on when on",
        ),
        ("G0 X0 Y0\nG41 D3", 3, 5, "tool 3 is not in the tool table"),
        ("G19 G41 D1", 2, 5, "allowed only in XY, XZ planes"),
        ("G41 D1\nG18", 3, 1, "Cannot change planes"),
        ("G41 D1\nG28", 3, 1, "Cannot use g28 or g30"),
        ("G41 D1\nG53 G0 X1", 3, 1, "Cannot use g53"),
        ("G41 D1\nG92 X0", 3, 1, "Cannot change axis offsets"),
        ("G41 D1\nT2 M6", 3, 4, "Cannot change tools"),
        ("G41 D1\nG43 H1", 3, 1, "Cannot change tool offset"),
        ("G41 D1\nG55", 3, 1, "Cannot change coordinate systems"),
        (
            "G0 X0 Y0\nG41 D1\nG1 X20\nG40\nG2 X30 R5",
            6,
            1,
            "must be straight, not an arc",
        ),
        (
            "G0 X0 Y0\nG41 D1\nG1 X20 Y0\nG3 X10 Y10 R10",
            5,
            1,
            "Arc move in concave corner cannot be reached by the tool without gouging",
        ),
        ("G41.1", 2, 1, "G41.1 needs a D word"),
        ("G42 D-1", 2, 5, "D word must be a tool number"),
        ("G1 X1 D1", 2, 7, "D word without G41"),
    ];
    for (src, line, col, msg) in cases {
        let e = comp_err(src);
        assert_eq!(e.kind, GcodeErrorKind::Invalid, "{src}: {e}");
        assert_eq!((e.line, e.col), (line, col), "{src}: {e}");
        assert!(e.msg.contains(msg), "{src}: {e}");
    }
}

#[test]
fn an_arc_entry_move_is_unsupported() {
    let e = comp_err("G0 X0 Y0\nG41 D1\nG2 X10 Y0 R5");
    assert!(e.is_unsupported(), "{e}");
    assert_eq!((e.line, e.col), (4, 1));
}
