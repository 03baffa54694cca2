use super::*;
use crate::sample::{sample_tables, AxisTravel, SamplingSpec};
use crate::testmodel::{Analytic, TRAVEL_MM};
use vmc_predict::controller::Compensator;

fn spec() -> SamplingSpec {
    SamplingSpec::new(TRAVEL_MM.map(|[min_mm, max_mm]| AxisTravel { min_mm, max_mm }))
}

const T_DEGC: f64 = 24.0;

fn frozen(scope: TableScope) -> TableCompensator {
    let set = sample_tables(&mut Analytic::at(T_DEGC), &spec()).unwrap();
    TableCompensator::new(set, scope)
}

/// The live compensator on the same model, at the same reading.
fn live() -> Compensator<Analytic> {
    let mut c = Compensator::new(Analytic::new());
    c.on_readings(0.0, &[T_DEGC]);
    c
}

/// Largest interpolation error of the set's tables, mm, plus 1 nm of quantisation and 1 nm for
/// the lookup at `p` instead of the fixed point (module doc: ≈ 0.5 nm).
fn interpolation_bound_mm(set: &TableSet) -> f64 {
    let own = set.own.iter().map(|t| t.check.max_abs_um);
    let cross = set.cross.iter().map(|t| t.check.max_abs_um);
    // Two tables add up per output axis along an axis line; three on a diagonal.
    3.0 * own.chain(cross).fold(0.0, f64::max) * 1e-3 + 2e-6
}

/// The body diagonal PPP through the test machine's travel, `n` points, positive motion.
fn diagonal(n: usize) -> Vec<[f64; 3]> {
    (0..n)
        .map(|i| {
            let f = i as f64 / (n - 1) as f64;
            std::array::from_fn(|k| TRAVEL_MM[k][0] + f * (TRAVEL_MM[k][1] - TRAVEL_MM[k][0]))
        })
        .collect()
}

#[test]
fn own_and_cross_tables_reproduce_the_live_correction_on_a_diagonal_but_for_the_two_axis_term() {
    let mut tab = frozen(TableScope::OwnAndCross);
    let bound = interpolation_bound_mm(tab.tables());
    let mut live = live();
    for p in diagonal(57) {
        let c_tab: [f64; 3] = std::array::from_fn(|k| tab.axis_command_mm(p)[k] - p[k]);
        let c_live: [f64; 3] = std::array::from_fn(|k| live.axis_command_mm(p)[k] - p[k]);
        // The model's only term that depends on two positions at once: no sum of one-axis
        // tables carries it (the analytic model's module doc).
        let two_axis_mm = [1e-8 * (p[0] - 280.0) * (p[1] - 200.0), 0.0, 0.0];
        for k in 0..3 {
            let diff = c_tab[k] - (c_live[k] + two_axis_mm[k]);
            assert!(
                diff.abs() <= bound,
                "axis {k} at {p:?}: {diff} mm > {bound} mm"
            );
        }
    }
    assert!(
        bound < 0.1e-3,
        "the 10 mm tables follow the model to {bound} mm"
    );
}

#[test]
fn per_joint_tables_lose_what_the_cross_terms_carry() {
    let mut own = frozen(TableScope::OwnAxis);
    let mut all = frozen(TableScope::OwnAndCross);
    let mut live = live();
    let (mut own_worst_mm, mut all_worst_mm) = ([0.0f64; 3], [0.0f64; 3]);
    for p in diagonal(57) {
        let q_live = live.axis_command_mm(p);
        let (q_own, q_all) = (own.axis_command_mm(p), all.axis_command_mm(p));
        for k in 0..3 {
            own_worst_mm[k] = own_worst_mm[k].max((q_own[k] - q_live[k]).abs());
            all_worst_mm[k] = all_worst_mm[k].max((q_all[k] - q_live[k]).abs());
        }
    }
    // Ey = 3e-3·sin(x/150) + …: a Y error along X, 3 µm peak to peak-ish over the X travel,
    // that a Y joint table cannot see; the cross table Y(X) carries it.
    assert!(own_worst_mm[1] > 2e-3, "per-joint Y: {own_worst_mm:?}");
    assert!(all_worst_mm[1] < 0.05e-3, "own+cross Y: {all_worst_mm:?}");
    // Ez's 4e-6·x is a cross term too: 1.1 µm from the reference to the ends of the diagonal.
    // (Ex's 1e-5·y − 1e-5·z cancel along this diagonal, where y and z rise together.)
    assert!(
        own_worst_mm[2] > all_worst_mm[2] + 1e-3,
        "{own_worst_mm:?} {all_worst_mm:?}"
    );
}

#[test]
fn a_negative_motion_takes_the_reverse_column_as_the_live_compensator_takes_its_reversal() {
    for scope in [TableScope::OwnAxis, TableScope::OwnAndCross] {
        let mut tab = frozen(scope);
        let mut live = live();
        let p = [300.0, 150.0, -100.0];
        let back = [250.0, 120.0, -100.0];
        for c in [&mut tab as &mut dyn Controller, &mut live] {
            c.on_commanded_motion([200.0, 100.0, -100.0], p);
        }
        let (tab_fwd, live_fwd) = (tab.axis_command_mm(p), live.axis_command_mm(p));
        for c in [&mut tab as &mut dyn Controller, &mut live] {
            c.on_commanded_motion(p, back);
            c.on_commanded_motion(back, p);
        }
        // Back at p, but X and Y arrived moving positive again: the forward column.
        assert_eq!(tab.axis_command_mm(p), tab_fwd);
        for c in [&mut tab as &mut dyn Controller, &mut live] {
            c.on_commanded_motion(p, [350.0, 200.0, -100.0]);
            c.on_commanded_motion([350.0, 200.0, -100.0], p);
        }
        let (tab_rev, live_rev) = (tab.axis_command_mm(p), live.axis_command_mm(p));
        // X and Y reached p moving negative, Z did not move: the same change as the live
        // compensator's reversal, −r on X and Y, none on Z, to the 1 nm of the tables.
        for k in 0..3 {
            let tab_step = tab_rev[k] - tab_fwd[k];
            let live_step = live_rev[k] - live_fwd[k];
            assert!((tab_step - live_step).abs() <= 1.5e-6, "{scope:?} axis {k}");
        }
        assert!((tab_rev[0] - tab_fwd[0] + 0.5e-3).abs() <= 1.5e-6);
        assert!((tab_rev[1] - tab_fwd[1] - 0.6e-3).abs() <= 1.5e-6);
        assert_eq!(tab_rev[2], tab_fwd[2]);
    }
}

#[test]
fn frozen_tables_ignore_new_readings_where_the_live_compensator_follows_them() {
    let mut tab = frozen(TableScope::OwnAndCross);
    let mut live = live();
    let p = [100.0, 300.0, -400.0];
    let (tab_before, live_before) = (tab.axis_command_mm(p), live.axis_command_mm(p));
    for c in [&mut tab as &mut dyn Controller, &mut live] {
        c.on_readings(3600.0, &[30.0]);
        c.on_spindle_speed(3600.0, 8000.0);
        c.on_axis_feeds(3600.0, [3000.0; 3]);
    }
    assert_eq!(tab.axis_command_mm(p), tab_before);
    // 6 °C warmer: Ex grows by 6 µm, Ez by 9 µm in the live model (to 1 nm: the fixed point
    // moves by 9 µm in Z, which Ex's 1e-5·z sees as 0.09 nm).
    let live_after = live.axis_command_mm(p);
    assert!((live_after[0] - live_before[0] + 6e-3).abs() < 1e-6);
    assert!((live_after[2] - live_before[2] + 9e-3).abs() < 1e-6);
}

#[test]
fn a_tool_change_is_refused_with_the_reason() {
    let mut tab = frozen(TableScope::OwnAxis);
    let e = tab.on_tool_change([0.0, 0.0, -120.0]).unwrap_err();
    assert!(e.contains("needs tables sampled for that tool"), "{e}");
}
