//! Canned cycle and feed mode tests. Every expected listing is LinuxCNC's: the motion, dwell
//! and pause calls printed by `rs274 -g -t tool.tbl prog.ngc` (LinuxCNC's stand-alone
//! interpreter) for `G21 G90 G17 F100`, `G0 X0 Y0 Z10`, the lines given, `M2`.

use super::*;

/// Our actions after the two set-up lines, in `rs274`'s call syntax (mm, 4 decimals).
fn listing(lines: &str) -> Vec<String> {
    let src = format!("G21 G90 G17 F100\nG0 X0 Y0 Z10\n{lines}\nM2");
    let moves = run_program(&src, &InterpConfig::default())
        .unwrap_or_else(|e| panic!("{lines}: rejected: {e}"));
    let p = |v: [f64; 3]| format!("{:.4}, {:.4}, {:.4}", v[0], v[1], v[2]);
    moves
        .iter()
        .filter(|m| m.line > 2)
        .filter_map(|m| match &m.kind {
            CanonKind::Traverse { end_mm, .. } => {
                Some(format!("STRAIGHT_TRAVERSE({})", p(*end_mm)))
            }
            CanonKind::Feed { end_mm, .. } => Some(format!("STRAIGHT_FEED({})", p(*end_mm))),
            CanonKind::Dwell { duration_s } => Some(format!("DWELL({duration_s:.4})")),
            CanonKind::Pause(PauseKind::Program) => Some("PROGRAM_STOP()".to_string()),
            _ => None,
        })
        .collect()
}

fn check(lines: &str, expected: &str) {
    let want: Vec<&str> = expected
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    assert_eq!(listing(lines), want, "{lines}");
}

fn err(src: &str) -> GcodeError {
    run_program(src, &InterpConfig::default()).expect_err("program must be rejected")
}

#[test]
fn g81_g98_g99_sticky_words_and_repeats() {
    check(
        "G98 G81 X5 Y5 Z-3 R2\nG99 X10\nX15 Z-4 R1 L2",
        "STRAIGHT_TRAVERSE(5.0000, 5.0000, 10.0000)
         STRAIGHT_TRAVERSE(5.0000, 5.0000, 2.0000)
         STRAIGHT_FEED(5.0000, 5.0000, -3.0000)
         STRAIGHT_TRAVERSE(5.0000, 5.0000, 10.0000)
         STRAIGHT_TRAVERSE(10.0000, 5.0000, 10.0000)
         STRAIGHT_TRAVERSE(10.0000, 5.0000, 2.0000)
         STRAIGHT_FEED(10.0000, 5.0000, -3.0000)
         STRAIGHT_TRAVERSE(10.0000, 5.0000, 2.0000)
         STRAIGHT_TRAVERSE(15.0000, 5.0000, 2.0000)
         STRAIGHT_TRAVERSE(15.0000, 5.0000, 1.0000)
         STRAIGHT_FEED(15.0000, 5.0000, -4.0000)
         STRAIGHT_TRAVERSE(15.0000, 5.0000, 1.0000)
         STRAIGHT_TRAVERSE(15.0000, 5.0000, 1.0000)
         STRAIGHT_FEED(15.0000, 5.0000, -4.0000)
         STRAIGHT_TRAVERSE(15.0000, 5.0000, 1.0000)",
    );
}

#[test]
fn g82_dwells_at_the_bottom() {
    check(
        "G82 X5 Z-3 R2 P0.5",
        "STRAIGHT_TRAVERSE(5.0000, 0.0000, 10.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)
         STRAIGHT_FEED(5.0000, 0.0000, -3.0000)
         DWELL(0.5000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)",
    );
}

#[test]
fn g73_breaks_chips_with_a_0_254_mm_back_off() {
    check(
        "G73 X5 Z-3.5 R2 Q1.5",
        "STRAIGHT_TRAVERSE(5.0000, 0.0000, 10.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)
         STRAIGHT_FEED(5.0000, 0.0000, 0.5000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 0.7540)
         STRAIGHT_FEED(5.0000, 0.0000, -1.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, -0.7460)
         STRAIGHT_FEED(5.0000, 0.0000, -2.5000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, -2.2460)
         STRAIGHT_FEED(5.0000, 0.0000, -3.5000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)",
    );
}

#[test]
fn g83_returns_to_r_and_comes_back_0_254_mm_above_the_last_depth() {
    check(
        "G98 G83 X5 Z-3.5 R2 Q1.5",
        "STRAIGHT_TRAVERSE(5.0000, 0.0000, 10.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)
         STRAIGHT_FEED(5.0000, 0.0000, 0.5000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 0.7540)
         STRAIGHT_FEED(5.0000, 0.0000, -1.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, -0.7460)
         STRAIGHT_FEED(5.0000, 0.0000, -2.5000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, -2.2460)
         STRAIGHT_FEED(5.0000, 0.0000, -3.5000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 10.0000)",
    );
}

#[test]
fn g84_and_g74_reverse_the_spindle_at_the_bottom_and_feed_out() {
    let tap = "STRAIGHT_TRAVERSE(5.0000, 0.0000, 10.0000)
               STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)
               STRAIGHT_FEED(5.0000, 0.0000, -3.0000)
               DWELL(0.0000)
               STRAIGHT_FEED(5.0000, 0.0000, 2.0000)";
    check("M3 S1000\nG84 X5 Z-3 R2", tap);
    check("M4 S1000\nG74 X5 Z-3 R2", tap);
    // rs274: STOP_SPINDLE_TURNING, START_SPINDLE_COUNTERCLOCKWISE at the bottom; STOP, START
    // clockwise at the top.
    let src = "G21 F100\nM3 S1000\nG84 X5 Z-3 R2\nM2";
    let dirs: Vec<SpindleDir> = run_program(src, &InterpConfig::default())
        .unwrap()
        .iter()
        .filter(|m| m.line == 3)
        .filter_map(|m| match m.kind {
            CanonKind::Spindle { dir, .. } => Some(dir),
            _ => None,
        })
        .collect();
    use SpindleDir::{Ccw, Cw, Off};
    assert_eq!(dirs, [Off, Ccw, Off, Cw]);
    assert!(err("G21 F100\nG84 X5 Z-3 R2").msg.contains("clockwise"));
    assert!(err("G21 F100\nM3 S100\nG74 X5 Z-3 R2")
        .msg
        .contains("counter-clockwise"));
}

#[test]
fn boring_cycles_g85_g86_g88_g89() {
    check(
        "G98 G85 X5 Z-3 R2",
        "STRAIGHT_TRAVERSE(5.0000, 0.0000, 10.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)
         STRAIGHT_FEED(5.0000, 0.0000, -3.0000)
         STRAIGHT_FEED(5.0000, 0.0000, 2.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 10.0000)",
    );
    check(
        "M3 S500\nG98 G86 X5 Z-3 R2 P1",
        "STRAIGHT_TRAVERSE(5.0000, 0.0000, 10.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)
         STRAIGHT_FEED(5.0000, 0.0000, -3.0000)
         DWELL(1.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 10.0000)",
    );
    check(
        "M3 S500\nG88 X5 Z-3 R2 P1",
        "STRAIGHT_TRAVERSE(5.0000, 0.0000, 10.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)
         STRAIGHT_FEED(5.0000, 0.0000, -3.0000)
         DWELL(1.0000)
         PROGRAM_STOP()",
    );
    check(
        "G98 G89 X5 Z-3 R2 P1",
        "STRAIGHT_TRAVERSE(5.0000, 0.0000, 10.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)
         STRAIGHT_FEED(5.0000, 0.0000, -3.0000)
         DWELL(1.0000)
         STRAIGHT_FEED(5.0000, 0.0000, 10.0000)",
    );
}

#[test]
fn g87_back_bores_from_below_with_the_spindle_oriented_on_the_way_in_and_out() {
    check(
        "M3 S500\nG98 G87 X5 Y1 Z-3 R2 I1 J0.5 K-1",
        "STRAIGHT_TRAVERSE(5.0000, 1.0000, 10.0000)
         STRAIGHT_TRAVERSE(5.0000, 1.0000, 2.0000)
         STRAIGHT_TRAVERSE(6.0000, 1.5000, 2.0000)
         STRAIGHT_TRAVERSE(6.0000, 1.5000, -3.0000)
         STRAIGHT_TRAVERSE(5.0000, 1.0000, -3.0000)
         STRAIGHT_FEED(5.0000, 1.0000, -1.0000)
         STRAIGHT_FEED(5.0000, 1.0000, -3.0000)
         STRAIGHT_TRAVERSE(6.0000, 1.5000, -3.0000)
         STRAIGHT_TRAVERSE(6.0000, 1.5000, 10.0000)
         STRAIGHT_TRAVERSE(5.0000, 1.0000, 10.0000)",
    );
}

#[test]
fn incremental_cycles_step_between_repeats_and_measure_r_from_the_initial_level() {
    check(
        "G91 G98 G81 X2 Y1 Z-4 R-5 L3",
        "STRAIGHT_TRAVERSE(2.0000, 1.0000, 10.0000)
         STRAIGHT_TRAVERSE(2.0000, 1.0000, 5.0000)
         STRAIGHT_FEED(2.0000, 1.0000, 1.0000)
         STRAIGHT_TRAVERSE(2.0000, 1.0000, 10.0000)
         STRAIGHT_TRAVERSE(4.0000, 2.0000, 10.0000)
         STRAIGHT_TRAVERSE(4.0000, 2.0000, 5.0000)
         STRAIGHT_FEED(4.0000, 2.0000, 1.0000)
         STRAIGHT_TRAVERSE(4.0000, 2.0000, 10.0000)
         STRAIGHT_TRAVERSE(6.0000, 3.0000, 10.0000)
         STRAIGHT_TRAVERSE(6.0000, 3.0000, 5.0000)
         STRAIGHT_FEED(6.0000, 3.0000, 1.0000)
         STRAIGHT_TRAVERSE(6.0000, 3.0000, 10.0000)",
    );
}

#[test]
fn cycles_in_the_zx_and_yz_planes_drill_along_y_and_x() {
    check(
        "G18\nG98 G81 X5 Y-3 Z1 R2",
        "STRAIGHT_TRAVERSE(0.0000, 2.0000, 10.0000)
         STRAIGHT_TRAVERSE(5.0000, 2.0000, 1.0000)
         STRAIGHT_FEED(5.0000, -3.0000, 1.0000)
         STRAIGHT_TRAVERSE(5.0000, 2.0000, 1.0000)",
    );
    check(
        "G19\nG99 G81 Y5 X-3 Z1 R2",
        "STRAIGHT_TRAVERSE(2.0000, 0.0000, 10.0000)
         STRAIGHT_TRAVERSE(2.0000, 5.0000, 1.0000)
         STRAIGHT_FEED(-3.0000, 5.0000, 1.0000)
         STRAIGHT_TRAVERSE(2.0000, 5.0000, 1.0000)",
    );
}

#[test]
fn the_initial_level_survives_cycle_changes_and_ends_with_another_motion_mode() {
    // rs274 on `G99 G81 X5 Z-3 R2`, `G98 G82 X20 Z-4 R3 P0.5`: back up to Z10 (the level
    // before the first cycle), not to Z2.
    check(
        "G99 G81 X5 Z-3 R2\nG98 G82 X20 Z-4 R3 P0.5\nG0 Z1\nG98 G81 X25 Z-3 R2",
        "STRAIGHT_TRAVERSE(5.0000, 0.0000, 10.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)
         STRAIGHT_FEED(5.0000, 0.0000, -3.0000)
         STRAIGHT_TRAVERSE(5.0000, 0.0000, 2.0000)
         STRAIGHT_TRAVERSE(20.0000, 0.0000, 10.0000)
         STRAIGHT_TRAVERSE(20.0000, 0.0000, 3.0000)
         STRAIGHT_FEED(20.0000, 0.0000, -4.0000)
         DWELL(0.5000)
         STRAIGHT_TRAVERSE(20.0000, 0.0000, 10.0000)
         STRAIGHT_TRAVERSE(20.0000, 0.0000, 1.0000)
         STRAIGHT_TRAVERSE(20.0000, 0.0000, 2.0000)
         STRAIGHT_TRAVERSE(25.0000, 0.0000, 2.0000)
         STRAIGHT_FEED(25.0000, 0.0000, -3.0000)
         STRAIGHT_TRAVERSE(25.0000, 0.0000, 2.0000)",
    );
}

#[test]
fn cycle_errors_name_the_word_and_where() {
    let cases: &[(&str, usize, &str)] = &[
        // rs274: "Z value unspecified in xy plane canned cycle".
        ("G21 F100\nG81 X5 R2", 1, "needs Z"),
        // rs274: "R clearance plane unspecified in cycle".
        ("G21 F100\nG81 X5 Z-3", 1, "needs R"),
        // rs274: "R less than z in cycle in xy plane".
        ("G21 F100\nG81 X5 Z3 R2", 1, "below the hole bottom"),
        // rs274: "Q word missing with g73".
        ("G21 F100\nG73 X5 Z-3 R2", 1, "needs Q"),
        // rs274: "Negative or zero q value used".
        ("G21 F100\nG83 X5 Z-3 R2 Q0", 15, "must be > 0"),
        // rs274: "Cannot do zero repeats of cycle".
        ("G21 F100\nG81 X5 Z-3 R2 L0", 15, "L0"),
        // rs274: "Dwell time p word missing with g82".
        ("G21 F100\nG82 X5 Z-3 R2", 1, "needs P"),
        // rs274: "P word with no G2 G3 G4 … to use it".
        ("G21 F100\nG81 X5 Z-3 R2 P1", 15, "P word with G81"),
        // rs274: "Q word with no … that uses it".
        ("G21 F100\nG81 X5 Z-3 R2 Q1", 15, "Q word with G81"),
        // rs274: "Cannot use inverse time feed with canned cycles".
        ("G21 G93\nG81 X5 Z-3 R2 F1", 1, "G93"),
        // rs274: "Spindle not turning in g88".
        ("G21 F100\nG88 X5 Z-3 R2 P1", 1, "spindle turning"),
    ];
    for &(src, col, text) in cases {
        let e = err(src);
        assert_eq!((e.line, e.col), (2, col), "{src}: {e}");
        assert!(e.msg.contains(text), "{src}: {e}");
    }
    // Beyond what a block may expand to (LinuxCNC has no limit): refused, never a hang.
    let e = err("G21 F100\nG83 X5 Z-1000 R2 Q0.01 L50");
    assert!(e.is_unsupported() && e.msg.contains("pecks"), "{e}");
    let e = err("G21 F100\nG81 X5 Z-1 R2 L100000");
    assert!(e.is_unsupported() && e.msg.contains("L100000"), "{e}");
    // rs274: "J word missing with g87".
    let e = err("G21 F100\nM3 S500\nG87 X5 Z-3 R2 I1 K-1");
    assert!(e.msg.contains("G87 needs I, J and K"), "{e}");
    for lathe in ["G76 X1 Z-1", "G71 X1 Z-1", "G70 X1 Z-1"] {
        assert!(err(lathe).msg.contains("lathe cycle"), "{lathe}");
    }
}

/// The feed of every Feed/Arc action of a program.
fn feeds(src: &str) -> Vec<f64> {
    run_program(src, &InterpConfig::default())
        .unwrap_or_else(|e| panic!("{src}: {e}"))
        .iter()
        .filter_map(|m| match m.kind {
            CanonKind::Feed {
                feed_mm_per_min, ..
            }
            | CanonKind::Arc {
                feed_mm_per_min, ..
            } => Some(feed_mm_per_min),
            _ => None,
        })
        .collect()
}

#[test]
fn inverse_time_and_per_revolution_feeds_become_mm_per_minute_as_in_rs274() {
    // rs274: SET_FEED_RATE(20.0000), (5.0000); arc: SET_FEED_RATE(66.6432).
    let f = feeds("G21 G0 Z10\nG93 G1 X10 F2\nX20 F0.5\nG2 X30 Y10 I5 J5 F3");
    assert_eq!(f.len(), 3);
    for (got, want) in f.iter().zip([20.0, 5.0, 66.6432]) {
        assert!((got - want).abs() < 1e-4, "{f:?}");
    }
    // rs274: G95 F0.1 at S1000 then S500 (SET_FEED_RATE(0.1000), programmed per revolution).
    let f = feeds("G21 M3 S1000\nG95 G1 X10 F0.1\nX20\nS500 X30\nG94 F100 X40");
    assert_eq!(f, [100.0, 100.0, 50.0, 100.0]);
    // rs274: "F word missing with inverse time g1 move".
    assert!(err("G21 G93 G1 X10 F2\nX20")
        .msg
        .contains("needs an F word"));
    // rs274: "Cannot feed with zero spindle speed in feed per rev mode".
    assert!(err("G21 G95 G1 X10 F0.1").msg.contains("S0"));
    // rs274: selecting a feed mode zeroes the feed rate: "Cannot do g1 with zero feed rate".
    assert!(err("G21 F100\nG94 G1 X5").msg.contains("zero feed"));
}

#[test]
fn m70_m72_and_m73_restore_the_modal_state_as_rs274_does() {
    // rs274 (mm program; its inch output converted): the G1 X1 under G20 G91 ends at
    // X25.4; after M72, G1 X5 is absolute mm again at F100 with the spindle back to M3 S500
    // and the flood coolant off; the M73 state comes back at `endsub`.
    let src = "G21 G90 G17 F100 S500 M3\nG0 X0 Y0 Z10\nM70\n\
               G20 G91 G18 F7 S800 M4 M8 G98\nG1 X1 F2\nM72\nG1 X5\n\
               o100 sub\nM73\nG20 G91 F9 S300 M5 G19\nG1 X1\no100 endsub\n\
               o100 call\nG1 X7\nM2";
    let moves = run_program(src, &InterpConfig::default()).unwrap();
    let feed_ends: Vec<([f64; 3], f64)> = moves
        .iter()
        .filter_map(|m| match m.kind {
            CanonKind::Feed {
                end_mm,
                feed_mm_per_min,
                ..
            } => Some((end_mm, feed_mm_per_min)),
            _ => None,
        })
        .collect();
    let want = [
        ([25.4, 0.0, 10.0], 2.0 * 25.4),
        ([5.0, 0.0, 10.0], 100.0),
        // F9 on the G20 line is read in mm, the units before that block (rs274 too).
        ([30.4, 0.0, 10.0], 9.0),
        ([7.0, 0.0, 10.0], 100.0),
    ];
    assert_eq!(feed_ends.len(), want.len());
    for ((end, f), (we, wf)) in feed_ends.iter().zip(want) {
        assert!(
            (0..3).all(|i| (end[i] - we[i]).abs() < 1e-9),
            "{feed_ends:?}"
        );
        assert!((f - wf).abs() < 1e-9, "{feed_ends:?}");
    }
    let at = |line: usize| -> Vec<CanonKind> {
        moves
            .iter()
            .filter(|m| m.line == line)
            .map(|m| m.kind.clone())
            .collect()
    };
    assert_eq!(
        at(6),
        [
            CanonKind::Spindle {
                dir: SpindleDir::Cw,
                rpm: 500.0
            },
            CanonKind::Coolant {
                mist: false,
                flood: false
            }
        ]
    );
    assert_eq!(
        at(12),
        [CanonKind::Spindle {
            dir: SpindleDir::Cw,
            rpm: 500.0
        }]
    );
    // rs274: "Cannot restore context from invalid stack frame - missing M70/M73?"
    for bad in [
        "G21\nM72",
        "G21\nM70\nM71\nM72",
        "G21\no1 sub\nM70\no1 endsub\no1 call\nM72",
    ] {
        let e = err(bad);
        assert!(e.msg.contains("M72: no modal state saved"), "{bad}: {e}");
    }
}
