//! The C header against the Rust side: a C program compiled with the system's C compiler (the
//! one Rust links with) against `include/vmc_rtcomp.h`, strict C99, prints the structs' sizes
//! and field offsets and the status constants; they must be Rust's.

use std::mem::{offset_of, size_of};
use std::path::PathBuf;
use std::process::Command;

use vmc_rtcomp::{Inputs, Outputs, Status};

/// The C program: every layout fact and constant of the header, one `name value` per line.
const PROBE_C: &str = r#"
#include <stdio.h>
#include "vmc_rtcomp.h"
#define SHOW(e) printf("%s %ld\n", #e, (long)(e))
int main(void) {
    SHOW(sizeof(VmcCompInputs));
    SHOW(offsetof(VmcCompInputs, temps_degc));
    SHOW(offsetof(VmcCompInputs, n_temps));
    SHOW(offsetof(VmcCompInputs, time_s));
    SHOW(offsetof(VmcCompInputs, commanded_mm));
    SHOW(offsetof(VmcCompInputs, spindle_rpm));
    SHOW(offsetof(VmcCompInputs, axis_feed_mm_per_min));
    SHOW(offsetof(VmcCompInputs, new_sample));
    SHOW(sizeof(VmcCompOutputs));
    SHOW(offsetof(VmcCompOutputs, correction_mm));
    SHOW(offsetof(VmcCompOutputs, last_step_mm));
    SHOW(offsetof(VmcCompOutputs, iterations));
    SHOW(offsetof(VmcCompOutputs, status));
    SHOW(VMC_COMP_OK);
    SHOW(VMC_COMP_NOT_CONVERGED);
    SHOW(VMC_COMP_NO_READINGS);
    SHOW(VMC_COMP_NOT_FINITE);
    SHOW(VMC_COMP_BAD_INPUT);
    return 0;
}
"#;

#[test]
fn the_header_describes_the_rust_layout_and_constants() {
    let crate_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("header_probe");
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    let source = dir.join("probe.c");
    let exe = dir.join("probe");
    std::fs::write(&source, PROBE_C).expect("writes the probe");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let built = Command::new(&cc)
        .args(["-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-I"])
        .arg(crate_dir.join("include"))
        .arg(&source)
        .arg("-o")
        .arg(&exe)
        .output()
        .unwrap_or_else(|e| panic!("the C compiler `{cc}` (set CC) could not run: {e}"));
    assert!(
        built.status.success(),
        "the header does not compile:\n{}",
        String::from_utf8_lossy(&built.stderr)
    );
    let run = Command::new(&exe).output().expect("the probe runs");
    let text = String::from_utf8_lossy(&run.stdout);
    let c: std::collections::HashMap<&str, i64> = text
        .lines()
        .filter_map(|l| l.rsplit_once(' '))
        .map(|(k, v)| (k, v.parse().expect("a number")))
        .collect();
    let rust = [
        ("sizeof(VmcCompInputs)", size_of::<Inputs>()),
        (
            "offsetof(VmcCompInputs, temps_degc)",
            offset_of!(Inputs, temps_degc),
        ),
        (
            "offsetof(VmcCompInputs, n_temps)",
            offset_of!(Inputs, n_temps),
        ),
        (
            "offsetof(VmcCompInputs, time_s)",
            offset_of!(Inputs, time_s),
        ),
        (
            "offsetof(VmcCompInputs, commanded_mm)",
            offset_of!(Inputs, commanded_mm),
        ),
        (
            "offsetof(VmcCompInputs, spindle_rpm)",
            offset_of!(Inputs, spindle_rpm),
        ),
        (
            "offsetof(VmcCompInputs, axis_feed_mm_per_min)",
            offset_of!(Inputs, axis_feed_mm_per_min),
        ),
        (
            "offsetof(VmcCompInputs, new_sample)",
            offset_of!(Inputs, new_sample),
        ),
        ("sizeof(VmcCompOutputs)", size_of::<Outputs>()),
        (
            "offsetof(VmcCompOutputs, correction_mm)",
            offset_of!(Outputs, correction_mm),
        ),
        (
            "offsetof(VmcCompOutputs, last_step_mm)",
            offset_of!(Outputs, last_step_mm),
        ),
        (
            "offsetof(VmcCompOutputs, iterations)",
            offset_of!(Outputs, iterations),
        ),
        (
            "offsetof(VmcCompOutputs, status)",
            offset_of!(Outputs, status),
        ),
    ];
    for (name, value) in rust {
        assert_eq!(
            c.get(name),
            Some(&(value as i64)),
            "{name}: C {:?}, Rust {value}",
            c.get(name)
        );
    }
    for (name, status) in [
        ("VMC_COMP_OK", Status::Ok),
        ("VMC_COMP_NOT_CONVERGED", Status::NotConverged),
        ("VMC_COMP_NO_READINGS", Status::NoReadings),
        ("VMC_COMP_NOT_FINITE", Status::NotFinite),
        ("VMC_COMP_BAD_INPUT", Status::BadInput),
    ] {
        assert_eq!(c.get(name), Some(&i64::from(status as i32)), "{name}");
    }
}
