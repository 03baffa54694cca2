//! The retiming against closed forms: with B = C = 0 the part frame is parallel to the bed, so
//! under G43.4 X, Y, Z follow the tip one for one and a limit on X alone must give the
//! trapezoid of [`SpeedProfile`] at that limit.

use super::*;
use crate::fiveaxis::plan::plan_program;
use crate::fiveaxis::FiveAxisSpec;
use crate::motion::SpeedProfile;

fn spec() -> FiveAxisSpec {
    FiveAxisSpec::from_toml_str(
        include_str!("../../../../machines/trunnion-bc.toml"),
        "trunnion-bc.toml",
    )
    .unwrap()
}

/// The line-4 segment of a G43.4 program moving 100 mm along X at F1500 with B = C = 0, and
/// the machine's geometry and tool length.
fn x_move() -> (Segment, Geometry, f64) {
    let s = spec();
    let program = "G10 L2 P1 X-150 Y0 Z-100\nG43.4 H1\nG0 X-50 Y0 Z50 B0 C0\nG1 X50 F1500\nM2\n";
    let plan = plan_program(program, "t.ngc", &s, "m.toml").unwrap();
    let piece = plan
        .pieces
        .iter()
        .find(|p| p.tcp_length_mm.is_some())
        .unwrap();
    let seg = piece
        .plan
        .segments()
        .iter()
        .find(|s| s.line == 4)
        .unwrap()
        .clone();
    (seg, s.geometry(), piece.tcp_length_mm.unwrap())
}

fn unlimited() -> JointLimits {
    JointLimits {
        vel: [f64::INFINITY; 6],
        accel: [f64::INFINITY; 6],
    }
}

#[test]
fn a_move_within_every_limit_keeps_its_programmed_timing() {
    let (seg, geom, len) = x_move();
    assert_eq!(retime(&seg, &geom, len, &unlimited()), None);
    let s = spec();
    let machine = JointLimits::new(&s.motion, &s.rotary_limits("m.toml").unwrap());
    assert_eq!(retime(&seg, &geom, len, &machine), None);
}

#[test]
fn a_speed_limit_on_x_gives_the_trapezoid_at_that_speed() {
    let (seg, geom, len) = x_move();
    let mut lim = unlimited();
    lim.vel[0] = 5.0;
    let r = retime(&seg, &geom, len, &lim).expect("retimed");
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
    let (seg, geom, len) = x_move();
    let mut lim = unlimited();
    lim.accel[0] = 50.0;
    let r = retime(&seg, &geom, len, &lim).expect("retimed");
    let want = SpeedProfile::new(100.0, 25.0, 50.0);
    let rel = (r.duration_s() - want.duration_s()).abs() / want.duration_s();
    assert!(rel < 1e-3, "{} vs {}", r.duration_s(), want.duration_s());
    assert_eq!(r.slowest_ratio, 1.0);
    assert_eq!(r.binding, ('X', LimitKind::Acceleration));
}

#[test]
fn the_retimed_distance_rises_from_zero_to_the_length() {
    let (seg, geom, len) = x_move();
    let mut lim = unlimited();
    lim.vel[0] = 7.0;
    lim.accel[0] = 40.0;
    let r = retime(&seg, &geom, len, &lim).unwrap();
    assert_eq!(r.distance_at(0.0), 0.0);
    assert_eq!(r.distance_at(r.duration_s()), 100.0);
    let mut last = 0.0;
    for k in 0..=1000 {
        let s = r.distance_at(r.duration_s() * f64::from(k) / 1000.0);
        assert!(s >= last - 1e-12, "{s} after {last}");
        last = s;
    }
}
