//! Tests of the replay: against a run of the same motion on the same machine.
use super::*;
use crate::machine::MachineSpec;
use crate::motion::Plan;
use crate::sim::{execute, CollectPoints, SampleMode};

/// A program without dwells, spindle on, moving each axis both ways.
const PROGRAM: &str = "G21 G90 G54\nS6000 M3\nG0 X10 Y60 Z-225\nG1 X300 Y200 F4000\nG1 X120 Y80 Z-180 F3000\nG1 X400 Y250 Z-230 F5000\nM30\n";

fn plan(spec: &MachineSpec) -> Plan {
    crate::program::plan_source(PROGRAM, "replay.ngc", spec, spec.axes.home_mm).unwrap()
}

/// The twin warmed by 20 min of spindle at 8000 rpm, so the thermal part is not zero.
fn warm_twin(spec: &MachineSpec, seed: u64) -> Twin {
    let mut twin = Twin::new(spec, seed).unwrap();
    let activity = Activity {
        spindle_rpm: 8000.0,
        ..Activity::default()
    };
    for _ in 0..1200 {
        twin.advance(1.0, &activity).unwrap();
    }
    twin
}

/// The run's points on `spec` at every 10 ms cycle.
fn run_points(spec: &MachineSpec, plan: &Plan) -> Vec<crate::sim::PointRecord> {
    let mut twin = warm_twin(spec, 3);
    let cfg = SimConfig::new(1.0, 0.01)
        .unwrap()
        .sampling(SampleMode::EveryCycle);
    let mut points = CollectPoints::default();
    execute(&mut twin, plan, &cfg, None, &mut points).unwrap();
    points.points
}

/// Replays `samples` on a twin warmed like the run's.
fn replay(spec: &MachineSpec, samples: &[LoggedSample]) -> Vec<crate::sim::PointRecord> {
    let mut twin = warm_twin(spec, 3);
    let cfg = SimConfig::new(1.0, 0.01).unwrap();
    let mut points = CollectPoints::default();
    let mut r = Replay::start(&twin, &cfg, 1, None, &points);
    for s in samples {
        r.push(&mut twin, s, None, &mut points).unwrap();
    }
    r.finish(&mut twin).unwrap();
    points.points
}

/// The run's points as a log (positions and spindle speed at the same times).
fn as_log(plan: &Plan, points: &[crate::sim::PointRecord]) -> Vec<LoggedSample> {
    points
        .iter()
        .enumerate()
        .map(|(i, p)| LoggedSample {
            time_s: p.time_s - points[0].time_s + 5.0,
            line: i + 1,
            commanded_mm: p.commanded_mm,
            correction_mm: None,
            spindle_rpm: plan.spindle_rpm_at(p.time_s - points[0].time_s),
        })
        .collect()
}

#[test]
fn a_replay_of_a_runs_own_samples_finds_the_runs_errors() {
    let spec = MachineSpec::reference();
    let plan = plan(&spec);
    let run = run_points(&spec, &plan);
    assert!(run.len() > 1000, "{} points", run.len());
    let replayed = replay(&spec, &as_log(&plan, &run));
    assert_eq!(replayed.len(), run.len());
    let mut worst_um = 0.0f64;
    for (a, b) in run.iter().zip(&replayed) {
        assert_eq!(a.commanded_mm, b.commanded_mm);
        for k in 0..3 {
            worst_um = worst_um.max((a.error_before_um[k] - b.error_before_um[k]).abs());
        }
    }
    // The heat load differs only by the sampled motion (straight lines between 10 ms samples
    // against the planner's ramps): nanometres, against errors of tens of µm.
    assert!(worst_um < 0.01, "worst difference {worst_um} µm");
    let largest = run
        .iter()
        .map(|p| p.error_before_um[0].abs())
        .fold(0.0, f64::max);
    assert!(largest > 1.0, "{largest} µm");
}

#[test]
fn zero_logged_corrections_give_the_uncompensated_error_as_compensated() {
    let spec = MachineSpec::reference();
    let plan = plan(&spec);
    let mut log = as_log(&plan, &run_points(&spec, &plan));
    for s in &mut log {
        s.correction_mm = Some([0.0; 3]);
    }
    for p in replay(&spec, &log) {
        assert_eq!(p.error_after_um, Some(p.error_before_um));
        assert_eq!(p.compensated_command_mm, Some(p.commanded_mm));
    }
}

#[test]
fn a_logged_correction_moves_the_axes_by_it() {
    let spec = MachineSpec::reference();
    let plan = plan(&spec);
    let mut log = as_log(&plan, &run_points(&spec, &plan));
    for s in &mut log {
        s.correction_mm = Some([0.01, 0.0, -0.02]);
    }
    for p in replay(&spec, &log).iter().take(50) {
        let q = p.compensated_command_mm.unwrap();
        let want = [
            p.commanded_mm[0] + 0.01,
            p.commanded_mm[1],
            p.commanded_mm[2] - 0.02,
        ];
        assert_eq!(q, want);
        // Moving X by +10 µm moves the tool by about +10 µm: the error grows by about that.
        let dx = p.error_after_um.unwrap()[0] - p.error_before_um[0];
        assert!((dx - 10.0).abs() < 0.5, "{dx} µm");
    }
}

#[test]
fn a_sample_not_later_than_the_previous_is_refused_with_its_line() {
    let spec = MachineSpec::reference();
    let mut twin = warm_twin(&spec, 3);
    let cfg = SimConfig::default();
    let mut null = crate::sim::NullObserver;
    let mut r = Replay::start(&twin, &cfg, 1, None, &null);
    let s = |t: f64, line| LoggedSample {
        time_s: t,
        line,
        commanded_mm: [10.0, 20.0, -100.0],
        correction_mm: None,
        spindle_rpm: 0.0,
    };
    r.push(&mut twin, &s(1.0, 1), None, &mut null).unwrap();
    let e = r.push(&mut twin, &s(1.0, 2), None, &mut null).unwrap_err();
    assert!(
        matches!(e, SimError::TimeNotIncreasing { line: 2, .. }),
        "{e}"
    );
}

#[test]
fn every_nth_sample_is_measured_and_the_thermal_state_advances_with_log_time() {
    let spec = MachineSpec::reference();
    let mut twin = warm_twin(&spec, 3);
    let t0 = twin.time_s();
    let cfg = SimConfig::default();
    let mut points = CollectPoints::default();
    let mut r = Replay::start(&twin, &cfg, 10, None, &points);
    for i in 0..=1000 {
        let s = LoggedSample {
            time_s: 100.0 + i as f64 * 0.01,
            line: i + 1,
            commanded_mm: [10.0 + i as f64 * 0.1, 60.0, -225.0],
            correction_mm: None,
            spindle_rpm: 3000.0,
        };
        r.push(&mut twin, &s, None, &mut points).unwrap();
    }
    assert_eq!(r.points(), 101);
    assert_eq!(r.samples(), 1001);
    r.finish(&mut twin).unwrap();
    assert!((twin.time_s() - t0 - 10.0).abs() < 1e-9);
    assert_eq!(points.points[1].line, 11);
    assert!((points.points[100].time_s - t0 - 10.0).abs() < 1e-9);
}
