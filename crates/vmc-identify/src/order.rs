//! The order of the rotary motion-error model, chosen from the probing data by cross-validation
//! over configurations.
//!
//! # Model family
//! The location and assembly errors are always fitted; each rotary axis `r` adds the cos/sin
//! harmonics up to `h_r` of its six motion errors ([`ParameterSet::with_motion_harmonics_per_axis`]:
//! orders 1…`h_r` of the angular positioning error, 2…`h_r` of the translations and tilts, whose
//! first harmonic is part of the average line; `h_r = 0` adds none). The candidates are every
//! combination of `h_r ∈ {0, 1, …, max_order}` over the rotary axes (25 for two axes and
//! `max_order = 4`).
//!
//! # Criterion
//! K-fold cross-validation over *configurations* (the three readings of one configuration stay
//! together): the configurations are shuffled with an explicit seed and dealt into `folds`
//! groups; each candidate is fitted by the first-order weighted least squares of
//! [`crate::identify`] (same whitening, column scaling and rank selection) on all folds but one,
//! and predicts the readings of the held-out fold. The score is the mean squared whitened
//! prediction error per reading (1 = probe noise). A candidate whose training folds give no more
//! readings than parameters cannot be scored.
//!
//! The chosen order is the candidate with the fewest parameters whose score is within one
//! standard error (over folds) of the best score — the one-standard-error rule: among models the
//! data cannot tell apart, the smallest, since a larger one spends the same data on more
//! parameters and so varies more away from the probed configurations. Nothing here sees the
//! machine's truth: only the probing observations and the nominal geometry.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::chain::Geometry;
use crate::errors::ParameterSet;
use crate::identify::{build_system, placements_in, select, IdentifyError, Observation};

/// Settings of [`choose_order`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrderOptions {
    /// Highest harmonic order tried on each rotary axis (default 4).
    pub max_order: u32,
    /// Number of cross-validation folds (default 5; at least 2).
    pub folds: usize,
    /// Seed of the shuffle of configurations into folds.
    pub seed: u64,
    /// Rank tolerance of the fits (as [`crate::identify::IdentifyOptions::rank_tol`]).
    pub rank_tol: f64,
}

impl Default for OrderOptions {
    fn default() -> Self {
        OrderOptions {
            max_order: 4,
            folds: 5,
            seed: 1,
            rank_tol: 1e-6,
        }
    }
}

/// One candidate order and its cross-validated score.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// Highest harmonic order per rotary axis ([`Geometry::rotary`] order; 0 = none).
    pub orders: Vec<u32>,
    /// Number of parameters of the set.
    pub n_params: usize,
    /// Mean squared whitened prediction error per held-out reading (`None`: too few readings
    /// in a training fold).
    pub cv_score: Option<f64>,
    /// Standard error of that mean over the folds.
    pub cv_std_error: Option<f64>,
}

/// The candidates and the one chosen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OrderChoice {
    /// Highest harmonic order per rotary axis of the chosen model.
    pub orders: Vec<u32>,
    /// Index of the chosen candidate in `candidates`.
    pub chosen: usize,
    /// Index of the candidate of lowest score.
    pub best: usize,
    /// Every candidate, fewest parameters first.
    pub candidates: Vec<Candidate>,
    /// Folds used.
    pub folds: usize,
    /// Seed of the fold shuffle.
    pub seed: u64,
}

/// The parameter set of a candidate: location and assembly errors plus the harmonics of
/// `orders`.
#[must_use]
pub fn parameter_set(geom: &Geometry, orders: &[u32]) -> ParameterSet {
    ParameterSet::location_and_assembly(geom).with_motion_harmonics_per_axis(geom, orders)
}

/// Every combination of orders `{0, 1, …, max_order}` over `n_axes` rotary axes.
fn candidate_orders(n_axes: usize, max_order: u32) -> Vec<Vec<u32>> {
    let levels: Vec<u32> = (0..=max_order).collect();
    let mut out = vec![Vec::new()];
    for _ in 0..n_axes {
        out = out
            .into_iter()
            .flat_map(|prefix| {
                levels.iter().map(move |&h| {
                    let mut v = prefix.clone();
                    v.push(h);
                    v
                })
            })
            .collect();
    }
    out
}

/// A deterministic permutation of `0..n` (Fisher–Yates driven by SplitMix64 from `seed`).
fn shuffled(n: usize, seed: u64) -> Vec<usize> {
    let mut state = seed ^ 0x0cde_5e1e_c700_0001;
    let mut next = || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let mut v: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let j = (next() % (i as u64 + 1)) as usize;
        v.swap(i, j);
    }
    v
}

/// Sum of squared whitened prediction errors on `test` configurations of the model of columns
/// `cols` fitted on `train` configurations; `None` when the training readings are too few.
fn fold_error(
    a: &DMatrix<f64>,
    b: &nalgebra::DVector<f64>,
    cols: &[usize],
    set: &ParameterSet,
    train: &[usize],
    test: &[usize],
    rank_tol: f64,
) -> Option<f64> {
    let rows = |cfgs: &[usize]| -> Vec<usize> {
        cfgs.iter()
            .flat_map(|&i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect()
    };
    let (tr, te) = (rows(train), rows(test));
    if tr.len() <= cols.len() {
        return None;
    }
    let a_tr = DMatrix::from_fn(tr.len(), cols.len(), |r, c| a[(tr[r], cols[c])]);
    let sel = select(&a_tr, set, rank_tol);
    let k = sel.kept.len();
    let ak = DMatrix::from_fn(tr.len(), k, |r, c| {
        a_tr[(r, sel.kept[c])] / sel.scale[sel.kept[c]]
    });
    let b_tr = nalgebra::DVector::from_fn(tr.len(), |r, _| b[tr[r]]);
    let xs = ak.svd(true, true).solve(&b_tr, 1e-14).ok()?;
    let mut sse = 0.0;
    for &r in &te {
        let pred: f64 = sel
            .kept
            .iter()
            .enumerate()
            .map(|(c, &j)| a[(r, cols[j])] * xs[c] / sel.scale[j])
            .sum();
        sse += (b[r] - pred).powi(2);
    }
    Some(sse)
}

/// Chooses the harmonic orders of the rotary motion errors by cross-validation over the
/// configurations (see the module doc).
///
/// # Errors
/// [`IdentifyError::BadObservation`] for a bad covariance or value;
/// [`IdentifyError::TooFewToChooseOrder`] when the training folds cannot fit even the
/// location and assembly errors.
pub fn choose_order(
    geom: &Geometry,
    obs: &[Observation],
    opts: &OrderOptions,
) -> Result<OrderChoice, IdentifyError> {
    let folds = opts.folds.max(2);
    let placements = placements_in(obs);
    let base = parameter_set(geom, &[]).with_placements(placements).len();
    // The smallest training set is n − ⌈n/folds⌉ configurations; the smallest model needs
    // more readings than parameters.
    let trainable = |n: usize| 3 * (n - n.div_ceil(folds)) > base;
    let too_few = || IdentifyError::TooFewToChooseOrder {
        n_configs: obs.len(),
        folds,
        n_params: base,
        needed: (folds..).find(|&n| trainable(n)).unwrap_or(folds),
    };
    if obs.len() < folds || !trainable(obs.len()) {
        return Err(too_few());
    }
    let n_axes = geom.rotary.len();
    let largest = parameter_set(geom, &vec![opts.max_order; n_axes]).with_placements(placements);
    let sys = build_system(geom, &largest, obs)?;
    let all_names = largest.names();
    let order = shuffled(obs.len(), opts.seed);
    let mut candidates = Vec::new();
    for orders in candidate_orders(n_axes, opts.max_order) {
        let set = parameter_set(geom, &orders).with_placements(placements);
        let cols: Vec<usize> = set
            .names()
            .iter()
            .map(|n| all_names.iter().position(|m| m == n).unwrap_or(0))
            .collect();
        let mut per_fold = Vec::with_capacity(folds);
        for f in 0..folds {
            let (test, train): (Vec<usize>, Vec<usize>) =
                (0..obs.len()).partition(|&i| i % folds == f);
            let test: Vec<usize> = test.iter().map(|&i| order[i]).collect();
            let train: Vec<usize> = train.iter().map(|&i| order[i]).collect();
            match fold_error(&sys.a, &sys.b, &cols, &set, &train, &test, opts.rank_tol) {
                Some(sse) => per_fold.push(sse / (3 * test.len()) as f64),
                None => break,
            }
        }
        let (score, se) = if per_fold.len() == folds {
            let m = per_fold.iter().sum::<f64>() / folds as f64;
            let var = per_fold.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (folds - 1) as f64;
            (Some(m), Some((var / folds as f64).sqrt()))
        } else {
            (None, None)
        };
        candidates.push(Candidate {
            orders,
            n_params: set.len(),
            cv_score: score,
            cv_std_error: se,
        });
    }
    // Fewest parameters first (stable: ties keep the lower orders of the first axis first).
    candidates.sort_by_key(|c| c.n_params);
    let best = candidates
        .iter()
        .enumerate()
        .filter_map(|(i, c)| c.cv_score.map(|s| (i, s)))
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .map(|(i, _)| i)
        .ok_or_else(too_few)?;
    let limit = candidates[best].cv_score.unwrap_or(f64::INFINITY)
        + candidates[best].cv_std_error.unwrap_or(0.0);
    let chosen = candidates
        .iter()
        .position(|c| c.cv_score.is_some_and(|s| s <= limit))
        .unwrap_or(best);
    Ok(OrderChoice {
        orders: candidates[chosen].orders.clone(),
        chosen,
        best,
        candidates,
        folds,
        seed: opts.seed,
    })
}

#[cfg(test)]
#[path = "order_tests.rs"]
mod tests;
