//! The static-table study through the real binary (`campaign --static-tables`, one seed), and a
//! differential check of the table path against the live hybrid it was sampled from: at the
//! freezing state, the own-axis and cross tables applied as a controller applies them give the
//! hybrid's correction along the axis lines through the tables' reference position, and on a
//! body diagonal its additive part (what any sum of one-axis tables can hold), each within the
//! tables' own interpolation error; per-joint tables lose the cross terms.

mod common;

use common::{ok, refused, vmc, TempDir};
use vmc_machine::machine::MachineSpec;
use vmc_tables::apply::{TableCompensator, TableScope};
use vmc_tables::sample::{sample_tables, TableSet};
use vmc_twin::predict::controller::{Compensator, Controller};
use vmc_twin::predict::predictor::{ErrorPredictor, HybridPredictor};
use vmc_twin::studies::tables::{self, model_at_freezing, sampling_spec};

/// Largest interpolation error of the set's tables, mm, three of them adding up on one output
/// axis, plus 1 nm of quantisation and 1 nm for the lookup at the commanded position instead of
/// the fixed point (`vmc_tables::apply` module doc).
fn bound_mm(set: &TableSet) -> f64 {
    let own = set.own.iter().map(|t| t.check.max_abs_um);
    let cross = set.cross.iter().map(|t| t.check.max_abs_um);
    3.0 * own.chain(cross).fold(0.0, f64::max) * 1e-3 + 2e-6
}

fn correction_mm(c: &mut dyn Controller, p: [f64; 3]) -> [f64; 3] {
    let q = c.axis_command_mm(p);
    std::array::from_fn(|k| q[k] - p[k])
}

fn max_abs_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max)
}

/// The differential check at the warm freezing state of seed 1 with the campaign's hybrid;
/// gives the study's JSON entry for it to compare with.
fn tables_reproduce_the_hybrid_at_their_state(model_json: &str, study: &serde_json::Value) {
    let spec = MachineSpec::reference();
    let hybrid = HybridPredictor::from_json_str(model_json).unwrap();
    let freezing = tables::freezing_states(tables::DEFAULT_WARM_H).unwrap();
    let (warm, state) = &freezing[1];
    assert_eq!(warm.name, "warm");
    let model = model_at_freezing(&spec, 1, 1, state, &hybrid).unwrap();
    let set = sample_tables(&mut model.clone(), &sampling_spec(&spec)).unwrap();
    // The study froze these very tables.
    let entry = study["tables"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["seed"] == 1 && t["frozen"] == "warm")
        .unwrap();
    for k in 0..3 {
        let um = entry["reference_error_um"][k].as_f64().unwrap();
        assert!(
            (um - set.reference_error_mm[k] * 1e3).abs() < 1e-9,
            "{entry}"
        );
    }
    let bound = bound_mm(&set);
    assert!(
        bound < 0.2e-3,
        "10 mm tables follow the hybrid to {bound} mm"
    );
    let mut live = Compensator::new(model.clone());
    let mut all = TableCompensator::new(set.clone(), TableScope::OwnAndCross);
    let r = set.reference_mm;
    let travel = &spec.axes;
    // Along each axis line through the reference, off the table grid (7.3 mm steps), moving
    // positive: own + cross = −E of the hybrid.
    for k in 0..3 {
        let mut x = travel.travel_min_mm[k];
        while x <= travel.travel_max_mm[k] {
            let mut p = r;
            p[k] = x;
            let d = max_abs_diff(correction_mm(&mut all, p), correction_mm(&mut live, p));
            assert!(d <= bound, "axis line {k} at {x} mm: {d} mm > {bound} mm");
            x += 7.3;
        }
    }
    // On the body diagonal (10 % inside the travel), forward: own + cross = the additive part
    // of −E, E(x,r,r) + E(r,y,r) + E(r,r,z) − 2E(r); per-joint tables miss the cross terms.
    let mut m = model.clone();
    let e_ref = m.predict_error_mm(r);
    let (mut all_vs_live, mut own_vs_live, mut all_vs_additive) = (0.0f64, 0.0f64, 0.0f64);
    let mut all_d = TableCompensator::new(set.clone(), TableScope::OwnAndCross);
    let mut own_d = TableCompensator::new(set, TableScope::OwnAxis);
    let mut live_d = Compensator::new(model);
    for i in 0..=100 {
        let f = 0.1 + 0.8 * i as f64 / 100.0;
        let p: [f64; 3] = std::array::from_fn(|k| {
            travel.travel_min_mm[k] + f * (travel.travel_max_mm[k] - travel.travel_min_mm[k])
        });
        let mut additive = [0.0; 3];
        for k in 0..3 {
            let mut q = r;
            q[k] = p[k];
            let e = m.predict_error_mm(q);
            for j in 0..3 {
                additive[j] -= e[j] - e_ref[j];
            }
        }
        for j in 0..3 {
            additive[j] -= e_ref[j];
        }
        let c_live = correction_mm(&mut live_d, p);
        let c_all = correction_mm(&mut all_d, p);
        all_vs_additive = all_vs_additive.max(max_abs_diff(c_all, additive));
        all_vs_live = all_vs_live.max(max_abs_diff(c_all, c_live));
        own_vs_live = own_vs_live.max(max_abs_diff(correction_mm(&mut own_d, p), c_live));
    }
    eprintln!(
        "body diagonal at the warm freezing state: own+cross vs live {:.3} µm, per-joint vs live \
         {:.3} µm, own+cross vs additive part {:.4} µm (bound {:.4} µm)",
        all_vs_live * 1e3,
        own_vs_live * 1e3,
        all_vs_additive * 1e3,
        bound * 1e3
    );
    assert!(
        all_vs_additive <= bound,
        "{all_vs_additive} mm > {bound} mm"
    );
    // What the cross terms carry (squareness, straightness, Abbe terms of one axis seen on
    // another) is micrometres; the part no one-axis table holds is less.
    assert!(
        own_vs_live > all_vs_live + 1e-3,
        "{own_vs_live} vs {all_vs_live} mm"
    );
}

#[test]
fn campaign_static_tables_judges_tables_and_the_live_hybrid_on_the_same_runs() {
    let dir = TempDir::new("static_tables");
    let d = dir.path();
    let text = ok(
        &vmc(
            d,
            &["campaign", "--seeds", "1", "--static-tables", "--out", "c"],
        ),
        "campaign --static-tables",
    );
    let head = text
        .find("static tables (")
        .unwrap_or_else(|| panic!("no static-table section:\n{text}"));
    let section = &text[head..];
    let rows: Vec<&str> = section.lines().collect();
    let figure = |name: &str| -> f64 {
        let line = rows
            .iter()
            .find(|l| l.trim_start().starts_with(name))
            .unwrap();
        let cols: Vec<&str> = line[2 + 24..].split_whitespace().collect();
        assert_eq!(cols[0], "84", "{line}");
        cols[1].parse().unwrap()
    };
    // The live hybrid's row is the campaign's own hybrid runs: the same median.
    let campaign_median: f64 = text
        .lines()
        .find(|l| l.trim_start().starts_with("hybrid     runs"))
        .and_then(|l| l.split("median reduction").nth(1))
        .and_then(|s| s.split('%').next())
        .map(|s| s.trim().parse().unwrap())
        .unwrap();
    assert_eq!(figure("live hybrid"), campaign_median, "{text}");
    let variants = [
        "per-joint, frozen cold",
        "per-joint, frozen warm",
        "own+cross, frozen cold",
        "own+cross, frozen warm",
    ];
    for v in variants {
        // A table that does not follow the machine stays below the live hybrid.
        assert!(figure(v) < campaign_median, "{v}: {section}");
    }
    // On the cold held-out state, next to the cold freezing state, the cross tables carry
    // what per-joint tables cannot (squareness, straightness of one axis along another).
    let cold: Vec<f64> = section
        .lines()
        .skip_while(|l| !l.starts_with("by thermal state"))
        .find(|l| l.starts_with("  cold "))
        .unwrap()
        .split_whitespace()
        .skip(1)
        .step_by(3)
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(cold.len(), 5, "{section}");
    assert!(
        cold[2] > cold[0] + 10.0,
        "own+cross vs per-joint, frozen cold: {section}"
    );
    assert!(section.contains("  frozen warm  cal_4000_8000rpm at 2 h (running at 4000 rpm"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("c/static-tables.json")).unwrap())
            .unwrap();
    assert_eq!(json["runs"].as_array().unwrap().len(), 5 * 84);
    assert_eq!(json["overall"].as_array().unwrap().len(), 5);
    assert_eq!(json["by_state"].as_array().unwrap().len(), 12);
    let model = std::fs::read_to_string(d.join("c/model_hybrid_seed1.json")).unwrap();
    tables_reproduce_the_hybrid_at_their_state(&model, &json);
}

#[test]
fn bad_static_table_options_are_refused_before_anything_runs() {
    let dir = TempDir::new("static_tables_bad");
    let d = dir.path();
    for (args, says) in [
        (
            vec!["--static-tables", "0"],
            "--static-tables 0: the warm freezing state is HOURS into the calibration cycle \
             cal_4000_8000rpm and must be within its 8 h",
        ),
        (
            vec!["--static-tables", "9"],
            "within its 8 h (0 < HOURS ≤ 8)",
        ),
        (vec!["--static-tables", "NaN"], "--static-tables NaN"),
        (
            vec!["--static-tables", "--shard", "1/2", "--out", "s"],
            "--static-tables runs the whole campaign: run it without --shard",
        ),
        (
            vec!["--static-tables", "--probe-every", "30"],
            "run it without --probe-every",
        ),
    ] {
        let mut a = vec!["campaign", "--seeds", "1"];
        a.extend(&args);
        let e = refused(&vmc(d, &a), &a.join(" "));
        assert!(e.contains(says), "{args:?}: {e}");
    }
    let out = vmc(d, &["campaign", "--seeds", "1", "--static-tables", "warm"]);
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("invalid value 'warm'"), "{e}");
    assert!(
        std::fs::read_dir(d).unwrap().next().is_none(),
        "nothing written"
    );
}
