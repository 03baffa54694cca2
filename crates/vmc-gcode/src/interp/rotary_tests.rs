//! Interpreter tests of the rotary axes A, B, C: positions against the values LinuxCNC's
//! `rs274` prints for the same blocks (its program coordinates plus the offsets it reports),
//! and the feed rule against closed forms.

use super::*;

/// 1e-9° (and 1e-9 mm): floating-point noise only; every expected value is exact arithmetic.
const TOL: f64 = 1e-9;

fn run(src: &str) -> Vec<CanonKind> {
    run_program(src, &InterpConfig::default())
        .unwrap_or_else(|e| panic!("program rejected: {e}"))
        .into_iter()
        .map(|m| m.kind)
        .collect()
}

fn err(src: &str) -> GcodeError {
    run_program(src, &InterpConfig::default()).expect_err("program must be rejected")
}

/// (end mm, end degrees, feed) of every motion; the feed of a traverse is NaN.
fn motions(kinds: &[CanonKind]) -> Vec<([f64; 3], [f64; 3], f64)> {
    kinds
        .iter()
        .filter_map(|k| match *k {
            CanonKind::Traverse {
                end_mm,
                end_abc_deg,
            } => Some((end_mm, end_abc_deg, f64::NAN)),
            CanonKind::Feed {
                end_mm,
                end_abc_deg,
                feed_mm_per_min,
            }
            | CanonKind::Arc {
                end_mm,
                end_abc_deg,
                feed_mm_per_min,
                ..
            } => Some((end_mm, end_abc_deg, feed_mm_per_min)),
            _ => None,
        })
        .collect()
}

fn abc(kinds: &[CanonKind]) -> Vec<[f64; 3]> {
    motions(kinds).into_iter().map(|m| m.1).collect()
}

fn assert_all_close(got: &[[f64; 3]], want: &[[f64; 3]]) {
    assert_eq!(got.len(), want.len(), "{got:?} != {want:?}");
    for (g, w) in got.iter().zip(want) {
        assert!(
            (0..3).all(|i| (g[i] - w[i]).abs() < TOL),
            "{got:?} != {want:?}"
        );
    }
}

#[test]
fn angles_are_absolute_or_incremental_and_never_scaled_by_g20() {
    let k = run("G21 G90\nG0 X1 A10\nG1 X5 A20 F100\nG20\nG1 A100 X1\nG91 G1 A5 B3 C-2\nM2");
    assert_all_close(
        &abc(&k),
        &[
            [10.0, 0.0, 0.0],
            [20.0, 0.0, 0.0],
            [100.0, 0.0, 0.0],
            [105.0, 3.0, -2.0],
        ],
    );
    // X of the G20 block is in inches.
    assert!((motions(&k)[2].0[0] - 25.4).abs() < TOL);
}

#[test]
fn work_offsets_g92_g52_and_their_suspension_shift_the_angles() {
    // rs274 (program coordinates + reported offsets) gives the same machine angles.
    let k = run(
        "G0 A10\nG10 L2 P1 A5 C7\nG0 A0 C0\nG92 A30\nG0 A40\nG92.2\nG0 A1\nG92.3\nG0 A2\n\
         G52 B7\nG0 B7\nG92.1\nG10 L20 P2 A3\nG55 G0 A0\nM2",
    );
    assert_all_close(
        &abc(&k),
        &[
            [10.0, 0.0, 0.0],
            [5.0, 0.0, 7.0],
            // G92 A30 at machine A5: offset 5 − 5 − 30 = −30; A40 → 40 + 5 − 30.
            [15.0, 0.0, 7.0],
            [6.0, 0.0, 7.0],
            [-23.0, 0.0, 7.0],
            // G52 B7 replaces the G92 offsets' B (A keeps −30).
            [-23.0, 14.0, 7.0],
            // G10 L20 P2 A3 at machine A−23 (G92 cleared): G55's A offset is −26; C stays.
            [-26.0, 14.0, 7.0],
        ],
    );
}

#[test]
fn g53_g28_and_g30_move_the_rotary_axes_with_their_stored_angles() {
    let k = run("G0 A60\nG28.1\nG0 X5 A33\nG28 A0\nG28 X1\nG10 L2 P1 A9\nG53 G0 A12\nG30 A5\nM2");
    assert_all_close(
        &abc(&k),
        &[
            [60.0, 0.0, 0.0],
            [33.0, 0.0, 0.0],
            // G28 A0: via A0, then A to the stored 60 (X stays).
            [0.0, 0.0, 0.0],
            [60.0, 0.0, 0.0],
            // G28 X1: A untouched on both legs.
            [60.0, 0.0, 0.0],
            [60.0, 0.0, 0.0],
            // G53: machine angle, no offset.
            [12.0, 0.0, 0.0],
            // G30 A5: via program A5 = machine 14, then the G30 angle 0.
            [14.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ],
    );
    let m = motions(&k);
    assert!((m[2].0[0] - 5.0).abs() < TOL && (m[5].0[0]).abs() < TOL);
}

#[test]
fn an_arc_carries_rotary_words_to_its_end() {
    let k = run("G0 X1 A10\nG2 X2 Y0 I0.5 A50 Z1 F100\nG3 X1 Y0 R0.5 B20 C30 P2\nM2");
    let m = motions(&k);
    assert_all_close(&[m[1].1, m[2].1], &[[50.0, 0.0, 0.0], [50.0, 20.0, 30.0]]);
    assert!(matches!(k[2], CanonKind::Arc { .. }));
}

#[test]
fn the_xy_rotation_of_a_work_offset_does_not_turn_the_angles() {
    let k = run("G10 L2 P1 R30 A9\nG0 X1 A7\nM2");
    let (end_mm, end_abc, _) = motions(&k)[0];
    let (s, c) = 30f64.to_radians().sin_cos();
    assert!((end_mm[0] - c).abs() < TOL && (end_mm[1] - s).abs() < TOL);
    assert_all_close(&[end_abc], &[[16.0, 0.0, 0.0]]);
}

#[test]
fn a_rotary_word_in_a_canned_cycle_is_refused_as_linuxcnc_refuses_it() {
    for cycle in ["G17 G81 X1 Y2 Z-1 R2 A5", "G18 G81 X1 Y2 Z-1 R2 C0"] {
        let e = err(&format!("G21 G90\n{cycle}\nM2"));
        assert_eq!((e.line, e.kind), (2, GcodeErrorKind::Invalid), "{e}");
        assert!(e.msg.contains("canned cycle"), "{e}");
    }
}

#[test]
fn the_feed_applies_to_the_xyz_path_unless_only_rotary_axes_move() {
    // G94, inches: X moves → F in inch/min (mm/min out); A alone → F in deg/min, unscaled.
    let k = run("G20 G94\nF10\nG1 X1 A90\nG1 A180\nG21\nF600\nG1 A90 B40\nM2");
    let feeds: Vec<f64> = motions(&k).iter().map(|m| m.2).collect();
    assert_eq!(feeds, [254.0, 10.0, 600.0]);
    assert!(rotary_only([0.0; 3], [0.0; 3], [0.0; 3], [1.0, 0.0, 0.0]));
    assert!(!rotary_only(
        [0.0; 3],
        [1.0, 0.0, 0.0],
        [0.0; 3],
        [1.0, 0.0, 0.0]
    ));
}

#[test]
fn inverse_time_feed_spreads_the_angle_or_the_xyz_length_over_one_over_f_minutes() {
    // 1/2 min: A 0 → 60 is 120 deg/min; X 0 → 3, Y 0 → 4 with A is 5 mm × 2 = 10 mm/min.
    let k = run("G93\nG1 A60 F2\nG1 X3 Y4 A0 F2\nG1 A30 B40 F0.5\nM2");
    let feeds: Vec<f64> = motions(&k).iter().map(|m| m.2).collect();
    assert_eq!(feeds, [120.0, 10.0, 25.0]);
}

#[test]
fn rotary_motion_under_cutter_compensation_is_unsupported_and_rotary_tool_offsets_too() {
    let e = err("G21 G90 F100\nG41.1 D2 G1 X10 Y0\nG1 X20 A5\nM2");
    assert_eq!((e.line, e.kind), (3, GcodeErrorKind::Unsupported), "{e}");
    let e = err("G10 L1 P1 A5\nM2");
    assert_eq!((e.line, e.kind), (1, GcodeErrorKind::Unsupported), "{e}");
    let e = err("G43.1 A2\nM2");
    assert_eq!((e.line, e.kind), (1, GcodeErrorKind::Unsupported), "{e}");
}

#[test]
fn rotary_offsets_are_linuxcnc_parameters() {
    // #5224 is G54's A offset, #5166 the G28 C angle, #5214 the G92 A offset.
    let k = run("G10 L2 P1 A4\nG0 C8\nG28.1\nG92 A1\nG0 A[#5224 + #5166 + #5214]\nM2");
    // G92 A1 at machine A0 (G54 A4): offset −5; A[4 + 8 − 5] = A7 → machine 7 + 4 − 5.
    assert_all_close(&[abc(&k)[1]], &[[6.0, 0.0, 8.0]]);
    let k = run("#5224 = 10\nG0 A0\nM2");
    assert_all_close(&abc(&k), &[[10.0, 0.0, 0.0]]);
}

#[test]
fn u_v_w_stay_unsupported_and_a_rotary_word_alone_is_a_move() {
    assert!(err("G0 U1").is_unsupported());
    assert_eq!(err("B5\nM2").line, 1);
    let k = run("G1 F100\nB5\nM2");
    assert_all_close(&abc(&k), &[[0.0; 3], [0.0, 5.0, 0.0]]);
}
