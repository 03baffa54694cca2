//! The HAL component in LinuxCNC's HAL: `deploy/linuxcnc/vmc_comp.comp` with the vmc-rtcomp
//! static library linked in (`build-comp.sh`), loaded by `halrun` with a model file into a
//! 1 ms servo thread, its pins driven (`hal-check.sh`: sensor samples, commanded positions,
//! a spindle speed and axis feeds) and its outputs read at full precision. They must be the
//! corrections the library's compensator (`Compensator` over the `HybridPredictor`, not the
//! compiled model the component runs) gives for the same samples and commands, to 1e-9 mm;
//! the function's `tmax` is reported.
//!
//! Skipped with the reason where LinuxCNC or its development files are not installed, or the
//! module cannot be shown to `loadrt` (`VMC_REQUIRE_LINUXCNC=1` turns the skip into a
//! failure). About 2 s: no motion controller, one short HAL session per test.

#[path = "common/linuxcnc.rs"]
mod linuxcnc_common;
#[path = "../crates/vmc-predict/tests/common/mod.rs"]
mod predict_common;
#[path = "../crates/vmc-gcode/tests/common/temp_dir.rs"]
mod temp_dir;

use std::process::Command;

use linuxcnc_common::{build_module, script, text};
use rand::rngs::StdRng;
use rand::SeedableRng;
use temp_dir::TempDir;
use vmc_predict::controller::{Compensator, Controller};
use vmc_predict::predictor::{train_hybrid, HybridPredictor};

/// 1e-9 mm: the agreement asked of the component with the library.
const SAME_MM: f64 = 1e-9;
/// The spindle speed (rpm) and axis feeds (mm/min) held during a session.
const RPM: f64 = 8000.0;
const FEEDS_MM_PER_MIN: [f64; 3] = [1200.0, -600.0, 300.0];

/// Whether the check can run here; prints why not (a failure under `VMC_REQUIRE_LINUXCNC=1`).
fn available() -> bool {
    linuxcnc_common::available("hal-check.sh")
}

/// The reference machine's features with the spindle speed as an input, 6 units per net.
fn model() -> HybridPredictor {
    let ds = predict_common::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
    let settings = predict_common::reference_like_settings(6).with_spindle_speed_input();
    train_hybrid(&ds, &predict_common::geometry(), &settings)
        .expect("trains")
        .0
}

/// One step of a session: a sample of readings, or a commanded position.
enum Step {
    Sample(Vec<f64>),
    Position([f64; 3]),
}

/// A position first (no sample yet), then four samples of a warming machine, each followed by
/// positions drawn over the work volume.
fn steps(seed: u64) -> Vec<Step> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut steps = vec![Step::Position([280.0, 200.0, -225.0])];
    for k in 0..4 {
        let t_s = 1800.0 * f64::from(k) + 600.0;
        steps.push(Step::Sample(predict_common::temps_degc(6.0, t_s)));
        for _ in 0..4 {
            steps.push(Step::Position(predict_common::random_p_mm(&mut rng)));
        }
    }
    steps
}

fn steps_csv(steps: &[Step]) -> String {
    let line = |kind: &str, v: &[f64]| {
        let nums: Vec<String> = v.iter().map(|x| format!("{x:?}")).collect();
        format!("{kind},{}\n", nums.join(","))
    };
    steps
        .iter()
        .map(|s| match s {
            Step::Sample(t) => line("sample", t),
            Step::Position(p) => line("position", p),
        })
        .collect()
}

/// One line of the session's output.
struct Row {
    sample_clock_s: f64,
    samples: u32,
    state: i32,
    iters: usize,
    corr_mm: [f64; 3],
    counts: [i64; 3],
    /// The servo thread's time of a period (CPU clocks): the function's cost there.
    thread_time: i64,
}

fn rows(out_csv: &str) -> (Vec<Row>, i64) {
    let mut rows = Vec::new();
    let mut tmax = -1;
    for line in out_csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f[0] == "tmax" {
            tmax = f[1].parse().unwrap();
            continue;
        }
        let num = |k: usize| f[k].parse::<f64>().unwrap();
        rows.push(Row {
            sample_clock_s: num(2),
            samples: f[3].parse().unwrap(),
            state: f[4].parse().unwrap(),
            iters: f[5].parse().unwrap(),
            corr_mm: [num(6), num(7), num(8)],
            counts: [
                f[9].parse().unwrap(),
                f[10].parse().unwrap(),
                f[11].parse().unwrap(),
            ],
            thread_time: f[12].parse().unwrap(),
        });
    }
    (rows, tmax)
}

/// The TSC rate, MHz (HAL's times are CPU clocks), when /proc/cpuinfo tells it.
fn cpu_mhz() -> Option<f64> {
    let info = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("cpu MHz"))?;
    line.split(':').nth(1)?.trim().parse().ok()
}

#[test]
fn the_component_in_a_servo_thread_gives_the_librarys_corrections() {
    if !available() {
        return;
    }
    let tmp = TempDir::new("lcnc-hal");
    let dir = tmp.path();
    let module = build_module(dir);
    let model = model();
    std::fs::write(dir.join("model.json"), model.to_json_string().unwrap()).unwrap();
    let steps = steps(29);
    std::fs::write(dir.join("steps.csv"), steps_csv(&steps)).unwrap();
    let feeds: Vec<String> = FEEDS_MM_PER_MIN.iter().map(|v| format!("{v:?}")).collect();
    let out = Command::new(script("hal-check.sh"))
        .arg("--module")
        .arg(&module)
        .args(["--rpm", &format!("{RPM:?}"), "--feeds", &feeds.join(",")])
        .arg(dir.join("model.json"))
        .arg(dir.join("steps.csv"))
        .arg(dir.join("out.csv"))
        .output()
        .expect("hal-check.sh starts");
    assert!(out.status.success(), "hal-check.sh: {}", text(&out));
    let (rows, tmax) = rows(&std::fs::read_to_string(dir.join("out.csv")).unwrap());
    assert_eq!(rows.len(), steps.len());

    // The library, fed what the component took: the readings at the component's clock of each
    // sample, the spindle speed and feeds held since the start (their mean).
    let mut lib = Compensator::new(model);
    // The component's first periods see the position pins at 0 (then a move to the first
    // position, negative in Z): the approach directions the reversal is keyed on start there.
    let mut p_mm = [0.0; 3];
    lib.axis_command_mm(p_mm);
    let mut worst_mm: f64 = 0.0;
    let mut taken = 0;
    for (step, row) in steps.iter().zip(&rows) {
        match step {
            Step::Sample(temps) => {
                taken += 1;
                assert_eq!(row.samples, taken, "one sample per rising edge");
                let t_s = row.sample_clock_s;
                lib.on_readings(t_s, temps);
                lib.on_spindle_speed(t_s, RPM);
                lib.on_axis_feeds(t_s, FEEDS_MM_PER_MIN.map(f64::abs));
            }
            Step::Position(p) => p_mm = *p,
        }
        if taken == 0 {
            assert_eq!(row.state, 2, "no sample yet");
            assert_eq!(row.corr_mm, [0.0; 3]);
            continue;
        }
        let q = lib.axis_command_mm(p_mm);
        assert_eq!(row.state, 0, "converged");
        assert_eq!(row.iters, lib.last_solve().iterations);
        for k in 0..3 {
            let want_mm = q[k] - p_mm[k];
            worst_mm = worst_mm.max((row.corr_mm[k] - want_mm).abs());
            // The external offsets' counts: the correction in µm, rounded.
            assert_eq!(row.counts[k], (row.corr_mm[k] * 1e6).round() as i64);
        }
        assert!(
            row.corr_mm.iter().any(|c| c.abs() > 1e-3),
            "a correction of µm"
        );
    }
    assert!(worst_mm < SAME_MM, "worst difference {worst_mm:e} mm");
    let mut times: Vec<i64> = rows.iter().map(|r| r.thread_time).collect();
    times.sort_unstable();
    let median = times[times.len() / 2];
    let us = |clocks: i64| {
        cpu_mhz().map_or(String::new(), |mhz| {
            format!(" ≈ {:.1} µs", clocks as f64 / mhz)
        })
    };
    eprintln!(
        "vmc_comp in a 1 ms servo thread: {} steps, worst |component − library| {worst_mm:.1e} mm; \
         function tmax {tmax} clocks{}; thread time per period, median of the steps {median} \
         clocks{}",
        rows.len(),
        us(tmax),
        us(median)
    );
}

#[test]
fn a_file_that_is_not_a_model_is_refused_when_the_module_loads() {
    if !available() {
        return;
    }
    let tmp = TempDir::new("lcnc-hal-bad");
    let dir = tmp.path();
    let module = build_module(dir);
    std::fs::write(dir.join("model.json"), "{\"not\": \"a model\"}").unwrap();
    std::fs::write(dir.join("steps.csv"), "position,1,2,3\n").unwrap();
    let out = Command::new(script("hal-check.sh"))
        .arg("--module")
        .arg(&module)
        .arg(dir.join("model.json"))
        .arg(dir.join("steps.csv"))
        .arg(dir.join("out.csv"))
        .output()
        .expect("hal-check.sh starts");
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    assert!(
        text(&out).contains("cannot be used"),
        "the reason is shown: {}",
        text(&out)
    );
    assert!(!dir.join("out.csv").exists());
}
