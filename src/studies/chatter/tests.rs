//! The chatter check on small programs: verdicts, the spindle rule, refusals.

use super::*;
use vmc_gcode::interp::{run_program, InterpConfig};

fn moves(src: &str) -> Vec<CanonMove> {
    run_program(src, &InterpConfig::default()).unwrap()
}

/// 60 × 40 × 10 mm block, top at Z0.
fn block() -> StockBox {
    StockBox {
        min_mm: [0.0, 0.0, -10.0],
        max_mm: [60.0, 40.0, 0.0],
    }
}

fn run(src: &str) -> Result<ChatterReport, ChatterError> {
    check(
        &moves(src),
        &block(),
        &ToolDynamics::benchmark(),
        &ChatterOptions::default(),
    )
}

#[test]
fn a_deep_slot_chatters_and_a_light_side_cut_does_not() {
    // The benchmark cutter (Ø16, flexible along X) at 10 000 rpm: slotting along X is
    // unstable above ≈ 0.33 mm; a 1 mm side cut of 1 mm stepover (a_e/D ≈ 0.06) is stable.
    // The slot starts from a plunge inside the block; the side cut enters from outside.
    let r = run("G0 X5 Y20 Z5\nM3 S10000\nG1 Z-1 F500\nG1 X70\n\
                 G0 Z5\nG0 X70 Y21\nG1 Z-1\nG1 X14\nM5\nM2")
    .unwrap();
    assert_eq!(r.feed_moves, 4);
    assert_eq!(r.cuts.len(), 3, "{:#?}", r.cuts);
    let (plunge, slot, side) = (&r.cuts[0], &r.cuts[1], &r.cuts[2]);
    assert_eq!((plunge.line, plunge.verdict), (3, Verdict::Plunge));
    assert!((plunge.axial_depth_mm - 1.0).abs() < 1e-6, "{plunge:?}");
    assert_eq!((slot.line, slot.motion), (4, "G1"));
    assert_eq!(slot.engagement, Engagement::Slot);
    assert!((slot.axial_depth_mm - 1.0).abs() < 1e-9);
    assert_eq!(slot.verdict, Verdict::Unstable);
    let lim = slot.critical_depth_mm.unwrap();
    assert!(lim > 0.3 && lim < 0.35, "{lim}");
    assert_eq!(side.line, 8);
    // Feeding −X 1 mm beside the slot: the new material (Y 28…29) is on the right of the
    // motion, down milling once in the block (its entry through the face at X60 sees material
    // ahead only).
    assert!(
        matches!(side.engagement, Engagement::Down | Engagement::Entry),
        "{side:?}"
    );
    assert!(
        (side.immersion - 1.0 / 16.0).abs() < 0.04,
        "{}",
        side.immersion
    );
    assert_eq!(side.verdict, Verdict::Stable, "{side:?}");
    // 1 mm deep: the slot from X5 on (55 × 16 mm², and its round end but for the 26.1 mm²
    // beyond X0) and the strip Y 28…29 from X 14 − 2.78 to X60.
    let want = 55.0 * 16.0 + std::f64::consts::PI * 32.0 - 26.1 + 48.8;
    assert!(
        (r.removed_mm3 / want - 1.0).abs() < 0.03,
        "{} vs {want}",
        r.removed_mm3
    );
}

#[test]
fn a_counter_clockwise_spindle_swaps_up_and_down() {
    let tool = ToolDynamics::benchmark();
    let table = StabilityTable::new(&tool, Resolution::default(), 0.025, 4.0);
    let contact = |side, entry_rad, exit_rad| Contact {
        s_mm: 0.0,
        position_mm: [0.0; 3],
        axial_depth_mm: 1.0,
        kind: ContactKind::Side(EngagedArc {
            feed_angle_rad: 0.0,
            entry_rad,
            exit_rad,
            side,
        }),
    };
    let engaged = |ccw| Engaged {
        line: 1,
        motion: "G1",
        spindle_rpm: 10_000.0,
        ccw,
        feed_mm_per_min: 100.0,
        contacts: Vec::new(),
    };
    let judged = |ccw, c: &Contact| -> Vec<(f64, Engagement)> {
        candidates(&table, &engaged(ccw), c)
            .into_iter()
            .map(|(k, imm, e)| {
                assert!(table.immersion_of(k) >= imm - 1e-12);
                (imm, e)
            })
            .collect()
    };
    let half = std::f64::consts::FRAC_PI_2;
    let left = contact(Side::Left, 0.0, half);
    let close = |j: Vec<(f64, Engagement)>, imm: f64, e| {
        assert_eq!(j.len(), 1);
        assert!((j[0].0 - imm).abs() < 1e-12 && j[0].1 == e, "{j:?}");
    };
    close(judged(false, &left), 0.5, Engagement::Up);
    close(judged(true, &left), 0.5, Engagement::Down);
    let right = contact(Side::Right, half, std::f64::consts::PI);
    close(judged(false, &right), 0.5, Engagement::Down);
    close(judged(true, &right), 0.5, Engagement::Up);
    // Ahead only: the narrower covering window; head on, both.
    let ahead = contact(Side::Neither, 0.2, 1.0);
    let j = judged(false, &ahead);
    assert_eq!(j.len(), 1);
    assert!((j[0].0 - 0.5 * (1.0 - 1.0f64.cos())).abs() < 1e-12);
    assert_eq!(judged(false, &contact(Side::Neither, 1.0, 2.1416)).len(), 2);
}

#[test]
fn bad_programs_are_refused_with_one_clear_message() {
    let err = |src: &str| run(src).unwrap_err().to_string();
    assert_eq!(
        err("G0 X10 Y10 Z5\nM2"),
        "the program has no cutting move (G1, G2 or G3)"
    );
    assert!(err("M3 S8000\nG0 Z5\nG1 X100 Y100 Z5 F300\nM2")
        .starts_with("the program never touches the stock: none of its 1 feed moves"));
    assert_eq!(
        err("G0 X-10 Y20 Z-1\nG1 X70 F300\nM2"),
        "line 2: G1 cuts the stock with the spindle stopped, at X-7.500 Y20.000 Z-1.000"
    );
    let bad_bin = check(
        &moves("G1 X1 F1"),
        &block(),
        &ToolDynamics::benchmark(),
        &ChatterOptions {
            immersion_bin: 0.0,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert_eq!(
        bad_bin.to_string(),
        "the immersion bin must be in [0.01, 1], got 0"
    );
}

#[test]
fn the_csv_has_a_row_per_cut_with_units_in_the_header() {
    let r = run("G0 X5 Y20 Z5\nM3 S10000\nG1 Z-1 F500\nG1 X70\nM2").unwrap();
    let csv = report_csv(&r);
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].starts_with("line,move,spindle_rpm,feed_mm_per_min,immersion_ae_over_d,"));
    assert_eq!(lines.len(), 3);
    assert!(
        lines[1].starts_with("3,G1,10000,500,1.0000,plunge,1.0000,,false,,plunge,5.0000,20.0000,"),
        "{}",
        lines[1]
    );
    assert!(
        lines[2].starts_with("4,G1,10000,500,1.0000,slot,1.0000,"),
        "{}",
        lines[2]
    );
    assert!(lines[2].contains(",unstable,"));
}

#[test]
fn a_segment_is_clipped_to_the_reach_of_the_stock() {
    let (lo, hi) = ([0.0, 0.0, f64::NEG_INFINITY], [10.0, 10.0, 0.0]);
    let (a, b) = clip_line([-10.0, 5.0, -1.0], [30.0, 5.0, -1.0], lo, hi).unwrap();
    assert_eq!((a, b), ([0.0, 5.0, -1.0], [10.0, 5.0, -1.0]));
    // Above the top, beside the box, or parallel outside: nothing.
    assert!(clip_line([-10.0, 5.0, 1.0], [30.0, 5.0, 1.0], lo, hi).is_none());
    assert!(clip_line([-10.0, 20.0, -1.0], [30.0, 11.0, -1.0], lo, hi).is_none());
    // A plunge from above ends in the box: from the top down.
    let (a, b) = clip_line([5.0, 5.0, 50.0], [5.0, 5.0, -3.0], lo, hi).unwrap();
    assert_eq!((a[2], b[2]), (0.0, -3.0));
    // A move of a billion millimetres across the block costs no more than the block.
    let r = run("M3 S10000\nG0 X-999999999 Y20 Z-1\nG1 X999999999 F500\nM2").unwrap();
    assert!(r.samples < 1000, "{}", r.samples);
}
