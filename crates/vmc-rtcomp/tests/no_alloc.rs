//! `vmc_comp_update` and the helpers allocate nothing once the handle exists (a counting global
//! allocator; its own test binary, so it counts only this test's work).

#[path = "../../vmc-predict/tests/common/mod.rs"]
mod common;
#[path = "../../vmc-predict/tests/common/counting_alloc.rs"]
mod counting_alloc;

use counting_alloc::allocations;

use vmc_rtcomp::ffi::{
    vmc_comp_free, vmc_comp_n_sensors, vmc_comp_new, vmc_comp_sensor_name,
    vmc_comp_set_tool_offset, vmc_comp_update,
};
use vmc_rtcomp::{Inputs, Outputs};

#[test]
fn the_servo_path_allocates_nothing() {
    let text = common::trained(10).to_json_string().expect("serialises");
    // SAFETY: a valid text; freed at the end; this thread only.
    let comp = unsafe { vmc_comp_new(text.as_ptr(), text.len()) };
    assert!(!comp.is_null());
    // The test's own readings and inputs, made before counting.
    let samples: Vec<Vec<f64>> = (0..30)
        .map(|k| common::temps_degc(6.0, 120.0 * f64::from(k)))
        .collect();
    let mut broken = samples[0].clone();
    broken[0] = f64::NAN;
    let mut out = Outputs::default();
    let before = allocations();
    let mut sum = 0.0;
    for n in 0..30_000u32 {
        let t_s = f64::from(n) * 0.001;
        let s = f64::from(n % 2000);
        let s = if s < 1000.0 { s } else { 2000.0 - s } * 0.3;
        let sample = n % 1000 == 0;
        let temps: &[f64] = match n {
            29_000 => &broken,
            _ => &samples[(n / 1000) as usize],
        };
        let input = Inputs {
            temps_degc: temps.as_ptr(),
            n_temps: if n == 15_500 { 3 } else { temps.len() },
            time_s: t_s,
            commanded_mm: [10.0 + s, 60.0 + 0.5 * s, -225.0],
            spindle_rpm: if n % 4000 < 2000 { 9000.0 } else { 0.0 },
            axis_feed_mm_per_min: [18_000.0, 9_000.0, 0.0],
            new_sample: i32::from(sample || n == 15_500),
        };
        // SAFETY: a live handle; `input` and its readings outlive the call.
        unsafe {
            vmc_comp_update(comp, &input, &mut out);
            sum += out.correction_mm[0] + vmc_comp_n_sensors(comp) as f64;
            assert!(!vmc_comp_sensor_name(comp, 3).is_null());
            if n == 20_000 {
                assert_eq!(vmc_comp_set_tool_offset(comp, 0.0, 0.0, -120.0), 0);
                assert_eq!(vmc_comp_set_tool_offset(comp, f64::NAN, 0.0, -120.0), -1);
            }
        }
    }
    let after = allocations();
    assert!(sum.is_finite());
    assert_eq!(after - before, 0, "the servo path allocated");
    // SAFETY: freed once.
    unsafe { vmc_comp_free(comp) };
}
