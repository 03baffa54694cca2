//! Hostile inputs on the real binary that used to give a silent wrong result, a crash or no
//! bound on the work: each is refused in one line naming the file and field (or line), or
//! handled and said so.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_vmc-twin");

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

struct Tmp(PathBuf);

impl Tmp {
    fn new(tag: &str) -> Self {
        let d = std::env::temp_dir().join(format!("vmc-twin-hostile-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        Tmp(d)
    }
}

impl Drop for Tmp {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn vmc(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

/// The one-line error of a refused command (exit 1, not a panic's 101).
fn one_line_error(dir: &Path, args: &[&str]) -> String {
    let o = vmc(dir, args);
    let err = String::from_utf8_lossy(&o.stderr).trim_end().to_string();
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    err
}

#[test]
fn implausible_machine_values_are_refused_naming_file_and_field() {
    let t = Tmp::new("machine");
    let reference = std::fs::read_to_string(repo("machines/vmc-reference.toml")).unwrap();
    let prog = repo("trajectories/diag_xy.ngc").display().to_string();
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
        std::fs::write(t.0.join("m.toml"), reference.replacen(from, to, 1)).unwrap();
        let err = one_line_error(&t.0, &["run", &prog, "--machine", "m.toml"]);
        assert!(
            err.contains("m.toml: field `") && err.contains(field),
            "{err}"
        );
        assert!(err.contains("is not plausible for"), "{err}");
    }
}

#[test]
fn a_machine_with_more_thermal_nodes_than_the_limit_says_how_to_go_beyond() {
    let t = Tmp::new("nodes");
    let reference = std::fs::read_to_string(repo("machines/vmc-reference.toml")).unwrap();
    let extra: String = (0..1000)
        .map(|i| format!("  {{ name = \"extra_{i}\", capacity_j_per_k = 100.0 }},\n"))
        .collect();
    let text = reference.replacen("nodes = [\n", &format!("nodes = [\n{extra}"), 1);
    std::fs::write(t.0.join("m.toml"), text).unwrap();
    let prog = repo("trajectories/diag_xy.ngc").display().to_string();
    let err = one_line_error(&t.0, &["check", &prog, "--machine", "m.toml"]);
    assert!(err.contains("more than the limit of 1000"), "{err}");
    assert!(err.contains("VMC_TWIN_MAX_THERMAL_NODES"), "{err}");
}

#[test]
fn a_speed_range_of_count_one_with_two_ends_and_an_endless_range_are_refused() {
    let t = Tmp::new("lobes");
    let err = one_line_error(&t.0, &["lobes", "--rpm", "5000:6000:1"]);
    assert!(err.contains("cannot include both ends"), "{err}");
    let err = one_line_error(&t.0, &["lobes", "--rpm", "5000:6000:100000000"]);
    assert!(err.contains("limit of 20000"), "{err}");
}

#[test]
fn an_edited_shard_result_is_refused_naming_the_file_of_its_own_shard() {
    let t = Tmp::new("shard");
    for s in ["1/2", "2/2"] {
        let name = format!("s{}", &s[..1]);
        let o = vmc(
            &t.0,
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
    assert!(vmc(&t.0, &merge).status.success());
    // One number changed by hand in shard 1, then the file emptied: both refused, shard 1 named.
    let points = t.0.join("s1/lobes.jsonl");
    let text = std::fs::read_to_string(&points).unwrap();
    let edited = text.replacen("\"spindle_rpm\":5000", "\"spindle_rpm\":5000.0", 1);
    for bad in [edited.as_str(), ""] {
        std::fs::write(&points, bad).unwrap();
        let err = one_line_error(&t.0, &["merge", "s1", "s2", "--out", "m2"]);
        assert!(
            err.contains("s1/lobes.jsonl: changed since its shard wrote it"),
            "{err}"
        );
    }
    // A file its shard did not write.
    std::fs::write(&points, &text).unwrap();
    std::fs::write(t.0.join("s2/extra.json"), "{\"x\":1}").unwrap();
    let err = one_line_error(&t.0, &["merge", "s1", "s2", "--out", "m3"]);
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
    let t = Tmp::new("order");
    // Swap the times of the first two data rows (lines 3 and 4 of the file).
    calibration_edited(&t.0, |text| {
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        let mut a: Vec<String> = lines[2].split(',').map(String::from).collect();
        let mut b: Vec<String> = lines[3].split(',').map(String::from).collect();
        std::mem::swap(&mut a[1], &mut b[1]);
        lines[2] = a.join(",");
        lines[3] = b.join(",");
        lines.join("\n") + "\n"
    });
    let err = one_line_error(
        &t.0,
        &[
            "train", "--data", "c.csv", "--kind", "linear", "-o", "m.json",
        ],
    );
    assert!(
        err.contains("line 4") && err.contains("time order"),
        "{err}"
    );
    calibration_edited(&t.0, |text| {
        text.replacen("\ncal_3000rpm,0,", "\ncal_3000rpm,-5,", 1)
    });
    let o = vmc(
        &t.0,
        &[
            "train", "--data", "c.csv", "--kind", "linear", "-o", "m.json",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("negative time"), "{err}");
}

#[test]
fn a_byte_order_mark_before_the_header_is_not_part_of_the_first_column_name() {
    let t = Tmp::new("bom");
    let data = std::fs::read(repo("tests/data/spindle-thermal/train_every60s.csv")).unwrap();
    let mut with_bom = vec![0xEF, 0xBB, 0xBF];
    with_bom.extend(data);
    std::fs::write(t.0.join("d.csv"), with_bom).unwrap();
    let o = vmc(
        &t.0,
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
        &t.0,
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
    let t = Tmp::new("still");
    let text =
        std::fs::read_to_string(repo("tests/data/spindle-thermal/train_every60s.csv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let rpm = header.split(',').position(|c| c == "spindle_rpm").unwrap();
    let mut out = vec![header.to_string()];
    for l in lines {
        let mut c: Vec<&str> = l.split(',').collect();
        c[rpm] = "0";
        out.push(c.join(","));
    }
    std::fs::write(t.0.join("z.csv"), out.join("\n") + "\n").unwrap();
    let err = one_line_error(
        &t.0,
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
