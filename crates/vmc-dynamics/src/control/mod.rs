//! Active chatter control: a piezo-actuated cantilever blade and its controllers.
//!
//! Model: the blade of [`blade`] is an Euler–Bernoulli cantilever milled at its free end and
//! driven by a stiff piezo stack at x = a (penalty spring), in the state-space form
//! ẋ = A x + B_w w + B_u u, y = C x ([`StateSpace`]). Controllers come from Riccati equations
//! ([`riccati`]): LQG ([`lqg`], LQR + Kalman filter) and H∞ ([`hinf`], Glover–Doyle central
//! controller, γ by bisection, optional low-pass output filter). [`pade`] gives the state-space
//! Padé approximation of the regenerative delay e^(−sτ) for designs on the structure coupled to
//! the cutting process; [`closed_loop`] joins plant and controller (poles, FRF attenuation,
//! actuator effort, the augmented matrix for closed-loop semi-discretisation).
//!
//! Units: SI unless a name says otherwise; the control input u is the amplifier voltage in V.
//! Pure numerics: no I/O.

pub mod blade;
pub mod closed_loop;
pub mod design;
pub mod hinf;
pub mod lqg;
pub mod pade;
pub mod riccati;
pub mod robust;
pub mod simulate;

use nalgebra::{Complex, DMatrix};
use thiserror::Error;

/// Errors of the control designs.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ControlError {
    /// A parameter is out of range.
    #[error(transparent)]
    Invalid(#[from] crate::params::DynamicsError),
    /// A dimension does not fit.
    #[error("{what}: expected {expected}, got {got}")]
    Dimension {
        /// What was checked.
        what: &'static str,
        /// Expected size.
        expected: usize,
        /// Size given.
        got: usize,
    },
    /// A Riccati equation has no stabilising solution (e.g. its Hamiltonian has eigenvalues on
    /// the imaginary axis, or the pair is not stabilisable/detectable).
    #[error("the {0} Riccati equation has no stabilising solution")]
    NoStabilisingSolution(&'static str),
    /// A matrix that must be invertible is singular.
    #[error("{0} is singular")]
    Singular(&'static str),
    /// The loop of the structure and the controller is unstable without cutting.
    #[error("the closed loop is unstable without cutting")]
    UnstableLoop,
    /// The controller's sampling cannot see a mode it acts on.
    #[error("a controller sampled at {sample_rate_hz} Hz cannot act on the {mode_hz:.1} Hz mode it claims to: its Nyquist frequency with a margin needs >= {needed_hz:.0} Hz (raise controller.sample_rate_hz)")]
    Undersampled {
        /// The sample rate, Hz.
        sample_rate_hz: f64,
        /// The highest mode the controller acts on, Hz.
        mode_hz: f64,
        /// The least sample rate that would do, Hz.
        needed_hz: f64,
    },
    /// No γ in the searched range gives an H∞ controller.
    #[error("no H-infinity controller with gamma <= {0}")]
    GammaTooSmall(f64),
}

/// A linear time-invariant system ẋ = A x + B u, y = C x + D u.
#[derive(Debug, Clone, PartialEq)]
pub struct StateSpace {
    /// State matrix A (n × n).
    pub a: DMatrix<f64>,
    /// Input matrix B (n × m).
    pub b: DMatrix<f64>,
    /// Output matrix C (p × n).
    pub c: DMatrix<f64>,
    /// Feed-through D (p × m).
    pub d: DMatrix<f64>,
}

impl StateSpace {
    /// A system with the given matrices (checks the dimensions).
    pub fn new(
        a: DMatrix<f64>,
        b: DMatrix<f64>,
        c: DMatrix<f64>,
        d: DMatrix<f64>,
    ) -> Result<Self, ControlError> {
        let n = a.nrows();
        check("A columns", n, a.ncols())?;
        check("B rows", n, b.nrows())?;
        check("C columns", n, c.ncols())?;
        check("D rows", c.nrows(), d.nrows())?;
        check("D columns", b.ncols(), d.ncols())?;
        Ok(Self { a, b, c, d })
    }

    /// Number of states.
    pub fn states(&self) -> usize {
        self.a.nrows()
    }

    /// The same system in balanced coordinates (see [`balance`]).
    pub fn balanced(&self) -> Self {
        let (a, d) = balance(&self.a, 0);
        Self {
            a,
            b: DMatrix::from_fn(self.b.nrows(), self.b.ncols(), |i, j| self.b[(i, j)] / d[i]),
            c: DMatrix::from_fn(self.c.nrows(), self.c.ncols(), |i, j| self.c[(i, j)] * d[j]),
            d: self.d.clone(),
        }
    }

    /// Frequency response G(iω) = C (iω I − A)⁻¹ B + D (p × m).
    pub fn frf(&self, omega_rad_per_s: f64) -> DMatrix<Complex<f64>> {
        let n = self.states();
        let m = DMatrix::from_fn(n, n, |i, j| {
            let diag = if i == j { omega_rad_per_s } else { 0.0 };
            Complex::new(-self.a[(i, j)], diag)
        });
        let b = self.b.map(|v| Complex::new(v, 0.0));
        let x = m
            .lu()
            .solve(&b)
            .unwrap_or_else(|| DMatrix::from_element(n, b.ncols(), Complex::new(f64::NAN, 0.0)));
        self.c.map(|v| Complex::new(v, 0.0)) * x + self.d.map(|v| Complex::new(v, 0.0))
    }

    /// Eigenvalues of A (the poles), computed on the balanced matrix.
    pub fn poles(&self) -> Vec<Complex<f64>> {
        balance(&self.a, 0)
            .0
            .complex_eigenvalues()
            .iter()
            .copied()
            .collect()
    }
}

fn check(what: &'static str, expected: usize, got: usize) -> Result<(), ControlError> {
    if expected == got {
        Ok(())
    } else {
        Err(ControlError::Dimension {
            what,
            expected,
            got,
        })
    }
}

/// Diagonal balancing (Parlett–Reinsch, powers of 2): scales d with D⁻¹ A D better conditioned
/// for eigenvalues and solves; the first `fixed` states keep the scale 1 (their units matter
/// to the caller). Returns (D⁻¹ A D, d).
pub fn balance(a: &DMatrix<f64>, fixed: usize) -> (DMatrix<f64>, Vec<f64>) {
    let n = a.nrows();
    let mut m = a.clone();
    let mut d = vec![1.0; n];
    for _ in 0..100 {
        let mut done = true;
        for i in fixed..n {
            let (mut c, mut r) = (0.0, 0.0);
            for j in 0..n {
                if j != i {
                    c += m[(j, i)].abs();
                    r += m[(i, j)].abs();
                }
            }
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let mut f = 1.0;
            let s = c + r;
            while c < r / 2.0 {
                c *= 2.0;
                r /= 2.0;
                f *= 2.0;
            }
            while c >= r * 2.0 {
                c /= 2.0;
                r *= 2.0;
                f /= 2.0;
            }
            if (c + r) < 0.95 * s {
                done = false;
                d[i] *= f;
                for j in 0..n {
                    m[(j, i)] *= f;
                    m[(i, j)] /= f;
                }
            }
        }
        if done {
            break;
        }
    }
    (m, d)
}

/// Largest singular value of a complex matrix (2-norm).
pub fn max_singular_value(m: &DMatrix<Complex<f64>>) -> f64 {
    if m.is_empty() {
        return 0.0;
    }
    m.clone().singular_values().max()
}
