//! Sampling a long plan must not allocate per sample: counted with a wrapping global allocator
//! (a separate test binary, so the counter sees only this test's thread).

#[path = "../crates/vmc-predict/tests/common/counting_alloc.rs"]
mod counting_alloc;

use counting_alloc::allocations;
use vmc_gcode::interp::{CanonKind, CanonMove};
use vmc_machine::motion::{plan, MotionLimits, DEFAULT_INTERPOLATION_CYCLE_S};

#[test]
fn sampling_a_one_hour_program_at_1_ms_does_not_allocate_per_sample() {
    let moves = [
        CanonMove {
            line: 1,
            kind: CanonKind::Feed {
                end_mm: [100.0, 50.0, 0.0],
                feed_mm_per_min: 3000.0,
                end_abc_deg: [0.0; 3],
            },
        },
        CanonMove {
            line: 2,
            kind: CanonKind::Dwell { duration_s: 3600.0 },
        },
        CanonMove {
            line: 3,
            kind: CanonKind::Traverse {
                end_mm: [0.0; 3],
                end_abc_deg: [0.0; 3],
            },
        },
    ];
    let p = plan(&moves, [0.0; 3], &MotionLimits::default()).expect("valid program");
    let before = allocations();
    let mut count = 0usize;
    let mut x_sum_mm = 0.0;
    for s in p
        .sample(DEFAULT_INTERPOLATION_CYCLE_S)
        .expect("valid period")
    {
        count += 1;
        x_sum_mm += s.pos_mm[0];
    }
    let allocations = allocations() - before;
    assert!(count > 3_600_000, "{count} samples");
    assert!(x_sum_mm > 0.0);
    assert_eq!(
        allocations, 0,
        "{allocations} allocations for {count} samples"
    );
}
