//! `export` on the real binary: the tables of a model trained on the twin's own calibration, at a
//! steady state given as readings and after a warm-up on the twin; every written table passes
//! the strict checks a controller's loader needs (LinuxCNC's silent stops, the CEC program's
//! parameters); the state changes the tables; bad input is refused in one line.

mod common;

use std::path::Path;

use common::{vmc, TempDir};
use vmc_tables::cec::parse_cec_program;
use vmc_tables::linuxcnc::check_comp_file;
use vmc_twin::predict::predictor::{AnyPredictor, ErrorPredictor};

fn ok(dir: &Path, args: &[&str]) -> String {
    let o = vmc(dir, args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn err(dir: &Path, args: &[&str]) -> String {
    let o = vmc(dir, args);
    assert_eq!(o.status.code(), Some(1), "{args:?} should fail");
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(e.trim_end().lines().count(), 1, "one line: {e}");
    e
}

/// Every sensor of the model at `degc`, as `--readings` takes them.
fn readings(model_json: &str, degc: f64) -> String {
    let model = AnyPredictor::from_json_str(model_json).unwrap();
    model
        .sensor_names()
        .iter()
        .map(|n| format!("{n}={degc}"))
        .collect::<Vec<_>>()
        .join(",")
}

/// The forward trims of a type-1 joint file, mm.
fn forward_trims_mm(text: &str) -> Vec<f64> {
    text.lines()
        .map(|l| l.split_whitespace().nth(1).unwrap().parse().unwrap())
        .collect()
}

#[test]
fn export_writes_tables_a_controller_loads_at_the_stated_thermal_state() {
    let t = TempDir::new("export");
    let d = t.path();
    ok(
        d,
        &["calibrate", "--measure-every-min", "120", "-o", "cal.csv"],
    );
    ok(d, &["train", "--data", "cal.csv", "-o", "model.json"]);
    let model = std::fs::read_to_string(d.join("model.json")).unwrap();
    let cold = readings(&model, 20.0);
    let out = ok(
        d,
        &[
            "export",
            "--model",
            "model.json",
            "--format",
            "linuxcnc,siemens-cec",
            "--readings",
            &cold,
            "--out",
            "cold",
        ],
    );
    assert!(out.contains("wrote 6 files to cold"), "{out}");
    for axis in ["0-x", "1-y", "2-z"] {
        let text = std::fs::read_to_string(d.join(format!("cold/joint{axis}.comp"))).unwrap();
        let summary = check_comp_file(&text).unwrap();
        assert!(summary.points >= 2 && summary.points <= 256, "{summary:?}");
    }
    let ini = std::fs::read_to_string(d.join("cold/comp-tables.ini")).unwrap();
    assert!(ini.contains("COMP_FILE_TYPE = 1"), "{ini}");
    let cec = std::fs::read_to_string(d.join("cold/NC_CEC.INI")).unwrap();
    let program = parse_cec_program(&cec).unwrap();
    // Three own-axis tables (or six with a reversal) and six cross tables.
    assert!(program.tables.len() >= 9, "{} tables", program.tables.len());
    assert!(std::fs::read_to_string(d.join("cold/tables-report.txt"))
        .unwrap()
        .contains("cross"));

    // The same model after 2 h at 4,000 rpm on the twin: the spindle's drift moves Z's table.
    ok(
        d,
        &[
            "export",
            "--model",
            "model.json",
            "--format",
            "linuxcnc",
            "--warmup",
            &common::repo_file("trajectories/warmup_2h_4000rpm.ngc")
                .display()
                .to_string(),
            "--out",
            "warm",
        ],
    );
    let z_cold = forward_trims_mm(&std::fs::read_to_string(d.join("cold/joint2-z.comp")).unwrap());
    let z_warm = forward_trims_mm(&std::fs::read_to_string(d.join("warm/joint2-z.comp")).unwrap());
    assert_eq!(z_cold.len(), z_warm.len());
    let moved_um = z_cold
        .iter()
        .zip(&z_warm)
        .map(|(c, w)| (c - w).abs() * 1e3)
        .fold(0.0, f64::max);
    assert!(
        moved_um > 1.0,
        "the warm-up moved Z's table by {moved_um} µm"
    );

    // Refusals: existing outputs, a sensor left out, a bad step, a file that is not readings.
    let e = err(
        d,
        &[
            "export",
            "--model",
            "model.json",
            "--format",
            "linuxcnc",
            "--readings",
            &cold,
            "--out",
            "cold",
        ],
    );
    assert!(e.contains("already exists"), "{e}");
    let missing = cold.split(',').skip(1).collect::<Vec<_>>().join(",");
    let e = err(
        d,
        &[
            "export",
            "--model",
            "model.json",
            "--format",
            "linuxcnc",
            "--readings",
            &missing,
            "--out",
            "m",
        ],
    );
    assert!(e.contains(cold.split('=').next().unwrap()), "{e}");
    let e = err(
        d,
        &[
            "export",
            "--model",
            "model.json",
            "--format",
            "linuxcnc",
            "--readings",
            &cold,
            "--step-mm",
            "0",
            "--out",
            "s",
        ],
    );
    assert!(e.contains("--step-mm must be a positive number"), "{e}");
    let e = err(
        d,
        &[
            "export",
            "--model",
            "model.json",
            "--format",
            "linuxcnc",
            "--readings",
            "no-such-file",
            "--out",
            "n",
        ],
    );
    assert!(
        e.contains("neither NAME=VALUE readings nor a readable file"),
        "{e}"
    );
}
