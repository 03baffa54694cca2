//! Probe moves (G38.2 … G38.5) on the real binary: `run` moves the touch probe through the
//! twin's drifted geometry onto the setup's gauge block and writes what the controller latched
//! (`probes.csv`); the drift it reads between a cold and a warm run is the twin's drift at the
//! block's top (the truth, read here by the test only) within the probe's repeatability.
//! `check` ends a probe move where the probe trips (no collision), still reports a rapid into
//! the block, and reports a G38.2 that reaches nothing. Programs of our own writing
//! (`tests/data/probing`).

mod common;
use common::{ok, refused, repo_file, vmc, TempDir};
use vmc_machine::machine::MachineSpec;
use vmc_machine::sim::{self, SampleMode, SimConfig};
use vmc_machine::twin::Twin;

/// The probing program and its setup, copied into `dir`.
fn probing_folder(name: &str) -> TempDir {
    let dir = TempDir::new(name);
    for f in ["gauge_block.ngc", "gauge_block.setup.toml"] {
        std::fs::copy(
            repo_file(&format!("tests/data/probing/{f}")),
            dir.path().join(f),
        )
        .unwrap();
    }
    dir
}

/// The tripped rows of `probes.csv`: (#5063 in program units, latched machine Z, touched).
fn probed(csv: &str) -> Vec<(f64, f64, String)> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (z, mz, t, touched) = (
        col("z"),
        col("machine_z_mm"),
        col("tripped"),
        col("touched"),
    );
    lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|f| f[t] == "1")
        .map(|f| {
            (
                f[z].parse().unwrap(),
                f[mz].parse().unwrap(),
                f[touched].trim_matches('"').to_string(),
            )
        })
        .collect()
}

/// Truth, read by the test only: the Z error of the ball's centre (stylus as long as the
/// machine's own tool) at axis command `q_mm`, mm.
fn true_ez_mm(twin: &Twin, q_mm: [f64; 3]) -> f64 {
    twin.tool_error_mm(q_mm, q_mm, [0.0; 3]).z
}

#[test]
fn a_gauge_block_probed_cold_and_warm_returns_the_twins_drift_at_its_top() {
    let dir = probing_folder("probe-run");
    let warmup = repo_file("trajectories/warmup_2h_4000rpm.ngc");
    let warmup = warmup.to_str().unwrap();
    let out = ok(
        &vmc(dir.path(), &["run", "gauge_block.ngc", "--out", "cold"]),
        "cold run",
    );
    assert!(out.contains("probe moves on the twin (5)"), "{out}");
    let args = [
        "run",
        "gauge_block.ngc",
        "--warmup",
        warmup,
        "--out",
        "warm",
    ];
    ok(&vmc(dir.path(), &args), "warm run");
    let read = |run: &str| {
        probed(&std::fs::read_to_string(dir.path().join(run).join("probes.csv")).unwrap())
    };
    let (cold, warm) = (read("cold"), read("warm"));
    assert_eq!((cold.len(), warm.len()), (5, 5));
    assert!(cold.iter().chain(&warm).all(|p| p.2 == "gauge_block"));
    let mean = |v: &[(f64, f64, String)], k: usize| {
        v.iter()
            .map(|p| if k == 0 { p.0 } else { p.1 })
            .sum::<f64>()
            / v.len() as f64
    };
    // #5063 is the machine Z less the G54 offset (Z −300): the ball at the top plus its radius.
    assert!((mean(&cold, 1) - (-300.0 + mean(&cold, 0))).abs() < 1e-5);
    assert!((mean(&cold, 0) - 3.0).abs() < 0.1, "{}", mean(&cold, 0));

    // The truth: the same machine (seed 1) cold, then after the same warm-up.
    let spec = MachineSpec::reference();
    let mut twin = Twin::new(&spec, 1).unwrap();
    let q_mm = [280.0, 200.0, mean(&cold, 1)];
    let cold_true = true_ez_mm(&twin, q_mm);
    let plan = vmc_machine::program::load_plan(
        std::path::Path::new(&repo_file("trajectories/warmup_2h_4000rpm.ngc")),
        &spec,
        spec.axes.home_mm,
    )
    .unwrap();
    let cfg = SimConfig::new(1.0, 1e-3)
        .unwrap()
        .sampling(SampleMode::Dwells);
    sim::execute(&mut twin, &plan, &cfg, None, &mut sim::NullObserver).unwrap();
    let warm_true = true_ez_mm(&twin, q_mm);
    let drift_um = (warm_true - cold_true) * 1e3;
    // The ball meets the top where q + E = top + r − pre-travel: the reading moves by −ΔE.
    let read_um = -(mean(&warm, 1) - mean(&cold, 1)) * 1e3;
    println!("gauge block top: drift {drift_um:.3} µm (truth), probed {read_um:.3} µm");
    assert!(
        drift_um.abs() > 3.0,
        "the warm-up moved the top by {drift_um} µm"
    );
    // Within the probe's stated repeatability (1 µm, 2σ).
    assert!(
        (read_um - drift_um).abs() <= 1.0,
        "probed {read_um:.3} µm, drift {drift_um:.3} µm"
    );
}

#[test]
fn a_g38_2_that_reaches_nothing_stops_run_and_check_with_its_line() {
    let dir = probing_folder("probe-miss");
    let miss = "G21 G90 G54\nG0 X50 Y0 Z20\nG0 Z6\nG38.2 Z-2 F50\nG0 Z20\nM2\n";
    std::fs::write(dir.path().join("miss.ngc"), miss).unwrap();
    std::fs::copy(
        dir.path().join("gauge_block.setup.toml"),
        dir.path().join("miss.setup.toml"),
    )
    .unwrap();
    let err = refused(
        &vmc(dir.path(), &["run", "miss.ngc"]),
        "run of a missing probe",
    );
    assert!(
        err.contains("miss.ngc: line 4")
            && err.contains("G38.2 move finished without making contact."),
        "{err}"
    );
    let out = vmc(dir.path(), &["check", "miss.ngc"]);
    let err = refused(&out, "check of a missing probe");
    assert!(
        err.contains("would stop at a probe move that reaches nothing"),
        "{err}"
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("line 4, column 1: G38.2 move finished without making contact."),
        "{text}"
    );
}

#[test]
fn check_lets_the_probe_touch_the_block_but_not_a_rapid_into_it() {
    let dir = probing_folder("probe-check");
    let out = ok(
        &vmc(dir.path(), &["check", "gauge_block.ngc"]),
        "check of the probing program",
    );
    assert!(out.contains("gauge_block (fixture)"), "{out}");
    assert!(out.contains("probe moves: 5"), "{out}");
    assert!(out.contains("no problem found"), "{out}");
    // The same descent as a rapid is a crash into the block.
    let rapid = std::fs::read_to_string(dir.path().join("gauge_block.ngc"))
        .unwrap()
        .replace("G38.2 Z-2 F50", "G0 Z-2");
    std::fs::write(dir.path().join("rapid.ngc"), rapid).unwrap();
    std::fs::copy(
        dir.path().join("gauge_block.setup.toml"),
        dir.path().join("rapid.setup.toml"),
    )
    .unwrap();
    let out = vmc(dir.path(), &["check", "rapid.ngc"]);
    refused(&out, "check of a rapid into the block");
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("G0 rapid: tool hits gauge_block (fixture)"),
        "{text}"
    );
}
