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
