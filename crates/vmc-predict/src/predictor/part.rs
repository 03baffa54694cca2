//! One part of the hybrid model: a linear regression plus an MLP on its residual.
//!
//! Model: `y(p, T) = c + a_p·p + A_T·T + net(p, T)` (units of the outputs, µm or µrad), where
//! `p` are the part's position inputs (one axis position, or none for the spindle) and `T` the
//! sensor readings (°C). The linear part is fitted first by ridge least squares; the one-hidden-
//! layer net is then fitted (Levenberg–Marquardt, as every net) to what the linear part leaves.
//! A *bilinear* part (the hybrid's axis parts, `Settings::axis_bilinear`) adds `p·(B·T)` to the
//! linear part: the products of the position with every temperature input, i.e. a scale error
//! that changes with temperature, as a ballscrew's or a scale's expansion does. At query time
//! `a_p + B·T` is cached with the readings, so a query costs the same.
//!
//! Why: the thermal drifts of a machine are close to linear in its temperatures, and outside
//! the calibrated range (a warmer ambient, a combination of readings never met in
//! calibration) a tanh net alone extrapolates badly — it bends back or saturates, and its value
//! at a cold machine is whatever the fit left there. With the linear part carrying the trend the
//! net only models the non-linear remainder (position profiles, lags), and away from the data
//! the part degrades to the linear model instead of an arbitrary curve.
//!
//! Parsimony: the residual net is kept only when it lowers the validation RMSE of the linear
//! part (held-out calibration cycles, mean over outputs of net/linear RMSE ratio) by at least
//! [`super::Settings::residual_net_min_gain`]. An output like the spindle drift, which depends
//! on the machine's thermal history more than on the present readings, gives a net that fits
//! the training cycles and not the validation ones; such a net is dropped.
//!
//! Query cost: the temperature part of the linear model and of the net's first layer are cached
//! per set of readings (see `fastnet`); a query adds `n_out` multiply-adds per position input.

use serde::{Deserialize, Serialize};

use crate::linreg::LinearModel;
use crate::nn::Regressor;

use super::data::{fit_linear, fit_mlp, CycleSplit, Table};
use super::fastnet::SplitNet;
use super::kind::check_linear_model;
use super::{NetSummary, PredictError, Settings};

/// A linear model plus an optional residual net, in the dataset's units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct LinearPlusNet {
    /// `[positions…, temperatures…] → outputs`.
    pub linear: LinearModel,
    /// The same inputs → what the linear model leaves; `None` when it did not pay on validation.
    pub net: Option<Regressor>,
    /// The linear model also takes the products of each position with each temperature: its
    /// inputs are then `[p…, T…, p_0·T…, p_1·T…, …]` (the net's stay `[p…, T…]`). Absent in
    /// model files before version 6 (false).
    #[serde(default)]
    pub bilinear: bool,
}

/// `x = [p…, T…]` followed by the products `p_i·T_j` (`i`-major), the inputs of a bilinear
/// linear part. `centre` (`[p…, T…]` means) centres each factor first.
fn with_products(x: &[f64], n_pos: usize, centre: Option<&[f64]>, out: &mut Vec<f64>) {
    out.clear();
    out.extend_from_slice(x);
    let c = |k: usize| centre.map_or(0.0, |m| m[k]);
    for i in 0..n_pos {
        let p = x[i] - c(i);
        for (j, t) in x.iter().enumerate().skip(n_pos) {
            out.push(p * (t - c(j)));
        }
    }
}

impl LinearPlusNet {
    /// Checks the widths: `n_pos + n_temps` inputs, `n_out` outputs.
    pub fn check(
        &self,
        name: &str,
        n_pos: usize,
        n_temps: usize,
        n_out: usize,
    ) -> Result<(), PredictError> {
        let n_in = n_pos + n_temps;
        if self.bilinear {
            // Say where the width comes from: it is not the sensor count alone.
            let n_products = n_pos * n_temps;
            check_linear_model(name, &self.linear, n_in + n_products, n_out).map_err(|e| {
                PredictError::Inconsistent {
                    reason: format!(
                        "{} — a bilinear part takes {n_pos} position(s), {n_temps} sensor \
                         inputs and their {n_products} products",
                        match e {
                            PredictError::Inconsistent { reason } => reason,
                            other => other.to_string(),
                        }
                    ),
                }
            })?;
        } else {
            check_linear_model(name, &self.linear, n_in, n_out)?;
        }
        if let Some(reg) = &self.net {
            if reg.n_in() != n_in || reg.n_out() != n_out {
                return Err(PredictError::Inconsistent {
                    reason: format!(
                        "network `{name}` maps {} → {} values; with {n_temps} sensors it must \
                         map {n_in} → {n_out}",
                        reg.n_in(),
                        reg.n_out()
                    ),
                });
            }
        }
        Ok(())
    }
}

/// Fits the linear part, then the residual net, and keeps the net only if it pays on
/// validation. The summary's RMSEs are those of the whole part; `hidden_units` is `None` when
/// the net was dropped. `bilinear_pos` > 0: the first `bilinear_pos` inputs are positions whose
/// products with the temperatures enter the linear part ([`LinearPlusNet::bilinear`]).
pub(crate) fn fit_linear_plus_net(
    name: &'static str,
    outputs: &[&str],
    table: &Table,
    split: &CycleSplit,
    settings: &Settings,
    net_index: u64,
    bilinear_pos: usize,
) -> Result<(LinearPlusNet, NetSummary), PredictError> {
    let bilinear = bilinear_pos > 0;
    let (linear, lin_summary) = if bilinear {
        fit_bilinear(
            name,
            outputs,
            table,
            split,
            settings.part_ridge,
            bilinear_pos,
        )?
    } else {
        fit_linear(name, outputs, table, split, settings.part_ridge)?
    };
    let mut residual = Table::new();
    residual.inputs = table.inputs.clone();
    residual.groups = table.groups.clone();
    let mut l = vec![0.0; outputs.len()];
    let mut xb = Vec::new();
    for (x, y) in table.inputs.iter().zip(&table.targets) {
        let x = if bilinear {
            with_products(x, bilinear_pos, None, &mut xb);
            &xb
        } else {
            x
        };
        linear
            .predict_into(x, &mut l)
            .map_err(|cause| PredictError::Linear { model: name, cause })?;
        residual
            .targets
            .push(y.iter().zip(&l).map(|(y, l)| y - l).collect());
    }
    let (net, summary) = fit_mlp(name, outputs, &residual, split, settings, net_index)?;
    // Mean over outputs of the validation RMSE ratio (whole part / linear part alone).
    let ratios: Vec<f64> = summary
        .val_rmse
        .iter()
        .zip(&lin_summary.val_rmse)
        .filter(|(_, l)| **l > 0.0)
        .map(|(n, l)| n / l)
        .collect();
    let mean_ratio = if ratios.is_empty() {
        1.0
    } else {
        ratios.iter().sum::<f64>() / ratios.len() as f64
    };
    if mean_ratio <= 1.0 - settings.residual_net_min_gain {
        Ok((
            LinearPlusNet {
                linear,
                net: Some(net),
                bilinear,
            },
            NetSummary {
                linear_val_rmse: lin_summary.val_rmse,
                ..summary
            },
        ))
    } else {
        Ok((
            LinearPlusNet {
                linear,
                net: None,
                bilinear,
            },
            NetSummary {
                linear_val_rmse: lin_summary.val_rmse.clone(),
                candidates: summary.candidates,
                ..lin_summary
            },
        ))
    }
}

/// Fits the bilinear linear part: ridge least squares on `[p…, T…]` and the products of the
/// *centred* factors `(p_i − p̄_i)(T_j − T̄_j)` (means over the table), so the products are not
/// nearly collinear with the positions before z-scoring; the centring is then folded into the
/// slopes and the intercept, leaving a model of the raw products (same function).
fn fit_bilinear(
    name: &'static str,
    outputs: &[&str],
    table: &Table,
    split: &CycleSplit,
    ridge: f64,
    n_pos: usize,
) -> Result<(LinearModel, NetSummary), PredictError> {
    let width = table.inputs.first().map_or(0, Vec::len);
    let n_t = width.saturating_sub(n_pos);
    let rows = table.inputs.len().max(1) as f64;
    let mut centre = vec![0.0; width];
    for x in &table.inputs {
        for (c, v) in centre.iter_mut().zip(x) {
            *c += v / rows;
        }
    }
    let mut centred = Table::new();
    centred.targets = table.targets.clone();
    centred.groups = table.groups.clone();
    for x in &table.inputs {
        let mut xb = Vec::with_capacity(width + n_pos * n_t);
        with_products(x, n_pos, Some(&centre), &mut xb);
        centred.inputs.push(xb);
    }
    let (fit, summary) = fit_linear(name, outputs, &centred, split, ridge)?;
    // b·(p − m)(T − μ) = b·p·T − b·μ·p − b·m·T + b·m·μ.
    let n_in = fit.n_in();
    let mut slopes = fit.slopes().to_vec();
    let mut intercept = fit.intercept().to_vec();
    for (o, row) in slopes.chunks_exact_mut(n_in).enumerate() {
        for i in 0..n_pos {
            for j in 0..n_t {
                let b = row[width + i * n_t + j];
                let (m, mu) = (centre[i], centre[n_pos + j]);
                row[i] -= b * mu;
                row[n_pos + j] -= b * m;
                intercept[o] += b * m * mu;
            }
        }
    }
    Ok((
        LinearModel::from_coefficients(n_in, intercept, slopes, fit.ridge()),
        summary,
    ))
}

/// Query-time evaluator of a [`LinearPlusNet`] with `N_OUT` outputs and the first `n_pos`
/// inputs positions.
#[derive(Debug, Clone)]
pub(crate) struct PartRuntime<const N_OUT: usize> {
    n_pos: usize,
    /// Intercept + temperature part of the linear model for the cached readings.
    lin_const: [f64; N_OUT],
    /// Linear slopes of the position inputs for the cached readings, `[input][output]`.
    lin_pos: [[f64; N_OUT]; 3],
    /// The same without the products with the temperatures.
    lin_pos_base: [[f64; N_OUT]; 3],
    /// Slopes of the position × temperature products, `[input][output][temperature]` (empty
    /// unless the part is bilinear).
    lin_bil: Vec<f64>,
    /// Linear slopes of the temperatures, row-major `N_OUT × n_temps`.
    lin_temp: Vec<f64>,
    intercept: [f64; N_OUT],
    net: Option<SplitNet>,
}

impl<const N_OUT: usize> PartRuntime<N_OUT> {
    /// Builds the evaluator (widths checked by [`LinearPlusNet::check`] first).
    pub fn new(part: &LinearPlusNet, n_pos: usize, name: &str) -> Result<Self, PredictError> {
        let lin = &part.linear;
        let n_in = lin.n_in();
        // Width of `[p…, T…]`: the bilinear model adds `n_pos·n_t` product inputs.
        let n_base = if part.bilinear {
            n_pos + (n_in.saturating_sub(n_pos)) / (1 + n_pos)
        } else {
            n_in
        };
        let n_t = n_base.saturating_sub(n_pos);
        let widths_ok = !part.bilinear || n_base + n_pos * n_t == n_in;
        if lin.n_out() != N_OUT || n_pos > 3 || n_in < n_pos || !widths_ok {
            return Err(PredictError::Inconsistent {
                reason: format!(
                    "model `{name}` maps {n_in} → {} values; expected {N_OUT} outputs and at \
                     least {n_pos} inputs",
                    lin.n_out()
                ),
            });
        }
        let mut lin_pos = [[0.0; N_OUT]; 3];
        let mut lin_temp = Vec::with_capacity(N_OUT * n_t);
        let mut lin_bil = vec![
            0.0;
            if part.bilinear {
                n_pos * N_OUT * n_t
            } else {
                0
            }
        ];
        let mut intercept = [0.0; N_OUT];
        for (o, row) in lin.slopes().chunks_exact(n_in).enumerate() {
            for (i, slope) in row[..n_pos].iter().enumerate() {
                lin_pos[i][o] = *slope;
            }
            lin_temp.extend_from_slice(&row[n_pos..n_base]);
            if part.bilinear {
                for i in 0..n_pos {
                    let from = n_base + i * n_t;
                    lin_bil[(i * N_OUT + o) * n_t..][..n_t].copy_from_slice(&row[from..from + n_t]);
                }
            }
            intercept[o] = lin.intercept()[o];
        }
        let net = match &part.net {
            Some(reg) => Some(SplitNet::new(reg, n_pos, name)?),
            None => None,
        };
        Ok(Self {
            n_pos,
            lin_const: intercept,
            lin_pos,
            lin_pos_base: lin_pos,
            lin_bil,
            lin_temp,
            intercept,
            net,
        })
    }

    /// Caches the temperature-only parts for new readings.
    #[inline]
    pub fn set_temps(&mut self, temps: &[f64]) {
        let n_temp = temps.len();
        for (o, c) in self.lin_const.iter_mut().enumerate() {
            let row = &self.lin_temp[o * n_temp..(o + 1) * n_temp];
            *c = row
                .iter()
                .zip(temps)
                .fold(self.intercept[o], |acc, (a, t)| acc + a * t);
        }
        if !self.lin_bil.is_empty() {
            for i in 0..self.n_pos {
                for o in 0..N_OUT {
                    let row = &self.lin_bil[(i * N_OUT + o) * n_temp..][..n_temp];
                    self.lin_pos[i][o] = row
                        .iter()
                        .zip(temps)
                        .fold(self.lin_pos_base[i][o], |acc, (b, t)| acc + b * t);
                }
            }
        }
        if let Some(net) = &mut self.net {
            net.set_temps(temps);
        }
    }

    /// Evaluates at positions `pos` (`n_pos` values) with the cached readings.
    #[inline]
    pub fn eval(&mut self, pos: &[f64], out: &mut [f64; N_OUT]) {
        match &mut self.net {
            Some(net) => net.eval(pos, out),
            None => *out = [0.0; N_OUT],
        }
        for (o, v) in out.iter_mut().enumerate() {
            let mut s = self.lin_const[o];
            for (i, p) in pos.iter().enumerate().take(self.n_pos) {
                s += self.lin_pos[i][o] * p;
            }
            *v += s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::Dataset;
    use crate::predictor::data::{CycleSplit, Table};

    /// Rows `[x, T] → [y]` over cycles; `y` linear in T plus a bump in x when `bump`.
    fn table(ds: &Dataset, split: &CycleSplit, bump: bool) -> Table {
        let mut t = Table::new();
        for (i, r) in ds.records.iter().enumerate() {
            let x = (i % 17) as f64 * 30.0;
            let temp = r.temps_degc[0];
            // Measurement noise (deterministic, ±0.1): what no model can predict.
            let noise = 0.2 * ((i as f64 * 12.9898).sin() * 43758.545).rem_euclid(1.0) - 0.1;
            let mut y = 2.0 * (temp - 20.0) + 0.01 * x + noise;
            if bump {
                y += 5.0 * (-(x - 250.0).powi(2) / 5000.0).exp();
            }
            t.inputs.push(vec![x, temp]);
            t.targets.push(vec![y]);
            t.groups.push(split.id(&r.cycle));
        }
        t
    }

    fn fit(bump: bool) -> (LinearPlusNet, NetSummary) {
        let ds = super::super::testdata::dataset(&[4.0, 7.0, 5.5, 3.0], 2);
        let s = Settings::default();
        let split = CycleSplit::new(&ds, &s).unwrap();
        fit_linear_plus_net("t", &["y"], &table(&ds, &split, bump), &split, &s, 0, 0).unwrap()
    }

    #[test]
    fn a_linear_truth_drops_the_net_and_a_bump_keeps_it() {
        let (lin_only, summary) = fit(false);
        assert!(lin_only.net.is_none(), "{summary:?}");
        assert_eq!(summary.hidden_units, None);
        let (with_net, summary) = fit(true);
        assert!(with_net.net.is_some(), "{summary:?}");
        assert!(summary.val_rmse[0] < 0.5 * summary.linear_val_rmse[0]);
    }

    /// A scale error, as a ballscrew's expansion: `y = 2(T − 20) + 0.01·x + 0.004·x·(T − 20)`
    /// plus the same ±0.1 noise as [`table`].
    fn scale_truth(x: f64, temp: f64) -> f64 {
        2.0 * (temp - 20.0) + 0.01 * x + 0.004 * x * (temp - 20.0)
    }

    #[test]
    fn a_bilinear_part_fits_a_scale_error_the_plain_linear_part_cannot() {
        let ds = super::super::testdata::dataset(&[4.0, 7.0, 5.5, 3.0], 2);
        let s = Settings::default();
        let split = CycleSplit::new(&ds, &s).unwrap();
        let mut t = table(&ds, &split, false);
        for (x, y) in t.inputs.iter().zip(&mut t.targets) {
            y[0] += scale_truth(x[0], x[1]) - (2.0 * (x[1] - 20.0) + 0.01 * x[0]);
        }
        let (plain, plain_summary) =
            fit_linear_plus_net("t", &["y"], &t, &split, &s, 0, 0).unwrap();
        let (bil, summary) = fit_linear_plus_net("t", &["y"], &t, &split, &s, 0, 1).unwrap();
        assert!(!plain.bilinear && bil.bilinear);
        // The products carry the whole truth: the net does not pay and is dropped; what is left
        // is the noise (uniform ±0.1, RMS 0.058).
        assert!(bil.net.is_none(), "{summary:?}");
        assert!(summary.val_rmse[0] < 0.08, "{summary:?}");
        assert!(
            plain_summary.linear_val_rmse[0] > 5.0 * summary.val_rmse[0],
            "{plain_summary:?}"
        );
        // The runtime folds the products into the position slope per set of readings.
        let mut rt = PartRuntime::<1>::new(&bil, 1, "t").unwrap();
        for temp in [21.0, 26.5] {
            rt.set_temps(&[temp]);
            for x in [0.0, 120.0, 250.0, 480.0] {
                let mut got = [0.0];
                rt.eval(&[x], &mut got);
                let want = bil.linear.predict(&[x, temp, x * temp]).unwrap()[0];
                assert!((got[0] - want).abs() < 1e-9, "{got:?} {want}");
                assert!(
                    (got[0] - scale_truth(x, temp)).abs() < 0.1,
                    "{x} {temp}: {got:?}"
                );
            }
        }
        // Model files before version 6 have no `bilinear`: the part reads as plain.
        let mut v = serde_json::to_value(&plain).unwrap();
        v.as_object_mut().unwrap().remove("bilinear");
        let back: LinearPlusNet = serde_json::from_value(v).unwrap();
        assert_eq!(back, plain);
    }

    #[test]
    fn the_runtime_equals_linear_plus_net() {
        let (part, _) = fit(true);
        let mut rt = PartRuntime::<1>::new(&part, 1, "t").unwrap();
        let temps = [23.0];
        rt.set_temps(&temps);
        for x in [0.0, 120.0, 250.0, 480.0] {
            let mut got = [0.0];
            rt.eval(&[x], &mut got);
            let want = part.linear.predict(&[x, 23.0]).unwrap()[0]
                + part.net.as_ref().unwrap().predict(&[x, 23.0]).unwrap()[0];
            assert!((got[0] - want).abs() < 1e-9, "{got:?} {want}");
        }
    }
}
