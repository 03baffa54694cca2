use super::*;
use crate::machine::MachineSpec;
use crate::thermal::Activity;

const BLOCK: Artefact = Artefact::GaugeBlock {
    top_mm: [280.0, 200.0, -300.0],
    half_width_mm: 15.0,
};

fn down_onto_block(probe: &TouchProbe) -> Touch {
    Touch {
        start_mm: [280.0, 200.0, -300.0 + probe.ball_radius_mm + 5.0],
        axis: 2,
        sign: -1.0,
        max_travel_mm: 10.0,
    }
}

/// Mean latched Z of `n` touches on the block's top.
fn mean_top_z(p: &mut ProbeOnTwin, twin: &mut Twin, n: usize) -> f64 {
    let touch = down_onto_block(p.probe());
    let mut sum = 0.0;
    for _ in 0..n {
        let trip = p.touch(twin, &BLOCK, &touch).unwrap().expect("contact");
        sum += trip.axis_mm[2];
    }
    sum / n as f64
}

/// Truth, read by the test only: the Z error of the stylus tip at the block's top, mm (no
/// random positioning part).
fn true_ez_at_top(twin: &mut Twin, probe: &TouchProbe) -> f64 {
    let q = [280.0, 200.0, -300.0 + probe.ball_radius_mm];
    let saved = twin.set_tool_offset_mm([0.0, 0.0, -probe.stylus_length_mm]);
    let e = twin.tool_error_mm(q, q, [0.0; 3]).z;
    twin.set_tool_offset_mm(saved);
    e
}

#[test]
fn a_gauge_block_probed_cold_and_warm_returns_the_drift_at_its_top() {
    let spec = MachineSpec::reference();
    let mut twin = Twin::with_noise_seed(&spec, 1, 77).unwrap();
    let probe = TouchProbe::typical(150.0);
    let mut p = ProbeOnTwin::new(probe, 5).unwrap();
    let n = 5;
    let cold_read = mean_top_z(&mut p, &mut twin, n);
    let cold_true = true_ez_at_top(&mut twin, &probe);
    // Two hours at 8000 rpm with the axes shuttling: tens of µm of drift.
    let warm = Activity {
        spindle_rpm: 8000.0,
        axis_pos_mm: [280.0, 200.0, -225.0],
        axis_speed_mm_per_min: [3000.0, 2000.0, 1000.0],
        coolant: false,
    };
    for _ in 0..7200 {
        twin.advance(1.0, &warm).unwrap();
    }
    let warm_read = mean_top_z(&mut p, &mut twin, n);
    let warm_true = true_ez_at_top(&mut twin, &probe);
    let drift_um = (warm_true - cold_true) * 1e3;
    assert!(drift_um.abs() > 10.0, "the machine drifted {drift_um} µm");
    // The ball reaches the top where q + E = top + r: the reading moves by −ΔE.
    let read_um = -(warm_read - cold_read) * 1e3;
    assert!(
        (read_um - drift_um).abs() <= probe.repeatability_2sigma_um,
        "probed {read_um:.3} µm, drift {drift_um:.3} µm"
    );
}

#[test]
fn the_trip_lies_past_contact_by_the_pretravel_and_at_most_one_servo_tick() {
    let spec = MachineSpec::reference();
    let mut twin = Twin::with_noise_seed(&spec, 2, 3).unwrap();
    let probe = TouchProbe {
        repeatability_2sigma_um: 0.0,
        ..TouchProbe::typical(150.0)
    };
    let mut p = ProbeOnTwin::new(probe, 1).unwrap();
    let touch = down_onto_block(&probe);
    let trip = p.touch(&mut twin, &BLOCK, &touch).unwrap().unwrap();
    // Contact where the real ball meets the real top: q_z + E_z = top + r.
    let ez = true_ez_at_top(&mut twin, &probe);
    let contact_z = -300.0 + probe.ball_radius_mm - ez;
    let past_mm = contact_z - trip.axis_mm[2];
    let rev = 0.5 * spec.errors.random[2].reversal_um * 1e-3;
    let machine_noise_mm = 4.0 * spec.errors.random[2].repeatability_sigma_um * 1e-3 + rev;
    assert!(
        past_mm >= probe.pretravel_mm() - machine_noise_mm
            && past_mm <= probe.pretravel_mm() + probe.latency_travel_mm() + machine_noise_mm,
        "{past_mm} mm past contact"
    );
}

#[test]
fn a_touch_that_meets_nothing_gives_no_trip_and_a_bad_touch_is_refused() {
    let spec = MachineSpec::reference();
    let mut twin = Twin::with_noise_seed(&spec, 1, 1).unwrap();
    let probe = TouchProbe::typical(150.0);
    let mut p = ProbeOnTwin::new(probe, 1).unwrap();
    let mut touch = down_onto_block(&probe);
    touch.max_travel_mm = 2.0;
    assert_eq!(p.touch(&mut twin, &BLOCK, &touch).unwrap(), None);
    touch.start_mm[2] = -301.0;
    assert_eq!(
        p.touch(&mut twin, &BLOCK, &touch),
        Err(ProbeError::AlreadyTripped)
    );
    touch.axis = 3;
    assert!(matches!(
        p.touch(&mut twin, &BLOCK, &touch),
        Err(ProbeError::Touch { axis: 3, .. })
    ));
    let bad = TouchProbe {
        ball_radius_mm: -1.0,
        ..probe
    };
    assert!(matches!(
        ProbeOnTwin::new(bad, 1),
        Err(ProbeError::Setting {
            field: "ball_radius_mm",
            ..
        })
    ));
}

#[test]
fn a_sphere_is_touched_on_its_side_at_its_radius_plus_the_ball() {
    let spec = MachineSpec::reference();
    let mut twin = Twin::with_noise_seed(&spec, 1, 1).unwrap();
    let probe = TouchProbe {
        repeatability_2sigma_um: 0.0,
        ..TouchProbe::typical(150.0)
    };
    let mut p = ProbeOnTwin::new(probe, 1).unwrap();
    let sphere = Artefact::Sphere {
        centre_mm: [100.0, 100.0, -350.0],
        radius_mm: 12.5,
    };
    let touch = Touch {
        start_mm: [100.0 - 12.5 - 3.0 - 5.0, 100.0, -350.0],
        axis: 0,
        sign: 1.0,
        max_travel_mm: 10.0,
    };
    let trip = p.touch(&mut twin, &sphere, &touch).unwrap().unwrap();
    // Within the machine's cold error (tens of µm) of the nominal contact plus pre-travel.
    let nominal = 100.0 - 15.5 + probe.pretravel_mm();
    assert!(
        (trip.axis_mm[0] - nominal).abs() < 0.1,
        "{:?}",
        trip.axis_mm
    );
}
