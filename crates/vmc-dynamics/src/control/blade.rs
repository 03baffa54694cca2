//! The plant: a cantilever blade milled at its free end, driven by a piezo stack at x = a.
//!
//! Structure: an Euler–Bernoulli beam clamped at x = 0, free at x = L, bending across its
//! thickness h (section b × h, I = b h³/12), truncated to n clamped-free modes φ_k (shapes of
//! [`crate::beam::clamped_free_shape`], normalised to 1 at the free end, so every mode has the
//! modal mass m = ρ b h L/4 and the tip stiffness k_k = m ω_k²) with modal damping ζ.
//!
//! Actuator: the stack is far stiffer than the blade, so it imposes a displacement at x = a.
//! It is modelled as a penalty spring k_p (two stacks in series ≈ 185 N/µm) between the stack's
//! free end d(t) and the blade at x = a: the force k_p (d − w(a, t)) enters mode k through
//! φ_k(a). With the stack held (d = 0) the spring props the blade. The stack extends by
//! g = stroke/V_max per volt of its amplifier's output e, a first-order lag of the command u:
//! ė = ω_a (u − e), ω_a = 2π × bandwidth.
//!
//! Equations (q the modal coordinates, φ_a = [φ_k(a)], 1 = [1, …, 1]):
//!
//! ```text
//! m q̈ + c q̇ + (K + k_p φ_a φ_aᵀ) q = 1 F + k_p g φ_a e,   K = diag(m ω_k²), c = diag(2ζ m ω_k)
//! x = [q; q̇; e]:  ẋ = A x + B_w F + B_u u,  y = C_y x (displacement at the sensor), z = C_z x (tip)
//! ```
//!
//! F is the cutting force at the free end (N, along the blade's bending direction), u the
//! amplifier command (V), y the measured displacement (m) of a displacement sensor at
//! x = `sensor_position_mm` (default the free end: the cut point).

use serde::{Deserialize, Serialize};

use nalgebra::{DMatrix, DVector};

use crate::beam::{clamped_free_root, clamped_free_shape};
use crate::params::{positive, DynamicsError, Mode};

/// Most modes accepted (the shapes are accurate to round-off well beyond).
pub const MAX_MODES: usize = 12;

/// The piezo actuator and its amplifier.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Actuator {
    /// Position a of the stack from the clamp, mm.
    pub position_mm: f64,
    /// Stiffness of the stack (penalty spring) in N/µm.
    pub stiffness_n_per_um: f64,
    /// Free stroke at the largest voltage, µm.
    pub stroke_um: f64,
    /// Largest amplifier voltage (saturation ±), V.
    pub max_voltage_v: f64,
    /// Amplifier bandwidth (first-order lag), Hz.
    pub bandwidth_hz: f64,
}

impl Actuator {
    /// Stack extension per volt g in m/V.
    pub fn gain_m_per_v(&self) -> f64 {
        self.stroke_um * 1e-6 / self.max_voltage_v
    }
}

/// A rectangular steel blade and its actuator.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Blade {
    /// Young's modulus E in Pa.
    pub youngs_modulus_pa: f64,
    /// Density ρ in kg/m³.
    pub density_kg_per_m3: f64,
    /// Free length L (clamp to free end) in mm.
    pub length_mm: f64,
    /// Width b (along the cutter axis) in mm.
    pub width_mm: f64,
    /// Thickness h (the bending direction) in mm.
    pub thickness_mm: f64,
    /// Modes kept n.
    pub modes: usize,
    /// Modal damping ratio ζ of every mode.
    pub damping_ratio: f64,
    /// Displacement sensor position from the clamp, mm.
    pub sensor_position_mm: f64,
    /// The piezo actuator.
    pub actuator: Actuator,
}

/// The state-space model of a blade.
#[derive(Debug, Clone, PartialEq)]
pub struct BladePlant {
    /// State matrix A, states [q (n); q̇ (n); e].
    pub a: DMatrix<f64>,
    /// Cutting-force input B_w (per N at the free end).
    pub b_w: DMatrix<f64>,
    /// Control input B_u (per V of command).
    pub b_u: DMatrix<f64>,
    /// Measured output C_y: displacement at the sensor, m.
    pub c_y: DMatrix<f64>,
    /// Performance output C_z: displacement at the free end (the cut point), m.
    pub c_z: DMatrix<f64>,
    /// Clamped-free modes at the free end (without the stack), for the milling models.
    pub tip_modes: Vec<Mode>,
}

impl Blade {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        positive("youngs_modulus_pa", self.youngs_modulus_pa)?;
        positive("density_kg_per_m3", self.density_kg_per_m3)?;
        positive("length_mm", self.length_mm)?;
        positive("width_mm", self.width_mm)?;
        positive("thickness_mm", self.thickness_mm)?;
        crate::params::non_negative("damping_ratio", self.damping_ratio)?;
        if self.modes == 0 {
            return Err(DynamicsError::TooFewSteps {
                name: "modes",
                min: 1,
                value: 0,
            });
        }
        if self.modes > MAX_MODES {
            return Err(DynamicsError::TooManySteps {
                name: "modes",
                max: MAX_MODES,
                value: self.modes,
            });
        }
        let ac = &self.actuator;
        positive("actuator.position_mm", ac.position_mm)?;
        positive(
            "length_mm - actuator.position_mm",
            self.length_mm - ac.position_mm,
        )?;
        positive("actuator.stiffness_n_per_um", ac.stiffness_n_per_um)?;
        positive("actuator.stroke_um", ac.stroke_um)?;
        positive("actuator.max_voltage_v", ac.max_voltage_v)?;
        positive("actuator.bandwidth_hz", ac.bandwidth_hz)?;
        positive("sensor_position_mm", self.sensor_position_mm)?;
        crate::params::non_negative(
            "length_mm - sensor_position_mm",
            self.length_mm - self.sensor_position_mm,
        )
    }

    /// Bending stiffness EI in N m².
    pub fn bending_stiffness_n_m2(&self) -> f64 {
        let (b, h) = (self.width_mm * 1e-3, self.thickness_mm * 1e-3);
        self.youngs_modulus_pa * b * h.powi(3) / 12.0
    }

    /// Modal mass ρ b h L / 4 in kg (shapes normalised to 1 at the free end).
    pub fn modal_mass_kg(&self) -> f64 {
        self.density_kg_per_m3 * self.width_mm * self.thickness_mm * self.length_mm * 1e-9 / 4.0
    }

    /// Clamped-free modes at the free end (stack absent).
    pub fn cantilever_modes(&self) -> Vec<Mode> {
        let l = self.length_mm * 1e-3;
        let rho_a = self.density_kg_per_m3 * self.width_mm * self.thickness_mm * 1e-6;
        let m = self.modal_mass_kg();
        (0..self.modes)
            .map(|k| {
                let bl = clamped_free_root(k);
                let w = bl * bl * (self.bending_stiffness_n_m2() / (rho_a * l.powi(4))).sqrt();
                Mode {
                    frequency_hz: w / (2.0 * std::f64::consts::PI),
                    damping_ratio: self.damping_ratio,
                    stiffness_n_per_m: m * w * w,
                }
            })
            .collect()
    }

    /// Static tip stiffness of the free cantilever 3EI/L³ in N/mm.
    pub fn cantilever_tip_stiffness_n_per_mm(&self) -> f64 {
        3.0 * self.bending_stiffness_n_m2() / (self.length_mm * 1e-3).powi(3) * 1e-3
    }

    /// Exact static tip stiffness of the beam propped by the held stack (spring k_p at a), in
    /// N/mm, from the cantilever's flexibilities f_LL = L³/3EI, f_aa = a³/3EI,
    /// f_La = a²(3L − a)/6EI: 1 / (f_LL − f_La²/(f_aa + 1/k_p)).
    pub fn propped_tip_stiffness_n_per_mm(&self) -> f64 {
        let ei = self.bending_stiffness_n_m2();
        let (l, a) = (self.length_mm * 1e-3, self.actuator.position_mm * 1e-3);
        let f_ll = l.powi(3) / (3.0 * ei);
        let f_aa = a.powi(3) / (3.0 * ei);
        let f_la = a * a * (3.0 * l - a) / (6.0 * ei);
        let kp = self.actuator.stiffness_n_per_um * 1e6;
        1e-3 / (f_ll - f_la * f_la / (f_aa + 1.0 / kp))
    }

    /// The state-space model (validated).
    pub fn plant(&self) -> Result<BladePlant, DynamicsError> {
        self.validate()?;
        let n = self.modes;
        let m = self.modal_mass_kg();
        let modes = self.cantilever_modes();
        let xi_a = self.actuator.position_mm / self.length_mm;
        let xi_s = self.sensor_position_mm / self.length_mm;
        let phi_a = DVector::from_fn(n, |k, _| clamped_free_shape(k, xi_a));
        let kp = self.actuator.stiffness_n_per_um * 1e6;
        let stiffness =
            DMatrix::from_diagonal(&DVector::from_fn(n, |k, _| modes[k].stiffness_n_per_m))
                + &phi_a * phi_a.transpose() * kp;
        let size = 2 * n + 1;
        let mut a = DMatrix::zeros(size, size);
        for k in 0..n {
            a[(k, n + k)] = 1.0;
            a[(n + k, n + k)] = -2.0 * self.damping_ratio * modes[k].omega_rad_per_s();
            for j in 0..n {
                a[(n + k, j)] = -stiffness[(k, j)] / m;
            }
            a[(n + k, 2 * n)] = kp * self.actuator.gain_m_per_v() * phi_a[k] / m;
        }
        let wa = 2.0 * std::f64::consts::PI * self.actuator.bandwidth_hz;
        a[(2 * n, 2 * n)] = -wa;
        let mut b_w = DMatrix::zeros(size, 1);
        let mut b_u = DMatrix::zeros(size, 1);
        let mut c_y = DMatrix::zeros(1, size);
        let mut c_z = DMatrix::zeros(1, size);
        for k in 0..n {
            b_w[(n + k, 0)] = 1.0 / m;
            c_y[(0, k)] = clamped_free_shape(k, xi_s);
            c_z[(0, k)] = 1.0;
        }
        b_u[(2 * n, 0)] = wa;
        Ok(BladePlant {
            a,
            b_w,
            b_u,
            c_y,
            c_z,
            tip_modes: modes,
        })
    }
}

impl BladePlant {
    /// Number of structural modes n.
    pub fn modes(&self) -> usize {
        self.tip_modes.len()
    }

    /// Static tip stiffness of the model with the stack held (e = 0), N/mm.
    pub fn static_tip_stiffness_n_per_mm(&self) -> f64 {
        let n = self.modes();
        // With q̇ = 0, e = 0: 0 = A_qq q + B F  →  tip = C_z q.
        let k_over_m = -self.a.view((n, 0), (n, n)).into_owned();
        let f = self.b_w.view((n, 0), (n, 1)).into_owned();
        match k_over_m.lu().solve(&f) {
            Some(q) => 1e-3 / q.sum(),
            None => 0.0,
        }
    }

    /// Natural frequencies (Hz) of the blade with the stack held, ascending.
    pub fn frequencies_hz(&self) -> Vec<f64> {
        let n = self.modes();
        let k_over_m = -self.a.view((n, 0), (n, n)).into_owned();
        let sym = (&k_over_m + k_over_m.transpose()) * 0.5;
        let mut f: Vec<f64> = sym
            .symmetric_eigenvalues()
            .iter()
            .map(|l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
            .collect();
        f.sort_by(f64::total_cmp);
        f
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The study's blade: steel 5 × 80 × 160 mm (thickness × width × length), stack at 36 mm.
    pub(crate) fn study_blade(modes: usize) -> Blade {
        Blade {
            youngs_modulus_pa: 210e9,
            density_kg_per_m3: 7850.0,
            length_mm: 160.0,
            width_mm: 80.0,
            thickness_mm: 5.0,
            modes,
            damping_ratio: 0.01,
            sensor_position_mm: 160.0,
            actuator: Actuator {
                position_mm: 36.0,
                stiffness_n_per_um: 185.0,
                stroke_um: 30.0,
                max_voltage_v: 150.0,
                bandwidth_hz: 2000.0,
            },
        }
    }

    #[test]
    fn the_propped_blade_tip_stiffness_is_near_the_studys() {
        let b = study_blade(4);
        // 3EI/L³ = 3·210e9·(80·5³/12 mm⁴)/160³ mm³ = 128.17 N/mm.
        assert!((b.cantilever_tip_stiffness_n_per_mm() - 128.17).abs() < 0.01);
        let exact = b.propped_tip_stiffness_n_per_mm();
        assert!((exact / 215.7 - 1.0).abs() < 0.01, "{exact}");
        // The truncated model is stiffer (Rayleigh–Ritz) and converges to the exact value.
        let k4 = b.plant().unwrap().static_tip_stiffness_n_per_mm();
        let k8 = study_blade(8)
            .plant()
            .unwrap()
            .static_tip_stiffness_n_per_mm();
        assert!(k4 >= k8 && k8 >= exact * 0.999, "{k4} {k8} {exact}");
        assert!(k8 / exact - 1.0 < 0.03, "{k8} {exact}");
    }

    #[test]
    fn without_the_stack_the_modes_are_the_cantilevers() {
        let mut b = study_blade(3);
        b.actuator.stiffness_n_per_um = 1e-9;
        let p = b.plant().unwrap();
        let f = p.frequencies_hz();
        for (fk, mk) in f.iter().zip(&p.tip_modes) {
            assert!((fk / mk.frequency_hz - 1.0).abs() < 1e-6);
        }
        assert!((p.static_tip_stiffness_n_per_mm() / b.cantilever_tip_stiffness_n_per_mm()) < 1.03);
    }

    #[test]
    fn a_stack_extension_moves_the_blade_at_a_by_the_spring_share() {
        // Static response to u: exact beam w(a) = g V · k_p f_aa / (1 + k_p f_aa), f_aa = a³/3EI
        // (the blade's own flexibility at a in series with the stack).
        let b = study_blade(6);
        let p = b.plant().unwrap();
        let s = StateSpaceCheck::dc(&p);
        let xi_a = b.actuator.position_mm / b.length_mm;
        let n = p.modes();
        let w_a: f64 = (0..n).map(|k| clamped_free_shape(k, xi_a) * s[k]).sum();
        let g = b.actuator.gain_m_per_v();
        let kf = b.actuator.stiffness_n_per_um * 1e6 * (b.actuator.position_mm * 1e-3).powi(3)
            / (3.0 * b.bending_stiffness_n_m2());
        let exact = kf / (1.0 + kf);
        assert!(
            (w_a / g / exact - 1.0).abs() < 0.01,
            "{} vs {exact}",
            w_a / g
        );
    }

    struct StateSpaceCheck;
    impl StateSpaceCheck {
        fn dc(p: &BladePlant) -> DVector<f64> {
            let x = (-&p.a).lu().solve(&p.b_u).unwrap();
            x.column(0).into_owned()
        }
    }
}
