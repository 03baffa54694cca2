//! Differential fuzzing against LinuxCNC's stand-alone interpreter `rs274`: seeded random
//! milling programs (see `fuzz_rs274/generator.rs`) run through both interpreters; where both
//! accept a program, the moves must agree (end points and arc centres within 1e-4 of the
//! program's unit, plane, rotation, feed or traverse); a program `rs274` refuses must be
//! refused by us too.
//!
//! - `stored_rs274_outputs_agree`: the first [`STORED_PROGRAMS`] programs against `rs274`'s
//!   outputs stored in `tests/data/rs274-fuzz/expected.txt` (runs everywhere, no `rs274`
//!   needed).
//! - `generated_programs_move_as_rs274_does`: `VMC_FUZZ_PROGRAMS` programs against `rs274`
//!   itself, when that variable is set and `rs274` is installed (`$RS274` or on the PATH);
//!   skipped with a message otherwise. The full run: `VMC_FUZZ_PROGRAMS=10000 cargo test --release --test
//!   gcode_fuzz -- --nocapture`.
//! - `regenerate_stored_rs274_outputs` (ignored): rewrites the stored outputs with `rs274`.

mod common;
#[path = "fuzz_rs274/generator.rs"]
mod generator;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use common::rs274::{compare, fixture_config, ours, parse_expected, rs274_binary, run_rs274};
use vmc_gcode::interp::{run_program, CanonKind};

/// The seed of every generated program (program `i` is `generator::program(SEED, i)`).
const SEED: u64 = 0x5EED_2025;
/// Programs whose `rs274` output is stored in the repository.
const STORED_PROGRAMS: u64 = 200;

fn stored_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/rs274-fuzz/expected.txt")
}

/// How one program fared in both interpreters.
#[derive(Debug)]
enum Outcome {
    /// Both accept it and the moves agree: how many were probe moves.
    Matched { probes: usize },
    /// Both refuse it.
    BothRefuse,
    /// Both accept it, the moves differ.
    Mismatch(String),
    /// `rs274` refuses it, we accept it.
    OnlyRs274Refuses(String),
    /// We refuse it, `rs274` accepts it.
    OnlyWeRefuse(String),
}

fn judge(text: &str, reference: &Result<String, String>) -> Outcome {
    let mine = run_program(text, &fixture_config());
    match (mine, reference) {
        (Ok(moves), Ok(calls)) => match compare(&ours(&moves), &parse_expected(calls)) {
            None => Outcome::Matched {
                probes: moves
                    .iter()
                    .filter(|m| matches!(m.kind, CanonKind::Probe { .. }))
                    .count(),
            },
            Some(diff) => Outcome::Mismatch(diff),
        },
        (Err(_), Err(_)) => Outcome::BothRefuse,
        (Ok(_), Err(why)) => Outcome::OnlyRs274Refuses(why.clone()),
        (Err(e), Ok(_)) => Outcome::OnlyWeRefuse(e.to_string()),
    }
}

/// Counts of outcomes, with the first few failures described.
#[derive(Default)]
struct Tally {
    matched: usize,
    /// Programs both accept whose moves agree and hold probe moves; those probe moves.
    matched_probing: usize,
    probe_moves: usize,
    /// Programs (judged) with G80 beside another motion code in a block.
    g80_beside_motion: usize,
    both_refuse: usize,
    failures: Vec<String>,
    we_refuse: Vec<String>,
}

impl Tally {
    fn add(&mut self, index: u64, text: &str, outcome: Outcome) {
        if text.lines().any(g80_beside_motion) {
            self.g80_beside_motion += 1;
        }
        match outcome {
            Outcome::Matched { probes } => {
                self.matched += 1;
                self.matched_probing += usize::from(probes > 0);
                self.probe_moves += probes;
            }
            Outcome::BothRefuse => self.both_refuse += 1,
            Outcome::Mismatch(d) => self
                .failures
                .push(format!("program {index}: mismatch: {d}")),
            Outcome::OnlyRs274Refuses(why) => self
                .failures
                .push(format!("program {index}: rs274 refuses ({why}), we accept")),
            Outcome::OnlyWeRefuse(e) => self.we_refuse.push(format!("program {index}: {e}")),
        }
    }

    fn report_and_check(&self, what: &str) {
        println!(
            "{what}: both accept and agree {} (with probe moves {}, {} probe moves), both \
             refuse {}, only we refuse {}, failures {}; programs with G80 beside a motion \
             code {}",
            self.matched,
            self.matched_probing,
            self.probe_moves,
            self.both_refuse,
            self.we_refuse.len(),
            self.failures.len(),
            self.g80_beside_motion
        );
        for f in self.failures.iter().chain(&self.we_refuse).take(20) {
            println!("  {f}");
        }
        assert!(
            self.failures.is_empty() && self.we_refuse.is_empty(),
            "{what}: {} failures, {} refused by us only (program i is generator::program({SEED:#x}, i))",
            self.failures.len(),
            self.we_refuse.len()
        );
        assert!(self.matched > 0, "{what}: no program accepted by both");
    }
}

/// True if a line has G80 and another motion code (G0–G3, G38.x, a canned cycle).
fn g80_beside_motion(line: &str) -> bool {
    let codes: Vec<&str> = line
        .split_whitespace()
        .filter(|w| w.starts_with('G'))
        .collect();
    let motion = |c: &&str| {
        matches!(
            *c,
            "G0" | "G1" | "G2" | "G3" | "G73" | "G81" | "G82" | "G83" | "G85" | "G89"
        ) || c.starts_with("G38.")
    };
    codes.contains(&"G80") && codes.iter().any(motion)
}

/// The stored outputs: one entry per program, `Ok(calls)` or `Err(message)`.
fn read_stored() -> Vec<Result<String, String>> {
    let text = std::fs::read_to_string(stored_path()).expect("stored rs274 outputs");
    let mut entries: Vec<Result<String, String>> = Vec::new();
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("=== ") {
            let (_, verdict) = rest.split_once(' ').expect("=== <index> <verdict>");
            entries.push(match verdict.strip_prefix("refused: ") {
                Some(why) => Err(why.to_string()),
                None => Ok(String::new()),
            });
        } else if let Some(Ok(calls)) = entries.last_mut() {
            calls.push_str(line);
            calls.push('\n');
        }
    }
    entries
}

/// `rs274`'s calls that the comparison reads (the rest is left out of the stored file).
fn kept(call: &str) -> bool {
    [
        "USE_LENGTH_UNITS(",
        "SET_G5X_OFFSET(",
        "SET_G92_OFFSET(",
        "SET_XY_ROTATION(",
        "SELECT_PLANE(",
        "USE_TOOL_LENGTH_OFFSET(",
        "STRAIGHT_TRAVERSE(",
        "STRAIGHT_FEED(",
        "ARC_FEED(",
        "STRAIGHT_PROBE(",
        "PROGRAM_END(",
    ]
    .iter()
    .any(|k| call.contains(k))
}

/// Runs program `index` through `rs274` in `dir`.
fn rs274_of(bin: &Path, dir: &Path, index: u64) -> Result<String, String> {
    let path = dir.join("fuzz.ngc");
    std::fs::write(&path, generator::program(SEED, index)).expect("write program");
    run_rs274(bin, &path)
}

#[test]
fn generator_is_deterministic_and_programs_end() {
    for i in 0..20 {
        let p = generator::program(SEED, i);
        assert_eq!(p, generator::program(SEED, i));
        assert!(p.trim_end().ends_with("M2"), "{p}");
    }
    assert_ne!(generator::program(SEED, 0), generator::program(SEED, 1));
}

#[test]
fn stored_rs274_outputs_agree() {
    let stored = read_stored();
    assert_eq!(stored.len() as u64, STORED_PROGRAMS, "stored entries");
    let mut tally = Tally::default();
    for (i, reference) in stored.iter().enumerate() {
        let text = generator::program(SEED, i as u64);
        tally.add(i as u64, &text, judge(&text, reference));
    }
    tally.report_and_check("stored rs274 outputs");
}

#[test]
fn generated_programs_move_as_rs274_does() {
    // Only on request: `rs274` runs outside the test's control (its own files and state), so
    // the default test run compares with the stored outputs alone.
    let Some(count) = std::env::var("VMC_FUZZ_PROGRAMS")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    else {
        println!("skipped: set VMC_FUZZ_PROGRAMS=N to compare N generated programs with rs274");
        return;
    };
    let Some(bin) = rs274_binary() else {
        println!("skipped: rs274 not found (set RS274 or put it on the PATH)");
        return;
    };
    let dir = common::TempDir::new("fuzz");
    // `VMC_FUZZ_KEEP=<folder>`: the programs that fail are written there (`<i>.ngc`).
    let keep = std::env::var_os("VMC_FUZZ_KEEP").map(PathBuf::from);
    // `VMC_FUZZ_FIRST=<i>`: start at program i (to rerun a failing one).
    let first: u64 = std::env::var("VMC_FUZZ_FIRST")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    let mut tally = Tally::default();
    for i in first..first + count {
        let reference = rs274_of(&bin, dir.path(), i);
        let text = generator::program(SEED, i);
        let outcome = judge(&text, &reference);
        if let (
            Some(keep),
            Outcome::Mismatch(_) | Outcome::OnlyRs274Refuses(_) | Outcome::OnlyWeRefuse(_),
        ) = (&keep, &outcome)
        {
            std::fs::create_dir_all(keep).expect("create VMC_FUZZ_KEEP folder");
            std::fs::write(keep.join(format!("{i}.ngc")), &text).expect("write kept program");
        }
        tally.add(i, &text, outcome);
    }
    tally.report_and_check(&format!("{count} programs against rs274"));
}

#[test]
#[ignore = "rewrites tests/data/rs274-fuzz/expected.txt with rs274"]
fn regenerate_stored_rs274_outputs() {
    let bin = rs274_binary().expect("rs274 (set RS274 or put it on the PATH)");
    let dir = common::TempDir::new("fuzz-store");
    let mut out = String::new();
    for i in 0..STORED_PROGRAMS {
        match rs274_of(&bin, dir.path(), i) {
            Ok(calls) => {
                let _ = writeln!(out, "=== {i} accepted");
                for call in calls.lines().filter(|c| kept(c)) {
                    // Without the sequence-number column, and without the A, B, C coordinates
                    // where all three are 0.
                    let call = call.trim_start_matches("N..... ");
                    let call = call
                        .strip_suffix(", 0.0000, 0.0000, 0.0000)")
                        .filter(|_| call.contains("STRAIGHT_") || call.contains("ARC_FEED("))
                        .map_or_else(|| call.to_string(), |c| format!("{c})"));
                    let _ = writeln!(out, "{call}");
                }
            }
            Err(why) => {
                let _ = writeln!(out, "=== {i} refused: {}", why.replace('\n', " "));
            }
        }
    }
    std::fs::create_dir_all(stored_path().parent().expect("folder")).expect("mkdir");
    std::fs::write(stored_path(), out).expect("write stored outputs");
}
