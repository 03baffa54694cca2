//! Dominant eigenvalues of a large real matrix by the Arnoldi method.
//!
//! The monodromy matrices of a finely semi-discretised delay equation are large (one row per
//! delayed sample) but their spectrum is that of a delay equation: a few multipliers of
//! modulus near the spectral radius and a cloud accumulating at 0. A Krylov space of a few
//! dozen vectors captures the outer ones, at O(k·N²) instead of the O(N³) of a full
//! eigenvalue decomposition.
//!
//! Method: Arnoldi with modified Gram–Schmidt, orthogonalised twice (Daniel–Gragg–Kaufman–
//! Stewart), from a fixed start vector with every entry nonzero (no random draw: results are
//! reproducible bit for bit). At Krylov dimensions 24, 48, 96, … (up to half the matrix) the
//! Ritz values are taken from the Hessenberg matrix, and the answer is accepted when every
//! Ritz value of modulus at least [`CLUSTER`] × the largest has a residual
//! |h_{k+1,k}|·|e_kᵀy|/‖y‖ ≤ [`RESIDUAL`] × the largest modulus. Otherwise the caller falls
//! back to the full decomposition (`None`).

use nalgebra::{Complex, DMatrix, DVector};

/// Ritz values within this fraction of the largest modulus must all have converged.
const CLUSTER: f64 = 0.8;
/// Largest accepted residual, relative to the largest modulus.
const RESIDUAL: f64 = 1e-10;
/// The first Krylov dimension checked.
const FIRST_CHECK: usize = 24;

/// The eigenvalue of largest modulus of the square matrix `a` (ties towards positive imaginary
/// part), or `None` when the Krylov space up to half the matrix's size does not converge it.
pub fn dominant_eigenvalue(a: &DMatrix<f64>) -> Option<Complex<f64>> {
    let n = a.nrows();
    let k_max = n / 2;
    if k_max < FIRST_CHECK {
        return None;
    }
    let scale = a
        .iter()
        .fold(0.0_f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    let mut v: Vec<DVector<f64>> = Vec::with_capacity(k_max + 1);
    let start = DVector::from_fn(n, |i, _| 1.0 + 0.5 * ((i as f64) * 0.618_033_988_75).sin());
    v.push(start.normalize());
    let mut h = DMatrix::zeros(k_max + 1, k_max);
    let mut check = FIRST_CHECK;
    for j in 0..k_max {
        let mut w = a * &v[j];
        for _ in 0..2 {
            for (i, vi) in v.iter().enumerate() {
                let c = vi.dot(&w);
                h[(i, j)] += c;
                w.axpy(-c, vi, 1.0);
            }
        }
        let beta = w.norm();
        h[(j + 1, j)] = beta;
        let k = j + 1;
        let invariant = beta <= 1e-14 * scale * (n as f64).sqrt();
        if invariant || k == check {
            let hk = h.view((0, 0), (k, k)).into_owned();
            if let Some(mu) = converged(&hk, if invariant { 0.0 } else { beta }) {
                return Some(mu);
            }
            if invariant {
                return None;
            }
            check *= 2;
        }
        v.push(w / beta);
    }
    None
}

/// The largest-modulus value of a list (ties towards positive imaginary part).
pub fn largest(values: &[Complex<f64>]) -> Complex<f64> {
    let mut best = Complex::new(0.0, 0.0);
    for &mu in values {
        let better = mu.norm() > best.norm() * (1.0 + 1e-12)
            || (mu.norm() >= best.norm() * (1.0 - 1e-12) && mu.im > best.im);
        if better {
            best = mu;
        }
    }
    best
}

/// The largest Ritz value of `hk` when the outer ones have converged (`beta` = h_{k+1,k}).
fn converged(hk: &DMatrix<f64>, beta: f64) -> Option<Complex<f64>> {
    let ritz: Vec<Complex<f64>> = hk.complex_eigenvalues().iter().copied().collect();
    let best = largest(&ritz);
    let top = best.norm();
    if top == 0.0 || !top.is_finite() {
        return None;
    }
    for &mu in ritz.iter().filter(|mu| mu.norm() >= CLUSTER * top) {
        let y = ritz_vector(hk, mu)?;
        let last = y[y.len() - 1].norm();
        if beta * last > RESIDUAL * top {
            return None;
        }
    }
    Some(best)
}

/// Unit eigenvector of `hk` for the Ritz value `mu`, by two steps of inverse iteration.
fn ritz_vector(hk: &DMatrix<f64>, mu: Complex<f64>) -> Option<DVector<Complex<f64>>> {
    let k = hk.nrows();
    // A tiny shift off the eigenvalue keeps the factorisation regular.
    let shift = mu + Complex::new(1e-12, 1e-12) * mu.norm().max(1e-300);
    let m = DMatrix::from_fn(k, k, |i, j| {
        let d = if i == j {
            shift
        } else {
            Complex::new(0.0, 0.0)
        };
        Complex::new(hk[(i, j)], 0.0) - d
    });
    let lu = m.lu();
    let mut y = DVector::from_element(k, Complex::new(1.0, 0.0));
    for _ in 0..2 {
        y = lu.solve(&y)?;
        let norm = y.norm();
        if !norm.is_finite() || norm == 0.0 {
            return None;
        }
        y /= Complex::new(norm, 0.0);
    }
    Some(y)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A block-diagonal matrix with known eigenvalues (2×2 rotation-scaling blocks and a
    /// decaying real tail), hidden by an orthogonal similarity.
    fn hidden(blocks: &[(f64, f64)], tail: usize) -> (DMatrix<f64>, f64) {
        let n = 2 * blocks.len() + tail;
        let mut d = DMatrix::zeros(n, n);
        for (b, &(r, th)) in blocks.iter().enumerate() {
            let (s, c) = th.sin_cos();
            let i = 2 * b;
            d[(i, i)] = r * c;
            d[(i, i + 1)] = -r * s;
            d[(i + 1, i)] = r * s;
            d[(i + 1, i + 1)] = r * c;
        }
        for t in 0..tail {
            let i = 2 * blocks.len() + t;
            d[(i, i)] = 0.3 / (1.0 + t as f64);
        }
        // A fixed dense orthogonal matrix from the QR of a deterministic one.
        let q = DMatrix::from_fn(n, n, |i, j| ((i * 7 + j * 13) as f64 * 0.37).sin())
            .qr()
            .q();
        let top = blocks.iter().map(|b| b.0).fold(0.3, f64::max);
        (&q * d * q.transpose(), top)
    }

    #[test]
    fn the_dominant_pair_of_a_hidden_spectrum_is_found_to_rounding() {
        let (a, top) = hidden(&[(0.95, 0.4), (1.02, 2.1), (0.7, 1.0), (0.99, 2.9)], 150);
        let mu = dominant_eigenvalue(&a).expect("converges");
        assert!((mu.norm() - top).abs() < 1e-10, "{mu}");
        assert!((mu.arg() - 2.1).abs() < 1e-9, "{mu}");
        let all: Vec<Complex<f64>> = a.complex_eigenvalues().iter().copied().collect();
        let dense = largest(&all);
        assert!((dense - mu).norm() < 1e-10, "{dense} vs {mu}");
    }

    #[test]
    fn small_matrices_are_left_to_the_full_decomposition() {
        let (a, _) = hidden(&[(0.9, 1.0)], 20);
        assert!(dominant_eigenvalue(&a).is_none());
    }
}
