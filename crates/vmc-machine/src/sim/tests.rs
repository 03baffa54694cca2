//! Tests of the simulation loop.
use super::*;
use crate::machine::MachineSpec;

/// The XY diagonal planned from home on `spec`.
fn diag_xy_plan(spec: &MachineSpec) -> Plan {
    crate::program::plan_source(
        include_str!("../../../../trajectories/diag_xy.ngc"),
        "diag_xy.ngc",
        spec,
        spec.axes.home_mm,
    )
    .unwrap()
}

/// Wants poses every 0.5 s and keeps them.
#[derive(Default)]
struct Poses {
    samples: Vec<(f64, [f64; 3])>,
    node_steps: usize,
    points: usize,
}

impl Observer for Poses {
    fn motion_sample_interval_s(&self) -> Option<f64> {
        Some(0.5)
    }
    fn on_motion_sample(&mut self, time_s: f64, axis_mm: [f64; 3]) {
        self.samples.push((time_s, axis_mm));
    }
    fn on_node_temps(&mut self, _time_s: f64, temps: &[f64]) {
        assert!(!temps.is_empty());
        self.node_steps += 1;
    }
    fn on_point(&mut self, _p: &PointRecord, _r: &SensorReadings) {
        self.points += 1;
    }
}

#[test]
fn motion_samples_follow_the_plan_at_the_requested_interval() {
    let spec = MachineSpec::reference();
    let plan = diag_xy_plan(&spec);
    let mut twin = Twin::new(&spec, 1).unwrap();
    // Start later than 0 so the twin-time offset is exercised.
    twin.advance(10.0, &activity_over(&plan, 0.0, 0.0)).unwrap();
    let mut poses = Poses::default();
    let mut other = CountPoints::default();
    let mut tee = Tee(&mut poses, &mut other);
    assert_eq!(tee.motion_sample_interval_s(), Some(0.5));
    execute(&mut twin, &plan, &SimConfig::default(), None, &mut tee).unwrap();
    assert_eq!(other.points, 10);
    assert_eq!(poses.points, 10);
    let n = (plan.duration_s() / 0.5).floor() as usize + 1;
    assert_eq!(poses.samples.len(), n);
    for (k, (t, q)) in poses.samples.iter().enumerate() {
        let plan_t = k as f64 * 0.5;
        assert!((t - (10.0 + plan_t)).abs() < 1e-9);
        assert_eq!(*q, plan.position_at(plan_t));
    }
    // One node-temperature report per whole thermal step.
    assert_eq!(poses.node_steps, plan.duration_s().floor() as usize);
}

/// Integrates the commanded spindle speed it is told, and counts the readings.
#[derive(Default)]
struct SpeedLog {
    last_t_s: Option<f64>,
    revolutions_min: f64,
    readings: usize,
    last_feed_t_s: Option<f64>,
    distance_mm: [f64; 3],
}

impl Controller for SpeedLog {
    fn axis_command_mm(&mut self, p_mm: [f64; 3]) -> [f64; 3] {
        p_mm
    }
    fn on_readings(&mut self, _time_s: f64, _values_degc: &[f64]) {
        self.readings += 1;
    }
    fn on_spindle_speed(&mut self, time_s: f64, rpm: f64) {
        if let Some(t0) = self.last_t_s {
            self.revolutions_min += rpm * (time_s - t0);
        }
        self.last_t_s = Some(time_s);
    }
    fn on_axis_feeds(&mut self, time_s: f64, feeds_mm_per_min: [f64; 3]) {
        if let Some(t0) = self.last_feed_t_s {
            for (d, f) in self.distance_mm.iter_mut().zip(feeds_mm_per_min) {
                *d += f / 60.0 * (time_s - t0);
            }
        }
        self.last_feed_t_s = Some(time_s);
    }
}

/// What a [`SpeedLog`] controller is told while `plan` runs on a fresh twin of `spec`.
fn logged(spec: &MachineSpec, plan: &crate::motion::Plan) -> SpeedLog {
    let mut twin = Twin::new(spec, 1).unwrap();
    let mut log = SpeedLog::default();
    let mut points = CountPoints::default();
    execute(
        &mut twin,
        plan,
        &SimConfig::default(),
        Some(&mut log),
        &mut points,
    )
    .unwrap();
    log
}

#[test]
fn the_controller_is_told_the_commanded_axis_feeds_at_every_step() {
    let spec = MachineSpec::reference();
    let h = spec.axes.home_mm;
    // Out and back along X (2 × 120 mm), then 80 mm down in Z, at feeds that take many steps;
    // the closing dwell puts the plan's last partial thermal step (which advances the twin but
    // brings no new sample) after the motion.
    let program = format!(
        "G21 G90\nG1 X{:.3} F1200\nG1 X{:.3}\nG1 Z{:.3} F600\nG4 P2\nM2\n",
        h[0] + 120.0,
        h[0],
        h[2] - 80.0
    );
    let plan = crate::program::plan_source(&program, "feeds.ngc", &spec, h).unwrap();
    let log = logged(&spec, &plan);
    // The mean |speed| of each step times its length adds up to the distance commanded.
    let d = log.distance_mm;
    assert!((d[0] - 240.0).abs() < 1e-6, "{d:?}");
    assert!(d[1].abs() < 1e-9, "{d:?}");
    assert!((d[2] - 80.0).abs() < 1e-6, "{d:?}");
}

#[test]
fn the_controller_is_told_the_commanded_spindle_speed_at_every_step() {
    let spec = MachineSpec::reference();
    // 60 s at 5000 rpm, then 30 s stopped: 5000 revolutions.
    let plan = crate::program::plan_source(
        "G21 G90\nS5000 M3\nG4 P60\nM5\nG4 P30\nM2\n",
        "speed.ngc",
        &spec,
        spec.axes.home_mm,
    )
    .unwrap();
    let log = logged(&spec, &plan);
    // rpm × s / 60 = revolutions; whole 1 s steps, the speed sampled mid-step.
    let revolutions = log.revolutions_min / 60.0;
    assert!(
        (revolutions - 5000.0).abs() <= 5000.0 / 60.0,
        "{revolutions}"
    );
    assert!(log.readings >= 90, "{}", log.readings);
}

/// Commands the programmed point shifted by `offset_mm` along X.
struct Shift(f64);

impl Controller for Shift {
    fn on_readings(&mut self, _time_s: f64, _values_degc: &[f64]) {}
    fn on_spindle_speed(&mut self, _time_s: f64, _rpm: f64) {}
    fn on_axis_feeds(&mut self, _time_s: f64, _feeds_mm_per_min: [f64; 3]) {}
    fn axis_command_mm(&mut self, p_mm: [f64; 3]) -> [f64; 3] {
        [p_mm[0] + self.0, p_mm[1], p_mm[2]]
    }
}

#[test]
fn a_correction_above_the_limit_or_not_a_number_stops_the_run_at_its_line() {
    let spec = MachineSpec::reference();
    let plan = diag_xy_plan(&spec);
    let run = |offset_mm: f64| {
        let mut twin = Twin::new(&spec, 1).unwrap();
        let mut c = Shift(offset_mm);
        let mut n = CountPoints::default();
        let r = execute(
            &mut twin,
            &plan,
            &SimConfig::default(),
            Some(&mut c),
            &mut n,
        );
        (r, n.points)
    };
    // 10 µm: an ordinary correction, every point measured.
    let (r, points) = run(0.01);
    assert!(r.is_ok());
    assert_eq!(points, 10);
    // 2 mm and NaN: refused at the first point, nothing measured with it.
    for offset in [2.0, f64::NAN] {
        let (r, points) = run(offset);
        match r {
            Err(SimError::Compensation {
                line,
                correction_mm,
                ..
            }) => {
                assert_eq!(
                    line,
                    plan.segments()
                        .iter()
                        .find(|s| s.kind == SegmentKind::Dwell)
                        .unwrap()
                        .line
                );
                assert!(offset.is_nan() && correction_mm.is_nan() || correction_mm == 2.0);
            }
            other => panic!("{offset}: {other:?}"),
        }
        assert_eq!(points, 0);
    }
}

#[test]
fn observers_that_want_no_poses_get_none() {
    let mut a = NullObserver;
    let mut b = CountPoints::default();
    assert_eq!(Tee(&mut a, &mut b).motion_sample_interval_s(), None);
}
