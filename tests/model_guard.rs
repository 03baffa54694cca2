//! A model knows what it was trained on: `run` refuses a model of another realisation of the
//! machine (unless told), and reports — or with `--strict` refuses — readings outside the
//! ranges the model was trained on. The model here is trained on the twin's own calibration
//! (`calibrate`, `train`); the out-of-range case narrows the range the file records for the
//! ambient sensor, so the same run leaves it.

mod common;

use common::{repo_file, vmc, TempDir};

fn ok(dir: &std::path::Path, args: &[&str]) -> String {
    let o = vmc(dir, args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn err(dir: &std::path::Path, args: &[&str]) -> String {
    let o = vmc(dir, args);
    assert_eq!(o.status.code(), Some(1), "{args:?} should fail");
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(e.trim_end().lines().count(), 1, "one line: {e}");
    e
}

#[test]
fn run_checks_the_models_machine_and_trained_ranges() {
    let t = TempDir::new("guard");
    let d = t.path();
    ok(
        d,
        &["calibrate", "--measure-every-min", "120", "-o", "cal.csv"],
    );
    ok(d, &["train", "--data", "cal.csv", "-o", "model.json"]);
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("model.json")).unwrap()).unwrap();
    assert_eq!(model["version"], 8);
    assert_eq!(model["trained_on"]["machine"]["realisation"], 1);
    let prog = repo_file("trajectories/diag_xy.ngc").display().to_string();

    // The machine it was calibrated on, inside its ranges: silent.
    let out = ok(
        d,
        &[
            "run",
            &prog,
            "--model",
            "model.json",
            "--compensate",
            "--strict",
            "--out",
            "a",
        ],
    );
    assert!(
        out.contains("every reading and command inside the trained ranges"),
        "{out}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("a/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["extrapolation"]["count"], 0);
    assert!(summary["extrapolation"]["samples"].as_u64().unwrap() > 0);

    // Another realisation: refused, then accepted when asked, with a note.
    let e = err(
        d,
        &[
            "run",
            &prog,
            "--seed",
            "2",
            "--model",
            "model.json",
            "--compensate",
        ],
    );
    assert!(
        e.contains("calibrated on realisation 1 of machine `vmc-reference`, this is realisation 2")
            && e.contains("--allow-other-machine"),
        "{e}"
    );
    let out = ok(
        d,
        &[
            "run",
            &prog,
            "--seed",
            "2",
            "--model",
            "model.json",
            "--compensate",
            "--allow-other-machine",
        ],
    );
    assert!(
        out.contains("note: model.json: it was calibrated on realisation 1"),
        "{out}"
    );

    // A model whose recorded ambient range the run leaves: reported, and refused with --strict.
    let mut narrow = model.clone();
    let inputs = &mut narrow["trained_on"]["inputs"];
    let amb = inputs["sensors"]
        .as_array()
        .unwrap()
        .iter()
        .position(|s| s == "Amb")
        .unwrap();
    inputs["sensor_degc"][amb] = serde_json::json!([10.0, 12.0]);
    std::fs::write(d.join("narrow.json"), narrow.to_string()).unwrap();
    let out = ok(
        d,
        &[
            "run",
            &prog,
            "--model",
            "narrow.json",
            "--compensate",
            "--out",
            "b",
        ],
    );
    assert!(out.contains("WARNING: the model extrapolated"), "{out}");
    assert!(
        out.contains("Amb") && out.contains("trained     10.00 …     12.00"),
        "{out}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("b/summary.json")).unwrap()).unwrap();
    let e = &summary["extrapolation"];
    assert!(e["count"].as_u64().unwrap() > 0);
    assert_eq!(e["first_time_s"], 0.0);
    assert_eq!(e["inputs"][0]["input"], "Amb");
    let e = err(
        d,
        &[
            "run",
            &prog,
            "--model",
            "narrow.json",
            "--compensate",
            "--strict",
            "--out",
            "c",
        ],
    );
    assert!(
        e.contains("--strict: the model was used outside the range it was trained on: Amb"),
        "{e}"
    );
    assert!(!d.join("c/summary.json").exists());

    // The hybrid reads the axes' filtered commanded feeds: the file records their ranges, and a
    // warm-up that drives them beyond (here: a range narrowed to 0–0.2 m/min under a 2 h warm-up
    // with axis motion) is reported by name.
    let feeds = &model["trained_on"]["inputs"]["axis_feeds"];
    assert_eq!(feeds["taus_s"], serde_json::json!([3600.0]));
    assert_eq!(feeds["filtered_m_per_min"].as_array().unwrap().len(), 3);
    let mut slow = model.clone();
    slow["trained_on"]["inputs"]["axis_feeds"]["filtered_m_per_min"] =
        serde_json::json!([[0.0, 0.2], [0.0, 0.2], [0.0, 0.2]]);
    std::fs::write(d.join("slow.json"), slow.to_string()).unwrap();
    let warmup = repo_file("trajectories/warmup_2h_4000rpm.ngc")
        .display()
        .to_string();
    let out = ok(
        d,
        &[
            "run",
            &prog,
            "--warmup",
            &warmup,
            "--model",
            "slow.json",
            "--compensate",
            "--out",
            "f",
        ],
    );
    assert!(out.contains("WARNING: the model extrapolated"), "{out}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("f/summary.json")).unwrap()).unwrap();
    let names: Vec<&str> = summary["extrapolation"]["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["input"].as_str().unwrap())
        .collect();
    assert!(
        names.contains(&"x_feed_3600s") && names.contains(&"z_feed_3600s"),
        "{names:?}"
    );
    let first = summary["extrapolation"]["inputs"][0]["first_time_s"]
        .as_f64()
        .unwrap();
    assert!(
        first > 60.0,
        "a filter needs time to pass 0.25 m/min: {first}"
    );
}
