//! Tests of the hybrid predictor: training on the synthetic calibration data, the model file
//! (versions, reversal, history features), tool changes and the error messages.

use super::super::testdata as td;
use super::*;

/// The default-settings model on four synthetic cycles, trained once for all tests.
fn trained() -> (HybridPredictor, TrainSummary) {
    static MODEL: std::sync::OnceLock<(HybridPredictor, TrainSummary)> = std::sync::OnceLock::new();
    MODEL
        .get_or_init(|| {
            let ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
            train_hybrid(&ds, &td::geometry(), &Settings::default()).unwrap()
        })
        .clone()
}

/// RMS of the prediction error and of the true error (µm) on a held-out cycle, with the
/// readings transformed by `tweak` before they reach the predictor.
fn held_out_rms(p: &mut HybridPredictor, tweak: impl Fn(&[f64]) -> Vec<f64>) -> (f64, f64) {
    let pairs: Vec<_> = td::held_out(6.0, 5)
        .into_iter()
        .map(|(q, t, e)| (td::predict_at(&mut *p, q, &tweak(&t)), e))
        .collect();
    td::rms_um(&pairs)
}

#[test]
fn a_version_5_file_reads_as_plain_parts_and_predicts_as_written() {
    // A model trained without the products, written as version 5 did (no `bilinear`).
    let ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
    let plain = Settings {
        axis_bilinear: false,
        hidden_candidates: vec![6],
        max_epochs: 20,
        ..Settings::default()
    };
    let (mut p, _) = train_hybrid(&ds, &td::geometry(), &plain).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&p.to_json_string().unwrap()).unwrap();
    v["version"] = 5.into();
    let model = v["model"].as_object_mut().unwrap();
    for part in model["axis_nets"].as_array_mut().unwrap() {
        assert_eq!(
            part.as_object_mut().unwrap().remove("bilinear"),
            Some(false.into())
        );
    }
    model["spindle_net"]
        .as_object_mut()
        .unwrap()
        .remove("bilinear");
    let mut old = HybridPredictor::from_json_str(&v.to_string()).unwrap();
    let hot = td::temps_degc(6.0, 7200.0);
    old.observe_readings(0.0, &hot);
    p.observe_readings(0.0, &hot);
    for q in [[100.0, 50.0, -80.0], [400.0, 300.0, -300.0]] {
        assert_eq!(old.predict_error_mm(q), p.predict_error_mm(q));
    }
}

#[test]
fn another_tool_gives_the_model_calibrated_with_that_tool() {
    // The parts learn elementary errors, which do not depend on the tool: a model moved to
    // a 250 mm tool predicts exactly what one trained with that tool predicts, and differs
    // from the 150 mm model by the angular errors times the extra 100 mm arm.
    let ds = td::dataset(&[4.0, 7.0, 5.5], 3);
    let quick = Settings {
        hidden_candidates: vec![6],
        max_epochs: 20,
        ..Settings::default()
    };
    let (p150, _) = train_hybrid(&ds, &td::geometry(), &quick).unwrap();
    let long = MachineGeometry {
        tool_offset_mm: [0.0, 0.0, -250.0],
        ..td::geometry()
    };
    let (mut p250, _) = train_hybrid(&ds, &long, &quick).unwrap();
    let mut moved = p150.with_tool_offset_mm([0.0, 0.0, -250.0]).unwrap();
    assert_eq!(moved.geometry(), &long);
    let mut p150 = p150;
    let hot = td::temps_degc(6.0, 7200.0);
    for p in [&mut moved, &mut p250, &mut p150] {
        p.observe_readings(0.0, &hot);
    }
    for q in [[100.0, 50.0, -80.0], [400.0, 300.0, -300.0]] {
        let m = moved.predict_error_mm(q);
        assert_eq!(m, p250.predict_error_mm(q));
        let short = p150.predict_error_mm(q);
        assert!(
            (0..3).any(|k| (m[k] - short[k]).abs() > 1e-6),
            "{m:?} vs {short:?}"
        );
    }
    assert!(p150.with_tool_offset_mm([0.0, f64::NAN, -250.0]).is_err());
    // A tool change in the loop (M6) keeps what the model has observed: no new readings
    // needed before it predicts for the new tool.
    let mut changed = p150.clone();
    changed.change_tool([0.0, 0.0, -250.0]).unwrap();
    let q = [250.0, 120.0, -200.0];
    assert_eq!(changed.predict_error_mm(q), p250.predict_error_mm(q));
    assert!(changed.change_tool([f64::NAN, 0.0, -250.0]).is_err());
}

#[test]
fn the_reversal_is_learned_from_alternating_sweeps_and_survives_the_model_file() {
    // Every other measurement round sweeps backward: the positioning reading shifts by R.
    let truth_um = [-0.5, -0.6, -0.4];
    let mut ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
    for r in &mut ds.records {
        let k = match r.instrument {
            Instrument::LaserX => 0,
            Instrument::LaserY => 1,
            Instrument::LaserZ => 2,
            _ => continue,
        };
        if (r.time_s / 1200.0).round() as usize % 2 == 1 {
            r.dir = -1;
            r.values[k] += truth_um[k];
        }
    }
    let quick = Settings {
        hidden_candidates: vec![6],
        max_epochs: 20,
        ..Settings::default()
    };
    let (p, _) = train_hybrid(&ds, &td::geometry(), &quick).unwrap();
    let r = p.reversal_um();
    for k in 0..3 {
        // The laser noise is 0.1 µm per reading over ~150 backward readings per axis.
        assert!((r[k] - truth_um[k]).abs() < 0.05, "axis {k}: {r:?}");
    }
    // At the tool: X and Y move the table (E = −δ), Z the head (E = +δ); mm.
    let shift = p.negative_approach_shift_mm();
    let expected = [-r[0] * 1e-3, -r[1] * 1e-3, r[2] * 1e-3];
    for k in 0..3 {
        assert!((shift[k] - expected[k]).abs() < 1e-12, "{shift:?}");
    }
    // The model file keeps it; a version 2 file (no `reversal_um`) reads with zero.
    let text = p.to_json_string().unwrap();
    let back = HybridPredictor::from_json_str(&text).unwrap();
    assert_eq!(back.reversal_um(), r);
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["version"] = 2.into();
    v["model"].as_object_mut().unwrap().remove("reversal_um");
    let old = HybridPredictor::from_json_str(&v.to_string()).unwrap();
    assert_eq!(old.reversal_um(), [0.0; 3]);
    assert_eq!(old.negative_approach_shift_mm(), [0.0; 3]);
    // Without backward runs the reversal is zero.
    let forward_only = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
    let (p, _) = train_hybrid(&forward_only, &td::geometry(), &quick).unwrap();
    assert_eq!(p.reversal_um(), [0.0; 3]);
}

#[test]
fn history_features_follow_the_observed_readings_and_survive_the_model_file() {
    let ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
    let settings = Settings {
        hidden_candidates: vec![6],
        max_epochs: 20,
        history_taus_s: vec![1800.0],
        ..Settings::default()
    };
    let (mut p, _) = train_hybrid(&ds, &td::geometry(), &settings).unwrap();
    assert_eq!(p.parts().history_taus_s, vec![1800.0]);
    let mut back = HybridPredictor::from_json_str(&p.to_json_string().unwrap()).unwrap();
    let q = [100.0, 50.0, -80.0];
    let hot = td::temps_degc(6.0, 7200.0);
    // The readings observed alone: the filters start at them (steady state).
    let mut fresh = p.clone();
    fresh.observe_readings(7200.0, &hot);
    let steady = fresh.predict_error_mm(q);
    // After a warm-up observed from cold up to the same readings, the history features are
    // non-zero.
    for k in 0..=120 {
        let t = 60.0 * f64::from(k);
        let temps = td::temps_degc(6.0, t);
        p.observe_readings(t, &temps);
        back.observe_readings(t, &temps);
    }
    let warmed = p.predict_error_mm(q);
    assert_eq!(warmed, back.predict_error_mm(q));
    assert_ne!(warmed, steady);
    // A bad time constant in a file is refused.
    let mut v: serde_json::Value = serde_json::from_str(&p.to_json_string().unwrap()).unwrap();
    v["model"]["history_taus_s"] = serde_json::json!([-5.0]);
    let err = HybridPredictor::from_json_str(&v.to_string()).unwrap_err();
    assert!(err.to_string().contains("history_taus_s"), "{err}");
    // So is one in the settings.
    let bad = Settings {
        history_taus_s: vec![0.0],
        ..settings
    };
    let err = train_hybrid(&ds, &td::geometry(), &bad).unwrap_err();
    assert!(err.to_string().contains("history_taus_s"), "{err}");
}

#[test]
fn spindle_only_history_reaches_the_spindle_part_alone_and_survives_the_model_file() {
    let ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
    let sensor = ds.sensor_names[1].clone();
    let settings = Settings {
        hidden_candidates: vec![6],
        max_epochs: 20,
        spindle_history_taus_s: vec![300.0],
        spindle_history_sensors: vec![sensor.clone()],
        ..Settings::default()
    };
    let (mut p, _) = train_hybrid(&ds, &td::geometry(), &settings).unwrap();
    let n = ds.sensor_names.len();
    // One more input for the spindle part only.
    assert_eq!(p.parts().spindle_net.linear.n_in(), n + 1);
    for part in &p.parts().axis_nets {
        // Position, readings, and position × readings (bilinear by default).
        assert_eq!(part.linear.n_in(), 1 + n + n);
    }
    assert_eq!(p.parts().squareness.n_in(), n);
    assert_eq!(p.parts().spindle_history_sensors, vec![1]);
    let mut back = HybridPredictor::from_json_str(&p.to_json_string().unwrap()).unwrap();
    let q = [100.0, 50.0, -80.0];
    let hot = td::temps_degc(6.0, 7200.0);
    let mut fresh = p.clone();
    fresh.observe_readings(7200.0, &hot);
    let steady = fresh.elementary_errors(q);
    for k in 0..=120 {
        let t = 60.0 * f64::from(k);
        let temps = td::temps_degc(6.0, t);
        p.observe_readings(t, &temps);
        back.observe_readings(t, &temps);
    }
    let warmed = p.elementary_errors(q);
    assert_eq!(warmed, back.elementary_errors(q));
    // The history moves the spindle drift and leaves the axis parts alone.
    assert_ne!(warmed.spindle, steady.spindle);
    assert_eq!(warmed.axes, steady.axes);
    // A sensor the model lacks is named in the error.
    let bad = Settings {
        spindle_history_sensors: vec!["nope".into()],
        ..settings
    };
    let err = train_hybrid(&ds, &td::geometry(), &bad).unwrap_err();
    assert!(err.to_string().contains("spindle_history_sensors"), "{err}");
    assert!(err.to_string().contains("nope"), "{err}");
}

#[test]
fn spindle_speed_features_reach_the_spindle_part_alone_and_survive_the_model_file() {
    let mut ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
    let settings = Settings {
        hidden_candidates: vec![6],
        max_epochs: 20,
        ..Settings::default()
    }
    .with_spindle_speed_input();
    // Without the `spindle_rpm` column the error names the first record lacking it.
    let err = train_hybrid(&ds, &td::geometry(), &settings).unwrap_err();
    assert!(
        matches!(err, PredictError::MissingSpindleSpeed { index: 0, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("spindle_rpm"), "{err}");
    // A logged speed: running in the first hour of each cycle.
    for r in &mut ds.records {
        r.spindle_rpm = Some(if r.time_s < 3600.0 { 6000.0 } else { 0.0 });
    }
    let (mut p, _) = train_hybrid(&ds, &td::geometry(), &settings).unwrap();
    let n = ds.sensor_names.len();
    // Per exponent (1, 2, 3): the present heat input and three filters.
    assert_eq!(p.parts().spindle_net.linear.n_in(), n + 3 * 4);
    for part in &p.parts().axis_nets {
        assert_eq!(part.linear.n_in(), 1 + n + n);
    }
    assert_eq!(p.parts().squareness.n_in(), n);
    let text = p.to_json_string().unwrap();
    let mut back = HybridPredictor::from_json_str(&text).unwrap();
    let q = [100.0, 50.0, -80.0];
    let hot = td::temps_degc(6.0, 7200.0);
    p.observe_readings(0.0, &hot);
    back.observe_readings(0.0, &hot);
    let rest = p.elementary_errors(q);
    for k in 0..=30 {
        let t = 60.0 * f64::from(k);
        p.observe_spindle_speed(t, 9000.0);
        back.observe_spindle_speed(t, 9000.0);
    }
    // The same readings: the speed alone moves the prediction.
    let ran = p.elementary_errors(q);
    assert_eq!(ran, back.elementary_errors(q));
    // The speed moves the spindle drift and leaves the axis parts alone.
    assert_ne!(ran.spindle, rest.spindle);
    assert_eq!(ran.axes, rest.axes);
    assert_eq!(ran.squareness, rest.squareness);
    // A model without speed features ignores the speed.
    let (mut plain, _) = train_hybrid(
        &ds,
        &td::geometry(),
        &Settings {
            hidden_candidates: vec![6],
            max_epochs: 20,
            ..Settings::default()
        },
    )
    .unwrap();
    plain.observe_readings(0.0, &hot);
    let before = plain.elementary_errors(q);
    plain.observe_spindle_speed(0.0, 0.0);
    plain.observe_spindle_speed(600.0, 9000.0);
    assert_eq!(plain.elementary_errors(q), before);
    assert!(!plain.to_json_string().unwrap().contains("spindle_speed"));
}

#[test]
fn own_axis_feeds_reach_that_axis_part_alone_and_survive_the_model_file() {
    let mut ds = td::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
    // Each cycle runs one axis in its first two hours (cycle c: axis c mod 3).
    for r in &mut ds.records {
        let c: usize = r.cycle.trim_start_matches("cycle").parse().unwrap();
        let mut f = [0.0; 3];
        if r.time_s < 7200.0 {
            f[c % 3] = 4000.0;
        }
        r.axis_feed_mm_per_min = Some(f);
    }
    let settings = Settings {
        hidden_candidates: vec![6],
        max_epochs: 20,
        axis_feed_taus_s: vec![600.0, 3600.0],
        axis_feed_own_axis: true,
        ..Settings::default()
    };
    let (mut p, _) = train_hybrid(&ds, &td::geometry(), &settings).unwrap();
    let n = ds.sensor_names.len();
    // Axis parts: position, readings, own feed's two filters (bilinear: × position too).
    for part in &p.parts().axis_nets {
        assert_eq!(part.linear.n_in(), 1 + (n + 2) + (n + 2));
    }
    assert_eq!(p.parts().spindle_net.linear.n_in(), n);
    assert_eq!(p.parts().squareness.n_in(), n);
    let text = p.to_json_string().unwrap();
    assert!(text
        .replace(char::is_whitespace, "")
        .contains("\"axis_feed_own_axis\":true"));
    let mut back = HybridPredictor::from_json_str(&text).unwrap();
    let q = [100.0, 50.0, -80.0];
    let hot = td::temps_degc(6.0, 7200.0);
    p.observe_readings(0.0, &hot);
    back.observe_readings(0.0, &hot);
    let rest = p.elementary_errors(q);
    for k in 0..=30 {
        let t = 60.0 * f64::from(k);
        p.observe_axis_feeds(t, [0.0, 0.0, 5000.0]);
        back.observe_axis_feeds(t, [0.0, 0.0, 5000.0]);
    }
    let ran = p.elementary_errors(q);
    assert_eq!(ran, back.elementary_errors(q));
    // Z's traffic moves the Z part only.
    assert_ne!(ran.axes[2], rest.axes[2]);
    assert_eq!(ran.axes[0], rest.axes[0]);
    assert_eq!(ran.axes[1], rest.axes[1]);
    assert_eq!(ran.spindle, rest.spindle);
    assert_eq!(ran.squareness, rest.squareness);
}

#[test]
fn hybrid_predicts_a_held_out_cycle_within_half_a_micrometre_rms() {
    let (mut p, summary) = trained();
    let (err, truth) = held_out_rms(&mut p, |t| t.to_vec());
    // True E is several µm RMS; the prediction must be within 0.5 µm RMS (instrument noise
    // is 0.1–0.2 µm) and remove ≥ 90 % of it.
    assert!(truth > 5.0, "truth RMS {truth} µm");
    assert!(
        err < 0.5,
        "prediction RMS error {err} µm vs truth {truth} µm\n{summary:#?}"
    );
    assert!(err < 0.1 * truth);
    assert_eq!(summary.val_cycles, vec!["cycle3".to_string()]);
    assert_eq!(summary.nets.len(), 5);
    for n in &summary.nets {
        assert_eq!(n.train_rmse.len(), n.outputs.len());
        assert_eq!(n.val_rmse.len(), n.outputs.len());
        assert!(n.n_val > 0 && n.n_train > 2 * n.n_val, "{n:?}");
    }
}

#[test]
fn zeroed_or_shuffled_temperatures_degrade_the_hybrid() {
    let (mut p, _) = trained();
    let (good, _) = held_out_rms(&mut p, |t| t.to_vec());
    let (zeroed, _) = held_out_rms(&mut p, |t| vec![20.0; t.len()]);
    let (shuffled, _) = held_out_rms(&mut p, |t| vec![t[2], t[0], t[3], t[1]]);
    assert!(
        zeroed > 5.0 * good,
        "good {good} µm, ambient-only {zeroed} µm"
    );
    assert!(
        shuffled > 5.0 * good,
        "good {good} µm, shuffled {shuffled} µm"
    );
}

#[test]
fn the_spindle_and_squareness_parts_follow_their_truth() {
    let (mut p, _) = trained();
    let temps = td::temps_degc(6.0, 7200.0);
    p.observe_readings(0.0, &temps);
    let e = p.elementary_errors([100.0, 100.0, -100.0]);
    let sp = td::spindle(&temps);
    let sq = td::squareness(&temps);
    // δz_b is tens of µm here; 0.5 µm and 0.5 µrad tolerances (noise 0.2).
    assert!(
        (e.spindle.lin_mm[2] * 1e3 - sp[2]).abs() < 0.5,
        "{e:?} {sp:?}"
    );
    assert!(
        (e.squareness.xy_rad * 1e6 - sq[2]).abs() < 0.5,
        "{e:?} {sq:?}"
    );
    assert!(
        (e.squareness.yz_rad * 1e6 - sq[0]).abs() < 0.5,
        "{e:?} {sq:?}"
    );
}

#[test]
fn same_seed_gives_identical_weights_and_another_seed_does_not() {
    let ds = td::dataset(&[4.0, 7.0, 5.5], 3);
    let s = Settings {
        hidden_candidates: vec![6],
        max_epochs: 20,
        ..Settings::default()
    };
    let (a, _) = train_hybrid(&ds, &td::geometry(), &s).unwrap();
    let (b, _) = train_hybrid(&ds, &td::geometry(), &s).unwrap();
    assert_eq!(a.parts(), b.parts());
    let (c, _) = train_hybrid(&ds, &td::geometry(), &Settings { seed: 1, ..s }).unwrap();
    assert_ne!(a.parts().axis_nets[0], c.parts().axis_nets[0]);
}

#[test]
fn a_dataset_without_spindle_records_is_named_in_the_error() {
    let mut ds = td::dataset(&[4.0, 7.0], 1);
    ds.records.retain(|r| r.instrument != Instrument::Spindle);
    let err = train_hybrid(&ds, &td::geometry(), &Settings::default()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "the dataset has no `spindle` records (needed for the spindle network)"
    );
}

#[test]
fn too_few_laser_records_are_rejected() {
    let mut ds = td::dataset(&[4.0, 7.0], 1);
    let mut kept = 0;
    ds.records.retain(|r: &Record| {
        if r.instrument != Instrument::LaserY {
            return true;
        }
        kept += 1;
        kept <= 7
    });
    let err = train_hybrid(&ds, &td::geometry(), &Settings::default()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "the dataset has 7 `laser_y` records, at least 20 are needed"
    );
}

#[test]
fn asking_for_a_sensor_the_dataset_lacks_lists_both_sets() {
    let ds = td::dataset(&[4.0, 7.0], 1);
    let s = Settings {
        sensors: vec!["S1".into(), "XD".into()],
        ..Settings::default()
    };
    let err = train_hybrid(&ds, &td::geometry(), &s).unwrap_err();
    assert_eq!(
        err.to_string(),
        "sensor columns differ from what is asked: missing [\"XD\"]; asked for [\"S1\", \
         \"XD\"], the dataset has [\"S1\", \"S2\", \"S3\", \"Amb\"]"
    );
}

#[test]
fn an_empty_laser_cell_is_reported_with_its_record() {
    let mut ds = td::dataset(&[4.0, 7.0], 1);
    if let Some(r) = ds
        .records
        .iter_mut()
        .find(|r| r.instrument == Instrument::LaserZ)
    {
        r.values[4] = f64::NAN;
    }
    let err = train_hybrid(&ds, &td::geometry(), &Settings::default()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "`laser_z` record of cycle \"cycle0\" at t = 0 s has no `ry_urad` value"
    );
}
