//! Drift updates from on-machine probing: what the model did not predict, measured by the
//! machine's own touch probe on a reference artefact and added to the prediction.
//!
//! **What the controller has.** A probing cycle touches an artefact fixed on the table (a
//! reference sphere, a gauge block) and latches the axis command `q` at each trip. The
//! controller's estimate of where its ball centre really was is `p̂ = q + E_pred(q)` (plus the
//! predictor's reversal shift for a touch in the negative direction): the same correction it
//! applies when it compensates. Where the machine's true error is `E`, the ball really was at
//! `q + E(q)`, the contact point (fixed on the table), so `p̂ = contact − (E − E_pred)`: each touch
//! measures the model's residual along the touched axis, up to constants (the contact radius, the
//! probe's pre-travel and mean latency) that cancel against a **reference** — the same cycle run
//! once on the cold machine with the same model ([`ArtefactFix`]). Both inputs are controller
//! data: latched axis positions and the controller's own predictions. Nothing of the machine's
//! truth enters.
//!
//! **Estimator.** One drift state `b_k` per axis (mm), the part of `E_k` the model misses, shared by
//! the whole working volume (an offset). Assumptions, stated: `b_k` is a random walk,
//! `b(t+Δt) = b(t) + w`, `w ~ N(0, q·Δt)` with `q = walk_sigma²` per hour; each measurement is
//! `y_k = b_k + v`, `v ~ N(0, r)` with `r` the variance of the artefact's position from one cycle
//! (the probe's repeatability and latency spread over the touches averaged); axes are
//! independent. The scalar Kalman filter per axis: predict `P ← P + q·Δt`; update
//! `K = P / (P + r)`, `b ← b + K·(y − b)`, `P ← (1 − K)·P`. Between probings `b` holds (a random
//! walk's best forecast) and [`WithDrift`] adds it to the model's prediction, so the compensator
//! corrects it. The filter starts at `b = 0` with variance `initial_sigma²` (the model's
//! residual before any probing).
//!
//! What it cannot do: a residual that varies over the volume (a screw's expansion the model
//! missed, a tilt of the head) is corrected only as the artefact's position sees it. For that,
//! [`DriftField`] estimates an offset and a gradient per component from artefacts at several
//! places (its own module doc).
//!
//! Units: mm and s in the state; µm and hours in the settings where the names say so.

use thiserror::Error;

use crate::predictor::{ErrorPredictor, PredictError};

mod field;
pub use field::{DriftField, FieldSettings};

/// An estimate of the drift the model misses, as a function of the axis position.
pub trait DriftModel {
    /// The estimated drift at axis position `q_mm`, mm per component.
    fn drift_at_mm(&self, q_mm: [f64; 3]) -> [f64; 3];
}

impl DriftModel for DriftFilter {
    /// The per-axis offset, the same everywhere.
    #[inline]
    fn drift_at_mm(&self, _q_mm: [f64; 3]) -> [f64; 3] {
        self.drift_mm
    }
}

impl DriftModel for DriftField {
    #[inline]
    fn drift_at_mm(&self, q_mm: [f64; 3]) -> [f64; 3] {
        DriftField::drift_at_mm(self, q_mm)
    }
}

/// A setting of the drift filter that is not a usable number.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
#[error("drift filter: {field} = {value} must be a finite number > 0")]
pub struct DriftSettingError {
    /// The setting.
    pub field: &'static str,
    /// Its value.
    pub value: f64,
}

/// The per-axis random-walk Kalman filter of the drift the model misses (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriftFilter {
    /// Random walk rate, mm² per s.
    walk_mm2_per_s: f64,
    /// Variance of one measurement, mm².
    measurement_mm2: f64,
    /// Drift estimate per axis, mm.
    drift_mm: [f64; 3],
    /// Its variance per axis, mm².
    var_mm2: [f64; 3],
    /// Time of the last update per axis, s (None before the first).
    updated_s: [Option<f64>; 3],
}

impl DriftFilter {
    /// A filter whose drift walks by `walk_sigma_um_per_sqrt_h` (µm per √h), measured with
    /// σ `measurement_sigma_um` (µm), starting at 0 with σ `initial_sigma_um` (µm).
    ///
    /// # Errors
    /// A setting that is not finite and > 0.
    pub fn new(
        walk_sigma_um_per_sqrt_h: f64,
        measurement_sigma_um: f64,
        initial_sigma_um: f64,
    ) -> Result<Self, DriftSettingError> {
        for (field, value) in [
            ("walk_sigma_um_per_sqrt_h", walk_sigma_um_per_sqrt_h),
            ("measurement_sigma_um", measurement_sigma_um),
            ("initial_sigma_um", initial_sigma_um),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(DriftSettingError { field, value });
            }
        }
        let mm2 = |um: f64| (um * 1e-3).powi(2);
        Ok(DriftFilter {
            walk_mm2_per_s: mm2(walk_sigma_um_per_sqrt_h) / 3600.0,
            measurement_mm2: mm2(measurement_sigma_um),
            drift_mm: [0.0; 3],
            var_mm2: [mm2(initial_sigma_um); 3],
            updated_s: [None; 3],
        })
    }

    /// The drift estimate per axis, mm (what [`WithDrift`] adds to the prediction).
    pub fn drift_mm(&self) -> [f64; 3] {
        self.drift_mm
    }

    /// The estimate's variance per axis at time `time_s`, mm² (grown by the walk since the last
    /// update).
    pub fn variance_mm2_at(&self, time_s: f64) -> [f64; 3] {
        [0, 1, 2].map(|a| self.var_mm2[a] + self.walk_mm2_per_s * self.elapsed_s(a, time_s))
    }

    fn elapsed_s(&self, axis: usize, time_s: f64) -> f64 {
        self.updated_s[axis].map_or(0.0, |t| (time_s - t).max(0.0))
    }

    /// A measurement `measured_mm` of the drift per axis (None: the axis was not measured) at
    /// time `time_s` (s): the filter's predict and update steps. Returns the innovations
    /// `y − b` before the update, mm (0 for an axis not measured). A measurement that is not
    /// finite is ignored.
    pub fn update(&mut self, time_s: f64, measured_mm: [Option<f64>; 3]) -> [f64; 3] {
        let mut innovation = [0.0; 3];
        for (a, y) in measured_mm.iter().enumerate() {
            let Some(y) = y.filter(|y| y.is_finite()) else {
                continue;
            };
            let prior = self.variance_mm2_at(time_s)[a];
            let gain = prior / (prior + self.measurement_mm2);
            innovation[a] = y - self.drift_mm[a];
            self.drift_mm[a] += gain * innovation[a];
            self.var_mm2[a] = (1.0 - gain) * prior;
            self.updated_s[a] = Some(time_s);
        }
        innovation
    }
}

/// A predictor whose prediction carries the probed drift: `E_pred(q) + d(q)`, `d` the estimate
/// of a [`DriftModel`] (a per-axis offset [`DriftFilter`] or an offset-and-gradient
/// [`DriftField`]).
#[derive(Debug, Clone)]
pub struct WithDrift<P, D = DriftFilter> {
    inner: P,
    filter: D,
}

impl<P: ErrorPredictor, D: DriftModel> WithDrift<P, D> {
    /// `inner` corrected by `filter`'s estimate.
    pub fn new(inner: P, filter: D) -> Self {
        WithDrift { inner, filter }
    }

    /// The model without the drift (what a probing cycle evaluates its touches with).
    pub fn inner_mut(&mut self) -> &mut P {
        &mut self.inner
    }

    /// The filter.
    pub fn filter(&self) -> &D {
        &self.filter
    }

    /// The filter, to update it with a probing cycle.
    pub fn filter_mut(&mut self) -> &mut D {
        &mut self.filter
    }
}

impl<P: ErrorPredictor, D: DriftModel> ErrorPredictor for WithDrift<P, D> {
    fn sensor_names(&self) -> &[String] {
        self.inner.sensor_names()
    }

    #[inline]
    fn predict_error_mm(&mut self, q_mm: [f64; 3]) -> [f64; 3] {
        let e = self.inner.predict_error_mm(q_mm);
        let b = self.filter.drift_at_mm(q_mm);
        [e[0] + b[0], e[1] + b[1], e[2] + b[2]]
    }

    fn negative_approach_shift_mm(&self) -> [f64; 3] {
        self.inner.negative_approach_shift_mm()
    }

    fn observe_readings(&mut self, time_s: f64, temps_degc: &[f64]) {
        self.inner.observe_readings(time_s, temps_degc);
    }

    fn observe_spindle_speed(&mut self, time_s: f64, rpm: f64) {
        self.inner.observe_spindle_speed(time_s, rpm);
    }

    fn observe_axis_feeds(&mut self, time_s: f64, feeds_mm_per_min: [f64; 3]) {
        self.inner.observe_axis_feeds(time_s, feeds_mm_per_min);
    }

    fn change_tool(&mut self, tool_offset_mm: [f64; 3]) -> Result<(), PredictError> {
        self.inner.change_tool(tool_offset_mm)
    }
}

/// One touch as the controller logged it: the latched axis command (mm), the moving axis and
/// its direction (±1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatchedTouch {
    /// Latched axis command, mm.
    pub axis_mm: [f64; 3],
    /// Moving axis (0 X, 1 Y, 2 Z).
    pub axis: usize,
    /// Direction of the touch, ±1.
    pub sign: f64,
}

/// The artefact's position per axis as the controller estimates it from one cycle's touches
/// under `model` (its readings as they are): each touch gives `q + E_pred(q)` along its axis
/// (plus the reversal shift for a negative touch); the touches of one axis are averaged (two
/// opposite touches of a sphere: its centre, the pre-travel cancelling). None for an axis not
/// touched.
pub fn artefact_position_mm<P: ErrorPredictor>(
    model: &mut P,
    touches: &[LatchedTouch],
) -> [Option<f64>; 3] {
    let shift = model.negative_approach_shift_mm();
    let mut sum = [0.0; 3];
    let mut n = [0usize; 3];
    for t in touches.iter().filter(|t| t.axis < 3) {
        let e = model.predict_error_mm(t.axis_mm);
        let a = t.axis;
        let rev = if t.sign < 0.0 { shift[a] } else { 0.0 };
        sum[a] += t.axis_mm[a] + e[a] + rev;
        n[a] += 1;
    }
    [0, 1, 2].map(|a| (n[a] > 0).then(|| sum[a] / n[a] as f64))
}

/// The artefact's reference position (mm per axis), from a cycle on the cold machine with the
/// same model: what later cycles are compared with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArtefactFix {
    /// Reference position per axis, mm (None: an axis the cycle does not touch).
    pub reference_mm: [Option<f64>; 3],
}

impl ArtefactFix {
    /// The drift the model misses per axis, mm, from a cycle's estimate `position_mm`
    /// (from [`artefact_position_mm`] with the model alone): `reference − position`.
    pub fn drift_mm(&self, position_mm: [Option<f64>; 3]) -> [Option<f64>; 3] {
        [0, 1, 2].map(|a| match (self.reference_mm[a], position_mm[a]) {
            (Some(r), Some(p)) => Some(r - p),
            _ => None,
        })
    }
}

#[cfg(test)]
mod tests;
