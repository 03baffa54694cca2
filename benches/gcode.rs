//! The G-code path on a large program.
//!
//! `cargo bench --bench gcode` — a CAM-like finishing program of 1 MB (≈ 38,000 `G1` lines,
//! `vmc_twin::benchmark::finishing_program`): the interpreter alone, and interpreter + motion
//! planner (what `run` and `check` do before simulating). `vmc-twin bench` measures the same
//! workloads and times LinuxCNC's `rs274` on the same file beside them; figures in
//! docs/results.md.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

use vmc_gcode::interp::{run_program, InterpConfig};
use vmc_machine::machine::MachineSpec;
use vmc_machine::program::plan_source_unchecked;
use vmc_twin::benchmark::finishing_program;

fn gcode_1mb(c: &mut Criterion) {
    let (text, _) = finishing_program(1 << 20);
    let spec = MachineSpec::reference();
    let cfg = InterpConfig::default();
    let mut g = c.benchmark_group("gcode_1mb");
    g.sample_size(20);
    g.bench_function("interpret", |b| {
        b.iter(|| black_box(run_program(black_box(&text), &cfg).unwrap()))
    });
    g.bench_function("interpret_and_plan", |b| {
        b.iter(|| {
            black_box(
                plan_source_unchecked(black_box(&text), "f.ngc", &spec, spec.axes.home_mm).unwrap(),
            )
        })
    });
    g.finish();
}

criterion_group!(benches, gcode_1mb);
criterion_main!(benches);
