//! Euler–Bernoulli cantilever (clamped at the holder, free at the tool tip).
//!
//! Mode shapes W(x) = cosh βx − cos βx − σ(sinh βx − sin βx), σ = (cosh βL + cos βL)/(sinh βL +
//! sin βL), with βL the roots of 1 + cos βL cosh βL = 0 (1.8751, 4.6941, 7.8548, …). Natural
//! frequencies ω = (βL)² √(EI/(ρAL⁴)). Normalised to 1 at the tip the shape gives the modal
//! mass m = ρA ∫₀^L W² dx / W(L)² = ρAL/4 (W(L)² = 4 for every clamped-free mode with the
//! form above; the integral equals L), and the tip modal stiffness k = m ω². The section is
//! a solid or hollow circle.

use std::f64::consts::PI;

use crate::params::{positive, DynamicsError, Mode};

/// Material and geometry of a cylindrical cantilever.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cantilever {
    /// Young's modulus E in Pa.
    pub youngs_modulus_pa: f64,
    /// Density ρ in kg/m³.
    pub density_kg_per_m3: f64,
    /// Free length L in mm.
    pub length_mm: f64,
    /// Outer diameter in mm.
    pub outer_diameter_mm: f64,
    /// Inner diameter in mm (0 for a solid section).
    pub inner_diameter_mm: f64,
}

/// βL of the n-th clamped-free mode (n from 0): Newton on 1 + cos x cosh x = 0 from the
/// asymptote (2n + 1)π/2.
pub fn clamped_free_root(n: usize) -> f64 {
    let mut x = (2 * n + 1) as f64 * PI / 2.0;
    if n == 0 {
        x = 1.875;
    }
    for _ in 0..50 {
        // Divide by cosh x so the iteration stays well scaled for high modes.
        let f = 1.0 / x.cosh() + x.cos();
        let df = -x.tanh() / x.cosh() - x.sin();
        let step = f / df;
        x -= step;
        if step.abs() < 1e-15 * x {
            break;
        }
    }
    x
}

/// Shape of the n-th clamped-free mode (n from 0) at ξ = x/L ∈ [0, 1], normalised to 1 at the
/// free end. Written with exponentials, (1 − σ) e^{βξ} + (1 + σ) e^{−βξ} over 2 for
/// cosh − σ sinh, so that high modes (σ → 1) do not lose their digits to cancellation.
pub fn clamped_free_shape(n: usize, xi: f64) -> f64 {
    let b = clamped_free_root(n);
    let den = b.sinh() + b.sin();
    let sigma = (b.cosh() + b.cos()) / den;
    // 1 − σ = (sinh b + sin b − cosh b − cos b)/den = (−e^{−b} + sin b − cos b)/den.
    let one_minus_sigma = (-(-b).exp() + b.sin() - b.cos()) / den;
    let w = |x: f64| {
        let bx = b * x;
        0.5 * (one_minus_sigma * bx.exp() + (1.0 + sigma) * (-bx).exp()) - bx.cos()
            + sigma * bx.sin()
    };
    w(xi) / w(1.0)
}

impl Cantilever {
    /// Checks positivity and that the bore is smaller than the outer diameter.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        positive("youngs_modulus_pa", self.youngs_modulus_pa)?;
        positive("density_kg_per_m3", self.density_kg_per_m3)?;
        positive("length_mm", self.length_mm)?;
        positive("outer_diameter_mm", self.outer_diameter_mm)?;
        crate::params::non_negative("inner_diameter_mm", self.inner_diameter_mm)?;
        positive(
            "outer_diameter_mm - inner_diameter_mm",
            self.outer_diameter_mm - self.inner_diameter_mm,
        )
    }

    fn section(&self) -> (f64, f64) {
        let (d, di) = (self.outer_diameter_mm * 1e-3, self.inner_diameter_mm * 1e-3);
        let area = PI / 4.0 * (d * d - di * di);
        let inertia = PI / 64.0 * (d.powi(4) - di.powi(4));
        (area, inertia)
    }

    /// First `count` tip modes with the given damping ratio.
    pub fn modes(&self, count: usize, damping_ratio: f64) -> Result<Vec<Mode>, DynamicsError> {
        self.validate()?;
        crate::params::non_negative("damping_ratio", damping_ratio)?;
        let (area, inertia) = self.section();
        let l = self.length_mm * 1e-3;
        let mass = self.density_kg_per_m3 * area * l / 4.0;
        Ok((0..count)
            .map(|n| {
                let bl = clamped_free_root(n);
                let w = bl
                    * bl
                    * (self.youngs_modulus_pa * inertia
                        / (self.density_kg_per_m3 * area * l.powi(4)))
                    .sqrt();
                Mode {
                    frequency_hz: w / (2.0 * PI),
                    damping_ratio,
                    stiffness_n_per_m: mass * w * w,
                }
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_and_tip_modal_mass() {
        let known = [
            1.875_104_068_711_961,
            4.694_091_132_974_175,
            7.854_757_438_237_613,
        ];
        for (n, k) in known.iter().enumerate() {
            assert!((clamped_free_root(n) - k).abs() < 1e-9, "{n}");
        }
        let r = clamped_free_root(9);
        assert!((1.0 + r.cos() * r.cosh()).abs() < 1e-6 * r.cosh());
        // Numerical check of ∫W² = L and W(L)² = 4 (βL = root 0 and 1, L = 1).
        for n in 0..3 {
            let b = clamped_free_root(n);
            let sigma = (b.cosh() + b.cos()) / (b.sinh() + b.sin());
            let w =
                |x: f64| (b * x).cosh() - (b * x).cos() - sigma * ((b * x).sinh() - (b * x).sin());
            let k = 20_000;
            let int: f64 = (0..k)
                .map(|i| w((i as f64 + 0.5) / k as f64).powi(2))
                .sum::<f64>()
                / k as f64;
            assert!(
                (int - 1.0).abs() < 1e-6 && (w(1.0).powi(2) - 4.0).abs() < 1e-8,
                "{n}: {int}"
            );
        }
        // The stable shape agrees with the textbook form and is 0 at the clamp, 1 at the tip.
        for n in 0..3 {
            let b = clamped_free_root(n);
            let sigma = (b.cosh() + b.cos()) / (b.sinh() + b.sin());
            let w =
                |x: f64| (b * x).cosh() - (b * x).cos() - sigma * ((b * x).sinh() - (b * x).sin());
            for xi in [0.0, 0.3, 0.7, 1.0] {
                assert!(
                    (clamped_free_shape(n, xi) - w(xi) / w(1.0)).abs() < 1e-9,
                    "{n} {xi}"
                );
            }
        }
        assert!(clamped_free_shape(9, 0.0).abs() < 1e-9);
        assert!((clamped_free_shape(9, 1.0) - 1.0).abs() < 1e-12);
        // Static check: first-mode tip stiffness is close to (but above) 3EI/L³.
        let c = Cantilever {
            youngs_modulus_pa: 210e9,
            density_kg_per_m3: 7850.0,
            length_mm: 100.0,
            outer_diameter_mm: 20.0,
            inner_diameter_mm: 0.0,
        };
        let m = c.modes(2, 0.02).unwrap();
        let (_, i) = c.section();
        let k_static = 3.0 * 210e9 * i / 1e-3;
        let ratio = m[0].stiffness_n_per_m / k_static;
        assert!(ratio > 1.0 && ratio < 1.05, "{ratio}");
        assert!(
            m[1].frequency_hz / m[0].frequency_hz > 6.26
                && m[1].frequency_hz / m[0].frequency_hz < 6.27
        );
    }
}
