//! Tests of setup files and command-line work offsets.

use super::*;

const SETUP: &str = "\
# part zero on the vise's fixed jaw
[work_offsets_mm]
G54 = [250.0, 180.0, -320.0]
\"G59.1\" = [10.0, 20.0, 30.0]

[[bodies]]
name = \"stock\"
role = \"stock\"
shape = \"box\"
min_mm = [250.0, 180.0, -340.0]
max_mm = [350.0, 240.0, -320.0]
";

#[test]
fn a_setup_file_sets_the_offsets_it_names_and_keeps_the_others() {
    let setup = SetupFile::from_toml_str(SETUP, "part.setup.toml").unwrap();
    assert_eq!(setup.work_offsets_mm[0], Some([250.0, 180.0, -320.0]));
    assert_eq!(setup.work_offsets_mm[6], Some([10.0, 20.0, 30.0]));
    assert_eq!(setup.work_offsets_mm[1], None);
    assert_eq!(setup.bodies.len(), 1);
    let machine = MachineSpec::reference();
    let mut machine_offsets = machine.clone();
    machine_offsets.axes.work_offsets_mm[1] = [1.0, 2.0, 3.0];
    let placed = Placement::of_machine(&machine_offsets)
        .with_setup(setup, Path::new("part.setup.toml"))
        .with_work_offset(0, [None, None, Some(-300.0)]);
    assert_eq!(placed.work_offsets_mm[0], [250.0, 180.0, -300.0]);
    assert_eq!(placed.work_offsets_mm[1], [1.0, 2.0, 3.0]);
    assert_eq!(placed.work_offsets_mm[6], [10.0, 20.0, 30.0]);
    assert!(placed.fixture(None).is_some());
}

#[test]
fn a_bad_setup_file_is_refused_with_its_line_and_field() {
    let cases = [
        (SETUP.replace("\"G59.1\"", "G60"), 4, "work_offsets_mm.G60"),
        (
            SETUP.replace("-320.0]\n\"", "1e9]\n\""),
            3,
            "work_offsets_mm.G54[2]",
        ),
        (
            SETUP.replace(
                "max_mm = [350.0, 240.0, -320.0]",
                "max_mm = [150.0, 240.0, -320.0]",
            ),
            6,
            "bodies[0]",
        ),
    ];
    for (text, line, field) in cases {
        let e = SetupFile::from_toml_str(&text, "part.setup.toml").unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.starts_with(&format!("part.setup.toml: line {line}: field `{field}")),
            "{msg}"
        );
    }
    // A misspelt key or a wrong type: the TOML parser's line.
    let e = SetupFile::from_toml_str("[work_offset_mm]\nG54 = [1.0, 2.0, 3.0]\n", "s.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 1") && e.contains("work_offset_mm"), "{e}");
    let e = SetupFile::from_toml_str("[work_offsets_mm]\nG54 = [1.0, 2.0]\n", "s.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 2"), "{e}");
}

#[test]
fn command_line_offsets_read_axes_in_any_order_and_refuse_what_is_not_an_offset() {
    assert_eq!(
        parse_work_offset("G54=X250,Y180,Z-320").unwrap(),
        (0, [Some(250.0), Some(180.0), Some(-320.0)])
    );
    assert_eq!(
        parse_work_offset("g59.3=z-1.5, x2").unwrap(),
        (8, [Some(2.0), None, Some(-1.5)])
    );
    for bad in [
        "G54",
        "G53=X1",
        "G54=",
        "G54=A10",
        "G54=Xten",
        "G54=X1,X2",
        "G54=Xinf",
    ] {
        assert!(parse_work_offset(bad).is_err(), "{bad}");
    }
}

#[test]
fn the_setup_beside_a_program_is_named_after_it() {
    let dir = std::env::temp_dir().join(format!("vmc-setup-beside-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let program = dir.join("part.ngc");
    assert_eq!(setup_beside(&program), None);
    std::fs::write(dir.join("part.setup.toml"), SETUP).unwrap();
    assert_eq!(setup_beside(&program), Some(dir.join("part.setup.toml")));
    let placed = Placement::of_machine(&MachineSpec::reference());
    assert_eq!(placed.search_path(Some(&program)), vec![dir.clone()]);
    std::fs::remove_dir_all(&dir).unwrap();
}

const PROBING: &str = "\
[probe]
stylus_length_mm = 120.0
ball_radius_mm = 2.0

[[artefacts]]
name = \"block\"
kind = \"gauge_block\"
top_mm = [280.0, 200.0, -300.0]
size_mm = [30.0, 30.0, 50.0]

[[artefacts]]
name = \"sphere\"
kind = \"sphere\"
centre_mm = [100.0, 100.0, -350.0]
radius_mm = 12.5
";

#[test]
fn a_setup_file_describes_the_probe_and_the_artefacts_it_touches() {
    let text = format!("{SETUP}\n{PROBING}");
    let setup = SetupFile::from_toml_str(&text, "p.setup.toml").unwrap();
    let machine = MachineSpec::reference();
    let placed = Placement::of_machine(&machine).with_setup(setup, Path::new("p.setup.toml"));
    let probe = crate::touch_probe::TouchProbe::of_placement(&placed, &machine);
    assert_eq!((probe.stylus_length_mm, probe.ball_radius_mm), (120.0, 2.0));
    let solids = placed.probe_solids(&machine, &[]);
    let names: Vec<&str> = solids.iter().map(|s| s.name.as_str()).take(3).collect();
    assert_eq!(names, ["block", "sphere", "stock"]);
    // Then the machine's own bodies (its table).
    let table = machine.collision.as_ref().map_or(0, |c| c.bodies.len());
    assert_eq!(solids.len(), 3 + table);
    // Fields left out are the typical probe's.
    let typical = crate::touch_probe::TouchProbe::typical(1.0);
    assert_eq!(probe.trigger_force_n, typical.trigger_force_n);
    // Without a [probe] section: the typical probe, as long as the machine's own tool.
    let bare =
        crate::touch_probe::TouchProbe::of_placement(&Placement::of_machine(&machine), &machine);
    assert_eq!(
        bare.stylus_length_mm,
        crate::tools::master_length_mm(&machine)
    );
}

#[test]
fn a_bad_probe_or_artefact_is_refused_with_its_line_and_field() {
    let cases = [
        (
            PROBING.replace("ball_radius_mm = 2.0", "ball_radius_mm = -2.0"),
            1,
            "probe.ball_radius_mm",
        ),
        (
            PROBING.replace("radius_mm = 12.5", "top_mm = [0.0, 0.0, 0.0]"),
            11,
            "artefacts[1].radius_mm",
        ),
        (
            PROBING.replace("\"sphere\"\nkind", "\"block\"\nkind"),
            11,
            "artefacts[1].name",
        ),
    ];
    for (text, line, field) in cases {
        let msg = SetupFile::from_toml_str(&text, "p.setup.toml")
            .unwrap_err()
            .to_string();
        assert!(
            msg.starts_with(&format!("p.setup.toml: line {line}: field `{field}")),
            "{msg}"
        );
    }
    let e = SetupFile::from_toml_str("[probe]\nstylus_mm = 3.0\n", "p.setup.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("stylus_mm"), "{e}");
}
