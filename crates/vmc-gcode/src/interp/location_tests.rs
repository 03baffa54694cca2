//! Tests of where errors are reported: the subroutine file a line is in and the calls that
//! led to it; errors of the main program keep their form.

use std::path::{Path, PathBuf};

use super::*;

/// A folder of subroutine files for one test, removed when dropped.
struct SubDir(PathBuf);

impl SubDir {
    fn new(name: &str, files: &[(&str, &str)]) -> Self {
        let dir = std::env::temp_dir().join(format!("vmc-loc-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("create the test folder");
        for (file, text) in files {
            std::fs::write(dir.join(file), text).expect("write a subroutine file");
        }
        Self(dir)
    }

    fn config(&self) -> InterpConfig {
        InterpConfig {
            subroutine_dirs: vec![self.0.clone()],
            ..InterpConfig::default()
        }
    }

    fn path(&self, file: &str) -> PathBuf {
        self.0.join(file)
    }
}

impl Drop for SubDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn site(file: Option<&Path>, line: usize) -> CallSite {
    CallSite {
        file: file.map(Path::to_path_buf),
        line,
    }
}

#[test]
fn an_error_in_a_subroutine_file_names_that_file_its_line_and_the_call() {
    let dir = SubDir::new(
        "one",
        &[(
            "bad.ngc",
            "(a subroutine)\no<bad> sub\nG1 X1 F100\nG2 X3\no<bad> endsub\n",
        )],
    );
    let e = run_program("G21\n\no<bad> call\nM2", &dir.config()).unwrap_err();
    let bad = dir.path("bad.ngc");
    assert_eq!((e.line, e.col), (4, 1));
    assert_eq!(e.file.as_deref(), Some(bad.as_path()));
    assert_eq!(e.calls, vec![site(None, 3)]);
    assert_eq!(
        e.to_string(),
        format!(
            "{}: line 4, column 1: G2 needs I/J/K or R (called from line 3)",
            bad.display()
        )
    );
    assert_eq!(
        e.display_in("prog.ngc").to_string(),
        format!(
            "{}: line 4, column 1: G2 needs I/J/K or R (called from prog.ngc line 3)",
            bad.display()
        )
    );
}

#[test]
fn the_call_chain_runs_through_files_and_subroutines_of_the_program() {
    let dir = SubDir::new(
        "chain",
        &[
            (
                "outer.ngc",
                "o<outer> sub\nG0 X1\no<inner> call\no<outer> endsub\n",
            ),
            ("inner.ngc", "o<inner> sub\nG0 X[1/0]\no<inner> endsub\n"),
        ],
    );
    let src = "o10 sub\no<outer> call\no10 endsub\nG0 X0\no10 call\nM2";
    let e = run_program(src, &dir.config()).unwrap_err();
    let outer = dir.path("outer.ngc");
    assert_eq!(e.file.as_deref(), Some(dir.path("inner.ngc").as_path()));
    assert_eq!(e.line, 2);
    assert_eq!(
        e.calls,
        vec![site(Some(&outer), 3), site(None, 2), site(None, 5)]
    );
    assert!(
        e.to_string().ends_with(&format!(
            "(called from {} line 3, from line 2, from line 5)",
            outer.display()
        )),
        "{e}"
    );
}

#[test]
fn a_syntax_error_in_a_subroutine_file_is_located_in_it() {
    let dir = SubDir::new(
        "syntax",
        &[("typo.ngc", "o<typo> sub\nG0 X[1\no<typo> endsub\n")],
    );
    let e = run_program("G21\no<typo> call\nM2", &dir.config()).unwrap_err();
    assert_eq!(e.file.as_deref(), Some(dir.path("typo.ngc").as_path()));
    assert_eq!((e.line, e.calls.clone()), (2, vec![site(None, 2)]));
}

#[test]
fn errors_of_the_main_program_keep_their_form_with_the_calls_as_data() {
    // In a subroutine of the program itself: the line is the program's.
    let e = run_program(
        "o10 sub\nG2 X1\no10 endsub\no10 call\nM2",
        &InterpConfig::default(),
    )
    .unwrap_err();
    assert_eq!(
        (e.file.clone(), e.calls.clone()),
        (None, vec![site(None, 4)])
    );
    assert_eq!(e.to_string(), "line 2, column 1: G2 needs I/J/K or R");
    let e = run_program("G0 X1\nG2 X2", &InterpConfig::default()).unwrap_err();
    assert_eq!((e.file, e.calls), (None, vec![]));
}

#[test]
fn a_probe_without_contact_in_a_subroutine_file_is_located_there() {
    let dir = SubDir::new(
        "probe",
        &[(
            "touch.ngc",
            "o<touch> sub\nG38.2 Z-5 F50\no<touch> endsub\n",
        )],
    );
    let mut run = ProgramRun::new("G0 Z1\no<touch> call\nM2", &dir.config()).unwrap();
    let mut out = Vec::new();
    assert!(matches!(run.resume(&mut out), Ok(RunEvent::Probe(_))));
    let e = run.probe_result(ProbeOutcome::NoContact).unwrap_err();
    assert_eq!(e.file.as_deref(), Some(dir.path("touch.ngc").as_path()));
    assert_eq!((e.line, e.calls.clone()), (2, vec![site(None, 2)]));
    assert_eq!(e.msg, "G38.2 move finished without making contact.");
    assert_eq!(run.resume(&mut out).unwrap_err(), e);
}

#[test]
fn each_move_carries_the_length_unit_of_the_block_it_came_from() {
    let (moves, units) = run_program_with_units(
        "G0 X1\nG20 G0 X1\nG1 X2 F10\nG21 G0 X2\nM2",
        &InterpConfig::default(),
    )
    .unwrap();
    assert_eq!(moves.len(), units.len());
    assert_eq!(
        units,
        [
            LengthUnit::Mm,
            LengthUnit::Inch,
            LengthUnit::Inch,
            LengthUnit::Mm,
            LengthUnit::Mm
        ]
    );
    assert_eq!(LengthUnit::Inch.format_mm(25.4), "1 in");
    assert_eq!(LengthUnit::Mm.format_mm(-0.0001), "0 mm");
}

#[test]
fn a_subroutine_not_found_names_the_folders_searched_and_no_internal_setting() {
    let e = run_program("o<part> call\nM2", &InterpConfig::default()).unwrap_err();
    assert!(e.msg.contains("no subroutine folder"), "{e}");
    let dir = SubDir::new("missing", &[]);
    let cfg = InterpConfig {
        subroutine_dirs: vec![dir.0.clone()],
        ..InterpConfig::default()
    };
    let e = run_program("o<part> call\nM2", &cfg).unwrap_err();
    assert!(e.msg.contains("part.ngc"), "{e}");
    assert!(e.msg.contains(&dir.0.display().to_string()), "{e}");
    assert!(!e.msg.contains("InterpConfig"), "{e}");
}
