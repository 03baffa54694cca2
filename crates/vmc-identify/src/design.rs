//! Choosing which configurations to probe: D-optimal design on the sensitivity matrix.
//!
//! Each candidate configuration `i` contributes the information `S_iᵀ·S_i` (columns scaled as
//! in [`crate::identify`], over the parameters the whole candidate set can separate). A design
//! of K configurations is scored by `log det(Σ_i S_iᵀ S_i)`, which is the (negative) log volume
//! of the parameters' confidence ellipsoid. K are chosen greedily (each step the candidate with
//! the largest gain, `log det(I + S_i M⁻¹ S_iᵀ)` by the determinant lemma, starting from a tiny
//! ridge), then improved by exchanges (swap a chosen and an unchosen one while the score grows,
//! the best swap first). Ties go to the lower index: the result is deterministic.

use nalgebra::{DMatrix, Matrix3};

use crate::chain::Geometry;
use crate::errors::ParameterSet;
use crate::identify::{build_system, select, IdentifyError, Observation};

/// Why a design could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DesignError {
    /// K out of range.
    #[error("cannot choose {k} of {n} candidate configurations (need 1 ≤ K ≤ N)")]
    BadCount {
        /// K asked.
        k: usize,
        /// Candidates.
        n: usize,
    },
    /// A candidate is unusable.
    #[error(transparent)]
    Candidate(#[from] IdentifyError),
}

/// The chosen configurations and the score.
#[derive(Debug, Clone, PartialEq)]
pub struct Design {
    /// Chosen candidate indices, ascending.
    pub chosen: Vec<usize>,
    /// `log det` of the chosen information matrix (scaled parameters).
    pub log_det: f64,
    /// Exchanges made after the greedy pass.
    pub exchanges: usize,
}

fn log_det(m: &DMatrix<f64>) -> f64 {
    match m.clone().cholesky() {
        Some(c) => 2.0 * c.l().diagonal().iter().map(|d| d.ln()).sum::<f64>(),
        None => f64::NEG_INFINITY,
    }
}

/// Chooses `k` of the `candidates` (their `measured_mm` is not used; set `cov_mm2` to the
/// expected centre covariance or the identity) maximising the D-criterion.
///
/// # Errors
/// [`DesignError`] for a bad `k` or a bad candidate.
pub fn d_optimal(
    geom: &Geometry,
    set: &ParameterSet,
    candidates: &[Observation],
    k: usize,
) -> Result<Design, DesignError> {
    let n = candidates.len();
    if k == 0 || k > n {
        return Err(DesignError::BadCount { k, n });
    }
    let sys = build_system(geom, set, candidates)?;
    let sel = select(&sys.a, set, 1e-6);
    let p = sel.kept.len();
    let blocks: Vec<DMatrix<f64>> = (0..n)
        .map(|i| {
            DMatrix::from_fn(3, p, |r, c| {
                sys.a[(3 * i + r, sel.kept[c])] / sel.scale[sel.kept[c]]
            })
        })
        .collect();
    let infos: Vec<DMatrix<f64>> = blocks.iter().map(|b| b.transpose() * b).collect();
    let total: f64 = infos.iter().map(|m| m.trace()).sum();
    let ridge = DMatrix::identity(p, p) * (1e-9 * total / (p.max(1) * n) as f64);
    let mut m = ridge.clone();
    let mut chosen: Vec<usize> = Vec::with_capacity(k);
    let mut used = vec![false; n];
    for _ in 0..k {
        let m_inv = m
            .clone()
            .try_inverse()
            .unwrap_or_else(|| DMatrix::identity(p, p));
        let mut best = (f64::NEG_INFINITY, 0);
        for i in (0..n).filter(|&i| !used[i]) {
            let g = Matrix3::identity() + {
                let x = &blocks[i] * &m_inv * blocks[i].transpose();
                Matrix3::from_fn(|r, c| x[(r, c)])
            };
            let gain = g.determinant().ln();
            if gain > best.0 {
                best = (gain, i);
            }
        }
        used[best.1] = true;
        chosen.push(best.1);
        m += &infos[best.1];
    }
    let mut score = log_det(&m);
    let mut exchanges = 0;
    for _ in 0..100 {
        let mut best = (score, None);
        for (slot, &i) in chosen.iter().enumerate() {
            let without = &m - &infos[i];
            for j in (0..n).filter(|&j| !used[j]) {
                let s = log_det(&(&without + &infos[j]));
                if s > best.0 + 1e-9 * score.abs().max(1.0) {
                    best = (s, Some((slot, j)));
                }
            }
        }
        let Some((slot, j)) = best.1 else { break };
        let i = chosen[slot];
        m = &m - &infos[i] + &infos[j];
        used[i] = false;
        used[j] = true;
        chosen[slot] = j;
        score = best.0;
        exchanges += 1;
    }
    chosen.sort_unstable();
    Ok(Design {
        chosen,
        log_det: score,
        exchanges,
    })
}
