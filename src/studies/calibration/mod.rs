//! Thermal cycles and the virtual calibration campaign; the held-out evaluation states.
//!
//! A [`ThermalCycle`] is a sequence of duty phases (spindle speed, axis speeds) under an ambient
//! profile. During a phase the axes shuttle over 10–90 % of their travel at the phase's speeds
//! (so the ballscrew nuts heat the screws where they run). Calibration cycles are *typical*
//! (constant speed heating then cooling); evaluation cycles are *atypical* (random speed steps,
//! ambient swing, restart after a stop) and never enter the calibration data.
//!
//! The calibration campaign runs each calibration cycle on a fresh, cold twin of the machine
//! (same machine seed, fresh noise) and every `measure_every_s` takes a measurement block: the
//! spindle test at the stop and for `spindle_stop_log_s` after it (the drift's fast transient
//! after a stop is what a diagonal test run right after a duty sees), laser sweeps of X, Y, Z,
//! squareness and a volumetric grid — all with the spindle stopped, taking machine time,
//! temperatures logged with each reading. Between blocks the spindle test logs with the spindle
//! running.

use rayon::prelude::*;

use crate::predict::dataset::{Dataset, Record};
use vmc_machine::instruments::Instruments;
use vmc_machine::machine::MachineSpec;
use vmc_machine::sim::{self, Observer, RunStart};
use vmc_machine::thermal::Activity;
use vmc_machine::twin::{sub_seed, Twin, TwinError};

mod cycles;

pub use cycles::{Phase, ThermalCycle};

/// Drives a twin through a cycle's duty (cycle time `from_s` → `to_s`), the axes shuttling
/// over 10–90 % of their travel at the phase speeds. `t0_s` is the twin time of the cycle start.
pub fn drive(
    twin: &mut Twin,
    cycle: &ThermalCycle,
    t0_s: f64,
    to_s: f64,
    step_s: f64,
) -> Result<(), TwinError> {
    drive_with(twin, cycle, t0_s, to_s, step_s, None)
}

/// [`drive`], passing the readings after every step to `controller` (if any) through
/// [`sim::step`], as a controller logging its sensors sees them.
pub fn drive_with(
    twin: &mut Twin,
    cycle: &ThermalCycle,
    t0_s: f64,
    to_s: f64,
    step_s: f64,
    mut controller: Option<&mut dyn vmc_machine::sim::Controller>,
) -> Result<(), TwinError> {
    if controller.is_some() {
        sim::hand_over(twin, sim::reborrow(&mut controller));
    }
    let min = twin.spec().axes.travel_min_mm;
    let max = twin.spec().axes.travel_max_mm;
    while twin.time_s() - t0_s < to_s - 1e-9 {
        let t = twin.time_s() - t0_s;
        let dt = step_s.min(to_s - t);
        let p = cycle.phase_at(t + 0.5 * dt);
        let mut pos = [0.0; 3];
        for a in 0..3 {
            let lo = min[a] + 0.1 * (max[a] - min[a]);
            let span = 0.8 * (max[a] - min[a]);
            let v_mm_per_s = p.axis_speed_mm_per_min[a] / 60.0;
            // Triangle wave: distance travelled folded into [0, span].
            let d = (v_mm_per_s * (t + 0.5 * dt)) % (2.0 * span);
            pos[a] = lo + if d <= span { d } else { 2.0 * span - d };
            if v_mm_per_s == 0.0 {
                pos[a] = 0.5 * (min[a] + max[a]);
            }
        }
        let activity = Activity {
            spindle_rpm: p.spindle_rpm,
            axis_pos_mm: pos,
            axis_speed_mm_per_min: p.axis_speed_mm_per_min,
            coolant: false,
        };
        sim::step(twin, dt, &activity, sim::reborrow(&mut controller))?;
    }
    Ok(())
}

/// Settings of the calibration campaign.
#[derive(Debug, Clone)]
pub struct CampaignConfig {
    /// Machine realisation (error field seed).
    pub machine_seed: u64,
    /// Time between measurement blocks, s (default 1800 = 30 min).
    pub measure_every_s: f64,
    /// Thermal step while driving the duty, s (default 1).
    pub step_s: f64,
    /// Volumetric grid: points per axis (default 3 → 27 points).
    pub grid_points_per_axis: usize,
    /// Interval of the continuously logging 5-probe spindle test, s (default 300).
    pub spindle_every_s: f64,
    /// How long the spindle test keeps logging after the spindle stops at the start of each
    /// measurement block, before the laser sweeps, s (default 180).
    pub spindle_stop_log_s: f64,
    /// Interval of the spindle readings during that stop, s (default 30).
    pub spindle_stop_every_s: f64,
}

impl CampaignConfig {
    /// Defaults for a machine seed.
    pub fn new(machine_seed: u64) -> Self {
        CampaignConfig {
            machine_seed,
            measure_every_s: 1800.0,
            step_s: 1.0,
            grid_points_per_axis: 3,
            spindle_every_s: 300.0,
            spindle_stop_log_s: 180.0,
            spindle_stop_every_s: 30.0,
        }
    }
}

/// Middle of the travel, mm.
fn mid(spec: &MachineSpec) -> [f64; 3] {
    [0, 1, 2].map(|a| 0.5 * (spec.axes.travel_min_mm[a] + spec.axes.travel_max_mm[a]))
}

/// Grid of `n` points per axis over 10–90 % of the travel.
pub fn volume_grid(spec: &MachineSpec, n: usize) -> Vec<[f64; 3]> {
    let n = n.max(2);
    let at = |a: usize, k: usize| {
        let lo = spec.axes.travel_min_mm[a];
        let span = spec.axes.travel_max_mm[a] - lo;
        lo + span * (0.1 + 0.8 * k as f64 / (n - 1) as f64)
    };
    let mut v = Vec::with_capacity(n * n * n);
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                v.push([at(0, i), at(1, j), at(2, k)]);
            }
        }
    }
    v
}

/// Runs one measurement block at the twin's current state.
fn measurement_block(
    twin: &mut Twin,
    inst: &mut Instruments,
    grid: &[[f64; 3]],
    cycle: &str,
    t0_s: f64,
    out: &mut Vec<Record>,
) -> Result<(), TwinError> {
    let park = mid(twin.spec());
    for axis in 0..3 {
        inst.laser_sweep(twin, axis, park, cycle, t0_s, out)?;
    }
    inst.squareness(twin, park, cycle, t0_s, out)?;
    inst.volumetric(twin, grid, cycle, t0_s, out)
}

/// Runs the calibration campaign over `cycles` and returns the dataset. The cycles are
/// independent (each on a fresh twin of the same realisation with its own noise stream) and run
/// side by side; their records are concatenated in cycle order, so the dataset does not depend
/// on how many threads ran them.
pub fn calibrate(
    spec: &MachineSpec,
    cycles: &[ThermalCycle],
    cfg: &CampaignConfig,
) -> Result<Dataset, TwinError> {
    let grid = volume_grid(spec, cfg.grid_points_per_axis);
    let per_cycle: Vec<Result<CycleRecords, TwinError>> = cycles
        .par_iter()
        .enumerate()
        .map(|(k, cycle)| calibrate_cycle(spec, cfg, &grid, k, cycle))
        .collect();
    let mut records = Vec::new();
    let mut sensor_names = Vec::new();
    for r in per_cycle {
        let (names, recs) = r?;
        sensor_names = names;
        records.extend(recs);
    }
    Ok(Dataset {
        origin: Some(spec.identity(Some(cfg.machine_seed))),
        sensor_names,
        records,
    })
}

/// The sensor names and the records of one calibration cycle.
type CycleRecords = (Vec<String>, Vec<Record>);

/// Cycle `k` of the calibration campaign: the sensor names and the records.
fn calibrate_cycle(
    spec: &MachineSpec,
    cfg: &CampaignConfig,
    grid: &[[f64; 3]],
    k: usize,
    cycle: &ThermalCycle,
) -> Result<CycleRecords, TwinError> {
    let mut records = Vec::new();
    let noise = sub_seed(cfg.machine_seed, 1000 + k as u64);
    let mut twin = Twin::with_noise_seed(spec, cfg.machine_seed, noise)?;
    cycle.prepare(&mut twin)?;
    let mut inst = Instruments::new(&twin, sub_seed(noise, 5));
    let sensor_names = twin.sensor_readings().names.to_vec();
    let t0 = twin.time_s();
    let end = cycle.duration_s();
    let mut next_block = 0.0;
    // The commanded spindle speed and axis feeds since the previous record (the dataset's
    // `spindle_rpm` and axis-feed columns): the spindle runs and the axes shuttle while the
    // duty is driven; during a block the spindle stands still and the axes' moves between
    // measurement points are short (logged as parked).
    let mut driven = (0.0, [0.0; 3]);
    let log_rpm = |records: &mut Vec<Record>, from: usize, (rpm, feed): (f64, [f64; 3])| {
        for r in &mut records[from..] {
            r.spindle_rpm = Some(rpm);
            r.axis_feed_mm_per_min = Some(feed);
        }
    };
    loop {
        let t = twin.time_s() - t0;
        if t >= next_block - 1e-9 {
            let first = records.len();
            inst.spindle_test(&twin, mid(spec), &cycle.name, t0, &mut records);
            log_rpm(&mut records, first, driven);
            let first = records.len();
            inst.spindle_stop_log(
                &mut twin,
                mid(spec),
                cfg.spindle_stop_log_s,
                cfg.spindle_stop_every_s,
                &cycle.name,
                t0,
                &mut records,
            )?;
            measurement_block(&mut twin, &mut inst, grid, &cycle.name, t0, &mut records)?;
            log_rpm(&mut records, first, (0.0, [0.0; 3]));
            next_block += cfg.measure_every_s;
            continue;
        }
        if t >= end - 1e-9 {
            break;
        }
        // Drive the duty to the next block, logging the spindle probes on the way.
        let target = next_block.min(end);
        while twin.time_s() - t0 < target - 1e-9 {
            let t = twin.time_s() - t0;
            let next_probe = ((t / cfg.spindle_every_s).floor() + 1.0) * cfg.spindle_every_s;
            drive(&mut twin, cycle, t0, next_probe.min(target), cfg.step_s)?;
            let now = twin.time_s() - t0;
            driven = (cycle.mean_rpm(t, now), cycle.mean_axis_feed(t, now));
            let first = records.len();
            inst.spindle_test(&twin, mid(spec), &cycle.name, t0, &mut records);
            log_rpm(&mut records, first, driven);
        }
    }
    Ok((sensor_names, records))
}

/// A thermal state at which diagonals are evaluated: a cycle run up to a time.
#[derive(Debug, Clone, PartialEq)]
pub struct EvalState {
    /// Report name, e.g. `cold` or `eval_restart@4h`.
    pub name: String,
    /// The cycle driving the machine.
    pub cycle: ThermalCycle,
    /// Cycle time at which the diagonal starts, s.
    pub at_s: f64,
}

/// The held-out evaluation states of machine `spec`: a cold machine, each atypical cycle after
/// 2 h and 4 h, and the stress cycles ([`ThermalCycle::stress_set`]): the Z strokes at their
/// end (3 h), the top speed after 3 h and 6 h, the warm shop after 1 h and 4 h.
pub fn evaluation_states(spec: &MachineSpec, seed: u64) -> Vec<EvalState> {
    let cycles = ThermalCycle::evaluation_set(seed);
    let mut v = vec![EvalState {
        name: "cold".into(),
        cycle: cycles[0].clone(),
        at_s: 0.0,
    }];
    let stress = ThermalCycle::stress_set(spec);
    let hours = [
        [2.0, 4.0].as_slice(),
        &[2.0, 4.0],
        &[2.0, 4.0],
        &[3.0],
        &[3.0, 6.0],
        &[1.0, 4.0],
    ];
    for (c, hours) in cycles.into_iter().chain(stress).zip(hours) {
        for &h in hours {
            v.push(EvalState {
                name: format!("{}@{h}h", c.name),
                cycle: c.clone(),
                at_s: h * 3600.0,
            });
        }
    }
    v
}

/// Runs `plan` at `state` on the machine `machine_seed` with evaluation noise `noise_seed`,
/// optionally compensated, and returns the measurement points.
pub fn run_at_state(
    spec: &MachineSpec,
    machine_seed: u64,
    noise_seed: u64,
    state: &EvalState,
    plan: &vmc_machine::motion::Plan,
    compensator: Option<&mut dyn vmc_machine::sim::Controller>,
) -> Result<Vec<vmc_machine::sim::PointRecord>, vmc_machine::sim::SimError> {
    let mut log = vmc_machine::sim::CollectPoints::default();
    run_at_state_observed(
        spec,
        machine_seed,
        noise_seed,
        state,
        plan,
        compensator,
        &mut log,
        None,
    )?;
    Ok(log.points)
}

/// [`run_at_state`] with an observer. The thermal history that leads to the state is reported
/// every `history_every_s` (if given) through [`Observer::on_thermal_step`] and
/// [`Observer::on_node_temps`]; the diagonal as usual. Both phases are announced with
/// [`Observer::on_run_start`]. The twin's steps are the same with or without reporting, so the
/// points are identical to [`run_at_state`]'s.
#[allow(clippy::too_many_arguments)]
pub fn run_at_state_observed(
    spec: &MachineSpec,
    machine_seed: u64,
    noise_seed: u64,
    state: &EvalState,
    plan: &vmc_machine::motion::Plan,
    mut compensator: Option<&mut dyn vmc_machine::sim::Controller>,
    observer: &mut dyn Observer,
    history_every_s: Option<f64>,
) -> Result<(), vmc_machine::sim::SimError> {
    let mut twin = Twin::with_noise_seed(spec, machine_seed, noise_seed)?;
    state.cycle.prepare(&mut twin)?;
    // The controller follows the readings through the thermal history, as it would on the
    // machine (it compensates nothing then).
    match history_every_s.filter(|dt| *dt > 0.0 && dt.is_finite()) {
        None => drive_with(
            &mut twin,
            &state.cycle,
            0.0,
            state.at_s,
            1.0,
            sim::reborrow(&mut compensator),
        )?,
        Some(every_s) => {
            observer.on_run_start(&RunStart {
                label: format!(
                    "thermal history: {} up to {:.1} h",
                    state.cycle.name,
                    state.at_s / 3600.0
                ),
                time_s: twin.time_s(),
                duration_s: state.at_s,
                measured: false,
            });
            let mut to_s = 0.0;
            while to_s < state.at_s - 1e-9 {
                to_s = (to_s + every_s).min(state.at_s);
                drive_with(
                    &mut twin,
                    &state.cycle,
                    0.0,
                    to_s,
                    1.0,
                    sim::reborrow(&mut compensator),
                )?;
                observer.on_thermal_step(twin.time_s(), &twin.sensor_readings());
                observer.on_node_temps(twin.time_s(), twin.node_temps_degc());
            }
        }
    }
    observer.on_run_start(&RunStart {
        label: format!("diagonal at {}", state.name),
        time_s: twin.time_s(),
        duration_s: plan.duration_s(),
        measured: true,
    });
    vmc_machine::sim::execute(
        &mut twin,
        plan,
        &vmc_machine::sim::SimConfig::default().with_thermal_part(true),
        compensator,
        observer,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::predict::dataset::Instrument;
    use cycles::phase;

    fn short_cycle() -> ThermalCycle {
        ThermalCycle {
            name: "short".into(),
            purpose: String::new(),
            ambient: cycles::AMBIENT_20,
            soak_degc: None,
            phases: vec![
                phase(0.25, 3000.0, [2000.0, 1000.0, 500.0]),
                phase(0.25, 6000.0, [2000.0, 1000.0, 500.0]),
                phase(0.5, 0.0, [0.0; 3]),
            ],
        }
    }

    #[test]
    fn the_mean_speed_integrates_the_phases() {
        let c = short_cycle();
        assert_eq!(c.mean_rpm(0.0, 900.0), 3000.0);
        assert_eq!(c.mean_rpm(600.0, 1200.0), 4500.0);
        assert_eq!(c.mean_rpm(1500.0, 2100.0), 3000.0);
        // Beyond the end the last phase goes on; an empty interval gives the speed there.
        assert_eq!(c.mean_rpm(3000.0, 9000.0), 0.0);
        assert_eq!(c.mean_rpm(100.0, 100.0), 3000.0);
    }

    #[test]
    fn the_calibration_log_carries_the_commanded_speed_since_the_previous_record() {
        let spec = MachineSpec::reference();
        let cfg = CampaignConfig {
            measure_every_s: 1800.0,
            ..CampaignConfig::new(1)
        };
        let ds = calibrate(&spec, &[short_cycle()], &cfg).unwrap();
        assert!(ds.records.iter().all(|r| r.spindle_rpm.is_some()));
        let rpm = |r: &Record| r.spindle_rpm.unwrap_or(f64::NAN);
        // The spindle-test records logged while the duty runs (every 300 s, first block at 0 s,
        // second at 1800 s): 3000 rpm up to 900 s, 6000 rpm up to 1800 s.
        let running: Vec<(f64, f64)> = ds
            .of(Instrument::Spindle)
            .filter(|r| rpm(r) > 0.0)
            .map(|r| (r.time_s, rpm(r)))
            .collect();
        assert!(running.iter().any(|r| r.1 == 3000.0) && running.iter().any(|r| r.1 == 6000.0));
        for &(t, n) in &running {
            let expected = if t <= 900.0 + 1e-6 { 3000.0 } else { 6000.0 };
            assert_eq!(n, expected, "t = {t}");
        }
        // Every record of a block (the stop log, the sweeps, the grid) is stopped, apart from the
        // spindle test at the block's start, which closes the interval the duty ran in.
        let block_start = ds
            .records
            .iter()
            .find(|r| r.instrument == Instrument::Spindle && (r.time_s - 1800.0).abs() < 1e-6)
            .unwrap();
        assert_eq!(rpm(block_start), 6000.0);
        assert!(ds
            .records
            .iter()
            .filter(|r| r.instrument != Instrument::Spindle)
            .all(|r| rpm(r) == 0.0));
        // The duty stops at 1800 s: nothing runs after.
        assert!(ds
            .records
            .iter()
            .filter(|r| r.time_s > 1800.0 + 1e-6)
            .all(|r| rpm(r) == 0.0));
    }
}
