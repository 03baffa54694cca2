//! Hostile inputs on the real binary that used to give a silent wrong result, a crash or no
//! bound on the work: each is refused in one line naming the file and field (or line), or
//! handled and said so.

mod common;
use common::{ok, refused, repo_file, vmc, TempDir};
use std::path::Path;

/// The one-line error of a refused command.
fn one_line_error(dir: &Path, args: &[&str]) -> String {
    refused(&vmc(dir, args), &format!("{args:?}"))
        .trim_end()
        .to_string()
}

#[test]
fn implausible_machine_values_are_refused_naming_file_and_field() {
    let t = TempDir::new("machine");
    let reference = std::fs::read_to_string(repo_file("machines/vmc-reference.toml")).unwrap();
    let prog = repo_file("trajectories/diag_xy.ngc").display().to_string();
    let cases = [
        (
            "temp_degc = 20.0 }",
            "temp_degc = 1e6 }",
            "thermal.ambient.temp_degc",
        ),
        (
            "temp_degc = 20.0 }",
            "temp_degc = -300.0 }",
            "thermal.ambient.temp_degc",
        ),
        (
            "poly = [0.0, -15.0, -4.0]",
            "poly = [0.0, -15e300, -4.0]",
            "errors.motion.EXX.poly[1]",
        ),
        (
            "torque_n_m = 1.2,",
            "torque_n_m = 4e12,",
            "thermal.sources[3].torque_n_m",
        ),
        (
            "capacity_j_per_k = 2500.0",
            "capacity_j_per_k = 1e300",
            "thermal.nodes[0].capacity_j_per_k",
        ),
    ];
    for (from, to, field) in cases {
        assert_eq!(reference.matches(from).count(), 1, "{from}");
        std::fs::write(t.path().join("m.toml"), reference.replacen(from, to, 1)).unwrap();
        let err = one_line_error(t.path(), &["run", &prog, "--machine", "m.toml"]);
        assert!(
            err.contains("m.toml: field `") && err.contains(field),
            "{err}"
        );
        assert!(err.contains("is not plausible for"), "{err}");
    }
}

#[test]
fn a_machine_with_more_thermal_nodes_than_the_limit_says_how_to_go_beyond() {
    let t = TempDir::new("nodes");
    let reference = std::fs::read_to_string(repo_file("machines/vmc-reference.toml")).unwrap();
    let extra: String = (0..1000)
        .map(|i| format!("  {{ name = \"extra_{i}\", capacity_j_per_k = 100.0 }},\n"))
        .collect();
    let text = reference.replacen("nodes = [\n", &format!("nodes = [\n{extra}"), 1);
    std::fs::write(t.path().join("m.toml"), text).unwrap();
    let prog = repo_file("trajectories/diag_xy.ngc").display().to_string();
    let err = one_line_error(t.path(), &["check", &prog, "--machine", "m.toml"]);
    assert!(err.contains("more than the limit of 1000"), "{err}");
    assert!(err.contains("VMC_TWIN_MAX_THERMAL_NODES"), "{err}");
}

#[test]
fn a_speed_range_of_count_one_with_two_ends_and_an_endless_range_are_refused() {
    let t = TempDir::new("lobes");
    let err = one_line_error(t.path(), &["lobes", "--rpm", "5000:6000:1"]);
    assert!(err.contains("cannot include both ends"), "{err}");
    let err = one_line_error(t.path(), &["lobes", "--rpm", "5000:6000:100000000"]);
    assert!(err.contains("limit of 20000"), "{err}");
}

#[test]
fn an_edited_shard_result_is_refused_naming_the_file_of_its_own_shard() {
    let t = TempDir::new("shard");
    for s in ["1/2", "2/2"] {
        let name = format!("s{}", &s[..1]);
        let o = vmc(
            t.path(),
            &[
                "lobes",
                "--immersion",
                "0.05",
                "--rpm",
                "5000:25000:5",
                "--shard",
                s,
                "--shard-dir",
                &name,
            ],
        );
        assert!(o.status.success(), "{o:?}");
    }
    let merge = ["merge", "s1", "s2", "--out", "m"];
    assert!(vmc(t.path(), &merge).status.success());
    // One number changed by hand in shard 1, then the file emptied: both refused, shard 1 named.
    let points = t.path().join("s1/lobes.jsonl");
    let text = std::fs::read_to_string(&points).unwrap();
    let edited = text.replacen("\"spindle_rpm\":5000", "\"spindle_rpm\":5000.0", 1);
    for bad in [edited.as_str(), ""] {
        std::fs::write(&points, bad).unwrap();
        let err = one_line_error(t.path(), &["merge", "s1", "s2", "--out", "m2"]);
        assert!(
            err.contains("s1/lobes.jsonl: changed since its shard wrote it"),
            "{err}"
        );
    }
    // A file its shard did not write.
    std::fs::write(&points, &text).unwrap();
    std::fs::write(t.path().join("s2/extra.json"), "{\"x\":1}").unwrap();
    let err = one_line_error(t.path(), &["merge", "s1", "s2", "--out", "m3"]);
    assert!(
        err.contains("s2/extra.json: not among the result files"),
        "{err}"
    );
}

/// A calibration dataset from the binary, then edited by `edit`.
fn calibration_edited(dir: &Path, edit: impl Fn(&str) -> String) {
    let o = vmc(
        dir,
        &[
            "calibrate",
            "--measure-every-min",
            "120",
            "-o",
            "c.csv",
            "--force",
        ],
    );
    assert!(o.status.success(), "{o:?}");
    let text = std::fs::read_to_string(dir.join("c.csv")).unwrap();
    std::fs::write(dir.join("c.csv"), edit(&text)).unwrap();
}

#[test]
fn training_data_out_of_time_order_or_before_time_zero_is_refused_with_its_line() {
    let t = TempDir::new("order");
    // Swap the times of the first two data rows (lines 3 and 4 of the file).
    calibration_edited(t.path(), |text| {
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        let mut a: Vec<String> = lines[2].split(',').map(String::from).collect();
        let mut b: Vec<String> = lines[3].split(',').map(String::from).collect();
        std::mem::swap(&mut a[1], &mut b[1]);
        lines[2] = a.join(",");
        lines[3] = b.join(",");
        lines.join("\n") + "\n"
    });
    let err = one_line_error(
        t.path(),
        &[
            "train", "--data", "c.csv", "--kind", "linear", "-o", "m.json",
        ],
    );
    assert!(
        err.contains("line 4") && err.contains("time order"),
        "{err}"
    );
    calibration_edited(t.path(), |text| {
        text.replacen("\ncal_3000rpm,0,", "\ncal_3000rpm,-5,", 1)
    });
    let o = vmc(
        t.path(),
        &[
            "train", "--data", "c.csv", "--kind", "linear", "-o", "m.json",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("negative time"), "{err}");
}

#[test]
fn a_byte_order_mark_before_the_header_is_not_part_of_the_first_column_name() {
    let t = TempDir::new("bom");
    let data = std::fs::read(repo_file("tests/data/spindle-thermal/train_every60s.csv")).unwrap();
    let mut with_bom = vec![0xEF, 0xBB, 0xBF];
    with_bom.extend(data);
    std::fs::write(t.path().join("d.csv"), with_bom).unwrap();
    let o = vmc(
        t.path(),
        &[
            "fit-thermal",
            "--data",
            "d.csv",
            "--inputs",
            "t1_degc",
            "--outputs",
            "ch1_um",
            "--arch",
            "linear",
            "-o",
            "m.json",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The work limit on rows, with the option that lifts it.
    let err = one_line_error(
        t.path(),
        &[
            "fit-thermal",
            "--data",
            "d.csv",
            "--inputs",
            "t1_degc",
            "--outputs",
            "ch1_um",
            "--arch",
            "linear",
            "-o",
            "m2.json",
            "--max-rows",
            "100",
        ],
    );
    assert!(
        err.contains("more than the limit of 100") && err.contains("--max-rows"),
        "{err}"
    );
}

#[test]
fn identify_thermal_on_data_where_the_spindle_never_turns_is_refused() {
    let t = TempDir::new("still");
    let text = std::fs::read_to_string(repo_file("tests/data/spindle-thermal/train_every60s.csv"))
        .unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let rpm = header.split(',').position(|c| c == "spindle_rpm").unwrap();
    let mut out = vec![header.to_string()];
    for l in lines {
        let mut c: Vec<&str> = l.split(',').collect();
        c[rpm] = "0";
        out.push(c.join(","));
    }
    std::fs::write(t.path().join("z.csv"), out.join("\n") + "\n").unwrap();
    let err = one_line_error(
        t.path(),
        &[
            "identify-thermal",
            "--data",
            "z.csv",
            "--rpm",
            "spindle_rpm",
            "--drifts",
            "ch1_um",
            "--temps",
            "t1_degc",
            "-o",
            "f.toml",
        ],
    );
    assert!(err.contains("0 rpm on every row"), "{err}");
}

/// The spindle slice split at row `at`: the rows before (the past) and from there on (a file
/// that starts in the middle of the test), each with the header.
fn split_spindle_data(dir: &Path, at: usize) {
    let text = std::fs::read_to_string(repo_file("tests/data/spindle-thermal/train_every60s.csv"))
        .unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let past = lines[..at].join("\n") + "\n";
    let now = [&lines[..1], &lines[at..]].concat().join("\n") + "\n";
    std::fs::write(dir.join("all.csv"), &text).unwrap();
    std::fs::write(dir.join("past.csv"), past).unwrap();
    std::fs::write(dir.join("now.csv"), now).unwrap();
}

#[test]
fn predicting_a_file_that_starts_mid_test_warns_refuses_under_strict_and_takes_its_history() {
    let t = TempDir::new("history");
    split_spindle_data(t.path(), 1001); // the past: 1,000 rows of 60 s, 16.7 h
    let fit = [
        "fit-thermal",
        "--data",
        "all.csv",
        "--inputs",
        "t1_degc,t2_degc,spindle_rpm",
        "--outputs",
        "ch1_um,ch3_um",
        "--arch",
        "linear",
        "-o",
        "m.json",
    ];
    ok(&vmc(t.path(), &fit), "fit-thermal");
    let predict = |extra: &[&str], out: &str| {
        let args = [
            &["predict-thermal", "--model", "m.json", "-o", out][..],
            extra,
        ]
        .concat();
        vmc(t.path(), &args)
    };
    // No history: a warning that states the memory and how many rows it spoils.
    let warned = ok(&predict(&["--data", "now.csv"], "cold.csv"), "cold start");
    let warning = warned.lines().next().unwrap();
    assert!(
        warning.starts_with("warning: now.csv: the model remembers"),
        "{warning}"
    );
    assert!(warning.contains("no history is given") && warning.contains("--history FILE"));
    // --strict refuses the same file and writes nothing.
    let err = refused(
        &predict(&["--data", "now.csv", "--strict"], "s.csv"),
        "strict",
    );
    assert!(
        err.contains("(--strict)") && err.contains("remembers"),
        "{err}"
    );
    assert!(!t.path().join("s.csv").exists());
    // Too short a history still warns, naming what it covers (12,000 s of 60 s rows).
    let text = std::fs::read_to_string(t.path().join("past.csv")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let short = [&lines[..1], &lines[lines.len() - 200..]]
        .concat()
        .join("\n")
        + "\n";
    std::fs::write(t.path().join("short.csv"), short).unwrap();
    let out = ok(
        &predict(
            &["--data", "now.csv", "--history", "short.csv"],
            "short_p.csv",
        ),
        "short history",
    );
    assert!(
        out.contains("its history short.csv covers 12000 s"),
        "{out}"
    );
    // A full history: no warning, and the predictions are those of the whole file's rows.
    let out = ok(
        &predict(
            &["--data", "now.csv", "--history", "past.csv", "--strict"],
            "warm.csv",
        ),
        "with history",
    );
    assert!(!out.contains("warning"), "{out}");
    ok(
        &predict(&["--data", "all.csv", "--starts-at-rest"], "whole.csv"),
        "whole",
    );
    let warm = std::fs::read_to_string(t.path().join("warm.csv")).unwrap();
    let whole = std::fs::read_to_string(t.path().join("whole.csv")).unwrap();
    let tail: Vec<&str> = whole.lines().skip(1001).collect();
    let warm_rows: Vec<&str> = warm.lines().skip(1).collect();
    assert_eq!(warm_rows, tail);
    let cold = std::fs::read_to_string(t.path().join("cold.csv")).unwrap();
    assert_ne!(
        cold.lines().nth(1),
        warm.lines().nth(1),
        "the history matters"
    );
    // A history that does not end before the data begins is refused.
    let err = refused(
        &predict(&["--data", "now.csv", "--history", "all.csv"], "x.csv"),
        "overlapping history",
    );
    assert!(
        err.contains("all.csv: the history ends at t = 115620 s"),
        "{err}"
    );
}
