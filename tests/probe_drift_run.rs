//! Drift updates from a program's own probe moves, on the real binary: the example program
//! `trajectories/probe_drift_diag.ngc` probes the reference gauge block of its setup cold,
//! runs a 60 min duty at 8000 rpm, settles 4 min, probes the block again and measures a body
//! diagonal. With `run --compensate` (a hybrid model trained here on the twin's calibration
//! campaign) the block's touches update the model's drift; with `--probe-update off` they are
//! reported only. The update must lower the diagonal's compensated max |E| by the margin
//! stated below; `summary.json` carries each probe move and the probing cost, and each
//! reference touch's measurement is reproduced from the latched position (`probes.csv`), the
//! model's prediction and the setup's nominal geometry alone (the information boundary).

mod common;
use common::{ok, refused, repo_file, vmc, TempDir};

/// The required improvement of the diagonal's compensated max |E|, µm (seed 1: 2.37 µm
/// without the update, 1.18 µm with it).
const MARGIN_UM: f64 = 0.5;

/// The example program and its setup, copied into a fresh folder.
fn example_folder(name: &str) -> TempDir {
    let dir = TempDir::new(name);
    for f in ["probe_drift_diag.ngc", "probe_drift_diag.setup.toml"] {
        std::fs::copy(repo_file(&format!("trajectories/{f}")), dir.path().join(f)).unwrap();
    }
    dir
}

/// The example's folder with a model trained on the twin's calibration campaign (seed 1),
/// `train` run with `train_args` (the model file among them).
fn trained_folder(name: &str, train_args: &[&str]) -> TempDir {
    let dir = example_folder(name);
    let d = dir.path();
    ok(
        &vmc(
            d,
            &["calibrate", "--measure-every-min", "120", "-o", "cal.csv"],
        ),
        "calibrate",
    );
    let mut args = vec!["train", "--data", "cal.csv"];
    args.extend_from_slice(train_args);
    ok(&vmc(d, &args), "train");
    dir
}

fn summary(dir: &std::path::Path, run: &str) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join(run).join("summary.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap()
}

#[test]
fn probing_a_reference_on_the_warm_machine_lowers_the_diagonals_residual() {
    let dir = trained_folder("probe-drift", &["-o", "hyb.json"]);
    let d = dir.path();
    let run = |update: &str| {
        let args = [
            "run",
            "probe_drift_diag.ngc",
            "--model",
            "hyb.json",
            "--compensate",
            "--probe-update",
            update,
            "--out",
            update,
        ];
        ok(&vmc(d, &args), update)
    };
    let on_text = run("on");
    run("off");
    assert!(on_text.contains("probing cost:"), "{on_text}");
    let (on, off) = (summary(d, "on"), summary(d, "off"));
    // The existing keys stay.
    for key in ["program", "points", "before", "after", "reduction"] {
        assert!(on.get(key).is_some(), "{key} missing");
    }
    let max_e = |s: &serde_json::Value| f(&s["after"]["max_abs_um"][3]);
    assert!(
        max_e(&on) <= max_e(&off) - MARGIN_UM,
        "with the update {:.2} µm, without {:.2} µm",
        max_e(&on),
        max_e(&off)
    );
    // Before compensation the two runs are the same machine and program.
    assert_eq!(on["before"], off["before"]);
    let p = &on["probing"];
    assert_eq!(p["probe_moves"], 10);
    assert_eq!(p["reference_touches"], 10);
    assert_eq!(p["drift_updates"], true);
    assert_eq!(off["probing"]["drift_updates"], false);
    // Ten touches of ≈ 1.2 s in a program of ≈ 67 min.
    assert!(f(&p["probe_time_s"]) > 5.0 && f(&p["probe_time_s"]) < 30.0);
    assert!(f(&p["cost_min_per_h"]) > 0.05 && f(&p["cost_min_per_h"]) < 0.5);
    // Without the update the drift stays 0; with it the last touches moved it.
    let last = |s: &serde_json::Value| s["probing"]["probes"][9]["reference"].clone();
    assert_eq!(last(&off)["drift_after_um"][2], 0.0);
    assert!(f(&last(&on)["drift_after_um"][2]).abs() > 0.3);
}

#[test]
fn a_reference_touch_is_measured_from_the_latched_position_and_the_setup_alone() {
    let dir = trained_folder(
        "probe-drift-boundary",
        &["--kind", "linear", "-o", "lin.json"],
    );
    let d = dir.path();
    let args = [
        "run",
        "probe_drift_diag.ngc",
        "--model",
        "lin.json",
        "--compensate",
        "--out",
        "out",
    ];
    ok(&vmc(d, &args), "run");
    let s = summary(d, "out");
    let csv = std::fs::read_to_string(d.join("out/probes.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    // Independently of the program: the block's top at Z −330 (the setup), the ball radius
    // 3 mm, the pre-travel 0.75 N / 0.25 N/µm = 3 µm, half a 1 ms servo tick at 50 mm/min.
    let expected_mm = -330.0 + 3.0 - 0.003 - 0.5 * 50.0 / 60.0 * 0.001;
    let probes = s["probing"]["probes"].as_array().unwrap();
    assert_eq!(probes.len(), rows.len());
    for (p, row) in probes.iter().zip(&rows) {
        let r = &p["reference"];
        assert_eq!(r["axis"], "Z");
        // Within the nominal trip search's bisection tolerance.
        assert!((f(&r["expected_mm"]) - expected_mm).abs() < 1e-6);
        // The latched Z the program read is the one the measurement used.
        let latched: f64 = row[10].parse().unwrap();
        assert!((f(&r["latched_mm"]) - latched).abs() < 1e-6);
        assert!((f(&p["trip_mm"][2]) - latched).abs() < 1e-6);
        // Probed minus expected = latched + the model's error − expected.
        let dev = (f(&r["latched_mm"]) - f(&r["expected_mm"])) * 1e3 + f(&r["model_error_um"]);
        assert!((f(&r["deviation_um"]) - dev).abs() < 1e-6);
        let csv_dev: f64 = row[13].parse().unwrap();
        assert!((csv_dev - f(&r["deviation_um"])).abs() < 1e-3);
    }
}

#[test]
fn a_program_branching_on_probed_micrometres_is_refused_not_run_on_another_path() {
    let dir = example_folder("probe-branch");
    let d = dir.path();
    // The nominal machine trips at Z −327.003, the cold twin about 20 µm higher (its cold
    // geometry): the two passes take different branches.
    std::fs::write(
        d.join("branch.ngc"),
        "G21 G90 G54\nG0 X500 Y60 Z-320\nG1 Z-326 F500\nG38.2 Z-330 F50\n\
         o10 if [#5063 GT -327.0]\n  G0 Z-300\no10 else\n  G0 Z-310\no10 endif\nG4 P1\nM2\n",
    )
    .unwrap();
    std::fs::copy(
        d.join("probe_drift_diag.setup.toml"),
        d.join("branch.setup.toml"),
    )
    .unwrap();
    let err = refused(&vmc(d, &["run", "branch.ngc"]), "branching run");
    assert!(err.contains("took another path"), "{err}");
    assert!(err.contains("after the probe move at line 4"), "{err}");
}

#[test]
fn probe_update_without_compensation_is_refused_by_the_command_line() {
    let dir = example_folder("probe-update-alone");
    let out = vmc(
        dir.path(),
        &["run", "probe_drift_diag.ngc", "--probe-update", "off"],
    );
    assert_eq!(out.status.code(), Some(2), "a usage error");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--compensate"), "{err}");
    assert!(!dir.path().join("out").exists());
}
