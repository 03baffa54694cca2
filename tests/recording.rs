//! Acceptance tests of the Rerun recordings, checked with the real Rerun CLI.
//!
//! The CLI comes from the PyPI wheel `rerun-sdk==0.36.3` (same version as the Rust SDK). It is
//! found through the environment variable `RERUN_BIN`, else at `target/rerun-venv/bin/rerun`;
//! if neither exists the test creates that virtual environment itself (`python3 -m venv` +
//! `pip install --no-deps rerun-sdk==0.36.3`, ~100 MB download). If that is impossible the
//! tests fail with a message saying what to install — they never skip silently.
//!
//! `rerun rrd verify` exits 0 even on a file that is not a recording ("0 files verified"), so
//! the tests assert the exact line `1 file verified without error.` and check the content with
//! `rerun rrd print`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Mutex;

mod common;
use common::*;

const RERUN_SDK: &str = "rerun-sdk==0.36.3";

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).to_string(),
        String::from_utf8_lossy(&o.stderr).to_string(),
    )
}

fn ok(o: Output, what: &str) -> String {
    let (out, err) = text(&o);
    assert!(o.status.success(), "{what} failed:\n{out}\n{err}");
    out
}

/// Runs a setup command, with a clear message if it cannot run or fails.
fn setup(cmd: &mut Command, what: &str) {
    match cmd.output() {
        Ok(o) if o.status.success() => {}
        Ok(o) => panic!(
            "cannot set up the Rerun CLI for the recording tests: `{what}` failed:\n{}\n{}\n\
             Install it by hand (python3 -m venv target/rerun-venv && \
             target/rerun-venv/bin/pip install --no-deps {RERUN_SDK}) or set RERUN_BIN.",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        ),
        Err(e) => panic!(
            "cannot set up the Rerun CLI for the recording tests: `{what}` could not run: {e}. \
             The tests need python3 (with venv and pip) and network access to PyPI, or a \
             rerun {RERUN_SDK} CLI given by RERUN_BIN."
        ),
    }
}

/// The `rerun` CLI: `RERUN_BIN`, else `target/rerun-venv/bin/rerun`, created if missing.
fn rerun_bin() -> PathBuf {
    static LOCK: Mutex<()> = Mutex::new(());
    let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(p) = std::env::var_os("RERUN_BIN") {
        let p = PathBuf::from(p);
        assert!(
            p.exists(),
            "RERUN_BIN={} does not exist (unset it to let the tests install the CLI)",
            p.display()
        );
        return p;
    }
    let venv = repo_file("target/rerun-venv");
    let bin = venv.join("bin").join("rerun");
    if !bin.exists() {
        eprintln!(
            "installing {RERUN_SDK} into {} for the recording tests",
            venv.display()
        );
        setup(
            Command::new("python3").args(["-m", "venv"]).arg(&venv),
            "python3 -m venv target/rerun-venv",
        );
        setup(
            Command::new(venv.join("bin").join("pip")).args([
                "install",
                "--quiet",
                "--no-deps",
                RERUN_SDK,
            ]),
            "pip install --no-deps rerun-sdk==0.36.3",
        );
        assert!(
            bin.exists(),
            "pip installed {RERUN_SDK} but {} is missing",
            bin.display()
        );
    }
    // No usage data from CI (idempotent).
    let _ = Command::new(&bin).args(["analytics", "disable"]).output();
    bin
}

fn rerun(args: &[&str], file: &Path) -> (bool, String) {
    let o = Command::new(rerun_bin())
        .args(args)
        .arg(file)
        .output()
        .expect("run rerun");
    let (out, err) = text(&o);
    (o.status.success(), format!("{out}{err}"))
}

/// `rerun rrd verify` accepts the file: the exact success line for one file.
fn assert_verified(file: &Path) {
    let (success, out) = rerun(&["rrd", "verify"], file);
    assert!(success, "rrd verify failed on {}:\n{out}", file.display());
    assert!(
        out.lines()
            .any(|l| l.trim() == "1 file verified without error."),
        "rrd verify did not verify {}:\n{out}",
        file.display()
    );
}

/// `rerun rrd print` output at a verbosity: `-vv` shows every chunk's entity path and index
/// (timeline) columns, `-vvv` the data too.
fn printed(file: &Path, verbosity: &str) -> String {
    let (success, out) = rerun(&["rrd", "print", verbosity], file);
    assert!(success, "rrd print failed:\n{out}");
    out
}

/// Every entity has a chunk (`Chunk(..) with N rows (..) - /path - …` headers) and every
/// timeline is an index column (`index_name: …`).
fn assert_has(out: &str, entities: &[&str], timelines: &[&str], what: &str) {
    let mut missing: Vec<String> = entities
        .iter()
        .filter(|e| !out.contains(&format!(" - /{e} -")))
        .map(|e| format!("entity /{e}"))
        .collect();
    missing.extend(
        timelines
            .iter()
            .filter(|t| !out.contains(&format!("index_name: {t} ")))
            .map(|t| format!("timeline {t}")),
    );
    assert!(
        missing.is_empty(),
        "{what}: missing {missing:?} in `rerun rrd print -vv` (first 3000 chars):\n{}",
        &out[..out.len().min(3000)]
    );
}

#[test]
fn the_rerun_cli_rejects_a_file_that_is_not_a_recording() {
    // The check below must be able to fail: garbage does not pass as "1 file verified".
    let dir = TempDir::new("garbage");
    let f = dir.path().join("garbage.rrd");
    std::fs::write(&f, b"this is not a recording").unwrap();
    let (_, out) = rerun(&["rrd", "verify"], &f);
    assert!(
        !out.lines()
            .any(|l| l.trim() == "1 file verified without error."),
        "{out}"
    );
}

#[test]
fn a_compensated_diagonal_run_writes_a_recording_the_rerun_cli_verifies() {
    let dir = TempDir::new("run");
    let d = dir.path();
    // A quick model: a coarse calibration and the linear predictor (enough to compensate).
    ok(
        vmc(
            d,
            &["calibrate", "-o", "cal.csv", "--measure-every-min", "120"],
        ),
        "calibrate",
    );
    ok(
        vmc(
            d,
            &[
                "train", "--data", "cal.csv", "--kind", "linear", "-o", "m.json",
            ],
        ),
        "train",
    );
    let program = repo_file("trajectories/diag_xy.ngc");
    let warmup = repo_file("trajectories/warmup_2h_4000rpm.ngc");
    let out = ok(
        vmc(
            d,
            &[
                "run",
                program.to_str().unwrap(),
                "--warmup",
                warmup.to_str().unwrap(),
                "--model",
                "m.json",
                "--compensate",
                "--rrd",
                "xy.rrd",
                "--magnify",
                "1500",
            ],
        ),
        "run --rrd",
    );
    assert!(out.contains("wrote xy.rrd"), "{out}");
    let rrd = d.join("xy.rrd");
    assert_verified(&rrd);
    let p = printed(&rrd, "-vv");
    assert_has(
        &p,
        &[
            "machine/table",
            "machine/head",
            "machine/head/tool",
            "paths/commanded",
            "paths/actual_uncompensated",
            "paths/actual_compensated",
            "errors/vectors/before",
            "errors/vectors/after",
            "errors/before/ex",
            "errors/before/norm",
            "errors/after/ez",
            "errors/after/norm",
            "thermal/sensors/BXH",
            "thermal/sensors/Amb",
            "thermal/nodes",
            "events",
            "report",
            "legend",
        ],
        &["sim_time", "sample", "diagonal_mm"],
        "run recording",
    );
    // Only the simulation's timelines in the data (the blueprint's own chunks carry the SDK's
    // log_time).
    let ours = [
        "/machine", "/paths", "/errors", "/thermal", "/events", "/report", "/legend",
    ];
    for chunk in p.split("Chunk(").skip(1) {
        let header = chunk.lines().next().unwrap_or("");
        if ours.iter().any(|e| header.contains(&format!(" - {e}"))) {
            assert!(
                !chunk.contains("index_name: log_time") && !chunk.contains("index_name: log_tick"),
                "wall-clock or tick timeline in {header}"
            );
        }
    }
    // The magnification is shown in the recording (path labels, legend, report).
    let data = printed(&rrd, "-vvv");
    assert!(data.contains("×1500"), "magnification not in the recording");
    assert!(
        !data.contains("×2000"),
        "default magnification used instead of --magnify"
    );
}

#[test]
fn a_one_seed_campaign_recording_holds_every_held_out_run_and_a_replayed_run() {
    let dir = TempDir::new("campaign");
    let d = dir.path();
    let out = ok(
        vmc(d, &["campaign", "--seeds", "1", "--rrd", "c.rrd"]),
        "campaign --rrd",
    );
    assert!(out.contains("wrote c.rrd"), "{out}");
    let rrd = d.join("c.rrd");
    assert_verified(&rrd);
    let size = std::fs::metadata(&rrd).unwrap().len();
    assert!(
        size < 20_000_000,
        "one-seed campaign recording {size} bytes"
    );
    let p = printed(&rrd, "-vv");
    let mut want = vec![
        "machine/saddle".to_string(),
        "paths/actual_compensated".into(),
        "errors/after/norm".into(),
        "thermal/sensors/ZT".into(),
        "thermal/nodes".into(),
        "report".into(),
    ];
    // 7 diagonals × 7 held-out states, before and after.
    for diag in ["XY", "YZ", "XZ", "PPP", "NPP", "PNP", "PPN"] {
        for state in ["cold", "eval_restart_4h", "eval_ambient_swing_2h"] {
            want.push(format!("runs/seed1/{state}/{diag}/before"));
            want.push(format!("runs/seed1/{state}/{diag}/after"));
        }
    }
    let want: Vec<&str> = want.iter().map(|s| s.as_str()).collect();
    assert_has(
        &p,
        &want,
        &["sim_time", "sample", "diagonal_mm"],
        "campaign recording",
    );
}

#[test]
fn bad_rrd_paths_fail_at_once_with_one_line() {
    let dir = TempDir::new("bad");
    let d = dir.path();
    let program = repo_file("trajectories/diag_xy.ngc");
    let prog = program.to_str().unwrap();
    let check = |args: &[&str], want: &str| {
        let o = vmc(d, args);
        let (out, err) = text(&o);
        assert!(!o.status.success(), "{args:?} succeeded:\n{out}");
        assert!(err.contains(want), "{args:?}: stderr {err:?}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err:?}");
        // Nothing was simulated: no report on stdout.
        assert!(out.is_empty(), "{args:?} printed {out:?}");
    };
    check(&["run", prog, "--rrd", "missing/x.rrd"], "does not exist");
    check(
        &["campaign", "--seeds", "1", "--rrd", "missing/x.rrd"],
        "does not exist",
    );
    check(&["run", prog, "--rrd", "x.txt"], "must end in .rrd");
    check(
        &["run", prog, "--rrd", "x.rrd", "--magnify", "0"],
        "--magnify",
    );
    std::fs::write(d.join("old.rrd"), b"keep me").unwrap();
    check(
        &["run", prog, "--rrd", "old.rrd"],
        "already exists (pass --force",
    );
    assert_eq!(std::fs::read(d.join("old.rrd")).unwrap(), b"keep me");
    // A folder without write permission (not testable as root, who may write anyway).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let ro = d.join("ro");
        std::fs::create_dir(&ro).unwrap();
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
        let writable_anyway = std::fs::write(ro.join("probe"), b"").is_ok();
        if writable_anyway {
            eprintln!("note: running with write access to read-only folders (root): permission case not checked");
        } else {
            check(
                &["run", prog, "--rrd", "ro/x.rrd"],
                "cannot write in directory",
            );
        }
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    // --magnify without --rrd is a usage error.
    let o = vmc(d, &["run", prog, "--magnify", "100"]);
    assert!(!o.status.success());
}

#[test]
fn a_crash_found_by_check_is_drawn_in_its_recording_at_its_time() {
    let dir = TempDir::new("check");
    let d = dir.path();
    let program = repo_file("tests/data/collision/rapid_into_vise.ngc");
    let fixture = repo_file("tests/data/collision/vise.toml");
    let o = vmc(
        d,
        &[
            "check",
            program.to_str().unwrap(),
            "--fixture",
            fixture.to_str().unwrap(),
            "--rrd",
            "crash.rrd",
        ],
    );
    // The check still fails (exit 1): the recording is written besides the report.
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{out}\n{err}");
    assert!(out.contains("wrote crash.rrd"), "{out}\n{err}");
    let file = d.join("crash.rrd");
    assert_verified(&file);
    let listing = printed(&file, "-vv");
    assert_has(
        &listing,
        &[
            "events",
            "paths/events",
            "paths/fixture/vise_fixed_jaw",
            "paths/fixture/stock",
            "paths/commanded",
        ],
        &["sim_time"],
        "check recording",
    );
    // The event carries the crash's own line: the bodies and the depth.
    let data = printed(&file, "-vvv");
    assert!(
        data.contains("tool hits vise_fixed_jaw"),
        "no crash text in the recording:\n{}",
        &data[..data.len().min(3000)]
    );
}

#[test]
fn a_lobe_diagram_is_drawn_with_hopf_and_flip_lobes_apart() {
    let dir = TempDir::new("lobes");
    let d = dir.path();
    let o = vmc(
        d,
        &[
            "lobes",
            "--immersion",
            "0.05",
            "--rpm",
            "8000:12000:41",
            "--rrd",
            "lobes.rrd",
        ],
    );
    let out = ok(o, "lobes --rrd");
    assert!(out.contains("wrote lobes.rrd"), "{out}");
    let file = d.join("lobes.rrd");
    assert_verified(&file);
    // At a_e/D = 0.05 this speed range holds both Hopf lobes and the flip lobe near 10 000 rpm.
    assert_has(
        &printed(&file, "-vv"),
        &[
            "lobes/critical_depth_mm/boundary",
            "lobes/critical_depth_mm/hopf",
            "lobes/critical_depth_mm/flip",
            "lobes/chatter_frequency_hz/hopf",
            "lobes/chatter_frequency_hz/flip",
            "report",
        ],
        &["spindle_rpm"],
        "lobes recording",
    );
    let data = printed(&file, "-vvv");
    // `rrd print` shows the first characters of the report.
    assert!(
        data.contains("Critical depth against spindle speed"),
        "no report in the recording"
    );
}

#[test]
fn a_cut_recording_holds_vibration_forces_and_spectra() {
    let dir = TempDir::new("cut");
    let d = dir.path();
    let o = vmc(
        d,
        &[
            "cut",
            "--rpm",
            "10000",
            "--depth-mm",
            "4.3",
            "--immersion",
            "0.05",
            "--revolutions",
            "100",
            "--rrd",
            "cut.rrd",
        ],
    );
    let out = ok(o, "cut --rrd");
    assert!(out.contains("verdict: chatter"), "{out}");
    assert!(out.contains("wrote cut.rrd"), "{out}");
    let file = d.join("cut.rrd");
    assert_verified(&file);
    assert_has(
        &printed(&file, "-vv"),
        &[
            "cut/vibration_um/x",
            "cut/vibration_um/y",
            "cut/force_n/fx",
            "cut/force_n/fy",
            "cut/change_per_tooth_um",
            "spectrum/vibration_um",
            "spectrum/disturbance_um",
            "report",
        ],
        &["sim_time"],
        "cut recording",
    );
}

#[test]
fn a_chatter_recording_draws_the_program_cuts_on_the_lobes_of_their_engagements() {
    let dir = TempDir::new("chatter");
    let d = dir.path();
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let program = repo.join("trajectories/pocket_chatter.ngc");
    let stock = repo.join("trajectories/pocket_chatter.stock.toml");
    let o = vmc(
        d,
        &[
            "chatter",
            program.to_str().unwrap(),
            "--stock",
            stock.to_str().unwrap(),
            "--rrd",
            "chatter.rrd",
        ],
    );
    // The example has unstable cuts: the command fails after writing its recording.
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}\n{err}");
    assert!(out.contains("wrote chatter.rrd"), "{out}");
    let file = d.join("chatter.rrd");
    assert_verified(&file);
    // Three engagements (the slot, the 2 mm passes, the sideways entries) and both verdicts.
    assert_has(
        &printed(&file, "-vv"),
        &[
            "chatter/depth_mm/lobes/a_e_D_1_000_slot",
            "chatter/depth_mm/lobes/a_e_D_0_200_down",
            "chatter/depth_mm/lobes/a_e_D_0_400_entry",
            "chatter/depth_mm/cuts/stable",
            "chatter/depth_mm/cuts/unstable",
            "diagram/lobes/a_e_D_1_000_slot",
            "diagram/cuts",
            "diagram/legend",
            "report",
        ],
        &["spindle_rpm"],
        "chatter recording",
    );
}

#[test]
fn controlled_lobes_are_drawn_with_the_open_loop_lobes() {
    let dir = TempDir::new("ctl-lobes");
    let d = dir.path();
    let plant = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/benchmarks/blade.toml");
    ok(
        vmc(
            d,
            &[
                "control",
                "design",
                "--plant",
                plant.to_str().unwrap(),
                "--controller",
                "lqg",
                "-o",
                "lqg.json",
            ],
        ),
        "control design",
    );
    let args = [
        "lobes",
        "--controller",
        "lqg.json",
        "--rpm",
        "2000:4000:5",
        "--steps",
        "40",
        "--rrd",
        "lobes.rrd",
    ];
    let out = ok(vmc(d, &args), "lobes --controller --rrd");
    assert!(out.contains("wrote lobes.rrd"), "{out}");
    let file = d.join("lobes.rrd");
    assert_verified(&file);
    assert_has(
        &printed(&file, "-vv"),
        &[
            "chatter/depth_mm/lobes/open_loop",
            "chatter/depth_mm/lobes/with_lqg__strategy_1_",
            "diagram/lobes/open_loop",
            "diagram/legend",
            "report",
        ],
        &["spindle_rpm"],
        "controlled lobes recording",
    );
}

#[test]
fn the_five_axis_recordings_hold_the_moving_trunnion_the_probing_and_the_error_fields() {
    let dir = TempDir::new("fiveaxis");
    let d = dir.path();
    let m = repo_file("machines/trunnion-ac.toml");
    let m = m.to_str().unwrap();
    let out = ok(
        vmc(
            d,
            &[
                "probe-campaign",
                "--machine",
                m,
                "--configs",
                "30",
                "-o",
                "p.csv",
                "--rrd",
                "probe.rrd",
                "--magnify",
                "500",
            ],
        ),
        "probe-campaign --rrd",
    );
    assert!(out.contains("wrote probe.rrd"), "{out}");
    ok(
        vmc(
            d,
            &[
                "identify",
                "--data",
                "p.csv",
                "--machine",
                m,
                "-o",
                "id.json",
                "--heldout-poses",
                "100",
                "--rrd",
                "id.rrd",
            ],
        ),
        "identify --rrd",
    );
    let program = repo_file("trajectories/trunnion_5axis.ngc");
    ok(
        vmc(
            d,
            &[
                "run",
                program.to_str().unwrap(),
                "--machine",
                m,
                "--identified",
                "id.json",
                "--rrd",
                "run.rrd",
            ],
        ),
        "run --rrd (five-axis)",
    );
    let table = "machine/X/Y/A/C";
    let w = "machine/X/Y/A/C/workpiece";
    for (file, entities, timeline) in [
        (
            "run.rrd",
            vec![
                format!("{table}"),
                "machine/X/Y/A".into(),
                "machine/Z".into(),
                format!("{w}/spheres"),
                format!("{w}/paths/commanded"),
                format!("{w}/paths/actual_uncompensated"),
                format!("{w}/paths/actual_compensated"),
                format!("{w}/errors/before"),
                format!("{w}/errors/after"),
                "errors/before/norm".into(),
                "errors/after/norm".into(),
                "axes/a_deg".into(),
                "axes/c_deg".into(),
                "report".into(),
            ],
            "sim_time",
        ),
        (
            "probe.rrd",
            vec![
                format!("{table}"),
                format!("{w}/probed/points"),
                format!("{w}/probed/centre_error"),
                "errors/before/norm".into(),
                "report".into(),
            ],
            "configuration",
        ),
        (
            "id.rrd",
            vec![
                format!("{table}"),
                format!("{w}/heldout/before"),
                format!("{w}/heldout/after"),
                "errors/after/norm".into(),
                "report".into(),
            ],
            "pose",
        ),
    ] {
        let rrd = d.join(file);
        assert_verified(&rrd);
        let refs: Vec<&str> = entities.iter().map(String::as_str).collect();
        assert_has(&printed(&rrd, "-vv"), &refs, &[timeline], file);
    }
    // The rotary axes move: the A and C transforms are logged at many times.
    let p = printed(&d.join("run.rrd"), "-vv");
    for axis in ["machine/X/Y/A", "machine/X/Y/A/C"] {
        let rows: usize = p
            .lines()
            .filter(|l| {
                l.ends_with(&format!(" - /{axis} - ")) || l.ends_with(&format!(" - /{axis} -"))
            })
            .filter_map(|l| l.split(" with ").nth(1)?.split(' ').next()?.parse().ok())
            .max()
            .unwrap_or(0);
        assert!(rows > 100, "{axis}: {rows} rows");
    }
    let data = printed(&d.join("run.rrd"), "-vvv");
    assert!(
        data.contains("×2000"),
        "default magnification in the run recording"
    );
    assert!(printed(&d.join("probe.rrd"), "-vvv").contains("×500"));
}

#[test]
fn an_identify_thermal_recording_holds_measured_and_predicted_drift_of_each_channel() {
    let dir = TempDir::new("idth");
    let d = dir.path();
    let csv = repo_file("tests/data/spindle-thermal/train_every60s.csv");
    let o = vmc(
        d,
        &[
            "identify-thermal",
            "--data",
            csv.to_str().expect("UTF-8 path"),
            "--drifts",
            "ch1_um,ch5_um",
            "--nodes",
            "1",
            "--no-baseline",
            "-o",
            "spindle.toml",
            "--rrd",
            "drift.rrd",
        ],
    );
    let out = ok(o, "identify-thermal --rrd");
    assert!(out.contains("wrote drift.rrd"), "{out}");
    let file = d.join("drift.rrd");
    assert_verified(&file);
    // Measured, grey box fitted on every row (pred0), each cycle held out (pred1).
    assert_has(
        &printed(&file, "-vv"),
        &[
            "drift/ch1_um/measured",
            "drift/ch1_um/pred0",
            "drift/ch1_um/pred1",
            "drift/ch5_um/measured",
            "drift/ch5_um/pred0",
            "drift/ch5_um/pred1",
        ],
        &["test_time"],
        "identify-thermal recording",
    );
}

#[test]
fn a_modal_fit_recording_holds_measured_and_fitted_receptance_per_direction() {
    let dir = TempDir::new("modalfit");
    let d = dir.path();
    let frf = repo_file("machines/benchmarks/frf-example.csv");
    let args = [
        "modal-fit",
        frf.to_str().expect("UTF-8 path"),
        "--rrd",
        "fit.rrd",
    ];
    let out = ok(vmc(d, &args), "modal-fit --rrd");
    assert!(out.contains("wrote fit.rrd"), "{out}");
    let file = d.join("fit.rrd");
    assert_verified(&file);
    let mut entities = vec!["report".to_string()];
    for dir in ["x", "y"] {
        for q in ["magnitude_um_per_n", "phase_deg"] {
            for s in ["measured", "fitted"] {
                entities.push(format!("frf/{dir}/{q}/{s}"));
            }
        }
    }
    let entities: Vec<&str> = entities.iter().map(String::as_str).collect();
    let what = "modal-fit recording";
    assert_has(&printed(&file, "-vv"), &entities, &["frequency_hz"], what);
}
