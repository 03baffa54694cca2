//! Diagnosis (truth side): predicted vs true elementary errors of one axis along its travel on a
//! cold machine, or at held-out evaluation state STATE (index into
//! `calibration::evaluation_states`, 0 = cold). `cargo run --release --example axis_profile -- SEED
//! AXIS [STATE]` (AXIS 0, 1, 2).
//!
//! The truth printed is the twin's error functions, without the approach: the predictor learns
//! the positive approach, which lies half a reversal above them in the axis's own positioning
//! error (0.25–0.3 µm on the reference machine).
use vmc_machine::machine::MachineSpec;
use vmc_machine::twin::Twin;
use vmc_twin::predict::predictor::{self, ErrorPredictor, Settings};
use vmc_twin::studies::calibration::{self, CampaignConfig, ThermalCycle};
use vmc_twin::studies::campaign::follow_to_state;
use vmc_twin::studies::campaign::ForMachine;

fn main() {
    let a: Vec<u64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("number"))
        .collect();
    let (seed, axis) = (a[0], a[1] as usize);
    let spec = MachineSpec::reference();
    let data = calibration::calibrate(
        &spec,
        &ThermalCycle::calibration_plan(&spec),
        &CampaignConfig::new(seed),
    )
    .unwrap();
    let (mut h, _) = predictor::train_hybrid(
        &data,
        &spec.geometry(),
        &Settings {
            seed,
            ..Settings::for_machine(&spec)
        },
    )
    .unwrap();
    let mut twin = Twin::new(&spec, seed).unwrap();
    if let Some(&si) = a.get(2) {
        // Drive to the state, the predictor following the readings as the controller does.
        let state = &calibration::evaluation_states(&spec, seed)[si as usize];
        println!("state {}", state.name);
        h = follow_to_state(&mut twin, state, h).unwrap();
    }
    // The present readings (already observed when the predictor followed the state).
    let r = twin.sensor_readings();
    h.observe_readings(r.time_s, &r.values_degc);
    let (lo, hi) = (spec.axes.travel_min_mm[axis], spec.axes.travel_max_mm[axis]);
    println!("pos_mm   true(dx dy dz µm, rx ry rz µrad) | predicted");
    for k in 0..=24 {
        let mut q =
            [0, 1, 2].map(|i| 0.5 * (spec.axes.travel_min_mm[i] + spec.axes.travel_max_mm[i]));
        q[axis] = lo + (hi - lo) * (0.05 + 0.9 * k as f64 / 24.0);
        let t = twin.elementary_errors(q).axes[axis];
        let p = h.elementary_errors(q).axes[axis];
        let f = |l: [f64; 3], r: [f64; 3]| {
            format!(
                "{:6.2} {:6.2} {:6.2} {:6.2} {:6.2} {:6.2}",
                l[0] * 1e3,
                l[1] * 1e3,
                l[2] * 1e3,
                r[0] * 1e6,
                r[1] * 1e6,
                r[2] * 1e6
            )
        };
        println!(
            "{:7.1}  {} | {}",
            q[axis],
            f(t.lin_mm, t.ang_rad),
            f(p.lin_mm, p.ang_rad)
        );
    }
}
