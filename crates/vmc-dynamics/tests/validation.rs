//! Every validation error is reported, typed, before any computation.

use vmc_dynamics::beam::Cantilever;
use vmc_dynamics::milling::{MillingSdm, SdmOptions};
use vmc_dynamics::time_domain::{TimeDomain, TimeOptions};
use vmc_dynamics::zoa::Zoa;
use vmc_dynamics::*;

fn tool() -> Tool {
    Tool::new(2, 20.0, 6e8, 2e8)
}

fn modes() -> TipModes {
    TipModes::x_only(vec![Mode::from_mass(922.0, 0.011, 0.03993)])
}

fn sdm_err(tool: &Tool, modes: &TipModes, immersion: f64) -> DynamicsError {
    MillingSdm::new(tool, modes, immersion, Milling::Down, SdmOptions::default()).unwrap_err()
}

#[test]
fn tool_errors() {
    let mut t = tool();
    t.teeth = 0;
    assert_eq!(sdm_err(&t, &modes(), 0.5), DynamicsError::NoTeeth);
    let mut t = tool();
    t.diameter_mm = 0.0;
    assert_eq!(
        sdm_err(&t, &modes(), 0.5),
        DynamicsError::NonPositive {
            name: "diameter_mm",
            value: 0.0
        }
    );
    let mut t = tool();
    t.kt_n_per_m2 = f64::NAN;
    assert_eq!(
        sdm_err(&t, &modes(), 0.5),
        DynamicsError::NonFinite {
            name: "kt_n_per_m2"
        }
    );
    let mut t = tool();
    t.kn_n_per_m2 = -1.0;
    assert_eq!(
        sdm_err(&t, &modes(), 0.5),
        DynamicsError::Negative {
            name: "kn_n_per_m2",
            value: -1.0
        }
    );
    for helix in [-1.0, 90.0, 120.0] {
        let mut t = tool();
        t.helix_deg = helix;
        assert_eq!(
            sdm_err(&t, &modes(), 0.5),
            DynamicsError::HelixOutOfRange(helix)
        );
    }
    let mut t = tool();
    t.helix_deg = 30.0;
    assert!(t.validate().is_ok());
    let mut t = tool();
    t.process_damping_n_per_m = -5.0;
    assert!(matches!(
        sdm_err(&t, &modes(), 0.5),
        DynamicsError::Negative {
            name: "process_damping_n_per_m",
            ..
        }
    ));
}

#[test]
fn mode_errors() {
    assert_eq!(
        sdm_err(&tool(), &TipModes::default(), 0.5),
        DynamicsError::NoModes
    );
    let mut m = Mode::from_mass(922.0, 0.011, 0.03993);
    m.damping_ratio = -0.01;
    assert_eq!(
        sdm_err(&tool(), &TipModes::x_only(vec![m]), 0.5),
        DynamicsError::Negative {
            name: "damping_ratio",
            value: -0.01
        }
    );
    let m = Mode {
        frequency_hz: 0.0,
        damping_ratio: 0.01,
        stiffness_n_per_m: 1e6,
    };
    assert!(matches!(
        sdm_err(&tool(), &TipModes::symmetric(m), 0.5),
        DynamicsError::NonPositive {
            name: "frequency_hz",
            ..
        }
    ));
    let m = Mode {
        frequency_hz: 900.0,
        damping_ratio: 0.01,
        stiffness_n_per_m: f64::INFINITY,
    };
    assert_eq!(
        sdm_err(&tool(), &TipModes::symmetric(m), 0.5),
        DynamicsError::NonFinite {
            name: "stiffness_n_per_m"
        }
    );
}

#[test]
fn cut_errors() {
    for bad in [0.0, -0.1, 1.0001] {
        assert_eq!(
            sdm_err(&tool(), &modes(), bad),
            DynamicsError::ImmersionOutOfRange(bad)
        );
        assert!(Zoa::new(&tool(), &modes(), bad, Milling::Up).is_err());
    }
    assert_eq!(
        sdm_err(&tool(), &modes(), f64::NAN),
        DynamicsError::NonFinite { name: "immersion" }
    );
    let sdm = MillingSdm::new(&tool(), &modes(), 0.5, Milling::Up, SdmOptions::default()).unwrap();
    assert_eq!(
        sdm.stability(0.0, 1.0).unwrap_err(),
        DynamicsError::ZeroSpeed(0.0)
    );
    assert!(matches!(
        sdm.stability(5000.0, -1.0).unwrap_err(),
        DynamicsError::Negative { .. }
    ));
    assert_eq!(
        lobes(
            Method::Zoa,
            &tool(),
            &modes(),
            0.5,
            Milling::Up,
            &[5000.0, -1.0]
        )
        .unwrap_err(),
        DynamicsError::ZeroSpeed(-1.0)
    );
    let cut = Cut {
        spindle_rpm: 5000.0,
        immersion: 0.5,
        milling: Milling::Up,
        feed_per_tooth_mm: -0.1,
        axial_depth_mm: 1.0,
    };
    assert!(matches!(
        cut.validate().unwrap_err(),
        DynamicsError::Negative {
            name: "feed_per_tooth_mm",
            ..
        }
    ));
    let cut = Cut {
        feed_per_tooth_mm: 0.1,
        ..cut
    };
    assert!(cut.validate().is_ok());
}

#[test]
fn option_errors() {
    let err = MillingSdm::new(
        &tool(),
        &modes(),
        0.5,
        Milling::Up,
        SdmOptions {
            steps_per_period: 2,
        },
    )
    .unwrap_err();
    assert_eq!(
        err,
        DynamicsError::TooFewSteps {
            name: "steps_per_period",
            min: 4,
            value: 2
        }
    );
    let cut = Cut {
        spindle_rpm: 9000.0,
        immersion: 0.5,
        milling: Milling::Up,
        feed_per_tooth_mm: 0.1,
        axial_depth_mm: 1.0,
    };
    for (c, want) in [
        (
            Cut {
                feed_per_tooth_mm: 0.0,
                ..cut
            },
            DynamicsError::NonPositive {
                name: "feed_per_tooth_mm",
                value: 0.0,
            },
        ),
        (
            Cut {
                axial_depth_mm: 0.0,
                ..cut
            },
            DynamicsError::NonPositive {
                name: "axial_depth_mm",
                value: 0.0,
            },
        ),
        (
            Cut {
                spindle_rpm: 0.0,
                ..cut
            },
            DynamicsError::ZeroSpeed(0.0),
        ),
    ] {
        let err = simulate_cut(&tool(), &modes(), &c, &CutOptions::default()).unwrap_err();
        assert_eq!(err, want);
    }
    for (periods, want) in [
        (
            15,
            DynamicsError::TooFewSteps {
                name: "tooth_periods",
                min: 16,
                value: 15,
            },
        ),
        (
            200_000,
            DynamicsError::TooManySteps {
                name: "tooth_periods",
                max: 100_000,
                value: 200_000,
            },
        ),
    ] {
        let opts = CutOptions {
            tooth_periods: periods,
            ..CutOptions::default()
        };
        assert_eq!(
            simulate_cut(&tool(), &modes(), &cut, &opts).unwrap_err(),
            want
        );
    }
    let opts = TimeOptions {
        tooth_periods: 3,
        ..TimeOptions::default()
    };
    let err = TimeDomain::new(&tool(), &modes(), 0.5, Milling::Up, opts).unwrap_err();
    assert_eq!(
        err,
        DynamicsError::TooFewSteps {
            name: "tooth_periods",
            min: 8,
            value: 3
        }
    );
    let beam = Cantilever {
        youngs_modulus_pa: 210e9,
        density_kg_per_m3: 7850.0,
        length_mm: 100.0,
        outer_diameter_mm: 10.0,
        inner_diameter_mm: 12.0,
    };
    assert!(matches!(
        beam.modes(3, 0.02).unwrap_err(),
        DynamicsError::NonPositive { .. }
    ));
    // Messages name the parameter.
    assert_eq!(
        DynamicsError::ZeroSpeed(0.0).to_string(),
        "spindle speed must be > 0 rpm, got 0"
    );
}
