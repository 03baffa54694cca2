//! The HAL component `vmc_comp` built for a test: `deploy/linuxcnc/build-comp.sh` with the
//! vmc-rtcomp static library cargo built for this test run (a dev-dependency of the root
//! crate), so no nested cargo build runs inside a test.

use std::path::{Path, PathBuf};
use std::process::Command;

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
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("deploy/linuxcnc/build-comp.sh");
    let out = Command::new(script)
        .arg("--lib")
        .arg(static_library())
        .arg("--out")
        .arg(dir)
        .output()
        .expect("build-comp.sh starts");
    assert!(
        out.status.success(),
        "build-comp.sh: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    dir.join("vmc_comp.so")
}
