//! The first-order sensitivity against the exact HTM model and against hand-derived cases.

use super::*;
use crate::errors::tests_support::trunnion;
use crate::errors::Parameter;
use crate::inverse::{linear_axes_for, nominal_linear_axes};

fn probe_pose(geom: &Geometry, c_deg: f64, a_deg: f64) -> Pose {
    Pose {
        linear_mm: nominal_linear_axes(geom, [c_deg, a_deg], Vector3::zeros()),
        rotary_deg: [c_deg, a_deg],
    }
}

/// Exact probe reading with one error of value `v`.
fn exact_reading(geom: &Geometry, pose: &Pose, c: &Component, v: f64) -> Vector3<f64> {
    let mut state = ErrorState::default();
    c.add_to(&mut state, v);
    let q = linear_axes_for(geom, pose.rotary_deg, Vector3::zeros(), &|_| state).unwrap();
    Vector3::from(q)
}

#[test]
fn every_single_error_column_matches_central_differences_of_the_exact_model() {
    let g = trunnion();
    let all = Component::all(&g);
    assert_eq!(all.len(), 49);
    let set = ParameterSet {
        params: all.iter().copied().map(Parameter::constant).collect(),
    };
    for (c_deg, a_deg) in [(0.0, 0.0), (37.0, -25.0), (160.0, -95.0), (290.0, 20.0)] {
        let pose = probe_pose(&g, c_deg, a_deg);
        let s = probe_sensitivity(&g, &pose, &set);
        for (j, comp) in all.iter().enumerate() {
            // Steps of 1 µm and 2 µrad: central differences then err by O(h²) ≈ 1e-9 relative.
            let h = if comp.is_angle() { 2e-6 } else { 1e-3 };
            let fd = (exact_reading(&g, &pose, comp, h) - exact_reading(&g, &pose, comp, -h))
                / (2.0 * h);
            let col = s.column(j);
            let scale = fd.norm().max(1.0);
            for i in 0..3 {
                assert!(
                    (col[i] - fd[i]).abs() < 1e-6 * scale,
                    "{} at C={c_deg} A={a_deg}: S = {} vs FD = {}",
                    comp.name(),
                    col.transpose(),
                    fd.transpose()
                );
            }
        }
    }
}

fn column(c: Component, c_deg: f64, a_deg: f64) -> Vector3<f64> {
    let g = trunnion();
    let set = ParameterSet {
        params: vec![Parameter::constant(c)],
    };
    let s = probe_sensitivity(&g, &probe_pose(&g, c_deg, a_deg), &set);
    Vector3::new(s[(0, 0)], s[(1, 0)], s[(2, 0)])
}

fn assert_close(got: Vector3<f64>, want: [f64; 3], what: &str) {
    for i in 0..3 {
        assert!((got[i] - want[i]).abs() < 1e-9, "{what}: {got} vs {want:?}");
    }
}

#[test]
fn hand_derived_columns() {
    // A longer stylus by 1 mm (E_ZT) is read as Z 1 mm lower, at any pose.
    assert_close(
        column(Component::Tool(2), 123.0, -40.0),
        [0.0, 0.0, -1.0],
        "E_ZT",
    );
    // A datum offset along table x turns with the table: C = 90° turns the table −90°, so
    // table x is bed −y.
    assert_close(
        column(Component::Workpiece(0), 90.0, 0.0),
        [0.0, -1.0, 0.0],
        "E_XW",
    );
    // A trunnion line offset along y carries everything on it: read 1 mm further in Y.
    let a = Component::Location {
        rotary: 1,
        axis: crate::chain::RotaryAxis::A,
        component: 1,
    };
    assert_close(column(a, 200.0, -70.0), [0.0, 1.0, 0.0], "E_Y0A");
    // Zero offset of C at C = A = 0: the sphere 150 mm from the C axis along x moves by
    // ε·150 along y.
    let c0c = Component::Location {
        rotary: 0,
        axis: crate::chain::RotaryAxis::C,
        component: 5,
    };
    assert_close(column(c0c, 0.0, 0.0), [0.0, 150.0, 0.0], "E_C0C");
    // Zero offset of A at C = A = 0: the sphere 150 mm above the A axis moves by −ε·150 in y.
    let a0a = Component::Location {
        rotary: 1,
        axis: crate::chain::RotaryAxis::A,
        component: 3,
    };
    assert_close(column(a0a, 0.0, 0.0), [0.0, -150.0, 0.0], "E_A0A");
    // X positioning error d moves the table (and sphere) by d: read at X + d.
    let exx = Component::Linear {
        axis: LinearAxis::X,
        component: 0,
    };
    assert_close(column(exx, 45.0, -10.0), [1.0, 0.0, 0.0], "E_XX");
    // Z pitch ε_yz with a 150 mm stylus moves the tip by −150·ε along x: read at X + 150·ε.
    let ebz = Component::Linear {
        axis: LinearAxis::Z,
        component: 4,
    };
    assert_close(column(ebz, 300.0, -20.0), [150.0, 0.0, 0.0], "E_BZ");
}

#[test]
fn the_first_order_model_of_a_realistic_state_is_within_a_few_nm_of_the_exact_one() {
    let g = trunnion();
    let mut state = ErrorState::default();
    for (k, c) in Component::all(&g).iter().enumerate() {
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        // 30 µm and 30 µrad (6″) everywhere: a badly built machine.
        c.add_to(&mut state, sign * if c.is_angle() { 3e-5 } else { 0.03 });
    }
    let pose = probe_pose(&g, 70.0, -60.0);
    let frames = Frames::new(&g, &pose);
    let jq_inv = frames.jq().try_inverse().unwrap();
    let first = -(jq_inv * frames.first_order_tip_error_mm(&g, &state));
    let exact =
        Vector3::from(linear_axes_for(&g, pose.rotary_deg, Vector3::zeros(), &|_| state).unwrap())
            - Vector3::from(pose.linear_mm);
    // Second order: ε²·arm + ε·δ ≈ (3e-5)²·500 + 3e-5·0.03·10 ≈ 1e-5 mm at most.
    assert!((first - exact).norm() < 2e-5, "{first} vs {exact}");
    assert!(exact.norm() > 0.05);
}
