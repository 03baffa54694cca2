//! Diagnosis (truth side; the estimator never sees any of this): does a probing cycle measure
//! the residual the diagonal measurement sees?
//!
//! For each state of development machines: the history with the hybrid following the readings
//! (no probing), then the spindle stopped and the axes parked, as in a probing cycle. At times
//! after the stop it prints, from the twin's truth and the model's prediction at the same
//! instant, the Z residual `E − E_pred` (µm, relative to the cold machine's, as the probe's
//! reference makes it) at the four spheres' tops (the probe's positions, the stylus as tool) and
//! the residual at the diagonal's 11 points (the tool as the diagonal measurement has it): mean
//! and range of Ez and Ex. It also runs one noise-free probing cycle from the stop on a copy of
//! the state and prints its Z drift per sphere with the time of the touches after the stop:
//! beside the truth at the tops at that time, this checks the probe's frame and sign against
//! the diagonal's convention.
//!
//! `cargo run --release --example probing_frame -- seeds=21 states=top`
//! Keys: `seeds=` (development seeds), `states=` (substring of the state names; default all but
//! `cold`).
use vmc_machine::machine::MachineSpec;
use vmc_machine::motion::SegmentKind;
use vmc_machine::sim;
use vmc_machine::touch_probe::ProbeOnTwin;
use vmc_machine::twin::{sub_seed, Twin};
use vmc_twin::predict::controller::Compensator;
use vmc_twin::predict::predictor::{ErrorPredictor, HybridPredictor};
use vmc_twin::studies::calibration::{self, drive_with};
use vmc_twin::studies::campaign::{diagonal_plans, eval_noise_seed};
use vmc_twin::studies::probing::{self, Probing};

#[path = "shared/dev_model.rs"]
mod dev_model;

/// Truth residual of the compensated model at axis position `q_mm`, µm (approach parts left out).
fn residual_um(twin: &Twin, ctrl: &mut Compensator<HybridPredictor>, q_mm: [f64; 3]) -> [f64; 3] {
    let e = twin.tool_error_mm(q_mm, q_mm, [0.0; 3]);
    let pred = ctrl.predictor_mut().predict_error_mm(q_mm);
    [0, 1, 2].map(|a| (e[a] - pred[a]) * 1e3)
}

/// The ball centre at each sphere's top, mm.
fn tops_mm(p: &Probing) -> Vec<[f64; 3]> {
    let rc = p.sphere_radius_mm + p.probe.ball_radius_mm;
    p.sphere_centres_mm
        .iter()
        .map(|c| [c[0], c[1], c[2] + rc])
        .collect()
}

/// The run's twin of state `si` driven to its time, with the model following the readings.
fn at_state(
    spec: &MachineSpec,
    seed: u64,
    si: usize,
    state: &calibration::EvalState,
    h: &HybridPredictor,
) -> (Twin, Compensator<HybridPredictor>) {
    let mut twin = Twin::with_noise_seed(spec, seed, eval_noise_seed(seed, si, 0)).unwrap();
    state.cycle.prepare(&mut twin).unwrap();
    let mut ctrl = Compensator::new(h.clone());
    drive_with(
        &mut twin,
        &state.cycle,
        0.0,
        state.at_s,
        1.0,
        Some(&mut ctrl),
    )
    .unwrap();
    (twin, ctrl)
}

fn main() {
    let spec = MachineSpec::reference();
    let mut seeds = vec![21u64];
    let mut filter = String::new();
    for a in std::env::args().skip(1) {
        let (k, v) = a.split_once('=').expect("key=value");
        match k {
            "seeds" => seeds = v.split(',').map(|s| s.parse().unwrap()).collect(),
            "states" => filter = v.to_string(),
            _ => panic!("unknown {k}"),
        }
    }
    let plans = diagonal_plans(&spec).unwrap();
    let diag: Vec<[f64; 3]> = plans[0]
        .1
        .segments()
        .iter()
        .filter(|s| matches!(s.kind, SegmentKind::Dwell))
        .map(|s| s.end_mm)
        .collect();
    let mut p = Probing::every(&spec, 60.0);
    p.probe.repeatability_2sigma_um = 0.0;
    p.probe.servo_period_s = 1e-7;
    let tops = tops_mm(&p);
    let times_s = [0.0, 30.0, 60.0, 120.0, 180.0, 240.0, 300.0, 360.0];
    println!("cycle {:.0} s: {:?}", p.cycle_s(), p.sequence());
    for &seed in &seeds {
        let h = dev_model::model(&spec, seed);
        let fix = probing::qualify(&spec, seed, &p, &h).unwrap();
        // The cold residual at the tops, as the qualification sees it.
        let twin = Twin::with_noise_seed(&spec, seed, sub_seed(seed, 7000)).unwrap();
        let mut ctrl = Compensator::new(h.clone());
        sim::hand_over(&twin, Some(&mut ctrl));
        let cold: Vec<[f64; 3]> = tops
            .iter()
            .map(|&q| residual_um(&twin, &mut ctrl, q))
            .collect();
        println!(
            "seed {seed}: cold Ez residual at the tops {:?} µm",
            cold.iter()
                .map(|r| (r[2] * 100.0).round() / 100.0)
                .collect::<Vec<_>>()
        );
        for (si, state) in calibration::evaluation_states(&spec, seed)
            .iter()
            .enumerate()
        {
            if state.at_s == 0.0 || !state.name.contains(&filter) {
                continue;
            }
            let (mut twin, mut ctrl) = at_state(&spec, seed, si, state, &h);
            println!("  {}:", state.name);
            let mut now_s = 0.0;
            for &t in &times_s {
                probing::park(&mut twin, tops[0], t - now_s, &mut ctrl).unwrap();
                now_s = t;
                let at_tops: Vec<f64> = tops
                    .iter()
                    .zip(&cold)
                    .map(|(&q, c)| residual_um(&twin, &mut ctrl, q)[2] - c[2])
                    .collect();
                let on_diag: Vec<[f64; 3]> = diag
                    .iter()
                    .map(|&q| residual_um(&twin, &mut ctrl, q))
                    .collect();
                let ez: Vec<f64> = on_diag.iter().map(|r| r[2]).collect();
                let ex: Vec<f64> = on_diag.iter().map(|r| r[0]).collect();
                let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
                let lo = |v: &[f64]| v.iter().cloned().fold(f64::INFINITY, f64::min);
                let hi = |v: &[f64]| v.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
                print!(
                    "    t+{t:>4.0} s: Ez at tops {:>5.2?}  diagonal NPP Ez mean {:+.2} [{:+.2}, {:+.2}] Ex mean {:+.2} [{:+.2}, {:+.2}]",
                    at_tops.iter().map(|v| (v * 100.0).round() / 100.0).collect::<Vec<_>>(),
                    mean(&ez), lo(&ez), hi(&ez), mean(&ex), lo(&ex), hi(&ex)
                );
                if t == 0.0 {
                    // A whole cycle from here on a copy of the state: its Z drift per sphere
                    // (taken over its last minute) against the truth at the tops then.
                    let mut on = ProbeOnTwin::new(p.probe, 1).unwrap();
                    let (mut twin2, mut ctrl2) = at_state(&spec, seed, si, state, &h);
                    let readings = probing::run_cycle(
                        &mut twin2,
                        &p,
                        &mut ctrl2,
                        Compensator::predictor_mut,
                        &mut on,
                    )
                    .unwrap();
                    let m = probing::drift_measurements(&readings, &fix);
                    let z: Vec<String> = m
                        .iter()
                        .filter(|m| m.1 == 2)
                        .map(|m| format!("{:.2}@{:.0}s", m.3 * 1e3, m.0 - state.at_s))
                        .collect();
                    print!("\n      cycle: probe Ez drift {z:?}");
                }
                println!();
            }
        }
    }
}
