//! Closed-loop stability lobes of the piezo-actuated blade (machines/benchmarks/blade.toml:
//! 4 modes, stack at 36 mm, LQG with a 2 kHz output filter, sampled at 50 kHz and modelled with
//! a second-order Padé delay): 200 speeds over 1500–4500 rpm, boundary tracer, tolerance
//! 1e-4 mm, one core. The augmented system has 24 states (9 blade + actuator, 13 controller,
//! 2 Padé).
//!
//! Figures (`taskset -c 0 cargo bench -p vmc-dynamics --bench control`), on the 2-core machine
//! shared with other builds (load average 14), so wall times say more about the load than the
//! code: `closed_loop_lobes_200_m40` 2.94 s, `closed_loop_lobes_200_m160` 11.0 s per iteration.
//! Through the command line (`vmc-twin lobes --controller lqg.json`, open and closed loop, 160
//! steps, `taskset -c 1`): 3.8 s of CPU time on the idle machine, 4.2–5.2 s under a load average
//! of 9 (23.1 s with the full monodromy product and bisection).
//!
//! Resolution, 20 of the speeds (every 10th), load average ≈ 5: `closed_loop_lobes_20_m160`
//! 1.08 s, `_m640` 3.28 s, `_converged640` (the converged rule capped at 640 steps, 320 and 640
//! extrapolated) 4.81 s. Over all 200 speeds the fixed 160 steps are up to 10 % deep in closed
//! loop; the capped rule is within 0.12 % of the uncapped converged lobes (decision record on
//! converged lobes).

use criterion::{criterion_group, criterion_main, Criterion};
use vmc_dynamics::control::blade::{Actuator, Blade};
use vmc_dynamics::control::closed_loop::{close, lobes, sampled_model, LobeCut};
use vmc_dynamics::control::design::{to_metres, DesignPlant, LqgWeights};
use vmc_dynamics::{Milling, Resolution, StepRule, Tool};

fn bench(c: &mut Criterion) {
    let blade = Blade {
        youngs_modulus_pa: 210e9,
        density_kg_per_m3: 7850.0,
        length_mm: 160.0,
        width_mm: 80.0,
        thickness_mm: 5.0,
        modes: 4,
        damping_ratio: 0.01,
        sensor_position_mm: 160.0,
        actuator: Actuator {
            position_mm: 36.0,
            stiffness_n_per_um: 185.0,
            stroke_um: 30.0,
            max_voltage_v: 150.0,
            bandwidth_hz: 2000.0,
        },
    };
    let plant = blade.plant().expect("valid blade");
    let rate = 50_000.0;
    let weights = LqgWeights {
        tip_weight_per_um2: 1.0,
        effort_weight_per_v2: 10.0,
        force_intensity_n2: 1.0,
        noise_intensity_um2: 0.01,
        lowpass_hz: Some(2000.0),
    };
    let design = DesignPlant::structure(&plant).sampled(rate).expect("rate");
    let k = to_metres(&design.lqg(&weights).expect("LQG"));
    let closed = close(&plant, &sampled_model(&k, rate).expect("model")).expect("loop");
    let cut = LobeCut {
        tool: Tool::new(2, 16.0, 1e9, 3e8),
        immersion: 1.0 / 16.0,
        milling: Milling::Down,
    };
    let speeds: Vec<f64> = (0..200)
        .map(|i| 1500.0 + 3000.0 * f64::from(i) / 199.0)
        .collect();
    let mut g = c.benchmark_group("control");
    g.sample_size(10);
    for m in [40, 160] {
        g.bench_function(format!("closed_loop_lobes_200_m{m}"), |b| {
            b.iter(|| lobes(&plant, &closed, &cut, &speeds, (50.0, 1e-4), m).expect("lobes"));
        });
    }
    // 20 of the speeds: the fixed 160 and 640 steps against the converged rule capped at 640
    // steps (extrapolated from 320 and 640).
    let few: Vec<f64> = speeds.iter().step_by(10).copied().collect();
    let capped = Resolution::Converged(StepRule {
        max_steps: 640,
        ..StepRule::default()
    });
    for (name, res) in [
        ("m160", Resolution::Fixed(160)),
        ("m640", Resolution::Fixed(640)),
        ("converged640", capped),
    ] {
        g.bench_function(format!("closed_loop_lobes_20_{name}"), |b| {
            b.iter(|| lobes(&plant, &closed, &cut, &few, (50.0, 1e-4), res).expect("lobes"));
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
