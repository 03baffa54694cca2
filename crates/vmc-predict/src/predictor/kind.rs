//! What the model modules share with the model file: which model class a predictor is
//! ([`ModelKind`], also the file's `kind` field) and the shape check of a stored linear model.
//!
//! Why a module of its own: the model modules (`hybrid`, `volumetric`, `linear`, `part`) and the
//! model file (`file`) both need these, and the file dispatches to the model modules; keeping
//! them here makes every dependency inside `predictor` point one way (models → `kind`, `file` →
//! models and `kind`).

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::linreg::LinearModel;

use super::PredictError;

/// Which model class a file or summary holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ModelKind {
    /// Elementary-error nets + kinematic synthesis.
    Hybrid,
    /// Direct volumetric MLP.
    Volumetric,
    /// Linear regression on position/temperature features.
    Linear,
}

impl ModelKind {
    /// The name used in the `kind` field.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Hybrid => "hybrid",
            ModelKind::Volumetric => "volumetric",
            ModelKind::Linear => "linear",
        }
    }

    /// The kind named `s` in a `kind` field, if any.
    pub(crate) fn from_name(s: &str) -> Option<Self> {
        [ModelKind::Hybrid, ModelKind::Volumetric, ModelKind::Linear]
            .into_iter()
            .find(|k| k.name() == s)
    }
}

impl fmt::Display for ModelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Checks a linear model's shape and values against the widths its predictor needs.
pub(crate) fn check_linear_model(
    name: &str,
    m: &LinearModel,
    n_in: usize,
    n_out: usize,
) -> Result<(), PredictError> {
    let ok = m.n_in() == n_in
        && m.n_out() == n_out
        && m.intercept().len() == n_out
        && m.slopes().len() == n_in * n_out
        && m.intercept()
            .iter()
            .chain(m.slopes())
            .all(|v| v.is_finite());
    if ok {
        Ok(())
    } else {
        Err(PredictError::Inconsistent {
            reason: format!(
                "linear model `{name}` must map {n_in} → {n_out} values with finite coefficients \
                 (has {} → {}, {} intercepts, {} slopes)",
                m.n_in(),
                m.n_out(),
                m.intercept().len(),
                m.slopes().len()
            ),
        })
    }
}
