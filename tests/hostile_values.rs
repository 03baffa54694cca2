//! Absurd but finite values and files without provenance, on the real binary: each gets a
//! message that names the option, the file and line, or the missing provenance, never a
//! silent absurd result.

mod common;
use common::{ok, refused, repo_file, vmc, TempDir};

#[test]
fn a_vanishing_immersion_is_refused_with_its_range_in_readable_numbers() {
    let t = TempDir::new("immersion");
    for cmd in [
        &["lobes"][..],
        &["cut", "--rpm", "9000", "--depth-mm", "1"][..],
    ] {
        let args = [cmd, &["--immersion", "1e-300"][..]].concat();
        let err = refused(&vmc(t.path(), &args), "--immersion 1e-300");
        assert!(
            err.contains("--immersion: immersion a_e/D must be in [0.01, 1]")
                && err.trim_end().ends_with("got 1e-300"),
            "{err}"
        );
    }
}

#[test]
fn absurd_cut_depths_feeds_and_speeds_are_refused_naming_the_option() {
    let t = TempDir::new("cut");
    let cut = |extra: &[&str]| {
        let args = [&["cut"][..], extra].concat();
        refused(&vmc(t.path(), &args), &format!("{extra:?}"))
    };
    let err = cut(&["--rpm", "9000", "--depth-mm", "1e300"]);
    assert!(
        err.contains("--depth-mm 1e300 is more than 10 tool diameters"),
        "{err}"
    );
    let err = cut(&[
        "--rpm",
        "9000",
        "--depth-mm",
        "1",
        "--feed-per-tooth-mm",
        "1e300",
    ]);
    assert!(
        err.contains("--feed-per-tooth-mm 1e300 is more than the tool's radius"),
        "{err}"
    );
    let err = cut(&["--rpm", "1e-9", "--depth-mm", "1"]);
    assert!(
        err.contains("--rpm: spindle speed 1e-9 rpm is below 1 rpm"),
        "{err}"
    );
    assert!(!err.contains("resonat"), "{err}");
    let err = cut(&["--rpm", "9000", "--depth-mm", "1", "--revolutions", "1e300"]);
    assert!(
        err.contains("--revolutions 1e300 is 2e300 tooth periods") && err.len() < 300,
        "{err}"
    );
}

#[test]
fn a_huge_work_offset_is_a_travel_error_on_the_line_that_moves() {
    let t = TempDir::new("g10");
    std::fs::write(
        t.path().join("far.ngc"),
        "G10 L2 P1 X100000000\nG54\nG1 X0 F100\nM30\n",
    )
    .unwrap();
    for cmd in ["run", "check", "interpret"] {
        let o = vmc(t.path(), &[cmd, "far.ngc"]);
        if cmd == "interpret" {
            // The interpreter alone knows no machine: it prints the canonical moves.
            ok(&o, "interpret");
            continue;
        }
        let err = refused(&o, cmd);
        assert!(
            err.contains("far.ngc: line 3: axis X reaches 100000000 mm, outside travel"),
            "{cmd}: {err}"
        );
    }
}

/// A probing file from the binary for the A/C trunnion.
fn probing_file(dir: &std::path::Path) -> String {
    let machine = repo_file("machines/trunnion-ac.toml").display().to_string();
    let args = [
        "probe-campaign",
        "--machine",
        &machine,
        "--seed",
        "1",
        "-o",
        "p.csv",
    ];
    ok(&vmc(dir, &args), "probe-campaign");
    std::fs::read_to_string(dir.join("p.csv")).unwrap()
}

#[test]
fn an_absurd_cell_of_a_probing_file_is_refused_naming_its_line_and_column() {
    let t = TempDir::new("identify");
    let text = probing_file(t.path());
    let machine = repo_file("machines/trunnion-ac.toml").display().to_string();
    let header_at = text.lines().position(|l| l.starts_with("config,")).unwrap();
    let header: Vec<&str> = text.lines().nth(header_at).unwrap().split(',').collect();
    let row = header_at + 3; // 0-based: line row + 1
    let cases = [
        (
            "X_measured_mm",
            "1e300",
            "X_measured_mm = 1e300 is beyond any probing value",
        ),
        (
            "C_deg",
            "1e300",
            "C_deg = 1e300 is beyond any probing value",
        ),
        (
            "cov_yy_mm2",
            "1e300",
            "cov_yy_mm2 = 1e300 is beyond any probing value",
        ),
        (
            "cov_xx_mm2",
            "0",
            "cov_xx_mm2 = 0e0 mm²: a variance of a probed centre must lie in",
        ),
        ("Z_measured_mm", "-100", "the measured centre is"),
    ];
    for (column, value, want) in cases {
        let k = header.iter().position(|c| *c == column).unwrap();
        let edited: Vec<String> = text
            .lines()
            .enumerate()
            .map(|(i, l)| {
                if i != row {
                    return l.to_string();
                }
                let mut cells: Vec<&str> = l.split(',').collect();
                cells[k] = value;
                cells.join(",")
            })
            .collect();
        std::fs::write(t.path().join("bad.csv"), edited.join("\n") + "\n").unwrap();
        let args = [
            "identify",
            "--data",
            "bad.csv",
            "--machine",
            &machine,
            "-o",
            "id.json",
        ];
        let err = refused(&vmc(t.path(), &args), column);
        let line = format!("bad.csv: line {}: ", row + 1);
        assert!(err.contains(&line) && err.contains(want), "{column}: {err}");
        assert!(!t.path().join("id.json").exists());
    }
}

/// A calibration dataset `c.csv` from the binary (every 2 h).
fn calibrate(dir: &std::path::Path) {
    let args = ["calibrate", "--measure-every-min", "120", "-o", "c.csv"];
    ok(&vmc(dir, &args), "calibrate");
}

#[test]
fn a_calibration_without_its_machine_line_trains_and_every_use_says_the_realisation_is_unknown() {
    let t = TempDir::new("provenance");
    calibrate(t.path());
    let text = std::fs::read_to_string(t.path().join("c.csv")).unwrap();
    assert!(text.starts_with("# machine: "), "the line the test removes");
    let without: String = text
        .lines()
        .filter(|l| !l.starts_with("# machine:"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(t.path().join("anon.csv"), without).unwrap();
    let train = [
        "train", "--data", "anon.csv", "--kind", "linear", "-o", "m.json",
    ];
    let out = ok(&vmc(t.path(), &train), "train");
    assert!(
        out.contains("note: anon.csv has no `# machine:` line")
            && out.contains("unknown realisation"),
        "{out}"
    );
    // Another realisation (seed 2) runs with the model, and is told which check is missing.
    let prog = repo_file("trajectories/diag_xy.ngc").display().to_string();
    let run = [
        "run",
        &prog,
        "--model",
        "m.json",
        "--compensate",
        "--seed",
        "2",
    ];
    let out = ok(&vmc(t.path(), &run), "run");
    assert!(
        out.contains(
            "note: m.json: trained on data of an unknown realisation of machine `vmc-reference`"
        ) && out.contains("is not checked"),
        "{out}"
    );
}

#[test]
fn a_model_without_trained_ranges_is_named_unchecked_and_refused_under_strict() {
    let t = TempDir::new("ranges");
    calibrate(t.path());
    let train = [
        "train", "--data", "c.csv", "--kind", "linear", "-o", "m.json",
    ];
    ok(&vmc(t.path(), &train), "train");
    // The same model with its `trained_on` record removed.
    let text = std::fs::read_to_string(t.path().join("m.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert!(json.as_object_mut().unwrap().remove("trained_on").is_some());
    std::fs::write(t.path().join("old.json"), json.to_string()).unwrap();
    let prog = repo_file("trajectories/diag_xy.ngc").display().to_string();
    let run = [
        "run",
        &prog,
        "--model",
        "old.json",
        "--compensate",
        "--seed",
        "1",
    ];
    let out = ok(&vmc(t.path(), &run), "run");
    assert!(
        out.contains("note: old.json records no machine or trained ranges"),
        "{out}"
    );
    assert!(out.contains("model inputs: not checked"), "{out}");
    assert!(!out.contains("inside the trained ranges"), "{out}");
    let strict = [&run[..], &["--strict"]].concat();
    let err = refused(&vmc(t.path(), &strict), "--strict");
    assert!(
        err.contains("old.json: --strict refuses") && err.contains("records none"),
        "{err}"
    );
}

#[test]
fn an_empty_program_is_refused_without_suggesting_an_option_already_given() {
    let t = TempDir::new("empty");
    std::fs::write(t.path().join("empty.ngc"), "(nothing)\nM30\n").unwrap();
    for extra in [&[][..], &["--every-cycle"][..]] {
        let args = [&["run", "empty.ngc"][..], extra].concat();
        let err = refused(&vmc(t.path(), &args), "empty program");
        assert!(
            err.contains("empty.ngc: the program has no measurement points"),
            "{err}"
        );
        assert!(!err.contains("use --every-cycle"), "{err}");
    }
}

#[test]
fn lobes_beyond_any_spindle_or_with_a_billion_steps_are_refused_not_computed_or_aborted() {
    let t = TempDir::new("lobes");
    let err = refused(
        &vmc(t.path(), &["lobes", "--rpm", "1e300:2e300:3"]),
        "1e300 rpm",
    );
    assert!(
        err.contains("spindle speed 1e300 rpm is above 200000 rpm"),
        "{err}"
    );
    let err = refused(
        &vmc(t.path(), &["lobes", "--steps", "1000000000"]),
        "1e9 steps",
    );
    assert!(
        err.contains("--steps must be <= 20000, got 1000000000"),
        "{err}"
    );
}
