use super::*;
use crate::cec::parse_cec_program;
use crate::linuxcnc::{check_comp_file, parse_comp_file};
use crate::number::Direction;
use crate::sample::{sample_tables, AxisTravel, SamplingSpec};
use crate::testmodel::{Analytic, TRAVEL_MM};

fn set_of(model: &mut Analytic) -> TableSet {
    let spec = SamplingSpec::new(TRAVEL_MM.map(|[min_mm, max_mm]| AxisTravel { min_mm, max_mm }));
    sample_tables(model, &spec).unwrap()
}

fn provenance() -> Provenance {
    Provenance {
        model: "hybrid.json (hybrid)".into(),
        thermal_state: "readings T=24 °C\nsteady".into(),
    }
}

#[test]
fn the_linuxcnc_files_are_three_checked_joint_tables_and_their_ini_lines() {
    let set = set_of(&mut Analytic::at(24.0));
    let files = linuxcnc_files(&set, &LinuxCncExport::default(), &provenance()).unwrap();
    let names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "joint0-x.comp",
            "joint1-y.comp",
            "joint2-z.comp",
            "comp-tables.ini"
        ]
    );
    for (k, f) in files[..3].iter().enumerate() {
        let summary = check_comp_file(&f.contents).unwrap();
        assert_eq!(summary.points, set.own[k].grid.points);
        let back = parse_comp_file(&f.contents, CompFileType::Trims).unwrap();
        for x in [0.0, 13.7, 199.99, 400.0, -300.0] {
            for dir in [Direction::Positive, Direction::Negative] {
                let want = set.own_correction_mm(k, x, dir);
                assert!(
                    (back.trim_mm(x, dir) - want).abs() < 1e-12,
                    "axis {k} at {x}"
                );
            }
        }
    }
    let ini = &files[3].contents;
    assert!(
        ini.contains("[JOINT_1]\nCOMP_FILE = joint1-y.comp\nCOMP_FILE_TYPE = 1\n"),
        "{ini}"
    );
    // Every line is a comment, a section header or a key = value line: nothing a user pastes
    // breaks the INI file, and the thermal state's line break did not escape its comment.
    for line in ini.lines() {
        assert!(
            line.starts_with('#') || line.starts_with("[JOINT_") || line.contains(" = "),
            "{line:?}"
        );
    }
    assert!(
        ini.contains("# thermal state: readings T=24 °C steady\n"),
        "{ini}"
    );
}

#[test]
fn joints_can_be_renumbered_but_not_repeated() {
    let set = set_of(&mut Analytic::at(24.0));
    let opts = LinuxCncExport {
        file_type: CompFileType::MeasuredPositions,
        joints: [2, 0, 1],
    };
    let files = linuxcnc_files(&set, &opts, &provenance()).unwrap();
    assert_eq!(files[0].name, "joint2-x.comp");
    assert!(files[3]
        .contents
        .contains("[JOINT_2]\nCOMP_FILE = joint2-x.comp\nCOMP_FILE_TYPE = 0\n"));
    let back = parse_comp_file(&files[0].contents, CompFileType::MeasuredPositions).unwrap();
    let want = set.own_correction_mm(0, 123.4, Direction::Positive);
    assert!((back.trim_mm(123.4, Direction::Positive) - want).abs() < 1e-12);
    for joints in [[0, 0, 1], [0, 1, 16]] {
        let opts = LinuxCncExport {
            joints,
            ..LinuxCncExport::default()
        };
        assert!(matches!(
            linuxcnc_files(&set, &opts, &provenance()).unwrap_err(),
            ExportError::BadOption {
                field: "joints",
                ..
            }
        ));
    }
}

#[test]
fn a_model_with_reversal_gets_direction_dependent_cec_tables_for_its_own_axes() {
    let set = set_of(&mut Analytic::at(24.0));
    let p = cec_program(&set, &CecExport::default(), &provenance()).unwrap();
    // Per axis: positive and negative own tables, then two cross tables.
    assert_eq!(p.tables.len(), 12);
    let d: Vec<i8> = p.tables.iter().map(|t| t.direction().number()).collect();
    assert_eq!(d, [1, -1, 0, 0, 1, -1, 0, 0, 1, -1, 0, 0]);
    assert_eq!(p.tables[2].input_axis(), "AX2");
    assert_eq!(p.tables[2].output_axis(), "AX1");
    assert!(p
        .comment_lines
        .contains(&"table 3: X along Z, both directions, zero at the reference".to_string()));
    assert!(p
        .comment_lines
        .iter()
        .any(|c| c == "thermal state: readings T=24 degC steady"));

    let mut no_reversal = Analytic::at(24.0);
    no_reversal.shift_mm = [0.0; 3];
    let p = cec_program(
        &set_of(&mut no_reversal),
        &CecExport::default(),
        &provenance(),
    )
    .unwrap();
    assert_eq!(p.tables.len(), 9);
    let own_only = CecExport {
        cross_tables: false,
        ..CecExport::default()
    };
    let p = cec_program(&set_of(&mut no_reversal), &own_only, &provenance()).unwrap();
    assert_eq!(p.tables.len(), 3);
    let long = Provenance {
        model: "m".repeat(500),
        thermal_state: "µ°".into(),
    };
    let p = cec_program(&set_of(&mut no_reversal), &own_only, &long).unwrap();
    assert!(p
        .comment_lines
        .iter()
        .all(|c| c.len() <= 7 + 160 && c.is_ascii()));
    assert!(p.comment_lines.contains(&"thermal state: udeg".to_string()));
}

#[test]
fn the_cec_program_read_back_compensates_the_model_along_each_axis_line() {
    // Differential: the program text, read back and evaluated as the controller sums its
    // tables, against the model's own −E on the three lines through the reference.
    let mut m = Analytic::at(24.0);
    let set = set_of(&mut m);
    let files = cec_files(&set, &CecExport::default(), &provenance()).unwrap();
    assert_eq!(files[0].name, "NC_CEC.INI");
    let program = parse_cec_program(&files[0].contents).unwrap();
    let names = ["AX1", "AX2", "AX3"];
    let axis = |n: &str| names.iter().position(|a| *a == n).unwrap();
    for k in 0..3 {
        let worst_um = set.own[k].check.max_abs_um.max(
            set.cross
                .iter()
                .filter(|t| t.input_axis == k)
                .map(|t| t.check.max_abs_um)
                .fold(0.0, f64::max),
        );
        for i in 0..=40 {
            let t = TRAVEL_MM[k];
            let mut q = set.reference_mm;
            q[k] = t[0] + (t[1] - t[0]) * i as f64 / 40.0;
            let e = Analytic::error_mm(q, 24.0);
            for dir in [Direction::Positive, Direction::Negative] {
                for j in 0..3 {
                    let c = program.total_compensation_mm(names[j], |a| q[axis(a)], |_| dir);
                    let reversal = if dir == Direction::Negative {
                        m.shift_mm[j]
                    } else {
                        0.0
                    };
                    let residual_um = (c + e[j] + reversal) * 1e3;
                    assert!(
                        residual_um.abs() <= worst_um + 2e-3,
                        "output {j} along {k} at {q:?} {dir:?}: {residual_um} um"
                    );
                }
            }
        }
    }
}

#[test]
fn bad_cec_options_are_refused() {
    let set = set_of(&mut Analytic::at(24.0));
    for names in [["AX1", "AX1", "AX3"], ["AX1", "AX(2)", "AX3"]] {
        let opts = CecExport {
            axis_names: names.map(String::from),
            ..CecExport::default()
        };
        assert!(matches!(
            cec_program(&set, &opts, &provenance()).unwrap_err(),
            ExportError::BadOption {
                field: "axis_names",
                ..
            }
        ));
    }
    let opts = CecExport {
        channel: 0,
        ..CecExport::default()
    };
    assert!(cec_files(&set, &opts, &provenance()).is_err());
}

#[test]
fn the_report_lists_every_table_and_the_volume_check() {
    let set = set_of(&mut Analytic::at(24.0));
    let text = report_text(&set, &provenance());
    assert_eq!(text.lines().filter(|l| l.contains(" along ")).count(), 9);
    assert!(
        text.contains(
            "reversal (negative minus positive approach) X/Y/Z: 0.500 / -0.600 / 0.400 um"
        ),
        "{text}"
    );
    assert!(
        text.contains("left by the own-axis tables (LinuxCNC) max 4.8"),
        "{text}"
    );
    assert!(
        text.contains("left by own-axis and cross tables (CEC) max 0.56"),
        "{text}"
    );
}
