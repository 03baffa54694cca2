//! Sampling a long plan must not allocate per sample: counted with a wrapping global allocator
//! (a separate test binary, so the counter sees only this test's thread).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use vmc_gcode::interp::{CanonKind, CanonMove};
use vmc_machine::motion::{plan, MotionLimits, DEFAULT_INTERPOLATION_CYCLE_S};

struct CountingAlloc;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: forwards every call unchanged to the system allocator; only counts allocations.
unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: same layout contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System.alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: CountingAlloc = CountingAlloc;

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
    let before = ALLOCATIONS.with(Cell::get);
    let mut count = 0usize;
    let mut x_sum_mm = 0.0;
    for s in p
        .sample(DEFAULT_INTERPOLATION_CYCLE_S)
        .expect("valid period")
    {
        count += 1;
        x_sum_mm += s.pos_mm[0];
    }
    let allocations = ALLOCATIONS.with(Cell::get) - before;
    assert!(count > 3_600_000, "{count} samples");
    assert!(x_sum_mm > 0.0);
    assert_eq!(
        allocations, 0,
        "{allocations} allocations for {count} samples"
    );
}
