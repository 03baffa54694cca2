//! Diagnosis: the hybrid predictor with and without on-machine probing, on development seeds.
//! `cargo run --release --example probing_variants -- seeds=21,22,23 every=30 walk=3`
//!
//! Keys: `seeds=` (machine seeds; use development seeds, never the campaign's held-out 1–3 for
//! choosing), `every=` probing interval (min; `0` no probing), `walk=` drift walk (µm/√h),
//! `meas=` measurement σ (µm, default: the probe's), `states=dev` adds the selection-only stress
//! states. Models are trained once per seed and cached under `target/probing-models/`.
//! Prints the headline figures, the worst runs with their max per axis and the mean signed
//! residual per axis of the run (an offset the probe could see) beside its spread (what an
//! offset cannot correct).
use vmc_machine::machine::MachineSpec;
use vmc_twin::predict::predictor::{self, HybridPredictor, ModelKind, Settings};
use vmc_twin::studies::calibration::{self, CampaignConfig, ThermalCycle};
use vmc_twin::studies::campaign::{self, diagonal_plans, eval_noise_seed, ForMachine};
use vmc_twin::studies::probing::{self, Probing};

#[path = "shared/dev_states.rs"]
mod dev_states;

fn model(spec: &MachineSpec, seed: u64) -> HybridPredictor {
    let dir = std::path::Path::new("target/probing-models");
    let path = dir.join(format!("hybrid_seed{seed}.json"));
    if let Ok(text) = std::fs::read_to_string(&path) {
        return HybridPredictor::from_json_str(&text).unwrap();
    }
    let data = calibration::calibrate(
        spec,
        &ThermalCycle::calibration_plan(spec),
        &CampaignConfig::new(seed),
    )
    .unwrap();
    let s = campaign::fit_to_data(
        Settings {
            seed,
            ..Settings::for_machine(spec)
        },
        &data,
    );
    let (h, _) = predictor::train_hybrid(&data, &spec.geometry(), &s).unwrap();
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(&path, h.to_json_string().unwrap()).unwrap();
    h
}

fn main() {
    let spec = MachineSpec::reference();
    let mut seeds = vec![21u64, 22, 23];
    let mut every_min = 30.0;
    let mut walk = None;
    let mut meas: Option<f64> = None;
    let mut gwalk: Option<f64> = None;
    let mut ginit: Option<f64> = None;
    let mut oinit: Option<f64> = None;
    let mut ideal = false;
    let mut single = false;
    let mut nograd = false;
    let mut repeats: Option<usize> = None;
    let mut spheres: Option<usize> = None;
    let mut dev = false;
    for a in std::env::args().skip(1) {
        let (k, v) = a.split_once('=').expect("key=value");
        match k {
            "seeds" => seeds = v.split(',').map(|s| s.parse().unwrap()).collect(),
            "every" => every_min = v.parse().unwrap(),
            "walk" => walk = Some(v.parse().unwrap()),
            "meas" => meas = Some(v.parse().unwrap()),
            "states" => dev = v == "dev",
            "gwalk" => gwalk = Some(v.parse().unwrap()),
            "ginit" => ginit = Some(v.parse().unwrap()),
            "oinit" => oinit = Some(v.parse().unwrap()),
            "ideal" => ideal = v == "1",
            "single" => single = v == "1",
            "nograd" => nograd = v == "1",
            "repeats" => repeats = Some(v.parse().unwrap()),
            "spheres" => spheres = Some(v.parse().unwrap()),
            _ => panic!("unknown {k}"),
        }
    }
    let plans = diagonal_plans(&spec).unwrap();
    let names: Vec<String> = spec.sensors.iter().map(|s| s.name.clone()).collect();
    let mut runs = Vec::new();
    let mut cost = 0.0;
    let mut floors = Vec::new();
    for &seed in &seeds {
        let h = model(&spec, seed);
        let mut states = calibration::evaluation_states(&spec, seed);
        if dev {
            states.extend(dev_states::dev_stress_states());
        }
        let probing = (every_min > 0.0).then(|| {
            let mut p = if single {
                Probing::single_sphere(&spec, every_min)
            } else {
                Probing::every(&spec, every_min)
            };
            if let Some(n) = spheres {
                p.sphere_centres_mm.truncate(n);
            }
            if let Some(r) = repeats {
                p.repeats = r;
            }
            p.gradient = !nograd && !single;
            if ideal {
                p.probe.repeatability_2sigma_um = 0.0;
                p.probe.servo_period_s = 1e-7;
            }
            p.field.measurement_sigma_um = p.measurement_sigma_um();
            if let Some(w) = walk {
                p.field.walk_offset_um_per_sqrt_h = w;
            }
            if let Some(w) = gwalk {
                p.field.walk_gradient_um_per_m_sqrt_h = w;
            }
            if let Some(w) = ginit {
                p.field.initial_gradient_um_per_m = w;
            }
            if let Some(w) = oinit {
                p.field.initial_offset_um = w;
            }
            if let Some(m) = meas {
                p.field.measurement_sigma_um = m;
            }
            p
        });
        let fix = probing
            .as_ref()
            .map(|p| probing::qualify(&spec, seed, p, &h).unwrap());
        if let Some(p) = &probing {
            cost = p.cost_min_per_h();
        }
        for (si, state) in states.iter().enumerate() {
            for (di, (diag, plan)) in plans.iter().enumerate() {
                let noise = eval_noise_seed(seed, si, di);
                let points = match (&probing, &fix) {
                    (Some(p), Some(fix)) => {
                        let mut ctrl = probing::probed_compensator(h.clone(), p, &names).unwrap();
                        let pts = probing::run_at_state_probed(
                            &spec, seed, noise, state, plan, p, fix, &mut ctrl,
                        )
                        .unwrap();
                        if std::env::var("PV_OFFSETS").is_ok() {
                            let f = ctrl.predictor_mut().filter().clone();
                            let o = f.offset_mm().map(|v| v * 1e3);
                            let g = f.gradient(2).map(|v| v * 1e6);
                            eprintln!(
                                "seed {seed} {} {diag}: offset µm {o:.2?} Ez gradient µm/m {g:.1?}",
                                state.name
                            );
                        }
                        pts
                    }
                    _ => {
                        let mut ctrl = vmc_twin::predict::controller::Compensator::for_machine(
                            h.clone(),
                            &names,
                        )
                        .unwrap();
                        calibration::run_at_state(&spec, seed, noise, state, plan, Some(&mut ctrl))
                            .unwrap()
                    }
                };
                let mut mean = [0.0; 3];
                let mut lo = [f64::INFINITY; 3];
                let mut hi = [f64::NEG_INFINITY; 3];
                let n = points.len() as f64;
                for p in &points {
                    let e = p.error_after_um.unwrap();
                    for a in 0..3 {
                        mean[a] += e[a] / n;
                        lo[a] = lo[a].min(e[a]);
                        hi[a] = hi[a].max(e[a]);
                    }
                }
                // Floors: the max |E| left by a perfect offset (mean removed) and by a perfect
                // linear field (a least-squares line along the diagonal removed).
                let floor = |linear: bool| {
                    let t: Vec<f64> = (0..points.len()).map(|i| i as f64).collect();
                    let tm = t.iter().sum::<f64>() / n;
                    let stt: f64 = t.iter().map(|x| (x - tm).powi(2)).sum();
                    let slope = |a: usize| {
                        if !linear {
                            return 0.0;
                        }
                        points
                            .iter()
                            .zip(&t)
                            .map(|(p, x)| (x - tm) * p.error_after_um.unwrap()[a])
                            .sum::<f64>()
                            / stt
                    };
                    let s3 = [slope(0), slope(1), slope(2)];
                    points
                        .iter()
                        .zip(&t)
                        .map(|(p, x)| {
                            let e = p.error_after_um.unwrap();
                            (0..3)
                                .map(|a| (e[a] - mean[a] - s3[a] * (x - tm)).powi(2))
                                .sum::<f64>()
                                .sqrt()
                        })
                        .fold(0.0, f64::max)
                };
                let r = campaign::run_report(ModelKind::Hybrid, diag, &state.name, seed, &points);
                if let Some(r) = r {
                    floors.push((floor(false), floor(true)));
                    runs.push((r, mean, [0, 1, 2].map(|a| hi[a] - lo[a])));
                }
            }
        }
    }
    let reports: Vec<_> = runs.iter().map(|r| r.0.clone()).collect();
    let h = campaign::headline(&reports, ModelKind::Hybrid).unwrap();
    let over = reports.iter().filter(|r| r.max_after_um > 2.0).count();
    let mut worst: Vec<_> = runs.iter().collect();
    worst.sort_by(|a, b| b.0.max_after_um.total_cmp(&a.0.max_after_um));
    for (r, mean, spread) in worst.iter().take(12) {
        println!(
            "  {:<4} {:<24} seed {:>2} max {:.2} (x {:.2} y {:.2} z {:.2}) mean ({:+.2} {:+.2} {:+.2}) spread ({:.2} {:.2} {:.2})",
            r.diagonal,
            r.thermal_state,
            r.seed,
            r.max_after_um,
            r.max_after_xyz_um[0],
            r.max_after_xyz_um[1],
            r.max_after_xyz_um[2],
            mean[0],
            mean[1],
            mean[2],
            spread[0],
            spread[1],
            spread[2]
        );
    }
    // Per state: the max residual and the mean offsets' extremes.
    let mut state_names: Vec<String> = runs.iter().map(|r| r.0.thermal_state.clone()).collect();
    state_names.dedup();
    state_names.sort();
    state_names.dedup();
    for s in &state_names {
        let rs: Vec<_> = runs.iter().filter(|r| &r.0.thermal_state == s).collect();
        let mx = rs.iter().map(|r| r.0.max_after_um).fold(0.0, f64::max);
        let mz = rs.iter().map(|r| r.1[2].abs()).fold(0.0, f64::max);
        let mxy = rs
            .iter()
            .map(|r| r.1[0].abs().max(r.1[1].abs()))
            .fold(0.0, f64::max);
        println!("  state {s:<24} max {mx:.2}  |mean z| ≤ {mz:.2}  |mean xy| ≤ {mxy:.2}");
    }
    let f0 = floors.iter().map(|f| f.0).fold(0.0, f64::max);
    let f1 = floors.iter().map(|f| f.1).fold(0.0, f64::max);
    let n0 = floors.iter().filter(|f| f.0 > 2.0).count();
    let n1 = floors.iter().filter(|f| f.1 > 2.0).count();
    println!("floors: perfect offset max {f0:.2} µm ({n0} runs > 2), perfect linear field max {f1:.2} µm ({n1} runs > 2)");
    println!(
        "{:?}: median {:.1} % worst {:.1} % max {:.2} µm, {over} of {} runs > 2 µm, cost {:.2} min/h",
        std::env::args().skip(1).collect::<Vec<_>>(),
        h.median_reduction * 100.0,
        h.worst_reduction * 100.0,
        h.max_after_um,
        reports.len(),
        cost
    );
}
