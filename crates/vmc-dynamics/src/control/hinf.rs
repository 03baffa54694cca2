//! H∞ output feedback: the Glover–Doyle two-Riccati central controller, γ by bisection.
//!
//! Generalised plant (the standard simplifying assumptions D₁₁ = 0, D₂₂ = 0, D₁₂ᵀC₁ = 0,
//! B₁D₂₁ᵀ = 0; R = D₁₂ᵀD₁₂ > 0, V = D₂₁D₂₁ᵀ > 0):
//!
//! ```text
//! ẋ = A x + B₁ w + B₂ u,   z = C₁ x + D₁₂ u,   y = C₂ x + D₂₁ w
//! ```
//!
//! A controller with ‖T_zw‖∞ < γ exists iff the stabilising solutions of
//! AᵀX + XA − X(B₂R⁻¹B₂ᵀ − γ⁻²B₁B₁ᵀ)X + C₁ᵀC₁ = 0 and
//! AY + YAᵀ − Y(C₂ᵀV⁻¹C₂ − γ⁻²C₁ᵀC₁)Y + B₁B₁ᵀ = 0 exist, X ≥ 0, Y ≥ 0 and ρ(XY) < γ².
//! The central controller is ẋ_K = A_K x_K + B_K y, u = C_K x_K with F = −R⁻¹B₂ᵀX,
//! L = −YC₂ᵀV⁻¹, Z = (I − γ⁻²YX)⁻¹, A_K = A + γ⁻²B₁B₁ᵀX + B₂F + ZLC₂, B_K = −ZL, C_K = F.
//! γ is bisected between a feasible upper and an infeasible lower value; the controller is
//! built at the smallest feasible γ found times (1 + `backoff`), since the central controller
//! degenerates as γ approaches its optimum.

use nalgebra::DMatrix;

use super::riccati::care;
use super::{ControlError, StateSpace};

/// The generalised plant of an H∞ design.
#[derive(Debug, Clone, PartialEq)]
pub struct GeneralisedPlant {
    /// A (n × n).
    pub a: DMatrix<f64>,
    /// B₁, disturbance input (n × m₁).
    pub b1: DMatrix<f64>,
    /// B₂, control input (n × m₂).
    pub b2: DMatrix<f64>,
    /// C₁, performance output (p₁ × n).
    pub c1: DMatrix<f64>,
    /// D₁₂ (p₁ × m₂), orthogonal to C₁.
    pub d12: DMatrix<f64>,
    /// C₂, measurement (p₂ × n).
    pub c2: DMatrix<f64>,
    /// D₂₁ (p₂ × m₁), orthogonal to B₁.
    pub d21: DMatrix<f64>,
}

/// An H∞ controller and the γ it guarantees.
#[derive(Debug, Clone, PartialEq)]
pub struct Hinf {
    /// The controller: input y, output u.
    pub controller: StateSpace,
    /// The γ the controller is built for: ‖T_zw‖∞ < γ.
    pub gamma: f64,
    /// The smallest feasible γ found by the bisection.
    pub gamma_min: f64,
}

/// The central controller at one γ, or the reason none exists.
pub fn central(p: &GeneralisedPlant, gamma: f64) -> Result<StateSpace, ControlError> {
    let g2 = 1.0 / (gamma * gamma);
    let r_inv = (p.d12.transpose() * &p.d12)
        .try_inverse()
        .ok_or(ControlError::Singular("D12ᵀD12"))?;
    let v_inv = (&p.d21 * p.d21.transpose())
        .try_inverse()
        .ok_or(ControlError::Singular("D21D21ᵀ"))?;
    let b1b1 = &p.b1 * p.b1.transpose();
    let c1c1 = p.c1.transpose() * &p.c1;
    let gx = &p.b2 * &r_inv * p.b2.transpose() - &b1b1 * g2;
    let x = care(&p.a, &gx, &c1c1, "H-infinity X")?.x;
    let gy = p.c2.transpose() * &v_inv * &p.c2 - &c1c1 * g2;
    let y = care(&p.a.transpose(), &gy, &b1b1, "H-infinity Y")?.x;
    let psd = |m: &DMatrix<f64>| {
        let e = m.clone().symmetric_eigenvalues();
        e.min() >= -1e-9 * e.max().abs().max(1e-300)
    };
    if !psd(&x) || !psd(&y) {
        return Err(ControlError::NoStabilisingSolution(
            "H-infinity (X or Y not >= 0)",
        ));
    }
    let rho = (&x * &y)
        .complex_eigenvalues()
        .iter()
        .map(|l| l.norm())
        .fold(0.0, f64::max);
    if rho >= gamma * gamma {
        return Err(ControlError::NoStabilisingSolution(
            "H-infinity (rho(XY) >= gamma^2)",
        ));
    }
    let n = p.a.nrows();
    let f = -(&r_inv * p.b2.transpose() * &x);
    let l = -(&y * p.c2.transpose() * &v_inv);
    let z = (DMatrix::identity(n, n) - &y * &x * g2)
        .try_inverse()
        .ok_or(ControlError::Singular("I - YX/gamma^2"))?;
    let ak = &p.a + &b1b1 * &x * g2 + &p.b2 * &f + &z * &l * &p.c2;
    let bk = -(&z * &l);
    StateSpace::new(ak, bk, f, DMatrix::zeros(p.b2.ncols(), p.c2.nrows()))
}

/// Bisection on γ in [`gamma_lo`, `gamma_hi`] to a relative width `rel_tol`; the controller is
/// built at (1 + `backoff`) × the smallest feasible γ.
pub fn hinf(
    p: &GeneralisedPlant,
    gamma_lo: f64,
    gamma_hi: f64,
    rel_tol: f64,
    backoff: f64,
) -> Result<Hinf, ControlError> {
    central(p, gamma_hi).map_err(|_| ControlError::GammaTooSmall(gamma_hi))?;
    let (mut lo, mut hi) = (gamma_lo, gamma_hi);
    while hi - lo > rel_tol * hi {
        let mid = (lo * hi).sqrt();
        if central(p, mid).is_ok() {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let gamma = hi * (1.0 + backoff);
    Ok(Hinf {
        controller: central(p, gamma)?,
        gamma,
        gamma_min: hi,
    })
}

/// The closed loop w → z of a generalised plant with a controller u = K y.
pub fn lower_lft(p: &GeneralisedPlant, k: &StateSpace) -> StateSpace {
    let (n, nk) = (p.a.nrows(), k.states());
    let bd = &p.b2 * &k.d;
    let mut a = DMatrix::zeros(n + nk, n + nk);
    a.view_mut((0, 0), (n, n)).copy_from(&(&p.a + &bd * &p.c2));
    a.view_mut((0, n), (n, nk)).copy_from(&(&p.b2 * &k.c));
    a.view_mut((n, 0), (nk, n)).copy_from(&(&k.b * &p.c2));
    a.view_mut((n, n), (nk, nk)).copy_from(&k.a);
    let mut b = DMatrix::zeros(n + nk, p.b1.ncols());
    b.view_mut((0, 0), (n, p.b1.ncols()))
        .copy_from(&(&p.b1 + &bd * &p.d21));
    b.view_mut((n, 0), (nk, p.b1.ncols()))
        .copy_from(&(&k.b * &p.d21));
    let dd = &p.d12 * &k.d;
    let mut c = DMatrix::zeros(p.c1.nrows(), n + nk);
    c.view_mut((0, 0), (p.c1.nrows(), n))
        .copy_from(&(&p.c1 + &dd * &p.c2));
    c.view_mut((0, n), (p.c1.nrows(), nk))
        .copy_from(&(&p.d12 * &k.c));
    let d = &dd * &p.d21;
    StateSpace { a, b, c, d }
}

/// H∞ norm by a frequency sweep: `points` log-spaced frequencies in [ω_lo, ω_hi] rad/s, then a
/// golden-section refinement around the largest; returns (norm, ω at the peak).
pub fn hinf_norm_sweep(
    sys: &StateSpace,
    omega_lo: f64,
    omega_hi: f64,
    points: usize,
) -> (f64, f64) {
    let gain = |w: f64| super::max_singular_value(&sys.frf(w));
    let ratio = (omega_hi / omega_lo).powf(1.0 / (points.max(2) - 1) as f64);
    let mut best = (0.0, omega_lo);
    let mut w = omega_lo;
    for _ in 0..points.max(2) {
        let g = gain(w);
        if g > best.0 {
            best = (g, w);
        }
        w *= ratio;
    }
    // Golden section on log ω within one grid step either side.
    let (mut a, mut b) = ((best.1 / ratio).ln(), (best.1 * ratio).ln());
    let phi = 0.618_033_988_749_895;
    for _ in 0..60 {
        let c = b - phi * (b - a);
        let d = a + phi * (b - a);
        if gain(c.exp()) > gain(d.exp()) {
            b = d;
        } else {
            a = c;
        }
    }
    let wp = (0.5 * (a + b)).exp();
    let gp = gain(wp);
    if gp > best.0 {
        (gp, wp)
    } else {
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_mode_plant(sigma_noise: f64, rho: f64) -> GeneralisedPlant {
        let (a, b, c) = crate::control::lqg::tests::two_modes();
        let mut b1 = DMatrix::zeros(4, 2);
        b1.view_mut((0, 0), (4, 1)).copy_from(&b);
        let mut c1 = DMatrix::zeros(2, 4);
        c1.view_mut((0, 0), (1, 4)).copy_from(&c);
        GeneralisedPlant {
            a,
            b1,
            b2: b,
            c1,
            d12: DMatrix::from_row_slice(2, 1, &[0.0, rho]),
            c2: c,
            d21: DMatrix::from_row_slice(1, 2, &[0.0, sigma_noise]),
        }
    }

    /// The open-loop norm force → position is 10.0170 (python-control `norm(sys, p="inf")`,
    /// tests/data/control_reference.py): the sweep finds it.
    #[test]
    fn the_sweep_finds_the_reference_norm() {
        let p = two_mode_plant(0.1, 0.1);
        let sys = StateSpace {
            a: p.a.clone(),
            b: p.b2.clone(),
            c: p.c2.clone(),
            d: DMatrix::zeros(1, 1),
        };
        let (norm, _) = hinf_norm_sweep(&sys, 0.1, 10.0, 400);
        assert!((norm / 10.016_975_402_832_031 - 1.0).abs() < 1e-4, "{norm}");
    }

    #[test]
    fn the_closed_loop_norm_is_below_gamma_and_gamma_is_nearly_optimal() {
        let p = two_mode_plant(0.1, 0.1);
        let h = hinf(&p, 1e-3, 1e3, 1e-3, 0.02).unwrap();
        let cl = lower_lft(&p, &h.controller);
        assert!(
            cl.poles().iter().all(|l| l.re < 0.0),
            "closed loop unstable"
        );
        let (norm, _) = hinf_norm_sweep(&cl, 1e-2, 1e2, 2000);
        assert!(norm < h.gamma, "{norm} >= {}", h.gamma);
        // Close to the optimum: no controller exists at 0.99 γ_min, and the achieved norm is
        // of the order of γ (not far below, which would hint at a loose bisection).
        assert!(central(&p, 0.99 * h.gamma_min).is_err());
        assert!(norm > 0.5 * h.gamma_min, "{norm} vs {}", h.gamma_min);
        // The open loop's norm is larger: the controller does something.
        let ol = StateSpace {
            a: p.a.clone(),
            b: p.b1.clone(),
            c: p.c1.clone(),
            d: DMatrix::zeros(2, 2),
        };
        assert!(hinf_norm_sweep(&ol, 1e-2, 1e2, 2000).0 > 2.0 * norm);
    }
}
