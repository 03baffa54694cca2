//! Placing a program on the machine from the command line, on the real binary: a program
//! written for its own part zero leaves the travel with G54 at machine zero and runs once a
//! setup file or `--work-offset` places it; a bad setup file is refused with its line and
//! field; travel messages in the program's units; subroutine files found next to the program
//! and in `--subroutines` folders by `interpret`, `run` and `check` alike; a program without
//! G4 dwells measured during motion by default. Programs of our own writing.

mod common;
use common::{ok, refused, vmc, TempDir};

/// A pocket for its own part zero on the top face of the stock: Z above 0 to clear, down to
/// Z −2 to cut; no dwell.
const PART: &str = "G21 G90 G54\nG0 X0 Y0 Z5\nG1 Z-2 F600\nG1 X40 Y30\nG0 Z5\nM2\n";

/// The setup that places it: part zero at X250 Y180 Z−320 on the reference machine.
const SETUP: &str = "[work_offsets_mm]\nG54 = [250.0, 180.0, -320.0]\n";

#[test]
fn a_program_for_its_own_part_zero_runs_once_the_setup_places_it() {
    let dir = TempDir::new("setup-place");
    std::fs::write(dir.path().join("part.ngc"), PART).unwrap();
    // Unplaced: G54 at machine zero, Z5 is above the travel.
    let err = refused(&vmc(dir.path(), &["check", "part.ngc"]), "check unplaced");
    assert!(err.contains("would crash or leave the travel"), "{err}");
    let run = vmc(dir.path(), &["run", "part.ngc"]);
    let err = refused(&run, "run unplaced");
    assert!(
        err.contains("line 2: axis Z reaches 5 mm, outside travel [-450, 0] mm"),
        "{err}"
    );
    // On the command line.
    let out = ok(
        &vmc(
            dir.path(),
            &["check", "part.ngc", "--work-offset", "G54=X250,Y180,Z-320"],
        ),
        "check placed by --work-offset",
    );
    assert!(out.contains("G54 X250 Y180 Z-320 mm"), "{out}");
    // In the setup file beside the program: found without an option.
    std::fs::write(dir.path().join("part.setup.toml"), SETUP).unwrap();
    let out = ok(
        &vmc(dir.path(), &["check", "part.ngc"]),
        "check with part.setup.toml",
    );
    assert!(out.contains("placement: setup part.setup.toml"), "{out}");
    // `run` measures it during motion (it has no dwell) at the default period.
    let out = ok(
        &vmc(dir.path(), &["run", "part.ngc"]),
        "run with part.setup.toml",
    );
    assert!(out.contains("measured during motion every 1 s"), "{out}");
    // The command line overrides the file, axis by axis: Z back to machine zero leaves the
    // travel again.
    let err = refused(
        &vmc(
            dir.path(),
            &["check", "part.ngc", "--work-offset", "G54=Z0"],
        ),
        "check with Z overridden",
    );
    assert!(err.contains("travel"), "{err}");
}

#[test]
fn a_bad_setup_file_is_refused_with_its_line_and_field() {
    let dir = TempDir::new("setup-bad");
    std::fs::write(dir.path().join("part.ngc"), PART).unwrap();
    let bad =
        "# part zero\n[work_offsets_mm]\nG54 = [250.0, 180.0, -320.0]\nG5 = [1.0, 2.0, 3.0]\n";
    std::fs::write(dir.path().join("part.setup.toml"), bad).unwrap();
    for cmd in ["check", "run", "interpret"] {
        let err = refused(&vmc(dir.path(), &[cmd, "part.ngc"]), cmd);
        assert!(
            err.contains(
                "part.setup.toml: line 4: field `work_offsets_mm.G5`: unknown work offset"
            ),
            "{cmd}: {err}"
        );
    }
    std::fs::remove_file(dir.path().join("part.setup.toml")).unwrap();
    let err = refused(
        &vmc(
            dir.path(),
            &["check", "part.ngc", "--work-offset", "G54=X1,Q2"],
        ),
        "bad --work-offset",
    );
    assert!(err.contains("--work-offset \"G54=X1,Q2\""), "{err}");
}

#[test]
fn an_inch_program_beyond_the_travel_is_told_in_inches_rounded() {
    let dir = TempDir::new("setup-inch");
    // X −2.99590 in = −76.09586 mm.
    std::fs::write(dir.path().join("inch.ngc"), "G20 G90\nG0 X-2.9959\nM2\n").unwrap();
    let err = refused(&vmc(dir.path(), &["run", "inch.ngc"]), "run inch");
    assert!(
        err.contains("line 2: axis X reaches -2.9959 in, outside travel [0, 22.0472] in"),
        "{err}"
    );
    let out = vmc(dir.path(), &["check", "inch.ngc"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("axis X reaches -2.9959 in"), "{text}");
}

#[test]
fn interpret_run_and_check_find_subroutines_beside_the_program_then_in_subroutine_folders() {
    let dir = TempDir::new("setup-subs");
    let lib = dir.path().join("lib");
    std::fs::create_dir_all(&lib).unwrap();
    std::fs::write(
        dir.path().join("main.ngc"),
        "G21 G90 G54\no<near> call\no<far> call\nM2\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("near.ngc"),
        "o<near> sub\nG0 X10 Y10 Z-10\no<near> endsub\n",
    )
    .unwrap();
    std::fs::write(
        lib.join("far.ngc"),
        "o<far> sub\nG1 X20 F600\nG4 P1\no<far> endsub\n",
    )
    .unwrap();
    for cmd in ["interpret", "check", "run"] {
        let err = refused(&vmc(dir.path(), &[cmd, "main.ngc"]), cmd);
        assert!(
            err.contains("o<far> call: no subroutine o<far>"),
            "{cmd}: {err}"
        );
        assert!(err.contains("far.ngc"), "{cmd}: {err}");
        assert!(!err.contains("InterpConfig"), "{cmd}: {err}");
        ok(
            &vmc(dir.path(), &[cmd, "main.ngc", "--subroutines", "lib"]),
            &format!("{cmd} --subroutines lib"),
        );
    }
}
