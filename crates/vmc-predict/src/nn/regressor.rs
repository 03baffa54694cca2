//! An MLP in physical units: `y = denorm_out(mlp(norm_in(x)))`.

use serde::{Deserialize, Serialize};

use super::mlp::Mlp;
use super::normalise::Normaliser;
use super::samples::Samples;
use super::train::{train, TrainConfig, TrainReport};
use super::NnError;

/// A trained net together with the normalisations fitted on its training data.
///
/// Inputs and outputs are in physical units (whatever units the training samples used);
/// normalisation happens inside. Deserialisation checks that the parts fit together.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RegressorData", into = "RegressorData")]
pub struct Regressor {
    input_norm: Normaliser,
    output_norm: Normaliser,
    mlp: Mlp,
}

/// The serialised form of [`Regressor`].
#[derive(Serialize, Deserialize)]
struct RegressorData {
    /// Input normalisation (input units).
    input_norm: Normaliser,
    /// Output normalisation (output units).
    output_norm: Normaliser,
    /// The net, in normalised units.
    mlp: Mlp,
}

impl TryFrom<RegressorData> for Regressor {
    type Error = NnError;
    fn try_from(d: RegressorData) -> Result<Self, NnError> {
        Regressor::new(d.input_norm, d.output_norm, d.mlp)
    }
}

impl From<Regressor> for RegressorData {
    fn from(r: Regressor) -> Self {
        RegressorData {
            input_norm: r.input_norm,
            output_norm: r.output_norm,
            mlp: r.mlp,
        }
    }
}

impl Regressor {
    /// Assembles a regressor from its parts, checking widths and normaliser values.
    pub fn new(input_norm: Normaliser, output_norm: Normaliser, mlp: Mlp) -> Result<Self, NnError> {
        if !input_norm.is_valid(mlp.n_in()) {
            return Err(NnError::BadModel {
                reason: "input normaliser width or values do not fit the net",
            });
        }
        if !output_norm.is_valid(mlp.n_out()) {
            return Err(NnError::BadModel {
                reason: "output normaliser width or values do not fit the net",
            });
        }
        Ok(Self {
            input_norm,
            output_norm,
            mlp,
        })
    }

    /// Fits normalisers on `train`, then trains a `n_in → hidden… → n_out` net with
    /// [`train`](super::train). `val` (same units) drives early stopping and restart selection.
    pub fn fit(
        train_set: &Samples,
        val: Option<&Samples>,
        hidden: &[usize],
        config: &TrainConfig,
    ) -> Result<(Self, TrainReport), NnError> {
        if train_set.is_empty() {
            return Err(NnError::EmptyTrainingSet);
        }
        let input_norm = Normaliser::fit_named(train_set.inputs(), train_set.n_in(), "inputs")?;
        let output_norm = Normaliser::fit_named(train_set.targets(), train_set.n_out(), "targets")?;
        let normalise = |s: &Samples| {
            s.map_rows(
                |x, z| input_norm.normalise_into(x, z),
                |y, z| output_norm.normalise_into(y, z),
            )
        };
        let train_n = normalise(train_set);
        let val_n = match val {
            Some(v) => {
                if v.n_in() != train_set.n_in() || v.n_out() != train_set.n_out() {
                    return Err(NnError::WidthMismatch {
                        net_in: train_set.n_in(),
                        net_out: train_set.n_out(),
                        data_in: v.n_in(),
                        data_out: v.n_out(),
                    });
                }
                Some(normalise(v))
            }
            None => None,
        };
        let mut sizes = Vec::with_capacity(hidden.len() + 2);
        sizes.push(train_set.n_in());
        sizes.extend_from_slice(hidden);
        sizes.push(train_set.n_out());
        let (mlp, report) = train(&sizes, &train_n, val_n.as_ref(), config)?;
        Ok((Self::new(input_norm, output_norm, mlp)?, report))
    }

    /// Number of inputs.
    pub fn n_in(&self) -> usize {
        self.mlp.n_in()
    }

    /// Number of outputs.
    pub fn n_out(&self) -> usize {
        self.mlp.n_out()
    }

    /// The underlying net (normalised units).
    pub fn mlp(&self) -> &Mlp {
        &self.mlp
    }

    /// Input normalisation (input units).
    pub fn input_norm(&self) -> &Normaliser {
        &self.input_norm
    }

    /// Output normalisation (output units).
    pub fn output_norm(&self) -> &Normaliser {
        &self.output_norm
    }

    /// Scratch length [`Regressor::predict_into`] needs.
    pub fn scratch_len(&self) -> usize {
        self.mlp.n_in() + self.mlp.scratch_len()
    }

    /// Prediction in physical units without allocation.
    ///
    /// `x.len() == n_in()`, `out.len() == n_out()`, `scratch.len() >= scratch_len()`.
    pub fn predict_into(
        &self,
        x: &[f64],
        scratch: &mut [f64],
        out: &mut [f64],
    ) -> Result<(), NnError> {
        let n_in = self.mlp.n_in();
        if x.len() != n_in {
            return Err(NnError::BufferLength {
                buffer: "input",
                expected: n_in,
                got: x.len(),
            });
        }
        if scratch.len() < self.scratch_len() {
            return Err(NnError::BufferLength {
                buffer: "scratch",
                expected: self.scratch_len(),
                got: scratch.len(),
            });
        }
        let (z, rest) = scratch.split_at_mut(n_in);
        self.input_norm.normalise_into(x, z);
        self.mlp.forward_into(z, rest, out)?;
        self.output_norm.denormalise_in_place(out);
        Ok(())
    }

    /// Prediction in physical units (allocates; use `predict_into` in loops).
    pub fn predict(&self, x: &[f64]) -> Result<Vec<f64>, NnError> {
        let mut out = vec![0.0; self.n_out()];
        let mut scratch = vec![0.0; self.scratch_len()];
        self.predict_into(x, &mut scratch, &mut out)?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::Metrics;
    use std::f64::consts::PI;

    /// RMSE of `model` on `data`, per output, through the public metrics.
    fn rmse_per_output(model: &Regressor, data: &Samples) -> Vec<f64> {
        (0..data.n_out())
            .map(|k| {
                let y: Vec<f64> = (0..data.len()).map(|i| data.target(i)[k]).collect();
                let p: Vec<f64> = (0..data.len())
                    .map(|i| model.predict(data.input(i)).unwrap()[k])
                    .collect();
                Metrics::of(&y, &p).unwrap().rmse
            })
            .collect()
    }

    #[test]
    fn lm_fits_sin_on_minus_pi_to_pi_to_rmse_below_1e_minus_3() {
        let grid = |n: usize, shift: f64| -> Samples {
            let x: Vec<f64> = (0..n)
                .map(|i| -PI + 2.0 * PI * (i as f64 + shift) / (n - 1) as f64)
                .filter(|v| *v <= PI)
                .collect();
            let y = x.iter().map(|v| v.sin()).collect();
            Samples::new(1, 1, x, y).unwrap()
        };
        let train_set = grid(101, 0.0);
        let test_set = grid(77, 0.37);
        let config = TrainConfig {
            max_epochs: 300,
            target_rmse: 1e-5,
            ..TrainConfig::default()
        };
        let (model, report) = Regressor::fit(&train_set, None, &[8], &config).unwrap();
        let rmse = rmse_per_output(&model, &test_set)[0];
        assert!(rmse < 1e-3, "test RMSE {rmse}, report {report:?}");
    }

    #[test]
    fn lm_fits_a_smooth_two_input_two_output_function_jointly() {
        // Inputs in physical-looking units (position 0…500 mm, temperature 20…30 °C) to exercise
        // the normalisation; outputs in µm.
        let f = |x_mm: f64, t_degc: f64| {
            let u = x_mm / 500.0;
            let v = (t_degc - 20.0) / 10.0;
            [
                10.0 * (PI * u).sin() * (1.0 + 0.5 * v),
                -5.0 + 8.0 * v * v + 3.0 * u * v,
            ]
        };
        let grid = |n: usize, shift: f64| -> Samples {
            let mut xs = Vec::new();
            let mut ys = Vec::new();
            for i in 0..n {
                for j in 0..n {
                    let x_mm = 500.0 * (i as f64 + shift) / n as f64;
                    let t_degc = 20.0 + 10.0 * (j as f64 + shift) / n as f64;
                    xs.push(vec![x_mm, t_degc]);
                    ys.push(f(x_mm, t_degc).to_vec());
                }
            }
            Samples::from_rows(&xs, &ys).unwrap()
        };
        let train_set = grid(14, 0.0);
        let test_set = grid(9, 0.5);
        let config = TrainConfig {
            max_epochs: 200,
            ..TrainConfig::default()
        };
        let (model, _) = Regressor::fit(&train_set, None, &[10], &config).unwrap();
        // 0.05 µm on outputs spanning ±10 µm: 0.25 % of range.
        for rmse in rmse_per_output(&model, &test_set) {
            assert!(rmse < 0.05, "test RMSE {rmse} µm");
        }
    }

    #[test]
    fn json_round_trip_gives_bit_identical_predictions() {
        let xs: Vec<Vec<f64>> = (0..30)
            .map(|i| vec![f64::from(i) * 0.1, 25.0 - f64::from(i)])
            .collect();
        let ys: Vec<Vec<f64>> = xs
            .iter()
            .map(|x| vec![x[0].sin() * x[1], x[0] + 1.0])
            .collect();
        let data = Samples::from_rows(&xs, &ys).unwrap();
        let config = TrainConfig {
            max_epochs: 10,
            ..TrainConfig::default()
        };
        let (model, _) = Regressor::fit(&data, None, &[5], &config).unwrap();
        let json = serde_json::to_string(&model).unwrap();
        let back: Regressor = serde_json::from_str(&json).unwrap();
        assert_eq!(model, back);
        for x in &xs {
            assert_eq!(model.predict(x).unwrap(), back.predict(x).unwrap());
        }
    }

    #[test]
    fn fast_tanh_nets_train_and_keep_their_activation_through_json() {
        let xs: Vec<Vec<f64>> = (0..41)
            .map(|i| vec![-PI + PI * f64::from(i) / 20.0])
            .collect();
        let ys: Vec<Vec<f64>> = xs.iter().map(|x| vec![x[0].sin()]).collect();
        let data = Samples::from_rows(&xs, &ys).unwrap();
        let config = TrainConfig {
            max_epochs: 100,
            activation: crate::nn::Activation::FastTanh,
            ..TrainConfig::default()
        };
        let (model, _) = Regressor::fit(&data, None, &[6], &config).unwrap();
        assert_eq!(model.mlp().activation(), crate::nn::Activation::FastTanh);
        // The approximation costs nothing visible in the fit: 1e-3 of a unit-amplitude sine.
        assert!(rmse_per_output(&model, &data)[0] < 1e-3);
        let back: Regressor =
            serde_json::from_str(&serde_json::to_string(&model).unwrap()).unwrap();
        assert_eq!(back.mlp().activation(), crate::nn::Activation::FastTanh);
        assert_eq!(
            model.predict(&[0.3]).unwrap(),
            back.predict(&[0.3]).unwrap()
        );
    }

    #[test]
    fn inconsistent_models_and_wrong_buffers_are_errors() {
        let mlp = Mlp::zeros(&[2, 3, 1]).unwrap();
        assert!(Regressor::new(
            Normaliser::identity(3),
            Normaliser::identity(1),
            mlp.clone()
        )
        .is_err());
        let mut zero_std = Normaliser::identity(2);
        zero_std.std[1] = 0.0;
        assert!(Regressor::new(zero_std, Normaliser::identity(1), mlp.clone()).is_err());
        let r = Regressor::new(Normaliser::identity(2), Normaliser::identity(1), mlp).unwrap();
        let mut out = [0.0];
        assert!(r
            .predict_into(&[1.0, 2.0], &mut [0.0; 2], &mut out)
            .is_err());
        assert!(r
            .predict_into(&[1.0], &mut vec![0.0; r.scratch_len()], &mut out)
            .is_err());
        let json = serde_json::to_string(&r)
            .unwrap()
            .replace("\"mean\":[0.0,0.0]", "\"mean\":[0.0]");
        assert!(serde_json::from_str::<Regressor>(&json).is_err());
    }
}
