//! LQR, Kalman filter and their combination, the LQG controller (continuous time).
//!
//! LQR: u = −K x minimises ∫ xᵀQx + uᵀRu dt, K = R⁻¹BᵀX with X the stabilising solution of
//! AᵀX + XA − XBR⁻¹BᵀX + Q = 0. Kalman filter of ẋ = Ax + Gw + …, y = Cx + v with white
//! E\[wwᵀ\] = W δ, E\[vvᵀ\] = V δ: x̂̇ = Ax̂ + Bu + L(y − Cx̂), L = PCᵀV⁻¹ with P the stabilising
//! solution of AP + PAᵀ − PCᵀV⁻¹CP + GWGᵀ = 0. LQG (separation principle): the controller
//! ẋ_c = (A − BK − LC) x_c + L y, u = −K x_c.

use nalgebra::DMatrix;

use super::riccati::{care, CareSolution};
use super::{ControlError, StateSpace};

/// A state-feedback or observer gain with its Riccati solution.
#[derive(Debug, Clone, PartialEq)]
pub struct Gain {
    /// The gain (K: m × n for LQR, L: n × p for the Kalman filter).
    pub gain: DMatrix<f64>,
    /// The Riccati solution (X or P) and its residual.
    pub riccati: CareSolution,
}

fn inverse(m: &DMatrix<f64>, what: &'static str) -> Result<DMatrix<f64>, ControlError> {
    m.clone().try_inverse().ok_or(ControlError::Singular(what))
}

/// LQR gain K = R⁻¹BᵀX.
pub fn lqr(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Result<Gain, ControlError> {
    let r_inv = inverse(r, "R")?;
    let g = b * &r_inv * b.transpose();
    let riccati = care(a, &g, q, "LQR")?;
    let gain = r_inv * b.transpose() * &riccati.x;
    Ok(Gain { gain, riccati })
}

/// Kalman gain L = PCᵀV⁻¹ for process noise G w (E\[wwᵀ\] = W) and measurement noise V.
pub fn kalman(
    a: &DMatrix<f64>,
    g: &DMatrix<f64>,
    c: &DMatrix<f64>,
    w: &DMatrix<f64>,
    v: &DMatrix<f64>,
) -> Result<Gain, ControlError> {
    let v_inv = inverse(v, "V")?;
    let gg = c.transpose() * &v_inv * c;
    let q = g * w * g.transpose();
    let riccati = care(&a.transpose(), &gg, &q, "Kalman")?;
    let gain = &riccati.x * c.transpose() * v_inv;
    Ok(Gain { gain, riccati })
}

/// An LQG controller and the two gains it is made of.
#[derive(Debug, Clone, PartialEq)]
pub struct Lqg {
    /// The controller: input y, output u.
    pub controller: StateSpace,
    /// State-feedback gain K.
    pub lqr: Gain,
    /// Kalman gain L.
    pub kalman: Gain,
}

/// LQG controller of ẋ = Ax + B u + G w, y = C x + v.
pub fn lqg(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    g: &DMatrix<f64>,
    c: &DMatrix<f64>,
    weights: (&DMatrix<f64>, &DMatrix<f64>),
    noise: (&DMatrix<f64>, &DMatrix<f64>),
) -> Result<Lqg, ControlError> {
    let lqr = lqr(a, b, weights.0, weights.1)?;
    let kalman = kalman(a, g, c, noise.0, noise.1)?;
    let ac = a - b * &lqr.gain - &kalman.gain * c;
    let controller = StateSpace::new(
        ac,
        kalman.gain.clone(),
        -&lqr.gain,
        DMatrix::zeros(b.ncols(), c.nrows()),
    )?;
    Ok(Lqg {
        controller,
        lqr,
        kalman,
    })
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    fn oscillator(w: f64, z: f64) -> (DMatrix<f64>, DMatrix<f64>) {
        (
            DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -w * w, -2.0 * z * w]),
            DMatrix::from_row_slice(2, 1, &[0.0, 1.0]),
        )
    }

    /// ẍ + 2ζωẋ + ω²x = u, Q = diag(q, 0), R = r: K₁ = −ω² + √(ω⁴ + q/r),
    /// K₂ = −2ζω + √(4ζ²ω² + 2K₁) (from the (1,2) and (2,2) entries of the Riccati equation).
    #[test]
    fn lqr_of_an_oscillator_has_the_closed_form_gain() {
        for (w, z, q, r) in [
            (1.0, 0.05, 10.0, 0.1),
            (922.0 * std::f64::consts::TAU, 0.011, 1e12, 1.0),
        ] {
            let (a, b) = oscillator(w, z);
            let qm = DMatrix::from_row_slice(2, 2, &[q, 0.0, 0.0, 0.0]);
            let k = lqr(&a, &b, &qm, &DMatrix::from_element(1, 1, r)).unwrap();
            let k1 = -w * w + (w.powi(4) + q / r).sqrt();
            let k2 = -2.0 * z * w + (4.0 * z * z * w * w + 2.0 * k1).sqrt();
            assert!((k.gain[(0, 0)] / k1 - 1.0).abs() < 1e-9, "{} {k1}", k.gain);
            assert!((k.gain[(0, 1)] / k2 - 1.0).abs() < 1e-9, "{} {k2}", k.gain);
            assert!(k.riccati.relative_residual < 1e-9);
        }
    }

    /// ẋ = a x + w, y = x + v: P = V(a + √(a² + W/V)), L = P/V.
    #[test]
    fn scalar_kalman_filter_has_the_closed_form_gain() {
        let (a, w, v) = (-2.0, 3.0, 0.5);
        let m = |x: f64| DMatrix::from_element(1, 1, x);
        let k = kalman(&m(a), &m(1.0), &m(1.0), &m(w), &m(v)).unwrap();
        let p = v * (a + (a * a + w / v).sqrt());
        assert!((k.gain[(0, 0)] - p / v).abs() < 1e-12);
    }

    /// Two lightly damped modes (1 and 3 rad/s), one input, one output: a test plant shared
    /// with the H∞ tests.
    pub(in crate::control) fn two_modes() -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        let (w1, w2, z1, z2) = (1.0, 3.0, 0.05, 0.02);
        let a = DMatrix::from_row_slice(
            4,
            4,
            &[
                0.0,
                0.0,
                1.0,
                0.0, //
                0.0,
                0.0,
                0.0,
                1.0, //
                -w1 * w1,
                0.0,
                -2.0 * z1 * w1,
                0.0, //
                0.0,
                -w2 * w2,
                0.0,
                -2.0 * z2 * w2,
            ],
        );
        let b = DMatrix::from_row_slice(4, 1, &[0.0, 0.0, 1.0, 0.5]);
        let c = DMatrix::from_row_slice(1, 4, &[1.0, 1.0, 0.0, 0.0]);
        (a, b, c)
    }

    /// Reference gains from python-control 0.10 (`ct.lqr`, `ct.lqe`), produced by
    /// `tests/data/control_reference.py`.
    #[test]
    fn lqr_and_kalman_gains_match_python_control() {
        let (a, b, c) = two_modes();
        let q = c.transpose() * &c * 10.0;
        let k = lqr(&a, &b, &q, &DMatrix::from_element(1, 1, 0.1)).unwrap();
        let k_ref = [
            9.258_199_926_296_552,
            6.203_128_336_018_928,
            3.679_708_918_226_284,
            2.376_777_138_655_148_4,
        ];
        for (i, r) in k_ref.iter().enumerate() {
            assert!((k.gain[(0, i)] / r - 1.0).abs() < 1e-9, "{i}: {}", k.gain);
        }
        let l = kalman(
            &a,
            &b,
            &c,
            &DMatrix::from_element(1, 1, 2.0),
            &DMatrix::from_element(1, 1, 0.01),
        )
        .unwrap();
        let l_ref = [
            4.378_111_928_255_255,
            1.573_253_396_877_752_2,
            12.976_617_001_931_178,
            4.732_757_614_666_578,
        ];
        for (i, r) in l_ref.iter().enumerate() {
            assert!((l.gain[(i, 0)] / r - 1.0).abs() < 1e-9, "{i}: {}", l.gain);
        }
        assert!(k.riccati.relative_residual < 1e-9 && l.riccati.relative_residual < 1e-9);
    }

    #[test]
    fn lqg_closed_loop_poles_are_the_regulator_and_observer_poles() {
        let (a, b, c) = two_modes();
        let q = c.transpose() * &c * 10.0;
        let r = DMatrix::from_element(1, 1, 0.1);
        let (w, v) = (
            DMatrix::from_element(1, 1, 2.0),
            DMatrix::from_element(1, 1, 0.01),
        );
        let ctrl = lqg(&a, &b, &b, &c, (&q, &r), (&w, &v)).unwrap();
        let n = 4;
        let k = &ctrl.controller;
        let mut acl = DMatrix::zeros(8, 8);
        acl.view_mut((0, 0), (n, n)).copy_from(&a);
        acl.view_mut((0, n), (n, n)).copy_from(&(&b * &k.c));
        acl.view_mut((n, 0), (n, n)).copy_from(&(&k.b * &c));
        acl.view_mut((n, n), (n, n)).copy_from(&k.a);
        let mut cl: Vec<f64> = acl.complex_eigenvalues().iter().map(|l| l.norm()).collect();
        let mut sep: Vec<f64> = (&a - &b * &ctrl.lqr.gain)
            .complex_eigenvalues()
            .iter()
            .chain((&a - &ctrl.kalman.gain * &c).complex_eigenvalues().iter())
            .map(|l| l.norm())
            .collect();
        cl.sort_by(f64::total_cmp);
        sep.sort_by(f64::total_cmp);
        for (x, y) in cl.iter().zip(&sep) {
            assert!((x - y).abs() < 1e-6 * y, "{cl:?} {sep:?}");
        }
    }
}
