//! The compensation query: the library's path against the compiled model.
//!
//! `cargo bench -p vmc-predict --bench compiled` — figures in the decision record
//! `docs/decisions/2026-11-28-compiled-model.md`.
//!
//! The model: a hybrid with the reference machine's features (12 sensors, the ambient history,
//! the spindle nose rate, the axis feeds), every residual net kept, trained on the synthetic
//! calibration data of `tests/common` with 6 or 10 hidden units. The query: the commanded
//! position moving as along a diagonal (as `vmc-twin bench`), one set of readings held.
//!
//! - `query/*`: one compensation (the fixed point `q = p − E(q, T)` with the reversal):
//!   `library` = `Compensator<HybridPredictor>` (today's path), `compiled` =
//!   `CompiledCompensator` (fused solve; the AVX2 + FMA code where the CPU has it),
//!   `compiled_portable` = the same with the portable code, `compiled_unfused` =
//!   `Compensator<CompiledHybrid>` (compiled evaluations, every iterate fresh).
//! - `evaluation/*`: one prediction `E(q, T)`.
//! - `activations/*`: three nets of 10 units: libm `exp` on 30 units against the kernel on 36
//!   (padded; portable code), fresh and fresh + moved.
//! - `synthesis`: the first-order synthesis alone.
//! - `readings_stage/*`: a new set of readings observed and the first query after it.
//!
//! Figures (release, the 2-core machine shared with other builds at load 8, criterion medians;
//! every figure about twice its idle value — the library's query is 0.73–0.86 µs idle), 6 / 10
//! hidden units:
//! - query: library 983 / 1,722 ns; compiled 343 / 509 ns; compiled portable 573 / 1,312 ns;
//!   compiled unfused 421 / 790 ns.
//! - evaluation: library 382 / 805 ns; compiled 194 / 274 ns.
//! - readings stage: library 2.71 / 3.41 µs; compiled 2.33 / 3.01 µs.
//! - activations: libm 30 units 354 ns; kernel (portable) 36 units 308 ns, fresh + moved 640 ns.
//! - synthesis: 44 ns.
//!
//! The load-robust figure (minimum over 400 batches of 2,000 queries, same machine): compiled
//! 0.20 / 0.25 µs against the library's 0.55 / 0.76 µs. Steps and analysis:
//! docs/decisions/2026-11-28-compiled-model.md.

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::hint::black_box;

use vmc_predict::compiled::{kernel, CompiledCompensator, CompiledHybrid};
use vmc_predict::controller::{Compensator, Controller};
use vmc_predict::predictor::{ErrorPredictor, HybridPredictor};
use vmc_predict::synthesis::{first_order_error_mm, ElementaryErrors};

/// The positions of `vmc-twin bench`: along a diagonal, back to the start every 1000 queries.
#[inline(always)]
fn position(k: u64) -> [f64; 3] {
    let s = (k % 1000) as f64 * 0.5;
    [10.0 + s, 60.0 + 0.5 * s, -225.0]
}

/// The held readings of `vmc-twin bench`.
fn readings() -> Vec<f64> {
    (0..common::SENSORS.len())
        .map(|i| 22.0 + 0.25 * i as f64)
        .collect()
}

fn bench_controller<C: Controller>(c: &mut Criterion, group: &str, id: BenchmarkId, ctl: &mut C) {
    ctl.on_readings(0.0, &readings());
    let mut k = 0u64;
    c.benchmark_group(group).bench_function(id, |b| {
        b.iter(|| {
            k = k.wrapping_add(1);
            black_box(ctl.axis_command_mm(black_box(position(k))))
        })
    });
}

fn bench_predictor<P: ErrorPredictor>(c: &mut Criterion, id: BenchmarkId, p: &mut P) {
    p.observe_readings(0.0, &readings());
    let mut k = 0u64;
    c.benchmark_group("evaluation").bench_function(id, |b| {
        b.iter(|| {
            k = k.wrapping_add(1);
            black_box(p.predict_error_mm(black_box(position(k))))
        })
    });
}

fn queries(c: &mut Criterion) {
    for hidden in [6, 10] {
        let model: HybridPredictor = common::trained(hidden);
        let compiled = CompiledHybrid::from_predictor(&model).expect("compiles");
        let id = |name: &str| BenchmarkId::new(name, format!("{hidden}_hidden"));
        bench_controller(
            c,
            "query",
            id("library"),
            &mut Compensator::new(model.clone()),
        );
        bench_controller(
            c,
            "query",
            id("compiled"),
            &mut CompiledCompensator::new(compiled.clone()),
        );
        bench_controller(
            c,
            "query",
            id("compiled_portable"),
            &mut CompiledCompensator::new(compiled.clone().with_portable_code()),
        );
        bench_controller(
            c,
            "query",
            id("compiled_unfused"),
            &mut Compensator::new(compiled.clone()),
        );
        bench_predictor(c, id("library"), &mut model.clone());
        bench_predictor(c, id("compiled"), &mut compiled.clone());
        let mut group = c.benchmark_group("readings_stage");
        let temps = [readings(), readings().iter().map(|t| t + 0.5).collect()];
        let mut lib = model.clone();
        let mut fast = compiled.clone();
        let mut n = 0u32;
        group.bench_function(id("library"), |b| {
            b.iter(|| {
                n = n.wrapping_add(1);
                lib.observe_readings(f64::from(n), &temps[(n % 2) as usize]);
                black_box(lib.predict_error_mm(position(u64::from(n))))
            })
        });
        group.bench_function(id("compiled"), |b| {
            b.iter(|| {
                n = n.wrapping_add(1);
                fast.observe_readings(f64::from(n), &temps[(n % 2) as usize]);
                black_box(fast.predict_error_mm(position(u64::from(n))))
            })
        });
        group.finish();
    }
}

fn activations(c: &mut Criterion) {
    // Three nets of 10 units (the kernel works on 12, padded), arguments over the tanh's range.
    let s: Vec<f64> = (0..36).map(|j| -2.5 + 0.14 * f64::from(j)).collect();
    let lanes = |s: &[f64]| -> Vec<kernel::Lane> {
        s.chunks_exact(4)
            .map(|c| kernel::Lane([c[0], c[1], c[2], c[3]]))
            .collect()
    };
    let (s_lanes, moved) = (
        lanes(&s),
        lanes(&s.iter().map(|v| v + 1e-4).collect::<Vec<_>>()),
    );
    let mut group = c.benchmark_group("activations");
    group.bench_function("libm_exp_30_units", |b| {
        let mut a = [0.0; 30];
        b.iter(|| {
            for (a, s) in a.iter_mut().zip(black_box(&s)) {
                *a = 1.0 - 2.0 / ((2.0 * s).exp() + 1.0);
            }
            black_box(a[29])
        })
    });
    let (mut e, mut a) = (
        vec![kernel::Lane::default(); 9],
        vec![kernel::Lane::default(); 9],
    );
    group.bench_function("kernel_36_units", |b| {
        b.iter(|| {
            kernel::exp2_tanh_block(black_box(&s_lanes), &mut e, &mut a);
            black_box(a[8])
        })
    });
    group.bench_function("kernel_move_36_units", |b| {
        b.iter(|| {
            kernel::exp2_tanh_block(&s_lanes, &mut e, &mut a);
            kernel::move_exp2_block(black_box(&s_lanes), &moved, &mut e, &mut a);
            black_box(a[8])
        })
    });
    group.finish();
}

fn synthesis(c: &mut Criterion) {
    let g = common::geometry();
    let mut e = ElementaryErrors::default();
    for (k, axis) in e.axes.iter_mut().enumerate() {
        axis.lin_mm = [1e-3 * k as f64, 2e-3, -3e-3];
        axis.ang_rad = [1e-6, -2e-6 * k as f64, 3e-6];
    }
    let mut k = 0u64;
    c.bench_function("synthesis", |b| {
        b.iter(|| {
            k = k.wrapping_add(1);
            black_box(first_order_error_mm(
                &g,
                black_box(position(k)),
                black_box(&e),
            ))
        })
    });
}

criterion_group!(benches, queries, activations, synthesis);
criterion_main!(benches);
