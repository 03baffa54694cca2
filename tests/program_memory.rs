//! The measured program of `vmc-twin run` is streamed: its peak resident memory must not grow
//! with the program's length in moves (the moves and the timed plan are made piece by piece)
//! nor with its number of measurement points (each point's row is written as it is taken).
//! Peak memory is the child's maximum resident set size (see `common::peak_rss_kb`).
//!
//! Nor does it grow with the program's text: the interpreter reads the file as it runs,
//! holding only its O-word lines' places.
//!
//! The programs are generated here: the ten moves of a diagonal test (no dwells: measured
//! during motion), back and forth, repeated in an O-word loop: a program of 100 000 moves
//! against one of 10 000, and 10× the points of one program against its default sampling;
//! the same moves written out line by line: a 3 MB text against a 0.3 MB one.
//!
//! `check` streams its program too (interpreted, planned and checked piece by piece): the same
//! two texts hold the same peak memory.

mod common;
use common::*;

/// A diagonal's ten moves repeated `repeats` times (10 × `repeats` moves, 0.6 s each).
fn diagonals(repeats: usize) -> String {
    let moves: Vec<String> = (0..10)
        .map(|k| {
            format!(
                "  G1 X{:.3} Y{:.3} Z-225.000 F20000",
                10 + 60 * k,
                60 + 30 * k
            )
        })
        .collect();
    format!(
        "%\n( {repeats} diagonals )\nG21 G17 G90 G54\nG0 X10 Y60 Z-225\no1 repeat [{repeats}]\n{}\n\
         o1 endrepeat\nM30\n%\n",
        moves.join("\n")
    )
}

/// The ten moves of [`diagonals`] written out `repeats` times, without a loop (about 300 bytes
/// a repeat).
fn flat_diagonals(repeats: usize) -> String {
    let once: String = (0..10)
        .map(|k| format!("  G1 X{} Y{} Z-225.000 F20000\n", 10 + 60 * k, 60 + 30 * k))
        .collect();
    format!(
        "%\n( {repeats} diagonals )\nG21 G17 G90 G54\nG0 X10 Y60 Z-225\n{}M30\n%\n",
        once.repeat(repeats)
    )
}

/// Peak RSS (kB) of `run` on `program` with the measurement period `period_ms` (a coarse
/// thermal step: the thermal network's cost is not what is measured); checks the report.
fn peak_kb(dir: &TempDir, name: &str, program: &str, period_ms: &str) -> u64 {
    let file = dir.path().join(format!("{name}.ngc"));
    std::fs::write(&file, program).unwrap();
    let out = dir.path().join(name);
    let kb = peak_rss_kb(
        dir.path(),
        &[
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--interp-cycle-ms",
            period_ms,
            "--thermal-step-s",
            "10",
        ],
    );
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let csv = std::fs::read_to_string(out.join("samples.csv")).unwrap();
    let points: usize = summary
        .lines()
        .find_map(|l| l.trim().strip_prefix("\"points\": "))
        .and_then(|v| v.trim_end_matches(',').parse().ok())
        .expect("points in summary.json");
    // Every point's row was streamed to samples.csv (plus its header).
    assert_eq!(csv.lines().count(), points + 1, "{name}");
    kb
}

#[test]
fn ten_times_the_moves_hold_no_more_memory() {
    let dir = TempDir::new("program-memory-moves");
    let short_kb = peak_kb(&dir, "short", &diagonals(1_000), "60000");
    let long_kb = peak_kb(&dir, "long", &diagonals(10_000), "60000");
    eprintln!("peak RSS: 10 000 moves {short_kb} kB, 100 000 moves {long_kb} kB");
    // Held whole, 90 000 more moves and their plan are some 40 MB.
    assert!(
        long_kb as f64 <= 1.2 * short_kb as f64,
        "peak RSS grew with the program's moves: {long_kb} kB against {short_kb} kB"
    );
}

#[test]
fn ten_times_the_text_holds_no_more_memory() {
    let dir = TempDir::new("program-memory-text");
    let short = flat_diagonals(1_000);
    let long = flat_diagonals(10_000);
    assert!(long.len() > 3_000_000, "{}", long.len());
    let short_kb = peak_kb(&dir, "short", &short, "60000");
    let long_kb = peak_kb(&dir, "long", &long, "60000");
    eprintln!(
        "peak RSS: {} byte text {short_kb} kB, {} byte text {long_kb} kB",
        short.len(),
        long.len()
    );
    // Held whole, the longer text and its parsed lines are some 40 MB more.
    assert!(
        long_kb as f64 <= 1.2 * short_kb as f64,
        "peak RSS grew with the program's text: {long_kb} kB against {short_kb} kB"
    );
}

#[test]
fn ten_times_the_points_hold_no_more_memory() {
    let dir = TempDir::new("program-memory-points");
    let program = diagonals(2_000);
    let few_kb = peak_kb(&dir, "few", &program, "1000");
    let many_kb = peak_kb(&dir, "many", &program, "100");
    eprintln!("peak RSS: 12 000 points {few_kb} kB, 120 000 points {many_kb} kB");
    // Held whole, 108 000 more points with their rows are some 60 MB.
    assert!(
        many_kb as f64 <= 1.2 * few_kb as f64,
        "peak RSS grew with the points: {many_kb} kB against {few_kb} kB"
    );
}

#[test]
fn check_holds_no_more_memory_for_ten_times_the_program() {
    let dir = TempDir::new("program-memory-check");
    let mut kb = Vec::new();
    for (name, repeats) in [("short", 1_000), ("long", 10_000)] {
        let file = dir.path().join(format!("{name}.ngc"));
        std::fs::write(&file, flat_diagonals(repeats)).unwrap();
        // Exit status 0: the program was checked to its end and found clean.
        kb.push(peak_rss_kb(dir.path(), &["check", file.to_str().unwrap()]));
    }
    let (short_kb, long_kb) = (kb[0], kb[1]);
    eprintln!("check peak RSS: 10 000 moves {short_kb} kB, 100 000 moves {long_kb} kB");
    // Held whole, the longer program's text, moves and plan are some 40 MB more.
    assert!(
        long_kb as f64 <= 1.2 * short_kb as f64,
        "check's peak RSS grew with the program: {long_kb} kB against {short_kb} kB"
    );
}
