//! Tests of the probe moves G38.2 … G38.5: the checks (LinuxCNC's messages, taken from
//! `rs274` on the same programs), the parameters #5061…#5070, the stand-alone convention and
//! results given from outside.

use super::*;
use crate::syntax::{parse_line, Block};

/// The machine points of the moves (traverses, feeds, probes) of a stand-alone run.
fn points(src: &str) -> Vec<[f64; 3]> {
    points_cfg(src, &InterpConfig::default())
}

fn points_cfg(src: &str, cfg: &InterpConfig) -> Vec<[f64; 3]> {
    run_program(src, cfg)
        .unwrap_or_else(|e| panic!("{src}: {e}"))
        .into_iter()
        .filter_map(|m| match m.kind {
            CanonKind::Traverse { end_mm, .. }
            | CanonKind::Feed { end_mm, .. }
            | CanonKind::Probe { end_mm, .. } => Some(end_mm),
            _ => None,
        })
        .collect()
}

fn err(src: &str) -> GcodeError {
    run_program(src, &InterpConfig::default()).expect_err("program must be rejected")
}

/// Work offsets with G54 at `offset_mm`, the others at 0.
fn g54(offset_mm: [f64; 3]) -> [[f64; 3]; WORK_OFFSETS] {
    let mut all = [[0.0; 3]; WORK_OFFSETS];
    all[0] = offset_mm;
    all
}

fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
    (0..3).all(|i| (a[i] - b[i]).abs() <= tol)
}

/// Runs `src` giving every probe move the outcome `f(request)`; the moves and the error.
fn run_with(
    src: &str,
    cfg: &InterpConfig,
    f: impl Fn(&ProbeRequest) -> ProbeOutcome,
) -> (Vec<CanonMove>, Result<(), GcodeError>) {
    let mut out = Vec::new();
    let result = (|| {
        let mut run = ProgramRun::new(src, cfg)?;
        while let RunEvent::Probe(r) = run.resume(&mut out)? {
            run.probe_result(f(&r))?;
        }
        Ok(())
    })();
    (out, result)
}

/// Tripped at `trip` (program = machine coordinates here), at rest there.
fn tripped_at(trip_mm: [f64; 3]) -> impl Fn(&ProbeRequest) -> ProbeOutcome {
    move |r| ProbeOutcome::Tripped {
        trip_mm,
        trip_abc_deg: r.end_abc_deg,
        rest_mm: trip_mm,
        rest_abc_deg: r.end_abc_deg,
    }
}

#[test]
fn a_probe_move_is_a_canonical_move_with_its_kind_and_feed() {
    let moves = run_program("G21 G38.3 X5 Z-2 F10\nM2", &InterpConfig::default()).unwrap();
    assert_eq!(
        moves[0].kind,
        CanonKind::Probe {
            end_mm: [5.0, 0.0, -2.0],
            end_abc_deg: [0.0; 3],
            feed_mm_per_min: 10.0,
            kind: ProbeKind {
                toward: true,
                error_on_no_contact: false
            },
        }
    );
    // Modal in group 1: the next block with axis words probes again (rs274 does).
    let p = points("G38.2 Z-1 F10\nZ-2\nM2");
    assert_eq!(p, vec![[0.0, 0.0, -1.0], [0.0, 0.0, -2.0]]);
}

#[test]
fn standalone_the_tool_rests_a_hundredth_of_an_inch_back_from_the_target() {
    // rs274: `G38.2 Z-2 X5 F10` then `G1 Y1` → STRAIGHT_FEED(4.7642, 1.0000, -1.9057);
    // `G38.2 Z-1 F10` then `G91 G1 X1` → STRAIGHT_FEED(1.0000, 0.0000, -0.7460).
    let p = points("G38.2 Z-2 X5 F10\nG1 Y1\nM2");
    assert!(close(p[1], [4.7642, 1.0, -1.9057], 5e-5), "{p:?}");
    let p = points("G38.2 Z-1 F10\nG91 G1 X1\nM2");
    assert!(close(p[1], [1.0, 0.0, -0.746], 1e-12), "{p:?}");
    // The same physical 0.254 mm in inches: `G20 G38.2 Z-2 X5 F10`, `G1 Y1` → (4.9907, 1,
    // -1.9963) inches.
    let p = points("G20 G38.2 Z-2 X5 F10\nG1 Y1\nM2");
    assert!(
        close(p[1], [4.9907 * 25.4, 25.4, -1.9963 * 25.4], 5e-5 * 25.4),
        "{p:?}"
    );
}

#[test]
fn standalone_parameters_hold_the_target_in_work_coordinates_and_5070_is_0() {
    // rs274 prints #5061…#5064 = 2 3 -1 10 and #5070 = 0 after this probe.
    let src = "G10 L2 P1 X10 Y20 Z30 A5\nG92 X1 Y1 Z1\nG38.2 X2 Y3 Z-1 A10 F10\n\
               G53 G0 X#5061 Y#5062 Z#5063 A#5064\nG53 G0 X#5070 Y#5065 Z#5069\nM2";
    let p = points(src);
    assert!(close(p[1], [2.0, 3.0, -1.0], 1e-12), "{p:?}");
    assert_eq!(p[2], [0.0, 0.0, 0.0]);
    // In inches, with the tool length removed too (rs274: 2 3 -1 with T1 M6 G43).
    let cfg = InterpConfig {
        tool_lengths_mm: vec![(1, 150.0)],
        ..InterpConfig::default()
    };
    let p = points_cfg(
        "G20 T1 M6 G43\nG38.2 X2 Y3 Z-1 F10\nG21 G53 G0 X#5061 Y#5062 Z#5063\nM2",
        &cfg,
    );
    assert!(close(p[1], [2.0, 3.0, -1.0], 1e-12), "{p:?}");
}

#[test]
fn probes_are_refused_where_linuxcnc_refuses_them() {
    for (src, line, msg) in [
        ("G38.2 Z-1", 1, "Cannot probe with zero feed rate"),
        ("G38.2 Z0", 1, "Cannot probe with zero feed rate"),
        (
            "G94 F10\nG95\nG94\nG38.2 Z-1",
            4,
            "Cannot probe with zero feed rate",
        ),
        (
            "G41 D1 G38.2 Z-1 F10",
            1,
            "Cannot probe with cutter radius comp on",
        ),
        (
            "S100 M3 G95 G38.2 Z-1 F1",
            1,
            "Cannot probe with feed per rev mode",
        ),
        ("G38.2 Z0 F10", 1, "Start point too close to probe point"),
        ("G38.4 Z0 F10", 1, "Start point too close to probe point"),
        (
            "G0 A10\nG38.2 Z0 A10 F10",
            2,
            "Start point too close to probe point",
        ),
        (
            "G38.2 Z-1 F10\nG38.4 Z-0.746",
            2,
            "Start point too close to probe point",
        ),
        ("G38.2 F10", 1, "G38.2 needs an axis word"),
        ("G53 G38.2 Z-1 F10", 1, "G53 needs G0 or G1"),
        ("G38.2 G28 Z-1 F10", 1, "both use the axis words"),
        ("F10 G38.6 Z-1", 1, "unknown code G38.6"),
    ] {
        let e = err(src);
        assert_eq!(
            (e.line, e.kind),
            (line, GcodeErrorKind::Invalid),
            "{src:?}: {e}"
        );
        assert!(e.msg.contains(msg), "{src:?}: {e}");
    }
    // LinuxCNC runs it at the feed of the last inverse-time move: not modelled.
    assert!(err("G94 F10\nG93 G38.2 Z-1 F1").is_unsupported());
}

#[test]
fn a_probe_of_no_length_in_a_rotated_frame_stays_of_no_length() {
    // rs274: "Start point too close to probe point"; `G91 G38.3 Z0` then `G91 G1 X1` →
    // STRAIGHT_FEED(2.1, 2.3, 3): no back-off, whatever the rounding of the rotation.
    let rotated = "G10 L2 P1 X10 Y20 R30\nG0 X1.1 Y2.3 Z3\n";
    let e = err(&format!("{rotated}G38.2 Z3 F10\nM2"));
    assert_eq!(
        (e.line, e.msg.as_str()),
        (3, "Start point too close to probe point")
    );
    let p = points(&format!("{rotated}G91 G38.3 Z0 F10\nG91 G1 X1\nM2"));
    let (sin, cos) = 30f64.to_radians().sin_cos();
    let expected = [
        10.0 + 2.1 * cos - 2.3 * sin,
        20.0 + 2.1 * sin + 2.3 * cos,
        3.0,
    ];
    assert!(close(p[2], expected, 1e-9), "{p:?}");
}

#[test]
fn g38_3_and_g38_5_accept_a_move_of_no_length_and_a_rotary_probe_feeds_in_degrees() {
    assert_eq!(points("G38.3 Z0 F10\nG38.5 Z0\nM2").len(), 2);
    let mut run = ProgramRun::new("G20\nG38.3 A10 F10\nM2", &InterpConfig::default()).unwrap();
    let mut moves = Vec::new();
    let RunEvent::Probe(request) = run.resume(&mut moves).unwrap() else {
        panic!("a probe move")
    };
    assert!(
        (request.feed_mm_per_min - 10.0).abs() < 1e-12,
        "{request:?}"
    );
    assert!(
        matches!(
            moves[0].kind,
            CanonKind::Probe { feed_mm_per_min, end_abc_deg: [a, ..], .. }
                if (feed_mm_per_min - 10.0).abs() < 1e-12 && a == 10.0
        ),
        "{:?}",
        moves[0]
    );
}

#[test]
fn after_g40_the_probe_leaves_from_the_compensated_point() {
    // rs274 with a Ø12 mm T1: the probe goes to (20, 0, -1), the next move to
    // (30, 0.2505, -0.9582): the rest point backs off toward (20, 6, 0), where the tool was.
    let cfg = InterpConfig {
        tool_diameters_mm: vec![(1, 12.0)],
        ..InterpConfig::default()
    };
    let src = "T1 M6\nG41 G1 X10 Y0 F10\nX20\nG40\nG38.2 Z-1\nG1 X30\nM2";
    let p = points_cfg(src, &cfg);
    assert_eq!(p[2], [20.0, 0.0, -1.0]);
    assert!(close(p[3], [30.0, 0.2505, -0.9582], 5e-5), "{p:?}");
}

#[test]
fn a_tripped_probe_sets_the_trip_point_and_5070_and_the_tool_goes_on_from_rest() {
    let cfg = InterpConfig {
        work_offsets_mm: g54([100.0, 0.0, 10.0]),
        ..InterpConfig::default()
    };
    // Program Z-2.5 is machine Z 7.5; the tool stops 0.2 mm lower.
    let outcome = |r: &ProbeRequest| ProbeOutcome::Tripped {
        trip_mm: [100.0, 0.0, 7.5],
        trip_abc_deg: r.end_abc_deg,
        rest_mm: [100.0, 0.0, 7.3],
        rest_abc_deg: r.end_abc_deg,
    };
    let src = "G38.2 X0 Z-10 F50\nG0 X#5070 Y#5063\nG38.2 X0 Z-10\nG91 G1 Y1\nM2";
    let (moves, result) = run_with(src, &cfg, outcome);
    result.unwrap();
    let ends: Vec<[f64; 3]> = moves
        .iter()
        .filter_map(|m| match m.kind {
            CanonKind::Traverse { end_mm, .. } | CanonKind::Feed { end_mm, .. } => Some(end_mm),
            _ => None,
        })
        .collect();
    // #5070 = 1, #5063 = -2.5 (work coordinates); G91 from the rest point.
    assert!(close(ends[0], [101.0, -2.5, 7.3], 1e-12), "{ends:?}");
    assert!(close(ends[1], [100.0, 1.0, 7.3], 1e-12), "{ends:?}");
}

#[test]
fn without_contact_g38_2_and_g38_4_fail_and_g38_3_sets_5070_to_0() {
    let cfg = InterpConfig::default();
    for (src, msg) in [
        (
            "G0 Z5\nG38.2 Z-1 F10\nM2",
            "G38.2 move finished without making contact.",
        ),
        (
            "G0 Z5\nG38.4 Z-1 F10\nM2",
            "G38.4 move finished without breaking contact.",
        ),
    ] {
        let (_, result) = run_with(src, &cfg, |_| ProbeOutcome::NoContact);
        let e = result.unwrap_err();
        assert_eq!((e.line, e.col, e.msg.as_str()), (2, 1, msg), "{src}");
    }
    let src = "G38.3 X4 Z-1 F10\nG0 X#5061 Y#5070 Z#5063\nM2";
    let (moves, result) = run_with(src, &cfg, |_| ProbeOutcome::NoContact);
    result.unwrap();
    assert!(matches!(
        moves[1].kind,
        CanonKind::Traverse {
            end_mm: [4.0, 0.0, -1.0],
            ..
        }
    ));
    // A result that is not a point is refused, not used.
    let (_, result) = run_with(src, &cfg, tripped_at([f64::NAN, 0.0, 0.0]));
    assert!(result.unwrap_err().msg.contains("not a finite point"));
}

#[test]
fn a_probe_in_a_block_with_m2_ends_the_program_after_its_result() {
    let (moves, result) = run_with("G38.3 Z-1 F10 M2\nG0 X5", &InterpConfig::default(), |_| {
        ProbeOutcome::NoContact
    });
    result.unwrap();
    assert_eq!(moves.len(), 2);
    assert_eq!(moves[1].kind, CanonKind::ProgramEnd);
}

#[test]
fn the_caller_must_give_each_probe_its_result_before_going_on() {
    let mut run = ProgramRun::new("G38.2 Z-1 F10\nG0 X1\nM2", &InterpConfig::default()).unwrap();
    let mut out = Vec::new();
    assert!(run.probe_result(ProbeOutcome::NoContact).is_err());
    let RunEvent::Probe(r) = run.resume(&mut out).unwrap() else {
        panic!("the probe move stops the run")
    };
    assert_eq!(
        (r.line, r.start_mm, r.end_mm),
        (1, [0.0; 3], [0.0, 0.0, -1.0])
    );
    assert!(run.resume(&mut out).is_err(), "resumed without the result");
    run.probe_result(tripped_at([0.0, 0.0, -0.5])(&r)).unwrap();
    assert_eq!(run.resume(&mut out).unwrap(), RunEvent::Ended);
    assert_eq!(run.resume(&mut out).unwrap(), RunEvent::Ended);
    assert_eq!(out.len(), 3);

    // The same contract block by block.
    let block = |s: &str| Block::from_literal_line(&parse_line(1, s).unwrap().unwrap()).unwrap();
    let mut it = Interpreter::new(InterpConfig::default());
    let mut out = Vec::new();
    let request = it.execute_block(&block("G38.3 Z-1 F10"), &mut out).unwrap();
    assert_eq!(request, it.pending_probe());
    assert!(request.is_some());
    assert!(it.execute_block(&block("G0 X1"), &mut out).is_err());
    let params = it.probe_result(ProbeOutcome::NoContact).unwrap();
    assert_eq!(params, [0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    assert_eq!(it.position_mm(), [0.0, 0.0, -1.0]);
    assert_eq!(it.execute_block(&block("G0 X1"), &mut out).unwrap(), None);
    assert!(it.probe_result(ProbeOutcome::NoContact).is_err());
}

#[test]
fn straight_probe_reads_as_rs274_prints_it() {
    assert_eq!(
        straight_probe_call([0.0, 0.0, -1.0], [10.0, 0.0, 0.0]),
        "STRAIGHT_PROBE(0.0000, 0.0000, -1.0000, 10.0000, 0.0000, 0.0000)"
    );
}

#[test]
fn a_probe_already_in_the_state_it_seeks_is_refused_by_g38_2_and_g38_4_and_trips_at_once_otherwise()
{
    let cfg = InterpConfig::default();
    for (src, msg) in [
        (
            "G0 Z5\nG38.2 Z-1 F10\nM2",
            "Probe is already tripped when starting G38.2 or G38.3 move",
        ),
        (
            "G0 Z5\nG38.4 Z-1 F10\nM2",
            "Probe is already clear when starting G38.4 or G38.5 move",
        ),
    ] {
        let (_, result) = run_with(src, &cfg, |_| ProbeOutcome::AlreadyInState);
        let e = result.unwrap_err();
        assert_eq!((e.line, e.col, e.msg.as_str()), (2, 1, msg), "{src}");
    }
    // G38.3 / G38.5: #5061… the start point (work coordinates: G54 at X100 here), #5070 = 1,
    // and the tool goes on from the start.
    let cfg = InterpConfig {
        work_offsets_mm: g54([100.0, 0.0, 0.0]),
        ..InterpConfig::default()
    };
    for code in ["G38.3", "G38.5"] {
        let src = format!("G0 X2 Z5\n{code} Z-1 F10\nG0 X#5061 Y#5070 Z#5063\nG91 G1 X1\nM2");
        let (moves, result) = run_with(&src, &cfg, |_| ProbeOutcome::AlreadyInState);
        result.unwrap();
        let ends: Vec<[f64; 3]> = moves
            .iter()
            .filter_map(|m| match m.kind {
                CanonKind::Traverse { end_mm, .. } | CanonKind::Feed { end_mm, .. } => Some(end_mm),
                _ => None,
            })
            .collect();
        assert_eq!(ends[1], [102.0, 1.0, 5.0], "{code}: {ends:?}");
        assert_eq!(ends[2], [103.0, 1.0, 5.0], "{code}: {ends:?}");
    }
}

#[test]
fn the_current_point_and_tool_read_in_work_coordinates_and_program_units_as_in_linuxcnc() {
    // rs274 (T1 Ø12 mm × 150 mm): the second traverse goes to program (1.5, 0.5, 1.4724)
    // A11, the feed to X5.9055 — #5420 + #5400, #<_y> · 2, #5422 + #5410, #<_a> +
    // #<_current_tool>, #5403, all in inches in the G54 frame.
    let cfg = InterpConfig {
        tool_lengths_mm: vec![(1, 150.0)],
        tool_diameters_mm: vec![(1, 12.0)],
        ..InterpConfig::default()
    };
    let src = "G20\nG10 L2 P1 X1 Y2 Z3\nT1 M6\nG43\nG0 X0.5 Y0.25 Z1 A10\n\
               G0 X[#5420 + #5400] Y[#<_y> * 2] Z[#5422 + #5410] A[#<_a> + #<_current_tool>]\n\
               G1 X#5403 F10\nM2";
    let moves: Vec<CanonKind> = run_program(src, &cfg)
        .unwrap()
        .into_iter()
        .map(|m| m.kind)
        .filter(|k| matches!(k, CanonKind::Traverse { .. } | CanonKind::Feed { .. }))
        .collect();
    let machine = |p: [f64; 3]| [p[0] + 1.0, p[1] + 2.0, p[2] + 3.0].map(|v| v * 25.4);
    let mut second = machine([1.5, 0.5, 1.0 + 12.0 / 25.4]);
    second[2] += 150.0;
    let mut feed = second;
    feed[0] = machine([150.0 / 25.4, 0.0, 0.0])[0];
    match (&moves[1], &moves[2]) {
        (
            CanonKind::Traverse {
                end_mm,
                end_abc_deg,
            },
            CanonKind::Feed { end_mm: f, .. },
        ) => {
            assert!(close(*end_mm, second, 1e-9), "{end_mm:?} {second:?}");
            assert_eq!(end_abc_deg[0], 11.0);
            assert!(close(*f, feed, 1e-9), "{f:?} {feed:?}");
        }
        other => panic!("{other:?}"),
    }
}
