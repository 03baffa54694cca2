//! Helpers shared by the integration tests that run the real binary in a temporary folder.
#![allow(dead_code, unused_imports)] // each test crate uses its own subset

#[path = "../../crates/vmc-gcode/tests/common/rs274.rs"]
pub mod rs274;
#[path = "../../crates/vmc-gcode/tests/common/temp_dir.rs"]
mod temp_dir;
pub use temp_dir::TempDir;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The binary under test.
pub const BIN: &str = env!("CARGO_BIN_EXE_vmc-twin");

/// A file of the repository (trajectories, test data).
pub fn repo_file(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Runs `vmc-twin <args>` with `cwd` as working folder.
pub fn vmc(cwd: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("the vmc-twin binary starts")
}

/// The standard output of a command that must succeed.
pub fn ok(out: &Output, what: &str) -> String {
    assert!(
        out.status.success(),
        "{what} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout.clone()).unwrap()
}

/// The standard error of a command that must fail: one line, `vmc-twin: error: …`.
pub fn refused(out: &Output, what: &str) -> String {
    assert!(!out.status.success(), "{what} was accepted");
    let err = String::from_utf8(out.stderr.clone()).unwrap();
    assert!(err.starts_with("vmc-twin: error: "), "{what}: {err}");
    assert_eq!(err.lines().count(), 1, "{what}: one line: {err}");
    err
}

/// A command's standard output (UTF-8).
pub fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).expect("stdout is UTF-8")
}

/// A command's standard error (UTF-8).
pub fn stderr(o: &Output) -> String {
    String::from_utf8(o.stderr.clone()).expect("stderr is UTF-8")
}

/// Runs `vmc-twin <args>` in `dir`, asserting success (else showing the status and both
/// streams); returns the standard output.
pub fn succeed(dir: &Path, args: &[&str]) -> String {
    let o = vmc(dir, args);
    assert!(
        o.status.success(),
        "{args:?}: {:?}\n{}\n{}",
        o.status,
        stdout(&o),
        stderr(&o)
    );
    stdout(&o)
}

/// Runs `vmc-twin <args>` in `dir`, asserting a clean refusal: exit status 1 (not a panic's
/// 101) and one line on stderr; returns that line without its `vmc-twin: error: ` prefix.
pub fn one_line_error(dir: &Path, args: &[&str]) -> String {
    let out = vmc(dir, args);
    let what = format!("{args:?}");
    let err = refused(&out, &what);
    assert_eq!(out.status.code(), Some(1), "{what}: {err}");
    err.trim_end()
        .strip_prefix("vmc-twin: error: ")
        .unwrap_or_else(|| panic!("{what}: prefix: {err}"))
        .to_string()
}

/// The `summary.json` that a run or replay wrote into `dir/folder`.
pub fn summary_json(dir: &Path, folder: &str) -> serde_json::Value {
    let path = dir.join(folder).join("summary.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Runs `vmc-twin args` in `dir` and returns its peak resident set size, kB: the child's
/// maximum resident set size as the kernel counts it (`getrusage(RUSAGE_CHILDREN)`, read
/// through `python3`). Fails the test if the command fails.
pub fn peak_rss_kb(dir: &Path, args: &[&str]) -> u64 {
    let script = "import resource, subprocess, sys\n\
                  r = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)\n\
                  sys.stderr.write(r.stderr.decode())\n\
                  print(r.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n";
    let out = Command::new("python3")
        .arg("-c")
        .arg(script)
        .arg(BIN)
        .args(args)
        .current_dir(dir)
        .output()
        .expect("python3 is needed to measure the peak memory of a child");
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let fields: Vec<&str> = text.split_whitespace().collect();
    assert_eq!(
        fields.first(),
        Some(&"0"),
        "vmc-twin {args:?} failed: {text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    fields[1].parse().expect("maxrss in kB")
}
