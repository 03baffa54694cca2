//! The retiming against closed forms: with the part frame parallel to the bed (B = C = 0 on a
//! trunnion) X, Y, Z follow the tip one for one, so a limit on X alone must give the trapezoid
//! of [`SpeedProfile`] at that limit.

use super::*;
use crate::motion::{plan, SpeedProfile};
use vmc_gcode::interp::{CanonKind, CanonMove};

/// The axes one for one with the tip, shifted (B = C = 0 on a trunnion).
fn parallel(p_mm: [f64; 3], _abc_deg: [f64; 3]) -> [f64; 3] {
    [p_mm[0] - 150.0, p_mm[1], p_mm[2] - 250.0]
}

/// A 100 mm move along X at F1500 (25 mm/s), planned with the default limits.
fn x_move() -> Segment {
    let mv = CanonMove {
        line: 4,
        kind: CanonKind::Feed {
            end_mm: [50.0, 0.0, 50.0],
            end_abc_deg: [0.0; 3],
            feed_mm_per_min: 1500.0,
        },
    };
    let limits = MotionLimits::default();
    let p = plan(&[mv], [-50.0, 0.0, 50.0], &limits).unwrap();
    p.segments()[0].clone()
}

fn unlimited() -> JointLimits {
    JointLimits {
        vel: [f64::INFINITY; 6],
        accel: [f64::INFINITY; 6],
    }
}

#[test]
fn a_move_within_every_limit_keeps_its_programmed_timing() {
    let seg = x_move();
    assert_eq!(retime(&seg, &parallel, &unlimited()), None);
    let machine = JointLimits::new(&MotionLimits::default(), &RotaryLimits::default());
    assert_eq!(retime(&seg, &parallel, &machine), None);
}

#[test]
fn a_speed_limit_on_x_gives_the_trapezoid_at_that_speed() {
    let seg = x_move();
    let mut lim = unlimited();
    lim.vel[0] = 5.0;
    let r = retime(&seg, &parallel, &lim).expect("retimed");
    let want = SpeedProfile::new(100.0, 5.0, seg.profile.accel_mm_per_s2);
    // The ramps (4 µm here) are shorter than one sample step of 0.1 mm: starting and stopping
    // take at most one step at the speed reached each, 2 × 0.1 / 5 s.
    let late_s = r.duration_s() - want.duration_s();
    assert!(
        (0.0..=0.04 + 1e-9).contains(&late_s),
        "{} vs {}",
        r.duration_s(),
        want.duration_s()
    );
    assert_eq!(r.binding, ('X', LimitKind::Velocity));
    assert!((r.slowest_ratio - 5.0 / 25.0).abs() < 1e-9);
    // Half-way in time, half-way along (the profile is symmetric).
    assert!((r.distance_at(0.5 * r.duration_s()) - 50.0).abs() < 1e-6);
}

#[test]
fn an_acceleration_limit_on_x_gives_the_gentler_trapezoid_at_the_feed() {
    let seg = x_move();
    let mut lim = unlimited();
    lim.accel[0] = 50.0;
    let r = retime(&seg, &parallel, &lim).expect("retimed");
    let want = SpeedProfile::new(100.0, 25.0, 50.0);
    let rel = (r.duration_s() - want.duration_s()).abs() / want.duration_s();
    assert!(rel < 1e-3, "{} vs {}", r.duration_s(), want.duration_s());
    assert_eq!(r.slowest_ratio, 1.0);
    assert_eq!(r.binding, ('X', LimitKind::Acceleration));
}

#[test]
fn the_retimed_distance_rises_from_zero_to_the_length() {
    let seg = x_move();
    let mut lim = unlimited();
    lim.vel[0] = 7.0;
    lim.accel[0] = 40.0;
    let r = retime(&seg, &parallel, &lim).unwrap();
    assert_eq!(r.distance_at(0.0), 0.0);
    assert_eq!(r.distance_at(r.duration_s()), 100.0);
    let mut last = 0.0;
    for k in 0..=1000 {
        let s = r.distance_at(r.duration_s() * f64::from(k) / 1000.0);
        assert!(s >= last - 1e-12, "{s} after {last}");
        last = s;
    }
}
