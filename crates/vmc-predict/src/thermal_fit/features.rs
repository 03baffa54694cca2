//! Causal features of the input series: each input as measured and through a bank of first-order
//! low-pass filters.
//!
//! Thermal drift lags temperature (heat has to diffuse from where a sensor sits to where the
//! structure deforms), so the drift at time t depends on the temperature history, not only on the
//! reading at t. A bank of first-order filters with time constants τ_k summarises that history:
//!
//! `f_k[0] = x[0]`, `f_k[n] = f_k[n−1] + (1 − e^(−Δt_n/τ_k)) · (x[n] − f_k[n−1])`,
//! `Δt_n = t[n] − t[n−1]` (s).
//!
//! This is the exact step response of `τ ḟ = x − f` for an input held between samples, so
//! irregular sampling is handled. The state at the first row is the first reading (the machine is
//! assumed in a steady state when the file starts: every filter output equals its input). Every
//! feature at row n uses rows 0…n only, so a real compensator can compute it on line.
//!
//! Feature layout per input j (in input order): `x_j`, then `x_j − f_{j,k}` for each τ_k. The
//! differences are used rather than the filtered values themselves because they carry the same
//! information (a linear model is indifferent) while being centred and well scaled for the net:
//! `x − f_k` is the part of the temperature that the structure with time constant τ_k has not
//! caught up with yet (≈ τ_k · ẋ for slow changes). Units: the input's unit.

use serde::{Deserialize, Serialize};

use super::ThermalFitError;

/// The feature construction stored with a model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FeatureSpec {
    /// Time constants of the filter bank, s (default: 900, 3600, 10800 s: 15 min, 1 h, 3 h,
    /// spanning the time scales of a spindle warm-up; ≤ 0 or non-finite values are rejected).
    pub time_constants_s: Vec<f64>,
}

impl Default for FeatureSpec {
    fn default() -> Self {
        Self {
            time_constants_s: vec![900.0, 3600.0, 10800.0],
        }
    }
}

impl FeatureSpec {
    /// Checks the time constants.
    pub fn validate(&self) -> Result<(), ThermalFitError> {
        if let Some(t) = self
            .time_constants_s
            .iter()
            .find(|t| !(t.is_finite() && **t > 0.0))
        {
            return Err(ThermalFitError::BadSettings {
                field: "time_constants_s",
                reason: format!("every time constant must be finite and > 0 s, got {t}"),
            });
        }
        Ok(())
    }

    /// Features per input.
    pub fn per_input(&self) -> usize {
        1 + self.time_constants_s.len()
    }

    /// Feature names for inputs `names`, in feature order: `<input>`, then `<input>-lowpass<τ>s`
    /// for each τ (the difference input − filtered input).
    pub fn names(&self, names: &[String]) -> Vec<String> {
        let mut out = Vec::new();
        for n in names {
            out.push(n.clone());
            for t in &self.time_constants_s {
                out.push(format!("{n}-lowpass{t}s"));
            }
        }
        out
    }

    /// Feature rows (row-major, `time_s.len()` × `inputs.len()·per_input()`) of the input
    /// columns `inputs` sampled at `time_s` (strictly increasing, s).
    pub fn compute(&self, time_s: &[f64], inputs: &[&[f64]]) -> Vec<f64> {
        let n_rows = time_s.len();
        let width = inputs.len() * self.per_input();
        let mut out = vec![0.0; n_rows * width];
        let n_tau = self.time_constants_s.len();
        for (j, x) in inputs.iter().enumerate() {
            let base = j * self.per_input();
            let mut state: Vec<f64> = vec![x.first().copied().unwrap_or(0.0); n_tau];
            for n in 0..n_rows {
                let row = &mut out[n * width + base..n * width + base + self.per_input()];
                row[0] = x[n];
                if n > 0 {
                    let dt_s = time_s[n] - time_s[n - 1];
                    for (f, tau) in state.iter_mut().zip(&self.time_constants_s) {
                        let a = 1.0 - (-dt_s / tau).exp();
                        *f += a * (x[n] - *f);
                    }
                }
                for (k, f) in state.iter().enumerate() {
                    row[1 + k] = x[n] - f;
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn filter_of_a_step_follows_one_minus_exp_minus_t_over_tau() {
        // Input 20 °C at t = 0, then 30 °C from the first step on; τ = 600 s, Δt = 15 s.
        let spec = FeatureSpec {
            time_constants_s: vec![600.0],
        };
        let t: Vec<f64> = (0..200).map(|i| 15.0 * f64::from(i)).collect();
        let x: Vec<f64> = (0..200).map(|i| if i == 0 { 20.0 } else { 30.0 }).collect();
        let f = spec.compute(&t, &[&x]);
        for n in 1..200 {
            let lowpass = 30.0 - 10.0 * (-t[n] / 600.0).exp();
            // x − f should equal 10·e^(−t/τ): exact discretisation, round-off only (1e-9 °C).
            assert!((f[2 * n + 1] - (30.0 - lowpass)).abs() < 1e-9, "row {n}");
            assert_eq!(f[2 * n], 30.0);
        }
        // Steady state at the first row: x − f = 0.
        assert_eq!(f[1], 0.0);
    }

    #[test]
    fn features_at_a_row_do_not_depend_on_later_rows() {
        let spec = FeatureSpec::default();
        let t: Vec<f64> = (0..50).map(|i| 15.0 * f64::from(i)).collect();
        let x: Vec<f64> = (0..50).map(|i| (f64::from(i) * 0.3).sin()).collect();
        let full = spec.compute(&t, &[&x]);
        let part = spec.compute(&t[..20], &[&x[..20]]);
        assert_eq!(&full[..part.len()], &part[..]);
    }
}
