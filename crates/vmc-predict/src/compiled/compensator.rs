//! The compensator over the compiled model: the [`Controller`] a servo thread (or the twin's
//! loop) drives, with the fixed point solved by the compiled model itself (it reuses the
//! activations of one iterate for the next, see the `compiled` module doc).
//!
//! Same behaviour as [`crate::controller::Compensator`]: the same tolerance and iteration cap
//! (defaults [`DEFAULT_TOL_MM`], [`DEFAULT_MAX_ITERATIONS`]) and the same tracking of each axis's
//! direction of commanded motion for the reversal, the same fixed-point loop (the same code,
//! `controller::fixed_point_mm`, with the compiled evaluations).

use crate::controller::{
    ApproachDirections, Controller, SolveInfo, DEFAULT_MAX_ITERATIONS, DEFAULT_TOL_MM,
};
use crate::predictor::{check_sensor_names, ErrorPredictor, PredictError};

use super::{CompiledHybrid, InputError};

/// Turns commanded tool positions (mm) into compensated axis commands (mm) with a
/// [`CompiledHybrid`]. Allocation-free after construction.
#[derive(Debug, Clone)]
pub struct CompiledCompensator {
    model: CompiledHybrid,
    tol_mm: f64,
    max_iterations: usize,
    directions: ApproachDirections,
    last: SolveInfo,
}

impl CompiledCompensator {
    /// A compensator with the default tolerance (1e-6 mm) and iteration cap (5).
    pub fn new(model: CompiledHybrid) -> Self {
        Self {
            model,
            tol_mm: DEFAULT_TOL_MM,
            max_iterations: DEFAULT_MAX_ITERATIONS,
            directions: ApproachDirections::default(),
            last: SolveInfo::default(),
        }
    }

    /// A compensator for a machine with sensors `machine_sensor_names` (checked against the
    /// model's, names and order).
    ///
    /// # Errors
    /// [`PredictError::SensorMismatch`] when names or order differ.
    pub fn for_machine(
        model: CompiledHybrid,
        machine_sensor_names: &[String],
    ) -> Result<Self, PredictError> {
        check_sensor_names(model.sensor_names(), machine_sensor_names)?;
        Ok(Self::new(model))
    }

    /// Sets the step tolerance (mm, clamped to ≥ 0) and the evaluation cap (≥ 1).
    #[must_use]
    pub fn with_tolerance(mut self, tol_mm: f64, max_iterations: usize) -> Self {
        self.tol_mm = tol_mm.max(0.0);
        self.max_iterations = max_iterations.max(1);
        self
    }

    /// Sets where the tool is commanded when the compensator takes over, so the first motion
    /// already gives directions.
    #[must_use]
    pub fn with_start_mm(mut self, p_mm: [f64; 3]) -> Self {
        self.directions = ApproachDirections::starting_at(p_mm);
        self
    }

    /// Notes a commanded tool position `p_mm` (mm) on the trajectory without computing a
    /// command (updates the axes' directions of motion).
    #[inline]
    pub fn note_commanded_mm(&mut self, p_mm: [f64; 3]) {
        self.directions.note_commanded_mm(p_mm);
    }

    /// Direction of each axis's last commanded motion: `1.0` positive (or none yet), `-1.0`
    /// negative.
    pub fn approach_directions(&self) -> [f64; 3] {
        self.directions.signs()
    }

    /// Takes new readings (°C, model sensor order) at `time_s`, refusing a wrong count.
    ///
    /// # Errors
    /// [`InputError::ReadingCount`]; nothing changes then.
    pub fn try_on_readings(&mut self, time_s: f64, values_degc: &[f64]) -> Result<(), InputError> {
        self.model.try_observe_readings(time_s, values_degc)
    }

    /// How the last [`Controller::axis_command_mm`] went.
    pub fn last_solve(&self) -> SolveInfo {
        self.last
    }

    /// The model.
    pub fn model(&self) -> &CompiledHybrid {
        &self.model
    }

    /// The model, mutably (e.g. to query it directly).
    pub fn model_mut(&mut self) -> &mut CompiledHybrid {
        &mut self.model
    }
}

impl Controller for CompiledCompensator {
    fn on_readings(&mut self, time_s: f64, values_degc: &[f64]) {
        self.model.observe_readings(time_s, values_degc);
    }

    fn on_spindle_speed(&mut self, time_s: f64, rpm: f64) {
        self.model.observe_spindle_speed(time_s, rpm);
    }

    fn on_axis_feeds(&mut self, time_s: f64, feeds_mm_per_min: [f64; 3]) {
        self.model.observe_axis_feeds(time_s, feeds_mm_per_min);
    }

    fn on_commanded_motion(&mut self, start_mm: [f64; 3], end_mm: [f64; 3]) {
        self.directions.note_motion_segment_mm(start_mm, end_mm);
    }

    fn on_tool_change(&mut self, tool_offset_mm: [f64; 3]) -> Result<(), String> {
        self.model
            .set_tool_offset_mm(tool_offset_mm)
            .map_err(|e| e.to_string())
    }

    /// Axis command `q` (mm) that should put the tool at `p_mm`; `p_mm` also counts as
    /// commanded motion for the directions. Allocation-free.
    #[inline]
    fn axis_command_mm(&mut self, p_mm: [f64; 3]) -> [f64; 3] {
        self.directions.note_commanded_mm(p_mm);
        let (q, info) = self.model.solve_mm(
            p_mm,
            self.directions.negative(),
            self.tol_mm,
            self.max_iterations,
        );
        self.last = info;
        q
    }
}
