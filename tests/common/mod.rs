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
