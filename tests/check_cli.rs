//! `vmc-twin check` on the real binary: one program per way to crash, a clean one, and
//! the refusal of `run` and `campaign` with the same travel message. Programs and the fixture are
//! in `tests/data/collision/`; the expected reports are written out here line by line.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_vmc-twin");

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs `vmc-twin <args>` in the repository folder (paths in reports stay short and stable).
fn vmc(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(repo())
        .output()
        .expect("run vmc-twin")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// The problem lines of a check report (those naming the program).
fn problem_lines(o: &Output, program: &str) -> Vec<String> {
    text(&o.stdout)
        .lines()
        .filter(|l| l.starts_with(&format!("{program}: ")))
        .map(str::to_string)
        .collect()
}

const VISE: &str = "tests/data/collision/vise.toml";

/// Checks `program` with the vise fixture; asserts exit code 1, one line on stderr, and returns
/// the problem lines.
fn failing_check(program: &str) -> Vec<String> {
    let o = vmc(&["check", program, "--fixture", VISE]);
    let err = text(&o.stderr);
    assert_eq!(
        o.status.code(),
        Some(1),
        "stdout:\n{}\nstderr:\n{err}",
        text(&o.stdout)
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.starts_with(&format!("vmc-twin: error: {program}: would crash")),
        "{err}"
    );
    problem_lines(&o, program)
}

#[test]
fn a_clean_program_passes_with_exit_code_0() {
    let p = "tests/data/collision/clean_pocket.ngc";
    let o = vmc(&["check", p, "--fixture", VISE]);
    let out = text(&o.stdout);
    assert!(o.status.success(), "{out}\n{}", text(&o.stderr));
    assert!(problem_lines(&o, p).is_empty(), "{out}");
    assert!(
        out.contains("stock (stock): X230.000 Y160.000 Z-380.000 … X330.000 Y240.000 Z-250.000 mm"),
        "{out}"
    );
    assert!(
        out.contains("0 collision(s), 0 travel violation(s)"),
        "{out}"
    );
    assert!(out.contains("no problem found"), "{out}");
}

#[test]
fn a_rapid_into_the_vise_is_reported_with_line_bodies_position_and_depth() {
    let p = "tests/data/collision/rapid_into_vise.ngc";
    // Expected report (the contact point's X and Y on the jaw's top face are where parry's EPA
    // puts it, anywhere under the tool; only its Z is asserted):
    // {p}: line 4: G0 rapid: tool hits vise_fixed_jaw (fixture), 5.000 mm deep at tool tip
    //   X280.000 Y150.000 Z-340.000 (t = 1.927 s), contact point X281.402 Y154.655 Z-335.000;
    //   first contact at tool tip X280.000 Y150.000 Z-335.200 (t = 1.847 s)
    let lines = failing_check(p);
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(lines[0].starts_with(&format!("{p}: line 4: G0 rapid: tool hits vise_fixed_jaw (fixture), 5.000 mm deep at tool tip X280.000 Y150.000 Z-340.000 (t = 1.927 s), contact point X")), "{lines:?}");
    assert!(
        lines[0].ends_with(
            " Z-335.000; first contact at tool tip X280.000 Y150.000 Z-335.200 (t = 1.847 s)"
        ),
        "{lines:?}"
    );
}

#[test]
fn the_holder_entering_the_stock_on_a_deep_plunge_is_a_crash() {
    let p = "tests/data/collision/holder_into_stock.ngc";
    let lines = failing_check(p);
    assert_eq!(lines.len(), 1, "{lines:?}");
    // The tool cutting the stock on line 6 is allowed; the holder 15 mm into it is not, and the
    // retraction on line 7 is the same crash (not reported twice).
    assert!(
        lines[0].starts_with(&format!("{p}: line 6: G1 feed: holder hits stock (stock), 15.000 mm deep at tool tip X280.000 Y200.000 Z-370.000")),
        "{lines:?}"
    );
    assert!(
        lines[0].contains("first contact at tool tip X280.000 Y200.000 Z-355.200"),
        "{lines:?}"
    );
}

#[test]
fn z_below_the_table_within_travel_is_a_crash_even_without_a_fixture() {
    let p = "tests/data/collision/z_below_table.ngc";
    let o = vmc(&["check", p]);
    assert_eq!(o.status.code(), Some(1));
    let lines = problem_lines(&o, p);
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(
        lines[0].starts_with(&format!("{p}: line 6: G1 feed: tool hits table (table), 5.000 mm deep at tool tip X100.000 Y100.000 Z-445.000")),
        "{lines:?}"
    );
    assert!(text(&o.stdout).contains("(no fixture file)"));
}

#[test]
fn x_past_travel_is_reported_per_move_and_run_refuses_with_the_same_message() {
    let p = "tests/data/collision/x_past_travel.ngc";
    let want = format!("{p}: line 4: axis X reaches 580 mm, outside travel [0, 560] mm");
    assert_eq!(
        failing_check(p),
        [
            want.clone(),
            format!("{p}: line 5: axis X reaches 580 mm, outside travel [0, 560] mm")
        ]
    );
    let o = vmc(&["run", p]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        text(&o.stderr).trim_end(),
        format!("vmc-twin: error: {want}")
    );
    assert!(
        o.stdout.is_empty(),
        "nothing simulated: {}",
        text(&o.stdout)
    );
}

#[test]
fn campaign_refuses_a_machine_its_diagonals_do_not_fit_with_the_check_message() {
    let dir = std::env::temp_dir().join(format!("vmc-twin-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let reference = std::fs::read_to_string(repo().join("machines/vmc-reference.toml")).unwrap();
    let small = reference.replacen("travel_max_mm = [560.0", "travel_max_mm = [500.0", 1);
    assert_ne!(small, reference);
    let machine = dir.join("small-x.toml");
    std::fs::write(&machine, small).unwrap();
    let m = machine.display().to_string();

    let check = vmc(&["check", "trajectories/diag_xy.ngc", "--machine", &m]);
    assert_eq!(check.status.code(), Some(1));
    let first = problem_lines(&check, "trajectories/diag_xy.ngc")
        .into_iter()
        .next()
        .expect("a travel violation");
    assert!(
        first.contains("axis X reaches") && first.contains("outside travel [0, 500] mm"),
        "{first}"
    );

    let campaign = vmc(&["campaign", "--seeds", "1", "--machine", &m]);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(campaign.status.code(), Some(1));
    assert_eq!(
        text(&campaign.stderr).trim_end(),
        format!("vmc-twin: error: {first}")
    );
}

#[test]
fn bad_fixture_files_are_one_line_errors_naming_file_and_field() {
    let dir = std::env::temp_dir().join(format!("vmc-twin-fixture-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("bad.toml");
    std::fs::write(
        &f,
        "bodies = [ { name = \"jaw\", role = \"fixture\", shape = \"box\", min_mm = [0.0, 0.0, 0.0], max_mm = [10.0, nan, 5.0] } ]\n",
    )
    .unwrap();
    let fs = f.display().to_string();
    let o = vmc(&[
        "check",
        "tests/data/collision/clean_pocket.ngc",
        "--fixture",
        &fs,
    ]);
    let missing = vmc(&[
        "check",
        "tests/data/collision/clean_pocket.ngc",
        "--fixture",
        "nope.toml",
    ]);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(o.status.code(), Some(1));
    let err = text(&o.stderr);
    assert_eq!(err.trim_end(), format!("vmc-twin: error: {fs}: field `bodies[0].max_mm[1]`: must be a finite number within ±100000 mm, got NaN"));
    assert_eq!(missing.status.code(), Some(1));
    assert!(text(&missing.stderr).contains("nope.toml: cannot read fixture file"));
}

#[test]
fn the_problem_report_does_not_depend_on_the_working_folder_path() {
    // Absolute paths work as well; the report names the program as given.
    let p = repo().join("tests/data/collision/rapid_into_vise.ngc");
    let v = repo().join(VISE);
    let o = Command::new(BIN)
        .args([
            "check",
            &p.display().to_string(),
            "--fixture",
            &v.display().to_string(),
        ])
        .current_dir(Path::new("/"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(problem_lines(&o, &p.display().to_string()).len(), 1);
}
