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
//!
//! **Speed inputs** (a column whose unit is `rpm`, e.g. `spindle_rpm`, when
//! [`FeatureSpec::speed_exponents`] is not empty) are not temperatures but the cause of the
//! heating: the bearings' and motor's heat input grows roughly as a power of the speed,
//! `q = (|n| / 1000 rpm)^k`, and a lumped part of the structure warms through a first-order lag
//! of it. Their features are a grey-box bank: for each exponent k, `q_k` as is (fast effects,
//! e.g. the spindle's centrifugal and bearing-preload growth) and `lowpass_τ(q_k)` for each τ of
//! the bank (the temperature rise of a part with time constant τ driven by that heat input). A
//! linear model on this bank is a sum of first-order transfer functions from `q_k` to the drift
//! (an output-error model with the gains fitted and the exponents and time constants taken from
//! the banks), so fitting stays linear and convex. Feature layout per speed input: for each k,
//! `q_k`, then `lowpass_τ(q_k)` for each τ. Unit: (krpm)^k.
//!
//! **Relative temperatures** ([`FeatureSpec::relative_to_mean`], off by default): every
//! temperature input (every input that is not a speed with heat-input features) is replaced by
//! its difference to the mean of those inputs at the same row, `x_j − x̄`, before the filter
//! bank. The features then describe the machine's temperature *gradients* and are blind to a
//! uniform change of all temperatures (e.g. the whole shop warming up), which a model fitted on
//! a few cycles can otherwise mistake for a cause of a slow drift trend. Needs at least two
//! temperature inputs.

use serde::{Deserialize, Serialize};

use super::ThermalFitError;

/// The feature construction stored with a model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FeatureSpec {
    /// Time constants of the filter bank, s (default: 900, 3600, 10800 s: 15 min, 1 h, 3 h,
    /// spanning the time scales of a spindle warm-up; ≤ 0 or non-finite values are rejected).
    pub time_constants_s: Vec<f64>,
    /// Exponents k of the heat-input features `(|n|/1000 rpm)^k` of speed inputs (columns whose
    /// unit is `rpm`); empty: speed inputs are treated like temperatures (default: 1, 2, 3;
    /// bearing friction heat grows between linearly and with the cube of the speed; finite,
    /// > 0).
    #[serde(default)]
    pub speed_exponents: Vec<f64>,
    /// Temperatures as differences to their mean at each row (see the module doc; default:
    /// false).
    #[serde(default)]
    pub relative_to_mean: bool,
}

impl Default for FeatureSpec {
    fn default() -> Self {
        Self {
            time_constants_s: vec![900.0, 3600.0, 10800.0],
            speed_exponents: vec![1.0, 2.0, 3.0],
            relative_to_mean: false,
        }
    }
}

/// Largest speed exponent accepted (the same rule as the predictor's speed input).
pub use crate::history::MAX_SPEED_EXPONENT;

/// True for an input column that is a speed (unit `rpm`), from its name.
pub fn is_speed(name: &str) -> bool {
    name.rsplit_once('_').is_some_and(|(_, u)| u == "rpm")
}

impl FeatureSpec {
    /// How far back the filters remember, s: three times the longest time constant (a
    /// starting state has decayed to e⁻³ ≈ 5 % of its size by then); 0 without filters.
    /// Predictions closer than this to the first row depend on the state assumed there (the
    /// inputs at rest at their first values).
    pub fn memory_s(&self) -> f64 {
        3.0 * self.time_constants_s.iter().copied().fold(0.0, f64::max)
    }

    /// Checks the time constants.
    pub fn validate(&self) -> Result<(), ThermalFitError> {
        if let Some(t) = crate::history::invalid_tau(&self.time_constants_s) {
            return Err(ThermalFitError::BadSettings {
                field: "time_constants_s",
                reason: format!("every time constant must be finite and > 0 s, got {t}"),
            });
        }
        if let Some(k) = crate::history::invalid_speed_exponent(&self.speed_exponents) {
            return Err(ThermalFitError::BadSettings {
                field: "speed_exponents",
                reason: if k.abs() < 1e6 {
                    format!("every speed exponent must lie in (0, {MAX_SPEED_EXPONENT}], got {k}")
                } else {
                    format!("every speed exponent must lie in (0, {MAX_SPEED_EXPONENT}], got {k:e}")
                },
            });
        }
        Ok(())
    }

    /// Checks the settings against the input names (relative temperatures need two).
    pub fn validate_inputs<S: AsRef<str>>(&self, names: &[S]) -> Result<(), ThermalFitError> {
        self.validate()?;
        let temperatures = names
            .iter()
            .filter(|n| !self.heat_input(n.as_ref()))
            .count();
        if self.relative_to_mean && temperatures < 2 {
            return Err(ThermalFitError::BadSettings {
                field: "relative_to_mean",
                reason: format!(
                    "temperatures relative to their mean need at least two temperature inputs, \
                     got {temperatures}"
                ),
            });
        }
        Ok(())
    }

    /// True when input `name` gets the heat-input features (a speed, and exponents given).
    pub fn heat_input(&self, name: &str) -> bool {
        !self.speed_exponents.is_empty() && is_speed(name)
    }

    /// Features of input `name`.
    pub fn per_input(&self, name: &str) -> usize {
        let per_signal = 1 + self.time_constants_s.len();
        if self.heat_input(name) {
            self.speed_exponents.len() * per_signal
        } else {
            per_signal
        }
    }

    /// Width of a feature row for inputs `names`.
    pub fn width<S: AsRef<str>>(&self, names: &[S]) -> usize {
        names.iter().map(|n| self.per_input(n.as_ref())).sum()
    }

    /// Feature names for inputs `names`, in feature order: for a temperature `<input>`, then
    /// `<input>-lowpass<τ>s` for each τ (the difference input − filtered input); for a speed
    /// with heat-input features, for each k `<input>^k` then `lowpass<τ>s(<input>^k)`.
    pub fn names<S: AsRef<str>>(&self, names: &[S]) -> Vec<String> {
        let mut out = Vec::new();
        for n in names {
            let n = n.as_ref();
            if self.heat_input(n) {
                for k in &self.speed_exponents {
                    out.push(format!("{n}^{k}"));
                    for t in &self.time_constants_s {
                        out.push(format!("lowpass{t}s({n}^{k})"));
                    }
                }
            } else {
                let n = if self.relative_to_mean {
                    format!("({n}-mean)")
                } else {
                    n.to_string()
                };
                out.push(n.clone());
                for t in &self.time_constants_s {
                    out.push(format!("{n}-lowpass{t}s"));
                }
            }
        }
        out
    }

    /// [`Self::compute`], refusing a non-finite feature (named, with its row's time).
    ///
    /// # Errors
    /// [`ThermalFitError::NonFiniteFeature`] for the first one.
    pub fn compute_checked<S: AsRef<str>>(
        &self,
        time_s: &[f64],
        names: &[S],
        inputs: &[&[f64]],
    ) -> Result<Vec<f64>, ThermalFitError> {
        let out = self.compute(time_s, names, inputs);
        let width = self.width(names).max(1);
        match out.iter().position(|v| !v.is_finite()) {
            None => Ok(out),
            Some(i) => Err(ThermalFitError::NonFiniteFeature {
                feature: self
                    .names(names)
                    .get(i % width)
                    .cloned()
                    .unwrap_or_default(),
                time_s: time_s.get(i / width).copied().unwrap_or(f64::NAN),
            }),
        }
    }

    /// Feature rows (row-major, `time_s.len()` × [`FeatureSpec::width`]) of the input columns
    /// `inputs` named `names` sampled at `time_s` (strictly increasing, s).
    pub fn compute<S: AsRef<str>>(
        &self,
        time_s: &[f64],
        names: &[S],
        inputs: &[&[f64]],
    ) -> Vec<f64> {
        let n_rows = time_s.len();
        let width = self.width(names);
        let mut out = vec![0.0; n_rows * width];
        // Mean of the temperature inputs per row, when they are taken relative to it.
        let temperatures: Vec<&[f64]> = names
            .iter()
            .zip(inputs)
            .filter(|(n, _)| !self.heat_input(n.as_ref()))
            .map(|(_, x)| *x)
            .collect();
        let mean: Vec<f64> = if self.relative_to_mean && !temperatures.is_empty() {
            (0..n_rows)
                .map(|r| temperatures.iter().map(|x| x[r]).sum::<f64>() / temperatures.len() as f64)
                .collect()
        } else {
            Vec::new()
        };
        let mut base = 0;
        let mut column = |signal: &[f64], difference: bool, base: usize| {
            self.filter_bank(time_s, signal, difference, &mut out, width, base);
        };
        for (name, x) in names.iter().zip(inputs) {
            if self.heat_input(name.as_ref()) {
                for k in &self.speed_exponents {
                    let q: Vec<f64> = x.iter().map(|v| (v.abs() / 1000.0).powf(*k)).collect();
                    column(&q, false, base);
                    base += 1 + self.time_constants_s.len();
                }
            } else if mean.is_empty() {
                column(x, true, base);
                base += 1 + self.time_constants_s.len();
            } else {
                let relative: Vec<f64> = x.iter().zip(&mean).map(|(v, m)| v - m).collect();
                column(&relative, true, base);
                base += 1 + self.time_constants_s.len();
            }
        }
        out
    }

    /// Writes `x`, then for each τ `x − lowpass_τ(x)` (`difference`) or `lowpass_τ(x)`, into
    /// columns `base…` of the row-major `out` of width `width`.
    fn filter_bank(
        &self,
        time_s: &[f64],
        x: &[f64],
        difference: bool,
        out: &mut [f64],
        width: usize,
        base: usize,
    ) {
        let n_tau = self.time_constants_s.len();
        let mut state: Vec<f64> = vec![x.first().copied().unwrap_or(0.0); n_tau];
        for n in 0..time_s.len().min(x.len()) {
            let row = &mut out[n * width + base..n * width + base + 1 + n_tau];
            row[0] = x[n];
            if n > 0 {
                let dt_s = time_s[n] - time_s[n - 1];
                for (f, tau) in state.iter_mut().zip(&self.time_constants_s) {
                    let a = 1.0 - (-dt_s / tau).exp();
                    *f += a * (x[n] - *f);
                }
            }
            for (k, f) in state.iter().enumerate() {
                row[1 + k] = if difference { x[n] - f } else { *f };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_memory_is_three_of_the_longest_time_constants_and_none_without_filters() {
        let spec = FeatureSpec::default();
        assert_eq!(spec.memory_s(), 3.0 * 10800.0);
        let none = FeatureSpec {
            time_constants_s: Vec::new(),
            ..FeatureSpec::default()
        };
        assert_eq!(none.memory_s(), 0.0);
    }

    #[test]
    fn filter_of_a_step_follows_one_minus_exp_minus_t_over_tau() {
        // Input 20 °C at t = 0, then 30 °C from the first step on; τ = 600 s, Δt = 15 s.
        let spec = FeatureSpec {
            time_constants_s: vec![600.0],
            speed_exponents: Vec::new(),
            relative_to_mean: false,
        };
        let t: Vec<f64> = (0..200).map(|i| 15.0 * f64::from(i)).collect();
        let x: Vec<f64> = (0..200).map(|i| if i == 0 { 20.0 } else { 30.0 }).collect();
        let f = spec.compute(&t, &["t1_degc"], &[&x]);
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
    fn a_feature_that_overflows_is_named_with_its_time() {
        let spec = FeatureSpec {
            time_constants_s: vec![600.0],
            speed_exponents: vec![1.0, 3.0],
            relative_to_mean: false,
        };
        let t = [0.0, 15.0, 30.0];
        let rpm = [0.0, 1e200, 0.0];
        let err = spec
            .compute_checked(&t, &["spindle_rpm"], &[&rpm])
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "feature \"spindle_rpm^3\" is not finite at t = 15 s: an input value too large for \
             it (a corrupt cell or a unit mistake?)"
        );
        // Plain values pass, and so do they through the unchecked path, bit for bit.
        let ok = [0.0, 2000.0, 0.0];
        assert_eq!(
            spec.compute_checked(&t, &["spindle_rpm"], &[&ok]).unwrap(),
            spec.compute(&t, &["spindle_rpm"], &[&ok])
        );
        // Exponents beyond the bound are refused when the settings are checked.
        let wild = FeatureSpec {
            speed_exponents: vec![1e300],
            ..spec
        };
        assert!(wild.validate().is_err());
    }

    #[test]
    fn features_at_a_row_do_not_depend_on_later_rows() {
        let spec = FeatureSpec::default();
        let t: Vec<f64> = (0..50).map(|i| 15.0 * f64::from(i)).collect();
        let x: Vec<f64> = (0..50).map(|i| (f64::from(i) * 0.3).sin()).collect();
        let full = spec.compute(&t, &["t1_degc"], &[&x]);
        let part = spec.compute(&t[..20], &["t1_degc"], &[&x[..20]]);
        assert_eq!(&full[..part.len()], &part[..]);
    }

    #[test]
    fn a_speed_step_gives_lagged_powers_of_the_speed_in_krpm() {
        // 0 rpm at t = 0, then 2000 rpm; k = 2 → q = 4 (krpm)²; τ = 600 s, Δt = 15 s.
        let spec = FeatureSpec {
            time_constants_s: vec![600.0],
            speed_exponents: vec![1.0, 2.0],
            relative_to_mean: false,
        };
        let t: Vec<f64> = (0..100).map(|i| 15.0 * f64::from(i)).collect();
        let rpm: Vec<f64> = (0..100)
            .map(|i| if i == 0 { 0.0 } else { 2000.0 })
            .collect();
        let temp = vec![20.0; 100];
        let names = ["t1_degc", "spindle_rpm"];
        assert_eq!(spec.width(&names), 2 + 2 * 2);
        assert_eq!(
            spec.names(&names)[2..],
            [
                "spindle_rpm^1",
                "lowpass600s(spindle_rpm^1)",
                "spindle_rpm^2",
                "lowpass600s(spindle_rpm^2)"
            ]
        );
        let f = spec.compute(&t, &names, &[&temp, &rpm]);
        for n in 1..100 {
            let row = &f[6 * n..6 * (n + 1)];
            let lag = 1.0 - (-t[n] / 600.0).exp();
            assert_eq!(row[..2], [20.0, 0.0]);
            assert!((row[2] - 2.0).abs() < 1e-12 && (row[4] - 4.0).abs() < 1e-12);
            assert!((row[3] - 2.0 * lag).abs() < 1e-9, "row {n}");
            assert!((row[5] - 4.0 * lag).abs() < 1e-9, "row {n}");
        }
        // Without exponents a speed is filtered like a temperature.
        let plain = FeatureSpec {
            speed_exponents: Vec::new(),
            ..spec
        };
        assert_eq!(plain.width(&names), 4);
        assert!(plain.validate().is_ok());
        let bad = FeatureSpec {
            speed_exponents: vec![0.0],
            ..plain
        };
        assert!(bad.validate().is_err());
    }

    #[test]
    fn relative_temperatures_are_blind_to_a_uniform_change_and_keep_speeds_apart() {
        let spec = FeatureSpec {
            time_constants_s: vec![600.0],
            speed_exponents: vec![1.0],
            relative_to_mean: true,
        };
        let t: Vec<f64> = (0..40).map(|i| 15.0 * f64::from(i)).collect();
        let ramp: Vec<f64> = t.iter().map(|s| 20.0 + s / 600.0).collect();
        let t1: Vec<f64> = ramp.iter().map(|v| v + 1.0).collect();
        let t2: Vec<f64> = ramp.iter().map(|v| v - 1.0).collect();
        let rpm = vec![1500.0; 40];
        let names = ["t1_degc", "t2_degc", "spindle_rpm"];
        let f = spec.compute(&t, &names, &[&t1, &t2, &rpm]);
        assert_eq!(
            spec.names(&names)[..2],
            ["(t1_degc-mean)", "(t1_degc-mean)-lowpass600s"]
        );
        for n in 0..40 {
            // Both sensors ramp together: ±1 °C about the mean, filters settled at it.
            assert_eq!(f[6 * n..6 * n + 4], [1.0, 0.0, -1.0, 0.0], "row {n}");
            assert!((f[6 * n + 4] - 1.5).abs() < 1e-12);
        }
        assert!(spec.validate_inputs(&names).is_ok());
        assert!(spec.validate_inputs(&["t1_degc", "spindle_rpm"]).is_err());
    }
}
