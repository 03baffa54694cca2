//! Analytic and conservation tests of the thermal network.

use super::*;

/// Spec with `nodes` and `links`, no sources, constant ambient 20 °C, step 1 s.
fn spec(nodes: Vec<NodeSpec>, links: Vec<LinkSpec>, sources: Vec<HeatSourceSpec>) -> ThermalSpec {
    ThermalSpec {
        step_s: 1.0,
        ambient: AmbientProfile::Constant { temp_degc: 20.0 },
        nodes,
        links,
        sources,
    }
}

fn node(name: &str, capacity_j_per_k: f64, ha_w_per_k: f64) -> NodeSpec {
    NodeSpec {
        name: name.into(),
        capacity_j_per_k,
        ha_w_per_k,
        ha_gain_per_krpm: 0.0,
        coolant_ha_w_per_k: 0.0,
    }
}

fn link(a: &str, b: &str, g: f64) -> LinkSpec {
    LinkSpec {
        a: a.into(),
        b: b.into(),
        conductance_w_per_k: g,
    }
}

#[test]
fn single_node_follows_the_analytic_exponential_within_0_01_degc() {
    // C = 6000 J/K, hA = 10 W/K → τ = 600 s; 50 W → T∞ = 20 + 5 = 25 °C; start at 40 °C.
    let s = spec(
        vec![node("n", 6000.0, 10.0)],
        vec![],
        vec![HeatSourceSpec::Constant {
            node: "n".into(),
            power_w: 50.0,
        }],
    );
    let mut net = ThermalNetwork::new(&s, 40.0).unwrap();
    let (t_inf, t0, tau) = (25.0, 40.0, 600.0);
    let mut max_err: f64 = 0.0;
    for _ in 0..(5 * 600) {
        net.advance(1.0, &Activity::default()).unwrap();
        let exact = t_inf + (t0 - t_inf) * (-net.time_s() / tau).exp();
        max_err = max_err.max((net.temps_degc()[0] - exact).abs());
    }
    assert!(max_err < 0.01, "max deviation {max_err} °C");
    // And it really moved: after 5τ it is within 0.1 °C of T∞, far from T0.
    assert!((net.temps_degc()[0] - t_inf).abs() < 0.11);
}

#[test]
fn two_node_chain_reaches_the_hand_computed_steady_state() {
    // 100 W into a, a–b 5 W/K, b to ambient 2 W/K: T_b = 20 + 100/2 = 70, T_a = 70 + 100/5 = 90.
    let s = spec(
        vec![node("a", 1000.0, 0.0), node("b", 2000.0, 2.0)],
        vec![link("a", "b", 5.0)],
        vec![HeatSourceSpec::Constant {
            node: "a".into(),
            power_w: 100.0,
        }],
    );
    let mut net = ThermalNetwork::new(&s, 20.0).unwrap();
    let ss = net.steady_state_degc(&Activity::default(), 20.0).unwrap();
    assert!(
        (ss[0] - 90.0).abs() < 1e-9 && (ss[1] - 70.0).abs() < 1e-9,
        "{ss:?}"
    );
    // τ ≈ (1000+2000)/2 = 1500 s at most; 20 τ of simulation lands on the steady state.
    net.advance(30_000.0, &Activity::default()).unwrap();
    assert!(
        (net.temps_degc()[0] - 90.0).abs() < 1e-3,
        "{:?}",
        net.temps_degc()
    );
    assert!((net.temps_degc()[1] - 70.0).abs() < 1e-3);
}

#[test]
fn forced_convection_grows_with_spindle_speed() {
    let mut n = node("s", 1000.0, 1.0);
    n.ha_gain_per_krpm = 0.5;
    let s = spec(
        vec![n],
        vec![],
        vec![HeatSourceSpec::Constant {
            node: "s".into(),
            power_w: 10.0,
        }],
    );
    let net = ThermalNetwork::new(&s, 20.0).unwrap();
    let still = net.steady_state_degc(&Activity::default(), 20.0).unwrap()[0];
    let spinning = Activity {
        spindle_rpm: 4000.0,
        ..Activity::default()
    };
    let fast = net.steady_state_degc(&spinning, 20.0).unwrap()[0];
    // hA = 1 W/K at rest, 1·(1 + 0.5·4) = 3 W/K at 4000 rpm: rise 10 K vs 3.33 K.
    assert!((still - 30.0).abs() < 1e-9 && (fast - (20.0 + 10.0 / 3.0)).abs() < 1e-9);
}

#[test]
fn screw_heat_goes_to_the_segment_under_the_nut() {
    let names = ["s0", "s1", "s2", "s3"];
    let s = spec(
        names.iter().map(|n| node(n, 500.0, 0.3)).collect(),
        vec![],
        vec![HeatSourceSpec::BallscrewNut {
            axis: Axis::Y,
            segments: names.iter().map(|n| n.to_string()).collect(),
            travel_min_mm: 0.0,
            travel_max_mm: 400.0,
            lead_mm: 10.0,
            torque_n_mm: 300.0,
        }],
    );
    let mut net = ThermalNetwork::new(&s, 20.0).unwrap();
    // Nut shuttling inside segment 2 (200..300 mm) at 3000 mm/min for 10 min.
    let a = Activity {
        axis_pos_mm: [0.0, 250.0, 0.0],
        axis_speed_mm_per_min: [0.0, 3000.0, 0.0],
        ..Activity::default()
    };
    net.advance(600.0, &a).unwrap();
    let t = net.temps_degc();
    // 1.047e-4·300 rpm·300 N·mm = 9.42 W for 600 s into 500 J/K: ≈ +10 K (less some convection).
    assert!(t[2] > 28.0, "{t:?}");
    for i in [0, 1, 3] {
        assert!(
            (t[i] - 20.0).abs() < 1e-9,
            "segment {i} has no link and no nut: {t:?}"
        );
    }
    assert_eq!(net.heat_input_w()[2], net.source_power_w(&a)[2]);
}

#[test]
fn heat_input_and_convection_balance_stored_energy() {
    // Energy test on a small asymmetric network with a varying ambient and activity.
    let s = ThermalSpec {
        ambient: AmbientProfile::Sinusoid {
            mean_degc: 20.0,
            amplitude_degc: 3.0,
            period_s: 3600.0,
            phase_rad: 0.3,
        },
        ..spec(
            vec![
                node("a", 800.0, 0.5),
                node("b", 3000.0, 2.0),
                node("c", 500.0, 0.0),
            ],
            vec![link("a", "b", 3.0), link("b", "c", 1.0)],
            vec![HeatSourceSpec::SpindleBearing {
                node: "a".into(),
                torque_n_mm: 40.0,
                torque_per_krpm_n_mm: 5.0,
            }],
        )
    };
    let mut net = ThermalNetwork::new(&s, 18.0).unwrap();
    let e0 = net.stored_energy_j();
    for k in 0..7200 {
        let a = Activity {
            spindle_rpm: if (k / 900) % 2 == 0 { 8000.0 } else { 0.0 },
            ..Activity::default()
        };
        net.advance(1.0, &a).unwrap();
    }
    let de = net.stored_energy_j() - e0;
    let balance = net.heat_in_j() - net.heat_out_j();
    assert!(
        net.heat_in_j() > 1e5,
        "sources must have worked: {}",
        net.heat_in_j()
    );
    assert!(
        (de - balance).abs() < 1e-9 * net.heat_in_j(),
        "ΔE {de} vs in−out {balance}"
    );
}

#[test]
fn ambient_table_interpolates_and_holds_its_ends() {
    let p = AmbientProfile::Table {
        points: vec![[0.0, 20.0], [3600.0, 22.0], [7200.0, 21.0]],
    };
    assert_eq!(p.temp_degc(-5.0), 20.0);
    assert!((p.temp_degc(1800.0) - 21.0).abs() < 1e-12);
    assert!((p.temp_degc(5400.0) - 21.5).abs() < 1e-12);
    assert_eq!(p.temp_degc(1e6), 21.0);
    let sine = AmbientProfile::Sinusoid {
        mean_degc: 20.0,
        amplitude_degc: 2.0,
        period_s: 86_400.0,
        phase_rad: 0.0,
    };
    assert!((sine.temp_degc(21_600.0) - 22.0).abs() < 1e-12);
}

#[test]
fn advance_uses_the_ambient_profile_and_a_short_last_step() {
    let s = ThermalSpec {
        ambient: AmbientProfile::Constant { temp_degc: 30.0 },
        ..spec(vec![node("n", 100.0, 1.0)], vec![], vec![])
    };
    let mut net = ThermalNetwork::new(&s, 20.0).unwrap();
    net.advance(2.5, &Activity::default()).unwrap();
    assert!((net.time_s() - 2.5).abs() < 1e-12);
    // Implicit Euler with steps 1, 1, 0.5 s toward 30 °C (τ = 100 s).
    let mut t = 20.0;
    for dt in [1.0, 1.0, 0.5] {
        t = (100.0 / dt * t + 30.0) / (100.0 / dt + 1.0);
    }
    assert!((net.temps_degc()[0] - t).abs() < 1e-12);
}

#[test]
fn validation_errors_name_the_field() {
    let mut s = spec(
        vec![
            node("a", 1.0, 0.0),
            node("b", 1.0, 0.0),
            node("c", 1.0, 0.0),
            node("d", -5.0, 0.0),
        ],
        vec![link("a", "b", 1.0)],
        vec![],
    );
    let msg = s.validate().unwrap_err().to_string();
    assert_eq!(msg, "thermal.nodes[3].capacity_j_per_k must be > 0, got -5");

    s.nodes[3].capacity_j_per_k = 1.0;
    s.links.push(link("a", "zz", 1.0));
    let msg = s.validate().unwrap_err().to_string();
    assert_eq!(msg, "thermal.links[1].b names unknown node `zz`");

    s.links.pop();
    s.nodes[2].name = "a".into();
    let msg = s.validate().unwrap_err().to_string();
    assert!(msg.contains("thermal.nodes[2].name"), "{msg}");

    s.nodes[2].name = "c".into();
    s.sources.push(HeatSourceSpec::SpindleMotor {
        node: "a".into(),
        torque_n_m: 1.0,
        torque_per_krpm_n_m: 0.0,
        efficiency: 1.5,
    });
    let msg = s.validate().unwrap_err().to_string();
    assert_eq!(
        msg,
        "thermal.sources[0].efficiency must be in (0, 1], got 1.5"
    );

    s.sources.clear();
    s.ambient = AmbientProfile::Table {
        points: vec![[0.0, 20.0], [0.0, 21.0]],
    };
    let msg = s.validate().unwrap_err().to_string();
    assert!(msg.starts_with("thermal.ambient.points[1][0]"), "{msg}");
}

#[test]
fn toml_with_an_unknown_field_is_rejected() {
    let text = r#"
        nodes = [ { name = "a", capacity_j_per_k = 1.0, capacity = 2.0 } ]
    "#;
    let err = toml::from_str::<ThermalSpec>(text).unwrap_err().to_string();
    assert!(err.contains("capacity"), "{err}");
    let text = r#"
        nodes = [ { name = "a", capacity_j_per_k = 1.0 } ]
        sources = [ { kind = "constant", node = "a", power_w = 1.0, watts = 3.0 } ]
    "#;
    assert!(toml::from_str::<ThermalSpec>(text).is_err());
}

#[test]
fn non_finite_activity_is_an_error_not_a_nan_state() {
    let s = spec(vec![node("n", 100.0, 1.0)], vec![], vec![]);
    let mut net = ThermalNetwork::new(&s, 20.0).unwrap();
    let a = Activity {
        spindle_rpm: f64::NAN,
        ..Activity::default()
    };
    let msg = net.step(1.0, &a, 20.0).unwrap_err().to_string();
    assert!(msg.starts_with("activity.spindle_rpm"), "{msg}");
    assert!(net.step(0.0, &Activity::default(), 20.0).is_err());
    assert_eq!(net.temps_degc()[0], 20.0);
}
