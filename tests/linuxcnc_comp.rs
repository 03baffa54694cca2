//! LinuxCNC applies the compensation tables: a headless LinuxCNC of the reference machine
//! (`deploy/linuxcnc`) loads a folder of joint tables, moves every joint to eight positions from
//! below and from above, and `joint.N.motor-pos-cmd − joint.N.pos-cmd` must be the table's value
//! to 1e-6 mm — or an arrival held by LinuxCNC's compensation ramp in its dead band, which the
//! check names and which must be exactly where the ramp's arithmetic puts it.
//!
//! Tables: hand-written ones of both `COMP_FILE_TYPE`s (multi-µm reversals, uneven points, a
//! table shorter than the travel, a joint without a table), flat ones whose reversals lie in
//! and out of the dead band, and the tables `vmc-twin export` writes from a model trained on
//! the twin's calibration.
//!
//! Skipped with the reason where LinuxCNC is not installed (`deploy/linuxcnc/install.sh`);
//! `VMC_REQUIRE_LINUXCNC=1` turns the skip into a failure. One LinuxCNC session at a time,
//! about 13 s each (four sessions). The check's own Python unit tests run without LinuxCNC.

mod common;
#[path = "common/linuxcnc.rs"]
mod linuxcnc_common;

use std::path::Path;
use std::process::{Command, Output};
use std::sync::Mutex;

use common::{repo_file, vmc, TempDir};
use linuxcnc_common::text;
use vmc_predict::predictor::{AnyPredictor, ErrorPredictor};

/// LinuxCNC sessions of this file run one after the other (the fallback without namespaces
/// allows one LinuxCNC per machine, and two cores are shared).
static ONE_SESSION: Mutex<()> = Mutex::new(());

fn comp_check(args: &[&str]) -> Output {
    Command::new(repo_file("deploy/linuxcnc/comp-check.sh"))
        .args(args)
        .output()
        .expect("deploy/linuxcnc/comp-check.sh starts")
}

/// Compares a kept run folder again (no LinuxCNC session).
fn compare_again(run: &Path, strict: bool) -> Output {
    let mut cmd = Command::new("python3");
    cmd.arg("-B")
        .arg(repo_file("deploy/linuxcnc/comp_check.py"))
        .args(["compare", "--run-dir"])
        .arg(run);
    if strict {
        cmd.arg("--strict");
    }
    cmd.output().expect("python3 starts")
}

/// Whether LinuxCNC can run here; prints why not (a failure under `VMC_REQUIRE_LINUXCNC=1`).
fn linuxcnc_available() -> bool {
    linuxcnc_common::available("comp-check.sh")
}

/// One arrival of the check's table: joint, direction, status (`ok`, `held`, `MISMATCH`).
struct Row {
    joint: usize,
    direction: String,
    status: String,
}

/// The arrival lines of a check's output.
fn rows(output: &str) -> Vec<Row> {
    output
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            let joint = f.first()?.parse().ok()?;
            (f.len() >= 7 && ["forward", "reverse"].contains(&f[2])).then(|| Row {
                joint,
                direction: f[2].to_string(),
                status: f.get(7).map_or("ok", |s| s).to_string(),
            })
        })
        .collect()
}

/// The check's summary line.
fn summary(output: &str) -> &str {
    output
        .lines()
        .find(|l| l.contains(" arrivals: "))
        .unwrap_or_else(|| panic!("no summary in: {output}"))
}

#[test]
fn the_checks_readers_and_classification_pass_their_unit_tests() {
    // Needs Python 3.11 (tomllib), not LinuxCNC.
    let probe = Command::new("python3")
        .args(["-c", "import tomllib"])
        .output();
    if !probe.is_ok_and(|o| o.status.success()) {
        eprintln!("skipped: no python3 >= 3.11 on PATH");
        return;
    }
    let out = Command::new("python3")
        .args(["-B", "-m", "unittest", "discover", "-s"])
        .arg(repo_file("deploy/linuxcnc"))
        .args(["-p", "test_*.py"])
        .output()
        .expect("python3 starts");
    assert!(out.status.success(), "{}", text(&out));
}

#[test]
fn linuxcnc_applies_hand_written_tables_of_both_file_types_to_a_nanometre() {
    if !linuxcnc_available() {
        return;
    }
    let _one = ONE_SESSION.lock().unwrap_or_else(|e| e.into_inner());
    let t = TempDir::new("lcnc-fixtures");
    for kind in ["type1", "type0"] {
        let run = t.path().join(kind);
        let fixture = repo_file(&format!("deploy/linuxcnc/fixtures/{kind}"));
        let out = comp_check(&[
            "--strict",
            "--run-dir",
            &run.display().to_string(),
            &fixture.display().to_string(),
        ]);
        let all = text(&out);
        assert!(out.status.success(), "{kind}: {all}");
        let s = summary(&all);
        assert!(
            s.starts_with("42 arrivals: 42 at the table's value"),
            "{kind}: {s}"
        );
        let r = rows(&all);
        for joint in 0..3 {
            for direction in ["forward", "reverse"] {
                let n = r
                    .iter()
                    .filter(|x| x.joint == joint && x.direction == direction)
                    .count();
                assert!(n >= 6, "{kind}: joint {joint} {direction}: {n} arrivals");
            }
        }
    }

    // The check finds a table value that is 2 nm off what LinuxCNC applied.
    let run = t.path().join("type1");
    let table = run.join("joint0-x.comp");
    let original = std::fs::read_to_string(&table).unwrap();
    assert!(original.starts_with("0.000000 0.001200 -0.002300\n"));
    std::fs::write(&table, original.replacen("-0.002300", "-0.002302", 1)).unwrap();
    let out = compare_again(&run, true);
    let all = text(&out);
    assert_eq!(out.status.code(), Some(1), "{all}");
    assert!(
        all.lines()
            .any(|l| l.contains(" X reverse     0.000000") && l.contains("MISMATCH")),
        "{all}"
    );
}

#[test]
fn linuxcnc_holds_trim_steps_inside_its_compensation_ramp_dead_band() {
    if !linuxcnc_available() {
        return;
    }
    let _one = ONE_SESSION.lock().unwrap_or_else(|e| e.into_inner());
    let t = TempDir::new("lcnc-deadband");
    let run = t.path().join("run");
    let fixture = repo_file("deploy/linuxcnc/fixtures/deadband");
    let out = comp_check(&[
        "--run-dir",
        &run.display().to_string(),
        &fixture.display().to_string(),
    ]);
    let all = text(&out);
    assert!(out.status.success(), "{all}");
    // Reversal steps from rest: X 0.8 µm in (0.5, 1.0] µm is never applied (every reverse
    // arrival keeps the forward trim), Y 0.3 µm below the band is, Z 0.45 µm in its band
    // (0.375, 0.75] µm (lower acceleration) keeps the reverse trim on every later forward one.
    let r = rows(&all);
    let held = |joint: usize, direction: &str| {
        r.iter()
            .filter(|x| x.joint == joint && x.direction == direction && x.status == "held")
            .count()
    };
    let arrivals = |joint: usize, direction: &str| {
        r.iter()
            .filter(|x| x.joint == joint && x.direction == direction)
            .count()
    };
    assert_eq!(held(0, "reverse"), arrivals(0, "reverse"), "{all}");
    assert_eq!(held(0, "forward"), 0, "{all}");
    assert_eq!(held(1, "forward") + held(1, "reverse"), 0, "{all}");
    assert_eq!(held(2, "forward"), arrivals(2, "forward"), "{all}");
    assert_eq!(held(2, "reverse"), 0, "{all}");
    assert!(!all.contains("MISMATCH"), "{all}");
    // Strict: a held arrival fails the check.
    assert_eq!(compare_again(&run, true).status.code(), Some(1));
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

fn ok(dir: &Path, args: &[&str]) -> String {
    let o = vmc(dir, args);
    assert!(o.status.success(), "{args:?}: {}", text(&o));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn linuxcnc_applies_the_tables_exported_from_a_trained_model() {
    if !linuxcnc_available() {
        return;
    }
    let t = TempDir::new("lcnc-export");
    let d = t.path();
    ok(
        d,
        &["calibrate", "--measure-every-min", "120", "-o", "cal.csv"],
    );
    ok(d, &["train", "--data", "cal.csv", "-o", "model.json"]);
    let model = std::fs::read_to_string(d.join("model.json")).unwrap();
    ok(
        d,
        &[
            "export",
            "--model",
            "model.json",
            "--format",
            "linuxcnc",
            "--readings",
            &readings(&model, 20.0),
            "--out",
            "tables",
        ],
    );
    let _one = ONE_SESSION.lock().unwrap_or_else(|e| e.into_inner());
    let out = comp_check(&[
        "--run-dir",
        &d.join("run").display().to_string(),
        &d.join("tables").display().to_string(),
    ]);
    let all = text(&out);
    assert!(out.status.success(), "{all}");
    eprintln!("{}", summary(&all));
    // Every joint shows its table's value (to 1 nm) after moves in both directions; what is
    // not at the table's value is held by the ramp's dead band (the model's sub-µm reversal
    // steps), never anything else.
    let r = rows(&all);
    assert!(!all.contains("MISMATCH"), "{all}");
    for joint in 0..3 {
        let at_value = r
            .iter()
            .filter(|x| x.joint == joint && x.status == "ok")
            .count();
        assert!(at_value >= 1, "joint {joint}: {all}");
        for direction in ["forward", "reverse"] {
            let n = r
                .iter()
                .filter(|x| x.joint == joint && x.direction == direction)
                .count();
            assert!(n >= 6, "joint {joint} {direction}: {n} arrivals: {all}");
        }
    }
}
