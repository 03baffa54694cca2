//! The planner with rotary axes: durations against the closed form of the trapezoidal
//! profile `T = L/v + v/a` (when the cruise speed is reached), the angles in step with the
//! path, every axis within its limits, and the 3-axis machine untouched.

use super::*;

/// 1 ns, s.
const NS: f64 = 1e-9;

fn mv(line: usize, kind: CanonKind) -> CanonMove {
    CanonMove { line, kind }
}

fn feed(line: usize, end_mm: [f64; 3], end_abc_deg: [f64; 3], f: f64) -> CanonMove {
    mv(
        line,
        CanonKind::Feed {
            end_mm,
            end_abc_deg,
            feed_mm_per_min: f,
        },
    )
}

fn rapid(line: usize, end_mm: [f64; 3], end_abc_deg: [f64; 3]) -> CanonMove {
    mv(
        line,
        CanonKind::Traverse {
            end_mm,
            end_abc_deg,
        },
    )
}

/// A trunnion: A and C at 180 deg/s, 720 deg/s²; no B.
fn trunnion() -> RotaryLimits {
    let axis = RotaryAxisLimits {
        max_speed_deg_per_s: 180.0,
        max_accel_deg_per_s2: 720.0,
    };
    RotaryLimits {
        axes: [Some(axis), None, Some(axis)],
    }
}

fn plan_5x(moves: &[CanonMove]) -> Plan {
    plan_with_rotary(
        moves,
        [0.0; 3],
        [0.0; 3],
        &MotionLimits::default(),
        &trunnion(),
    )
    .expect("plan")
}

/// Closed-form duration of a trapezoid of length `l` at speed `v`, acceleration `a`.
fn trapezoid_s(l: f64, v: f64, a: f64) -> f64 {
    assert!(l >= v * v / a, "the cruise speed is reached");
    l / v + v / a
}

#[test]
fn a_pure_rotary_feed_takes_its_angle_over_the_feed_in_degrees_per_minute() {
    // A 0 → 90° at F1800 deg/min = 30 deg/s.
    let p = plan_5x(&[feed(1, [0.0; 3], [90.0, 0.0, 0.0], 1800.0)]);
    let want = trapezoid_s(90.0, 30.0, 720.0);
    assert!((p.duration_s() - want).abs() < NS, "{}", p.duration_s());
    // X, Y, Z stay; A ends at 90.
    assert_eq!(p.position_at(1.0), [0.0; 3]);
    assert_eq!(p.abc_at(p.duration_s()), [90.0, 0.0, 0.0]);
}

#[test]
fn a_combined_xyz_and_a_move_is_timed_by_its_xyz_length_and_turns_in_step() {
    // X 0 → 100 mm at F600 (10 mm/s, X accel 2000 mm/s²); A turns 10° (0.1°/mm: far within
    // its limits).
    let p = plan_5x(&[feed(1, [100.0, 0.0, 0.0], [10.0, 0.0, 0.0], 600.0)]);
    let want = trapezoid_s(100.0, 10.0, 2000.0);
    assert!((p.duration_s() - want).abs() < NS);
    // The profile is symmetric: halfway in time is halfway along X and A.
    let half = p.duration_s() / 2.0;
    assert!((p.position_at(half)[0] - 50.0).abs() < 1e-9);
    assert!((p.abc_at(half)[0] - 5.0).abs() < 1e-9);
}

#[test]
fn rotary_speed_and_acceleration_limits_cap_rapids_and_combined_feeds() {
    // A rapid A 0 → 360°: at 180 deg/s, 720 deg/s².
    let p = plan_5x(&[rapid(1, [0.0; 3], [360.0, 0.0, 0.0])]);
    assert!((p.duration_s() - trapezoid_s(360.0, 180.0, 720.0)).abs() < NS);
    // X 10 mm with A 360° at F6000 (100 mm/s): 36°/mm caps X at 180/36 = 5 mm/s and
    // 720/36 = 20 mm/s².
    let p = plan_5x(&[feed(1, [10.0, 0.0, 0.0], [360.0, 0.0, 0.0], 6000.0)]);
    assert!((p.duration_s() - trapezoid_s(10.0, 5.0, 20.0)).abs() < NS);
    // A and C together (Θ = 50°): C turns 40/50 of the angle, so the angle rate is capped at
    // 180·50/40 = 225 deg/s; the requested 300 deg/s is not reached.
    let p = plan_5x(&[feed(1, [0.0; 3], [30.0, 0.0, 40.0], 18_000.0)]);
    let seg = &p.segments()[0];
    assert!((seg.profile.v_limit_mm_per_s - 225.0).abs() < 1e-9);
    assert!((seg.profile.accel_mm_per_s2 - 900.0).abs() < 1e-9);
}

#[test]
fn sampled_angular_speeds_stay_within_every_axis_limit() {
    let moves = [
        rapid(1, [0.0; 3], [200.0, 0.0, -90.0]),
        feed(2, [50.0, 0.0, 0.0], [-100.0, 0.0, 0.0], 3000.0),
        feed(3, [50.0, 0.0, 0.0], [-40.0, 0.0, 45.0], 50_000.0),
    ];
    let p = plan_5x(&moves);
    let dt = 1e-4;
    let n = (p.duration_s() / dt) as usize;
    let mut prev = p.abc_at(0.0);
    for k in 1..=n {
        let now = p.abc_at(k as f64 * dt);
        for axis in [0, 2] {
            let speed = (now[axis] - prev[axis]).abs() / dt;
            // The mean speed over one step never exceeds the cap (+1e-6 of rounding).
            assert!(
                speed <= 180.0 * (1.0 + 1e-6),
                "axis {axis} at {speed} deg/s"
            );
        }
        prev = now;
    }
    assert_eq!(p.abc_at(p.duration_s() + 1.0), [-40.0, 0.0, 45.0]);
}

#[test]
fn a_machine_without_the_axis_refuses_the_move_naming_line_and_axis() {
    let moves = [
        feed(1, [10.0, 0.0, 0.0], [0.0; 3], 600.0),
        feed(2, [10.0, 0.0, 0.0], [3.0, 5.0, 0.0], 600.0),
    ];
    let err = plan(&moves, [0.0; 3], &MotionLimits::default()).unwrap_err();
    assert_eq!(err, MotionError::NoRotaryAxis { line: 2, axis: 'A' });
    // The trunnion has no B.
    let err = plan_with_rotary(
        &moves,
        [0.0; 3],
        [0.0; 3],
        &MotionLimits::default(),
        &trunnion(),
    )
    .unwrap_err();
    assert_eq!(err, MotionError::NoRotaryAxis { line: 2, axis: 'B' });
}

#[test]
fn moves_that_do_not_turn_rotary_axes_plan_exactly_as_on_a_three_axis_machine() {
    let moves = [
        rapid(1, [10.0, 20.0, 5.0], [0.0; 3]),
        feed(2, [40.0, -20.0, 0.0], [0.0; 3], 1200.0),
        mv(
            3,
            CanonKind::Arc {
                end_mm: [60.0, 0.0, 3.0],
                end_abc_deg: [0.0; 3],
                center_mm: [50.0, -10.0, 0.0],
                plane: vmc_gcode::interp::Plane::Xy,
                clockwise: false,
                extra_turns: 1,
                feed_mm_per_min: 800.0,
            },
        ),
    ];
    let three_axis = plan(&moves, [0.0; 3], &MotionLimits::default()).unwrap();
    assert_eq!(plan_5x(&moves), three_axis);
}

#[test]
fn invalid_rotary_limits_are_named() {
    let mut limits = trunnion();
    limits.axes[2] = Some(RotaryAxisLimits {
        max_speed_deg_per_s: 90.0,
        max_accel_deg_per_s2: -1.0,
    });
    match limits.validate() {
        Err(MotionError::InvalidLimit { field, .. }) => {
            assert_eq!(field, "rotary.C.max_accel_deg_per_s2")
        }
        other => panic!("expected InvalidLimit, got {other:?}"),
    }
}

#[test]
fn a_move_beyond_a_rotary_travel_limit_is_refused_with_its_line_and_the_angle() {
    let plan = plan_5x(&[
        rapid(1, [0.0; 3], [-30.0, 0.0, 90.0]),
        feed(2, [0.0; 3], [-120.0, 0.0, 90.0], 3600.0),
    ]);
    let travel = [Some((-110.0, 30.0)), None, Some((0.0, 360.0))];
    let err = check_rotary_travel(&plan, &travel).unwrap_err();
    assert_eq!(
        err,
        MotionError::RotaryOutOfTravel {
            line: 2,
            axis: 'A',
            angle_deg: -120.0,
            min_deg: -110.0,
            max_deg: 30.0
        }
    );
    assert!(err
        .to_string()
        .contains("line 2: rotary axis A reaches -120°"));
    // At the limit exactly is inside.
    let at_limit = plan_5x(&[rapid(1, [0.0; 3], [-110.0, 0.0, 360.0])]);
    assert!(check_rotary_travel(&at_limit, &travel).is_ok());
}
