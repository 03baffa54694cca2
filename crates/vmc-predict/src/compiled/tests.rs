//! Tests of the compiled model against the library's query path (`HybridPredictor` and
//! `Compensator`), on hybrid models trained on the crate's synthetic calibration data.

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use super::*;
use crate::controller::{Compensator, Controller};
use crate::dataset::Dataset;
use crate::predictor::testdata as td;
use crate::predictor::{train_hybrid, train_linear, train_volumetric, Settings};

/// 1e-12 µm in mm: the agreement asked of the compiled form's predicted error (round-off of
/// ~10 µm values).
const SAME_MM: f64 = 1e-15;

/// Whether two axis commands (mm) are the same but for the rounding of `q = p − E`: an `E` that
/// differs in its last bits may round `q` (hundreds of mm, ulp ~1e-13 mm) to the neighbouring
/// double, so a command is compared to within `SAME_MM` plus one rounding of its own size.
fn same_command(a: f64, b: f64) -> bool {
    (a - b).abs() <= SAME_MM + f64::EPSILON * a.abs().max(b.abs())
}

/// Quick settings that keep every residual net (so the query evaluates tanh units).
fn with_nets(hidden: usize) -> Settings {
    Settings {
        hidden_candidates: vec![hidden],
        max_epochs: 15,
        residual_net_min_gain: f64::NEG_INFINITY,
        ..Settings::default()
    }
}

/// The synthetic dataset with a logged spindle speed and axis feeds (a duty per cycle hour).
fn dataset_with_commands() -> Dataset {
    let mut ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
    for r in &mut ds.records {
        let hour = (r.time_s / 3600.0).floor();
        r.spindle_rpm = Some(if hour < 2.0 {
            3000.0 * (hour + 1.0)
        } else {
            0.0
        });
        r.axis_feed_mm_per_min = Some([2000.0 * (hour % 2.0), 500.0 * hour, 300.0]);
    }
    ds
}

/// Every feature the hybrid has: shared and spindle-only history, speed and feed filters.
fn all_features(own_axis: bool) -> Settings {
    Settings {
        history_taus_s: vec![1800.0],
        history_sensors: vec!["Amb".into()],
        spindle_history_taus_s: vec![300.0],
        spindle_history_sensors: vec!["S1".into()],
        axis_feed_taus_s: vec![3600.0],
        axis_feed_own_axis: own_axis,
        ..with_nets(10)
    }
    .with_spindle_speed_input()
}

/// Drives the library model and the compiled one through the same hours of readings, speeds,
/// feeds and commanded positions (random, with reversals; each coordinate held from the previous
/// query one time in three, as an axis at rest, so a solve also starts from its kept first
/// evaluation; one query in eight beyond the travel, where units saturate), comparing every prediction and every
/// compensated command (to [`same_command`]); returns the largest difference of the
/// predictions, mm.
fn compare(lib: HybridPredictor, compiled: CompiledHybrid, seed: u64) -> f64 {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut lib = Compensator::new(lib);
    let mut fast = CompiledCompensator::new(compiled);
    let mut worst_e = 0.0_f64;
    // Kept across new readings: a held coordinate's kept evaluation must not outlive them.
    let mut prev = td::random_q(&mut rng);
    for step in 0..40 {
        let t_s = 300.0 * f64::from(step);
        let temps = td::temps_degc(6.0, t_s);
        let rpm = if step % 7 < 4 { 8000.0 } else { 0.0 };
        let feeds = [1500.0, 200.0 * f64::from(step % 3), 50.0];
        for c in [&mut lib as &mut dyn Controller, &mut fast] {
            c.on_readings(t_s, &temps);
            c.on_spindle_speed(t_s, rpm);
            c.on_axis_feeds(t_s, feeds);
        }
        for _ in 0..25 {
            let mut p = td::random_q(&mut rng);
            for k in 0..3 {
                match rng.random_range(0..24) {
                    0..8 => p[k] = prev[k],
                    8..11 => p[k] *= 4.0,
                    _ => {}
                }
            }
            prev = p;
            let e_lib = lib.predictor_mut().predict_error_mm(p);
            let e_fast = fast.model_mut().predict_error_mm(p);
            let q_lib = lib.axis_command_mm(p);
            let q_fast = fast.axis_command_mm(p);
            assert_eq!(lib.last_solve().iterations, fast.last_solve().iterations);
            assert_eq!(lib.approach_directions(), fast.approach_directions());
            for k in 0..3 {
                assert!(e_lib[k].is_finite() && q_lib[k].is_finite(), "{e_lib:?}");
                worst_e = worst_e.max((e_lib[k] - e_fast[k]).abs());
                assert!(same_command(q_lib[k], q_fast[k]), "{q_lib:?} {q_fast:?}");
            }
        }
    }
    worst_e
}

#[test]
fn the_compiled_model_predicts_and_compensates_as_the_query_path_to_1e_12_um() {
    let ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
    let (p, _) = train_hybrid(&ds, &td::geometry(), &with_nets(10)).unwrap();
    let c = CompiledHybrid::from_predictor(&p).unwrap();
    assert_eq!(c.hidden_units(), [10; 3]);
    // Both instantiations of the query code (the detected one is the portable one on a CPU
    // without AVX2 and FMA).
    let portable = c.clone().with_portable_code();
    assert_eq!(portable.instruction_set(), "portable");
    for c in [c, portable] {
        let e = compare(p.clone(), c, 1);
        assert!(e < SAME_MM, "E {e:e} mm");
    }
}

#[test]
fn every_feature_of_the_hybrid_compiles_to_the_same_numbers() {
    let ds = dataset_with_commands();
    for own_axis in [false, true] {
        let (p, _) = train_hybrid(&ds, &td::geometry(), &all_features(own_axis)).unwrap();
        assert!(p.parts().spindle_net.net.is_some());
        let c = CompiledHybrid::from_predictor(&p).unwrap();
        let e = compare(p, c, 2);
        assert!(e < SAME_MM, "own {own_axis}: E {e:e} mm");
    }
}

#[test]
fn linear_only_parts_and_an_odd_hidden_width_compile_too() {
    let ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
    // A gain no net reaches: every part is its linear model alone.
    let linear_only = Settings {
        residual_net_min_gain: 2.0,
        ..with_nets(6)
    };
    let (p, _) = train_hybrid(&ds, &td::geometry(), &linear_only).unwrap();
    let c = CompiledHybrid::from_predictor(&p).unwrap();
    assert_eq!(c.hidden_units(), [0; 3]);
    let e = compare(p, c, 3);
    assert!(e < SAME_MM, "E {e:e} mm");
    // 7 units: padded to 8 with units that add exactly nothing.
    let (p, _) = train_hybrid(&ds, &td::geometry(), &with_nets(7)).unwrap();
    let c = CompiledHybrid::from_predictor(&p).unwrap();
    assert_eq!(c.hidden_units(), [7; 3]);
    let e = compare(p, c, 4);
    assert!(e < SAME_MM, "E {e:e} mm");
}

#[test]
fn a_step_too_large_for_the_polynomial_takes_the_fresh_path_and_agrees() {
    // A reversal of 5 mm moves the second iterate ~5 mm from the first: far beyond the
    // polynomial's range for every unit.
    let ds = td::dataset(&[4.0, 7.0, 5.5], 5);
    let (p, _) = train_hybrid(&ds, &td::geometry(), &with_nets(6)).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&p.to_json_string().unwrap()).unwrap();
    v["model"]["reversal_um"] = serde_json::json!([5000.0, -4000.0, 3000.0]);
    let p = HybridPredictor::from_json_str(&v.to_string()).unwrap();
    let c = CompiledHybrid::from_predictor(&p).unwrap();
    let mut lib = Compensator::new(p).with_start_mm([600.0, 500.0, 0.0]);
    let mut fast = CompiledCompensator::new(c).with_start_mm([600.0, 500.0, 0.0]);
    let temps = td::temps_degc(5.0, 4000.0);
    lib.on_readings(0.0, &temps);
    fast.on_readings(0.0, &temps);
    for p_mm in [[300.0, 200.0, -100.0], [250.0, 150.0, -150.0]] {
        let (a, b) = (lib.axis_command_mm(p_mm), fast.axis_command_mm(p_mm));
        assert_eq!(fast.approach_directions(), [-1.0, -1.0, -1.0]);
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < SAME_MM, "{a:?} {b:?}");
            assert!(
                (a[k] - p_mm[k]).abs() > 2.0,
                "the reversal must show: {a:?}"
            );
        }
        assert_eq!(lib.last_solve(), fast.last_solve());
    }
}

#[test]
fn the_model_file_compiles_and_the_baselines_are_refused_by_name() {
    let ds = td::dataset(&[4.0, 7.0], 2);
    let g = td::geometry();
    let (h, _) = train_hybrid(&ds, &g, &with_nets(6)).unwrap();
    let text = h.to_json_string().unwrap();
    let mut from_file = CompiledHybrid::from_model_file(&text).unwrap();
    let mut from_model = CompiledHybrid::from_predictor(&h).unwrap();
    let temps = td::temps_degc(4.0, 3600.0);
    from_file.observe_readings(0.0, &temps);
    from_model.observe_readings(0.0, &temps);
    let q = [120.0, 80.0, -300.0];
    assert_eq!(
        from_file.predict_error_mm(q),
        from_model.predict_error_mm(q)
    );
    assert_eq!(from_file.sensor_names(), h.sensor_names());
    let (v, _) = train_volumetric(&ds, &g, &with_nets(6)).unwrap();
    let (l, _) = train_linear(&ds, &g, &with_nets(6)).unwrap();
    for (text, kind) in [
        (v.to_json_string().unwrap(), "volumetric"),
        (l.to_json_string().unwrap(), "linear"),
    ] {
        let err = CompiledHybrid::from_model_file(&text).unwrap_err();
        assert!(matches!(err, CompileError::NotHybrid { .. }), "{err}");
        assert!(
            err.to_string()
                .starts_with(&format!("a `{kind}` model cannot be compiled")),
            "{err}"
        );
    }
    let err = CompiledHybrid::from_model_file("{ not json").unwrap_err();
    assert!(err.to_string().starts_with("model file: "), "{err}");
}

#[test]
fn a_net_trained_with_the_approximate_tanh_is_refused() {
    let ds = td::dataset(&[4.0, 7.0], 2);
    let (h, _) = train_hybrid(&ds, &td::geometry(), &with_nets(6)).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&h.to_json_string().unwrap()).unwrap();
    v["model"]["axis_nets"][1]["net"]["mlp"]["activation"] = "FastTanh".into();
    let err = CompiledHybrid::from_model_file(&v.to_string()).unwrap_err();
    assert_eq!(err, CompileError::ApproximateActivation { net: "axis_y" });
}

#[test]
fn a_warm_predictor_compiles_warm() {
    let ds = dataset_with_commands();
    let (mut p, _) = train_hybrid(&ds, &td::geometry(), &all_features(false)).unwrap();
    for step in 0..30 {
        let t_s = 240.0 * f64::from(step);
        p.observe_readings(t_s, &td::temps_degc(7.0, t_s));
        p.observe_spindle_speed(t_s, 9000.0);
        p.observe_axis_feeds(t_s, [3000.0, 0.0, 800.0]);
    }
    let mut c = CompiledHybrid::from_predictor(&p).unwrap();
    let mut cold = HybridPredictor::from_json_str(&p.to_json_string().unwrap()).unwrap();
    cold.observe_readings(7200.0, &td::temps_degc(7.0, 7200.0));
    let q = [400.0, 100.0, -50.0];
    let (warm_e, fast_e) = (p.predict_error_mm(q), c.predict_error_mm(q));
    for k in 0..3 {
        assert!(
            (warm_e[k] - fast_e[k]).abs() < SAME_MM,
            "{warm_e:?} {fast_e:?}"
        );
    }
    assert_ne!(
        cold.predict_error_mm(q),
        warm_e,
        "the history must matter here"
    );
}

#[test]
fn the_compiled_model_follows_a_tool_change() {
    let ds = td::dataset(&[4.0, 7.0], 2);
    let (p, _) = train_hybrid(&ds, &td::geometry(), &with_nets(6)).unwrap();
    let mut c = CompiledHybrid::from_predictor(&p).unwrap();
    let mut moved = p.with_tool_offset_mm([5.0, -3.0, -250.0]).unwrap();
    c.change_tool([5.0, -3.0, -250.0]).unwrap();
    let temps = td::temps_degc(4.0, 5000.0);
    c.observe_readings(0.0, &temps);
    moved.observe_readings(0.0, &temps);
    let q = [10.0, 390.0, -440.0];
    let (a, b) = (moved.predict_error_mm(q), c.predict_error_mm(q));
    for k in 0..3 {
        assert!((a[k] - b[k]).abs() < SAME_MM, "{a:?} {b:?}");
    }
    assert_eq!(
        c.set_tool_offset_mm([0.0, f64::INFINITY, 0.0]),
        Err(InputError::ToolOffset)
    );
    assert!(c.change_tool([f64::NAN, 0.0, 0.0]).is_err());
}

#[test]
fn before_any_reading_the_prediction_is_nan_and_a_wrong_count_is_refused() {
    let ds = td::dataset(&[4.0, 7.0], 2);
    let (p, _) = train_hybrid(&ds, &td::geometry(), &with_nets(6)).unwrap();
    let mut c = CompiledHybrid::from_predictor(&p).unwrap();
    assert!(!c.has_readings());
    assert!(c
        .predict_error_mm([1.0, 2.0, -3.0])
        .iter()
        .all(|e| e.is_nan()));
    assert_eq!(
        c.try_observe_readings(0.0, &[20.0; 3]),
        Err(InputError::ReadingCount {
            expected: 4,
            got: 3
        })
    );
    assert!(!c.has_readings());
    c.try_observe_readings(0.0, &[20.0; 4]).unwrap();
    assert!(c.has_readings());
    assert!(c
        .predict_error_mm([1.0, 2.0, -3.0])
        .iter()
        .all(|e| e.is_finite()));
    assert_eq!(
        InputError::ReadingCount {
            expected: 4,
            got: 3
        }
        .to_string(),
        "3 readings given, the model has 4 sensors"
    );
}

#[test]
fn the_query_block_holds_the_padded_parts() {
    let ds = td::dataset(&[4.0, 7.0], 2);
    let (p, _) = train_hybrid(&ds, &td::geometry(), &with_nets(10)).unwrap();
    let c = CompiledHybrid::from_predictor(&p).unwrap();
    // Per axis: a head (416 bytes with its alignment) and 3 blocks of 4 units (416 bytes each).
    assert_eq!(c.query_block_bytes(), 3 * (416 + 3 * 416));
}
