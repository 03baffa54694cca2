//! Runs LinuxCNC's interpreter test corpus (`tests/data/linuxcnc`, see its
//! SOURCE.md) through our interpreter.
//!
//! - `interp/<case>/`: if we accept the program, our Traverse/Feed/Arc sequence must equal the
//!   reference's STRAIGHT_TRAVERSE/STRAIGHT_FEED/ARC_FEED lines (end points, arc centres, plane,
//!   rotation = ±(1 + extra turns), + for G3) within 1e-4 of the program's unit (the reference
//!   prints 4 decimals); if we reject it, the error must be of the "unsupported" kind, or the
//!   reference must itself end with an error. The counts of matched cases and accepted
//!   example programs are floors.
//! - `interp/bad/*.ngc`: every program must be rejected (either kind).
//! - `interp/good/*.ngc`: must not be rejected as invalid.
//! - `nc_files/**.ngc`: every program is interpreted without a panic (errors are fine).
//! - A case folder's `*.tbl` tool table is loaded (diameters for cutter radius compensation,
//!   lengths for G43). `crazy-paths`, `inside-corners` and `cam-nisley` check compensated paths
//!   (lines and arcs, inside and outside corners, both sides, mm and inch) against LinuxCNC.

use std::fs;
use std::path::{Path, PathBuf};

mod common;
use common::rs274::{compare, fixture_config, ours, parse_expected};
use vmc_gcode::interp::{run_program, CanonMove, GcodeError, InterpConfig};

/// The corpus: `$VMC_LINUXCNC_CORPUS` if set, else the copy vendored in `tests/data/linuxcnc`
/// (taken unchanged from LinuxCNC's interpreter tests, see tests/data/linuxcnc/SOURCE.md).
fn corpus_dir() -> PathBuf {
    let dir = match std::env::var_os("VMC_LINUXCNC_CORPUS") {
        Some(d) => PathBuf::from(d),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/linuxcnc"),
    };
    assert!(
        dir.is_dir(),
        "LinuxCNC corpus not found at {}",
        dir.display()
    );
    dir
}

fn read_lossy(path: &Path) -> String {
    let bytes = fs::read(path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    String::from_utf8_lossy(&bytes).into_owned()
}

fn files_with_ext(dir: &Path, ext: &str, recursive: bool, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            if recursive {
                files_with_ext(&path, ext, true, out);
            }
        } else if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case(ext))
        {
            out.push(path);
        }
    }
}

/// The program(s) of a case directory: `test.ngc` if present, else all `.ngc` files.
fn case_programs(dir: &Path) -> Vec<PathBuf> {
    let test = dir.join("test.ngc");
    if test.is_file() {
        return vec![test];
    }
    let mut programs = Vec::new();
    files_with_ext(dir, "ngc", false, &mut programs);
    programs
}

fn case_dirs(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = fs::read_dir(dir)
        .expect("list case dir")
        .map(|e| e.expect("entry").path())
        .collect();
    entries.sort();
    for path in entries.into_iter().filter(|p| p.is_dir()) {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if dir.ends_with("interp") && (name == "bad" || name == "good") {
            continue;
        }
        if path.join("expected").is_file() {
            out.push(path.clone());
        }
        case_dirs(&path, out);
    }
}

/// Reference cases whose output our interpreter reproduces exactly (a floor: it may only rise).
const MATCHED_FLOOR: usize = 59;
/// Example programs (`nc_files`) accepted (a floor).
const NC_ACCEPTED_FLOOR: usize = 154;

/// True if LinuxCNC's output ends with an error message (a line that is not a canonical call).
/// (An output without `PROGRAM_END()` also counts: LinuxCNC stopped before the end.)
fn reference_stopped_with_an_error(expected: &str) -> bool {
    expected.lines().any(|l| {
        let t = l.trim();
        !t.is_empty() && t != "executing" && !t.contains("N.....")
    })
}

/// Runs a corpus program; subroutine files are looked up in its folder and its `subs` folder.
fn run(path: &Path) -> Result<Vec<CanonMove>, GcodeError> {
    run_program(&read_lossy(path), &with_sub_dirs(case_config(path), path))
}

/// The interpreter settings of a case: the tool table of its folder (`*.tbl`, LinuxCNC's
/// `T… P… Z… D…` lines, read in inches as the stand-alone `rs274` reads it without an INI file)
/// if there is one.
fn case_config(program: &Path) -> InterpConfig {
    let mut cfg = InterpConfig::default();
    let mut tables = Vec::new();
    if let Some(dir) = program.parent() {
        files_with_ext(dir, "tbl", false, &mut tables);
    }
    for table in tables {
        for line in read_lossy(&table).lines() {
            let data = line.split(';').next().unwrap_or("");
            let word = |letter: char| {
                data.split_whitespace()
                    .find(|w| w.to_ascii_uppercase().starts_with(letter))
                    .and_then(|w| w[1..].parse::<f64>().ok())
            };
            if let Some(t) = word('T') {
                let tool = t as u32;
                cfg.tool_lengths_mm
                    .push((tool, word('Z').unwrap_or(0.0) * 25.4));
                cfg.tool_diameters_mm
                    .push((tool, word('D').unwrap_or(0.0) * 25.4));
            }
        }
    }
    cfg
}

fn with_sub_dirs(cfg: InterpConfig, program: &Path) -> InterpConfig {
    let dir = program.parent().expect("program in a folder").to_path_buf();
    InterpConfig {
        subroutine_dirs: vec![dir.clone(), dir.join("subs")],
        ..cfg
    }
}

/// Cases whose stored output goes on after an error (LinuxCNC's test runs the interpreter so
/// that it recovers from it), with the error; `rs274 -g` stops there, as we do.
const REFERENCE_GOES_ON_AFTER_AN_ERROR: &[(&str, &str)] = &[
    // `#100 = [1/0]` in the subroutine file fail.ngc: rs274 "Attempt to divide by zero".
    ("oword-unwind", "division by zero"),
];

/// Cases whose `expected` holds the output of several runs, one per program (LinuxCNC's test
/// script runs each in turn): the index of each program's run.
const SEPARATE_RUNS: &[(&str, &[(&str, usize)])] = &[
    (
        "m98m99/06-error-mixed-sub-styles",
        &[
            ("O...-called-with-O..._call.ngc", 0),
            ("O...-ended-with-O..._endsub.ngc", 1),
            ("O...-sub-called-with-M98.ngc", 2),
            ("O...-sub-ended-with-M99.ngc", 3),
        ],
    ),
    // Runs 0–3 read INI files (Fanuc-style subroutines on, then disabled); 4 and 5 run
    // without one, as we do.
    (
        "m98m99/09-disable-fanuc-subs",
        &[("test-fanuc.ngc", 4), ("test-rs274ngc.ngc", 5)],
    ),
    (
        "m98m99/11-main-program-oword",
        &[
            ("test-legal-end-main-with-m2.ngc", 0),
            ("test-legal-end-main-with-m02.ngc", 1),
            ("test-legal-end-main-with-m30.ngc", 2),
            ("test-legal-end-main-with-percent.ngc", 3),
            ("test-illegal-end-main-with-eof.ngc", 4),
            ("test-illegal-no-m30-before-osub.ngc", 5),
            ("test-illegal-sub-after-percent.ngc", 6),
        ],
    ),
    (
        "m98m99/13-named-program",
        &[("test-named.ngc", 0), ("test-numbered.ngc", 1)],
    ),
];

/// Splits an `expected` holding several runs at each start-up sequence of the interpreter
/// (`USE_LENGTH_UNITS`, `SET_G5X_OFFSET`, `SET_G92_OFFSET`, `SET_XY_ROTATION`,
/// `SET_FEED_REFERENCE`). Lines that are not canonical calls just before a start-up sequence
/// (a title the test script printed) are left out; elsewhere they are the run's error message.
fn split_runs(text: &str) -> Vec<String> {
    let lines: Vec<&str> = text.lines().collect();
    let is_call = |l: &str| l.contains("N.....");
    let starts_run = |i: usize| {
        let calls: Vec<&str> = lines[i..].iter().take(5).copied().collect();
        let names = [
            "USE_LENGTH_UNITS(",
            "SET_G5X_OFFSET(",
            "SET_G92_OFFSET(",
            "SET_XY_ROTATION(",
            "SET_FEED_REFERENCE(",
        ];
        calls.len() == 5 && calls.iter().zip(names).all(|(l, n)| l.contains(n))
    };
    let mut runs: Vec<Vec<&str>> = Vec::new();
    let mut pending: Vec<&str> = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        if starts_run(i) {
            // `pending` (titles since the last call) precedes this run: dropped.
            pending.clear();
            runs.push(vec![line]);
        } else if is_call(line) {
            if let Some(run) = runs.last_mut() {
                run.append(&mut pending);
                run.push(line);
            }
        } else {
            pending.push(line);
        }
    }
    runs.into_iter().map(|r| r.join("\n")).collect()
}

#[test]
fn linuxcnc_reference_cases_match_or_are_rejected_as_unsupported() {
    let interp = corpus_dir().join("interp");
    let mut dirs = Vec::new();
    case_dirs(&interp, &mut dirs);
    assert!(
        dirs.len() > 40,
        "expected the full corpus, found {} cases",
        dirs.len()
    );
    let (mut matched, mut unsupported, mut skipped, mut refused_by_both) = (0, 0, 0, 0);
    let mut failures = Vec::new();
    let mut unsupported_cases: std::collections::BTreeMap<String, Vec<String>> = Default::default();
    let mut messages_only = Vec::new();
    for dir in &dirs {
        let programs = case_programs(dir);
        let expected_text = read_lossy(&dir.join("expected"));
        let name = dir
            .strip_prefix(&interp)
            .unwrap_or(dir)
            .display()
            .to_string();
        let goes_on = REFERENCE_GOES_ON_AFTER_AN_ERROR
            .iter()
            .find(|(case, _)| *case == name);
        let runs = SEPARATE_RUNS.iter().find(|(case, _)| *case == name);
        let all_runs = split_runs(&expected_text);
        for program in &programs {
            let file = program
                .file_name()
                .and_then(|f| f.to_str())
                .unwrap_or_default();
            // The run of this program in an `expected` that holds several.
            let run_text = match runs {
                Some((_, table)) => {
                    let index = table
                        .iter()
                        .find(|(f, _)| *f == file)
                        .unwrap_or_else(|| panic!("{name}: no run listed for {file}"))
                        .1;
                    assert!(index < all_runs.len(), "{name}: no run {index}");
                    Some(all_runs[index].as_str())
                }
                None => None,
            };
            let text = run_text.unwrap_or(&expected_text);
            if !text.contains("USE_LENGTH_UNITS(") {
                // Only the program's `(debug, …)` messages were kept: no moves to compare.
                messages_only.push(name.clone());
                continue;
            }
            let reference = parse_expected(text);
            let reference_failed = reference_stopped_with_an_error(text)
                || !text.contains("PROGRAM_END()")
                || goes_on.is_some();
            match run(program) {
                Err(e) if e.is_unsupported() => {
                    unsupported += 1;
                    unsupported_cases
                        .entry(reason(&e))
                        .or_default()
                        .push(name.clone());
                }
                Err(e) if goes_on.is_some_and(|(_, why)| !e.msg.contains(why)) => {
                    failures.push(format!("{name}: rejected for another reason: {e}"));
                }
                // LinuxCNC refused it too.
                Err(_) if reference_failed => refused_by_both += 1,
                Err(e) => failures.push(format!("{name}/{file}: rejected as invalid: {e}")),
                // Several programs share one `expected`: we cannot tell which produced it.
                Ok(_) if programs.len() > 1 && run_text.is_none() => skipped += 1,
                Ok(moves) => match compare(&ours(&moves), &reference) {
                    None => matched += 1,
                    Some(diff) => failures.push(format!("{name}/{file}: mismatch: {diff}")),
                },
            }
        }
    }
    let mismatched = failures
        .iter()
        .filter(|f| f.contains(": mismatch: "))
        .count();
    println!(
        "matched {matched}, rejected-unsupported {unsupported}, mismatched {mismatched}, \
         rejected-invalid {}, rejected-like-linuxcnc {refused_by_both}, \
         accepted-but-ambiguous {skipped}",
        failures.len() - mismatched
    );
    println!(
        "  expected output holds messages only, not compared ({}): {}",
        messages_only.len(),
        messages_only.join(", ")
    );
    for (why, names) in &unsupported_cases {
        println!(
            "  unsupported ({}): {why}: {}",
            names.len(),
            names.join(", ")
        );
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        matched >= MATCHED_FLOOR,
        "only {matched} cases matched, floor {MATCHED_FLOOR}"
    );
}

#[test]
fn linuxcnc_bad_programs_are_all_rejected() {
    let mut programs = Vec::new();
    files_with_ext(
        &corpus_dir().join("interp/bad"),
        "ngc",
        false,
        &mut programs,
    );
    assert!(
        programs.len() >= 20,
        "found only {} bad programs",
        programs.len()
    );
    let accepted: Vec<String> = programs
        .iter()
        .filter(|p| run(p).is_ok())
        .map(|p| p.display().to_string())
        .collect();
    println!(
        "bad programs rejected: {} of {}",
        programs.len() - accepted.len(),
        programs.len()
    );
    assert!(
        accepted.is_empty(),
        "accepted bad programs:\n{}",
        accepted.join("\n")
    );
}

#[test]
fn linuxcnc_good_programs_are_never_rejected_as_invalid() {
    let mut programs = Vec::new();
    files_with_ext(
        &corpus_dir().join("interp/good"),
        "ngc",
        false,
        &mut programs,
    );
    assert!(!programs.is_empty());
    for p in &programs {
        if let Err(e) = run(p) {
            assert!(e.is_unsupported(), "{}: {e}", p.display());
        }
    }
}

/// Example programs that LinuxCNC's own interpreter refuses as well, with the words of our
/// refusal: `rs274 -g` stops on the same line.
const REFUSED_BY_LINUXCNC_TOO: &[(&str, &str)] = &[
    // `O<g20sub> callsub`: `callsub` is not an O-word keyword.
    ("nestedcall.ngc", "unknown O-word keyword \"callsub\""),
    // `g41` then `g0z1` from the same point: an entry move of length 0.
    ("g76.ngc", ENTRY_TOO_SHORT),
    ("lathe-g76.ngc", ENTRY_TOO_SHORT),
    // `g30` to the G30 position (0, the default) then `g38.2 z0`: a probe move of length 0.
    (
        "tool-length-probe.ngc",
        "line 18, column 1: Start point too close to probe point",
    ),
];

const ENTRY_TOO_SHORT: &str =
    "Length of cutter compensation entry move is not greater than the tool radius";

#[test]
fn linuxcnc_example_programs_never_panic_and_are_rejected_as_invalid_only_where_linuxcnc_is() {
    let mut programs = Vec::new();
    files_with_ext(&corpus_dir().join("nc_files"), "ngc", true, &mut programs);
    assert!(
        programs.len() > 100,
        "found only {} example programs",
        programs.len()
    );
    // They run on LinuxCNC: what is refused must be an unsupported feature, named where it is.
    let (mut ok, mut unsupported, mut invalid) = (0, 0, Vec::new());
    for p in &programs {
        match run(p) {
            Ok(moves) => {
                ok += 1;
                assert!(moves.iter().all(|m| m.line >= 1));
            }
            Err(e) if e.is_unsupported() => {
                unsupported += 1;
                assert!(e.line >= 1 && e.col >= 1, "{}: {e}", p.display());
            }
            Err(e) => invalid.push((p.file_name().unwrap().to_string_lossy().to_string(), e)),
        }
    }
    println!("nc_files: accepted {ok}, unsupported {unsupported}");
    assert!(ok > 0, "no example program is accepted");
    // What is refused as invalid must be refused by LinuxCNC's `rs274` too, for the same reason.
    for (name, e) in &invalid {
        println!("  invalid: {name}: {e}");
        let reason = REFUSED_BY_LINUXCNC_TOO
            .iter()
            .find(|(file, _)| file == name)
            .map(|(_, why)| *why);
        match reason {
            Some(why) => assert!(e.to_string().contains(why), "{name}: {e} (expected: {why})"),
            None => panic!("{name}: rejected as invalid: {e}"),
        }
    }
    assert!(
        ok >= NC_ACCEPTED_FLOOR,
        "only {ok} example programs accepted, floor {NC_ACCEPTED_FLOOR}"
    );
}
/// Example programs (`nc_files`) whose stored `rs274` output (`rs274-expected`, made by
/// `scripts/linuxcnc-fixtures.sh`) our moves reproduce exactly (a floor).
const NC_MATCHED_FLOOR: usize = 109;

/// Example programs whose moves differ from `rs274`'s by design, with the reason.
const NC_DIVERGENT: &[(&str, &str)] = &[(
    "skeleton.ngc",
    "G43 in a block without Z: rs274 keeps the tool tip where it is (the axis would move by the \
     length at the next move), we keep the spindle where it is until the next Z move",
)];

/// An error message without its position and numbers: programs refused for one reason group.
fn reason(e: &GcodeError) -> String {
    let text: String = e
        .msg
        .chars()
        .map(|c| if c.is_ascii_digit() { '#' } else { c })
        .collect();
    text.chars().take(70).collect()
}

#[test]
fn linuxcnc_example_programs_we_accept_move_as_rs274_does() {
    let corpus = corpus_dir();
    let expected_dir = corpus.join("rs274-expected");
    let mut programs = Vec::new();
    files_with_ext(&corpus.join("nc_files"), "ngc", true, &mut programs);
    let (mut compared, mut matched) = (0, 0);
    let mut mismatches = Vec::new();
    let mut refused: std::collections::BTreeMap<String, Vec<String>> = Default::default();
    for p in &programs {
        let rel = p
            .strip_prefix(corpus.join("nc_files"))
            .expect("under nc_files");
        let out = expected_dir.join(format!("{}.out", rel.display()));
        if !out.is_file() {
            continue;
        }
        compared += 1;
        let reference = parse_expected(&read_lossy(&out));
        match run_program(&read_lossy(p), &with_sub_dirs(fixture_config(), p)) {
            Ok(moves) => match compare(&ours(&moves), &reference) {
                None => matched += 1,
                Some(diff) => {
                    let name = rel.display().to_string();
                    match NC_DIVERGENT.iter().find(|(n, _)| *n == name) {
                        Some((_, why)) => println!("  divergent by design: {name}: {why}"),
                        None => mismatches.push(format!("{name}: {diff}")),
                    }
                }
            },
            Err(e) => refused
                .entry(reason(&e))
                .or_default()
                .push(rel.display().to_string()),
        }
    }
    println!(
        "nc_files with an rs274 output: {compared}; matched move for move {matched}, \
         mismatched {}, refused by us {}",
        mismatches.len(),
        refused.values().map(Vec::len).sum::<usize>()
    );
    for (why, names) in &refused {
        println!("  refused ({}): {why}: {}", names.len(), names.join(", "));
    }
    for m in &mismatches {
        println!("  mismatch: {m}");
    }
    assert!(compared > 100, "only {compared} stored rs274 outputs");
    assert!(mismatches.is_empty(), "{}", mismatches.join("\n"));
    assert!(
        matched >= NC_MATCHED_FLOOR,
        "only {matched} example programs matched, floor {NC_MATCHED_FLOOR}"
    );
}
