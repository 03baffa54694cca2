//! G43.4 moves within the machine's axis limits: the planner slows the tool tip where the axes
//! would exceed their speed or acceleration limits (near the rotary singularity, where C swings
//! round while the tip barely moves), keeps the tip on the programmed path, and leaves moves
//! the axes can follow at the programmed feed.
//!
//! The axes' speeds and accelerations are measured from the planned setpoints alone (finite
//! differences of the commanded axes at the interpolation cycle), and the tip from the
//! closed-form forward kinematics of the B/C trunnion written here from the chain conventions
//! (as in `fiveaxis_tcp_kinematics.rs`), not the crate's transforms.

use vmc_machine::fiveaxis::plan::{plan_program, FivePlan};
use vmc_machine::fiveaxis::run::{commanded_points, Commanded, Sampling};
use vmc_machine::fiveaxis::tcp_timing::{LimitKind, Retimed};
use vmc_machine::fiveaxis::FiveAxisSpec;

type V = [f64; 3];

/// Interpolation cycle of the measurements, s.
const DT_S: f64 = 1e-3;

fn rot(axis: char, angle_deg: f64, v: V) -> V {
    let (s, c) = angle_deg.to_radians().sin_cos();
    match axis {
        'B' => [c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]],
        _ => [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]],
    }
}

/// Closed-form forward kinematics of `machines/trunnion-bc.toml` (C line through
/// (0, 0, −450), B line through (0, 0, −500), datum (150, 0, −350), tool 150 mm): the tip in
/// the part frame of work offset (−150, 0, −100) for axes `q`, `abc`.
fn tip(q: V, abc: V) -> V {
    let (b, c) = (abc[1], abc[2]);
    let p_t = [0.0, 0.0, -500.0];
    let bed = [q[0] - p_t[0], q[1] - p_t[1], q[2] - 150.0 - p_t[2]];
    let on_t = rot('B', b, bed);
    // About the C line, 50 mm above the B line; part zero (datum + offset) lies on it.
    rot('C', c, [on_t[0], on_t[1], on_t[2] - 50.0])
}

fn spec() -> FiveAxisSpec {
    FiveAxisSpec::from_toml_str(
        include_str!("../../../machines/trunnion-bc.toml"),
        "trunnion-bc.toml",
    )
    .unwrap()
}

/// Limits X, Y, Z, A, B, C of the machine file: speed (mm/s, deg/s), acceleration.
const VEL: [f64; 6] = [500.0, 500.0, 500.0, f64::INFINITY, 90.0, 180.0];
const ACC: [f64; 6] = [3000.0, 3000.0, 3000.0, f64::INFINITY, 360.0, 720.0];

fn joints(p: &Commanded) -> [f64; 6] {
    [
        p.q_mm[0],
        p.q_mm[1],
        p.q_mm[2],
        p.abc_deg[0],
        p.abc_deg[1],
        p.abc_deg[2],
    ]
}

/// The largest speed and acceleration of each axis over the setpoints of `line`, as fractions
/// of its limits (finite differences at the interpolation cycle).
fn peak_ratios(points: &[Commanded], line: usize) -> ([f64; 6], [f64; 6]) {
    let q: Vec<[f64; 6]> = points
        .iter()
        .filter(|p| !p.at_dwell && p.line == line)
        .map(joints)
        .collect();
    assert!(q.len() > 50, "line {line}: {} setpoints", q.len());
    let (mut vel, mut acc) = ([0.0f64; 6], [0.0f64; 6]);
    for w in q.windows(3) {
        for j in 0..6 {
            let v = (w[1][j] - w[0][j]) / DT_S;
            let a = (w[2][j] - 2.0 * w[1][j] + w[0][j]) / (DT_S * DT_S);
            vel[j] = vel[j].max(v.abs() / VEL[j]);
            acc[j] = acc[j].max(a.abs() / ACC[j]);
        }
    }
    (vel, acc)
}

fn plan(program: &str) -> FivePlan {
    plan_program(program, "t.ngc", &spec(), "trunnion-bc.toml").unwrap()
}

/// `plan` at the programmed timing: the retiming dropped (the planner's timing before it).
fn programmed(plan: &FivePlan) -> FivePlan {
    let mut p = plan.clone();
    for piece in &mut p.pieces {
        piece.timing = None;
    }
    p
}

/// The retiming of the move of `line` (piece index, segment index, retiming).
fn retimed(plan: &FivePlan, line: usize) -> (usize, usize, Option<Retimed>) {
    for (k, piece) in plan.pieces.iter().enumerate() {
        if let Some(i) = piece.plan.segments().iter().position(|s| s.line == line) {
            let r = piece.timing.as_ref().and_then(|t| t.retimed[i].clone());
            return (k, i, r);
        }
    }
    panic!("no move on line {line}");
}

/// The tip 200 mm from the C axis while B passes through 0 (the singularity) and C swings
/// half a turn along 10 mm of path: at the programmed timing (C at its own 180 deg/s) X and Y
/// would run at 200·π ≈ 630 mm/s, above their 500 mm/s.
const THROUGH_SINGULARITY: &str = "G10 L2 P1 X-150 Y0 Z-100
G43.4 H1
G0 X200 Y0 Z30 B-3 C0
G4 P0.1
G1 X200 Y10 Z30 B3 C180 F3000
G4 P0.1
G49
M2
";

#[test]
fn a_g43_4_move_through_the_singularity_is_slowed_within_every_axis_limit() {
    let plan = plan(THROUGH_SINGULARITY);
    let points = commanded_points(&plan, Sampling::EveryCycle(DT_S));
    let (vel, acc) = peak_ratios(&points, 5);
    // Speeds within 1 % (sampling of the path at 0.1 mm); accelerations, second differences
    // of the setpoints at 1 ms, within 5 %.
    for j in 0..6 {
        assert!(vel[j] <= 1.01, "axis {j}: speed {:.4} of its limit", vel[j]);
        assert!(
            acc[j] <= 1.05,
            "axis {j}: acceleration {:.4} of its limit",
            acc[j]
        );
    }
    // The limit binds: the fastest linear axis runs at its speed limit.
    assert!(vel[0].max(vel[1]) > 0.97, "{vel:?}");
    // At the programmed timing it ran a quarter beyond it.
    let before = commanded_points(&programmed(&plan), Sampling::EveryCycle(DT_S));
    let (vel_before, _) = peak_ratios(&before, 5);
    assert!(vel_before[0].max(vel_before[1]) > 1.2, "{vel_before:?}");

    let (k, i, r) = retimed(&plan, 5);
    let r = r.expect("the move was slowed");
    assert!(
        matches!(r.binding, ('X' | 'Y', LimitKind::Velocity)),
        "{:?}",
        r.binding
    );
    // 500 mm/s over about 630 mm/s.
    assert!(
        r.slowest_ratio > 0.7 && r.slowest_ratio < 0.85,
        "{}",
        r.slowest_ratio
    );
    // Longer than at the programmed timing (slowed over the part of the move near C 90°).
    let piece = &plan.pieces[k];
    let programmed_s = piece.plan.segments()[i].duration_s;
    assert_eq!(r.programmed_s, programmed_s);
    let retimed_s = piece.segment_duration_s(i);
    assert!(
        retimed_s > 1.05 * programmed_s,
        "{retimed_s} vs {programmed_s}"
    );
    let report = plan.tcp_limits().expect("a report");
    assert_eq!(report.slowest_line, 5);
    assert!(report.slowest_ratio <= r.slowest_ratio);
    assert!(report.added_s >= piece.segment_duration_s(i) - programmed_s);
    let programmed_total_s: f64 = plan.pieces.iter().map(|p| p.plan.duration_s()).sum();
    assert!((plan.duration_s() - programmed_total_s - report.added_s).abs() < 1e-9);
}

#[test]
fn the_slowed_move_keeps_the_tip_on_the_programmed_line() {
    let plan = plan(THROUGH_SINGULARITY);
    let points = commanded_points(&plan, Sampling::EveryCycle(DT_S));
    let moving: Vec<_> = points
        .iter()
        .filter(|p| !p.at_dwell && p.line == 5)
        .collect();
    assert!(moving.len() > 100);
    let mut last_f = 0.0;
    for p in moving {
        // The fraction of the move from C (0 → 180), the tip where the line puts it then.
        let f = p.abc_deg[2] / 180.0;
        assert!(f >= last_f - 1e-12, "the tip goes back at {f}");
        last_f = f;
        assert!((p.abc_deg[1] - (-3.0 + 6.0 * f)).abs() < 1e-9);
        let want = [200.0, 10.0 * f, 30.0];
        let got = tip(p.q_mm, p.abc_deg);
        for i in 0..3 {
            assert!(
                (got[i] - want[i]).abs() < 1e-9,
                "{got:?} vs {want:?} at f = {f}"
            );
        }
    }
}

#[test]
fn a_g43_4_move_the_axes_can_follow_keeps_the_programmed_feed() {
    // B tilted 30–40° (far from the singularity), C turning 10°, the tip 40 mm from the C axis.
    let program = "G10 L2 P1 X-150 Y0 Z-100
G43.4 H1
G0 X-40 Y30 Z45 B-30 C0
G4 P0.1
G1 X-40 Y-30 Z45 B-40 C10 F1500
G4 P0.1
G49
M2
";
    let plan = plan(program);
    let (k, i, r) = retimed(&plan, 5);
    assert_eq!(r, None);
    let piece = &plan.pieces[k];
    let seg = &piece.plan.segments()[i];
    assert_eq!(piece.segment_duration_s(i), seg.duration_s);
    // 60 mm at 25 mm/s: the programmed feed is reached and held.
    assert!((seg.profile.v_peak_mm_per_s - 25.0).abs() < 1e-12);
    let points = commanded_points(&plan, Sampling::EveryCycle(DT_S));
    let (vel, acc) = peak_ratios(&points, 5);
    // B accelerates at its own limit (the planner's cap of the programmed profile).
    assert!(
        vel.iter().chain(&acc).all(|r| *r < 1.0 + 1e-6),
        "{vel:?} {acc:?}"
    );
}

#[test]
fn a_rotary_turn_alone_under_g43_4_is_slowed_for_the_linear_axes() {
    // The tip stays on a point 200 mm from the C axis while C turns at its full 180 deg/s
    // (F10800 deg/min): X and Y would circle at 630 mm/s.
    let program = "G10 L2 P1 X-150 Y0 Z-100
G43.4 H1
G0 X200 Y0 Z30 B-20 C0
G1 C120 F10800
G4 P0.1
G49
M2
";
    let plan = plan(program);
    let (k, i, r) = retimed(&plan, 4);
    let r = r.expect("slowed");
    assert!(
        matches!(r.binding, ('X' | 'Y', LimitKind::Velocity)),
        "{:?}",
        r.binding
    );
    let retimed_s = plan.pieces[k].segment_duration_s(i);
    assert!(
        retimed_s > 1.03 * r.programmed_s,
        "{retimed_s} vs {}",
        r.programmed_s
    );
    let points = commanded_points(&plan, Sampling::EveryCycle(DT_S));
    let (vel, acc) = peak_ratios(&points, 4);
    for j in 0..6 {
        assert!(
            vel[j] <= 1.01 && acc[j] <= 1.05,
            "axis {j}: {vel:?} {acc:?}"
        );
    }
    let (vel_before, _) = peak_ratios(
        &commanded_points(&programmed(&plan), Sampling::EveryCycle(DT_S)),
        4,
    );
    assert!(vel_before[0] > 1.1, "{vel_before:?}");
    // X and Y bind in turn (each at its 500 mm/s where it moves fastest: C near 0 and 90°).
    assert!(vel[0] > 0.97 && vel[1] > 0.97, "{vel:?}");
    for p in points.iter().filter(|p| p.line == 4) {
        let got = tip(p.q_mm, p.abc_deg);
        for (g, w) in got.iter().zip([200.0, 0.0, 30.0]) {
            assert!((g - w).abs() < 1e-9, "{got:?}");
        }
    }
}
