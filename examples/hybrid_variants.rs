//! Diagnosis: the hybrid predictor alone over seeds 1–3 with training-setting variants.
//! `cargo run --release --example hybrid_variants -- states=dev seeds=21,22,23 bil=0`
//!
//! Keys: `states=dev` (selection-only states), `seeds=`, predictor settings (`taus=`, `hist=`,
//! `staus=`, `shist=`, `bil=0|1`, `ridge=`, `hidden=`, `restarts=`, `gain=`, `members=`,
//! `seedoff=`, and the opt-in commanded spindle speed: `rpmexp=` heat-input exponents, `rpmtaus=`
//! their filters' time constants, s; `feedtaus=` the axis feeds' filters, s; `feedown=1` each
//! axis part sees only its own axis's feed; `val=` validation cycles;
//! `plan=full|noaxes|nosweep|noshops|combined` the calibration plan) and campaign settings
//! (`every=`, `stoplog=`, `stopevery=`, `spevery=`, s).
//! Prints per seed the kept nets, then the headline figures and the eight worst runs.
use vmc_machine::machine::MachineSpec;
use vmc_twin::predict::predictor::{self, ModelKind, Settings};
use vmc_twin::studies::calibration::{self, CampaignConfig, ThermalCycle};
use vmc_twin::studies::campaign::ForMachine;
use vmc_twin::studies::campaign::{self, diagonal_plans};

#[path = "shared/dev_states.rs"]
mod dev_states;
use dev_states::dev_stress_states;

fn main() {
    let spec = MachineSpec::reference();
    // The campaign's settings (ambient history on), unless the arguments change them.
    let mut settings = Settings::for_machine(&spec);
    let mut seed_off = 0u64;
    let mut members = 1u64;
    let mut seeds = vec![1u64, 2, 3];
    // `states=dev`: the selection-only states (placement stream 9001), for choosing settings
    // without looking at the held-out evaluation states.
    let mut dev = false;
    // `plan=`: the calibration plan (`full`, or without a group of cycles: `noaxes`,
    // `nosweep`, `noshops`; `combined`: the seven combined-duty cycles only).
    let mut plan = String::from("full");
    // Campaign settings: `every=` (s between measurement blocks), `stoplog=` / `stopevery=`
    // (spindle log after the stop), `spevery=` (spindle test interval while driving).
    let cfg_of = CampaignConfig::new;
    let mut every = None;
    let mut stoplog = None;
    let mut stopevery = None;
    let mut spevery = None;
    for a in std::env::args().skip(1) {
        let (k, v) = a.split_once('=').expect("key=value");
        let list = || -> Vec<f64> {
            v.split(',')
                .filter(|s| !s.is_empty())
                .map(|s| s.parse().unwrap())
                .collect()
        };
        match k {
            "taus" => settings.history_taus_s = list(),
            "seedoff" => seed_off = v.parse().unwrap(),
            "seeds" => seeds = list().into_iter().map(|x| x as u64).collect(),
            "gain" => settings.residual_net_min_gain = v.parse().unwrap(),
            "ridge" => settings.part_ridge = v.parse().unwrap(),
            "hidden" => {
                settings.hidden_candidates = list().into_iter().map(|x| x as usize).collect()
            }
            "restarts" => settings.restarts = v.parse().unwrap(),
            "bil" => settings.axis_bilinear = v == "1",
            "members" => members = v.parse().unwrap(),
            "staus" => settings.spindle_history_taus_s = list(),
            "shist" => settings.spindle_history_sensors = v.split(',').map(String::from).collect(),
            "states" => dev = v == "dev",
            "every" => every = Some(v.parse().unwrap()),
            "stoplog" => stoplog = Some(v.parse().unwrap()),
            "stopevery" => stopevery = Some(v.parse().unwrap()),
            "spevery" => spevery = Some(v.parse().unwrap()),
            "hist" => settings.history_sensors = v.split(',').map(String::from).collect(),
            "rpmexp" => settings.spindle_speed_exponents = list(),
            "rpmtaus" => settings.spindle_speed_taus_s = list(),
            "feedtaus" => settings.axis_feed_taus_s = list(),
            "feedown" => settings.axis_feed_own_axis = v == "1",
            "rpm" if v == "1" => settings = settings.clone().with_spindle_speed_input(),
            "plan" => plan = v.to_string(),
            "val" => settings.val_cycles = v.split(',').map(String::from).collect(),
            _ => panic!("unknown {k}"),
        }
    }
    let geom = spec.geometry();
    let plans = diagonal_plans(&spec).unwrap();
    let mut runs = Vec::new();
    for &seed in &seeds {
        let cycles: Vec<ThermalCycle> = ThermalCycle::calibration_plan(&spec)
            .into_iter()
            .filter(|c| match plan.as_str() {
                "full" => true,
                "noaxes" => !c.name.ends_with("_axis_alone"),
                "nosweep" => c.name != "cal_spindle_sweep",
                "noshops" => !c.name.ends_with("_shop"),
                "combined" => ThermalCycle::combined_duty_set()
                    .iter()
                    .any(|d| d.name == c.name),
                other => panic!("unknown plan {other}"),
            })
            .collect();
        let data = calibration::calibrate(&spec, &cycles, &{
            let mut c = cfg_of(seed);
            if let Some(v) = every {
                c.measure_every_s = v;
            }
            if let Some(v) = stoplog {
                c.spindle_stop_log_s = v;
            }
            if let Some(v) = stopevery {
                c.spindle_stop_every_s = v;
            }
            if let Some(v) = spevery {
                c.spindle_every_s = v;
            }
            c
        })
        .unwrap();
        let mut hs = Vec::new();
        let mut sum = None;
        for m in 0..members {
            let s = campaign::fit_to_data(
                Settings {
                    seed: seed + seed_off + 100 * m,
                    ..settings.clone()
                },
                &data,
            );
            let (h, su) = predictor::train_hybrid(&data, &geom, &s).unwrap();
            hs.push(h);
            sum = Some(su);
        }
        let sum = sum.unwrap();
        let h = Ensemble(hs);
        let kept: Vec<String> = sum
            .nets
            .iter()
            .map(|n| {
                let v: f64 =
                    n.val_rmse.iter().map(|x| x * x).sum::<f64>() / n.val_rmse.len() as f64;
                format!("{}:{:?}:{:.3}", n.name, n.hidden_units, v.sqrt())
            })
            .collect();
        let states = if dev {
            let mut v = vmc_twin::studies::placement::validation_states(seed);
            v.extend(dev_stress_states());
            v
        } else {
            calibration::evaluation_states(&spec, seed)
        };
        let r = campaign::evaluate_predictor(&spec, seed, ModelKind::Hybrid, &h, &states, &plans)
            .unwrap();
        let mx = r.iter().map(|x| x.max_after_um).fold(0.0, f64::max);
        let qm = (r.iter().map(|x| x.rms_after_um.powi(2)).sum::<f64>() / r.len() as f64).sqrt();
        println!("seed {seed}: nets {kept:?} max {mx:.2} qmean rms {qm:.3}");
        runs.extend(r);
    }
    let h = campaign::headline(&runs, ModelKind::Hybrid).unwrap();
    let (med, worst, max, rmse) = (
        h.median_reduction,
        h.worst_reduction,
        h.max_after_um,
        h.mean_rmse_um,
    );
    let over = runs.iter().filter(|r| r.max_after_um > 2.0).count();
    // The worst runs, with the max of each component (µm).
    let mut worst_runs: Vec<_> = runs.iter().collect();
    worst_runs.sort_by(|a, b| b.max_after_um.total_cmp(&a.max_after_um));
    for r in worst_runs.iter().take(8) {
        println!(
            "  {:<4} {:<26} seed {:>2}  max {:.2} µm  (Ex {:.2} Ey {:.2} Ez {:.2})",
            r.diagonal,
            r.thermal_state,
            r.seed,
            r.max_after_um,
            r.max_after_xyz_um[0],
            r.max_after_xyz_um[1],
            r.max_after_xyz_um[2]
        );
    }
    println!(
        "{:?}: median {:.1} % worst {:.1} % max {:.2} µm rmse {:.2} µm, {over} runs > 2 µm",
        std::env::args().skip(1).collect::<Vec<_>>(),
        med * 100.0,
        worst * 100.0,
        max,
        rmse
    );
}

#[derive(Clone)]
struct Ensemble(Vec<predictor::HybridPredictor>);
impl predictor::ErrorPredictor for Ensemble {
    fn sensor_names(&self) -> &[String] {
        self.0[0].sensor_names()
    }
    fn predict_error_mm(&mut self, q: [f64; 3]) -> [f64; 3] {
        let n = self.0.len() as f64;
        let mut e = [0.0; 3];
        for p in &mut self.0 {
            let v = p.predict_error_mm(q);
            for k in 0..3 {
                e[k] += v[k] / n;
            }
        }
        e
    }
    fn negative_approach_shift_mm(&self) -> [f64; 3] {
        self.0[0].negative_approach_shift_mm()
    }
    fn observe_readings(&mut self, t: f64, x: &[f64]) {
        for p in &mut self.0 {
            p.observe_readings(t, x);
        }
    }
    fn observe_spindle_speed(&mut self, t: f64, rpm: f64) {
        for p in &mut self.0 {
            p.observe_spindle_speed(t, rpm);
        }
    }
    fn observe_axis_feeds(&mut self, t: f64, feeds: [f64; 3]) {
        for p in &mut self.0 {
            p.observe_axis_feeds(t, feeds);
        }
    }
}
