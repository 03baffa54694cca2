//! Tests of the reference machine's network (`machines/vmc-reference.toml`): serde round trip,
//! conservation, robustness and the warm-up calibration figures.

use super::*;

/// The `[thermal]` section of the reference machine file (its sensors are tested with the
/// machine, which joins them to the network).
#[derive(Deserialize)]
pub(crate) struct Fragment {
    pub thermal: ThermalSpec,
}

pub(crate) const REFERENCE_TOML: &str = include_str!("../../../../machines/vmc-reference.toml");

pub(crate) fn reference() -> Fragment {
    toml::from_str(REFERENCE_TOML).expect("reference fragment parses")
}

/// Travels (mm) of the reference machine, and their lower ends (Z is −450…0, Z up).
const TRAVEL_MM: [f64; 3] = [560.0, 400.0, 450.0];
const TRAVEL_MIN_MM: [f64; 3] = [0.0, 0.0, -450.0];

/// Position of an axis shuttling over its full travel at constant speed (triangle wave).
fn shuttle_mm(time_s: f64, speed_mm_per_min: f64, travel_mm: f64) -> f64 {
    let d = (time_s * speed_mm_per_min / 60.0) % (2.0 * travel_mm);
    if d <= travel_mm {
        d
    } else {
        2.0 * travel_mm - d
    }
}

/// The calibration duty: spindle at `rpm`, X/Y/Z shuttling at 4000/3000/2000 mm/min.
fn duty(time_s: f64, rpm: f64) -> Activity {
    let v = [4000.0, 3000.0, 2000.0];
    Activity {
        spindle_rpm: rpm,
        axis_pos_mm: [0, 1, 2].map(|i| TRAVEL_MIN_MM[i] + shuttle_mm(time_s, v[i], TRAVEL_MM[i])),
        axis_speed_mm_per_min: v,
        coolant: false,
    }
}

fn run(net: &mut ThermalNetwork, duration_s: f64, rpm: f64) {
    let end = net.time_s() + duration_s;
    while net.time_s() < end - 1e-9 {
        let a = duty(net.time_s() + 0.5, rpm);
        net.advance(1.0, &a).unwrap();
    }
}

fn t(net: &ThermalNetwork, name: &str) -> f64 {
    net.temp_degc(name)
        .unwrap_or_else(|| panic!("node {name} missing"))
}

#[test]
fn reference_fragment_validates_and_round_trips_through_toml() {
    let f = reference();
    f.thermal.validate().unwrap();
    ThermalNetwork::new(&f.thermal, 20.0).unwrap();
    // Round trip through serde keeps the spec.
    let text = toml::to_string(&f.thermal).unwrap();
    assert_eq!(toml::from_str::<ThermalSpec>(&text).unwrap(), f.thermal);
}

#[test]
fn reference_network_conserves_energy_under_varying_activity_and_ambient() {
    let mut spec = reference().thermal;
    spec.ambient = AmbientProfile::Table {
        points: vec![[0.0, 19.0], [3.0 * 3600.0, 23.0], [6.0 * 3600.0, 20.0]],
    };
    let mut net = ThermalNetwork::new(&spec, 20.0).unwrap();
    let e0 = net.stored_energy_j();
    for k in 0..(6 * 3600) {
        let rpm = [0.0, 3000.0, 12_000.0, 8000.0][(k / 1800) % 4];
        let mut a = duty(k as f64, rpm);
        a.coolant = (k / 2700) % 2 == 1;
        net.advance(1.0, &a).unwrap();
    }
    let de = net.stored_energy_j() - e0;
    let balance = net.heat_in_j() - net.heat_out_j();
    assert!(net.heat_in_j() > 1e6, "{}", net.heat_in_j());
    // 1e-9 of the heat input: rounding only (≈ 1e-5 J on a few MJ).
    assert!(
        (de - balance).abs() < 1e-9 * net.heat_in_j(),
        "ΔE {de} vs {balance}"
    );
}

#[test]
fn day_of_extreme_inputs_stays_finite_and_physically_bounded() {
    let spec = reference().thermal;
    let mut net = ThermalNetwork::new(&spec, 20.0).unwrap();
    // 24 h at 15 000 rpm with every axis shuttling at 30 m/min (rapid) over its full travel,
    // coolant off, ambient at 35 °C.
    for k in 0..(24 * 3600) {
        let time_s = k as f64 + 0.5;
        let v = [30_000.0; 3];
        let a = Activity {
            spindle_rpm: 15_000.0,
            axis_pos_mm: [0, 1, 2]
                .map(|i| TRAVEL_MIN_MM[i] + shuttle_mm(time_s, v[i], TRAVEL_MM[i])),
            axis_speed_mm_per_min: v,
            coolant: false,
        };
        net.step(1.0, &a, 35.0).unwrap();
    }
    let max = net.temps_degc().iter().copied().fold(f64::MIN, f64::max);
    let min = net.temps_degc().iter().copied().fold(f64::MAX, f64::min);
    assert!(net.temps_degc().iter().all(|t| t.is_finite()));
    // Grease and motor insulation limits: a sensible machine never passes ~150 °C.
    assert!(
        max < 150.0 && min >= 20.0 - 1e-9,
        "min {min} max {max}: {:?}",
        net.node_names()
            .iter()
            .zip(net.temps_degc())
            .collect::<Vec<_>>()
    );
}

#[test]
fn reference_long_run_matches_the_linear_steady_state() {
    let spec = reference().thermal;
    let mut net = ThermalNetwork::new(&spec, 20.0).unwrap();
    let a = Activity {
        spindle_rpm: 9000.0,
        axis_pos_mm: [100.0, 350.0, 200.0],
        axis_speed_mm_per_min: [4000.0, 3000.0, 2000.0],
        coolant: true,
    };
    let ss = net.steady_state_degc(&a, 21.0).unwrap();
    // Implicit Euler's fixed point is the steady state: big steps get there fast (bed τ ≈ days).
    for _ in 0..400 {
        net.step(20_000.0, &a, 21.0).unwrap();
    }
    for (i, (sim, lin)) in net.temps_degc().iter().zip(&ss).enumerate() {
        assert!(
            (sim - lin).abs() < 1e-6,
            "{}: {sim} vs {lin}",
            net.node_names()[i]
        );
    }
    assert!(
        ss.iter().any(|t| *t > 30.0),
        "the sources must heat something: {ss:?}"
    );
}

#[test]
fn steps_reuse_one_factorisation_per_speed() {
    let spec = reference().thermal;
    let mut net = ThermalNetwork::new(&spec, 20.0).unwrap();
    run(&mut net, 600.0, 8000.0);
    assert_eq!(net.cached_operator_count(), 1);
    run(&mut net, 600.0, 0.0);
    run(&mut net, 600.0, 8000.0);
    assert_eq!(net.cached_operator_count(), 2);
}

/// Time (s) for `node` to reach 63.2 % of its steady-state rise under constant activity.
fn time_constant_s(spec: &ThermalSpec, node: &str, a: &Activity) -> f64 {
    let mut spec = spec.clone();
    spec.step_s = 10.0;
    let mut net = ThermalNetwork::new(&spec, 20.0).unwrap();
    let i = net.node_index(node).unwrap();
    let target = 20.0 + 0.632 * (net.steady_state_degc(a, 20.0).unwrap()[i] - 20.0);
    while net.temps_degc()[i] < target && net.time_s() < 30.0 * 86_400.0 {
        net.advance(10.0, a).unwrap();
    }
    net.time_s()
}

#[test]
fn reference_warm_up_matches_the_study_figures() {
    let spec = reference().thermal;
    let mut net = ThermalNetwork::new(&spec, 20.0).unwrap();
    let show = [
        "spindle_front_bearing",
        "spindle_rear_bearing",
        "spindle_motor",
        "spindle_nose",
        "spindle_housing",
        "headstock_left",
        "headstock_right",
        "headstock_front",
        "headstock_back",
        "column_top_front",
        "column_top_back",
        "column_mid_front",
        "column_mid_back",
        "column_bottom_front",
        "column_bottom_back",
        "x_motor",
        "x_support",
        "x_screw_0",
        "x_screw_2",
        "x_screw_4",
        "y_motor",
        "y_support",
        "y_screw_1",
        "z_motor",
        "z_support",
        "z_screw_2",
        "saddle",
        "table",
        "bed_top",
        "bed_bottom",
        "work_zone",
    ];
    let marks_h = [0.5, 1.0, 2.0, 4.0, 5.0, 6.0, 8.0];
    let mut table = vec![Vec::new(); show.len()];
    let mut at_4h = Vec::new();
    let started = std::time::Instant::now();
    for &h in &marks_h {
        // 4 h at 9000 rpm with the calibration duty, then everything stopped (cool-down).
        let warm = (4.0 * 3600.0 - net.time_s())
            .max(0.0)
            .min(h * 3600.0 - net.time_s());
        run(&mut net, warm, 9000.0);
        let still = h * 3600.0 - net.time_s();
        if still > 0.0 {
            net.advance(still, &Activity::default()).unwrap();
        }
        for (row, name) in table.iter_mut().zip(show) {
            row.push(t(&net, name));
        }
        if h == 4.0 {
            at_4h = net.temps_degc().to_vec();
        }
    }
    let elapsed_ms = started.elapsed().as_secs_f64() * 1e3;
    let mid = duty(0.0, 9000.0);
    println!(
        "\n8 h of 1 s steps ({} nodes): {elapsed_ms:.1} ms wall (this build)",
        net.node_names().len()
    );
    println!("\nReference warm-up: 9000 rpm, X/Y/Z 4000/3000/2000 mm/min, 0–4 h; stop 4–8 h");
    print!("{:<22}", "node  (°C) \\ h");
    marks_h.iter().for_each(|h| print!("{h:>7.1}"));
    println!("{:>10}", "τ63 (min)");
    for (row, name) in table.iter().zip(show) {
        print!("{name:<22}");
        row.iter().for_each(|v| print!("{v:>7.2}"));
        println!("{:>10.0}", time_constant_s(&spec, name, &mid) / 60.0);
    }
    let at = |name: &str| at_4h[net.node_index(name).unwrap()];
    // Study: near the spindle ~30 °C, along the axes ~26 °C, work zone < 23 °C.
    assert!(
        (28.0..34.0).contains(&at("spindle_housing")),
        "{}",
        at("spindle_housing")
    );
    assert!(at("spindle_front_bearing") > at("spindle_housing"));
    for n in [
        "x_motor",
        "y_motor",
        "z_motor",
        "x_screw_2",
        "y_screw_1",
        "z_screw_2",
    ] {
        assert!((24.0..28.5).contains(&at(n)), "{n}: {}", at(n));
    }
    assert!(at("work_zone") < 23.0, "{}", at("work_zone"));
    let gradient = at("column_top_front") - at("column_top_back");
    assert!(
        (1.0..3.0).contains(&gradient),
        "column front–back {gradient}"
    );
    // Time constants: spindle 30–60 min, column several hours.
    let tau_spindle = time_constant_s(&spec, "spindle_housing", &mid) / 60.0;
    assert!((30.0..60.0).contains(&tau_spindle), "{tau_spindle}");
    let tau_column = time_constant_s(&spec, "column_mid_back", &mid) / 3600.0;
    assert!(tau_column > 3.0, "{tau_column} h");
    // Cool-down: 4 h after stopping the spindle is back within 40 % of its rise.
    let i = net.node_index("spindle_housing").unwrap();
    assert!(net.temps_degc()[i] - 20.0 < 0.4 * (at("spindle_housing") - 20.0));
}
