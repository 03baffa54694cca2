use super::*;
use vmc_machine::machine::MachineSpec;
use vmc_machine::sim::{self, SimConfig};
use vmc_machine::sim::{Observer, PointRecord, RunStart};
use vmc_machine::twin::Twin;

fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vmc-record-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn rrd_paths_are_checked_before_anything_runs() {
    let d = temp_dir("paths");
    let missing = d.join("no_such_dir").join("x.rrd");
    let e = check_rrd_path(&missing, false).unwrap_err().to_string();
    assert!(e.contains("does not exist"), "{e}");
    let e = check_rrd_path(&d.join("x.txt"), false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("must end in .rrd"), "{e}");
    let dir_named_rrd = d.join("dir.rrd");
    std::fs::create_dir_all(&dir_named_rrd).unwrap();
    let e = check_rrd_path(&dir_named_rrd, true)
        .unwrap_err()
        .to_string();
    assert!(e.contains("is a directory"), "{e}");
    let existing = d.join("old.rrd");
    std::fs::write(&existing, b"old").unwrap();
    assert!(matches!(
        check_rrd_path(&existing, false),
        Err(RecordError::Exists(_))
    ));
    check_rrd_path(&existing, true).unwrap();
    check_rrd_path(&d.join("new.rrd"), false).unwrap();
    // No probe file left behind.
    let left: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    assert!(left.iter().all(|n| !n.contains("probe")), "{left:?}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_diagonal_is_recognised_only_on_a_line() {
    let pts = [
        [10.0, 60.0, -225.0],
        [70.0, 90.0, -225.0],
        [130.0, 120.0, -225.0],
    ];
    let d = Diagonal::through(&pts).unwrap();
    assert!((d.position_mm(pts[1]) - (60.0f64.powi(2) + 30.0f64.powi(2)).sqrt()).abs() < 1e-9);
    assert!((d.length_mm - 2.0 * (4500.0f64).sqrt()).abs() < 1e-9);
    assert!(Diagonal::through(&[[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.1, 0.0]]).is_none());
    assert!(Diagonal::through(&[[1.0; 3]]).is_none());
    assert!(Diagonal::through(&[]).is_none());
    let plan = vmc_machine::program::plan_source(
        include_str!("../../trajectories/diag_ppp.ngc"),
        "diag_ppp.ngc",
        &MachineSpec::reference(),
        [0.0; 3],
    )
    .unwrap();
    let d = Diagonal::of_plan(&plan).unwrap();
    assert!(
        (d.length_mm - (520.0f64.powi(2) + 360.0f64.powi(2) + 400.0f64.powi(2)).sqrt()).abs()
            < 1e-6
    );
}

#[test]
fn bad_settings_are_refused() {
    for k in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let s = RecordSettings {
            magnify: k,
            ..Default::default()
        };
        assert!(s.validate().is_err(), "magnify {k}");
    }
    let s = RecordSettings {
        motion_sample_s: 0.0,
        ..Default::default()
    };
    assert!(s.validate().is_err());
}

#[test]
fn a_recording_is_written_atomically_and_an_unfinished_one_leaves_nothing() {
    let d = temp_dir("write");
    let spec = MachineSpec::reference();
    let plan = vmc_machine::program::plan_source(
        include_str!("../../trajectories/diag_xy.ngc"),
        "diag_xy.ngc",
        &spec,
        spec.axes.home_mm,
    )
    .unwrap();
    let path = d.join("xy.rrd");
    let file = RrdFile::create(&path, false, "test xy", layout::run_blueprint(2000.0)).unwrap();
    // While writing, only the temporary file exists.
    assert!(!path.exists());
    let mut rec = Recorder::new(
        &file,
        &spec,
        RecordSettings::default(),
        Diagonal::of_plan(&plan),
    )
    .unwrap();
    let mut twin = Twin::new(&spec, 1).unwrap();
    rec.on_run_start(&RunStart {
        label: "diag_xy".into(),
        time_s: 0.0,
        duration_s: plan.duration_s(),
        measured: true,
    });
    sim::execute(&mut twin, &plan, &SimConfig::default(), None, &mut rec).unwrap();
    assert_eq!(rec.series.points.len(), 10);
    // Poses: one per 50 ms of motion, unchanged poses (dwells) skipped.
    assert!(
        rec.series.motion_t_s.len() > 100,
        "{}",
        rec.series.motion_t_s.len()
    );
    assert!(rec.series.motion_t_s.windows(2).all(|w| w[1] > w[0]));
    assert_eq!(rec.path_before.as_slice().len(), 10);
    assert!(rec.path_after.is_empty());
    rec.finish(Some("# report")).unwrap();
    let size = file.finish().unwrap();
    assert!(size > 1000, "{size} bytes");
    assert_eq!(std::fs::metadata(&path).unwrap().len(), size);
    // Refuses to overwrite without force.
    assert!(matches!(
        RrdFile::create(&path, false, "again", layout::run_blueprint(2000.0)),
        Err(RecordError::Exists(_))
    ));
    // Dropped unfinished: no file, no temporary.
    let other = d.join("other.rrd");
    drop(RrdFile::create(&other, false, "dropped", layout::run_blueprint(2000.0)).unwrap());
    assert!(!other.exists());
    let names: Vec<String> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    assert_eq!(names, vec!["xy.rrd".to_string()]);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn magnified_paths_put_the_error_times_k_on_the_commanded_point() {
    let d = temp_dir("magnify");
    let spec = MachineSpec::reference();
    let file = RrdFile::create(&d.join("m.rrd"), false, "m", layout::run_blueprint(500.0)).unwrap();
    let settings = RecordSettings {
        magnify: 500.0,
        ..Default::default()
    };
    let mut rec = Recorder::new(&file, &spec, settings, None).unwrap();
    let p = PointRecord {
        index: 0,
        time_s: 1.0,
        line: 1,
        commanded_mm: [100.0, 200.0, -300.0],
        error_before_um: [10.0, -20.0, 4.0],
        thermal_part_um: None,
        compensated_command_mm: Some([100.0, 200.0, -300.0]),
        error_after_um: Some([1.0, 0.0, -2.0]),
        at_dwell: true,
    };
    let readings = Twin::new(&spec, 1).unwrap().sensor_readings();
    rec.on_point(&p, &readings);
    assert_eq!(rec.path_before.as_slice()[0], [105.0, 190.0, -298.0]);
    assert_eq!(rec.path_after.as_slice()[0], [100.5, 200.0, -301.0]);
    assert_eq!(rec.arrows_before.as_slice()[0], [5.0, -10.0, 2.0]);
    assert!(rec.series.points[0].diagonal_mm.is_none());
    rec.finish(None).unwrap();
    file.finish().unwrap();
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn run_markdown_states_the_magnification() {
    let md = run_markdown("table\n", 2000.0, true);
    assert!(md.contains("×2000"));
    assert!(md.contains("40 mm"));
    assert!(md.contains("```text\ntable\n```"));
}

#[test]
fn a_diagonal_checked_point_by_point_agrees_with_the_line_through_the_points() {
    let on = [
        [10.0, 60.0, -225.0],
        [70.0, 90.0, -225.0],
        [130.0, 120.0, -225.0],
    ];
    let streamed = Diagonal::between(on[0], on[2]).unwrap();
    assert!(on.iter().all(|p| streamed.holds(*p)));
    assert_eq!(Some(streamed), Diagonal::through(&on));
    // 0.02 mm off the line: refused both ways.
    let off = [on[0], [70.0, 90.02, -225.0], on[2]];
    assert!(!streamed.holds(off[1]));
    assert!(Diagonal::through(&off).is_none());
    assert!(Diagonal::between(on[0], on[0]).is_none());
}
