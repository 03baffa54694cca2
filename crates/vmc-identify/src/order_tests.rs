//! Order selection on synthetic probing data from the exact model.

use super::*;
use crate::errors::tests_support::trunnion;
use crate::identify::tests::{observe, spread, Rng};

/// Location and assembly errors of tens of µm/µrad, plus harmonics of the rotary motion errors
/// up to `orders` (per axis) of about 1.5 µm and 6 µrad.
fn truth_with(orders: &[u32], rng: &mut Rng) -> (ParameterSet, Vec<f64>) {
    let g = trunnion();
    let set = parameter_set(&g, orders);
    let values = set
        .params
        .iter()
        .map(|p| {
            let x = 2.0 * rng.uniform() - 1.0;
            match (p.harmonic.is_some(), p.component.is_angle()) {
                (false, true) => 3e-5 * x,
                (false, false) => 0.03 * x,
                (true, true) => 6e-6 * x,
                (true, false) => 1.5e-3 * x,
            }
        })
        .collect();
    (set, values)
}

fn chosen_for(orders: &[u32], seed: u64) -> OrderChoice {
    let mut rng = Rng(seed);
    let (set, values) = truth_with(orders, &mut rng);
    let obs = observe(&set, &values, &spread(60, None), 1.25e-4, &mut rng);
    choose_order(&trunnion(), &obs, &OrderOptions::default()).unwrap()
}

#[test]
fn third_order_errors_of_the_c_table_alone_are_found_as_such() {
    for seed in [3, 4] {
        let c = chosen_for(&[3, 0], seed);
        assert_eq!(c.orders, vec![3, 0], "seed {seed}: {:?}", c.candidates);
    }
}

#[test]
fn without_motion_errors_the_location_model_is_chosen() {
    let c = chosen_for(&[0, 0], 5);
    assert_eq!(c.orders, vec![0, 0], "{:?}", c.candidates);
    assert_eq!(c.candidates.len(), 25);
    assert_eq!(c.candidates[c.chosen].n_params, 19);
}

#[test]
fn the_choice_depends_on_the_seed_only_through_the_folds_and_is_repeatable() {
    let a = chosen_for(&[2, 2], 6);
    let b = chosen_for(&[2, 2], 6);
    assert_eq!(a, b);
    assert_eq!(a.orders, vec![2, 2], "{:?}", a.candidates);
}

#[test]
fn fewer_configurations_than_folds_is_an_error() {
    let mut rng = Rng(1);
    let (set, values) = truth_with(&[0, 0], &mut rng);
    let obs = observe(&set, &values, &spread(3, None), 1.25e-4, &mut rng);
    let e = choose_order(&trunnion(), &obs, &OrderOptions::default()).unwrap_err();
    assert!(
        e.to_string().contains("3 configurations in 5 folds")
            && e.to_string().contains("need at least 9 configurations"),
        "{e}"
    );
}

#[test]
fn the_shuffle_is_a_permutation() {
    let mut v = shuffled(50, 9);
    assert_ne!(v, (0..50).collect::<Vec<_>>());
    v.sort_unstable();
    assert_eq!(v, (0..50).collect::<Vec<_>>());
}
