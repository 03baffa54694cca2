//! `vmc-twin replay`: servo logs of the twin's own planner (the diagonal program sampled at a
//! fixed period, as a controller's servo thread would log it) played back on the twin, against
//! `run` on the same program.
mod common;

use std::path::Path;

use common::{ok, refused, repo_file, summary_json as summary, vmc, TempDir};
use vmc_machine::machine::MachineSpec;
use vmc_machine::motion::Plan;

const WARMUP: &str = "trajectories/warmup_2h_4000rpm.ngc";
const DIAGONAL: &str = "trajectories/diag_xy.ngc";
/// Servo period of the test logs, s (10 ms keeps the logs at ~5800 lines).
const PERIOD_S: f64 = 0.01;

/// The diagonal's plan as `run` plans it after the warm-up: from where the warm-up ends.
fn diagonal_plan() -> Plan {
    let spec = MachineSpec::reference();
    let warm = vmc_machine::program::load_plan(&repo_file(WARMUP), &spec, spec.axes.home_mm)
        .expect("the warm-up plans");
    vmc_machine::program::load_plan(&repo_file(DIAGONAL), &spec, warm.end_mm())
        .expect("the diagonal plans")
}

/// The plan's commanded positions every `PERIOD_S`: (sample number, position, spindle rpm).
fn samples(plan: &Plan) -> Vec<(usize, [f64; 3], f64)> {
    let n = (plan.duration_s() / PERIOD_S).floor() as usize;
    (0..=n)
        .map(|k| {
            let t = k as f64 * PERIOD_S;
            (k, plan.position_at(t), plan.spindle_rpm_at(t))
        })
        .collect()
}

/// The samples as a CSV log, with `corr` as every sample's logged correction if given.
fn csv_log(samples: &[(usize, [f64; 3], f64)], corr: Option<[f64; 3]>) -> String {
    let mut s = String::from("time_s,x_mm,y_mm,z_mm,spindle_rpm");
    if corr.is_some() {
        s.push_str(",corr_x_mm,corr_y_mm,corr_z_mm");
    }
    s.push('\n');
    for (k, p, rpm) in samples {
        s.push_str(&format!(
            "{},{:.6},{:.6},{:.6},{rpm}",
            *k as f64 * PERIOD_S,
            p[0],
            p[1],
            p[2]
        ));
        if let Some(c) = corr {
            s.push_str(&format!(",{},{},{}", c[0], c[1], c[2]));
        }
        s.push('\n');
    }
    s
}

/// The samples as `halsampler -t` prints them (sample number first, spaces).
fn hal_log(samples: &[(usize, [f64; 3], f64)]) -> String {
    samples
        .iter()
        .map(|(k, p, rpm)| format!("{k} {:.6} {:.6} {:.6} {rpm}\n", p[0], p[1], p[2]))
        .collect()
}

/// `stats[field][i]` of a summary, µm.
fn stat(s: &serde_json::Value, part: &str, field: &str, i: usize) -> f64 {
    s[part][field][i]
        .as_f64()
        .unwrap_or_else(|| panic!("{part}.{field}: {s}"))
}

fn arg(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn a_csv_and_a_halsampler_log_of_the_same_trajectory_give_the_same_figures() {
    let dir = TempDir::new("replay-formats");
    let d = dir.path();
    let s = samples(&diagonal_plan());
    std::fs::write(d.join("trace.csv"), csv_log(&s, None)).unwrap();
    std::fs::write(d.join("trace.hal"), hal_log(&s)).unwrap();
    let warmup = repo_file(WARMUP);
    let csv = ok(
        &vmc(
            d,
            &[
                "replay",
                "trace.csv",
                "--warmup",
                arg(&warmup),
                "--out",
                "c",
            ],
        ),
        "replay csv",
    );
    assert!(
        csv.contains(&format!("replayed {} samples", s.len())),
        "{csv}"
    );
    let hal = ok(
        &vmc(
            d,
            &[
                "replay",
                "trace.hal",
                "--format",
                "halsampler",
                "--columns",
                "n,x,y,z,s",
                "--period-ms",
                "10",
                "--warmup",
                arg(&warmup),
                "--out",
                "h",
            ],
        ),
        "replay halsampler",
    );
    assert!(hal.contains("halsampler, period 10 ms"), "{hal}");
    let (a, b) = (summary(d, "c"), summary(d, "h"));
    assert_eq!(a["points"], b["points"]);
    assert_eq!(a["points"].as_u64(), Some(s.len() as u64));
    for field in ["max_abs_um", "rms_um"] {
        for i in 0..4 {
            let (x, y) = (stat(&a, "before", field, i), stat(&b, "before", field, i));
            assert!((x - y).abs() < 1e-6, "before {field}[{i}]: {x} against {y}");
        }
    }
    assert!(stat(&a, "before", "max_abs_um", 3) > 1.0);
    // The warm-up heated the machine: a thermal part is reported, as by `run`.
    assert!(stat(&a, "thermal_part", "max_abs_um", 3) > 0.5, "{a}");
}

#[test]
fn zero_logged_corrections_give_the_uncompensated_figure_as_compensated() {
    let dir = TempDir::new("replay-zero");
    let d = dir.path();
    let s = samples(&diagonal_plan());
    std::fs::write(d.join("zero.csv"), csv_log(&s, Some([0.0; 3]))).unwrap();
    let text = ok(
        &vmc(d, &["replay", "zero.csv", "--every", "7", "--out", "z"]),
        "replay with zero corrections",
    );
    assert!(
        text.contains("with the corrections the controller logged"),
        "{text}"
    );
    let z = summary(d, "z");
    assert_eq!(z["points"].as_u64(), Some(s.len().div_ceil(7) as u64));
    assert_eq!(z["before"], z["after"]);
    assert_eq!(z["reduction"].as_f64(), Some(0.0));
    let csv = std::fs::read_to_string(d.join("z").join("samples.csv")).unwrap();
    assert!(csv.lines().next().unwrap().contains("ex_comp_um"));
}

#[test]
fn a_replay_with_the_models_compensation_is_close_to_the_run_of_the_same_program() {
    let dir = TempDir::new("replay-compensate");
    let d = dir.path();
    // A quick model: a coarse calibration and the linear predictor.
    ok(
        &vmc(
            d,
            &["calibrate", "-o", "cal.csv", "--measure-every-min", "120"],
        ),
        "calibrate",
    );
    ok(
        &vmc(
            d,
            &[
                "train", "--data", "cal.csv", "--kind", "linear", "-o", "m.json",
            ],
        ),
        "train",
    );
    let s = samples(&diagonal_plan());
    std::fs::write(d.join("trace.csv"), csv_log(&s, None)).unwrap();
    let warmup = repo_file(WARMUP);
    let program = repo_file(DIAGONAL);
    ok(
        &vmc(
            d,
            &[
                "run",
                arg(&program),
                "--warmup",
                arg(&warmup),
                "--model",
                "m.json",
                "--compensate",
                "--every-cycle",
                "--interp-cycle-ms",
                "10",
                "--out",
                "run",
            ],
        ),
        "run",
    );
    let text = ok(
        &vmc(
            d,
            &[
                "replay",
                "trace.csv",
                "--warmup",
                arg(&warmup),
                "--compensate",
                "m.json",
                "--out",
                "rep",
                "--rrd",
                "rep.rrd",
            ],
        ),
        "replay",
    );
    assert!(text.contains("with m.json in the twin's loop"), "{text}");
    assert!(text.contains("wrote rep.rrd"), "{text}");
    let (r, p) = (summary(d, "run"), summary(d, "rep"));
    // The same path in the same thermal state, so "before" agrees closely: the replay
    // measures every 10 ms of the 4 s dwells too (the run once per dwell), which weights the
    // dwell points more in the RMS, and its samples lie on straight lines between the planner's
    // positions. "After" is small and dominated by the random non-repeatability drawn at each
    // point (σ = 0.25 µm per axis): its largest value over ~5800 points against ~1900 differs
    // by up to a few σ.
    for (part, max_abs_um, rms_abs_um, rel) in
        [("before", 0.5, 0.5, 0.05), ("after", 1.0, 0.3, 0.2)]
    {
        let (a, b) = (
            stat(&r, part, "max_abs_um", 3),
            stat(&p, part, "max_abs_um", 3),
        );
        eprintln!("{part} max |E|: run {a:.3} µm, replay {b:.3} µm");
        assert!(
            (a - b).abs() < max_abs_um + rel * a,
            "{part} max |E|: run {a}, replay {b}"
        );
        let (a, b) = (stat(&r, part, "rms_um", 3), stat(&p, part, "rms_um", 3));
        eprintln!("{part} RMS |E|: run {a:.3} µm, replay {b:.3} µm");
        assert!(
            (a - b).abs() < rms_abs_um + rel * a,
            "{part} RMS |E|: run {a}, replay {b}"
        );
    }
    assert!(stat(&p, "after", "rms_um", 3) < 0.7 * stat(&p, "before", "rms_um", 3));
}

#[test]
fn bad_logs_are_refused_with_their_line() {
    let dir = TempDir::new("replay-bad");
    let d = dir.path();
    let head = "time_s,x_mm,y_mm,z_mm\n";
    let cases = [
        (
            "missing.csv",
            "time_s,x_mm,y_mm\n0,1,2\n".to_string(),
            "line 1: no `z_mm` column",
        ),
        (
            "short.csv",
            format!("{head}0,10,60,-225\n0.001,10,60\n"),
            "line 3: 3 fields",
        ),
        (
            "repeat.csv",
            format!("{head}0,10,60,-225\n0,10,60,-225\n"),
            "line 3: time 0 s is not after",
        ),
        (
            "back.csv",
            format!("{head}1,10,60,-225\n0.5,10,60,-225\n"),
            "line 3: time 0.5 s",
        ),
        (
            "nan.csv",
            format!("{head}0,10,NaN,-225\n"),
            "line 2: column `y_mm`: NaN",
        ),
        (
            "inf.csv",
            format!("{head}0,10,60,inf\n"),
            "line 2: column `z_mm`: inf",
        ),
        (
            "word.csv",
            format!("{head}0,10,60,-225\n0.001,ten,60,-225\n"),
            "line 3: column `x_mm`: `ten`",
        ),
        (
            "twice.csv",
            "time_s,x_mm,y_mm,y_mm,z_mm\n".to_string(),
            "line 1: column `y_mm` is named twice",
        ),
        (
            "unknown.csv",
            "time_s,x_mm,y_mm,z_mm,feed\n".to_string(),
            "line 1: unknown column `feed`",
        ),
        (
            "sensor.csv",
            "time_s,x_mm,y_mm,z_mm,nowhere_degc\n0,1,2,3,20\n".to_string(),
            "unknown column `nowhere_degc`",
        ),
        ("empty.csv", String::new(), "the log has no samples"),
        ("header.csv", head.to_string(), "the log has no samples"),
    ];
    for (name, text, want) in cases {
        std::fs::write(d.join(name), text).unwrap();
        let err = refused(&vmc(d, &["replay", name]), name);
        assert!(err.contains(&format!("{name}: {want}")), "{name}: {err}");
    }
    std::fs::write(d.join("log.txt"), "0 10 60 -225\n1 10 60 -225 4\n").unwrap();
    let err = refused(&vmc(d, &["replay", "log.txt"]), "no format");
    assert!(err.contains("give --format csv"), "{err}");
    let err = refused(
        &vmc(
            d,
            &[
                "replay",
                "log.txt",
                "--columns",
                "n,x,y,z",
                "--period-ms",
                "1",
            ],
        ),
        "halsampler field count",
    );
    assert!(
        err.contains("log.txt: line 2: 5 fields, the log has 4 columns"),
        "{err}"
    );
    std::fs::write(
        d.join("corr.csv"),
        "time_s,x_mm,y_mm,z_mm,corr_x_mm,corr_y_mm,corr_z_mm\n0,10,60,-225,0,0,0\n",
    )
    .unwrap();
    let err = refused(
        &vmc(d, &["replay", "corr.csv", "--compensate", "m.json"]),
        "corrections and a model",
    );
    assert!(
        err.contains("the log has the controller's corrections"),
        "{err}"
    );
    std::fs::write(
        d.join("big.csv"),
        "time_s,x_mm,y_mm,z_mm,corr_x_mm,corr_y_mm,corr_z_mm\n0,10,60,-225,0,0,0\n\
         0.001,10,60,-225,0,0,0\n0.002,10,60,-225,0,0,15\n",
    )
    .unwrap();
    let err = refused(&vmc(d, &["replay", "big.csv"]), "a correction of 15 mm");
    assert!(
        err.contains("big.csv: line 4: the logged correction moves the axes 15.0000 mm"),
        "{err}"
    );
}
