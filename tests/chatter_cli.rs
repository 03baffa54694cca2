//! `vmc-twin chatter` on the real binary: the example pocket (stable and unstable cuts, exit
//! status 1, the CSV) and one clear message for each kind of bad input.

mod common;

use common::{repo_file, vmc, TempDir};

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

const PROGRAM: &str = "trajectories/pocket_chatter.ngc";
const STOCK: &str = "trajectories/pocket_chatter.stock.toml";

#[test]
fn the_example_pocket_has_stable_and_unstable_cuts_and_fails() {
    let dir = TempDir::new("pocket");
    let csv = dir.path().join("cuts.csv");
    let repo = repo_file("");
    let o = vmc(
        &repo,
        &[
            "chatter",
            PROGRAM,
            "--stock",
            STOCK,
            "--out",
            csv.to_str().unwrap(),
        ],
    );
    let (out, err) = (text(&o.stdout), text(&o.stderr));
    assert_eq!(o.status.code(), Some(1), "stdout:\n{out}\nstderr:\n{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.starts_with(&format!(
            "vmc-twin: error: {PROGRAM}: 13 of 26 cuts would chatter (unstable) — line(s) 10, 14, 19,"
        )),
        "{err}"
    );
    let cut = |line: usize| {
        out.lines()
            .find(|l| l.starts_with(&format!("{PROGRAM}: line {line:>4}: ")))
            .unwrap_or_else(|| panic!("no line {line} in\n{out}"))
            .to_string()
    };
    // The first pass is a full slot: 1 mm deep where 0.32 mm is the limit at 10 000 rpm.
    let slot = cut(10);
    assert!(
        slot.contains("a_e/D 1.000 slot") && slot.ends_with("unstable"),
        "{slot}"
    );
    assert!(slot.contains("a_p,lim   0.322 mm"), "{slot}");
    // The step-over into the end wall meets material ahead: unstable.
    assert!(cut(14).contains(" entry ") && cut(14).ends_with("unstable"));
    // The climb passes 2 mm wide are stable.
    for line in [15, 40, 70] {
        let l = cut(line);
        assert!(l.contains(" down ") && l.ends_with("stable"), "{l}");
    }
    assert!(
        out.contains("12 stable, 0 marginal, 13 unstable, 1 plunge(s)"),
        "{out}"
    );
    let table = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<&str> = table.lines().collect();
    assert_eq!(rows.len(), 27);
    assert!(rows[0].starts_with(
        "line,move,spindle_rpm,feed_mm_per_min,immersion_ae_over_d,milling,axial_depth_mm,critical_depth_mm,"
    ));
    assert!(rows.iter().any(|r| r.contains(",stable,")));
    assert!(rows.iter().any(|r| r.contains(",unstable,")));
    // The CSV is not overwritten without --force; with it, the same bytes (deterministic).
    let again = vmc(
        &repo,
        &[
            "chatter",
            PROGRAM,
            "--stock",
            STOCK,
            "--out",
            csv.to_str().unwrap(),
        ],
    );
    assert!(
        text(&again.stderr).contains("exists"),
        "{}",
        text(&again.stderr)
    );
    vmc(
        &repo,
        &[
            "chatter",
            PROGRAM,
            "--stock",
            STOCK,
            "--out",
            csv.to_str().unwrap(),
            "--force",
        ],
    );
    assert_eq!(std::fs::read_to_string(&csv).unwrap(), table);
}

#[test]
fn a_program_of_stable_cuts_exits_with_status_0() {
    let dir = TempDir::new("stable");
    // The same block, one climb pass 1 mm wide along the edge at Y = −7 (a_e/D = 1/16).
    std::fs::write(
        dir.path().join("edge.ngc"),
        "G0 X110 Y-7 Z-1\nM3 S10000\nG1 X-10 F800\nM5\nM2\n",
    )
    .unwrap();
    let stock = repo_file(STOCK);
    let o = vmc(
        dir.path(),
        &["chatter", "edge.ngc", "--stock", stock.to_str().unwrap()],
    );
    let out = text(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{out}\n{}", text(&o.stderr));
    assert!(out.contains("edge.ngc: line    3: G1 "), "{out}");
    assert!(out.ends_with("no unstable cut\n"), "{out}");
}

/// Runs `chatter` in a folder holding `files`; asserts one error line and exit status 1.
fn refused(files: &[(&str, &str)], args: &[&str]) -> String {
    let dir = TempDir::new("bad");
    for (name, body) in files {
        std::fs::write(dir.path().join(name), body).unwrap();
    }
    let mut all = vec!["chatter"];
    all.extend_from_slice(args);
    let o = vmc(dir.path(), &all);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{}\n{err}", text(&o.stdout));
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err.trim_end()
        .strip_prefix("vmc-twin: error: ")
        .unwrap_or(&err)
        .to_string()
}

#[test]
fn bad_input_gets_one_clear_message() {
    const BOX: &str = "min_mm = [0, 0, -20]\nmax_mm = [100, 80, 0]\n";
    const CUT: &str = "G0 X72 Y28 Z5\nM3 S10000\nG1 Z-1 F300\nG1 X28\nM2\n";
    let with = |program: &str, stock: &str, extra: &[&str]| {
        let mut args = vec!["p.ngc", "--stock", "s.toml"];
        args.extend_from_slice(extra);
        refused(&[("p.ngc", program), ("s.toml", stock)], &args)
    };
    assert_eq!(
        with("M3 S8000\nG0 X10 Y10 Z5\nM2\n", BOX, &[]),
        "p.ngc: the program has no cutting move (G1, G2 or G3)"
    );
    assert_eq!(
        with("M3 S8000\nG0 Z50\nG1 X150 F200\nM2\n", BOX, &[]),
        "p.ngc: the program never touches the stock: none of its 1 feed moves reaches the material of the box X0.000 Y0.000 Z-20.000 … X100.000 Y80.000 Z0.000 mm"
    );
    assert_eq!(
        with("G0 X72 Y28 Z5\nG1 Z-1 F300\nM2\n", BOX, &[]),
        "p.ngc: line 2: G1 cuts the stock with the spindle stopped, at X72.000 Y28.000 Z-0.250"
    );
    assert_eq!(
        with(CUT, "min_mm = [0, 0, 0]\nmax_mm = [100, -80, 10]\n", &[]),
        "s.toml: the stock box is empty along y: min_mm 0 must be below max_mm -80"
    );
    let unknown = with(CUT, &format!("{BOX}material = \"steel\"\n"), &[]);
    assert!(
        unknown.starts_with("s.toml: ") && unknown.contains("unknown field `material`"),
        "{unknown}"
    );
    assert!(with(CUT, "min_mm = [0, 0]\n", &[]).starts_with("s.toml: "));
    assert_eq!(
        with(CUT, BOX, &["--grid-mm", "6"]),
        "p.ngc: the grid spacing 6 mm is too coarse for a 16 mm tool: at most a quarter of its diameter"
    );
    assert_eq!(
        with(CUT, BOX, &["--immersion-bin", "1.5"]),
        "--immersion-bin must be in [0.01, 1], got 1.5"
    );
    assert_eq!(
        with("G1 X1 F100 Q3\n", BOX, &[]).split(':').next(),
        Some("p.ngc")
    );
    assert_eq!(
        refused(&[("s.toml", BOX)], &["none.ngc", "--stock", "s.toml"]),
        "none.ngc: cannot read program: No such file or directory (os error 2)"
    );
    let tool = with(CUT, BOX, &["--tool", "t.toml"]);
    assert!(tool.starts_with("t.toml: cannot read tool file"), "{tool}");
}

#[test]
fn cutter_compensation_offsets_the_path_by_the_tool_radius() {
    // A contour along the block's edges: with G42 (tool right of this counter-clockwise path,
    // outside the block) the Ø16 cutter only grazes the block; with G41 it cuts inside.
    let contour = |side: &str| {
        format!(
            "G0 X-20 Y-20 Z5\nM3 S10000\nG0 Z-1\n{side} D1\nG1 X0 Y0 F600\nG1 X100\nG1 Y80\nG1 X0\nG1 Y0\nG40\nG1 X-20 Y-20\nM5\nM2\n"
        )
    };
    let stock = repo_file(STOCK);
    let dir = TempDir::new("comp");
    for (side, cuts) in [("G42", false), ("G41", true)] {
        std::fs::write(dir.path().join("c.ngc"), contour(side)).unwrap();
        let o = vmc(
            dir.path(),
            &["chatter", "c.ngc", "--stock", stock.to_str().unwrap()],
        );
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(1));
        assert_eq!(
            err.contains("the program never touches the stock"),
            !cuts,
            "{side}: {err}"
        );
    }
}
