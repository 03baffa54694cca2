//! Stability-lobe benchmarks on the Insperger–Stépán 1-DOF benchmark (N = 2, K_t = 6e8,
//! K_n = 2e8 N/m², 922 Hz, ζ = 0.011, 0.03993 kg), a_e/D = 0.05 down milling, one core.
//!
//! Figures (release, one core via `taskset -c 0 cargo bench -p vmc-dynamics --bench lobes`, on a
//! 2-core machine shared with other work; two runs, so figures vary with the load):
//! * `sdm_grid_201x100` — full grid, 201 speeds (5000–13000 rpm) × 100 depths (0.15–15 mm),
//!   m = 40, 20 100 stability evaluations: 0.84–0.89 s (≈ 43 µs per evaluation).
//! * `sdm_tracer_201` — boundary tracer on the same speeds, tolerance 0.03 mm:
//!   1 648 evaluations (12× fewer; within one grid cell of the grid's boundary at all 201
//!   speeds, asserted in `tests/agreement.rs`): 52–84 ms.
//! * `time_domain_400_teeth` — linear time-domain simulation, 400 tooth periods × 64 RK4
//!   steps = 25 600 steps: 3.0–5.1 ms, i.e. 5.0–8.7 M RK4 steps/s = 78 000–135 000 tooth
//!   passes/s (64 steps each).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use vmc_dynamics::milling::{MillingSdm, SdmOptions};
use vmc_dynamics::time_domain::{ForceModel, TimeDomain, TimeOptions};
use vmc_dynamics::{Milling, Mode, TipModes, Tool};

fn setup() -> (Tool, TipModes) {
    (
        Tool::new(2, 20.0, 6e8, 2e8),
        TipModes::x_only(vec![Mode::from_mass(922.0, 0.011, 0.03993)]),
    )
}

fn speeds() -> Vec<f64> {
    (0..201).map(|i| 5000.0 + 40.0 * f64::from(i)).collect()
}

fn bench(c: &mut Criterion) {
    let (tool, modes) = setup();
    let depths: Vec<f64> = (1..=100).map(|j| 15.0 * f64::from(j) / 100.0).collect();
    let speeds = speeds();
    let mut g = c.benchmark_group("lobes");
    g.sample_size(10);
    g.bench_function("sdm_grid_201x100", |b| {
        b.iter(|| {
            let sdm =
                MillingSdm::new(&tool, &modes, 0.05, Milling::Down, SdmOptions::default()).unwrap();
            sdm.grid(&speeds, &depths).unwrap()
        })
    });
    g.bench_function("sdm_tracer_201", |b| {
        b.iter(|| {
            let sdm =
                MillingSdm::new(&tool, &modes, 0.05, Milling::Down, SdmOptions::default()).unwrap();
            sdm.trace(&speeds, 15.0, 0.03).unwrap()
        })
    });
    let opts = TimeOptions::default();
    let td = TimeDomain::new(&tool, &modes, 0.05, Milling::Down, opts).unwrap();
    g.throughput(Throughput::Elements(
        (opts.steps_per_tooth * opts.tooth_periods) as u64,
    ));
    g.bench_function("time_domain_400_teeth", |b| {
        b.iter(|| td.simulate(9000.0, 2.0, 0.0, ForceModel::Linear).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
