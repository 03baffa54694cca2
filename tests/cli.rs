//! Acceptance tests of the command line: they run the real `vmc-twin` binary in a
//! temporary folder, as a user would, and read what it prints and writes.
//!
//! Tolerances are physical: the table prints µm with 2 decimals (±0.005 µm), `samples.csv` with
//! 4 decimals; the machine's non-repeatability is σ ≈ 0.25–0.3 µm per axis.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Output;

mod common;
use common::*;

/// The XY face diagonal's programmed points: X steps 60 mm from 10, Y steps 30 mm from 60, Z −225.
fn diag_xy_points_mm() -> Vec<[f64; 3]> {
    (0..10)
        .map(|k| [10.0 + 60.0 * k as f64, 60.0 + 30.0 * k as f64, -225.0])
        .collect()
}

fn diag_xy() -> String {
    repo_file("trajectories/diag_xy.ngc").display().to_string()
}

fn warmup_4h() -> String {
    repo_file("trajectories/warmup_4h_8000rpm.ngc")
        .display()
        .to_string()
}

fn assert_success(o: &Output, what: &str) {
    assert!(
        o.status.success(),
        "{what}: expected success, got {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status,
        stdout(o),
        stderr(o)
    );
}

/// One row of the terminal table.
#[derive(Debug, Clone, Copy)]
struct Row {
    commanded_mm: [f64; 3],
    e_um: [f64; 3],
    norm_um: f64,
    therm_um: f64,
}

/// Parses the table rows between the `pt …` header and the `summary` line.
fn table_rows(out: &str) -> Vec<Row> {
    let mut rows = Vec::new();
    let mut in_table = false;
    for line in out.lines() {
        let t = line.trim();
        if t.starts_with("pt ") && t.contains("ex_um") {
            in_table = true;
            continue;
        }
        if t.starts_with("summary") {
            break;
        }
        if in_table {
            let v: Vec<f64> = t
                .split_whitespace()
                .map(|s| {
                    s.parse::<f64>()
                        .unwrap_or_else(|_| panic!("table cell {s:?} in {line:?}"))
                })
                .collect();
            assert_eq!(v.len(), 11, "table row has 11 columns: {line:?}");
            rows.push(Row {
                commanded_mm: [v[3], v[4], v[5]],
                e_um: [v[6], v[7], v[8]],
                norm_um: v[9],
                therm_um: v[10],
            });
        }
    }
    rows
}

/// `samples.csv` as column name → values.
struct Csv {
    header: Vec<String>,
    cols: BTreeMap<String, Vec<f64>>,
    rows: usize,
}

impl Csv {
    fn read(path: &Path) -> Csv {
        let text = std::fs::read_to_string(path).expect("samples.csv readable");
        let mut lines = text.lines();
        let header: Vec<String> = lines
            .next()
            .expect("header line")
            .split(',')
            .map(|s| s.trim().to_string())
            .collect();
        let mut cols: BTreeMap<String, Vec<f64>> =
            header.iter().map(|h| (h.clone(), Vec::new())).collect();
        let mut rows = 0;
        for line in lines.filter(|l| !l.trim().is_empty()) {
            let cells: Vec<&str> = line.split(',').collect();
            assert_eq!(
                cells.len(),
                header.len(),
                "row width = header width: {line:?}"
            );
            for (h, c) in header.iter().zip(cells) {
                let v: f64 = c
                    .trim()
                    .parse()
                    .unwrap_or_else(|_| panic!("column {h}: {c:?} is not a number"));
                assert!(v.is_finite(), "column {h}: {v} is not finite");
                cols.get_mut(h).expect("known column").push(v);
            }
            rows += 1;
        }
        Csv { header, cols, rows }
    }

    fn col(&self, name: &str) -> &[f64] {
        self.cols
            .get(name)
            .unwrap_or_else(|| panic!("samples.csv has no column {name}; header {:?}", self.header))
    }

    /// Error vectors (µm) of each row from three columns.
    fn vectors(&self, names: [&str; 3]) -> Vec<[f64; 3]> {
        (0..self.rows)
            .map(|i| names.map(|n| self.col(n)[i]))
            .collect()
    }

    fn sensor_columns(&self) -> Vec<String> {
        self.header
            .iter()
            .filter(|h| h.ends_with("_degc"))
            .cloned()
            .collect()
    }
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).expect("summary.json readable");
    serde_json::from_str(&text).expect("summary.json is valid JSON")
}

/// The four numbers of an `ErrorStats` array field (`[x, y, z, |E|]`).
fn stats4(v: &serde_json::Value, group: &str, field: &str) -> [f64; 4] {
    let arr = v[group][field]
        .as_array()
        .unwrap_or_else(|| panic!("summary.json: {group}.{field} is an array; got {v}"));
    assert_eq!(arr.len(), 4, "{group}.{field} has X, Y, Z, |E|");
    let mut out = [0.0; 4];
    for (o, a) in out.iter_mut().zip(arr) {
        *o = a.as_f64().expect("number");
        assert!(o.is_finite() && *o >= 0.0, "{group}.{field}: {o}");
    }
    out
}

#[test]
fn the_xy_diagonal_runs_cold_and_prints_ten_points_at_the_programmed_positions() {
    let tmp = TempDir::new("table");
    let o = vmc(tmp.path(), &["run", &diag_xy()]);
    assert_success(&o, "run diag_xy.ngc");
    let out = stdout(&o);
    let rows = table_rows(&out);
    assert_eq!(rows.len(), 10, "10 measurement points:\n{out}");
    for (r, p) in rows.iter().zip(diag_xy_points_mm()) {
        for a in 0..3 {
            // The table prints mm with 3 decimals.
            assert!(
                (r.commanded_mm[a] - p[a]).abs() < 5e-4,
                "commanded {:?} vs program {p:?}",
                r.commanded_mm
            );
        }
        // |E| column is the norm of the printed components (2 decimals each).
        assert!((r.norm_um - norm(r.e_um)).abs() < 0.02, "{r:?}");
        // A real machine errs: a few µm at least, well under a tenth of a millimetre.
        assert!(
            r.norm_um > 1.0 && r.norm_um < 100.0,
            "implausible |E| {r:?}"
        );
    }
    assert!(
        out.contains("cold start"),
        "states the thermal state:\n{out}"
    );
    let summary = out
        .lines()
        .skip_while(|l| !l.starts_with("summary"))
        .collect::<Vec<_>>();
    assert!(summary.len() >= 3, "a summary follows the table:\n{out}");
    assert!(
        summary
            .iter()
            .any(|l| l.contains("max |Ex|") && l.contains("|E|") && l.contains("RMS")),
        "max/RMS line:\n{out}"
    );
    assert!(
        summary
            .iter()
            .any(|l| l.contains("thermal") && l.contains("RMS")),
        "thermal part line:\n{out}"
    );
    assert!(
        stderr(&o).trim().is_empty(),
        "nothing on stderr: {}",
        stderr(&o)
    );
}

#[test]
fn out_writes_samples_and_summary_and_never_overwrites_without_force() {
    let tmp = TempDir::new("out");
    let dir = tmp.path().join("results");
    let dir_s = dir.display().to_string();
    let o = vmc(tmp.path(), &["run", &diag_xy(), "--out", &dir_s]);
    assert_success(&o, "run --out");
    let rows = table_rows(&stdout(&o));

    let csv_path = dir.join("samples.csv");
    let json_path = dir.join("summary.json");
    let csv = Csv::read(&csv_path);
    for c in [
        "time_s", "line", "x_mm", "y_mm", "z_mm", "ex_um", "ey_um", "ez_um",
    ] {
        assert!(
            csv.header.iter().any(|h| h == c),
            "header {:?} lacks {c}",
            csv.header
        );
    }
    assert_eq!(csv.rows, 10, "one row per measurement point");
    let pos = csv.vectors(["x_mm", "y_mm", "z_mm"]);
    let err = csv.vectors(["ex_um", "ey_um", "ez_um"]);
    for i in 0..10 {
        let p = diag_xy_points_mm()[i];
        for a in 0..3 {
            assert!(
                (pos[i][a] - p[a]).abs() < 1e-3,
                "row {i}: {:?} vs {p:?}",
                pos[i]
            );
            // The CSV (4 decimals) and the table (2 decimals) report the same error.
            assert!(
                (err[i][a] - rows[i].e_um[a]).abs() < 0.006,
                "row {i}: csv {:?} table {:?}",
                err[i],
                rows[i].e_um
            );
        }
    }
    let t = csv.col("time_s");
    assert!(t.windows(2).all(|w| w[1] > w[0]), "time increases: {t:?}");
    // One column per sensor of the machine, in its order, in °C.
    let sensors: Vec<String> = vmc_machine::machine::MachineSpec::reference()
        .sensors
        .iter()
        .map(|s| format!("{}_degc", s.name))
        .collect();
    assert_eq!(csv.sensor_columns(), sensors);

    let js = read_json(&json_path);
    assert_eq!(js["points"].as_u64(), Some(10));
    let max = stats4(&js, "before", "max_abs_um");
    let rms = stats4(&js, "before", "rms_um");
    stats4(&js, "thermal_part", "max_abs_um");
    stats4(&js, "thermal_part", "rms_um");
    let max_norm = err.iter().map(|e| norm(*e)).fold(0.0, f64::max);
    assert!(
        (max[3] - max_norm).abs() < 0.01,
        "summary max |E| {} vs samples {max_norm}",
        max[3]
    );
    let rms_norm = (err.iter().map(|e| norm(*e).powi(2)).sum::<f64>() / 10.0).sqrt();
    assert!(
        (rms[3] - rms_norm).abs() < 0.01,
        "summary RMS |E| {} vs samples {rms_norm}",
        rms[3]
    );

    // Again, with another seed so a silent overwrite would change the files: refused, untouched.
    let csv_before = std::fs::read(&csv_path).unwrap();
    let json_before = std::fs::read(&json_path).unwrap();
    let o = vmc(
        tmp.path(),
        &["run", &diag_xy(), "--seed", "2", "--out", &dir_s],
    );
    assert!(!o.status.success(), "second run without --force must fail");
    let msg = stderr(&o);
    assert_eq!(msg.trim().lines().count(), 1, "one line: {msg}");
    assert!(
        msg.contains(&csv_path.display().to_string()) && msg.contains("exists"),
        "names the file: {msg}"
    );
    assert!(msg.contains("--force"), "says how to proceed: {msg}");
    assert_eq!(
        std::fs::read(&csv_path).unwrap(),
        csv_before,
        "samples.csv unchanged"
    );
    assert_eq!(
        std::fs::read(&json_path).unwrap(),
        json_before,
        "summary.json unchanged"
    );

    let o = vmc(
        tmp.path(),
        &["run", &diag_xy(), "--seed", "2", "--out", &dir_s, "--force"],
    );
    assert_success(&o, "run --out --force");
    assert_ne!(
        std::fs::read(&csv_path).unwrap(),
        csv_before,
        "--force replaced samples.csv"
    );
    assert_eq!(
        read_json(&json_path)["seed"].as_u64(),
        Some(2),
        "--force replaced summary.json"
    );
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.contains(".tmp"))
        .collect();
    assert!(
        leftovers.is_empty(),
        "no temporary files left: {leftovers:?}"
    );
}

#[test]
fn after_a_4_h_warm_up_the_errors_change_by_what_the_thermal_state_explains() {
    let tmp = TempDir::new("warm");
    let cold_dir = tmp.path().join("cold").display().to_string();
    let warm_dir = tmp.path().join("warm").display().to_string();
    let cold = vmc(tmp.path(), &["run", &diag_xy(), "--out", &cold_dir]);
    assert_success(&cold, "cold run");
    let warm = vmc(
        tmp.path(),
        &[
            "run",
            &diag_xy(),
            "--warmup",
            &warmup_4h(),
            "--out",
            &warm_dir,
        ],
    );
    assert_success(&warm, "warm run");
    assert!(
        stdout(&warm).contains("after warm-up"),
        "states the thermal state"
    );

    let c = Csv::read(&tmp.path().join("cold/samples.csv"));
    let w = Csv::read(&tmp.path().join("warm/samples.csv"));
    assert_eq!((c.rows, w.rows), (10, 10));

    // Sensors: the warm machine reads hotter, most near the spindle; ambient is the same.
    let sensors = c.sensor_columns();
    let mut hotter = Vec::new();
    for s in &sensors {
        let (tc, tw) = (c.col(s)[0], w.col(s)[0]);
        // 0.0625 °C quantisation + 0.02 °C noise: anything above −0.15 °C is "not colder".
        assert!(tw > tc - 0.15, "{s}: warm {tw} °C below cold {tc} °C");
        if tw > tc + 1.0 {
            hotter.push(s.clone());
        }
    }
    let amb = (c.col("Amb_degc")[0], w.col("Amb_degc")[0]);
    assert!((amb.0 - amb.1).abs() < 0.15, "ambient unchanged: {amb:?}");
    for s in ["BXB_degc", "BYB_degc"] {
        assert!(
            w.col(s)[0] > c.col(s)[0] + 3.0,
            "spindle sensor {s} warms by > 3 °C"
        );
    }
    assert!(
        hotter.len() >= 4,
        "several sensors warmed by > 1 °C: {hotter:?}"
    );

    // Thermal part of |E|: negligible cold (a minute of motion), > 10 µm warm.
    let th = ["thermal_ex_um", "thermal_ey_um", "thermal_ez_um"];
    let cold_th_max = c.vectors(th).into_iter().map(norm).fold(0.0, f64::max);
    let warm_th_max = w.vectors(th).into_iter().map(norm).fold(0.0, f64::max);
    let warm_th_min = w.vectors(th).into_iter().map(norm).fold(f64::MAX, f64::min);
    println!("thermal part of |E|: cold max {cold_th_max:.3} µm, warm {warm_th_min:.2}…{warm_th_max:.2} µm");
    assert!(cold_th_max < 1.0, "cold thermal part {cold_th_max} µm");
    assert!(
        warm_th_min > 10.0,
        "warm thermal part {warm_th_min} µm at some point"
    );
    // The table's therm_um column and the summary agree with the samples.
    let table_therm: f64 = table_rows(&stdout(&warm))
        .iter()
        .map(|r| r.therm_um)
        .fold(0.0, f64::max);
    assert!(
        (table_therm - warm_th_max).abs() < 0.01,
        "table {table_therm} vs csv {warm_th_max}"
    );
    let js = read_json(&tmp.path().join("warm/summary.json"));
    assert!((stats4(&js, "thermal_part", "max_abs_um")[3] - warm_th_max).abs() < 0.01);

    // The errors differ, and the difference is the change of the thermal part. What remains is
    // the non-repeatability (σ 0.25–0.3 µm per axis, drawn independently in the two runs since
    // the warm-up's dwells draw too): 3 µm is > 7σ of the difference of two draws.
    let ec = c.vectors(["ex_um", "ey_um", "ez_um"]);
    let ew = w.vectors(["ex_um", "ey_um", "ez_um"]);
    let (tc, tw) = (c.vectors(th), w.vectors(th));
    let mut max_change: f64 = 0.0;
    let mut max_unexplained: f64 = 0.0;
    for i in 0..10 {
        for a in 0..3 {
            let change = ew[i][a] - ec[i][a];
            let thermal_change = tw[i][a] - tc[i][a];
            max_change = max_change.max(change.abs());
            max_unexplained = max_unexplained.max((change - thermal_change).abs());
        }
    }
    println!("warm − cold error: max {max_change:.2} µm, unexplained by the thermal part: max {max_unexplained:.2} µm");
    assert!(
        max_change > 10.0,
        "warm-up changed the errors by only {max_change} µm"
    );
    assert!(
        max_unexplained < 3.0,
        "{max_unexplained} µm of the change is not thermal"
    );
}

#[test]
fn another_seed_is_another_machine_and_the_same_seed_is_the_same_run() {
    let tmp = TempDir::new("seed");
    let a = vmc(tmp.path(), &["run", &diag_xy(), "--seed", "1"]);
    let b = vmc(tmp.path(), &["run", &diag_xy(), "--seed", "1"]);
    let c = vmc(tmp.path(), &["run", &diag_xy(), "--seed", "2"]);
    for o in [&a, &b, &c] {
        assert_success(o, "seeded run");
    }
    assert_eq!(a.stdout, b.stdout, "same seed ⇒ byte-identical output");
    let (ra, rc) = (table_rows(&stdout(&a)), table_rows(&stdout(&c)));
    assert_eq!((ra.len(), rc.len()), (10, 10));
    let max_diff = ra
        .iter()
        .zip(&rc)
        .flat_map(|(x, y)| (0..3).map(move |k| (x.e_um[k] - y.e_um[k]).abs()))
        .fold(0.0, f64::max);
    // Random profile parts have σ ≈ 1 µm (positioning) and a few µrad (angles).
    assert!(
        max_diff > 0.5,
        "seed 2 differs from seed 1 by only {max_diff} µm"
    );
}

/// A failed run: non-zero exit, exactly one line on stderr containing every fragment, no panic.
fn assert_one_line_failure(o: &Output, fragments: &[&str]) {
    let err = stderr(o);
    assert!(
        !o.status.success(),
        "expected failure; stdout:\n{}",
        stdout(o)
    );
    assert_eq!(
        o.status.code(),
        Some(1),
        "a handled error exits with 1, not a panic's 101: {err}"
    );
    assert!(!err.contains("panicked"), "panic: {err}");
    assert_eq!(
        err.trim_end().lines().count(),
        1,
        "one line on stderr:\n{err}"
    );
    for f in fragments {
        assert!(err.contains(f), "stderr lacks {f:?}:\n{err}");
    }
}

#[test]
fn a_missing_program_is_one_line_naming_it() {
    let tmp = TempDir::new("missing");
    let o = vmc(tmp.path(), &["run", "nonexistent.ngc"]);
    assert_one_line_failure(&o, &["nonexistent.ngc", "cannot read"]);
}

#[test]
fn an_arc_without_centre_or_radius_names_the_line_and_column() {
    let tmp = TempDir::new("arc");
    let prog = repo_file("tests/data/g2_without_centre.ngc")
        .display()
        .to_string();
    let o = vmc(tmp.path(), &["run", &prog]);
    assert_one_line_failure(
        &o,
        &[
            "g2_without_centre.ngc",
            "line 3, column 5",
            "G2",
            "I/J/K or R",
        ],
    );
}

#[test]
fn lobes_writes_the_csv_of_its_table_and_refuses_bad_input_in_one_line() {
    let tmp = TempDir::new("lobes");
    let o = vmc(
        tmp.path(),
        &[
            "lobes",
            "--method",
            "zoa",
            "--rpm",
            "5000:15000:11",
            "--out",
            "l.csv",
        ],
    );
    assert_success(&o, "lobes");
    let out = stdout(&o);
    assert!(out.contains("minimum critical depth"), "{out}");
    let csv = std::fs::read_to_string(tmp.path().join("l.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(
        rows[0],
        "spindle_rpm,critical_depth_mm,chatter_frequency_hz,kind,steps_per_period"
    );
    assert_eq!(rows.len(), 12, "{csv}");
    // The zero-order solution has no time steps: the column is empty, the table says `-`.
    assert!(rows[1..].iter().all(|r| r.ends_with(',')), "{csv}");
    assert!(out.contains("resolution: analytic in frequency"), "{out}");
    // The printed minimum is the smallest depth of the file.
    let min = rows[1..]
        .iter()
        .map(|r| r.split(',').nth(1).unwrap().parse::<f64>().unwrap())
        .fold(f64::INFINITY, f64::min);
    assert!(
        out.contains(&format!("minimum critical depth {min:.3} mm")),
        "{out}\n{csv}"
    );
    // The file is not overwritten without --force.
    let again = vmc(tmp.path(), &["lobes", "--rpm", "5000", "--out", "l.csv"]);
    assert!(!again.status.success());
    assert!(stderr(&again).contains("--force"), "{}", stderr(&again));
    std::fs::write(tmp.path().join("bad.toml"), "[tool]\nteeth = 0\ndiameter_mm = 10\nkt_n_per_m2 = 1e8\nkn_n_per_m2 = 1e8\n[[modes.x]]\nfrequency_hz = 900\ndamping_ratio = 0.01\nstiffness_n_per_m = 1e6\n").unwrap();
    for (args, want) in [
        (
            &["lobes", "--immersion", "0"][..],
            "--immersion: immersion a_e/D must be in [0.01, 1] (a radial depth of at least 1 % of the tool diameter), got 0",
        ),
        (
            &["lobes", "--rpm", "0"][..],
            "--rpm: a spindle speed must be > 0 rpm, got 0",
        ),
        (
            &["lobes", "--tool", "bad.toml"][..],
            "bad.toml: the tool has no teeth",
        ),
        (&["lobes", "--steps", "3"][..], "--steps must be >= 4, got 3"),
        (
            &["lobes", "--method", "zoa", "--steps", "40"][..],
            "--steps sets the semi-discretisation's resolution: it applies to --method sdm (and --controller) only",
        ),
    ] {
        let o = vmc(tmp.path(), args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert_eq!(
            stderr(&o).trim(),
            format!("vmc-twin: error: {want}"),
            "{args:?}"
        );
    }
}

#[test]
fn a_recording_may_go_into_the_output_folder_the_command_creates() {
    // The folder `o` does not exist before: `--out o/xy` creates it, then the recording's path
    // is checked.
    let tmp = TempDir::new("rrd-in-out");
    let o = vmc(
        tmp.path(),
        &["run", &diag_xy(), "--out", "o/xy", "--rrd", "o/xy.rrd"],
    );
    assert_success(&o, "run");
    assert!(tmp.path().join("o/xy.rrd").is_file());
    assert!(tmp.path().join("o/xy/summary.json").is_file());
}
