//! Benchmark of the chatter check (`vmc-twin chatter`) on the example pocket.
//!
//! `cargo bench --bench chatter` — figures are recorded in docs/results.md.
//!
//! - `pocket_x1`, `pocket_x4`, `pocket_x16`: trajectories/pocket_chatter.ngc (26 feed moves,
//!   0.6 m of cutting path) cleared in 1, 4 and 16 levels of 1 mm (the program repeated with
//!   Z−1, Z−2, …), each level cutting fresh material: interpretation, the Z-map and engagement
//!   of every sample, the critical depths (computed once per stability key, so the deeper levels
//!   reuse them) and the verdicts.
//!
//! Figures, release build, 2-core machine while two other builds ran (criterion medians):
//! ×1 30 ms, ×4 68 ms, ×16 208 ms — after the first level about 12 ms per level of 26 moves
//! (5 µs per sample of the Z-map and engagement), the stability part (18 keys, 212 SDM
//! evaluations) paid once.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

use vmc_gcode::interp::{run_program, InterpConfig};
use vmc_machine::milling::ToolDynamics;
use vmc_twin::studies::chatter::stock_file::StockSpec;
use vmc_twin::studies::chatter::{check, ChatterOptions};

const PROGRAM: &str = include_str!("../trajectories/pocket_chatter.ngc");
const STOCK: &str = include_str!("../trajectories/pocket_chatter.stock.toml");

/// The example cleared in `levels` levels of 1 mm.
fn pocket(levels: usize) -> String {
    let body = PROGRAM
        .strip_suffix("M5\nM2\n")
        .expect("the example ends with M5 M2");
    let mut text = String::new();
    for level in 1..=levels {
        text.push_str(&body.replace("Z-1", &format!("Z-{level}")));
    }
    text + "M5\nM2\n"
}

fn chatter_check(c: &mut Criterion) {
    let stock = StockSpec::from_toml_str(STOCK, "stock").unwrap();
    let tool = ToolDynamics::benchmark();
    let mut group = c.benchmark_group("chatter");
    group.sample_size(10);
    for levels in [1, 4, 16] {
        let text = pocket(levels);
        group.bench_function(format!("pocket_x{levels}"), |b| {
            b.iter(|| {
                let moves = run_program(black_box(&text), &InterpConfig::default()).unwrap();
                let report =
                    check(&moves, &stock.stock, &tool, &ChatterOptions::default()).unwrap();
                assert_eq!(report.cuts.len(), 26 * levels);
                black_box(report)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, chatter_check);
criterion_main!(benches);
