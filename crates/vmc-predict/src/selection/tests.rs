//! Unit tests of the selection on toy datasets.
use super::*;
use crate::dataset::Record;

/// Two cycles; the error follows sensor `b` exactly, `c` is a near-copy of `b`, `a` is noise.
fn toy() -> Dataset {
    let mut records = Vec::new();
    for (cyc, amp) in [("c1", 1.0), ("c2", 2.0), ("c3", 1.5)] {
        for i in 0..40 {
            let t = i as f64 * 60.0;
            let b = 20.0 + amp * (1.0 - (-t / 900.0).exp());
            let a = 20.0 + 0.3 * ((i * 7 % 11) as f64 / 11.0);
            let c = b + 1e-4 * i as f64;
            records.push(Record {
                cycle: cyc.into(),
                time_s: t,
                instrument: Instrument::Spindle,
                pos_mm: [0.0; 3],
                values: [0.0, 0.0, 10.0 * (b - 20.0), f64::NAN, f64::NAN, f64::NAN],
                temps_degc: vec![20.0, a, b, c],
                dir: 1,
                spindle_rpm: None,
                axis_feed_mm_per_min: None,
            });
        }
    }
    Dataset {
        origin: None,
        sensor_names: vec!["ambient".into(), "a".into(), "b".into(), "c".into()],
        records,
    }
}

#[test]
fn the_sensor_that_drives_the_error_is_chosen_first() {
    let cfg = SelectionConfig {
        count: 1,
        ..Default::default()
    };
    let s = select_sensors(&toy(), &cfg).unwrap();
    assert_eq!(s.steps[0].name, "b");
    // The drift is linear in b: held-out error falls to the ridge bias, under 1 nm.
    assert!(s.steps[0].score_um < 1e-3, "{}", s.steps[0].score_um);
    assert!(s.reference_score_um > 1.0);
}

#[test]
fn a_near_copy_of_a_chosen_sensor_is_not_eligible() {
    let cfg = SelectionConfig {
        count: 2,
        ..Default::default()
    };
    let s = select_sensors(&toy(), &cfg).unwrap();
    let names: Vec<_> = s.steps.iter().map(|x| x.name.as_str()).collect();
    assert_eq!(names[1], "a", "c is a copy of b: {names:?}");
    // b explains everything, so a is chosen for coverage, not information.
    assert_eq!(s.steps[0].phase, Phase::Information);
    assert_eq!(s.steps[1].phase, Phase::Coverage);
    let b = s.candidates.iter().find(|c| c.name == "b").unwrap();
    let c = s.candidates.iter().find(|c| c.name == "c").unwrap();
    assert_eq!(b.cluster, c.cluster);
    assert!(b.max_abs_corr > 0.999);
}

#[test]
fn a_channel_of_pure_noise_is_not_a_thermal_error() {
    let mut ds = toy();
    // rx: an angle that only carries instrument noise.
    for (i, r) in ds.records.iter_mut().enumerate() {
        r.values[3] = ((i * 37 % 17) as f64 - 8.0) * 0.05;
    }
    let cfg = SelectionConfig {
        count: 1,
        ..Default::default()
    };
    let s = select_sensors(&ds, &cfg).unwrap();
    assert_eq!(s.n_channels, 1, "only dz drifts");
    assert_eq!(s.n_channels_dropped, 3, "dx, dy (constant) and rx (noise)");
    assert_eq!(s.steps[0].name, "b");
}

#[test]
fn average_linkage_groups_similar_behaviours() {
    // Items 0, 1 move together, 2, 3 together, 4 on its own.
    let r = |a: usize, b: usize| match (a.min(b), a.max(b)) {
        (x, y) if x == y => 1.0,
        (0, 1) => 0.99,
        (2, 3) => 0.95,
        (0 | 1, 2 | 3) => 0.5,
        _ => 0.1,
    };
    let sim: Vec<Vec<f64>> = (0..5).map(|a| (0..5).map(|b| r(a, b)).collect()).collect();
    assert_eq!(
        proposals::average_linkage(&sim, 3),
        vec![vec![0, 1], vec![2, 3], vec![4]]
    );
    assert_eq!(
        proposals::average_linkage(&sim, 2),
        vec![vec![0, 1, 2, 3], vec![4]]
    );
    assert_eq!(proposals::average_linkage(&sim, 9).len(), 5);
}

#[test]
fn cluster_proposals_take_one_sensor_per_cluster() {
    let cfg = SelectionConfig {
        count: 2,
        ..Default::default()
    };
    let s = select_sensors(&toy(), &cfg).unwrap();
    assert_eq!(s.proposals.len(), 5);
    for p in &s.proposals {
        assert_eq!(p.sensors[0], "ambient");
        assert_eq!(p.sensors.len(), 3, "{p:?}");
        assert_eq!(p.ranking.len(), 2);
        if p.rule == Rule::LinearForward {
            assert!(p.clusters.is_empty());
            continue;
        }
        // b and its near-copy c share a cluster; a, the noise, is alone.
        assert_eq!(p.clusters.len(), 2, "{p:?}");
        assert!(p.clusters.contains(&vec!["a".to_string()]), "{p:?}");
        assert!(p.sensors.contains(&"a".to_string()), "{p:?}");
        let mut cl: Vec<usize> = p.ranking.iter().map(|r| r.cluster.unwrap()).collect();
        cl.sort_unstable();
        assert_eq!(cl, [0, 1], "{p:?}");
        // The sensor that drives the error ranks first, with the largest gain.
        assert!(["b", "c"].contains(&p.ranking[0].name.as_str()), "{p:?}");
        assert!(p.ranking[0].gain_um > p.ranking[1].gain_um);
    }
}

#[test]
fn asking_for_more_than_the_candidates_is_an_error() {
    let cfg = SelectionConfig {
        count: 3,
        ..Default::default()
    };
    assert!(matches!(
        select_sensors(&toy(), &cfg),
        Err(SelectionError::NotEnoughCandidates { .. })
    ));
}

#[test]
fn a_single_cycle_cannot_be_cross_validated() {
    let mut ds = toy();
    ds.records.retain(|r| r.cycle == "c1");
    assert_eq!(
        select_sensors(&ds, &SelectionConfig::default()).unwrap_err(),
        SelectionError::TooFewCycles(1)
    );
}

#[test]
fn an_unknown_reference_is_named() {
    let cfg = SelectionConfig {
        reference: vec!["Amb".into()],
        ..Default::default()
    };
    assert_eq!(
        select_sensors(&toy(), &cfg).unwrap_err(),
        SelectionError::UnknownReference("Amb".into())
    );
}
