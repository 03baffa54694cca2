use super::*;

fn sample() -> Dataset {
    Dataset {
        origin: None,
        sensor_names: vec!["BXH".into(), "Amb".into()],
        records: vec![
            Record {
                cycle: "c1".into(),
                time_s: 0.0,
                instrument: Instrument::LaserX,
                pos_mm: [40.0, 200.0, -225.0],
                values: [-1.25, 0.5, 0.1, 3.0, -2.0, 1.0],
                temps_degc: vec![20.0625, 20.0],
                dir: -1,
                spindle_rpm: None,
                axis_feed_mm_per_min: None,
            },
            Record {
                cycle: "c1".into(),
                time_s: 30.5,
                instrument: Instrument::Spindle,
                pos_mm: [280.0, 200.0, -100.0],
                values: [0.3, -0.2, -12.7, 1.5, 0.25, f64::NAN],
                temps_degc: vec![25.125, 20.1],
                dir: 1,
                spindle_rpm: None,
                axis_feed_mm_per_min: None,
            },
        ],
    }
}

#[test]
fn csv_round_trip_keeps_every_bit_and_empty_cells() {
    let d = sample();
    let text = d.to_csv();
    assert!(text.starts_with("cycle,time_s,instrument,x_mm,y_mm,z_mm,dx_um"));
    assert!(text.contains(",1.5,0.25,,1,25.125,20.1\n"));
    let back = Dataset::from_csv(&text, "d.csv").unwrap();
    assert_eq!(back.sensor_names, d.sensor_names);
    assert_eq!(back.records.len(), 2);
    assert_eq!(back.records[0], d.records[0]);
    assert!(back.records[1].values[5].is_nan());
}

#[test]
fn the_origin_line_round_trips_and_other_comments_are_skipped() {
    let mut d = sample();
    d.origin = Some(MachineIdentity {
        name: "vmc-reference".into(),
        realisation: Some(2),
        fingerprint: "0123abcd".into(),
    });
    let text = format!("# a note\n{}", d.to_csv());
    assert!(text.contains("\n# machine: vmc-reference; realisation: 2; fingerprint: 0123abcd\n"));
    let back = Dataset::from_csv(&text, "d.csv").unwrap();
    assert_eq!(back.origin, d.origin);
    assert_eq!(back.records.len(), d.records.len());
    assert_eq!(back.records[0], d.records[0]);
    let unknown = text.replace("realisation: 2", "realisation: unknown");
    let back = Dataset::from_csv(&unknown, "d.csv").unwrap();
    assert_eq!(back.origin.unwrap().realisation, None);
}

#[test]
fn a_file_without_the_dir_column_reads_as_forward_approach() {
    let d = sample();
    let text: String = d
        .to_csv()
        .lines()
        .map(|l| {
            let mut c: Vec<&str> = l.split(',').collect();
            c.remove(12);
            c.join(",") + "\n"
        })
        .collect();
    assert!(!text.contains("dir"));
    let back = Dataset::from_csv(&text, "old.csv").unwrap();
    assert!(back.records.iter().all(|r| r.dir == 1));
    assert_eq!(back.records[0].values, d.records[0].values);
}

#[test]
fn the_spindle_speed_column_round_trips_and_is_checked() {
    let mut d = sample();
    assert!(!d.to_csv().contains(SPINDLE_RPM_COLUMN));
    d.records[0].spindle_rpm = Some(3000.0);
    let text = d.to_csv();
    assert!(text.contains(",dir,spindle_rpm,BXH_degc"), "{text}");
    let back = Dataset::from_csv(&text, "d.csv").unwrap();
    assert_eq!(back.records[0].spindle_rpm, Some(3000.0));
    assert_eq!(back.records[1].spindle_rpm, None);
    for (cell, why) in [("-5", "must lie in [0, 1e6]"), ("fast", "not a number")] {
        let err = Dataset::from_csv(&text.replace(",3000,", &format!(",{cell},")), "d.csv")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("d.csv: line 2, column `spindle_rpm`: ") && err.contains(why),
            "{err}"
        );
    }
}

#[test]
fn a_bad_direction_names_line_and_column() {
    let text = sample().to_csv().replace(",-1,", ",0.5,");
    let err = Dataset::from_csv(&text, "d.csv").unwrap_err();
    assert_eq!(
        err.to_string(),
        "d.csv: line 2, column `dir`: approach direction must be 1 or -1, got \"0.5\""
    );
}

#[test]
fn a_missing_column_is_named() {
    let text = sample().to_csv().replace("ry_urad", "ry");
    let err = Dataset::from_csv(&text, "d.csv").unwrap_err();
    assert_eq!(err.to_string(), "d.csv: missing column `ry_urad`");
}

#[test]
fn a_column_named_twice_is_rejected() {
    // A sensor column pasted twice would otherwise make two sensors of one name.
    let text = sample().to_csv().replacen("_degc\n", "_degc,BXH_degc\n", 1);
    let text: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 0 {
                format!("{l}\n")
            } else {
                format!("{l},20\n")
            }
        })
        .collect();
    let err = Dataset::from_csv(&text, "d.csv").unwrap_err();
    assert!(
        err.to_string()
            .starts_with("d.csv: column `BXH_degc` appears twice in the header (columns 14 and "),
        "{err}"
    );
    // A fixed column too.
    let text = sample().to_csv().replacen("dir", "x_mm", 1);
    let err = Dataset::from_csv(&text, "d.csv").unwrap_err();
    assert!(
        err.to_string()
            .contains("column `x_mm` appears twice in the header (columns 4 and 13)"),
        "{err}"
    );
}

#[test]
fn implausible_values_name_line_and_column() {
    let d = sample();
    let mut huge = d.clone();
    huge.records[1].values[0] = 1e150;
    let err = Dataset::from_csv(&huge.to_csv(), "d.csv").unwrap_err();
    assert!(
        err.to_string()
            .starts_with("d.csv: line 3, column `dx_um`: implausible value 1e150"),
        "{err}"
    );
    let mut cold = d.clone();
    cold.records[0].temps_degc[0] = -300.0;
    let err = Dataset::from_csv(&cold.to_csv(), "d.csv").unwrap_err();
    assert!(
        err.to_string()
            .ends_with("temperature -300 °C is below absolute zero"),
        "{err}"
    );
    // The bound is far from any machine: a 1 mm (1000 µm) error still reads.
    let mut big = d;
    big.records[1].values[0] = 1000.0;
    assert!(Dataset::from_csv(&big.to_csv(), "d.csv").is_ok());
}

#[test]
fn a_nan_temperature_names_line_and_column() {
    let text = sample().to_csv().replace("25.125", "NaN");
    let err = Dataset::from_csv(&text, "d.csv").unwrap_err();
    assert_eq!(
        err.to_string(),
        "d.csv: line 3, column `BXH_degc`: not a finite temperature: \"NaN\""
    );
}

#[test]
fn an_unknown_instrument_is_rejected() {
    let text = sample().to_csv().replace("spindle", "ballbar");
    let err = Dataset::from_csv(&text, "d.csv").unwrap_err();
    assert!(
        err.to_string().contains("unknown instrument \"ballbar\""),
        "{err}"
    );
}
