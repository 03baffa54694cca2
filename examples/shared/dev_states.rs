//! Selection-only stress states shared by the diagnosis examples.
use vmc_twin::studies::calibration::{self, ThermalCycle};

/// Selection-only stress states (never the held-out ones): Z strokes at another feed and
/// length, a high speed below the maximum, a shop at 24.5 °C.
pub fn dev_stress_states() -> Vec<calibration::EvalState> {
    use vmc_machine::thermal::AmbientProfile;
    use vmc_twin::studies::calibration::Phase;
    let ph = |h: f64, rpm: f64, f: [f64; 3]| Phase {
        duration_s: h * 3600.0,
        spindle_rpm: rpm,
        axis_speed_mm_per_min: f,
    };
    let cyc = |name: &str, t: f64, soak: Option<f64>, phases| ThermalCycle {
        name: name.into(),
        purpose: String::new(),
        ambient: AmbientProfile::Constant { temp_degc: t },
        soak_degc: soak,
        phases,
    };
    let st = |c: ThermalCycle, h: f64| calibration::EvalState {
        name: format!("{}@{h}h", c.name),
        cycle: c,
        at_s: h * 3600.0,
    };
    vec![
        st(
            cyc(
                "dev_z_strokes",
                20.0,
                None,
                vec![ph(2.5, 0.0, [800.0, 200.0, 5000.0])],
            ),
            2.5,
        ),
        st(
            cyc(
                "dev_high_speed",
                20.0,
                None,
                vec![ph(5.0, 11000.0, [2000.0, 2500.0, 1500.0])],
            ),
            4.0,
        ),
        st(
            cyc(
                "dev_warm_shop",
                24.5,
                Some(24.5),
                vec![ph(3.0, 5000.0, [2500.0, 2500.0, 1000.0])],
            ),
            2.0,
        ),
    ]
}
