//! Tests of the log reader.
use super::*;

fn all(text: &str, format: &LogFormat) -> Result<Vec<LogSample>, LogError> {
    let mut r = LogReader::new(text.as_bytes(), format)?;
    let mut out = Vec::new();
    while let Some(s) = r.next_sample()? {
        out.push(s);
    }
    Ok(out)
}

fn hal(columns: &str, period_ms: f64) -> LogFormat {
    LogFormat::Halsampler {
        columns: columns.split(',').map(String::from).collect(),
        period_s: Some(period_ms * 1e-3),
    }
}

#[test]
fn a_csv_and_a_halsampler_log_of_the_same_samples_read_the_same() {
    let csv = "time_s,x_mm,y_mm,z_mm,corr_x_mm,corr_y_mm,corr_z_mm,spindle_rpm\n\
               0.000,10,60,-225,0.001,0,-0.002,4000\n\
               0.001,10.5,60.25,-225,0.001,0,-0.002,4000\n";
    let h = "17 10 60 -225 0.001 0 -0.002 4000\n18 10.5 60.25 -225 0.001 0 -0.002 4000\n";
    let a = all(csv, &LogFormat::Csv).unwrap();
    let b = all(h, &hal("n,x,y,z,cx,cy,cz,s", 1.0)).unwrap();
    assert_eq!(a.len(), 2);
    for (a, b) in a.iter().zip(&b) {
        assert_eq!(a.commanded_mm, b.commanded_mm);
        assert_eq!(a.correction_mm, b.correction_mm);
        assert_eq!(a.spindle_rpm, b.spindle_rpm);
    }
    // Time from the sample number: 17 ms, 18 ms.
    assert!((b[0].time_s - 0.017).abs() < 1e-12 && (b[1].time_s - 0.018).abs() < 1e-12);
    assert_eq!((a[1].line, b[1].line), (3, 2));
}

#[test]
fn without_a_sample_number_the_rows_are_one_period_apart_and_skipped_columns_are_ignored() {
    let s = all("1 2 3 junk\n\n4 5 6 more\n", &hal("x,y,z,_", 2.0)).unwrap();
    assert_eq!(s[1].commanded_mm, [4.0, 5.0, 6.0]);
    assert_eq!(s[1].line, 3);
    assert!((s[1].time_s - 0.002).abs() < 1e-12);
    assert_eq!(s[0].correction_mm, None);
}

#[test]
fn sensor_temperature_columns_are_read_by_name() {
    let r = LogReader::new(
        "time_s,x_mm,y_mm,z_mm,spindle_front_degc\n0,1,2,3,24.5\n".as_bytes(),
        &LogFormat::Csv,
    )
    .unwrap();
    assert_eq!(r.columns().sensor_names(), vec!["spindle_front"]);
    assert!(!r.columns().has_spindle());
}

/// The error of reading `text`.
fn refusal(text: &str, format: &LogFormat) -> String {
    all(text, format).unwrap_err().to_string()
}

#[test]
fn bad_logs_are_refused_with_their_line() {
    let csv = LogFormat::Csv;
    let cases: [(&str, &str); 9] = [
        ("time_s,x_mm,y_mm\n0,1,2\n", "line 1: no `z_mm` column"),
        (
            "time_s,x_mm,y_mm,z_mm\n0,1,2,3\n1,1,2\n",
            "line 3: 3 fields, the log has 4 columns",
        ),
        (
            "time_s,x_mm,y_mm,z_mm\n0,1,2,3\n0,1,2,3\n",
            "line 3: time 0 s is not after",
        ),
        (
            "time_s,x_mm,y_mm,z_mm\n1,1,2,3\n0.5,1,2,3\n",
            "line 3: time 0.5 s is not after",
        ),
        (
            "time_s,x_mm,y_mm,z_mm\n0,1,NaN,3\n",
            "line 2: column `y_mm`: NaN is not a finite",
        ),
        (
            "time_s,x_mm,y_mm,z_mm\n0,1,inf,3\n",
            "line 2: column `y_mm`: inf is not a finite",
        ),
        (
            "time_s,x_mm,y_mm,z_mm\n0,1,2,3\n1,1,2,abc\n",
            "line 3: column `z_mm`: `abc` is not a number",
        ),
        (
            "time_s,x_mm,x_mm,y_mm,z_mm\n",
            "line 1: column `x_mm` is named twice",
        ),
        (
            "time_s,x_mm,y_mm,z_mm,feed\n",
            "line 1: unknown column `feed`",
        ),
    ];
    for (text, want) in cases {
        let e = refusal(text, &csv);
        assert!(e.starts_with(want), "{text:?}: {e}");
    }
    assert_eq!(refusal("", &csv), "the log has no samples");
    assert!(refusal("time_s,x_mm,y_mm,z_mm,corr_x_mm\n", &csv).contains("no `corr_y_mm`"));
    assert!(refusal("x_mm,y_mm,z_mm\n", &csv).contains("no `time_s`"));
    let h = hal("n,x,y,z", 1.0);
    assert!(refusal("1 1 2 3\n1 1 2 3\n", &h).starts_with("line 2: time 0.001 s"));
    assert!(refusal("1 1 2 3 4\n", &h).starts_with("line 1: 5 fields, the log has 4"));
    assert!(refusal("1 2 3\n", &hal("x,y,x_mm", 1.0)).contains("`x_mm` is named twice"));
    assert!(refusal("1 2 3\n", &hal("x,y,z", 0.0)).contains("period must be > 0"));
}
