//! The compiled model allocates nothing after it is built: observations, the readings stage,
//! predictions and compensations, under a counting global allocator (its own test binary, so
//! the allocator counts only this test's work).

mod common;
#[path = "common/counting_alloc.rs"]
mod counting_alloc;

use std::hint::black_box;

use counting_alloc::allocations;
use vmc_predict::compiled::{CompiledCompensator, CompiledHybrid, InputError};
use vmc_predict::controller::Controller;
use vmc_predict::predictor::ErrorPredictor;

#[test]
fn the_counter_sees_an_allocation() {
    let before = allocations();
    black_box(vec![1.0_f64; 16]);
    assert_eq!(allocations() - before, 1);
}

#[test]
fn observing_predicting_and_compensating_allocate_nothing() {
    let model = CompiledHybrid::from_predictor(&common::trained(10)).expect("compiles");
    assert_eq!(model.hidden_units(), [10; 3]);
    let mut comp = CompiledCompensator::new(model);
    let wrong = [20.0; 3];
    // The test's own readings, made before counting.
    let samples: Vec<Vec<f64>> = (0..40)
        .map(|n| common::temps_degc(6.0, f64::from(n) * 250.0))
        .collect();
    let before = allocations();
    let mut acc = 0.0;
    for i in 0..20_000_u32 {
        if i % 500 == 0 {
            // A sensor sample: readings, speed and feeds; the readings stage runs at the next
            // query.
            let t_s = f64::from(i) * 0.5;
            let (rpm, feeds) = common::commands(6.0, t_s);
            comp.on_readings(t_s, &samples[(i / 500) as usize]);
            comp.on_spindle_speed(t_s, rpm);
            comp.on_axis_feeds(t_s, feeds);
            // A refused observation returns its error by value.
            assert_eq!(
                comp.try_on_readings(t_s, &wrong),
                Err(InputError::ReadingCount {
                    expected: 12,
                    got: 3
                })
            );
        }
        // Back and forth along a diagonal: every axis reverses now and then.
        let s = f64::from(i % 1000);
        let s = if s < 500.0 { s } else { 1000.0 - s };
        let p = [10.0 + s, 60.0 + 0.5 * s, -225.0 - 0.2 * s];
        let q = comp.axis_command_mm(black_box(p));
        acc += q[0] + comp.model_mut().predict_error_mm(p)[2];
        if i == 10_000 {
            comp.on_tool_change([0.0, 0.0, -120.0])
                .expect("a finite tool");
        }
    }
    let after = allocations();
    assert!(acc.is_finite());
    assert!(comp.last_solve().converged);
    assert_eq!(after - before, 0, "the compiled model allocated");
}
