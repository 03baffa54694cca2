//! The thermal-drift model: its parts, its prediction and its file format.
//!
//! Each output k is predicted by one of four forms ([`OutputModel`]), on the causal features
//! `φ(t)` ([`FeatureSpec`]) or the raw inputs `x(t)`:
//! - `plain-ls`: `y_k = P_k(x)`, plain least squares on the raw inputs (intercept and one slope
//!   per input column as read; no filters, no ridge);
//! - `linear`: `y_k = L_k(φ)`, a ridge linear regression on the filter-bank features (its ridge
//!   λ chosen per output);
//! - `linear-mlp`: `y_k = L_k(φ) + R_k(φ)`, `R` an MLP fitted to the linear part's residual
//!   (the linear part extrapolates sensibly to a hotter cycle than any seen, the net corrects
//!   what is not linear);
//! - `mlp`: `y_k = N_k(φ)`, an MLP fitted to the outputs directly.
//!
//! `L` is one multi-output linear model, `R` and `N` are small ensembles of multi-output nets
//! (tanh hidden layer, input and output normalisation inside, see [`Regressor`]; the members
//! differ by their seeded initialisation and their predictions are averaged: with a few thermal
//! cycles to learn from, one net's result depends on its initialisation by several µm, the
//! average much less); which form serves which output, the ridge λ of each output and the width
//! of the filter bank are chosen by leave-one-cycle-out cross-validation when fitting (see
//! `fit.rs` and `cv.rs`).
//!
//! File: JSON with `format` = [`FORMAT_NAME`] and `version` = [`FORMAT_VERSION`], the input and
//! output names and units, the feature spec, the parts with their normalisations and weights,
//! the per-output choice and the evaluation. Reading checks all of it. Version 1 files (before
//! plain least squares and the cross-validation) read without their evaluation and predict as
//! they did.

use serde::{Deserialize, Serialize};

use super::features::FeatureSpec;
use super::split::Split;
use super::ThermalFitError;
use crate::linreg::LinearModel;
use crate::nn::Regressor;

/// The `format` field of every thermal-drift model file.
pub const FORMAT_NAME: &str = "vmc-twin thermal-drift model";
/// Version of the model file layout this build reads and writes.
pub const FORMAT_VERSION: u32 = 2;

/// Which forms the fit may use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Architecture {
    /// Linear regression only (the baseline).
    Linear,
    /// MLP on the outputs directly, every output.
    Mlp,
    /// Linear + MLP on its residual, on the outputs where the net lowers the validation error
    /// (linear elsewhere; the default).
    LinearMlp,
    /// Per output, whichever of the three forms has the lowest validation error.
    Auto,
}

impl Architecture {
    /// Parses `auto`, `linear`, `mlp` or `linear-mlp`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "linear" => Some(Self::Linear),
            "mlp" => Some(Self::Mlp),
            "linear-mlp" => Some(Self::LinearMlp),
            "auto" => Some(Self::Auto),
            _ => None,
        }
    }

    /// The name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Linear => "linear",
            Self::Mlp => "mlp",
            Self::LinearMlp => "linear-mlp",
            Self::Auto => "auto",
        }
    }
}

/// The form that predicts one output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OutputModel {
    /// `P_k(x)`: plain least squares on the raw inputs.
    PlainLs,
    /// `L_k(φ)`.
    Linear,
    /// `L_k(φ) + R_k(φ)`.
    LinearMlp,
    /// `N_k(φ)`.
    Mlp,
}

impl OutputModel {
    /// The name used in files and reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::PlainLs => "plain-ls",
            Self::Linear => "linear",
            Self::LinearMlp => "linear-mlp",
            Self::Mlp => "mlp",
        }
    }
}

/// A named column and the unit its name ends with (`t1_degc` → `degc`; empty if no `_`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Channel {
    /// Column name as in the file.
    pub name: String,
    /// Unit suffix of the name.
    pub unit: String,
}

impl Channel {
    /// The channel of column `name`.
    pub fn from_name(name: &str) -> Self {
        let unit = name
            .rsplit_once('_')
            .map(|(_, u)| u.to_string())
            .unwrap_or_default();
        Self {
            name: name.to_string(),
            unit,
        }
    }
}

/// Scores of one output channel (RMS values in the channel's unit).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelScore {
    /// The output.
    pub output: Channel,
    /// The form chosen for it.
    pub form: OutputModel,
    /// RMS of the measured values on the held-out part (the drift left with no compensation).
    pub raw_rms: f64,
    /// RMSE of a constant prediction (the mean over training + validation rows) on the
    /// held-out part.
    pub constant_rmse: f64,
    /// RMSE of the linear baseline on the held-out part.
    pub linear_rmse: f64,
    /// RMSE of the fitted model on the held-out part.
    pub model_rmse: f64,
    /// RMSE on the held-out part of plain least squares on the raw inputs (intercept and one
    /// slope per input, fitted on training + validation rows; None if that regression is
    /// singular or the file predates it).
    #[serde(default)]
    pub plain_ls_rmse: Option<f64>,
    /// `linear_rmse / raw_rms` (None when the held-out values are all zero).
    pub linear_ratio: Option<f64>,
    /// `model_rmse / raw_rms` (None when the held-out values are all zero).
    pub model_ratio: Option<f64>,
    /// Leave-one-cycle-out: mean over the folds of the chosen form's held-out RMSE / that
    /// fold's raw drift RMS.
    pub cv_model_ratio: f64,
    /// The same for the filter-bank linear form.
    pub cv_linear_ratio: f64,
    /// The same for plain least squares on the raw inputs (None if singular in some fold).
    pub cv_plain_ls_ratio: Option<f64>,
}

/// One leave-one-cycle-out fold: a cycle held out, every other row fitting (per output, in
/// output order; RMS values in the output's unit).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FoldScore {
    /// First time of the held-out cycle, s.
    pub from_s: f64,
    /// Last time of the held-out cycle, s.
    pub to_s: f64,
    /// Rows held out.
    pub rows: usize,
    /// RMS of the measured drift on the held-out cycle.
    pub raw_rms: Vec<f64>,
    /// RMSE of the chosen form (per output) on it.
    pub model_rmse: Vec<f64>,
    /// RMSE of plain least squares on the raw inputs on it (None if singular).
    pub plain_ls_rmse: Vec<Option<f64>>,
}

/// The held-out evaluation written by [`super::fit`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    /// The split used.
    pub split: Split,
    /// Training rows of the selection stage.
    pub n_train: usize,
    /// Validation rows.
    pub n_val: usize,
    /// Rows the final nets trained on (training + validation, thinned to `min_train_step_s`).
    pub n_fit_net: usize,
    /// Held-out rows.
    pub n_holdout: usize,
    /// How the selection folds were formed (for the report).
    pub selection: String,
    /// Scale applied to the feature spec's time constants, chosen by cross-validation (the
    /// model's `features` hold the scaled ones).
    pub tau_scale: f64,
    /// Ridge λ of the linear part, per output, chosen by cross-validation.
    pub ridges: Vec<f64>,
    /// The cross-validation folds (each cycle held out once; the validation part alone when the
    /// file has fewer than two cycles).
    pub folds: Vec<FoldScore>,
    /// Residual nets: hidden width and LM epochs of each member's final fit, if used.
    pub residual_net: Option<(usize, Vec<usize>)>,
    /// Direct nets: hidden width and LM epochs of each member's final fit, if used.
    pub direct_net: Option<(usize, Vec<usize>)>,
    /// Per output.
    pub channels: Vec<ChannelScore>,
    /// When the kept model was fitted again on every row after this evaluation: how many rows
    /// (None: the kept model is the evaluated one).
    #[serde(default)]
    pub refit_rows: Option<usize>,
}

/// A fitted thermal-drift model, as saved in JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThermalModel {
    /// Always [`FORMAT_NAME`].
    pub format: String,
    /// Always [`FORMAT_VERSION`] when written by this build.
    pub version: u32,
    /// Forms the fit was allowed to use.
    pub architecture: Architecture,
    /// Time column of the training file (prediction files may name theirs differently).
    pub time_column: String,
    /// Input columns, in feature order.
    pub inputs: Vec<Channel>,
    /// Output columns, in output order.
    pub outputs: Vec<Channel>,
    /// Feature construction.
    pub features: FeatureSpec,
    /// The form predicting each output.
    pub output_models: Vec<OutputModel>,
    /// Linear part `L` (features → outputs), physical units.
    pub linear: LinearModel,
    /// Plain least squares `P` (raw inputs → outputs), physical units; None when no output uses
    /// it.
    #[serde(default)]
    pub plain: Option<LinearModel>,
    /// Residual net `R` (features → outputs − L): an ensemble whose members' predictions are
    /// averaged, each with its normalisations; empty when no output uses it.
    pub residual_mlp: Vec<Regressor>,
    /// Direct net `N` (features → outputs): an ensemble as `residual_mlp`.
    pub direct_mlp: Vec<Regressor>,
    /// The held-out evaluation made when fitting.
    pub evaluation: Option<Evaluation>,
}

impl ThermalModel {
    /// Width of a feature row.
    pub(crate) fn feature_width(&self) -> usize {
        self.features.width(&self.input_names())
    }

    /// The input column names, in feature order.
    pub fn input_names(&self) -> Vec<&str> {
        self.inputs.iter().map(|c| c.name.as_str()).collect()
    }

    /// Predictions (output-major: one column per output) from row-major feature rows and the
    /// row-major raw input rows they were computed from.
    pub(crate) fn predict_features(
        &self,
        feats: &[f64],
        raw: &[f64],
    ) -> Result<Vec<Vec<f64>>, ThermalFitError> {
        let width = self.feature_width();
        let n_in = self.inputs.len();
        let n = feats.len() / width.max(1);
        let n_out = self.outputs.len();
        let mut plain = vec![0.0; n_out];
        let mut out = vec![vec![0.0; n]; n_out];
        let mut lin = vec![0.0; n_out];
        let mut res = vec![0.0; n_out];
        let mut dir = vec![0.0; n_out];
        let scratch_len = self
            .residual_mlp
            .iter()
            .chain(&self.direct_mlp)
            .map(Regressor::scratch_len)
            .max()
            .unwrap_or(0);
        let mut scratch = vec![0.0; scratch_len];
        let mut one = vec![0.0; n_out];
        for r in 0..n {
            let x = &feats[r * width..(r + 1) * width];
            self.linear.predict_into(x, &mut lin)?;
            if let Some(p) = &self.plain {
                p.predict_into(&raw[r * n_in..(r + 1) * n_in], &mut plain)?;
            }
            for (nets, out) in [(&self.residual_mlp, &mut res), (&self.direct_mlp, &mut dir)] {
                out.iter_mut().for_each(|v| *v = 0.0);
                for m in nets.iter() {
                    m.predict_into(x, &mut scratch, &mut one)?;
                    let w = 1.0 / nets.len() as f64;
                    out.iter_mut().zip(&one).for_each(|(o, v)| *o += w * v);
                }
            }
            for (k, c) in out.iter_mut().enumerate() {
                c[r] = match self.output_models[k] {
                    OutputModel::PlainLs => plain[k],
                    OutputModel::Linear => lin[k],
                    OutputModel::LinearMlp => lin[k] + res[k],
                    OutputModel::Mlp => dir[k],
                };
            }
        }
        Ok(out)
    }

    /// Predicts every output at every row of `time_s` (s, strictly increasing) from the input
    /// columns (in [`ThermalModel::inputs`] order). Returns one column per output.
    pub fn predict(
        &self,
        time_s: &[f64],
        inputs: &[&[f64]],
    ) -> Result<Vec<Vec<f64>>, ThermalFitError> {
        if inputs.len() != self.inputs.len() || inputs.iter().any(|c| c.len() != time_s.len()) {
            return Err(ThermalFitError::BadSettings {
                field: "inputs",
                reason: format!(
                    "the model needs {} input columns of {} rows",
                    self.inputs.len(),
                    time_s.len()
                ),
            });
        }
        let feats = self
            .features
            .compute_checked(time_s, &self.input_names(), inputs)?;
        self.predict_features(&feats, &raw_rows(inputs))
    }

    /// Serialises the model (pretty JSON).
    pub fn to_json(&self) -> String {
        // Serialising plain numbers, strings and vectors cannot fail.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Reads a model written by [`ThermalModel::to_json`], checking format, version and that
    /// the parts fit together. `source` names the file in errors.
    pub fn from_json(text: &str, source: &str) -> Result<Self, ThermalFitError> {
        let bad = |reason: String| ThermalFitError::BadModel {
            source_name: source.to_string(),
            reason,
        };
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| bad(format!("not JSON: {e}")))?;
        match value.get("format").and_then(|f| f.as_str()) {
            Some(FORMAT_NAME) => {}
            Some(other) => {
                return Err(bad(format!(
                    "not a thermal-drift model: format is \"{other}\", expected \"{FORMAT_NAME}\""
                )))
            }
            None => {
                return Err(bad(format!(
                    "not a thermal-drift model (no \"format\": \"{FORMAT_NAME}\" field; a \
                     predictor model from `vmc-twin train` is a different kind of file)"
                )))
            }
        }
        let mut value = value;
        match value.get("version").and_then(|v| v.as_u64()) {
            Some(v) if v == u64::from(FORMAT_VERSION) => {}
            // Version 1 predicts with the same parts; its evaluation (a single validation
            // cycle) has other fields and is not kept.
            Some(1) => {
                if let Some(o) = value.as_object_mut() {
                    o.insert("evaluation".into(), serde_json::Value::Null);
                    o.insert("version".into(), FORMAT_VERSION.into());
                }
            }
            v => {
                return Err(bad(format!(
                    "model file version {v:?}, this build reads versions 1 and {FORMAT_VERSION}"
                )))
            }
        }
        let m: ThermalModel =
            serde_json::from_value(value).map_err(|e| bad(format!("malformed model: {e}")))?;
        // The feature spec as a fit would have checked it, named by the file.
        m.features
            .validate()
            .and_then(|()| m.features.validate_inputs(&m.input_names()))
            .map_err(|e| bad(e.to_string()))?;
        let width = m.feature_width();
        let n_out = m.outputs.len();
        let net_ok = |nets: &[Regressor], form: OutputModel| {
            nets.iter().all(|r| r.n_in() == width && r.n_out() == n_out)
                && (!nets.is_empty() || !m.output_models.contains(&form))
        };
        if m.inputs.is_empty()
            || n_out == 0
            || m.output_models.len() != n_out
            || m.linear.n_in() != width
            || m.linear.n_out() != n_out
            || !net_ok(&m.residual_mlp, OutputModel::LinearMlp)
            || !net_ok(&m.direct_mlp, OutputModel::Mlp)
            || !plain_ok(&m)
        {
            return Err(bad(format!(
                "inconsistent model: {} inputs ({width} features) and {n_out} outputs do not \
                 match its linear part, plain least squares, nets or per-output forms",
                m.inputs.len(),
            )));
        }
        Ok(m)
    }
}

/// The plain least-squares part fits the inputs and outputs, and is there if an output uses it.
fn plain_ok(m: &ThermalModel) -> bool {
    match &m.plain {
        Some(p) => p.n_in() == m.inputs.len() && p.n_out() == m.outputs.len(),
        None => !m.output_models.contains(&OutputModel::PlainLs),
    }
}

/// Input columns as row-major rows.
pub(crate) fn raw_rows(cols: &[&[f64]]) -> Vec<f64> {
    let n = cols.first().map_or(0, |c| c.len());
    let mut raw = Vec::with_capacity(n * cols.len());
    for r in 0..n {
        raw.extend(cols.iter().map(|c| c[r]));
    }
    raw
}
