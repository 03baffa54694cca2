//! Thermal-drift models fitted on a user's measurements.
//!
//! A user brings a CSV file with a time column, temperature columns (and optionally the spindle
//! speed) and measured drift columns, e.g. a spindle thermal test (5 probes, 16 thermometers,
//! one row every 15 s). This module turns it into a model `drift(t) = g(features(t))`:
//!
//! - features ([`FeatureSpec`]): each named input as read and its differences to a bank of
//!   first-order low-pass filters (time constants 15 min, 1 h, 3 h by default), all computed
//!   causally (row n uses rows 0…n only) with the filter state set to the first reading; a speed
//!   input (unit `rpm`) becomes a grey-box heat-input bank `(|n|/1000)^k`, as is and low-passed;
//!   optionally temperatures relative to their mean (gradients);
//! - model ([`ThermalModel`]): per output, plain least squares on the raw inputs, a ridge linear
//!   regression on the features, the same plus an MLP fitted to its residual, or an MLP on the
//!   features (Levenberg–Marquardt, normalisation, early stopping, seeded initialisation: the
//!   predictor's [`crate::nn`] machinery);
//! - selection (`cv.rs`): leave-one-cycle-out cross-validation chooses the filter-bank width,
//!   each output's ridge λ and each output's form;
//! - split ([`Split`]): time-ordered; its cycles are the folds. The held-out part (the last
//!   cycle) scores the chosen forms fitted on the rows before it; the nets' early-stopping
//!   validation is the cycle before it (never a shuffled subset of one time series);
//! - evaluation ([`Evaluation`]): per fold and per output, residual RMS of the chosen form and of
//!   plain least squares and the raw drift RMS of the held-out cycle; on the last cycle, RMSE of
//!   the model, of the filter-bank linear form, of plain least squares and of a constant (the
//!   training mean), and residual RMS / raw drift RMS, where the raw drift RMS is the RMS of the
//!   measured values (what is left with no compensation).
//!
//! Units: whatever the column names say (`_degc`, `_um`, `_rpm`); the time column is converted to
//! seconds. Nothing here touches files; [`read_csv`] parses text.

mod common;
mod cv;
mod features;
mod fit;
mod model;
mod settings;
mod split;
mod table;

pub use features::FeatureSpec;
pub use fit::fit;
pub use model::{
    Architecture, Channel, ChannelScore, Evaluation, FoldScore, OutputModel, ThermalModel,
    FORMAT_NAME, FORMAT_VERSION,
};
pub use settings::FitSettings;
pub use split::Split;
pub use table::{read_csv, Table, TableRequest};

use thiserror::Error;

/// Everything that can go wrong reading tables, fitting and applying thermal-drift models.
#[derive(Debug, Error)]
pub enum ThermalFitError {
    /// The text has no header line.
    #[error("{source_name}: the file is empty (expected a header line with column names)")]
    EmptyTable {
        /// File name.
        source_name: String,
    },
    /// Header problem (empty or duplicate name).
    #[error("{source_name}: line 1 (header): {reason}")]
    BadHeader {
        /// File name.
        source_name: String,
        /// What is wrong.
        reason: String,
    },
    /// A named column is not in the header.
    #[error(
        "{source_name}: no {role} column \"{column}\"{}; columns in the file: {}",
        suggestion.as_ref().map(|s| format!(" (did you mean \"{s}\"?)")).unwrap_or_default(),
        available.join(", ")
    )]
    MissingColumn {
        /// File name.
        source_name: String,
        /// The name asked for.
        column: String,
        /// `"input"`, `"output"` or `"time"`.
        role: &'static str,
        /// The closest header name, if any is close.
        suggestion: Option<String>,
        /// Every header name.
        available: Vec<String>,
    },
    /// No unique time column and none was named.
    #[error(
        "{source_name}: cannot tell the time column: {} (rule: the only column whose name starts \
         with \"time\"); name it with --time; columns in the file: {}",
        if candidates.is_empty() { "no column name starts with \"time\"".to_string() }
        else { format!("several candidates {}", candidates.join(", ")) },
        available.join(", ")
    )]
    NoTimeColumn {
        /// File name.
        source_name: String,
        /// Columns starting with "time".
        candidates: Vec<String>,
        /// Every header name.
        available: Vec<String>,
    },
    /// The time column's unit suffix is not one of `_s`, `_min`, `_h`.
    #[error("{source_name}: time column \"{column}\" has no known unit suffix (_s, _min or _h)")]
    TimeUnit {
        /// File name.
        source_name: String,
        /// The column.
        column: String,
    },
    /// A row with a different number of fields than the header.
    #[error("{source_name}: line {line}: {got} fields, the header has {expected}")]
    RaggedRow {
        /// File name.
        source_name: String,
        /// 1-based line.
        line: usize,
        /// Header width.
        expected: usize,
        /// Fields on this line.
        got: usize,
    },
    /// A cell that is not a finite number.
    #[error("{source_name}: line {line}, column \"{column}\": {reason} (\"{text}\")")]
    BadCell {
        /// File name.
        source_name: String,
        /// 1-based line.
        line: usize,
        /// Column name.
        column: String,
        /// The cell's text.
        text: String,
        /// Why it was rejected.
        reason: String,
    },
    /// Time does not increase strictly.
    #[error(
        "{source_name}: line {line}: time does not increase (column \"{column}\": {time_s} s \
         after {previous_s} s on the previous row); rows must be in time order without repeats"
    )]
    TimeNotIncreasing {
        /// File name.
        source_name: String,
        /// 1-based line.
        line: usize,
        /// Time column.
        column: String,
        /// Time of this row, s.
        time_s: f64,
        /// Time of the previous row, s.
        previous_s: f64,
    },
    /// Not enough rows for the task.
    #[error("{source_name}: {rows} data rows, need at least {needed}")]
    TooFewRows {
        /// File name.
        source_name: String,
        /// Rows found.
        rows: usize,
        /// Rows needed.
        needed: usize,
    },
    /// A setting is out of range.
    #[error("invalid setting {field}: {reason}")]
    BadSettings {
        /// The setting.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The model file is not a thermal-drift model of a supported version, or is inconsistent.
    #[error("{source_name}: {reason}")]
    BadModel {
        /// File name.
        source_name: String,
        /// What is wrong.
        reason: String,
    },
    /// A column holds a value too large to fit (its square overflows).
    #[error(
        "column \"{column}\" at t = {time_s} s: a value too large to fit (its square overflows): \
         a corrupt cell or a unit mistake?"
    )]
    TooLarge {
        /// The column.
        column: String,
        /// Time of the row, s.
        time_s: f64,
    },
    /// A feature computed from the inputs is not finite (e.g. a huge speed raised to a power).
    #[error(
        "feature \"{feature}\" is not finite at t = {time_s} s: an input value too large for it \
         (a corrupt cell or a unit mistake?)"
    )]
    NonFiniteFeature {
        /// The feature (`<input>`, `<input>-lowpass<τ>s`, `<speed>^<k>…`).
        feature: String,
        /// Time of the row, s.
        time_s: f64,
    },
    /// Training a net failed. The message includes the cause; it is not also given as
    /// `source()`, so a printer of the error chain shows it once.
    #[error("training the residual MLP: {0}")]
    Net(crate::nn::NnError),
    /// Linear regression failed (the cause is in the message, as for [`Self::Net`]).
    #[error("fitting the linear part: {0}")]
    Linear(crate::linreg::LinRegError),
}

impl From<crate::nn::NnError> for ThermalFitError {
    fn from(e: crate::nn::NnError) -> Self {
        ThermalFitError::Net(e)
    }
}

impl From<crate::linreg::LinRegError> for ThermalFitError {
    fn from(e: crate::linreg::LinRegError) -> Self {
        ThermalFitError::Linear(e)
    }
}
