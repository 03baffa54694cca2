//! Diagnosis (truth side): would the axes' travel history help the axis parts?
//!
//! A CNC knows each axis's commanded speed; the heat of a ballscrew's nut and bearings follows
//! it. This probe asks how much of the axes' *thermal* positioning change (truth: the twin's
//! error functions at the far end of each axis minus the same at the cold start) a linear
//! model explains from the sensor readings alone, and from the readings plus low-pass filters
//! of each axis's commanded speed (τ = 20 min and 1 h). Fitted by least squares on the
//! typical (calibration) cycles, scored on the atypical ones: the held-out evaluation cycles
//! and the selection-only cycles. Sampled every 60 s while the cycle's duty runs (no
//! measurement stops). Not a predictor: a bound on what such features could add.
//!
//! `cargo run --release --example travel_probe -- SEED [every=MIN] [noise=µm]` — `every=30
//! noise=0.3` thins and blurs the training samples like the campaign's laser blocks.
use vmc_machine::machine::MachineSpec;
use vmc_machine::twin::{sub_seed, Twin};
use vmc_twin::predict::linreg::LinearModel;
use vmc_twin::predict::nn::Samples;
use vmc_twin::studies::calibration::{self, ThermalCycle};

const TAUS_S: [f64; 2] = [1200.0, 3600.0];

/// Rows of one cycle: (readings, travel features, thermal change of δx, δy, δz at the far end).
fn rows(
    spec: &MachineSpec,
    seed: u64,
    k: u64,
    cycle: &ThermalCycle,
) -> Vec<(Vec<f64>, Vec<f64>, [f64; 3])> {
    let mut twin = Twin::with_noise_seed(spec, seed, sub_seed(seed, 5000 + k)).unwrap();
    twin.set_ambient(cycle.ambient.clone()).unwrap();
    let far = [0, 1, 2].map(|a| {
        let (lo, hi) = (spec.axes.travel_min_mm[a], spec.axes.travel_max_mm[a]);
        // X and Y: far from the motor end; Z: the bottom of the travel.
        if a == 2 {
            lo + 0.05 * (hi - lo)
        } else {
            lo + 0.95 * (hi - lo)
        }
    });
    let mid = [0, 1, 2].map(|a| 0.5 * (spec.axes.travel_min_mm[a] + spec.axes.travel_max_mm[a]));
    let change = |twin: &Twin| {
        [0, 1, 2].map(|a| {
            let mut q = mid;
            q[a] = far[a];
            twin.elementary_errors(q).axes[a].lin_mm[a] * 1e3
        })
    };
    let cold = change(&twin);
    let mut filt = [[0.0f64; 3]; TAUS_S.len()];
    let mut out = Vec::new();
    let end = cycle.duration_s();
    let mut t = 0.0;
    while t < end - 1e-9 {
        let to = (t + 60.0).min(end);
        calibration::drive(&mut twin, cycle, 0.0, to, 1.0).unwrap();
        // The commanded speeds over the step (the duty is constant within a phase).
        let v = cycle.phase_at(0.5 * (t + to)).axis_speed_mm_per_min;
        for (f, tau) in filt.iter_mut().zip(TAUS_S) {
            let a = 1.0 - (-(to - t) / tau).exp();
            for ax in 0..3 {
                f[ax] += a * (v[ax].abs() / 1000.0 - f[ax]);
            }
        }
        t = to;
        let now = change(&twin);
        out.push((
            twin.sensor_readings().values_degc,
            filt.iter().flatten().copied().collect(),
            [0, 1, 2].map(|a| now[a] - cold[a]),
        ));
    }
    out
}

/// Least squares with intercept on `train`; RMS and max |residual| on `test`, per output.
fn fit_score(train: &[(Vec<f64>, [f64; 3])], test: &[(Vec<f64>, [f64; 3])]) -> [(f64, f64); 3] {
    let xs: Vec<Vec<f64>> = train.iter().map(|(x, _)| x.clone()).collect();
    let ys: Vec<Vec<f64>> = train.iter().map(|(_, y)| y.to_vec()).collect();
    // The project's ridge regression (z-scored inputs), a tiny ridge for conditioning.
    let model = LinearModel::fit(&Samples::from_rows(&xs, &ys).unwrap(), 1e-6).unwrap();
    let predicted: Vec<Vec<f64>> = test
        .iter()
        .map(|(x, _)| model.predict(x).unwrap())
        .collect();
    [0, 1, 2].map(|o| {
        let residuals: Vec<f64> = predicted
            .iter()
            .zip(test)
            .map(|(p, (_, y))| p[o] - y[o])
            .collect();
        let s: f64 = residuals.iter().map(|e| e * e).sum();
        let mx = residuals.iter().fold(0.0f64, |m, e| m.max(e.abs()));
        ((s / test.len() as f64).sqrt(), mx)
    })
}

fn main() {
    let seed: u64 = std::env::args()
        .nth(1)
        .map_or(21, |s| s.parse().expect("seed"));
    let spec = MachineSpec::reference();
    let collect = |cycles: &[ThermalCycle], base: u64| {
        cycles
            .iter()
            .enumerate()
            .flat_map(|(k, c)| rows(&spec, seed, base + k as u64, c))
            .collect::<Vec<_>>()
    };
    // `every=N`: keep every N-th training sample (N = 30: one per 30 min, as the campaign's
    // blocks); `noise=σ`: add that much Gaussian-like noise (µm) to the training targets.
    let arg = |k: &str| {
        std::env::args().find_map(|a| a.strip_prefix(k).map(|v| v.parse::<f64>().unwrap()))
    };
    let every = arg("every=").unwrap_or(1.0) as usize;
    let noise = arg("noise=").unwrap_or(0.0);
    let mut state = sub_seed(seed, 4242);
    let mut gauss = || {
        // Sum of 12 uniforms − 6: unit variance.
        (0..12)
            .map(|_| {
                state = sub_seed(state, 1);
                (state >> 11) as f64 / (1u64 << 53) as f64
            })
            .sum::<f64>()
            - 6.0
    };
    let train: Vec<_> = collect(&ThermalCycle::calibration_plan(&spec), 0)
        .into_iter()
        .step_by(every.max(1))
        .map(|(r, f, y)| (r, f, y.map(|v| v + noise * gauss())))
        .collect();
    let mut test_cycles = ThermalCycle::evaluation_set(seed);
    test_cycles.extend(
        vmc_twin::studies::placement::validation_states(seed)
            .into_iter()
            .map(|s| s.cycle),
    );
    test_cycles.dedup_by(|a, b| a.name == b.name);
    let test = collect(&test_cycles, 100);
    let only = |v: &[(Vec<f64>, Vec<f64>, [f64; 3])], with: bool| {
        v.iter()
            .map(|(r, f, y)| {
                let mut x = r.clone();
                if with {
                    x.extend_from_slice(f);
                }
                (x, *y)
            })
            .collect::<Vec<_>>()
    };
    let spread: [f64; 3] = [0, 1, 2].map(|o| {
        let m = test.iter().map(|r| r.2[o]).sum::<f64>() / test.len() as f64;
        (test.iter().map(|r| (r.2[o] - m).powi(2)).sum::<f64>() / test.len() as f64).sqrt()
    });
    let a = fit_score(&only(&train, false), &only(&test, false));
    let b = fit_score(&only(&train, true), &only(&test, true));
    println!(
        "seed {seed}: thermal change at the far end over {} atypical samples, µm \
         (RMS / max |residual|; training every {every} min, noise {noise} µm)",
        test.len()
    );
    println!(
        "  spread of the truth (RMS)     δx {:.3}  δy {:.3}  δz {:.3}",
        spread[0], spread[1], spread[2]
    );
    let f = |r: [(f64, f64); 3]| {
        format!(
            "δx {:.3} / {:.3}  δy {:.3} / {:.3}  δz {:.3} / {:.3}",
            r[0].0, r[0].1, r[1].0, r[1].1, r[2].0, r[2].1
        )
    };
    println!("  readings only                 {}", f(a));
    println!("  readings + travel history     {}", f(b));
}
