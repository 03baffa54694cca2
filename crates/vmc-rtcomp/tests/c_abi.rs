//! The C functions against the library: a controller's servo loop driven through
//! `vmc_comp_update` gives the corrections the library's compensator (`Compensator` over the
//! `HybridPredictor`, not the compiled model) gives for the same samples and commands.

#[path = "../../vmc-predict/tests/common/mod.rs"]
mod common;

use std::ffi::CStr;

use vmc_predict::controller::{Compensator, Controller};
use vmc_predict::predictor::{train_hybrid, HybridPredictor};
use vmc_rtcomp::ffi::{
    vmc_comp_free, vmc_comp_n_sensors, vmc_comp_new, vmc_comp_new_err, vmc_comp_sensor_name,
    vmc_comp_set_tool_offset, vmc_comp_update,
};
use vmc_rtcomp::{Inputs, Outputs, RtComp, Status};

/// 1e-9 mm: the agreement asked of the component with the library.
const SAME_MM: f64 = 1e-9;

/// The reference machine's features with the spindle speed as an input, 6 units per net.
fn model() -> HybridPredictor {
    let ds = common::dataset(&[4.0, 7.0, 5.5, 3.0], 11);
    let settings = common::reference_like_settings(6).with_spindle_speed_input();
    train_hybrid(&ds, &common::geometry(), &settings)
        .expect("trains")
        .0
}

/// The commands of the servo loop at `t_s`: a path back and forth in X, Y, Z (reversals every
/// few seconds), its axis speeds, and a spindle that runs in bursts within a sensor period.
fn commands(t_s: f64) -> ([f64; 3], [f64; 3], f64) {
    let w = [0.9, 0.7, 0.5];
    let amp = [200.0, 150.0, 100.0];
    let p = [
        280.0 + amp[0] * (w[0] * t_s).sin(),
        200.0 + amp[1] * (w[1] * t_s).cos(),
        -225.0 + amp[2] * (w[2] * t_s).sin(),
    ];
    let v = [
        amp[0] * w[0] * (w[0] * t_s).cos() * 60.0,
        -amp[1] * w[1] * (w[1] * t_s).sin() * 60.0,
        amp[2] * w[2] * (w[2] * t_s).cos() * 60.0,
    ];
    let rpm = if (t_s % 3.0) < 1.3 { 8000.0 } else { 0.0 };
    (p, v, rpm)
}

fn inputs(t_s: f64, temps: Option<&[f64]>) -> Inputs {
    let (p, v, rpm) = commands(t_s);
    Inputs {
        temps_degc: temps.map_or(std::ptr::null(), <[f64]>::as_ptr),
        n_temps: temps.map_or(0, <[f64]>::len),
        time_s: t_s,
        commanded_mm: p,
        spindle_rpm: rpm,
        axis_feed_mm_per_min: v,
        new_sample: i32::from(temps.is_some()),
    }
}

#[test]
fn the_servo_loop_through_the_c_functions_gives_the_librarys_corrections() {
    let model = model();
    let text = model.to_json_string().expect("serialises");
    // SAFETY: a valid text of `len` bytes; the handle is freed at the end, used by this thread.
    let comp = unsafe { vmc_comp_new(text.as_ptr(), text.len()) };
    assert!(!comp.is_null());
    // SAFETY: a live handle.
    assert_eq!(unsafe { vmc_comp_n_sensors(comp) }, 12);
    // SAFETY: a live handle; the name lives as long as it.
    let name = unsafe { CStr::from_ptr(vmc_comp_sensor_name(comp, 11)) };
    assert_eq!(name.to_str(), Ok("Amb"));
    // SAFETY: a live handle.
    assert!(unsafe { vmc_comp_sensor_name(comp, 12) }.is_null());

    let mut lib = Compensator::new(model);
    // The servo period and the sensor period, s; 20 minutes of machine time.
    let (dt_s, per_sample) = (0.05, 20);
    // The library gets the commands averaged over each sensor period, each period's command
    // (as sent) held over it: what the component does.
    let (mut rpm_s, mut feeds_s, mut span_s) = (0.0, [0.0; 3], 0.0);
    let mut sent: Option<Inputs> = None;
    let mut worst: f64 = 0.0;
    let mut statuses = [0usize; 3];
    for n in 0..24_000u32 {
        let t_s = f64::from(n) * dt_s;
        if let Some(prev) = sent {
            let dt = t_s - prev.time_s;
            rpm_s += prev.spindle_rpm * dt;
            for (f, v) in feeds_s.iter_mut().zip(prev.axis_feed_mm_per_min) {
                *f += v.abs() * dt;
            }
            span_s += dt;
        }
        // The first sample comes after ten periods: no readings before.
        let sample = n >= 10 && n % per_sample == 10;
        let temps = sample.then(|| common::temps_degc(6.0, t_s + 3600.0));
        let input = inputs(t_s, temps.as_deref());
        sent = Some(input);
        let mut out = Outputs::default();
        // SAFETY: a live handle; `input` and its readings outlive the call.
        let status = unsafe { vmc_comp_update(comp, &input, &mut out) };
        assert_eq!(status, out.status);
        if let Some(temps) = &temps {
            let (mean_rpm, mean_feeds) = if span_s > 0.0 {
                (rpm_s / span_s, feeds_s.map(|f| f / span_s))
            } else {
                (input.spindle_rpm, input.axis_feed_mm_per_min.map(f64::abs))
            };
            lib.on_readings(t_s, temps);
            lib.on_spindle_speed(t_s, mean_rpm);
            lib.on_axis_feeds(t_s, mean_feeds);
            (rpm_s, feeds_s, span_s) = (0.0, [0.0; 3], 0.0);
        }
        let p = input.commanded_mm;
        let q = lib.axis_command_mm(p);
        if n < 10 {
            assert_eq!(status, Status::NoReadings as i32);
            assert_eq!(out.correction_mm, [0.0; 3]);
            continue;
        }
        statuses[usize::from(status != Status::Ok as i32)] += 1;
        assert_eq!(out.iterations as usize, lib.last_solve().iterations);
        for k in 0..3 {
            worst = worst.max((out.correction_mm[k] - (q[k] - p[k])).abs());
        }
    }
    assert!(worst < SAME_MM, "worst difference {worst:e} mm");
    assert_eq!(statuses[1], 0, "every period converged");
    // SAFETY: a live handle, freed once.
    unsafe { vmc_comp_free(comp) };
}

#[test]
fn bad_input_gives_zero_corrections_and_takes_nothing() {
    let text = model().to_json_string().expect("serialises");
    // SAFETY: a valid text; freed at the end.
    let comp = unsafe { vmc_comp_new(text.as_ptr(), text.len()) };
    let temps = common::temps_degc(5.0, 3600.0);
    let mut out = Outputs {
        correction_mm: [9.0; 3],
        ..Outputs::default()
    };
    let bad = Status::BadInput as i32;
    let good = inputs(1.0, Some(&temps));
    let cases = [
        Inputs {
            n_temps: 11,
            ..good
        },
        Inputs {
            temps_degc: std::ptr::null(),
            ..good
        },
        Inputs {
            time_s: f64::NAN,
            ..good
        },
        Inputs {
            commanded_mm: [1.0, f64::INFINITY, 0.0],
            ..good
        },
        Inputs {
            spindle_rpm: f64::NAN,
            ..good
        },
    ];
    for case in &cases {
        // SAFETY: a live handle; pointers valid or null.
        assert_eq!(unsafe { vmc_comp_update(comp, case, &mut out) }, bad);
        assert_eq!(out.correction_mm, [0.0; 3]);
    }
    // Nothing was taken: still no readings.
    let held = inputs(1.0, None);
    // SAFETY: as above.
    assert_eq!(
        unsafe { vmc_comp_update(comp, &held, &mut out) },
        Status::NoReadings as i32
    );
    // Null pointers anywhere.
    // SAFETY: null pointers are allowed.
    unsafe {
        assert_eq!(vmc_comp_update(std::ptr::null_mut(), &good, &mut out), bad);
        assert_eq!(vmc_comp_update(comp, std::ptr::null(), &mut out), bad);
        assert_eq!(vmc_comp_update(comp, &good, std::ptr::null_mut()), 0);
        assert_eq!(vmc_comp_n_sensors(std::ptr::null()), 0);
        assert!(vmc_comp_sensor_name(std::ptr::null(), 0).is_null());
        assert_eq!(vmc_comp_set_tool_offset(comp, 0.0, f64::NAN, -100.0), bad);
        assert_eq!(vmc_comp_set_tool_offset(comp, 0.0, 0.0, -100.0), 0);
        vmc_comp_free(std::ptr::null_mut());
    }
    // A failed sensor (a NaN reading) gives no correction, and so says.
    let mut broken = temps.clone();
    broken[3] = f64::NAN;
    let sample = inputs(2.0, Some(&broken));
    // SAFETY: as above.
    assert_eq!(
        unsafe { vmc_comp_update(comp, &sample, &mut out) },
        Status::NotFinite as i32
    );
    assert_eq!(out.correction_mm, [0.0; 3]);
    // SAFETY: freed once.
    unsafe { vmc_comp_free(comp) };
}

#[test]
fn a_model_that_cannot_be_compiled_is_refused_with_its_reason() {
    // The linear baseline learns from volumetric records: add some (any smooth values).
    let mut ds = common::dataset(&[4.0, 7.0], 2);
    let laser: Vec<_> = ds.records.iter().step_by(3).cloned().collect();
    for (i, mut r) in laser.into_iter().enumerate() {
        let f = i as f64;
        r.instrument = vmc_predict::dataset::Instrument::Volumetric;
        r.pos_mm = [
            (f * 37.0) % 560.0,
            (f * 53.0) % 400.0,
            -((f * 71.0) % 450.0),
        ];
        r.values = [
            0.01 * r.pos_mm[0] + r.temps_degc[0],
            0.02 * r.pos_mm[1] - r.temps_degc[1],
            0.005 * r.pos_mm[2],
            f64::NAN,
            f64::NAN,
            f64::NAN,
        ];
        ds.records.push(r);
    }
    let settings = vmc_predict::predictor::Settings {
        hidden_candidates: vec![6],
        max_epochs: 5,
        ..Default::default()
    };
    let (linear, _) =
        vmc_predict::predictor::train_linear(&ds, &common::geometry(), &settings).expect("trains");
    let text = linear.to_json_string().expect("serialises");
    let mut err = [0 as std::ffi::c_char; 64];
    // SAFETY: a valid text; `err` has 64 writable bytes.
    let comp = unsafe { vmc_comp_new_err(text.as_ptr(), text.len(), err.as_mut_ptr(), 64) };
    assert!(comp.is_null());
    // SAFETY: NUL-terminated within the 64 bytes by contract.
    let message = unsafe { CStr::from_ptr(err.as_ptr()) }.to_string_lossy();
    assert_eq!(message.len(), 63, "cut to fit: {message}");
    assert!(
        message.starts_with("a `linear` model cannot be compiled"),
        "{message}"
    );
    // Not UTF-8, not JSON, null.
    let junk = [0xff_u8, 0xfe];
    // SAFETY: valid pointers of the given lengths, or null.
    unsafe {
        assert!(vmc_comp_new(junk.as_ptr(), 2).is_null());
        assert!(vmc_comp_new(b"{}".as_ptr(), 2).is_null());
        assert!(vmc_comp_new(std::ptr::null(), 10).is_null());
    }
    assert!(RtComp::new("{ not json").is_err());
}
