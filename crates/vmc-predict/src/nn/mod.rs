//! Multilayer perceptrons and their training.
//!
//! - [`Mlp`]: `n_in → tanh hidden layers → linear n_out`, f64 weights in one flat vector, an
//!   allocation-free forward pass ([`Mlp::forward_into`]) and an analytic Jacobian by
//!   backpropagation ([`Mlp::jacobian_into`]).
//! - [`Regressor`]: an `Mlp` wrapped in input and output [`Normaliser`]s, so callers pass and
//!   receive physical units (mm, °C, µm, rad); this is what gets saved as JSON.
//! - [`train`] / [`train_from`]: Levenberg–Marquardt on nalgebra (see `train.rs` for the
//!   algorithm), seeded initialisation, early stopping on a validation set, restarts.
//! - [`Samples`]: datasets and leakage-free splits by group or contiguous block.
//!
//! Why tanh: the per-axis nets are small (≈ 12-20-6) and must be smooth for the fixed-point
//! compensation iteration. std `f64::tanh` is the default; [`Activation::FastTanh`] (|error|
//! < 3e-7, ~8× cheaper, measured) is opt-in for the < 1 µs compensation query.

mod activation;
mod mlp;
mod normalise;
mod regressor;
mod samples;
mod train;

pub use activation::{fast_tanh, Activation};
pub use mlp::{Init, Mlp};
pub use normalise::Normaliser;
pub use regressor::Regressor;
pub use samples::{DataError, Samples};
pub use train::{train, train_from, Damping, StopReason, TrainConfig, TrainReport, MAX_LM_WEIGHTS};

use thiserror::Error;

/// Errors of network construction, evaluation and training.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum NnError {
    /// Dataset problem (shape, non-finite values, split).
    #[error(transparent)]
    Data(#[from] DataError),
    /// Layer widths unusable: need at least input and output layer, every width ≥ 1.
    #[error("invalid layer sizes {sizes:?}: need ≥ 2 layers, every width ≥ 1")]
    BadArchitecture {
        /// The rejected widths.
        sizes: Vec<usize>,
    },
    /// A buffer passed in has the wrong length.
    #[error("{buffer} buffer: expected {expected} values, got {got}")]
    BufferLength {
        /// Which buffer.
        buffer: &'static str,
        /// Required length (minimum for scratch buffers).
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// A weight is NaN or infinite.
    #[error("weight {index} is not finite")]
    NonFiniteWeight {
        /// Index into the flat weight vector.
        index: usize,
    },
    /// The dataset's widths do not match the net's.
    #[error("net maps {net_in} → {net_out} values but the data have {data_in} → {data_out}")]
    WidthMismatch {
        /// Net inputs.
        net_in: usize,
        /// Net outputs.
        net_out: usize,
        /// Data inputs.
        data_in: usize,
        /// Data outputs.
        data_out: usize,
    },
    /// Training needs at least one sample.
    #[error("the training set is empty")]
    EmptyTrainingSet,
    /// Too many weights for Levenberg–Marquardt, which solves a weights × weights system.
    #[error(
        "a net of widths {sizes:?} has {weights} weights; Levenberg–Marquardt solves a \
         weights × weights system, so at most {max} weights are supported: use smaller hidden widths"
    )]
    TooManyWeights {
        /// The layer widths asked for.
        sizes: Vec<usize>,
        /// Their number of weights (saturating).
        weights: usize,
        /// The most supported ([`MAX_LM_WEIGHTS`]).
        max: usize,
    },
    /// A training setting is out of range.
    #[error("invalid training setting {field}: {reason}")]
    BadConfig {
        /// The setting.
        field: &'static str,
        /// What is wrong.
        reason: &'static str,
    },
    /// A saved model is internally inconsistent.
    #[error("inconsistent model: {reason}")]
    BadModel {
        /// What does not fit.
        reason: &'static str,
    },
}
