//! LinuxCNC's example subroutines that probe with G38.2 … G38.5 (basic_probe, the probe
//! folder's edge finders, probe-hole, rectangle_probe, touchoff), each called by a program of
//! ours in `tests/data/linuxcnc/probe-calls/` that then moves to the probe parameters
//! (X Y Z to #5061 #5062 #5063, A to #5070), run as LinuxCNC's stand-alone `rs274` runs them:
//! the moves, `STRAIGHT_PROBE` targets included, equal its stored output
//! (`scripts/linuxcnc-probe-calls.sh`) within 1e-4 of the program's unit, so the parameters
//! after each probe are its parameters. With `rs274` installed, the stored outputs are also
//! checked against a fresh run.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

mod common;
use common::rs274::{compare, fixture_config, fixture_tool_table, ours, parse_expected};
use common::rs274::{rs274_binary, RefMove};
use vmc_gcode::interp::{run_program, InterpConfig};

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/linuxcnc")
}

/// The calling programs and the folder (under `nc_files`) of the subroutine each calls.
fn callers() -> Vec<(PathBuf, PathBuf)> {
    let mut out: Vec<(PathBuf, PathBuf)> = fs::read_dir(corpus().join("probe-calls"))
        .expect("probe-calls folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "ngc"))
        .map(|p| {
            let text = fs::read_to_string(&p).expect("caller");
            let first = text.lines().next().unwrap_or_default();
            let dir = first
                .strip_prefix("(subroutines: ")
                .and_then(|d| d.strip_suffix(')'))
                .unwrap_or_else(|| panic!("{}: no (subroutines: DIR) line", p.display()));
            (p.clone(), corpus().join("nc_files").join(dir))
        })
        .collect();
    out.sort();
    out
}

#[test]
fn linuxcnc_probing_subroutines_move_and_set_the_probe_parameters_as_rs274() {
    let callers = callers();
    assert!(callers.len() >= 15, "only {} callers", callers.len());
    let mut probes = 0;
    let mut failures = Vec::new();
    for (program, dir) in &callers {
        let out = PathBuf::from(format!("{}.out", program.display()));
        let reference = parse_expected(&fs::read_to_string(&out).expect("stored rs274 output"));
        let cfg = InterpConfig {
            subroutine_dirs: vec![dir.clone()],
            ..fixture_config()
        };
        let text = fs::read_to_string(program).expect("caller");
        let name = program.file_name().and_then(|f| f.to_str()).unwrap_or("?");
        let moves = match run_program(&text, &cfg) {
            Ok(moves) => moves,
            Err(e) => {
                failures.push(format!("{name}: refused: {e}"));
                continue;
            }
        };
        let mine = ours(&moves);
        if let Some(diff) = compare(&mine, &reference) {
            failures.push(format!("{name}: {diff}"));
            continue;
        }
        let n = mine
            .iter()
            .filter(|m| matches!(m, RefMove::Probe(_)))
            .count();
        assert!(n > 0, "{}: no probe move", program.display());
        probes += n;
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    println!(
        "{} probing subroutines, {probes} probe moves as rs274",
        callers.len()
    );
}

#[test]
fn the_stored_rs274_outputs_are_what_rs274_prints() {
    let Some(bin) = rs274_binary() else {
        println!("rs274 not installed: stored outputs not rechecked");
        return;
    };
    for (program, dir) in callers() {
        // A private HOME: rs274 keeps its tool table in $HOME/.tool.mmap.
        let home = std::env::temp_dir().join(format!(
            "vmc-probe-calls-{}-{}",
            std::process::id(),
            program.file_stem().and_then(|s| s.to_str()).unwrap_or("p")
        ));
        fs::create_dir_all(&home).expect("temp HOME");
        let fresh = Command::new(&bin)
            .arg("-g")
            .arg("-t")
            .arg(fixture_tool_table())
            .arg(&program)
            .current_dir(&dir)
            .env("HOME", &home)
            .stdin(Stdio::null())
            .output()
            .expect("rs274 runs");
        let _ = fs::remove_dir_all(&home);
        let fresh = parse_expected(&String::from_utf8_lossy(&fresh.stdout));
        let stored = parse_expected(
            &fs::read_to_string(format!("{}.out", program.display())).expect("stored"),
        );
        let fresh: Vec<RefMove> = fresh.into_iter().map(|(m, _)| m).collect();
        assert!(
            compare(&fresh, &stored).is_none(),
            "{}: stored output is stale (scripts/linuxcnc-probe-calls.sh)",
            program.display()
        );
    }
}
