//! Modal model of the tool tip and its state-space form.
//!
//! Each mode k (direction x or y, mode shape 1 at the tip) obeys
//! m_k q̈_k + 2ζ_k ω_k m_k q̇_k + k_k q_k = F_dir, and the tip displacement in a direction is
//! the sum of its modal coordinates. The state is s = [q; q̇] (2·n_modes), and
//! ṡ = A s + B_in F, p = C s with p the tip displacements of the flexible directions only
//! (a direction without modes is rigid and dropped, so the delayed state stays small).

use nalgebra::{Complex, DMatrix, Matrix2};

use crate::params::{DynamicsError, Mode, TipModes};

/// A feed-plane direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// Feed direction x.
    X,
    /// Normal direction y.
    Y,
}

impl Axis {
    fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
        }
    }
}

/// State-space modal model of the tool tip.
#[derive(Debug, Clone, PartialEq)]
pub struct ModalModel {
    modes: Vec<(Axis, Mode)>,
    axes: Vec<Axis>,
}

impl ModalModel {
    /// Builds the model from validated tip modes.
    pub fn new(modes: &TipModes) -> Result<Self, DynamicsError> {
        modes.validate()?;
        let list: Vec<(Axis, Mode)> = modes
            .x
            .iter()
            .map(|m| (Axis::X, *m))
            .chain(modes.y.iter().map(|m| (Axis::Y, *m)))
            .collect();
        let mut axes = Vec::new();
        if !modes.x.is_empty() {
            axes.push(Axis::X);
        }
        if !modes.y.is_empty() {
            axes.push(Axis::Y);
        }
        Ok(Self { modes: list, axes })
    }

    /// Number of modes.
    pub fn mode_count(&self) -> usize {
        self.modes.len()
    }

    /// State dimension 2·n_modes.
    pub fn state_dim(&self) -> usize {
        2 * self.modes.len()
    }

    /// Flexible directions, in the order of the output rows.
    pub fn axes(&self) -> &[Axis] {
        &self.axes
    }

    /// Free-vibration system matrix A = [0, I; −ω², −2ζω].
    pub fn system_matrix(&self) -> DMatrix<f64> {
        let n = self.mode_count();
        let mut a = DMatrix::zeros(2 * n, 2 * n);
        for (k, (_, m)) in self.modes.iter().enumerate() {
            let w = m.omega_rad_per_s();
            a[(k, n + k)] = 1.0;
            a[(n + k, k)] = -w * w;
            a[(n + k, n + k)] = -2.0 * m.damping_ratio * w;
        }
        a
    }

    /// Output matrix C (d × 2n): tip displacement of each flexible direction.
    pub fn output_matrix(&self) -> DMatrix<f64> {
        let mut c = DMatrix::zeros(self.axes.len(), self.state_dim());
        for (k, (ax, _)) in self.modes.iter().enumerate() {
            c[(self.row(*ax), k)] = 1.0;
        }
        c
    }

    /// Output matrix of the tip velocities (d × 2n).
    pub fn velocity_output_matrix(&self) -> DMatrix<f64> {
        let n = self.mode_count();
        let mut c = DMatrix::zeros(self.axes.len(), self.state_dim());
        for (k, (ax, _)) in self.modes.iter().enumerate() {
            c[(self.row(*ax), n + k)] = 1.0;
        }
        c
    }

    /// Input matrix B_in (2n × d): a tip force in a flexible direction drives q̈_k by 1/m_k.
    pub fn input_matrix(&self) -> DMatrix<f64> {
        let n = self.mode_count();
        let mut b = DMatrix::zeros(self.state_dim(), self.axes.len());
        for (k, (ax, m)) in self.modes.iter().enumerate() {
            b[(n + k, self.row(*ax))] = 1.0 / m.modal_mass_kg();
        }
        b
    }

    fn row(&self, ax: Axis) -> usize {
        self.axes.iter().position(|a| *a == ax).unwrap_or(0)
    }

    /// Restricts a 2×2 x/y matrix to the flexible directions (d × d).
    pub fn restrict(&self, m: &Matrix2<f64>) -> DMatrix<f64> {
        let d = self.axes.len();
        DMatrix::from_fn(d, d, |i, j| m[(self.axes[i].index(), self.axes[j].index())])
    }

    /// Tip frequency-response matrix G(iω) in m/N (x/y; rigid directions give 0).
    pub fn frf(&self, omega_rad_per_s: f64) -> Matrix2<Complex<f64>> {
        let mut g = Matrix2::from_element(Complex::new(0.0, 0.0));
        for (ax, m) in &self.modes {
            let r = omega_rad_per_s / m.omega_rad_per_s();
            let den = Complex::new(1.0 - r * r, 2.0 * m.damping_ratio * r) * m.stiffness_n_per_m;
            let i = ax.index();
            g[(i, i)] += Complex::new(1.0, 0.0) / den;
        }
        g
    }

    /// Natural frequencies of all modes in Hz.
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.modes.iter().map(|(_, m)| m.frequency_hz).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frf_static_value_is_compliance_and_state_space_matches() {
        let m = Mode::from_mass(922.0, 0.011, 0.03993);
        let model = ModalModel::new(&TipModes::x_only(vec![m])).unwrap();
        let g0 = model.frf(0.0);
        assert!((g0[(0, 0)].re * m.stiffness_n_per_m - 1.0).abs() < 1e-12);
        assert_eq!(g0[(1, 1)].norm(), 0.0);
        // C (−A)⁻¹ B = static compliance.
        let a = model.system_matrix();
        let x = (-a).try_inverse().unwrap();
        let s = model.output_matrix() * x * model.input_matrix();
        assert!((s[(0, 0)] * m.stiffness_n_per_m - 1.0).abs() < 1e-9);
        assert!((m.modal_mass_kg() - 0.03993).abs() < 1e-15);
    }
}
