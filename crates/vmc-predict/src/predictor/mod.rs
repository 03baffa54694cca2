//! Volumetric error predictors trained on a calibration [`Dataset`].
//!
//! Every predictor answers one question at run time: given the axis positions `q` (mm) and the
//! current temperature sensor readings `T` (°C, in the model's sensor order), what is the
//! volumetric error `E(q, T)` = actual − nominal tool tip relative to the workpiece, in the
//! workpiece frame, in mm ([`ErrorPredictor::predict_error_mm`]). Three model classes:
//!
//! - [`HybridPredictor`] (the study's method): per axis `k` an MLP `(q_k, T) → (δx, δy, δz, εx,
//!   εy, εz)_k` trained on `laser_k` records; a spindle MLP `T → (δx_b, δy_b, δz_b, εx_b, εy_b)`
//!   on `spindle` records; squareness `α = α₀ + A·T` by linear regression on `squareness`
//!   records; all 26 elementary errors feed [`first_order_error_mm`]. Each axis and spindle
//!   "MLP" is a linear regression plus an MLP on its residual (`part`): the linear part carries
//!   the thermal trend and extrapolates sanely, the MLP the non-linear rest, and it is dropped
//!   when it does not pay on the validation cycles ([`Settings::residual_net_min_gain`]). Nets
//!   work in the dataset's units (µm, µrad); the conversion to mm and rad (×1e-3, ×1e-6)
//!   happens at the synthesis.
//! - [`VolumetricPredictor`] (baseline): one MLP `(X, Y, Z, T) → (Ex, Ey, Ez)` in µm on
//!   `volumetric` records.
//! - [`LinearPredictor`] (baseline): per component of E a linear model of the features
//!   `[1, x, y, z, x², y², z², xy, xz, yz, ΔT_i, ΔT_i·x, ΔT_i·y, ΔT_i·z]` with `x = (X − c_x)/h_x`
//!   (centre and half range of the training positions) and `ΔT_i = T_i − T̄_i` (training mean),
//!   on `volumetric` records.
//!
//! All MLPs have one tanh hidden layer; its width is picked among
//! [`Settings::hidden_candidates`] by validation RMSE. Training uses Levenberg–Marquardt with
//! early stopping ([`crate::nn`]); the validation set is made of whole thermal cycles (the
//! `cycle` column, see [`Settings::val_cycles`]) so that near-copies of validation samples never
//! sit in the training set. Only when a dataset holds a single cycle are contiguous time blocks
//! used instead ([`SplitKind`]). Every seed is derived from [`Settings::seed`].
//!
//! Readings enter a predictor by one door, [`ErrorPredictor::observe_readings`]; the predictor
//! holds them, and queries ([`ErrorPredictor::predict_error_mm`]) take positions only.
//!
//! Query cost: the temperature part of each first layer (`b₁ + W₁,T · z_T`), the spindle drifts
//! and the squareness are computed once per observed set of readings and cached (readings are
//! held for a whole sensor period while the controller queries at the interpolation rate, and the
//! compensation's fixed-point iterations reuse them); a query then costs the position columns,
//! the tanh of each hidden unit and the output layers. Nothing is allocated on the query path.
//!
//! Models are written to and read from versioned JSON text ([`mod@file`]).

mod data;
mod fastnet;
mod feed_ranges;
pub mod file;
mod hybrid;
mod kind;
mod linear;
mod part;
mod volumetric;

#[cfg(test)]
pub(crate) mod testdata;

pub(crate) use hybrid::FilterState;
pub(crate) use part::LinearPlusNet;

pub use feed_ranges::feed_ranges;
pub use file::{AnyPredictor, SensorInfo, FORMAT_NAME, FORMAT_VERSION, OLDEST_READ_VERSION};
pub use hybrid::{train_hybrid, HybridPredictor};
pub use kind::ModelKind;
pub use linear::{train_linear, LinearPredictor};
pub use volumetric::{train_volumetric, VolumetricPredictor};

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::linreg::LinRegError;
use crate::nn::{NnError, StopReason};
#[allow(unused_imports)] // for the module doc links
use crate::{dataset::Dataset, synthesis::first_order_error_mm};

/// A volumetric error model usable in the control loop.
///
/// Sensor readings enter by one door, [`Self::observe_readings`]: the model holds the readings
/// last observed and predicts for them. Everything that depends on the readings only (history
/// features, the temperature part of the networks' first layers, drifts that do not depend on
/// the position) is recomputed because readings (or a spindle speed) were observed, at the
/// observation or at the first query after it, never by comparing readings at query time.
pub trait ErrorPredictor {
    /// Sensor names the model expects, in the order of the observed readings.
    fn sensor_names(&self) -> &[String];

    /// Predicted volumetric error E (actual − nominal tool tip, workpiece frame, mm) at axis
    /// positions `q_mm` (mm) under the readings last given to [`Self::observe_readings`].
    ///
    /// Allocation-free. Before any reading the model has none to predict for: the prediction is
    /// NaN.
    fn predict_error_mm(&mut self, q_mm: [f64; 3]) -> [f64; 3];

    /// Change of the volumetric error (mm), component `k`, when axis `k` reached its position
    /// moving in the negative direction instead of the positive one that
    /// [`Self::predict_error_mm`] assumes: the reversal (backlash) of each axis as it shows at
    /// the tool. The default, zero, is a model that knows no reversal (trained on forward
    /// approaches only).
    fn negative_approach_shift_mm(&self) -> [f64; 3] {
        [0.0; 3]
    }

    /// Takes the sensor readings `temps_degc` (°C, [`Self::sensor_names`] order) at time
    /// `time_s` (s, any origin, increasing): the model holds them for the following predictions,
    /// and a model with history features (see [`crate::history`]) filters them. A controller
    /// passes every new reading, also while it is not compensating (warm-up), so the model
    /// knows the thermal past; offline, observe the readings of a state before predicting at it.
    ///
    /// Allocation-free. `temps_degc.len()` must equal `sensor_names().len()` (checked with an
    /// assertion: the sensor set is validated once when the model is attached to a machine,
    /// see [`check_sensor_names`]).
    fn observe_readings(&mut self, time_s: f64, temps_degc: &[f64]);

    /// The spindle ran at the commanded speed `rpm` since the previous call, up to `time_s`
    /// (the same clock as [`Self::observe_readings`]). A model with spindle-speed features
    /// ([`Settings::spindle_speed_exponents`]) filters it; a model without such an input
    /// ignores it. Required of every model (no default), so that a wrapper around a model
    /// cannot drop the signal by forgetting to pass it on.
    fn observe_spindle_speed(&mut self, time_s: f64, rpm: f64);

    /// The axes ran at the commanded mean speeds `feeds_mm_per_min` (|v| of X, Y, Z, mm/min)
    /// since the previous call, up to `time_s`. A model with axis-feed features
    /// ([`Settings::axis_feed_taus_s`]) filters them; a model without such inputs ignores
    /// them. Required of every model, as [`Self::observe_spindle_speed`].
    fn observe_axis_feeds(&mut self, time_s: f64, feeds_mm_per_min: [f64; 3]);

    /// The spindle now holds a tool whose tip sits at `tool_offset_mm` (mm) from the gauge
    /// point: the controller commanded the change (M6) and knows its tool table. A model that
    /// synthesises the tool-tip error from elementary errors follows it, keeping its state (the
    /// filtered history of its inputs); one fitted on the tool-tip error of its calibration
    /// tool accepts only that tool. The default refuses any change.
    ///
    /// # Errors
    /// [`PredictError::GeometryMismatch`] (or [`PredictError::Inconsistent`] for a non-finite
    /// offset) when the model cannot predict for that tool.
    fn change_tool(&mut self, tool_offset_mm: [f64; 3]) -> Result<(), PredictError> {
        Err(PredictError::Inconsistent {
            reason: format!(
                "this model cannot follow a tool change (to tool offset {tool_offset_mm:?} mm)"
            ),
        })
    }
}

/// A mutable borrow predicts like the predictor itself (e.g. `Compensator::new(&mut model)`).
impl<P: ErrorPredictor + ?Sized> ErrorPredictor for &mut P {
    fn sensor_names(&self) -> &[String] {
        (**self).sensor_names()
    }

    #[inline]
    fn predict_error_mm(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        (**self).predict_error_mm(q_mm)
    }

    fn negative_approach_shift_mm(&self) -> [f64; 3] {
        (**self).negative_approach_shift_mm()
    }

    fn observe_readings(&mut self, time_s: f64, temps_degc: &[f64]) {
        (**self).observe_readings(time_s, temps_degc);
    }

    fn observe_spindle_speed(&mut self, time_s: f64, rpm: f64) {
        (**self).observe_spindle_speed(time_s, rpm);
    }

    fn observe_axis_feeds(&mut self, time_s: f64, feeds_mm_per_min: [f64; 3]) {
        (**self).observe_axis_feeds(time_s, feeds_mm_per_min);
    }

    fn change_tool(&mut self, tool_offset_mm: [f64; 3]) -> Result<(), PredictError> {
        (**self).change_tool(tool_offset_mm)
    }
}

/// Errors of training, loading and checking predictors.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PredictError {
    /// The dataset has no records of an instrument the model needs.
    #[error("the dataset has no `{instrument}` records (needed for {needed_for})")]
    MissingInstrument {
        /// Instrument name as in the `instrument` column.
        instrument: &'static str,
        /// What the records are needed for.
        needed_for: &'static str,
    },
    /// The dataset has too few records of an instrument.
    #[error("the dataset has {found} `{instrument}` records, at least {needed} are needed")]
    TooFewRecords {
        /// Instrument name.
        instrument: &'static str,
        /// Records found.
        found: usize,
        /// Minimum required.
        needed: usize,
    },
    /// The settings use the axes' commanded feeds, and a record does not carry them.
    #[error(
        "the axis-feed features need the `x_feed_mm_per_min`, `y_feed_mm_per_min` and \
         `z_feed_mm_per_min` columns on every record; record {index} (cycle `{cycle}`, t = \
         {time_s} s) has none"
    )]
    MissingAxisFeeds {
        /// 0-based record index in the dataset.
        index: usize,
        /// Its cycle.
        cycle: String,
        /// Its time, s.
        time_s: f64,
    },
    /// The settings use the commanded spindle speed, and a record does not carry it.
    #[error(
        "the spindle-speed features need the `spindle_rpm` column on every record; record \
         {index} (cycle `{cycle}`, t = {time_s} s) has none"
    )]
    MissingSpindleSpeed {
        /// 0-based record index in the dataset.
        index: usize,
        /// Its cycle.
        cycle: String,
        /// Its time, s.
        time_s: f64,
    },
    /// Sensors asked for in the settings are not columns of the dataset.
    #[error(
        "sensor columns differ from what is asked: missing {missing:?}; asked for {asked:?}, \
         the dataset has {found:?}"
    )]
    SensorsNotInDataset {
        /// Asked names absent from the dataset.
        missing: Vec<String>,
        /// The names asked for.
        asked: Vec<String>,
        /// The dataset's sensor names.
        found: Vec<String>,
    },
    /// A model's sensors do not match the machine's (names or order).
    #[error("sensor mismatch: the model expects sensors {expected:?} (in this order), the machine has {found:?}")]
    SensorMismatch {
        /// The model's sensor names.
        expected: Vec<String>,
        /// The machine's sensor names.
        found: Vec<String>,
    },
    /// A model's nominal geometry (chain, tool offset) is not the machine's: its predictions
    /// are for another kinematics or another tool.
    #[error(
        "geometry mismatch: the model was trained for chain `{model_chain}` with tool offset \
         {model_tool_mm:?} mm, the machine has chain `{machine_chain}` with tool offset \
         {machine_tool_mm:?} mm{}",
        if model_chain == machine_chain {
            " (a hybrid model follows a tool change; a volumetric or linear one is fitted on the \
             calibration tool's tip: recalibrate with this tool)"
        } else {
            ""
        }
    )]
    GeometryMismatch {
        /// The model's chain.
        model_chain: String,
        /// The model's tool offset, mm.
        model_tool_mm: [f64; 3],
        /// The machine's chain.
        machine_chain: String,
        /// The machine's tool offset, mm.
        machine_tool_mm: [f64; 3],
    },
    /// A record lacks a value the model needs (empty cell).
    #[error(
        "`{instrument}` record of cycle \"{cycle}\" at t = {time_s} s has no `{column}` value"
    )]
    MissingValue {
        /// Instrument name.
        instrument: &'static str,
        /// Cycle of the record.
        cycle: String,
        /// Time of the record, s.
        time_s: f64,
        /// The empty column.
        column: &'static str,
    },
    /// A record's number of temperatures differs from the dataset's sensor list.
    #[error("record {index} has {got} temperatures, the dataset lists {expected} sensors")]
    RaggedTemperatures {
        /// Record index in the dataset.
        index: usize,
        /// Sensors listed.
        expected: usize,
        /// Temperatures in the record.
        got: usize,
    },
    /// A setting is unusable.
    #[error("invalid setting `{field}`: {reason}")]
    BadSettings {
        /// The setting.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// Network construction or training failed.
    ///
    /// The message includes the cause; it is not also given as `source()`, so a printer of the
    /// error chain shows it once.
    #[error("network `{net}`: {cause}")]
    Net {
        /// Which network.
        net: &'static str,
        /// The cause.
        cause: NnError,
    },
    /// A linear regression failed (the cause is in the message, as for [`Self::Net`]).
    #[error("linear model `{model}`: {cause}")]
    Linear {
        /// Which model.
        model: &'static str,
        /// The cause.
        cause: LinRegError,
    },
    /// The text is not a vmc-twin model file.
    #[error("not a vmc-twin model file: {reason}")]
    NotAModel {
        /// What is wrong.
        reason: String,
    },
    /// The model file has a version this build cannot read.
    #[error(
        "model file version {found} is not supported (this build reads versions {oldest} to \
         {supported})"
    )]
    UnsupportedVersion {
        /// Version in the file.
        found: u64,
        /// The oldest version this build reads.
        oldest: u64,
        /// The version this build writes (the newest it reads).
        supported: u64,
    },
    /// The model file holds another kind of model than asked for.
    #[error("model file holds a `{found}` model, expected `{expected}`")]
    WrongKind {
        /// Kind asked for.
        expected: String,
        /// Kind in the file.
        found: String,
    },
    /// The model file is malformed JSON or does not fit the schema.
    #[error("model file: {msg}")]
    Json {
        /// The parser's message (with line and column).
        msg: String,
    },
    /// The model file parses but its parts do not fit together.
    #[error("inconsistent model file: {reason}")]
    Inconsistent {
        /// What does not fit.
        reason: String,
    },
}

/// Training settings shared by the three predictors. Defaults in brackets.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Settings {
    /// Master seed; every network's initialisation seed is derived from it (default: 0).
    pub seed: u64,
    /// Hidden-layer widths tried for each MLP; the best on validation is kept (default: 6, 10).
    /// Why these: with ~12 sensors, 6 tanh units already fit smooth thermal drifts; more
    /// than ~12 over-fits four-hour cycles and slows the 1 MHz query.
    pub hidden_candidates: Vec<usize>,
    /// Maximum Levenberg–Marquardt iterations per net (default: 150).
    pub max_epochs: usize,
    /// Early stopping: epochs without validation improvement (default: 8).
    pub patience: usize,
    /// Independent initialisations per candidate (default: 1).
    pub restarts: usize,
    /// Validation cycles when [`Settings::val_cycles`] is empty: every `round(1/val_fraction)`-th
    /// cycle in file order (at least one when there are ≥ 2 cycles) (default: 0.25).
    pub val_fraction: f64,
    /// Explicit validation cycles (names of the `cycle` column) (default: empty = automatic).
    pub val_cycles: Vec<String>,
    /// Sensors to use, in this order (default: empty = all dataset sensors in column order).
    pub sensors: Vec<String>,
    /// Minimum records per network (each axis, spindle, volumetric) (default: 20).
    pub min_records: usize,
    /// Ridge λ (dimensionless, on normalised slopes) of the squareness regression (default: 1e-3).
    pub squareness_ridge: f64,
    /// Ridge λ of the linear baseline (default: 1e-6): just enough to survive collinear features.
    pub linear_ridge: f64,
    /// Ridge λ of the linear part of each hybrid network (default: 1e-3), see `part`.
    pub part_ridge: f64,
    /// A hybrid network's residual MLP is kept only if it lowers the validation RMSE of its
    /// linear part by at least this fraction (mean over outputs) (default: 0.2).
    pub residual_net_min_gain: f64,
    /// Time constants (s) of the hybrid's history features, see [`crate::history`]: each
    /// network also sees, per sensor, the reading minus its first-order low-pass filter with
    /// each of these time constants (default: empty = present readings only). The baselines
    /// always use the present readings only. Measured (docs/decisions, history features of every sensor): with 30 min
    /// and 2 h the held-out max residual got worse (2.31 → 3.30 µm), so it is off by default.
    pub history_taus_s: Vec<f64>,
    /// Sensors that get history features (default: empty = all the model's sensors).
    pub history_sensors: Vec<String>,
    /// Time constants (s) of history features that only the hybrid's spindle part sees (default:
    /// empty). The spindle drift follows the bearings, which no sensor touches and which lead
    /// the spindle nose and housing readings; the rate at which those readings change (the
    /// feature `x − y_τ` ≈ τ·dx/dt for a short τ) tells how much warmer the bearings are.
    pub spindle_history_taus_s: Vec<f64>,
    /// Sensors with spindle-only history features (default: empty = all the model's sensors).
    pub spindle_history_sensors: Vec<String>,
    /// Position × temperature products in the linear part of each axis network (default:
    /// true), see `part`: a ballscrew or scale expands in proportion to the distance from its
    /// fixed end, so the thermal positioning error is bilinear in position and temperatures.
    pub axis_bilinear: bool,
    /// Heat-input exponents of the commanded spindle speed for the hybrid's spindle part
    /// (default: empty = the speed is not used). **Opt-in**: the controller knows
    /// the speed it commands, so it is information the knowledge side may use; the default
    /// model uses temperature readings only. With exponents, the spindle part also sees per exponent `e` the heat
    /// input `(n / 1000 rpm)^e` and its low-pass filters with [`Self::spindle_speed_taus_s`]
    /// ([`crate::history::SpeedHistory`]); the dataset needs the `spindle_rpm` column.
    pub spindle_speed_exponents: Vec<f64>,
    /// Time constants (s) of the spindle speed's heat-input filters (used with
    /// [`Self::spindle_speed_exponents`]).
    pub spindle_speed_taus_s: Vec<f64>,
    /// Time constants (s) of the axes' commanded-feed heat-input filters (default: empty = the
    /// feeds are not used). With them, the axis parts, the squareness and the spindle part also
    /// see per axis the mean |speed| since the previous sample and its low-pass filters
    /// ([`crate::history::FeedHistory`]): the heat of the screws and motors, which no sensor
    /// may touch. The dataset needs the axis-feed columns.
    pub axis_feed_taus_s: Vec<f64>,
    /// With [`Self::axis_feed_taus_s`]: each axis part sees only its own axis's feed features,
    /// and the spindle part and the squareness none (default: `false`, every part sees all
    /// three axes'). A screw heats with its own axis's traffic and stretches its own axis.
    pub axis_feed_own_axis: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            seed: 0,
            hidden_candidates: vec![6, 10],
            max_epochs: 150,
            patience: 8,
            restarts: 1,
            val_fraction: 0.25,
            val_cycles: Vec::new(),
            sensors: Vec::new(),
            min_records: 20,
            squareness_ridge: 1e-3,
            linear_ridge: 1e-6,
            part_ridge: 1e-3,
            residual_net_min_gain: 0.2,
            history_taus_s: Vec::new(),
            history_sensors: Vec::new(),
            spindle_history_taus_s: Vec::new(),
            spindle_history_sensors: Vec::new(),
            axis_feed_taus_s: Vec::new(),
            axis_feed_own_axis: false,
            axis_bilinear: true,
            spindle_speed_exponents: Vec::new(),
            spindle_speed_taus_s: Vec::new(),
        }
    }
}

impl Settings {
    /// These settings with the commanded spindle speed as the spindle part's heat input
    /// (opt-in, see [`Self::spindle_speed_exponents`]): the same grey-box bank as `fit-thermal`'s
    /// speed inputs ([`crate::thermal_fit::FeatureSpec`]'s defaults: exponents 1, 2, 3 and
    /// filters of 15 min, 1 h, 3 h), chosen there from physics, not tuned here.
    #[must_use]
    pub fn with_spindle_speed_input(self) -> Self {
        let bank = crate::thermal_fit::FeatureSpec::default();
        Self {
            spindle_speed_exponents: bank.speed_exponents,
            spindle_speed_taus_s: bank.time_constants_s,
            ..self
        }
    }

    /// Whether the hybrid's spindle part uses the commanded spindle speed.
    pub fn uses_spindle_speed(&self) -> bool {
        !self.spindle_speed_exponents.is_empty()
    }
}

/// How a network's data were split into training and validation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum SplitKind {
    /// Whole cycles held out (the normal case).
    ByCycle,
    /// Contiguous time blocks (every 5th fifth) — only when the records span a single cycle.
    Blocks,
}

/// Score of one hidden-layer width tried.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CandidateScore {
    /// Hidden units.
    pub hidden_units: usize,
    /// Best validation RMSE, normalised units (multiples of each output's training std).
    pub val_rmse_norm: f64,
}

/// What training one network (or regression) gave.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NetSummary {
    /// Network name (`axis_x`, `axis_y`, `axis_z`, `spindle`, `squareness`, `volumetric`, `linear`).
    pub name: String,
    /// Output names with units (`dx_um`, `rx_urad`, `ex_um`, …), in output order.
    pub outputs: Vec<String>,
    /// Hidden units of the kept net (`None` for a linear regression).
    pub hidden_units: Option<usize>,
    /// Training samples.
    pub n_train: usize,
    /// Validation samples.
    pub n_val: usize,
    /// How the split was made.
    pub split: SplitKind,
    /// Training RMSE per output, in the output's unit.
    pub train_rmse: Vec<f64>,
    /// Validation RMSE per output, in the output's unit.
    pub val_rmse: Vec<f64>,
    /// LM iterations of the kept run (`None` for a regression).
    pub epochs: Option<usize>,
    /// Why the kept run stopped (`None` for a regression).
    pub stop_reason: Option<StopReason>,
    /// Every width tried and its validation score.
    pub candidates: Vec<CandidateScore>,
    /// For a hybrid part (linear model + residual MLP): validation RMSE per output of the
    /// linear model alone, in the output's unit (empty otherwise).
    #[serde(default)]
    pub linear_val_rmse: Vec<f64>,
}

/// What a training call did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainSummary {
    /// Which model class.
    pub kind: ModelKind,
    /// Sensors used, in model order.
    pub sensors: Vec<String>,
    /// Cycles held out for validation (empty when the dataset has one cycle).
    pub val_cycles: Vec<String>,
    /// One entry per network or regression.
    pub nets: Vec<NetSummary>,
}

/// A tool change for a model fitted on one tool's tip error: accepted only when the new tool is
/// that tool (offset within 1 nm).
///
/// # Errors
/// [`PredictError::GeometryMismatch`] naming both tools.
pub(crate) fn same_tool_only(
    model: &crate::synthesis::MachineGeometry,
    tool_offset_mm: [f64; 3],
) -> Result<(), PredictError> {
    let same = model
        .tool_offset_mm
        .iter()
        .zip(&tool_offset_mm)
        .all(|(a, b)| (a - b).abs() <= 1e-6);
    if same {
        Ok(())
    } else {
        Err(PredictError::GeometryMismatch {
            model_chain: model.chain.to_string(),
            model_tool_mm: model.tool_offset_mm,
            machine_chain: model.chain.to_string(),
            machine_tool_mm: tool_offset_mm,
        })
    }
}

/// Checks that a model's sensor list equals the machine's, names and order.
///
/// # Errors
/// [`PredictError::SensorMismatch`] listing both lists.
pub fn check_sensor_names(model: &[String], machine: &[String]) -> Result<(), PredictError> {
    if model == machine {
        Ok(())
    } else {
        Err(PredictError::SensorMismatch {
            expected: model.to_vec(),
            found: machine.to_vec(),
        })
    }
}

/// Asserts the reading count at the door (a programming error, see
/// [`ErrorPredictor::observe_readings`]).
#[inline]
fn assert_temps_len(temps_degc: &[f64], n_sensors: usize) {
    assert_eq!(
        temps_degc.len(),
        n_sensors,
        "predictor observed {} readings, the model has {} sensors",
        temps_degc.len(),
        n_sensors
    );
}
