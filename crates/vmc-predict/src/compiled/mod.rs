//! The compiled hybrid model: a trained [`HybridPredictor`] lowered to the flat,
//! allocation-free form a controller's servo thread runs.
//!
//! What it computes is what the library's query path computes, to round-off: the volumetric
//! error `E(q, T)` (mm, workpiece frame) of the hybrid model — three axis parts
//! `(q_k, T) → (δ, ε)_k`, the spindle part and the squareness, through the first-order synthesis
//! ([`crate::synthesis::first_order_error_mm`]) — and the compensated axis command, the fixed
//! point `q ← p − E(q, T) − R` of [`crate::controller`] (`R` the reversal of the axes whose last
//! commanded motion was negative; tolerance and iteration cap as there). Inputs: the sensor
//! readings (°C, with their time in s: the history features filter them), the commanded spindle
//! speed (rpm) and axis feeds (mm/min) as the model uses them, the commanded position (mm).
//!
//! # The form
//!
//! - **Two stages.** Whatever depends on the readings only (history, speed and feed features,
//!   the temperature columns of every first layer `c_j = b_j + Σ_T W_jT z_T`, the linear parts'
//!   intercepts and their position slopes with the bilinear products, the spindle drifts, the
//!   squareness) is recomputed at the first query after an observation, in the arithmetic order
//!   of the library (these values are bit-identical), then folded for the query (below). A query
//!   evaluates the position column only.
//! - **Folded query.** Per hidden unit `x_j = 2s_j = c₂_j + w₂_j·q` (`w₂ = 2w/σ_q`,
//!   `c₂ = 2c − w₂·m`: the position's normalisation folded in), `a_j = 1 − 2/(e^{x_j} + 1)`; six
//!   output sums per axis part whose de-normalisation also carries the synthesis's units
//!   (µm → mm, µrad → rad) and the sign of the axis's side of the chain; the spindle's part of `E`
//!   cached per readings and tool.
//! - **Flat memory.** Everything a query reads or writes sits in two places: per axis a head
//!   (output biases and de-normalisation, the cached linear terms, the position of the last
//!   evaluation) held in the model itself, and one boxed slice of blocks of four hidden units,
//!   each block holding what a query does with its units (`w₂`, `c₂`, the exponentials and
//!   activations of the last evaluation and of the last solve's start, the output weights
//!   unit-major and padded to eight outputs so a unit adds to the six sums in two 4-wide
//!   multiply–adds). Hidden layers are padded to a multiple of 4 units with zero weights (a
//!   padded unit adds exactly 0). Built once; nothing is allocated afterwards.
//! - **Two passes per axis and evaluation**, four units at a time, fixed-size loops only (no
//!   length-dependent code, no calls): the activations, then the output sums.
//! - **Activations** by the [`kernel`]: a branch-free exponential exact to ~2 ulp, which runs
//!   through SIMD lanes (the library calls libm's `exp` per unit).
//! - **Two instantiations**: portable, and AVX2 with fused multiply–adds where the CPU has them
//!   (detected at build; [`CompiledHybrid::with_portable_code`] forces the portable one). Their
//!   last bits may differ.
//! - **The fixed point** reuses its own work: the first evaluation of a solve is fresh; every
//!   later one starts from the previous iterate's `e^{x_j}` and multiplies by `e^{w₂_j·Δq}`
//!   (a polynomial: the iterates differ by the change of `E`, nanometres to micrometres, so the
//!   step is ~1e-4 or less), afresh for a block of units whose step is too large for the
//!   polynomial ([`kernel::SMALL_STEP_MAX`]). A solve therefore depends on its own inputs only,
//!   never on earlier queries. A solve whose axis coordinate is bit for bit the one the last
//!   solve started at (same readings: an axis at rest) reuses that fresh evaluation of the
//!   part, which is what a fresh evaluation would give to the bit.
//!
//! Equivalence: the readings stage is the library's arithmetic; the folds, the exponential, the
//! order of the output sums and the fused multiply–adds each round differently from the
//! library, by ~1e-16 relative: the predicted error differs by ≤ 2.1e-17 mm (2e-14 µm) on the
//! test models, checked against 1e-12 µm in the tests; the compensated command by at most one
//! rounding of `q = p − E`. The figures are in docs/decisions/2026-11-28-compiled-model.md.
//!
//! Only the hybrid model compiles ([`CompileError::NotHybrid`] for the volumetric and linear
//! baselines, which the library's [`crate::controller::Compensator`] runs).
//!
//! Units: mm, rad, °C, s at the interface; µm and µrad inside the parts (the dataset's units).

mod compensator;
pub mod kernel;
mod lower;
mod query;
mod temps;
#[cfg(test)]
mod tests;

use thiserror::Error;

use crate::predictor::{AnyPredictor, ErrorPredictor, HybridPredictor, ModelKind, PredictError};

pub use compensator::CompiledCompensator;

use query::{AxisHead, Isa, UnitBlock};
use temps::{Inputs, SpindleStage, SquarenessStage, TempPart};

/// Why a model cannot be compiled.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CompileError {
    /// The model is not a hybrid one.
    #[error(
        "a `{kind}` model cannot be compiled: the compiled form covers the hybrid model \
         (elementary-error parts and the synthesis); run a {kind} model on the library's query \
         path (the compensator over the predictor)"
    )]
    NotHybrid {
        /// The kind of the model given.
        kind: ModelKind,
    },
    /// The model file does not load (the cause is in the message).
    #[error("{cause}")]
    Model {
        /// Why it does not load.
        cause: PredictError,
    },
    /// A network of the model uses the rational tanh approximation; the compiled form (as the
    /// library's query path) evaluates the exact tanh, so it would not give the trained net.
    #[error(
        "network `{net}` was trained with the approximate tanh (`FastTanh`); the compiled form \
         evaluates the exact tanh only"
    )]
    ApproximateActivation {
        /// Which network.
        net: &'static str,
    },
    /// The parts do not have the shapes a loaded hybrid model has.
    #[error("the model's parts do not fit together: {reason}")]
    Inconsistent {
        /// What does not fit.
        reason: String,
    },
}

impl From<PredictError> for CompileError {
    fn from(cause: PredictError) -> Self {
        CompileError::Model { cause }
    }
}

/// Bad input at run time (no allocation: the servo thread can return it as it is).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum InputError {
    /// The number of readings is not the model's number of sensors.
    #[error("{got} readings given, the model has {expected} sensors")]
    ReadingCount {
        /// The model's sensors.
        expected: usize,
        /// Readings given.
        got: usize,
    },
    /// A tool offset component is not finite.
    #[error("the tool offset has a non-finite component")]
    ToolOffset,
}

/// The first-order synthesis of a chain, folded: per axis the sign of its side and which
/// positions enter its Abbe arm (as [`crate::synthesis::Chain`] gives them), and the tool.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Synthesis {
    /// `+1` tool side, `−1` workpiece side, per axis.
    sign: [f64; 3],
    /// `arm_mask[k][i]`: 1.0 when position `i` enters axis `k`'s arm, else 0.0.
    arm_mask: [[f64; 3]; 3],
    /// Tool tip relative to the spindle gauge point, mm.
    tool_offset_mm: [f64; 3],
}

/// The hybrid model in its compiled form (module doc). Build it with
/// [`CompiledHybrid::from_predictor`] or [`CompiledHybrid::from_model_file`]; feed it as any
/// [`ErrorPredictor`] (readings, spindle speed, axis feeds); query it with
/// [`ErrorPredictor::predict_error_mm`], or solve the compensation with a
/// [`CompiledCompensator`].
#[derive(Debug, Clone)]
pub struct CompiledHybrid {
    sensors: Vec<String>,
    synthesis: Synthesis,
    /// The reversal as it shows at the tool, mm per E component.
    neg_shift_mm: [f64; 3],
    /// What a query reads of each axis part beside its units.
    heads: [AxisHead; 3],
    /// The units of the three axis parts, four to a block (module doc).
    units: Box<[UnitBlock]>,
    /// Which instantiation of the query code runs.
    isa: Isa,
    /// The readings stage's first-layer columns of one part, before they go to `units`.
    c_scratch: Box<[f64]>,
    /// The readings stage of the three axis parts.
    axis_temps: [TempPart; 3],
    spindle: SpindleStage,
    squareness: SquarenessStage,
    inputs: Inputs,
    /// Spindle drifts for the held readings: δ (mm) then tilts (rad).
    spindle_lin_mm: [f64; 3],
    spindle_tilt_rad: [f64; 2],
    /// Squareness for the held readings, rad: yz, xz, xy.
    squareness_rad: [f64; 3],
    /// The spindle's drifts and tilts at the tool for the held readings and tool, mm.
    constant_mm: [f64; 3],
    /// Whether the readings stage must run before the next query.
    stale: bool,
}

impl CompiledHybrid {
    /// Compiles a hybrid predictor, starting from its present state (filters and held readings:
    /// a warm predictor gives a warm compiled model).
    ///
    /// # Errors
    /// [`CompileError::ApproximateActivation`] for a net trained with the approximate tanh;
    /// [`CompileError::Inconsistent`] for parts of shapes a loaded model cannot have.
    pub fn from_predictor(predictor: &HybridPredictor) -> Result<Self, CompileError> {
        lower::lower(predictor)
    }

    /// Compiles a loaded model of any kind: a hybrid one compiles, the baselines are refused.
    ///
    /// # Errors
    /// [`CompileError::NotHybrid`] for a volumetric or linear model; as
    /// [`Self::from_predictor`] otherwise.
    pub fn from_any(predictor: &AnyPredictor) -> Result<Self, CompileError> {
        match predictor {
            AnyPredictor::Hybrid(h) => Self::from_predictor(h),
            other => Err(CompileError::NotHybrid { kind: other.kind() }),
        }
    }

    /// Compiles the model file text `train` writes (format in [`crate::predictor::file`]).
    ///
    /// # Errors
    /// [`CompileError::Model`] when the text is not a loadable model file;
    /// [`CompileError::NotHybrid`] for a volumetric or linear model; as
    /// [`Self::from_predictor`] otherwise.
    pub fn from_model_file(text: &str) -> Result<Self, CompileError> {
        Self::from_any(&AnyPredictor::from_json_str(text)?)
    }

    /// Number of sensors (readings per observation).
    pub fn n_sensors(&self) -> usize {
        self.sensors.len()
    }

    /// Takes the readings `temps_degc` (°C, model sensor order) at `time_s` (s), as
    /// [`ErrorPredictor::observe_readings`] does, but refuses a wrong count instead of
    /// asserting. Allocation-free.
    ///
    /// # Errors
    /// [`InputError::ReadingCount`]; the model is then unchanged.
    pub fn try_observe_readings(
        &mut self,
        time_s: f64,
        temps_degc: &[f64],
    ) -> Result<(), InputError> {
        if temps_degc.len() != self.sensors.len() {
            return Err(InputError::ReadingCount {
                expected: self.sensors.len(),
                got: temps_degc.len(),
            });
        }
        self.inputs.observe_readings(time_s, temps_degc);
        self.stale = true;
        Ok(())
    }

    /// Whether readings were observed (before the first, predictions are NaN; so are they
    /// after a reading that is not a number).
    pub fn has_readings(&self) -> bool {
        self.inputs.has_readings()
    }

    /// Follows a tool change (tool tip relative to the spindle gauge point, mm): only the
    /// synthesis's arm changes; the filters are kept.
    ///
    /// # Errors
    /// [`InputError::ToolOffset`] for a non-finite component; the model is then unchanged.
    pub fn set_tool_offset_mm(&mut self, tool_offset_mm: [f64; 3]) -> Result<(), InputError> {
        if tool_offset_mm.iter().any(|v| !v.is_finite()) {
            return Err(InputError::ToolOffset);
        }
        self.synthesis.tool_offset_mm = tool_offset_mm;
        self.refresh_constant();
        Ok(())
    }

    /// Hidden units of the X, Y, Z parts' nets (0 where the part is linear only).
    pub fn hidden_units(&self) -> [usize; 3] {
        self.heads.map(|a| a.hidden)
    }

    /// Bytes a query reads and writes: the three heads and the blocks of units.
    pub fn query_block_bytes(&self) -> usize {
        std::mem::size_of_val(&self.heads) + std::mem::size_of_val(&*self.units)
    }

    /// The same model running the portable instantiation of the query code whatever the CPU
    /// (the AVX2 + FMA one, chosen when the CPU has it, may differ in the last bits: fused
    /// multiply–adds round once).
    #[must_use]
    pub fn with_portable_code(mut self) -> Self {
        self.isa = Isa::Portable;
        // The kept start of a solve came from the other code's bits.
        for head in &mut self.heads {
            head.start_valid = false;
        }
        self
    }

    /// Which instantiation of the query code runs: `"portable"` or `"avx2+fma"`.
    pub fn instruction_set(&self) -> &'static str {
        match self.isa {
            Isa::Portable => "portable",
            Isa::Avx2Fma => "avx2+fma",
        }
    }
}

impl ErrorPredictor for CompiledHybrid {
    fn sensor_names(&self) -> &[String] {
        &self.sensors
    }

    /// One fresh evaluation (every activation from its exponential). Allocation-free.
    #[inline]
    fn predict_error_mm(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        if self.stale {
            self.update_temps();
        }
        self.error_fresh_mm(q_mm)
    }

    fn negative_approach_shift_mm(&self) -> [f64; 3] {
        self.neg_shift_mm
    }

    fn observe_readings(&mut self, time_s: f64, temps_degc: &[f64]) {
        assert_eq!(
            temps_degc.len(),
            self.sensors.len(),
            "compiled model observed {} readings, the model has {} sensors",
            temps_degc.len(),
            self.sensors.len()
        );
        self.inputs.observe_readings(time_s, temps_degc);
        self.stale = true;
    }

    fn observe_spindle_speed(&mut self, time_s: f64, rpm: f64) {
        if self.inputs.observe_spindle_speed(time_s, rpm) {
            self.stale = true;
        }
    }

    fn observe_axis_feeds(&mut self, time_s: f64, feeds_mm_per_min: [f64; 3]) {
        if self.inputs.observe_axis_feeds(time_s, feeds_mm_per_min) {
            self.stale = true;
        }
    }

    fn change_tool(&mut self, tool_offset_mm: [f64; 3]) -> Result<(), PredictError> {
        self.set_tool_offset_mm(tool_offset_mm)
            .map_err(|_| PredictError::Inconsistent {
                reason: format!("tool offset holds a non-finite value ({tool_offset_mm:?})"),
            })
    }
}
