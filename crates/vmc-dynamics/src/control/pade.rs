//! Padé approximation of the delay e^(−sτ) as a state-space system.
//!
//! The [n/n] approximant is N(sτ)/N(−sτ) with N(p) = Σₖ cₖ (−p)ᵏ,
//! cₖ = (2n − k)! n! / ((2n)! k! (n − k)!): all-pass (|·| = 1 at every frequency), with the
//! phase error ≈ (n!)² / ((2n)! (2n + 1)!) (ωτ)^(2n+1) at small ωτ (the leading term of the
//! remainder e^(−p) − R(p), Padé's classical result). It is built for τ = 1 in controllable
//! canonical form and rescaled, A = A₁/τ, B = B₁/τ, which keeps it well conditioned for small τ.

use nalgebra::DMatrix;

use super::{ControlError, StateSpace};
use crate::params::{positive, DynamicsError};

/// Most accepted order (the canonical form grows ill-conditioned beyond).
pub const MAX_ORDER: usize = 10;

/// Coefficients cₖ, k = 0..=n, of the [n/n] Padé approximant (c₀ = 1).
pub fn coefficients(order: usize) -> Vec<f64> {
    let n = order;
    let mut c = vec![1.0; n + 1];
    for k in 1..=n {
        // c_k / c_{k−1} = (n − k + 1) / (k (2n − k + 1)).
        c[k] = c[k - 1] * (n - k + 1) as f64 / (k as f64 * (2 * n - k + 1) as f64);
    }
    c
}

/// Leading phase error in rad of the order-n approximant at ωτ (the textbook bound).
pub fn phase_error_bound(order: usize, omega_tau: f64) -> f64 {
    let fact = |k: usize| (1..=k).map(|i| i as f64).product::<f64>();
    let n = order;
    fact(n).powi(2) / (fact(2 * n) * fact(2 * n + 1)) * omega_tau.powi(2 * n as i32 + 1)
}

/// State-space model of the order-n Padé approximation of e^(−sτ) (input 1, output 1).
pub fn pade(delay_s: f64, order: usize) -> Result<StateSpace, ControlError> {
    positive("delay_s", delay_s)?;
    if order == 0 {
        return Err(DynamicsError::TooFewSteps {
            name: "pade order",
            min: 1,
            value: order,
        }
        .into());
    }
    if order > MAX_ORDER {
        return Err(DynamicsError::TooManySteps {
            name: "pade order",
            max: MAX_ORDER,
            value: order,
        }
        .into());
    }
    let n = order;
    let c = coefficients(n);
    // Denominator Σ c_k p^k (monic after dividing by c_n), numerator Σ c_k (−p)^k.
    let den: Vec<f64> = c.iter().map(|v| v / c[n]).collect();
    let num: Vec<f64> = c
        .iter()
        .enumerate()
        .map(|(k, v)| if k % 2 == 0 { *v } else { -*v } / c[n])
        .collect();
    let d0 = num[n];
    let mut a = DMatrix::zeros(n, n);
    for i in 0..n - 1 {
        a[(i, i + 1)] = 1.0;
    }
    for k in 0..n {
        a[(n - 1, k)] = -den[k];
    }
    let mut b = DMatrix::zeros(n, 1);
    b[(n - 1, 0)] = 1.0;
    let cm = DMatrix::from_fn(1, n, |_, k| num[k] - d0 * den[k]);
    StateSpace::new(
        a / delay_s,
        b / delay_s,
        cm,
        DMatrix::from_element(1, 1, d0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Complex;

    #[test]
    fn coefficients_are_the_textbook_ones() {
        // [2/2]: (1 − p/2 + p²/12)/(1 + p/2 + p²/12); python-control pade(1, 2) = [1, −6, 12].
        let c = coefficients(2);
        assert!((c[1] - 0.5).abs() < 1e-15 && (c[2] - 1.0 / 12.0).abs() < 1e-15);
        let c4 = coefficients(4);
        // python-control pade(1, 4) denominator [1, 20, 180, 840, 1680] (highest power first).
        let expect = [1680.0, 840.0, 180.0, 20.0, 1.0];
        for (k, e) in expect.iter().enumerate() {
            assert!((c4[k] * 1680.0 - e).abs() < 1e-9, "{k}");
        }
    }

    #[test]
    fn phase_error_at_omega_tau_one_is_within_the_textbook_bound() {
        // Phases of python-control's pade(1, n) at ω = 1 (tests/data/control_reference.py).
        let reference = [
            -0.927_295_218_001_612_2,
            -0.998_693_443_360_260_2,
            -0.999_990_460_039_653_5,
            -0.999_999_961_768_968_3,
        ];
        for order in 1..=4 {
            for tau in [1e-3, 1.0] {
                let sys = pade(tau, order).unwrap();
                let g = sys.frf(1.0 / tau)[(0, 0)];
                assert!((g.norm() - 1.0).abs() < 1e-12, "all-pass");
                let exact = Complex::from_polar(1.0, -1.0);
                let err = (g / exact).arg().abs();
                let bound = phase_error_bound(order, 1.0);
                assert!(
                    err < bound && err > 0.8 * bound,
                    "{order}: {err} vs {bound}"
                );
                assert!((g.arg() - reference[order - 1]).abs() < 1e-9, "{order}");
                // Against e^(−jωτ) itself: |G − e^(−jωτ)| = 2 sin(err/2).
                assert!(((g - exact).norm() - 2.0 * (err / 2.0).sin()).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn bad_orders_and_delays_are_refused() {
        assert!(pade(1.0, 0).is_err());
        assert!(pade(1.0, 11).is_err());
        assert!(pade(0.0, 2).is_err());
        assert!(pade(f64::NAN, 2).is_err());
    }
}
