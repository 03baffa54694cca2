//! Stability-lobe benchmarks on the Insperger–Stépán 1-DOF benchmark (N = 2, K_t = 6e8,
//! K_n = 2e8 N/m², 922 Hz, ζ = 0.011, 0.03993 kg), a_e/D = 0.05 down milling, one core.
//!
//! Figures (release, one core via `taskset -c 0 cargo bench -p vmc-dynamics --bench lobes`, on a
//! 2-core machine shared with other work; two runs, so figures vary with the load):
//! * `sdm_grid_201x100` — full grid, 201 speeds (5000–13000 rpm) × 100 depths (0.15–15 mm),
//!   m = 40, 20 100 stability evaluations: 0.84–0.89 s (≈ 43 µs per evaluation).
//! * `sdm_tracer_201` — boundary tracer on the same speeds, tolerance 0.03 mm, restarting
//!   every 8 speeds: 1 424 evaluations (14× fewer; within one grid cell of the grid's boundary
//!   at all 201 speeds, asserted in `tests/agreement.rs`): 24–26 ms (idle machine, one run).
//! * `time_domain_400_teeth` — linear time-domain simulation, 400 tooth periods × 64 RK4
//!   steps = 25 600 steps: 3.0–5.1 ms, i.e. 5.0–8.7 M RK4 steps/s = 78 000–135 000 tooth
//!   passes/s (64 steps each); 3.18 ms (8.1 M steps/s) in a later run, after helical teeth were
//!   added (unchanged for straight teeth).
//! * `cut_400_teeth` — one `cut` (9000 rpm, 2 mm, f_z 0.1 mm): steady state, 400 tooth periods
//!   × 64 RK4 steps of the process model with every step recorded, verdict and two spectra
//!   (radix-2 FFTs of 16 384 points): 7.07 ms, i.e. 3.6 M steps/s = 56 600 tooth passes/s.
//! * `lobes_*_m40` / `lobes_*_converged` — the SDM lobes of `lobes` (tracer from the zero-order
//!   minimum, tolerance 1e-3 of it) at 40 fixed steps and at the converged resolution
//!   (`Resolution::default()`), D = 20 mm, down milling (load average ≈ 5): a_e/D 0.05,
//!   5000–25 000 rpm, 201 speeds 82.6 ms → 470 ms; slotting, same speeds 1.29 s → 3.74 s;
//!   slotting, 2000–30 000 rpm every 250 rpm 0.80 s → 2.63 s (decision record on converged
//!   lobes). `sdm_tracer_201` in the same run: 67.6 ms (1429 evaluations; the load, not the
//!   code, makes it slower than the idle figure above).
//! * `cut_400_teeth_helix30` — the same cut with a 4-tooth 30° helical cutter, modes in x and
//!   y (3 axial disks: 12 tooth-disk force evaluations per stage instead of 2): 21.2 ms,
//!   1.2 M steps/s.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use vmc_dynamics::lobes::lobes_block_at;
use vmc_dynamics::milling::{MillingSdm, SdmOptions};
use vmc_dynamics::time_domain::{ForceModel, TimeDomain, TimeOptions};
use vmc_dynamics::{
    simulate_cut, Cut, CutOptions, Method, Milling, Mode, Resolution, TipModes, Tool,
};

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
    // The lobes of `lobes` (start at the zero-order minimum, tolerance 1e-3 of it): the fixed
    // 40 steps of before and the converged resolution, at a_e/D = 0.05 and in slotting over
    // 5000–25 000 rpm (201 speeds) and 2000–30 000 rpm every 250 rpm (113 speeds).
    let wide: Vec<f64> = (0..201).map(|i| 5000.0 + 100.0 * f64::from(i)).collect();
    let every_250: Vec<f64> = (0..113).map(|i| 2000.0 + 250.0 * f64::from(i)).collect();
    for (name, immersion, list) in [
        ("ae005_5k_25k", 0.05, &wide),
        ("slot_5k_25k", 1.0, &wide),
        ("slot_2k_30k", 1.0, &every_250),
    ] {
        for (res_name, res) in [
            ("m40", Resolution::Fixed(40)),
            ("converged", Resolution::default()),
        ] {
            g.bench_function(format!("lobes_{name}_{res_name}"), |b| {
                b.iter(|| {
                    let cut = (immersion, Milling::Down);
                    let all = 0..list.len();
                    lobes_block_at(Method::Sdm, &tool, &modes, cut, list, all, &res).unwrap()
                })
            });
        }
    }
    let opts = TimeOptions::default();
    let td = TimeDomain::new(&tool, &modes, 0.05, Milling::Down, opts).unwrap();
    g.throughput(Throughput::Elements(
        (opts.steps_per_tooth * opts.tooth_periods) as u64,
    ));
    g.bench_function("time_domain_400_teeth", |b| {
        b.iter(|| td.simulate(9000.0, 2.0, 0.0, ForceModel::Linear).unwrap())
    });
    // One `cut`: steady state, 400 tooth periods of the process model recorded at every step,
    // verdict and the two spectra (SDM comparison not included).
    let cut = Cut {
        spindle_rpm: 9000.0,
        immersion: 0.05,
        milling: Milling::Down,
        feed_per_tooth_mm: 0.1,
        axial_depth_mm: 2.0,
    };
    let copts = CutOptions::default();
    g.throughput(Throughput::Elements(
        (copts.steps_per_tooth * copts.tooth_periods) as u64,
    ));
    g.bench_function("cut_400_teeth", |b| {
        b.iter(|| simulate_cut(&tool, &modes, &cut, &copts).unwrap())
    });
    // The same with a 4-tooth 30° helical cutter in x and y, 2 mm deep: 3 disks.
    let mut helical = Tool::new(4, 16.0, 6e8, 2e8);
    helical.helix_deg = 30.0;
    let sym = TipModes::symmetric(Mode::from_mass(922.0, 0.011, 0.03993));
    g.bench_function("cut_400_teeth_helix30", |b| {
        b.iter(|| simulate_cut(&helical, &sym, &cut, &copts).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
