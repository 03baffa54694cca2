//! Diagnosis (truth side): where the hybrid predictor's error comes from on the held-out states.
//!
//! For each seed given on the command line, calibrates and trains the hybrid predictor, then for
//! every held-out evaluation state drives a twin (evaluation noise) to the state and, at a 3×3×3
//! grid of poses over the diagonals' region, compares predicted and true elementary errors. The
//! error of the predicted volumetric error is split by part (X, Y, Z axis nets, spindle,
//! squareness) by substituting each predicted part into the true set (first-order synthesis, so
//! the parts add up). Prints per state the max |contribution| of each part to Ex, Ey, Ez (µm),
//! at the state and over the next 90 s with the spindle stopped, as during a diagonal test,
//! then the max |E| of the whole prediction error and of the error with the spindle part taken
//! as true (`|E|-sp`: what a perfect spindle part would leave, before non-repeatability).
//!
//! `cargo run --release --example residual_breakdown -- 1 2 3` (add `dev` for the selection-only
//! states, `rpm` for the opt-in commanded spindle speed, `--spindle-speed`)

use vmc_machine::machine::MachineSpec;
use vmc_machine::twin::{sub_seed, Twin};
use vmc_twin::predict::predictor::{self, ErrorPredictor, Settings};
use vmc_twin::predict::synthesis::first_order_error_mm;
use vmc_twin::studies::calibration::{self, CampaignConfig, ThermalCycle};
use vmc_twin::studies::campaign::follow_to_state;
use vmc_twin::studies::campaign::ForMachine;

#[path = "shared/dev_states.rs"]
mod dev_states;

fn main() {
    // `dev` among the arguments: the selection-only states (placement stream 9001) instead of
    // the held-out ones.
    let dev = std::env::args().any(|a| a == "dev");
    // `staus=…` and `shist=…`: spindle-only history features (as in `hybrid_variants`).
    let mut base = Settings::for_machine(&MachineSpec::reference());
    for a in std::env::args().skip(1) {
        if let Some(v) = a.strip_prefix("staus=") {
            base.spindle_history_taus_s = v.split(',').map(|x| x.parse().unwrap()).collect();
        } else if let Some(v) = a.strip_prefix("shist=") {
            base.spindle_history_sensors = v.split(',').map(String::from).collect();
        } else if let Some(v) = a.strip_prefix("feedtaus=") {
            base.axis_feed_taus_s = v.split(',').map(|x| x.parse().unwrap()).collect();
        } else if a == "feedown=1" {
            base.axis_feed_own_axis = true;
        } else if a == "rpm" {
            base = base.with_spindle_speed_input();
        }
    }
    let seeds: Vec<u64> = std::env::args()
        .skip(1)
        .filter(|a| a != "dev" && a != "rpm" && !a.contains('='))
        .map(|s| s.parse().expect("seed"))
        .collect();
    let spec = MachineSpec::reference();
    let geom = spec.geometry();
    let grid = calibration::volume_grid(&spec, 3);
    for seed in seeds {
        let data = calibration::calibrate(
            &spec,
            &ThermalCycle::calibration_plan(&spec),
            &CampaignConfig::new(seed),
        )
        .unwrap();
        let (h, _) = predictor::train_hybrid(
            &data,
            &geom,
            &Settings {
                seed,
                ..base.clone()
            },
        )
        .unwrap();
        let rev = h.reversal_um();
        println!(
            "seed {seed}: learned reversal X {:.3} Y {:.3} Z {:.3} µm (negative − positive approach)",
            rev[0], rev[1], rev[2]
        );
        println!("seed {seed}: max |prediction error| contribution, µm (Ex Ey Ez)");
        println!(
            "  {:<24} {:>17} {:>17} {:>17} {:>17} {:>17} | {:>17} | {:>6} {:>6}",
            "state",
            "axis X",
            "axis Y",
            "axis Z",
            "spindle",
            "squareness",
            "total",
            "|E|",
            "|E|-sp"
        );
        let states = if dev {
            let mut v = vmc_twin::studies::placement::validation_states(seed);
            v.extend(dev_states::dev_stress_states());
            v
        } else {
            calibration::evaluation_states(&spec, seed)
        };
        for (si, state) in states.iter().enumerate() {
            let mut twin =
                Twin::with_noise_seed(&spec, seed, sub_seed(seed, 9000 + si as u64)).unwrap();
            // The predictor follows the readings through the thermal history (its history
            // features), as the controller does in the campaign.
            let mut hs = follow_to_state(&mut twin, state, h.clone()).unwrap();
            let mut worst = [[0.0f64; 3]; 6];
            // Max |E| of the prediction error: all parts; all but the spindle.
            let mut norms = [0.0f64; 2];
            // At the state and over the next 90 s with the spindle stopped (a diagonal test).
            for step in 0..4 {
                if step > 0 {
                    let stopped = vmc_machine::thermal::Activity {
                        spindle_rpm: 0.0,
                        axis_pos_mm: grid[13],
                        axis_speed_mm_per_min: [0.0; 3],
                        coolant: false,
                    };
                    for _ in 0..30 {
                        twin.advance(1.0, &stopped).unwrap();
                        let r = twin.sensor_readings();
                        hs.observe_readings(r.time_s, &r.values_degc);
                        hs.observe_spindle_speed(r.time_s, 0.0);
                        hs.observe_axis_feeds(r.time_s, [0.0; 3]);
                    }
                }
                // The predictor holds the readings it last observed: the present ones.
                for &q in &grid {
                    let t = twin.elementary_errors(q);
                    let p = hs.elementary_errors(q);
                    let base = first_order_error_mm(&geom, q, &t);
                    let mut parts = Vec::new();
                    for part in 0..5 {
                        let mut m = t;
                        match part {
                            0..=2 => m.axes[part] = p.axes[part],
                            3 => m.spindle = p.spindle,
                            _ => m.squareness = p.squareness,
                        }
                        parts.push(first_order_error_mm(&geom, q, &m) - base);
                    }
                    parts.push(first_order_error_mm(&geom, q, &p) - base);
                    // Everything predicted but the spindle, which is taken as true: what a
                    // perfect spindle part (e.g. one that knew the spindle speed) would leave.
                    let mut no_spindle = p;
                    no_spindle.spindle = t.spindle;
                    let rest = first_order_error_mm(&geom, q, &no_spindle) - base;
                    for (w, d) in worst.iter_mut().zip(&parts) {
                        for c in 0..3 {
                            w[c] = w[c].max((d[c] * 1e3).abs());
                        }
                    }
                    norms[0] = norms[0].max(parts[5].norm() * 1e3);
                    norms[1] = norms[1].max(rest.norm() * 1e3);
                }
            }
            let f = |w: [f64; 3]| format!("{:5.2} {:5.2} {:5.2}", w[0], w[1], w[2]);
            println!(
                "  {:<24} {:>17} {:>17} {:>17} {:>17} {:>17} | {:>17} | {:6.2} {:6.2}",
                state.name,
                f(worst[0]),
                f(worst[1]),
                f(worst[2]),
                f(worst[3]),
                f(worst[4]),
                f(worst[5]),
                norms[0],
                norms[1]
            );
        }
    }
}
