//! Benchmarks of the control loop and the simulation.
//!
//! `cargo bench --bench loop` — figures are recorded in docs/results.md.
//!
//! - `compensation_query`: one compensation of the hybrid predictor (fixed-point solve of
//!   q = p − E_pred(q, T): all networks + first-order synthesis), from held sensor readings and a
//!   commanded position that moves as along a diagonal.
//! - `compensation_query_per_kind`: the same query with the hybrid, volumetric and linear models.
//! - `thermal_8h`: 8 h of machine time of the thermal network alone (1 s steps) under a duty.
//! - `machine_8h_with_diagonals`: 8 h of machine time with an XY diagonal test every 30 min,
//!   motion sampled at the 1 ms interpolation cycle (error evaluated at every sample).
//! - `campaign_one_seed`: calibration + training of the three predictors + 147 held-out runs.
//!
//! Figures, release build, 2-core machine (before → after the profile-driven work;
//! "after" measured with `vmc-twin bench` on the idle machine, which runs the same workloads):
//! - compensation query: 0.99 µs → 0.97 µs median (the hybrid grew linear parts and a reversal
//!   lookup in between; the spindle MLP became a linear part).
//! - 8 h with diagonals at 1 ms: 1.03 s → 0.34 s (the thermal network no longer steps to every
//!   1 ms sample: 8.4 G → 3.9 G instructions under callgrind).
//! - default campaign, 3 seeds: ≈ 23 s → 15.0 s wall (the campaign also grew a 7th calibration
//!   cycle and bidirectional sweeps).

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

use vmc_machine::machine::MachineSpec;
use vmc_machine::thermal::Activity;
use vmc_machine::twin::Twin;
use vmc_twin::predict::controller::{Compensator, Controller};
use vmc_twin::predict::dataset::Dataset;
use vmc_twin::predict::predictor::{self, AnyPredictor, Settings};
use vmc_twin::studies::calibration::{self, CampaignConfig, ThermalCycle};

/// The reference machine and its calibration dataset (machine seed 1).
fn reference_calibration() -> (MachineSpec, Dataset) {
    let spec = MachineSpec::reference();
    let data = calibration::calibrate(
        &spec,
        &ThermalCycle::calibration_plan(&spec),
        &CampaignConfig::new(1),
    )
    .unwrap();
    (spec, data)
}

fn compensation_query(c: &mut Criterion) {
    let (spec, data) = reference_calibration();
    let (model, _) = predictor::train_hybrid(
        &data,
        &spec.geometry(),
        &Settings {
            seed: 1,
            ..Settings::default()
        },
    )
    .unwrap();
    let names: Vec<String> = spec.sensors.iter().map(|s| s.name.clone()).collect();
    let mut comp = Compensator::for_machine(model, &names).unwrap();
    let temps: Vec<f64> = (0..names.len()).map(|i| 22.0 + 0.25 * i as f64).collect();
    comp.on_readings(0.0, &temps);
    let mut k = 0u64;
    c.bench_function("compensation_query", |b| {
        b.iter(|| {
            k = k.wrapping_add(1);
            let s = (k % 1000) as f64 * 0.5;
            black_box(comp.axis_command_mm(black_box([10.0 + s, 60.0 + 0.5 * s, -225.0])))
        })
    });
}

fn thermal_8h(c: &mut Criterion) {
    let spec = MachineSpec::reference();
    let duty = Activity {
        spindle_rpm: 8000.0,
        axis_pos_mm: [280.0, 200.0, -225.0],
        axis_speed_mm_per_min: [3000.0, 2000.0, 1000.0],
        coolant: false,
    };
    c.bench_function("thermal_8h", |b| {
        b.iter(|| {
            let mut twin = Twin::new(&spec, 1).unwrap();
            twin.advance(8.0 * 3600.0, &duty).unwrap();
            black_box(twin.sensor_readings())
        })
    });
}

fn machine_8h_with_diagonals(c: &mut Criterion) {
    let spec = MachineSpec::reference();
    let workload = vmc_twin::benchmark::workload_8h(&spec, 1.0).unwrap();
    let mut g = c.benchmark_group("machine_8h_with_diagonals");
    g.sample_size(10);
    g.bench_function("xy_every_30min_1ms", |b| {
        b.iter(|| black_box(vmc_twin::benchmark::run_8h(&spec, &workload).unwrap()))
    });
    g.finish();
}

fn campaign_one_seed(c: &mut Criterion) {
    let spec = MachineSpec::reference();
    let mut g = c.benchmark_group("campaign");
    g.sample_size(10);
    g.bench_function("one_seed", |b| {
        b.iter(|| {
            black_box(
                vmc_twin::studies::campaign::run_campaign(&spec, &[1], &Settings::default())
                    .unwrap()
                    .0
                    .runs
                    .len(),
            )
        })
    });
    g.finish();
}

/// One compensation query with each model class (the hybrid, the volumetric MLP, the linear
/// regression) through the same compensator, readings held.
fn compensation_query_per_kind(c: &mut Criterion) {
    let (spec, data) = reference_calibration();
    let settings = Settings {
        seed: 1,
        ..Settings::default()
    };
    let g = spec.geometry();
    let models = [
        AnyPredictor::Hybrid(predictor::train_hybrid(&data, &g, &settings).unwrap().0),
        AnyPredictor::Volumetric(predictor::train_volumetric(&data, &g, &settings).unwrap().0),
        AnyPredictor::Linear(predictor::train_linear(&data, &g, &settings).unwrap().0),
    ];
    let names: Vec<String> = spec.sensors.iter().map(|s| s.name.clone()).collect();
    let temps: Vec<f64> = (0..names.len()).map(|i| 22.0 + 0.25 * i as f64).collect();
    let mut group = c.benchmark_group("compensation_query_per_kind");
    for model in models {
        let kind = model.kind().name();
        let mut comp = Compensator::for_machine(model, &names).unwrap();
        comp.on_readings(0.0, &temps);
        let mut k = 0u64;
        group.bench_function(kind, |b| {
            b.iter(|| {
                k = k.wrapping_add(1);
                let s = (k % 1000) as f64 * 0.5;
                black_box(comp.axis_command_mm(black_box([10.0 + s, 60.0 + 0.5 * s, -225.0])))
            })
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    compensation_query,
    compensation_query_per_kind,
    thermal_8h,
    machine_8h_with_diagonals,
    campaign_one_seed
);
criterion_main!(benches);
