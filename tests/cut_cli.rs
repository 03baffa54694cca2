//! `vmc-twin cut` as a user runs it: the real binary in a temporary folder.

mod common;
use common::*;

/// The number after `prefix` on the line that starts with it.
fn number_after(out: &str, prefix: &str) -> f64 {
    let line = out
        .lines()
        .find(|l| l.starts_with(prefix))
        .unwrap_or_else(|| panic!("no line `{prefix}` in:\n{out}"));
    line[prefix.len()..]
        .split_whitespace()
        .next()
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no number after `{prefix}` in `{line}`"))
}

/// On the benchmark (the default tool) at a_e/D = 0.05 down milling, the printed SDM critical
/// depth at 9000 (Hopf), 10 000 (flip) and 12 000 rpm (Hopf): 5 % under it `cut` says stable,
/// 5 % over it chatter, and the printed chatter frequency is SDM's within 1 % (these speeds
/// peak at the same alias as SDM's; see the crate's tests for the others).
#[test]
fn cut_agrees_with_the_sdm_depth_it_prints() {
    let tmp = TempDir::new("cut-sdm");
    for rpm in ["9000", "10000", "12000"] {
        let base = ["cut", "--rpm", rpm, "--immersion", "0.05"];
        let probe = succeed(tmp.path(), &[&base[..], &["--depth-mm", "1"]].concat());
        let prefix = format!("SDM critical depth at {rpm} rpm: ");
        let a = number_after(&probe, &prefix);
        let sdm_line = probe.lines().find(|l| l.starts_with(&prefix)).unwrap();
        let f_sdm: f64 = sdm_line
            .split(", ")
            .nth(1)
            .and_then(|w| w.split(" Hz").next())
            .and_then(|w| w.parse().ok())
            .unwrap_or_else(|| panic!("{sdm_line}"));
        for (factor, verdict) in [(0.95, "stable"), (1.05, "chatter")] {
            let depth = format!("{}", factor * a);
            let out = succeed(tmp.path(), &[&base[..], &["--depth-mm", &depth]].concat());
            assert!(
                out.contains(&format!("\nverdict: {verdict} (")),
                "{rpm} rpm, {depth} mm:\n{out}"
            );
            if verdict == "chatter" {
                let f = number_after(&out, "chatter frequency: ");
                assert!((f / f_sdm - 1.0).abs() < 0.01, "{f} vs {f_sdm}:\n{out}");
            } else {
                assert!(out.contains("chatter frequency: none"), "{out}");
            }
        }
    }
}

#[test]
fn cut_writes_its_time_series_and_overwrites_only_with_force() {
    let tmp = TempDir::new("cut-csv");
    let args = [
        "cut",
        "--rpm",
        "9000",
        "--depth-mm",
        "0.5",
        "--immersion",
        "0.5",
        "--milling",
        "up",
        "--revolutions",
        "50",
        "--out",
        "cut.csv",
    ];
    let out = succeed(tmp.path(), &args);
    assert!(
        out.contains("simulated 100 tooth periods (50.0 revolutions"),
        "{out}"
    );
    assert!(out.contains("wrote cut.csv"), "{out}");
    let csv = std::fs::read_to_string(tmp.path().join("cut.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows[0], "time_s,x_um,y_um,fx_n,fy_n");
    // 100 tooth periods × 64 steps.
    assert_eq!(rows.len(), 1 + 6400);
    let row = |i: usize| -> Vec<f64> { rows[i].split(',').map(|v| v.parse().unwrap()).collect() };
    // Step = τ/64 = 60/(2·9000)/64 s; the printed maximum vibration is the CSV's (0.01 µm).
    assert!((row(2)[0] - 60.0 / 18_000.0 / 64.0).abs() < 1e-9);
    let max_um = (1..rows.len())
        .map(|i| {
            let r = row(i);
            r[1].hypot(r[2])
        })
        .fold(0.0, f64::max);
    let printed = number_after(&out, "max vibration: ");
    assert!((printed - max_um).abs() < 0.01, "{printed} vs {max_um}");
    // Up milling at a_e/D 0.5 loads the tool: forces of some newtons.
    let max_n = number_after(&out, "max force: ");
    assert!(max_n > 1.0 && max_n < 1000.0, "{out}");
    // Existing output: refused without --force, replaced with it.
    let again = vmc(tmp.path(), &args);
    assert_eq!(again.status.code(), Some(1));
    assert_eq!(
        stderr(&again).trim(),
        "vmc-twin: error: cut.csv: already exists (pass --force to overwrite)"
    );
    succeed(tmp.path(), &[&args[..], &["--force"]].concat());
}

#[test]
fn bad_cut_input_fails_in_one_line_without_a_panic() {
    let tmp = TempDir::new("cut-bad");
    std::fs::write(tmp.path().join("old.csv"), "x").unwrap();
    std::fs::write(tmp.path().join("old.rrd"), "x").unwrap();
    for (extra, want) in [
        (
            &["--rpm", "0"][..],
            "--rpm: spindle speed must be > 0 rpm, got 0",
        ),
        (&["--depth-mm", "-1"][..], "--depth-mm must be > 0 mm, got -1"),
        (&["--depth-mm", "0"][..], "--depth-mm must be > 0 mm, got 0"),
        (
            &["--immersion", "1.5"][..],
            "--immersion: immersion a_e/D must be in [0.01, 1] (a radial depth of at least 1 % of the tool diameter), got 1.5",
        ),
        (
            &["--immersion", "0"][..],
            "--immersion: immersion a_e/D must be in [0.01, 1] (a radial depth of at least 1 % of the tool diameter), got 0",
        ),
        (
            &["--feed-per-tooth-mm", "-0.1"][..],
            "--feed-per-tooth-mm must be > 0 mm, got -0.1",
        ),
        (
            &["--out", "old.csv"][..],
            "old.csv: already exists (pass --force to overwrite)",
        ),
        (
            &["--rrd", "old.rrd"][..],
            "old.rrd: already exists (pass --force to overwrite)",
        ),
        (
            &["--out", "missing/c.csv"][..],
            "missing/c.csv: the folder missing does not exist",
        ),
        (
            &["--rrd", "c.txt"][..],
            "c.txt: a Rerun recording file name must end in .rrd",
        ),
        (
            &["--duration-s", "0.01"][..],
            "--duration-s 0.01 is 3 tooth periods at 9000 rpm; at least 16 are needed (0.0533 s, 8.0 revolutions)",
        ),
        (&["--revolutions", "-2"][..], "--revolutions must be > 0, got -2"),
        (
            &["--tool", "none.toml"][..],
            "none.toml",
        ),
    ] {
        // Defaults for what a case does not set: 9000 rpm, 1 mm deep.
        let mut args = vec!["cut"];
        if !extra.contains(&"--rpm") {
            args.extend(["--rpm", "9000"]);
        }
        if !extra.contains(&"--depth-mm") {
            args.extend(["--depth-mm", "1"]);
        }
        args.extend(extra);
        let o = vmc(tmp.path(), &args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(
            err.starts_with(&format!("vmc-twin: error: {want}")),
            "{args:?}: {err}"
        );
        assert!(stdout(&o).is_empty(), "{args:?}");
    }
    // Nothing was written over the existing files.
    assert_eq!(
        std::fs::read_to_string(tmp.path().join("old.csv")).unwrap(),
        "x"
    );
}
