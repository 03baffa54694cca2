//! Multiple linear regression, the "linear thermal model" baseline of the compensation study.
//!
//! Model, per output k: `y_k = c_k + Σ_j a_kj · x_j` (physical units).
//!
//! Fitting: inputs are z-scored (`z_j = (x_j − mean_j)/std_j`, see [`Normaliser`]) so that
//! sensors in °C and positions in mm are equally conditioned, then the least-squares problem
//! `min ‖Z β − y‖² + λ ‖β_slopes‖²` is solved by Householder QR of the augmented matrix
//! `[Z; √λ·I]` (the intercept column `1` of `Z` is not penalised). QR avoids squaring the
//! condition number as the normal equations would; with `λ = 0` it is plain least squares and
//! recovers noise-free linear data to round-off. The ridge λ acts on normalised slopes, so it is
//! dimensionless and comparable across inputs. The solution is converted back to physical
//! coefficients once, so prediction is one dot product per output.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::nn::{DataError, Normaliser, Samples};

/// Why a linear model could not be fitted or evaluated.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum LinRegError {
    /// Dataset problem.
    #[error(transparent)]
    Data(#[from] DataError),
    /// Fewer samples than coefficients (without ridge the problem is under-determined).
    #[error("{samples} samples cannot determine {coefficients} coefficients without ridge")]
    TooFewSamples {
        /// Samples given.
        samples: usize,
        /// Coefficients per output (inputs + 1).
        coefficients: usize,
    },
    /// The design matrix is rank deficient (collinear or constant inputs) and λ = 0.
    #[error("inputs are collinear or constant; use a small ridge")]
    RankDeficient,
    /// The ridge parameter is negative or not finite.
    #[error("ridge must be finite and ≥ 0, got {ridge}")]
    BadRidge {
        /// The rejected value.
        ridge: f64,
    },
    /// A buffer has the wrong length.
    #[error("{buffer}: expected {expected} values, got {got}")]
    BufferLength {
        /// Which buffer.
        buffer: &'static str,
        /// Required length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
}

/// A fitted multi-output linear model in physical units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinearModel {
    n_in: usize,
    n_out: usize,
    /// c_k, one per output (output unit).
    intercept: Vec<f64>,
    /// a_kj row-major (`n_out` rows × `n_in` columns), output unit per input unit.
    slopes: Vec<f64>,
    /// The ridge λ used in the fit (dimensionless, on normalised slopes).
    ridge: f64,
}

impl LinearModel {
    /// Fits all outputs of `data` by (ridge) least squares; `ridge = 0` for plain least squares.
    pub fn fit(data: &Samples, ridge: f64) -> Result<Self, LinRegError> {
        if !(ridge.is_finite() && ridge >= 0.0) {
            return Err(LinRegError::BadRidge { ridge });
        }
        let (n, n_in, n_out) = (data.len(), data.n_in(), data.n_out());
        let n_coef = n_in + 1;
        if n < n_coef && ridge == 0.0 {
            return Err(LinRegError::TooFewSamples {
                samples: n,
                coefficients: n_coef,
            });
        }
        let norm = Normaliser::fit_named(data.inputs(), n_in, "inputs")?;
        let rows = if ridge > 0.0 { n + n_in } else { n };
        let mut z = DMatrix::<f64>::zeros(rows, n_coef);
        let mut y = DMatrix::<f64>::zeros(rows, n_out);
        let mut zi = vec![0.0; n_in];
        for i in 0..n {
            norm.normalise_into(data.input(i), &mut zi);
            z[(i, 0)] = 1.0;
            for j in 0..n_in {
                z[(i, j + 1)] = zi[j];
            }
            for k in 0..n_out {
                y[(i, k)] = data.target(i)[k];
            }
        }
        for j in 0..n_in.min(rows - n) {
            z[(n + j, j + 1)] = ridge.sqrt();
        }
        let beta = solve_least_squares(z, y)?;
        // Back to physical units: y = β0 + Σ β_j (x_j − m_j)/s_j.
        let mut intercept = vec![0.0; n_out];
        let mut slopes = vec![0.0; n_out * n_in];
        for k in 0..n_out {
            let mut c = beta[(0, k)];
            for j in 0..n_in {
                let a = beta[(j + 1, k)] / norm.std[j];
                slopes[k * n_in + j] = a;
                c -= a * norm.mean[j];
            }
            intercept[k] = c;
        }
        Ok(Self {
            n_in,
            n_out,
            intercept,
            slopes,
            ridge,
        })
    }

    /// A model from its coefficients (physical units): `slopes` row-major `n_out × n_in`.
    pub(crate) fn from_coefficients(
        n_in: usize,
        intercept: Vec<f64>,
        slopes: Vec<f64>,
        ridge: f64,
    ) -> Self {
        debug_assert_eq!(slopes.len(), intercept.len() * n_in);
        Self {
            n_in,
            n_out: intercept.len(),
            intercept,
            slopes,
            ridge,
        }
    }

    /// Number of inputs.
    pub fn n_in(&self) -> usize {
        self.n_in
    }

    /// Number of outputs.
    pub fn n_out(&self) -> usize {
        self.n_out
    }

    /// Intercepts c_k (output units).
    pub fn intercept(&self) -> &[f64] {
        &self.intercept
    }

    /// Slopes a_kj, row-major `n_out × n_in` (output unit per input unit).
    pub fn slopes(&self) -> &[f64] {
        &self.slopes
    }

    /// The ridge λ the model was fitted with.
    pub fn ridge(&self) -> f64 {
        self.ridge
    }

    /// `out_k = c_k + Σ_j a_kj x_j` without allocation.
    pub fn predict_into(&self, x: &[f64], out: &mut [f64]) -> Result<(), LinRegError> {
        if x.len() != self.n_in {
            return Err(LinRegError::BufferLength {
                buffer: "input",
                expected: self.n_in,
                got: x.len(),
            });
        }
        if out.len() != self.n_out {
            return Err(LinRegError::BufferLength {
                buffer: "output",
                expected: self.n_out,
                got: out.len(),
            });
        }
        for ((o, c), row) in out
            .iter_mut()
            .zip(&self.intercept)
            .zip(self.slopes.chunks_exact(self.n_in))
        {
            *o = row.iter().zip(x).fold(*c, |acc, (a, xj)| acc + a * xj);
        }
        Ok(())
    }

    /// Prediction (allocates).
    pub fn predict(&self, x: &[f64]) -> Result<Vec<f64>, LinRegError> {
        let mut out = vec![0.0; self.n_out];
        self.predict_into(x, &mut out)?;
        Ok(out)
    }
}

/// Least squares `min ‖Z β − Y‖` by Householder QR (`Z` has at least as many rows as columns).
fn solve_least_squares(z: DMatrix<f64>, y: DMatrix<f64>) -> Result<DMatrix<f64>, LinRegError> {
    let n_coef = z.ncols();
    let qr = z.qr();
    let r = qr.r();
    // A pivot tiny relative to the largest one means a (numerically) collinear design.
    let max_pivot = r.diagonal().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if r.diagonal()
        .iter()
        .any(|v| v.abs() <= 1e-12 * max_pivot.max(f64::MIN_POSITIVE))
    {
        return Err(LinRegError::RankDeficient);
    }
    let mut qty = y;
    qr.q_tr_mul(&mut qty);
    let qty = qty.rows(0, n_coef).into_owned();
    r.solve_upper_triangular(&qty)
        .ok_or(LinRegError::RankDeficient)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Noise-free data: y0 = 2 + 0.5·x0 − 3·x1 + 0.01·x2, y1 = −1 + 4·x1 (x in mm/°C-like scales).
    fn linear_data() -> Samples {
        let mut rows_x = Vec::new();
        let mut rows_y = Vec::new();
        for i in 0..40 {
            let t = f64::from(i);
            let x = [
                100.0 + 7.0 * t,
                20.0 + (0.37 * t).sin() * 5.0,
                300.0 * (0.11 * t).cos(),
            ];
            rows_y.push(vec![
                2.0 + 0.5 * x[0] - 3.0 * x[1] + 0.01 * x[2],
                -1.0 + 4.0 * x[1],
            ]);
            rows_x.push(x.to_vec());
        }
        Samples::from_rows(&rows_x, &rows_y).unwrap()
    }

    #[test]
    fn least_squares_recovers_known_coefficients_of_noise_free_data() {
        let m = LinearModel::fit(&linear_data(), 0.0).unwrap();
        let want_slopes = [0.5, -3.0, 0.01, 0.0, 4.0, 0.0];
        let want_intercept = [2.0, -1.0];
        // Round-off only: 1e-9 of a unit (1e-9 µm if the outputs are µm).
        for (a, b) in m.slopes().iter().zip(&want_slopes) {
            assert!((a - b).abs() < 1e-9, "slopes {:?}", m.slopes());
        }
        for (a, b) in m.intercept().iter().zip(&want_intercept) {
            assert!((a - b).abs() < 1e-9, "intercept {:?}", m.intercept());
        }
        let p = m.predict(&[150.0, 21.0, -10.0]).unwrap();
        assert!((p[0] - (2.0 + 75.0 - 63.0 - 0.1)).abs() < 1e-9);
        assert!((p[1] - 83.0).abs() < 1e-9);
    }

    #[test]
    fn ridge_shrinks_slopes_towards_zero() {
        let plain = LinearModel::fit(&linear_data(), 0.0).unwrap();
        let ridged = LinearModel::fit(&linear_data(), 10.0).unwrap();
        let norm = |m: &LinearModel| m.slopes().iter().map(|a| a * a).sum::<f64>();
        assert!(norm(&ridged) < norm(&plain));
        assert_eq!(ridged.ridge(), 10.0);
    }

    #[test]
    fn collinear_inputs_without_ridge_are_rejected_but_fit_with_ridge() {
        let xs: Vec<Vec<f64>> = (0..10)
            .map(|i| vec![f64::from(i), 2.0 * f64::from(i)])
            .collect();
        let ys: Vec<Vec<f64>> = (0..10).map(|i| vec![f64::from(i)]).collect();
        let s = Samples::from_rows(&xs, &ys).unwrap();
        assert_eq!(LinearModel::fit(&s, 0.0), Err(LinRegError::RankDeficient));
        assert!(LinearModel::fit(&s, 1e-6).is_ok());
        assert!(matches!(
            LinearModel::fit(&s, -1.0),
            Err(LinRegError::BadRidge { .. })
        ));
        let tiny = Samples::from_rows(&xs[..2], &ys[..2]).unwrap();
        assert!(matches!(
            LinearModel::fit(&tiny, 0.0),
            Err(LinRegError::TooFewSamples {
                samples: 2,
                coefficients: 3
            })
        ));
    }

    #[test]
    fn json_round_trip_and_buffer_checks() {
        let m = LinearModel::fit(&linear_data(), 0.0).unwrap();
        let back: LinearModel = serde_json::from_str(&serde_json::to_string(&m).unwrap()).unwrap();
        let x = [123.0, 19.5, 42.0];
        assert_eq!(m.predict(&x).unwrap(), back.predict(&x).unwrap());
        assert!(m.predict(&[1.0]).is_err());
        assert!(m.predict_into(&x, &mut [0.0; 3]).is_err());
    }
}
