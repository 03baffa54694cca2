//! Bad inputs on the real binary: each kind of bad program, machine file and
//! option gives exactly one line on stderr, exit code 1 (not a panic's 101), with a location,
//! and the message docs/usage.md shows. Each guard added for a hang or a missing location
//! found by the property tests (`tests/fuzz.rs`) has its regression case here.

mod common;

use common::{ok, one_line_error, repo_file as repo, succeed, vmc, TempDir};

/// (program text, expected message after `bad.ngc: `), run with `vmc-twin run bad.ngc`.
const PROGRAMS: &[(&str, &str)] = &[
    (
        "G21 G90\nG1 X10 F0\nM30\n",
        "line 2, column 1: G1 with zero feed rate (no F word > 0 given yet)",
    ),
    (
        "G21 G90\nG0 X10 Y10\nG2 X10 Y10 I0 J0 F100\nM30\n",
        "line 3, column 1: zero-radius arc (radius to start 0.0000, to end 0.0000)",
    ),
    (
        // LinuxCNC's bad-arc.small.metric case with numbers: |r1 − r2| = 0.0286 mm > 0.02·√2
        // and 0.114 % > 0.1 %.
        "G21 G90 F100\nG0 X0 Y0 Z-100\nG2 X50 Y0 I24.9857 J0\nM30\n",
        "line 3, column 1: radius to end of arc differs from radius to start (r1 = 24.9857, r2 = 25.0143)",
    ),
    (
        "G21 G90\nS30000 M3\nG4 P1\nM30\n",
        "line 2: spindle speed 30000 rpm is above the machine's maximum of 12000 rpm (motion.max_spindle_rpm)",
    ),
    ("G21 G90\nS-5 M3\nM30\n", "line 2, column 1: S word must not be negative"),
    (
        "G21 G90\nG4 P100000000\nM30\n",
        "line 2: the program reaches 100000000 s of machine time, above the limit of 604800 s (7 days)",
    ),
    (
        "G21 G90\nG0 X100 Y100 Z-100\nG2 X100 Y100 I10 J0 P1000000 F100\nM30\n",
        "line 3, column 21: G2 turn count P1000000 above the supported maximum 1000",
    ),
    (
        "G21 G90\nG0 X100 Y100 Z-100\nG2 X100 Y100 Z-200 I10 J0 P999 F1\nM30\n",
        "line 3: the program reaches 3766147 s of machine time, above the limit of 604800 s (7 days)",
    ),
    (
        "G21 G90\nG1 X500 F0.000001\nM30\n",
        "line 2: the program reaches 30000000000 s of machine time, above the limit of 604800 s (7 days)",
    ),
    (
        "G21 G90\nG0 X12345678901\nM30\n",
        "line 2, column 4: X word value out of range (|value| > 1e9)",
    ),
    ("G21 G90\nG1 XNaN F100\nM30\n", "line 2, column 4: X word: missing number"),
    (
        "G21\nG0 X#<nope>\nM30\n",
        "line 2, column 4: named parameter #<nope> not defined",
    ),
    (
        "G21\no1 while [1]\no1 endwhile\nM30\n",
        "line 3, column 1: more than 1000000 loop iterations (endless loop?)",
    ),
    (
        "G21 G90\nG0 X600 Y100 Z-100\nM30\n",
        "line 2: axis X reaches 600 mm, outside travel [0, 560] mm",
    ),
];

#[test]
fn every_bad_program_is_one_line_with_its_location() {
    let t = TempDir::new("prog");
    for (text, want) in PROGRAMS {
        std::fs::write(t.path().join("bad.ngc"), text).unwrap();
        assert_eq!(
            one_line_error(t.path(), &["run", "bad.ngc"]),
            format!("bad.ngc: {want}"),
            "{text:?}"
        );
        // `check` rejects the same way, except out of travel, which it reports as a problem.
        if !want.contains("outside travel") {
            assert_eq!(
                one_line_error(t.path(), &["check", "bad.ngc"]),
                format!("bad.ngc: {want}")
            );
        }
    }
}

#[test]
fn an_arc_within_linuxcncs_tolerance_is_accepted() {
    let t = TempDir::new("arcok");
    // |r1 − r2| = 0.02 mm < 0.02·√2 mm: accepted, as LinuxCNC does.
    std::fs::write(
        t.path().join("ok.ngc"),
        "G21 G90 F100\nG0 X0 Y0 Z-100\nG2 X50 Y0 I24.99 J0\nM30\n",
    )
    .unwrap();
    ok(
        &vmc(t.path(), &["check", "ok.ngc"]),
        "an arc within tolerance",
    );
}

#[test]
fn bytes_that_are_not_utf8_are_located() {
    let t = TempDir::new("utf8");
    std::fs::write(t.path().join("bin.ngc"), b"G21\nG1 X1 (\xc3\xa9) \xff\n").unwrap();
    assert_eq!(
        one_line_error(t.path(), &["run", "bin.ngc"]),
        "bin.ngc: cannot read program: not UTF-8 text: line 2, column 11: byte 0xFF"
    );
    assert_eq!(
        one_line_error(t.path(), &["check", "bin.ngc", "--machine", "bin.ngc"]),
        "bin.ngc: cannot read machine file: not UTF-8 text: line 2, column 11: byte 0xFF"
    );
}

/// (replace in the reference machine, by, expected message after `m.toml: `).
const MACHINES: &[(&str, &str, &str)] = &[
    (
        "travel_max_mm = [560.0",
        "travel_max_mm = [nan",
        "field `axes.travel_max_mm[0]`: NaN is not plausible for a length, mm (±100 m): the range is [-1e5, 1e5]",
    ),
    (
        "travel_max_mm = [560.0",
        "travel_max_mm = [-10.0",
        "field `axes.travel_max_mm[0]`: X travel must be positive: max -10 mm ≤ min 0 mm (travel -10 mm)",
    ),
    ("diameter_mm = 12.0", "diameter_mm = inf", "field `tool.diameter_mm`: inf is not plausible for a length, mm (±100 m): the range is [-1e5, 1e5]"),
    (
        "step_s = 1.0",
        "step_s = 1e-300",
        "field `thermal`: thermal.step_s must be in [0.001, 3600] s, got 1e-300",
    ),
    (
        "laser_step_mm = [40.0",
        "laser_step_mm = [1e-9",
        "field `instruments.laser_step_mm[0]`: must be in [1 mm, travel = 560 mm], got 0.000000001",
    ),
    (
        "max_spindle_rpm = 12000.0",
        "max_spindle_rpm = -1.0",
        "field `motion.max_spindle_rpm`: -1 is not plausible for a spindle speed, rpm: the range is [0, 2e5]",
    ),
    (
        "holder = { diameter_mm = 50.0, length_mm = 45.0 }",
        "holder = { diameter_mm = 50.0, length_mm = 200.0 }",
        "field `collision.holder.length_mm`: must be shorter than the tool length (−tool.offset_mm[2] = 150 mm), got 200",
    ),
    (
        "max_feed_mm_per_min = 10000.0",
        "max_feed_mm_per_min = 10000.0.0",
        "TOML parse error at line 37, column 30    | 37 | max_feed_mm_per_min = 10000.0.0    |                              ^^ invalid float, expected nothing",
    ),
    (
        "laser_point_s",
        "laser_pont_s",
        "TOML parse error at line 49, column 1    | 49 | laser_pont_s = 6.0    | ^^^^^^^^^^^^ unknown field `laser_pont_s`, expected one of `laser_noise_um`, `laser_noise_um_per_m`, `angular_noise_urad`, `straightness_noise_um`, `probe_noise_um`, `laser_step_mm`, `laser_point_s`",
    ),
    (
        "unit = \"urad\"\npoly = [-6.0, 14.0]",
        "unit = \"um\"\npoly = [-6.0, 14.0]",
        "field `errors.motion.EBX.unit`: must be \"urad\" for this error",
    ),
    (
        "poly = [-6.0, 14.0]",
        "poly = [-6.0, nan]",
        "field `errors.motion.EBX.poly[1]`: NaN is not plausible for an error term in urad: the range is [-1e4, 1e4]",
    ),
];

#[test]
fn every_bad_machine_value_names_its_field_or_line() {
    let t = TempDir::new("machine");
    let reference = std::fs::read_to_string(repo("machines/vmc-reference.toml")).unwrap();
    let prog = repo("trajectories/diag_xy.ngc").display().to_string();
    for (from, to, want) in MACHINES {
        // Each edit lands in one place of the file, the one the message names.
        assert_eq!(reference.matches(from).count(), 1, "{from}");
        std::fs::write(t.path().join("m.toml"), reference.replacen(from, to, 1)).unwrap();
        for cmd in ["run", "check"] {
            assert_eq!(
                one_line_error(t.path(), &[cmd, &prog, "--machine", "m.toml"]),
                format!("m.toml: {want}")
            );
        }
    }
}

#[test]
fn a_five_axis_machine_given_to_a_three_axis_command_is_named_as_such() {
    let t = TempDir::new("five-axis-to-three");
    let machine = repo("machines/trunnion-bc.toml").display().to_string();
    let prog = repo("trajectories/trunnion_bc_tcp.ngc")
        .display()
        .to_string();
    for args in [
        vec!["check", &prog, "--machine", &machine],
        vec!["interpret", &prog, "--machine", &machine],
    ] {
        let err = one_line_error(t.path(), &args);
        assert!(
            err.starts_with(&format!("{machine}: a five-axis machine")),
            "{args:?}: {err}"
        );
        assert!(err.contains("`run`"), "what to use instead: {err}");
    }
}

#[test]
fn absurd_steps_are_refused_before_any_simulation() {
    let t = TempDir::new("steps");
    let prog = repo("trajectories/diag_xy.ngc").display().to_string();
    assert_eq!(
        one_line_error(t.path(), &["run", &prog, "--thermal-step-s", "1e-9"]),
        format!("{prog}: 59 s of machine time at thermal step 1e-9 s is 5.908e10 steps, above the limit of 2e7: use a larger --thermal-step-s")
    );
    assert_eq!(
        one_line_error(t.path(), &["run", &prog, "--every-cycle", "--interp-cycle-ms", "1e-6"]),
        format!("{prog}: 59 s of machine time at interpolation cycle 1e-9 s is 5.908e10 steps, above the limit of 2e7: use a larger --interp-cycle-ms (or drop --every-cycle)")
    );
    assert_eq!(
        one_line_error(
            t.path(),
            &["calibrate", "--measure-every-min", "1e-300", "-o", "c.csv"]
        ),
        "--measure-every-min must be at least 1 (minute), got 1e-300"
    );
    assert!(!t.path().join("c.csv").exists());
}

#[test]
fn bad_datasets_and_model_files_are_one_line_naming_what_is_wrong() {
    let t = TempDir::new("data");
    succeed(
        t.path(),
        &["calibrate", "--measure-every-min", "120", "-o", "cal.csv"],
    );
    let text = std::fs::read_to_string(t.path().join("cal.csv")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let write = |name: &str, lines: &[String]| {
        std::fs::write(t.path().join(name), lines.join("\n") + "\n").unwrap();
    };
    // The header follows the comment lines (the machine's identity).
    let h = lines.iter().position(|l| !l.starts_with('#')).unwrap();
    let dx = lines[h].split(',').position(|c| c == "dx_um").unwrap();
    // A corrupt measurement cell in the first record (file line h + 2).
    let mut huge = lines.clone();
    let mut cells: Vec<String> = huge[h + 1].split(',').map(String::from).collect();
    cells[dx] = "1e308".into();
    huge[h + 1] = cells.join(",");
    write("huge.csv", &huge);
    assert_eq!(
        one_line_error(t.path(), &["train", "--data", "huge.csv", "-o", "m.json"]),
        format!(
            "huge.csv: line {}, column `dx_um`: implausible value 1e308: beyond ±1e6 (a corrupt \
             cell or a unit mistake?)",
            h + 2
        )
    );
    // A column pasted twice.
    let header = lines[h].clone();
    let last = header.rsplit(',').next().unwrap().to_string();
    let n = header.split(',').count();
    lines[h] = format!("{header},{last}");
    for l in lines.iter_mut().skip(h + 1) {
        let v = l.rsplit(',').next().unwrap().to_string();
        l.push(',');
        l.push_str(&v);
    }
    write("dup.csv", &lines);
    assert_eq!(
        one_line_error(t.path(), &["train", "--data", "dup.csv", "-o", "m.json"]),
        format!(
            "dup.csv: column `{last}` appears twice in the header (columns {n} and {})",
            n + 1
        )
    );
    assert!(!t.path().join("m.json").exists());
    // A missing model file is named once; a file that is not a model says so.
    let prog = repo("trajectories/diag_xy.ngc").display().to_string();
    let err = one_line_error(
        t.path(),
        &["run", &prog, "--model", "nope.json", "--compensate"],
    );
    assert!(err.starts_with("nope.json: "), "{err}");
    assert_eq!(err.matches("nope.json").count(), 1, "{err}");
    std::fs::write(t.path().join("x.json"), "{}").unwrap();
    assert_eq!(
        one_line_error(
            t.path(),
            &["run", &prog, "--model", "x.json", "--compensate"]
        ),
        "x.json: not a vmc-twin model file: no `format` field"
    );
    // A well-formed model whose prediction is absurd (an intercept of 5 mm, in µm) is stopped at
    // the first compensated point, not run with the axes 5 mm off.
    succeed(
        t.path(),
        &[
            "train", "--data", "cal.csv", "--kind", "linear", "-o", "lin.json",
        ],
    );
    let mut model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(t.path().join("lin.json")).unwrap()).unwrap();
    model["model"]["regression"]["intercept"][0] = serde_json::json!(5000.0);
    std::fs::write(t.path().join("wild.json"), model.to_string()).unwrap();
    let err = one_line_error(
        t.path(),
        &["run", &prog, "--model", "wild.json", "--compensate"],
    );
    assert!(err.starts_with(&format!("{prog}: line 7 (t = ")), "{err}");
    assert!(
        err.contains("above the limit of 1 mm for a geometric and thermal correction"),
        "{err}"
    );
}

#[test]
fn repeated_seeds_and_empty_options_are_refused_before_any_work() {
    let t = TempDir::new("options");
    let cases: [(&[&str], &str); 6] = [
        (
            &["select-sensors", "--candidates", "saddle,x_motor,saddle"],
            "--candidates: `saddle` is named twice",
        ),
        (
            &["campaign", "--seeds", "1,2,1"],
            "--seeds: seed 1 is given twice (its runs would count twice)",
        ),
        (
            &["select-sensors", "--compare-seeds", "3,3"],
            "--compare-seeds: seed 3 is given twice (its runs would count twice)",
        ),
        (
            &["select-sensors", "--candidates", "spindle_nose,,saddle"],
            "--candidates: an empty name in `spindle_nose,,saddle`",
        ),
        (
            &["select-sensors", "--count", "1000"],
            "--count 1000: there are only 39 candidate locations besides ambient",
        ),
        (&["bench", "--repeats", "0"], "--repeats must be at least 1"),
    ];
    for (args, want) in cases {
        assert_eq!(one_line_error(t.path(), args), want);
    }
    assert!(
        std::fs::read_dir(t.path()).unwrap().next().is_none(),
        "nothing written"
    );
}

#[test]
fn a_model_of_another_kinematics_is_refused_before_the_run() {
    let t = TempDir::new("geometry");
    let reference = std::fs::read_to_string(repo("machines/vmc-reference.toml")).unwrap();
    let gantry = reference.replacen("chain = \"w X Y b Z t\"", "chain = \"w Y b X Z t\"", 1);
    assert_ne!(gantry, reference);
    std::fs::write(t.path().join("gantry.toml"), gantry).unwrap();
    succeed(
        t.path(),
        &[
            "calibrate",
            "--machine",
            "gantry.toml",
            "--measure-every-min",
            "120",
            "-o",
            "g.csv",
        ],
    );
    succeed(
        t.path(),
        &[
            "train",
            "--data",
            "g.csv",
            "--machine",
            "gantry.toml",
            "--kind",
            "linear",
            "-o",
            "g.json",
        ],
    );
    let prog = repo("trajectories/diag_xy.ngc").display().to_string();
    assert_eq!(
        one_line_error(
            t.path(),
            &["run", &prog, "--model", "g.json", "--compensate"]
        ),
        "g.json: model does not fit machine vmc-reference: geometry mismatch: the model was \
         trained for chain `w Y b X Z t` with tool offset [0.0, 0.0, -150.0] mm, the machine has \
         chain `w X Y b Z t` with tool offset [0.0, 0.0, -150.0] mm"
    );
}

/// The run's "reduction of RMS |E|" is at least `min_percent`.
fn assert_reduction_at_least(out: &str, min_percent: f64) {
    let reduction: f64 = out
        .lines()
        .find_map(|l| l.trim().strip_prefix("reduction of RMS |E|: "))
        .and_then(|v| v.trim_end_matches(" %").parse().ok())
        .unwrap_or_else(|| panic!("no reduction line in\n{out}"));
    assert!(reduction >= min_percent, "{reduction} %\n{out}");
}

#[test]
fn after_a_tool_change_a_hybrid_model_follows_and_a_baseline_is_refused() {
    let t = TempDir::new("tool");
    let reference = std::fs::read_to_string(repo("machines/vmc-reference.toml")).unwrap();
    let long = reference.replacen(
        "offset_mm = [0.0, 0.0, -150.0]",
        "offset_mm = [0.0, 0.0, -250.0]",
        1,
    );
    assert_ne!(long, reference);
    std::fs::write(t.path().join("long.toml"), long).unwrap();
    succeed(
        t.path(),
        &["calibrate", "--measure-every-min", "120", "-o", "c.csv"],
    );
    succeed(
        t.path(),
        &[
            "train", "--data", "c.csv", "--kind", "linear", "-o", "lin.json",
        ],
    );
    succeed(t.path(), &["train", "--data", "c.csv", "-o", "hyb.json"]);
    let prog = repo("trajectories/diag_xy.ngc").display().to_string();
    let args = |model: &'static str| {
        [
            "run".to_string(),
            prog.clone(),
            "--machine".into(),
            "long.toml".into(),
            "--model".into(),
            model.into(),
            "--compensate".into(),
        ]
    };
    let lin = args("lin.json");
    let err = one_line_error(t.path(), &lin.each_ref().map(String::as_str));
    assert!(
        err.ends_with(
            "tool offset [0.0, 0.0, -250.0] mm (a hybrid model follows a tool change; a volumetric \
             or linear one is fitted on the calibration tool's tip: recalibrate with this tool)"
        ),
        "{err}"
    );
    let hyb = args("hyb.json");
    let out = succeed(t.path(), &hyb.each_ref().map(String::as_str));
    assert!(
        out.contains(
            "note: hyb.json was calibrated with tool offset [0.0, 0.0, -150.0] mm; its elementary \
             errors are synthesised for this machine's tool offset [0.0, 0.0, -250.0] mm"
        ),
        "{out}"
    );
    assert_reduction_at_least(&out, 80.0);
    // The same change by the program itself: M6 loads the 250 mm tool 2 of a tool table on the
    // reference machine. The hybrid follows it in the loop; the baseline stops at the M6.
    std::fs::write(
        t.path().join("tools.toml"),
        "[[tool]]\nnumber = 1\nlength_mm = 150.0\ndiameter_mm = 12.0\n\
         [[tool]]\nnumber = 2\nlength_mm = 250.0\ndiameter_mm = 12.0\n",
    )
    .unwrap();
    let diag = std::fs::read_to_string(repo("trajectories/diag_xy.ngc")).unwrap();
    // After the program's opening `%`.
    let body = diag.trim_start().trim_start_matches('%');
    std::fs::write(t.path().join("t2.ngc"), format!("%\nT2 M6\nG43 H2{body}")).unwrap();
    let run = |model: &str| {
        vec![
            "run",
            "t2.ngc",
            "--tools",
            "tools.toml",
            "--model",
            model,
            "--compensate",
        ]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>()
    };
    let err = one_line_error(
        t.path(),
        &run("lin.json")
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    assert!(
        err.starts_with("t2.ngc: line 2: tool change: geometry mismatch"),
        "{err}"
    );
    let out = succeed(
        t.path(),
        &run("hyb.json")
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    assert_reduction_at_least(&out, 80.0);
    // A tool the table does not have is refused before the run, at its line.
    std::fs::write(t.path().join("t5.ngc"), format!("%\nT5 M6{body}")).unwrap();
    let err = one_line_error(t.path(), &["run", "t5.ngc", "--tools", "tools.toml"]);
    assert_eq!(
        err,
        "t5.ngc: line 2: M6 loads tool 5, which is not in the tool table"
    );
}

#[test]
fn the_opt_in_spindle_speed_needs_a_hybrid_and_a_logged_speed() {
    let t = TempDir::new("rpm");
    succeed(
        t.path(),
        &["calibrate", "--measure-every-min", "120", "-o", "cal.csv"],
    );
    let text = std::fs::read_to_string(t.path().join("cal.csv")).unwrap();
    // The first line names the machine the data was measured on.
    assert!(text.starts_with("# machine: vmc-reference; realisation: 1; fingerprint: "));
    let header = text.lines().nth(1).unwrap();
    assert!(header.contains(",dir,spindle_rpm,"));
    assert_eq!(
        one_line_error(
            t.path(),
            &[
                "train",
                "--data",
                "cal.csv",
                "--kind",
                "linear",
                "--spindle-speed"
            ]
        ),
        "--spindle-speed applies to the hybrid model only (its spindle part), not to --kind linear"
    );
    // A dataset from a machine whose controller did not log the speed.
    let col = header.split(',').position(|c| c == "spindle_rpm").unwrap();
    let stripped: String = text
        .lines()
        .skip(1)
        .map(|l| {
            let mut c: Vec<&str> = l.split(',').collect();
            c.remove(col);
            c.join(",") + "\n"
        })
        .collect();
    std::fs::write(t.path().join("no_rpm.csv"), stripped).unwrap();
    assert_eq!(
        one_line_error(
            t.path(),
            &["train", "--data", "no_rpm.csv", "--spindle-speed"]
        ),
        "the spindle-speed features need the `spindle_rpm` column on every record; record 0 \
         (cycle `cal_3000rpm`, t = 0 s) has none"
    );
    assert!(!t.path().join("model.json").exists());
    // Trained with it, the model compensates in the loop, fed the program's speed.
    succeed(t.path(), &["train", "--data", "cal.csv", "--spindle-speed"]);
    let model = std::fs::read_to_string(t.path().join("model.json")).unwrap();
    assert!(model.contains("\"spindle_speed_exponents\""));
    let prog = repo("trajectories/diag_xy.ngc").display().to_string();
    let out = succeed(
        t.path(),
        &["run", &prog, "--model", "model.json", "--compensate"],
    );
    assert!(out.contains("compensated"), "{out}");
}
