use super::*;

/// Three 4 h on / 4 h off cycles at rising speeds, one row a minute, ambient 20 °C with a slow
/// wave.
fn test_series() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..1440).map(|i| 60.0 * f64::from(i)).collect();
    let rpm = (0..1440)
        .map(|i| {
            if (i % 480) < 240 {
                1250.0 * f64::from(i / 480 + 1)
            } else {
                0.0
            }
        })
        .collect();
    let amb = t
        .iter()
        .map(|s| 20.0 + 0.5 * (s / 20_000.0).sin())
        .collect();
    (t, rpm, amb)
}

#[test]
fn one_node_steps_as_implicit_euler_and_settles_at_q_over_h() {
    let net = RcNetwork {
        capacity_j_per_k: vec![36_000.0],
        link_w_per_k: vec![],
        ambient_w_per_k: vec![10.0],
        ha_gain_per_krpm: 0.0,
        heat_w_per_krpm: 20.0,
        heat_w_per_krpm2: 5.0,
    };
    let t: Vec<f64> = (0..2000).map(|i| 60.0 * f64::from(i)).collect();
    let rpm = vec![2000.0; 2000];
    let amb = vec![20.0; 2000];
    let temps = net.simulate(&t, &rpm, &amb);
    // q = 20·2 + 5·4 = 60 W, H = 10 W/K: 6 K above ambient at steady state.
    assert!((temps[0][1999] - 26.0).abs() < 1e-9, "{}", temps[0][1999]);
    // One step: (C/dt + H)·T₁ = C/dt·T₀ + q + H·T_a.
    let c_dt = 36_000.0 / 60.0;
    let t1 = (c_dt * 20.0 + 60.0 + 10.0 * 20.0) / (c_dt + 10.0);
    assert!((temps[0][1] - t1).abs() < 1e-12);
}

#[test]
fn a_three_node_network_is_recovered_from_its_own_drifts_and_node_temperatures() {
    let (t, rpm, amb) = test_series();
    let truth = RcNetwork {
        capacity_j_per_k: vec![20_000.0, 150_000.0, 900_000.0],
        link_w_per_k: vec![6.0, 15.0],
        ambient_w_per_k: vec![3.0, 4.0, 30.0],
        ha_gain_per_krpm: 0.3,
        heat_w_per_krpm: 8.0,
        heat_w_per_krpm2: 2.0,
    };
    // Constant ambient (no ambient column): the fit sees the rises of the nodes above it.
    let flat = vec![amb[0]; t.len()];
    let temps = truth.simulate(&t, &rpm, &flat);
    let gains = [[0.5, 2.0, -1.0, 0.3], [0.0, -0.7, 3.0, -2.0]];
    let drifts: Vec<Vec<f64>> = gains
        .iter()
        .map(|c| {
            (0..t.len())
                .map(|r| {
                    c[0] + (0..3)
                        .map(|i| c[i + 1] * (temps[i][r] - amb[0]))
                        .sum::<f64>()
                })
                .collect()
        })
        .collect();
    let node_temps = [
        Some(temps[0].as_slice()),
        Some(temps[1].as_slice()),
        Some(temps[2].as_slice()),
    ];
    let data = RcData {
        time_s: &t,
        rpm: &rpm,
        ambient_degc: None,
        drifts: &drifts,
        node_temps: &node_temps,
        temps: &[],
    };
    let settings = RcSettings {
        nodes: 3,
        ..RcSettings::default()
    };
    let rows: Vec<usize> = (0..t.len()).collect();
    let fit = identify(&data, &rows, &settings, Mode::SpeedOnly).unwrap();
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    let n = &fit.network;
    let pairs = [
        (n.capacity_j_per_k[1], truth.capacity_j_per_k[1]),
        (n.capacity_j_per_k[2], truth.capacity_j_per_k[2]),
        (n.link_w_per_k[0], truth.link_w_per_k[0]),
        (n.link_w_per_k[1], truth.link_w_per_k[1]),
        (n.ambient_w_per_k[0], truth.ambient_w_per_k[0]),
        (n.ambient_w_per_k[1], truth.ambient_w_per_k[1]),
        (n.ambient_w_per_k[2], truth.ambient_w_per_k[2]),
        (n.ha_gain_per_krpm, truth.ha_gain_per_krpm),
        (n.heat_w_per_krpm, truth.heat_w_per_krpm),
        (n.heat_w_per_krpm2, truth.heat_w_per_krpm2),
    ];
    for (i, (got, want)) in pairs.iter().enumerate() {
        assert!(
            rel(*got, *want) < 1e-6,
            "parameter {i}: {got} vs {want}; {fit:?}"
        );
    }
    for (g, w) in fit.gains.iter().zip(&gains) {
        for (a, b) in g.iter().zip(w) {
            assert!((a - b).abs() < 1e-6 * b.abs().max(1.0), "{g:?} vs {w:?}");
        }
    }
    assert!(fit.at_bounds.is_empty(), "{:?}", fit.at_bounds);
}

#[test]
fn negative_speeds_and_short_columns_are_errors_not_panics() {
    let (t, mut rpm, amb) = test_series();
    let drifts = vec![vec![0.0; t.len()]];
    rpm[7] = -5.0;
    let data = RcData {
        time_s: &t,
        rpm: &rpm,
        ambient_degc: Some(&amb),
        drifts: &drifts,
        node_temps: &[],
        temps: &[],
    };
    let rows: Vec<usize> = (0..100).collect();
    let e = identify(&data, &rows, &RcSettings::default(), Mode::SpeedOnly).unwrap_err();
    assert_eq!(e, RcError::NegativeSpeed { row: 7, rpm: -5.0 });
    let short = vec![vec![0.0; 10]];
    let data = RcData {
        drifts: &short,
        ..data
    };
    let e = identify(&data, &rows, &RcSettings::default(), Mode::SpeedOnly).unwrap_err();
    assert!(e.to_string().contains("equally long columns"), "{e}");
}
