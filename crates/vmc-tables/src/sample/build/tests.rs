use super::super::{AxisTravel, Spacing};
use super::*;
use crate::testmodel::{Analytic, TRAVEL_MM};

fn spec() -> SamplingSpec {
    SamplingSpec::new(TRAVEL_MM.map(|[min_mm, max_mm]| AxisTravel { min_mm, max_mm }))
}

/// 1 nm quantisation, half of it either way, plus float noise.
const NM: f64 = 0.5e-6 + 1e-12;

#[test]
fn the_default_spacing_gives_at_most_10_mm_between_points() {
    let s = spec();
    let grids = check_spec(&s).unwrap();
    assert_eq!(grids.map(|g| g.points), [57, 41, 46]);
    assert_eq!(grids.map(|g| g.step_mm), [10.0, 10.0, 10.0]);
    assert_eq!(grids[2].start_mm, -450.0);
    assert_eq!(grids[2].end_mm(), 0.0);
    assert_eq!(s.reference_mm, [280.0, 200.0, -225.0]);
}

#[test]
fn the_own_axis_tables_hold_minus_the_model_error_and_the_reversal() {
    let mut m = Analytic::at(24.0);
    let set = sample_tables(&mut m, &spec()).unwrap();
    let r = set.reference_mm;
    for t in &set.own {
        let k = t.axis;
        for (i, x) in t.grid.positions_mm().into_iter().enumerate() {
            let mut q = r;
            q[k] = x;
            let e = Analytic::error_mm(q, 24.0)[k];
            assert!((t.forward_mm[i] + e).abs() <= NM, "axis {k} at {x}");
            let rev = -(e + m.shift_mm[k]);
            assert!((t.reverse_mm[i] - rev).abs() <= NM, "axis {k} at {x}");
        }
    }
    assert_eq!(set.reversal_shift_mm, m.shift_mm);
}

#[test]
fn a_cross_table_is_zero_at_the_reference_and_follows_the_other_axis_error() {
    let mut m = Analytic::at(24.0);
    let set = sample_tables(&mut m, &spec()).unwrap();
    assert_eq!(set.cross.len(), 6);
    let pairs: Vec<(usize, usize)> = set
        .cross
        .iter()
        .map(|t| (t.output_axis, t.input_axis))
        .collect();
    assert_eq!(pairs, [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)]);
    // Y along X: −(3e-3 sin(x/150) − 3e-3 sin(280/150)).
    let t = &set.cross[2];
    for (i, x) in t.grid.positions_mm().into_iter().enumerate() {
        let want = -3e-3 * ((x / 150.0).sin() - (280.0f64 / 150.0).sin());
        assert!((t.correction_mm[i] - want).abs() <= NM, "at {x}");
    }
    assert_eq!(t.correction_mm[28], 0.0, "x = 280 mm is the reference");
}

#[test]
fn the_interpolation_check_finds_the_quarter_curvature_times_step_squared_of_a_parabola() {
    // Along X, Ex = 2e-7 (x − 280)² at the reference: linear interpolation over a step h
    // errs by a·h²/4 in the middle of each interval, 2e-7 × 80² / 4 mm = 0.32 µm for 8 points.
    let mut s = spec();
    s.spacing = Spacing::Points(8);
    let set = sample_tables(&mut Analytic::at(20.0), &s).unwrap();
    let c = set.own[0].check;
    assert!((c.max_abs_um - 0.32).abs() < 1e-3, "{c:?}");
    assert_eq!(c.samples, 7 * 16 + 1);
    // Half-way between two points.
    assert!(((c.at_mm / 80.0).fract() - 0.5).abs() < 1e-9, "{c:?}");
}

#[test]
fn the_volume_check_reports_what_only_cross_tables_and_two_axis_terms_carry() {
    let set = sample_tables(&mut Analytic::at(20.0), &spec()).unwrap();
    let v = set.volume;
    assert_eq!(v.points, 729);
    // Own-axis tables only: Ex keeps 1e-5 (y − 200) − 1e-5 (z + 225) + 1e-8 (x − 280)(y − 200),
    // largest at (560, 400, −450): 2 + 2.25 + 0.56 = 4.81 µm.
    assert!((v.own_axis_only.max_abs_um[0] - 4.81).abs() < 0.01, "{v:?}");
    // With the cross tables only the product term is left: 1e-8 × 280 × 200 mm = 0.56 µm, plus
    // interpolation errors of a few nanometres.
    assert!((v.own_and_cross.max_abs_um[0] - 0.56).abs() < 0.01, "{v:?}");
    // Ey and Ez are sums of one-axis terms: the cross tables take them to the interpolation
    // error.
    assert!(v.own_and_cross.max_abs_um[1] < 0.01, "{v:?}");
    assert!(v.own_and_cross.max_abs_um[2] < 0.01, "{v:?}");
    assert!(v.own_axis_only.max_abs_um[2] > 1.0, "{v:?}");
}

#[test]
fn a_warmer_state_shifts_the_tables_by_the_models_thermal_term() {
    let cool = sample_tables(&mut Analytic::at(20.0), &spec()).unwrap();
    let warm = sample_tables(&mut Analytic::at(26.0), &spec()).unwrap();
    for (a, b) in cool.own[0].forward_mm.iter().zip(&warm.own[0].forward_mm) {
        assert!((b - a + 6e-3).abs() <= 2.0 * NM);
    }
    for (a, b) in cool.own[2].forward_mm.iter().zip(&warm.own[2].forward_mm) {
        assert!((b - a + 9e-3).abs() <= 2.0 * NM);
    }
}

#[test]
fn a_model_without_readings_is_refused() {
    let err = sample_tables(&mut Analytic::new(), &spec()).unwrap_err();
    assert!(matches!(err, SampleError::NoPrediction { .. }), "{err:?}");
    assert!(err.to_string().contains("observed the sensor readings"));
}

#[test]
fn unusable_specifications_are_refused() {
    let mut s = spec();
    s.reference_mm[2] = 10.0;
    assert!(matches!(
        sample_tables(&mut Analytic::at(20.0), &s).unwrap_err(),
        SampleError::ReferenceOutsideTravel { axis: "Z", .. }
    ));
    let mut s = spec();
    s.spacing = Spacing::MaxStepMm(1.0);
    let err = sample_tables(&mut Analytic::at(20.0), &s).unwrap_err();
    assert!(
        matches!(
            err,
            SampleError::PointCount {
                axis: "X",
                points: 561,
                max: 256,
                ..
            }
        ),
        "{err:?}"
    );
    let mut s = spec();
    s.spacing = Spacing::Points(1);
    assert!(sample_tables(&mut Analytic::at(20.0), &s).is_err());
    let mut s = spec();
    s.travel[1] = AxisTravel {
        min_mm: 5.0,
        max_mm: 5.0,
    };
    assert!(matches!(
        sample_tables(&mut Analytic::at(20.0), &s).unwrap_err(),
        SampleError::BadTravel { axis: "Y", .. }
    ));
    let mut s = spec();
    s.check_subdivisions = 0;
    assert!(sample_tables(&mut Analytic::at(20.0), &s).is_err());
    let mut m = Analytic::at(20.0);
    m.shift_mm[1] = f64::NAN;
    assert!(matches!(
        sample_tables(&mut m, &spec()).unwrap_err(),
        SampleError::BadReversal { .. }
    ));
}

#[test]
fn a_step_is_rounded_to_the_nanometre_and_the_grid_stays_within_half_a_nanometre_per_point() {
    let g = Grid::over(
        0,
        AxisTravel {
            min_mm: 0.0,
            max_mm: 560.0,
        },
        100,
    )
    .unwrap();
    assert_eq!(g.step_mm, 5.656566);
    assert!((g.end_mm() - 560.0).abs() <= 99.0 * 0.5e-6);
    let max_step = Grid::with_spacing(
        0,
        AxisTravel {
            min_mm: 0.0,
            max_mm: 560.0,
        },
        Spacing::MaxStepMm(7.0),
    )
    .unwrap();
    assert_eq!(max_step.points, 81);
}
