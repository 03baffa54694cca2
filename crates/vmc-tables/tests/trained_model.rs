//! Tables from a real hybrid model, loaded from its model-file text the way the application
//! loads `--model FILE`, against that model and against the live compensator of `vmc-predict`
//! (an independent implementation of the same correction: a fixed-point solve with the
//! reversal keyed on the commanded direction).

#[path = "../examples/support/synthetic.rs"]
mod synthetic;

use synthetic::{model_at_state, spec, REVERSAL_UM, TRAVEL_MM};
use vmc_predict::controller::{Compensator, Controller};
use vmc_predict::predictor::ErrorPredictor;
use vmc_tables::cec::parse_cec_program;
use vmc_tables::export::{cec_files, linuxcnc_files, CecExport, LinuxCncExport, Provenance};
use vmc_tables::linuxcnc::{parse_comp_file, CompFileType};
use vmc_tables::number::Direction;
use vmc_tables::sample::sample_tables;

#[test]
fn the_tables_of_a_loaded_hybrid_carry_its_reversal_and_its_error() {
    let mut model = model_at_state();
    let shift = model.negative_approach_shift_mm();
    // The model learned the reversal: REVERSAL_UM in size, its sign at the tool set by the
    // carriage's side of the chain (X and Y carry the workpiece, Z the tool).
    for k in 0..3 {
        assert!(
            (shift[k].abs() * 1e3 - REVERSAL_UM[k]).abs() < 0.2,
            "axis {k}: learned {} um",
            shift[k] * 1e3
        );
    }
    let set = sample_tables(&mut model, &spec()).unwrap();
    assert_eq!(set.reversal_shift_mm, shift);
    let files = linuxcnc_files(&set, &LinuxCncExport::default(), &Provenance::default()).unwrap();
    for k in 0..3 {
        let table = parse_comp_file(&files[k].contents, CompFileType::Trims).unwrap();
        let tol_mm = set.own[k].check.max_abs_um * 1e-3 + 1e-6;
        for i in 0..=50 {
            let [lo, hi] = TRAVEL_MM[k];
            let mut q = set.reference_mm;
            q[k] = lo + (hi - lo) * i as f64 / 50.0;
            let e = model.predict_error_mm(q)[k];
            let fwd = table.trim_mm(q[k], Direction::Positive);
            let rev = table.trim_mm(q[k], Direction::Negative);
            assert!(
                (fwd + e).abs() <= tol_mm,
                "axis {k} at {q:?}: {fwd} vs {}",
                -e
            );
            assert!((rev - fwd + shift[k]).abs() <= 1e-6, "axis {k} at {q:?}");
        }
    }
}

#[test]
fn the_cec_tables_of_a_loaded_hybrid_agree_with_the_live_compensator_on_the_axis_lines() {
    let mut model = model_at_state();
    let set = sample_tables(&mut model, &spec()).unwrap();
    let text = &cec_files(&set, &CecExport::default(), &Provenance::default()).unwrap()[0];
    let program = parse_cec_program(&text.contents).unwrap();
    let names = ["AX1", "AX2", "AX3"];
    for k in 0..3 {
        let worst_um = set.own[k].check.max_abs_um.max(
            set.cross
                .iter()
                .filter(|t| t.input_axis == k)
                .map(|t| t.check.max_abs_um)
                .fold(0.0, f64::max),
        );
        // Along axis k through the reference, up then down: the compensator infers the
        // direction from the commands, the tables are told it.
        let [lo, hi] = TRAVEL_MM[k];
        let mut start = set.reference_mm;
        start[k] = lo;
        let mut comp = Compensator::new(model.clone()).with_start_mm(start);
        let up = (1..=40).map(|i| lo + (hi - lo) * i as f64 / 40.0);
        let down = (0..40).rev().map(|i| lo + (hi - lo) * i as f64 / 40.0);
        for (n, x) in up.chain(down).enumerate() {
            let motion = if n < 40 {
                Direction::Positive
            } else {
                Direction::Negative
            };
            let mut p = set.reference_mm;
            p[k] = x;
            let q = comp.axis_command_mm(p);
            let dir_of = |a: &str| {
                if a == names[k] {
                    motion
                } else {
                    Direction::Positive
                }
            };
            for j in 0..3 {
                let table_mm = program.total_compensation_mm(
                    names[j],
                    |a| p[names.iter().position(|b| *b == a).unwrap()],
                    dir_of,
                );
                let diff_um = (table_mm - (q[j] - p[j])) * 1e3;
                // Interpolation, the 1 nm print and the fixed point's second order (< 1 nm).
                assert!(
                    diff_um.abs() <= worst_um + 3e-3,
                    "output {j} along {k} at {p:?} {motion:?}: {diff_um} um"
                );
            }
        }
    }
}
