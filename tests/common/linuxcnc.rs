//! What the LinuxCNC tests share: whether LinuxCNC can run here (a script's `--probe`), the
//! output of a script, and the HAL component `vmc_comp` built for a test
//! (`deploy/linuxcnc/build-comp.sh` with the vmc-rtcomp static library cargo built for this
//! test run, a dev-dependency of the root crate, so no nested cargo build runs inside a test).
#![allow(dead_code)] // each test crate uses its own subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A script of `deploy/linuxcnc`.
pub fn script(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("deploy/linuxcnc")
        .join(name)
}

/// Standard output and standard error of a command, together.
pub fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// Whether `script --probe` says it can run here (exit 0; 77 and the reason: not here, printed,
/// and a failure under `VMC_REQUIRE_LINUXCNC=1`).
pub fn available(script_name: &str) -> bool {
    let out = Command::new(script(script_name))
        .arg("--probe")
        .output()
        .unwrap_or_else(|e| panic!("{script_name} starts: {e}"));
    match out.status.code() {
        Some(0) => true,
        Some(77) => {
            let reason = text(&out);
            let required = std::env::var("VMC_REQUIRE_LINUXCNC").is_ok_and(|v| v == "1");
            assert!(!required, "VMC_REQUIRE_LINUXCNC=1 but {reason}");
            eprintln!("{reason}");
            false
        }
        _ => panic!("{script_name} --probe: {}", text(&out)),
    }
}

/// The static library cargo built for this test (a dev-dependency), newest first.
pub fn static_library() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's path");
    let deps = exe.parent().expect("the deps folder");
    let mut found: Vec<(std::time::SystemTime, PathBuf)> = std::fs::read_dir(deps)
        .expect("the deps folder lists")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("libvmc_rtcomp") && n.ends_with(".a"))
        })
        .filter_map(|p| Some((p.metadata().ok()?.modified().ok()?, p)))
        .collect();
    found.sort();
    found
        .pop()
        .expect("cargo built libvmc_rtcomp.a next to the test")
        .1
}

/// Builds the module into `dir` with the library of this build; gives its path.
pub fn build_module(dir: &Path) -> PathBuf {
    let out = Command::new(script("build-comp.sh"))
        .arg("--lib")
        .arg(static_library())
        .arg("--out")
        .arg(dir)
        .output()
        .expect("build-comp.sh starts");
    assert!(out.status.success(), "build-comp.sh: {}", text(&out));
    dir.join("vmc_comp.so")
}
