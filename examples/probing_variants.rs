//! Diagnosis: the hybrid predictor with and without on-machine probing, on development seeds.
//! `cargo run --release --example probing_variants -- seeds=21,22,23 every=30 walk=3`
//!
//! Keys: `seeds=` (machine seeds; use development seeds, never the campaign's held-out 1–3 for
//! choosing), `every=` probing interval (min; `0` no probing), `walk=` drift walk (µm/√h),
//! `states=dev` adds the selection-only stress
//! states, `repeats=`/`toprep=` repeats of each touch along X, Y / of each top, `passes=` passes over the tops per cycle (1 or 2), `rate=` the drift rate's σ
//! (µm/min; 1e-9: none), `tau=` its fading time (s). Models are trained once per seed and cached under `target/probing-models/`.
//! `terms=zz,xx` opens single gradient terms (component then axis) with prior `tinit=` µm/m and
//! walk `twalk=` µm/m/√h; `qual=` cycles averaged into the spheres' references. `PV_FIELD=1`
//! prints which first-order field the residual follows (per-state fits on the twin's truth,
//! `shared/residual_field.rs`), `PV_OFFSETS=1` the drift estimated before each diagonal.
//! Prints the headline figures, the worst runs with their max per axis and the mean signed
//! residual per axis of the run (an offset the probe could see) beside its spread (what an
//! offset cannot correct).
use vmc_machine::machine::MachineSpec;
use vmc_twin::predict::predictor::ModelKind;
use vmc_twin::studies::calibration;
use vmc_twin::studies::campaign::{self, diagonal_plans, eval_noise_seed};
use vmc_twin::studies::probing::{self, Probing};

#[path = "shared/dev_model.rs"]
mod dev_model;
#[path = "shared/dev_states.rs"]
mod dev_states;
#[path = "shared/residual_field.rs"]
mod residual_field;
use dev_model::model;

fn main() {
    let spec = MachineSpec::reference();
    let mut seeds = vec![21u64, 22, 23];
    let mut every_min = 30.0;
    let mut walk = None;
    let mut gwalk: Option<f64> = None;
    let mut ginit: Option<f64> = None;
    let mut oinit: Option<f64> = None;
    let mut ideal = false;
    let mut single = false;
    let mut nograd = false;
    let mut repeats: Option<usize> = None;
    let mut spheres: Option<usize> = None;
    let mut dev = false;
    let mut passes: Option<usize> = None;
    let mut top_repeats: Option<usize> = None;
    let mut rate: Option<f64> = None;
    let mut tau: Option<f64> = None;
    // Gradient terms `terms=zz,xx` (component then axis) with prior `tinit=` µm/m and walk
    // `twalk=` µm/m/√h.
    let mut terms: Vec<(usize, usize)> = Vec::new();
    let mut tinit = 2.0;
    let mut twalk = 1.0;
    // Cycles averaged into the spheres' references, `qual=`.
    let mut qualify: Option<usize> = None;
    for a in std::env::args().skip(1) {
        let (k, v) = a.split_once('=').expect("key=value");
        match k {
            "seeds" => seeds = v.split(',').map(|s| s.parse().unwrap()).collect(),
            "every" => every_min = v.parse().unwrap(),
            "walk" => walk = Some(v.parse().unwrap()),
            "states" => dev = v == "dev",
            "gwalk" => gwalk = Some(v.parse().unwrap()),
            "ginit" => ginit = Some(v.parse().unwrap()),
            "oinit" => oinit = Some(v.parse().unwrap()),
            "ideal" => ideal = v == "1",
            "single" => single = v == "1",
            "nograd" => nograd = v == "1",
            "repeats" => repeats = Some(v.parse().unwrap()),
            "spheres" => spheres = Some(v.parse().unwrap()),
            "passes" => passes = Some(v.parse().unwrap()),
            "toprep" => top_repeats = Some(v.parse().unwrap()),
            "rate" => rate = Some(v.parse().unwrap()),
            "tau" => tau = Some(v.parse().unwrap()),
            "terms" => {
                let ax = |c: char| "xyz".find(c).expect("x, y or z");
                terms = v
                    .split(',')
                    .map(|t| {
                        let c: Vec<char> = t.chars().collect();
                        (ax(c[0]), ax(c[1]))
                    })
                    .collect();
            }
            "tinit" => tinit = v.parse().unwrap(),
            "qual" => qualify = Some(v.parse().unwrap()),
            "twalk" => twalk = v.parse().unwrap(),
            _ => panic!("unknown {k}"),
        }
    }
    let plans = diagonal_plans(&spec).unwrap();
    let names: Vec<String> = spec.sensors.iter().map(|s| s.name.clone()).collect();
    let mut runs = Vec::new();
    let mut cost = 0.0;
    let mut floors = Vec::new();
    // With PV_FIELD set: each state's four diagonals kept for the field fits at the end.
    let keep_points = std::env::var("PV_FIELD").is_ok();
    let mut kept: Vec<(u64, String, Vec<Vec<vmc_machine::sim::PointRecord>>)> = Vec::new();
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
            if let Some(r) = top_repeats {
                p.top_repeats = r;
            }
            if let Some(n) = passes {
                p.top_passes = n;
            }
            if let Some(r) = rate {
                p.field.rate_sigma_um_per_min = r;
            }
            if let Some(t) = tau {
                p.field.rate_tau_s = t;
            }
            if let Some(n) = qualify {
                p.qualify_cycles = n;
            }
            p.gradient = !nograd && !single && terms.is_empty();
            p.gradient_terms = terms
                .iter()
                .map(|&(component, axis)| probing::GradientTerm {
                    component,
                    axis,
                    initial_um_per_m: tinit,
                    walk_um_per_m_sqrt_h: twalk,
                })
                .collect();
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
                if keep_points {
                    if di == 0 {
                        kept.push((seed, state.name.clone(), Vec::new()));
                    }
                    if let Some(k) = kept.last_mut() {
                        k.2.push(points.clone());
                    }
                }
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
        let bz = rs.iter().map(|r| r.1[2]).sum::<f64>() / rs.len() as f64;
        println!(
            "  state {s:<24} max {mx:.2}  |mean z| ≤ {mz:.2} (average {bz:+.2})  |mean xy| ≤ {mxy:.2}"
        );
    }
    if keep_points {
        print_field_fits(&kept);
    }
    // The run means over all runs: a bias common to the runs (the offset estimate behind or
    // ahead of the residual) against their scatter.
    let nr = runs.len().max(1) as f64;
    let bias = [0, 1, 2].map(|a| runs.iter().map(|r| r.1[a]).sum::<f64>() / nr);
    let sd = [0, 1, 2]
        .map(|a| (runs.iter().map(|r| (r.1[a] - bias[a]).powi(2)).sum::<f64>() / nr).sqrt());
    println!("run means µm: bias {bias:+.2?} sd {sd:.2?}");
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

/// Per gradient choice, the max |E| left and the runs above 2 µm over all kept states; the
/// states whose offset floor is above 2 µm with the fitted gradients.
fn print_field_fits(kept: &[(u64, String, Vec<Vec<vmc_machine::sim::PointRecord>>)]) {
    for terms in &residual_field::VARIANTS {
        let mut worst = 0.0f64;
        let mut over = 0;
        for (_, _, runs) in kept {
            let refs: Vec<&[vmc_machine::sim::PointRecord]> =
                runs.iter().map(|r| r.as_slice()).collect();
            let (max, _) = residual_field::fit(&refs, terms);
            worst = max.iter().copied().fold(worst, f64::max);
            over += max.iter().filter(|m| **m > 2.0).count();
        }
        println!(
            "field fit {:<12} max {worst:.2} µm, {over} runs > 2",
            terms.name
        );
    }
    for (seed, state, runs) in kept {
        let refs: Vec<&[vmc_machine::sim::PointRecord]> =
            runs.iter().map(|r| r.as_slice()).collect();
        let (max0, _) = residual_field::fit(&refs, &residual_field::VARIANTS[0]);
        let (_, g) = residual_field::fit(&refs, &residual_field::VARIANTS[11]);
        let m0 = max0.iter().copied().fold(0.0, f64::max);
        println!(
            "  seed {seed:>2} {state:<24} offset floor {m0:.2}  gradients µm/m Ex {:+.1?} Ey {:+.1?} Ez {:+.1?}",
            g[0], g[1], g[2]
        );
    }
}
