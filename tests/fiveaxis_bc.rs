//! The B/C trunnion (`machines/trunnion-bc.toml`, chain `w C B X Y b Z t`) on the real binary:
//! its example program runs, an A/C program is refused, and the identified model (order chosen
//! from the probing data) removes at least 90 % of the RMS error on the program, seeds 1–3.

mod common;

use common::{repo_file, succeed, summary_json as summary, vmc, TempDir};

/// A repository file as a command-line argument.
fn repo(rel: &str) -> String {
    repo_file(rel).display().to_string()
}

#[test]
fn the_b_c_program_runs_on_the_b_c_machine_and_an_a_c_program_is_refused() {
    let t = TempDir::new("run");
    let m = repo("machines/trunnion-bc.toml");
    let out = succeed(
        t.path(),
        &[
            "run",
            &repo("trajectories/trunnion_bc_5axis.ngc"),
            "--machine",
            &m,
            "--seed",
            "1",
            "--out",
            "o",
        ],
    );
    assert!(out.contains("b_deg    c_deg"), "{out}");
    let csv = std::fs::read_to_string(t.path().join("o/samples.csv")).unwrap();
    assert!(
        csv.starts_with("time_s,line,x_mm,y_mm,z_mm,b_deg,c_deg,"),
        "{csv}"
    );
    let dwells = std::fs::read_to_string(repo("trajectories/trunnion_bc_5axis.ngc"))
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("G4"))
        .count();
    let s = summary(t.path(), "o");
    assert_eq!(s["points"].as_u64().unwrap() as usize, dwells);
    let rms = s["before"]["rms_um"][3].as_f64().unwrap();
    // The realisation's location errors: tens of µm.
    assert!(rms > 10.0 && rms < 200.0, "{rms}");
    let o = vmc(
        t.path(),
        &[
            "run",
            &repo("trajectories/trunnion_5axis.ngc"),
            "--machine",
            &m,
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("A axis"), "{err}");
}

#[test]
fn the_identified_model_removes_90_percent_of_the_rms_error_on_the_b_c_program() {
    let t = TempDir::new("ident");
    let m = repo("machines/trunnion-bc.toml");
    let p = repo("trajectories/trunnion_bc_5axis.ngc");
    for seed in ["1", "2", "3"] {
        let (csv, json) = (format!("p{seed}.csv"), format!("id{seed}.json"));
        succeed(
            t.path(),
            &[
                "probe-campaign",
                "--machine",
                &m,
                "--seed",
                seed,
                "-o",
                &csv,
            ],
        );
        let report = succeed(
            t.path(),
            &[
                "identify",
                "--data",
                &csv,
                "--machine",
                &m,
                "-o",
                &json,
                "--heldout-poses",
                "200",
            ],
        );
        assert!(report.contains("model order from the data"), "{report}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(t.path().join(&json)).unwrap()).unwrap();
        assert!(
            v["heldout_characterised_share"].as_f64().unwrap() >= 0.95,
            "seed {seed}: {report}"
        );
        succeed(
            t.path(),
            &[
                "run",
                &p,
                "--machine",
                &m,
                "--seed",
                seed,
                "--identified",
                &json,
                "--out",
                seed,
            ],
        );
        let reduction = summary(t.path(), seed)["reduction"].as_f64().unwrap();
        assert!(reduction >= 0.9, "seed {seed}: {reduction}");
    }
}
