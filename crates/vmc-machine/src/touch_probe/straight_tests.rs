//! Tests of straight probe moves.

use super::*;
use crate::machine::MachineSpec;
use crate::touch_probe::{Artefact, Touch};
use vmc_gcode::interp::ProbeKind;

const TOP_Z_MM: f64 = -300.0;

fn block() -> Solid {
    Solid::Box {
        min_mm: [265.0, 185.0, TOP_Z_MM - 50.0],
        max_mm: [295.0, 215.0, TOP_Z_MM],
    }
}

fn request(kind: (bool, bool), start_mm: [f64; 3], end_mm: [f64; 3]) -> ProbeRequest {
    ProbeRequest {
        line: 7,
        kind: ProbeKind {
            toward: kind.0,
            error_on_no_contact: kind.1,
        },
        start_mm,
        start_abc_deg: [0.0; 3],
        end_mm,
        end_abc_deg: [0.0; 3],
        feed_mm_per_min: 50.0,
    }
}

/// A ball centred on the commanded tip, the reference machine's accelerations.
fn motion() -> ProbeMotion {
    ProbeMotion {
        ball_offset_mm: [0.0; 3],
        max_accel_mm_per_s2: MachineSpec::reference().motion.max_accel_mm_per_s2,
    }
}

fn tripped(m: &ProbeMove) -> ([f64; 3], [f64; 3]) {
    match m.outcome {
        ProbeOutcome::Tripped {
            trip_mm, rest_mm, ..
        } => (trip_mm, rest_mm),
        other => panic!("not tripped: {other:?}"),
    }
}

#[test]
fn the_nominal_trip_lies_the_pretravel_past_contact_and_the_axes_brake_after_it() {
    let probe = TouchProbe::typical(150.0);
    let r = probe.ball_radius_mm;
    let down = request(
        (true, true),
        [280.0, 200.0, TOP_Z_MM + 10.0],
        [280.0, 200.0, -320.0],
    );
    let m = nominal_move(&probe, &[block()], &motion(), &down);
    assert_eq!(m.touched, Some(0));
    let (trip, rest) = tripped(&m);
    let expected = TOP_Z_MM + r - probe.pretravel_mm();
    assert!((trip[2] - expected).abs() < 1e-6, "{trip:?}");
    assert_eq!((trip[0], trip[1]), (280.0, 200.0));
    // 50 mm/min braked at the Z axis's acceleration.
    let a = motion().max_accel_mm_per_s2[2];
    let brake = (50.0f64 / 60.0).powi(2) / (2.0 * a);
    assert!((trip[2] - rest[2] - brake).abs() < 1e-9, "{rest:?}");
    // A ball offset moves the trip by the offset.
    let high = ProbeMotion {
        ball_offset_mm: [0.0, 0.0, -2.0],
        ..motion()
    };
    let (trip_low, _) = tripped(&nominal_move(&probe, &[block()], &high, &down));
    assert!((trip_low[2] - (expected + 2.0)).abs() < 1e-6);
}

#[test]
fn an_oblique_move_onto_a_sphere_trips_where_the_ball_meets_it() {
    let probe = TouchProbe::typical(150.0);
    let sphere = Solid::Sphere {
        centre_mm: [100.0, 100.0, -350.0],
        radius_mm: 12.5,
    };
    // Along the diagonal toward the centre.
    let s = 30.0 / 3f64.sqrt();
    let start = [100.0 + s, 100.0 + s, -350.0 + s];
    let m = nominal_move(
        &probe,
        &[sphere],
        &motion(),
        &request((true, false), start, [100.0, 100.0, -350.0]),
    );
    let (trip, _) = tripped(&m);
    let d: f64 = (0..3)
        .map(|a| (trip[a] - [100.0, 100.0, -350.0][a]).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!((d - (12.5 + probe.ball_radius_mm - probe.pretravel_mm())).abs() < 1e-6);
}

#[test]
fn moves_that_never_change_state_or_start_in_it_say_so() {
    let probe = TouchProbe::typical(150.0);
    let m = motion();
    // Beside the block: nothing within the travel.
    let beside = request((true, true), [350.0, 200.0, -290.0], [350.0, 200.0, -320.0]);
    let got = nominal_move(&probe, &[block()], &m, &beside);
    assert_eq!((got.outcome, got.touched), (ProbeOutcome::NoContact, None));
    // Pressed into the top: already tripped for G38.2, and G38.4 trips on leaving it.
    let pressed = [280.0, 200.0, TOP_Z_MM + 2.0];
    let into = request((true, true), pressed, [280.0, 200.0, -320.0]);
    let got = nominal_move(&probe, &[block()], &m, &into);
    assert_eq!(got.outcome, ProbeOutcome::AlreadyInState);
    let away = request((false, true), pressed, [280.0, 200.0, -280.0]);
    let (trip, _) = tripped(&nominal_move(&probe, &[block()], &m, &away));
    let expected = TOP_Z_MM + probe.ball_radius_mm - probe.pretravel_mm();
    assert!((trip[2] - expected).abs() < 1e-6, "{trip:?}");
    // No solid at all: no contact.
    let none = nominal_move(&probe, &[], &m, &beside);
    assert_eq!(none.outcome, ProbeOutcome::NoContact);
}

#[test]
fn on_the_twin_a_straight_move_agrees_with_the_single_axis_touch() {
    // Differential: the older single-axis touch (contact, then pre-travel along the move) and
    // the straight move (overlap reaching the pre-travel) on twins built alike, no scatter.
    let spec = MachineSpec::reference();
    let probe = TouchProbe {
        repeatability_2sigma_um: 0.0,
        servo_period_s: 0.0,
        ..TouchProbe::typical(150.0)
    };
    let start = [280.0, 200.0, TOP_Z_MM + probe.ball_radius_mm + 5.0];
    let mut twin_a = Twin::with_noise_seed(&spec, 3, 9).unwrap();
    let mut a = ProbeOnTwin::new(probe, 1).unwrap();
    let artefact = Artefact::GaugeBlock {
        top_mm: [280.0, 200.0, TOP_Z_MM],
        half_width_mm: 15.0,
    };
    let touch = Touch {
        start_mm: start,
        axis: 2,
        sign: -1.0,
        max_travel_mm: 10.0,
    };
    let old = a.touch(&mut twin_a, &artefact, &touch).unwrap().unwrap();
    let mut twin_b = Twin::with_noise_seed(&spec, 3, 9).unwrap();
    let mut b = ProbeOnTwin::new(probe, 1).unwrap();
    let down = request((true, true), start, [280.0, 200.0, start[2] - 10.0]);
    let m = b
        .straight_move(&mut twin_b, &[block()], &motion(), &down)
        .unwrap();
    let (trip, _) = tripped(&m);
    assert!(
        (trip[2] - old.axis_mm[2]).abs() < 1e-5,
        "{} vs {}",
        trip[2],
        old.axis_mm[2]
    );
    // The twin's answer is the nominal one moved by the machine's error (µm, not zero).
    let (nominal, _) = tripped(&nominal_move(&probe, &[block()], &motion(), &down));
    let diff_um = (trip[2] - nominal[2]).abs() * 1e3;
    assert!(diff_um > 0.01 && diff_um < 200.0, "{diff_um} µm");
}

#[test]
fn a_probe_move_without_a_feed_is_refused() {
    let spec = MachineSpec::reference();
    let mut twin = Twin::new(&spec, 1).unwrap();
    let mut p = ProbeOnTwin::new(TouchProbe::typical(150.0), 1).unwrap();
    let mut r = request((true, true), [280.0, 200.0, -290.0], [280.0, 200.0, -320.0]);
    r.feed_mm_per_min = 0.0;
    assert!(matches!(
        p.straight_move(&mut twin, &[block()], &motion(), &r),
        Err(ProbeError::Setting {
            field: "feed_mm_per_min",
            ..
        })
    ));
}
