//! Feed directions other than the x axis of the tip modes: turning the engagement window is the
//! same as turning the modes.

use std::f64::consts::FRAC_PI_2;

use vmc_dynamics::milling::{MillingSdm, SdmOptions};
use vmc_dynamics::*;

fn tool() -> Tool {
    Tool::new(2, 16.0, 6e8, 2e8)
}

fn mode() -> Mode {
    Mode::from_mass(922.0, 0.011, 0.03993)
}

/// Critical depth at one speed by bisection on (0, 10] mm to 1e-4 mm.
fn critical_mm(sdm: &MillingSdm, rpm: f64) -> f64 {
    sdm.at_speed(rpm)
        .unwrap()
        .critical_depth(None, 10.0, 1e-4)
        .unwrap()
        .expect("a boundary below 10 mm")
        .critical_depth_mm
}

#[test]
fn feeding_along_y_on_an_x_mode_is_feeding_along_x_on_a_y_mode() {
    let opts = SdmOptions::default();
    for (immersion, milling) in [
        (0.25, Milling::Up),
        (0.5, Milling::Down),
        (1.0, Milling::Down),
    ] {
        let turned = MillingSdm::with_feed_angle(
            &tool(),
            &TipModes::x_only(vec![mode()]),
            immersion,
            milling,
            FRAC_PI_2,
            opts,
        )
        .unwrap();
        let swapped = MillingSdm::new(
            &tool(),
            &TipModes {
                x: Vec::new(),
                y: vec![mode()],
            },
            immersion,
            milling,
            opts,
        )
        .unwrap();
        for rpm in [7000.0, 10000.0, 16000.0] {
            let (a, b) = (critical_mm(&turned, rpm), critical_mm(&swapped, rpm));
            // A quarter turn is half a tooth pitch of this 2-tooth cutter, 20 of the 40 steps:
            // the two discretisations coincide up to the bisection tolerance (1e-4 mm).
            assert!(
                (a - b).abs() < 2e-4,
                "{immersion} {milling:?} {rpm}: {a} vs {b}"
            );
        }
    }
}

#[test]
fn a_symmetric_tip_does_not_care_about_the_feed_direction() {
    let modes = TipModes::symmetric(mode());
    let opts = SdmOptions::default();
    let plain = MillingSdm::new(&tool(), &modes, 0.3, Milling::Down, opts).unwrap();
    for angle in [0.3, 1.0, 2.5] {
        let turned =
            MillingSdm::with_feed_angle(&tool(), &modes, 0.3, Milling::Down, angle, opts).unwrap();
        for rpm in [8000.0, 12000.0] {
            let (a, b) = (critical_mm(&plain, rpm), critical_mm(&turned, rpm));
            // Same continuous system shifted in time; the 40-step grids cut the window at
            // other places, which moves the boundary by under 2 %.
            assert!((a / b - 1.0).abs() < 0.02, "{angle} {rpm}: {a} vs {b}");
        }
    }
    let err = MillingSdm::with_feed_angle(&tool(), &modes, 0.3, Milling::Down, f64::NAN, opts)
        .unwrap_err();
    assert_eq!(
        err,
        DynamicsError::NonFinite {
            name: "feed_angle_rad"
        }
    );
}
