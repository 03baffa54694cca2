//! Continuous algebraic Riccati equations AᵀX + XA − XGX + Q = 0 (G, Q symmetric).
//!
//! Method: the stabilising solution spans the stable invariant subspace [I; X] of the
//! Hamiltonian H = [[A, −G], [−Q, −Aᵀ]]. The matrix sign function W = sign(H) (Newton
//! iteration Z ← (Z/c + c Z⁻¹)/2 with determinant scaling c = |det Z|^(1/2n)) has
//! (W + I)[I; X] = 0, so X is the least-squares solution of [W₁₂; W₂₂ + I] X = −[W₁₁ + I; W₂₁].
//! Newton–Kleinman steps then refine it: with A_cl = A − G X and the residual R(X), solve the
//! Lyapunov equation A_clᵀ Δ + Δ A_cl = −R(X) (Kronecker form, fine for the few tens of states
//! of a blade model) and set X ← X + Δ. The solution is accepted when A − G X is Hurwitz and
//! the relative residual ‖R‖_F / (‖AᵀX‖_F + ‖XA‖_F + ‖XGX‖_F + ‖Q‖_F) is below 1e-9.
//!
//! LQR: G = B R⁻¹ Bᵀ, Q ≥ 0. Kalman filter: the dual, A → Aᵀ, G = Cᵀ V⁻¹ C, Q = B W Bᵀ.
//! H∞ uses indefinite G (see [`super::hinf`]).

use nalgebra::DMatrix;

use super::ControlError;

/// Largest relative residual accepted.
pub const MAX_RELATIVE_RESIDUAL: f64 = 1e-9;

/// A solved Riccati equation.
#[derive(Debug, Clone, PartialEq)]
pub struct CareSolution {
    /// The stabilising solution X (symmetric).
    pub x: DMatrix<f64>,
    /// Relative residual ‖R(X)‖_F / (‖AᵀX‖_F + ‖XA‖_F + ‖XGX‖_F + ‖Q‖_F).
    pub relative_residual: f64,
}

/// Residual R(X) = AᵀX + XA − XGX + Q and its relative size.
pub fn residual(
    a: &DMatrix<f64>,
    g: &DMatrix<f64>,
    q: &DMatrix<f64>,
    x: &DMatrix<f64>,
) -> (DMatrix<f64>, f64) {
    let atx = a.transpose() * x;
    let xa = x * a;
    let xgx = x * g * x;
    let r = &atx + &xa - &xgx + q;
    let scale = atx.norm() + xa.norm() + xgx.norm() + q.norm();
    let rel = if scale > 0.0 { r.norm() / scale } else { 0.0 };
    (r, rel)
}

/// Solves A X + X Aᵀ… in the form Fᵀ Δ + Δ F = −R by the Kronecker product (n² unknowns).
pub fn lyapunov(f: &DMatrix<f64>, r: &DMatrix<f64>) -> Result<DMatrix<f64>, ControlError> {
    let n = f.nrows();
    let ft = f.transpose();
    let mut k = DMatrix::zeros(n * n, n * n);
    // vec(FᵀΔ) = (I ⊗ Fᵀ) vec Δ, vec(Δ F) = (Fᵀ ⊗ I) vec Δ (column-major vec).
    for j in 0..n {
        for i in 0..n {
            let row = j * n + i;
            for l in 0..n {
                k[(row, j * n + l)] += ft[(i, l)];
                k[(row, l * n + i)] += f[(l, j)];
            }
        }
    }
    let rhs = DMatrix::from_iterator(n * n, 1, r.iter().map(|v| -v));
    let sol = k
        .lu()
        .solve(&rhs)
        .ok_or(ControlError::Singular("Lyapunov operator"))?;
    let d = DMatrix::from_column_slice(n, n, sol.as_slice());
    Ok((&d + d.transpose()) * 0.5)
}

/// Matrix sign function by the scaled Newton iteration; `None` when an iterate is singular or
/// the iteration does not settle (eigenvalues on or near the imaginary axis).
pub fn sign(h: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let n = h.nrows();
    let mut z = h.clone();
    for _ in 0..100 {
        let lu = z.clone().lu();
        let det = lu.determinant();
        if !det.is_finite() || det == 0.0 {
            return None;
        }
        let inv = lu.try_inverse()?;
        let c = det.abs().powf(1.0 / n as f64);
        let next = (&z / c + inv * c) * 0.5;
        let change = (&next - &z).norm();
        let size = next.norm();
        z = next;
        if !size.is_finite() {
            return None;
        }
        if change <= 1e-13 * size {
            return Some(z);
        }
    }
    None
}

/// Stabilising solution of AᵀX + XA − XGX + Q = 0; `what` names the equation in errors.
pub fn care(
    a: &DMatrix<f64>,
    g: &DMatrix<f64>,
    q: &DMatrix<f64>,
    what: &'static str,
) -> Result<CareSolution, ControlError> {
    let n = a.nrows();
    let mut h = DMatrix::zeros(2 * n, 2 * n);
    h.view_mut((0, 0), (n, n)).copy_from(a);
    h.view_mut((0, n), (n, n)).copy_from(&(-g));
    h.view_mut((n, 0), (n, n)).copy_from(&(-q));
    h.view_mut((n, n), (n, n)).copy_from(&(-a.transpose()));
    let fail = ControlError::NoStabilisingSolution(what);
    let w = sign(&h).ok_or(fail.clone())?;
    let mut lhs = DMatrix::zeros(2 * n, n);
    lhs.view_mut((0, 0), (n, n))
        .copy_from(&w.view((0, n), (n, n)));
    lhs.view_mut((n, 0), (n, n))
        .copy_from(&(w.view((n, n), (n, n)) + DMatrix::identity(n, n)));
    let mut rhs = DMatrix::zeros(2 * n, n);
    rhs.view_mut((0, 0), (n, n))
        .copy_from(&(-(w.view((0, 0), (n, n)) + DMatrix::identity(n, n))));
    rhs.view_mut((n, 0), (n, n))
        .copy_from(&(-w.view((n, 0), (n, n))));
    let x = lhs
        .svd(true, true)
        .solve(&rhs, 1e-14)
        .map_err(|_| fail.clone())?;
    let mut x = (&x + x.transpose()) * 0.5;
    if !x.iter().all(|v| v.is_finite()) {
        return Err(fail);
    }
    // Newton–Kleinman refinement.
    let (mut r, mut rel) = residual(a, g, q, &x);
    for _ in 0..6 {
        if rel < 1e-14 {
            break;
        }
        let f = a - g * &x;
        let Ok(delta) = lyapunov(&f, &r) else { break };
        let candidate = &x + delta;
        let (r2, rel2) = residual(a, g, q, &candidate);
        if rel2.partial_cmp(&rel) != Some(std::cmp::Ordering::Less) {
            break;
        }
        x = candidate;
        r = r2;
        rel = rel2;
    }
    let _ = r;
    let stable = (a - g * &x)
        .complex_eigenvalues()
        .iter()
        .all(|l| l.re < 0.0);
    if !stable || rel > MAX_RELATIVE_RESIDUAL {
        return Err(fail);
    }
    Ok(CareSolution {
        x,
        relative_residual: rel,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Scalar CARE 2 a x − g x² + q = 0: x = (a + √(a² + g q))/g.
    #[test]
    fn scalar_equation_has_the_closed_form_root() {
        for (a, g, q) in [(1.0, 2.0, 3.0), (-4.0, 0.5, 1.0), (0.0, 1.0, 1e-3)] {
            let s = care(
                &DMatrix::from_element(1, 1, a),
                &DMatrix::from_element(1, 1, g),
                &DMatrix::from_element(1, 1, q),
                "test",
            )
            .unwrap();
            let x = (a + (a * a + g * q).sqrt()) / g;
            assert!(
                (s.x[(0, 0)] - x).abs() < 1e-12 * x.abs().max(1.0),
                "{a} {g} {q}"
            );
        }
    }

    #[test]
    fn lyapunov_solution_satisfies_its_equation() {
        let f = DMatrix::from_row_slice(3, 3, &[-1.0, 2.0, 0.0, 0.0, -3.0, 1.0, 0.5, 0.0, -2.0]);
        let r = DMatrix::from_row_slice(3, 3, &[2.0, 1.0, 0.0, 1.0, 3.0, 0.5, 0.0, 0.5, 1.0]);
        let d = lyapunov(&f, &r).unwrap();
        let e = f.transpose() * &d + &d * &f + &r;
        assert!(e.norm() < 1e-12, "{e}");
    }

    #[test]
    fn imaginary_axis_hamiltonian_is_refused() {
        // Undamped oscillator with no input: not stabilisable.
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -1.0, 0.0]);
        let g = DMatrix::zeros(2, 2);
        let q = DMatrix::identity(2, 2);
        assert!(care(&a, &g, &q, "test").is_err());
    }
}
