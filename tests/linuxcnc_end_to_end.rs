//! The compensation end to end through LinuxCNC's motion controller, CI-sized: a model trained
//! on the twin's default calibration (`calibrate`, `train`; about 20 s — the sparser
//! `--measure-every-min 120` model leans on the history features the component starts at rest,
//! and lands 1.9 points from `run --compensate`, too near the limit), the twin warmed up
//! (2 h at 4000 rpm), a headless LinuxCNC of the reference machine running the XY face
//! diagonal (dwells shortened to 1 s) with the `vmc_comp` component between each joint's
//! `motor-pos-cmd` and its simulated drive, a `halsampler` log at the servo rate, and `vmc-twin
//! replay` of that log on the twin in the same state (`deploy/linuxcnc/end-to-end.sh`).
//! The reduction of RMS |E| through LinuxCNC must be at least 80 % and within 2 percentage
//! points of `run --compensate` on the same program and state.
//!
//! Skipped with the reason where LinuxCNC, its development files, root or namespaces are not
//! available (`VMC_REQUIRE_LINUXCNC=1` turns the skip into a failure). 41–61 s: one
//! LinuxCNC session of about 32 s, the calibration and training, the twin's runs.

mod common;
#[path = "common/linuxcnc.rs"]
mod linuxcnc_common;

use std::process::Command;

use common::{ok, repo_file, vmc, TempDir};
use linuxcnc_common::text;

/// One row of `end-to-end.csv`, by column name.
fn field(header: &str, row: &str, name: &str) -> f64 {
    let k = header
        .split(',')
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("end-to-end.csv has no column {name}"));
    row.split(',')
        .nth(k)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("end-to-end.csv: {name} is not a number in {row}"))
}

#[test]
fn linuxcnc_with_the_component_in_its_servo_thread_removes_what_run_compensate_removes() {
    if !linuxcnc_common::available("end-to-end.sh") {
        eprintln!("skipped: LinuxCNC is not available here");
        return;
    }
    let dir = TempDir::new("lcnc-e2e");
    let d = dir.path();
    ok(&vmc(d, &["calibrate", "-o", "cal.csv"]), "calibrate");
    ok(
        &vmc(d, &["train", "--data", "cal.csv", "-o", "model.json"]),
        "train",
    );
    // The XY face diagonal with 1 s dwells: the same path, half the session.
    let program = std::fs::read_to_string(repo_file("trajectories/diag_xy.ngc"))
        .expect("diag_xy.ngc reads")
        .replace("G4 P4", "G4 P1");
    std::fs::write(d.join("diag_xy_short.ngc"), program).expect("the program is written");
    let module = linuxcnc_common::build_module(d);
    let warmup = repo_file("trajectories/warmup_2h_4000rpm.ngc");
    let state = format!("2h={}", warmup.display());
    let out = Command::new(repo_file("deploy/linuxcnc/end-to-end.sh"))
        .current_dir(d)
        .args(["--model", "model.json", "--out", "e2e", "--program"])
        .arg(d.join("diag_xy_short.ngc"))
        .args(["--state", &state, "--vmc", common::BIN, "--module"])
        .arg(&module)
        .output()
        .expect("end-to-end.sh starts");
    let said = text(&out);
    eprintln!("{said}");
    let csv = std::fs::read_to_string(d.join("e2e/end-to-end.csv"))
        .unwrap_or_else(|_| panic!("no end-to-end.csv: {said}"));
    let mut lines = csv.lines();
    let header = lines.next().expect("a header");
    let row = lines.next().expect("one row");
    let before_um = field(header, row, "linuxcnc_before_um");
    let through_linuxcnc = field(header, row, "linuxcnc_reduction");
    let by_run = field(header, row, "twin_reduction");
    // The machine is warm: there is an error to remove.
    assert!(before_um > 10.0, "RMS |E| before {before_um} µm: {said}");
    assert!(
        through_linuxcnc >= 0.80,
        "reduction {through_linuxcnc}: {said}"
    );
    assert!(
        (through_linuxcnc - by_run).abs() <= 0.02,
        "through LinuxCNC {through_linuxcnc}, run --compensate {by_run}: {said}"
    );
    assert!(out.status.success(), "end-to-end.sh: {said}");
}
