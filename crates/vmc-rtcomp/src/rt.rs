//! The component's work in plain Rust (the C functions are thin wrappers around it): the
//! averaging of the commands between samples, the observation of a sample, the compensation of
//! each period, and the status of what came out.
//!
//! Units: s, °C, mm, rpm, mm/min.

use std::ffi::CString;

use vmc_predict::compiled::{CompileError, CompiledCompensator, CompiledHybrid, InputError};
use vmc_predict::controller::Controller;
use vmc_predict::predictor::ErrorPredictor;

/// What the controller gives the component every servo period (the C struct `VmcCompInputs`;
/// the field order is the C layout, pointers and 8-byte values first).
#[derive(Debug, Clone, Copy)]
#[repr(C)]
pub struct Inputs {
    /// The latest readings (°C, model sensor order), `n_temps` of them; read only when
    /// `new_sample` is nonzero (may be null otherwise).
    pub temps_degc: *const f64,
    /// Number of readings at `temps_degc` (must be the model's number of sensors).
    pub n_temps: usize,
    /// The controller's clock, s (increasing).
    pub time_s: f64,
    /// Commanded tool position X, Y, Z (workpiece coordinates, mm), without the corrections.
    pub commanded_mm: [f64; 3],
    /// Commanded spindle speed now, rpm (0 when stopped).
    pub spindle_rpm: f64,
    /// Commanded axis speeds now, X, Y, Z, mm/min (signed or not: |v| is used).
    pub axis_feed_mm_per_min: [f64; 3],
    /// Nonzero when `temps_degc` holds a new sensor sample.
    pub new_sample: i32,
}

/// What the component gives back every servo period (the C struct `VmcCompOutputs`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[repr(C)]
pub struct Outputs {
    /// Corrections to add to the commanded position X, Y, Z, mm (the compensated axis command
    /// minus the commanded position); zero unless the status is `Ok` or `NotConverged`.
    pub correction_mm: [f64; 3],
    /// Size of the fixed point's last step, mm.
    pub last_step_mm: f64,
    /// Predictor evaluations of the fixed point.
    pub iterations: i32,
    /// A [`Status`] as an integer.
    pub status: i32,
}

/// How a period went (the C constants `VMC_COMP_*`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(i32)]
pub enum Status {
    /// Corrections computed.
    Ok = 0,
    /// The fixed point used its evaluations without reaching the tolerance; the corrections of
    /// its last iterate are given (as the library's compensator does).
    NotConverged = 1,
    /// No sample observed yet: zero corrections.
    NoReadings = 2,
    /// The prediction is not a number (a reading that is not, e.g. a failed sensor): zero
    /// corrections.
    NotFinite = 3,
    /// Bad input (a null pointer, a reading count other than the model's, a time, position or
    /// command that is not finite): zero corrections, nothing taken.
    BadInput = -1,
}

/// The component: the compiled model's compensator and the commands averaged since the last
/// sample.
#[derive(Debug, Clone)]
pub struct RtComp {
    comp: CompiledCompensator,
    /// Sensor names, NUL-terminated, for the C side.
    names: Vec<CString>,
    /// Clock of the previous period, s.
    last_time_s: Option<f64>,
    /// The commands of the previous period, in effect since it (rpm; mm/min).
    held_rpm: f64,
    held_feeds: [f64; 3],
    /// Time integrals of |rpm| and |v| since the last sample, and their span (s).
    rpm_s: f64,
    feeds_s: [f64; 3],
    span_s: f64,
}

impl RtComp {
    /// A component for the model file text `model_json` (as `train` writes it). Allocates.
    ///
    /// # Errors
    /// What [`CompiledHybrid::from_model_file`] refuses (not a model file, not a hybrid model,
    /// …).
    pub fn new(model_json: &str) -> Result<Self, CompileError> {
        let model = CompiledHybrid::from_model_file(model_json)?;
        let names = model
            .sensor_names()
            .iter()
            .map(|n| {
                // A JSON string may hold a NUL; such a name is cut there for C.
                let bytes: Vec<u8> = n.bytes().take_while(|b| *b != 0).collect();
                CString::new(bytes).unwrap_or_default()
            })
            .collect();
        Ok(Self {
            comp: CompiledCompensator::new(model),
            names,
            last_time_s: None,
            held_rpm: 0.0,
            held_feeds: [0.0; 3],
            rpm_s: 0.0,
            feeds_s: [0.0; 3],
            span_s: 0.0,
        })
    }

    /// Number of sensors (readings per sample).
    pub fn n_sensors(&self) -> usize {
        self.names.len()
    }

    /// Name of sensor `index` (model order), NUL-terminated; None out of range.
    pub fn sensor_name(&self, index: usize) -> Option<&CString> {
        self.names.get(index)
    }

    /// The model in use.
    pub fn model(&self) -> &CompiledHybrid {
        self.comp.model()
    }

    /// Follows a tool change (tool tip from the spindle gauge point, mm). Allocation-free.
    ///
    /// # Errors
    /// [`InputError::ToolOffset`] for a non-finite component (nothing changes then).
    pub fn set_tool_offset_mm(&mut self, tool_offset_mm: [f64; 3]) -> Result<(), InputError> {
        self.comp.model_mut().set_tool_offset_mm(tool_offset_mm)
    }

    /// One servo period: takes a sample when `temps_degc` is given, then compensates
    /// `commanded_mm`. Allocation-free; never panics.
    pub fn update(
        &mut self,
        time_s: f64,
        temps_degc: Option<&[f64]>,
        commanded_mm: [f64; 3],
        spindle_rpm: f64,
        feeds_mm_per_min: [f64; 3],
    ) -> Outputs {
        let finite = time_s.is_finite()
            && spindle_rpm.is_finite()
            && commanded_mm
                .iter()
                .chain(&feeds_mm_per_min)
                .all(|v| v.is_finite());
        if !finite || temps_degc.is_some_and(|t| t.len() != self.n_sensors()) {
            return status_only(Status::BadInput);
        }
        self.integrate_commands(time_s);
        if let Some(temps) = temps_degc {
            self.take_sample(time_s, temps, spindle_rpm, feeds_mm_per_min);
        }
        self.held_rpm = spindle_rpm;
        self.held_feeds = feeds_mm_per_min;
        let q = self.comp.axis_command_mm(commanded_mm);
        let info = self.comp.last_solve();
        if !self.comp.model().has_readings() {
            return status_only(Status::NoReadings);
        }
        if q.iter().any(|v| !v.is_finite()) {
            return status_only(Status::NotFinite);
        }
        Outputs {
            correction_mm: [
                q[0] - commanded_mm[0],
                q[1] - commanded_mm[1],
                q[2] - commanded_mm[2],
            ],
            last_step_mm: info.last_step_mm,
            iterations: i32::try_from(info.iterations).unwrap_or(i32::MAX),
            status: if info.converged {
                Status::Ok
            } else {
                Status::NotConverged
            } as i32,
        }
    }

    /// Adds the previous period's commands over the time since it.
    fn integrate_commands(&mut self, time_s: f64) {
        if let Some(t0) = self.last_time_s {
            let dt = time_s - t0;
            if dt > 0.0 {
                self.rpm_s += self.held_rpm.abs() * dt;
                for (f, v) in self.feeds_s.iter_mut().zip(self.held_feeds) {
                    *f += v.abs() * dt;
                }
                self.span_s += dt;
            }
        }
        if self.last_time_s.is_none_or(|t0| time_s > t0) {
            self.last_time_s = Some(time_s);
        }
    }

    /// Observes a sample: the readings, then the mean commands since the previous sample (the
    /// present ones when no time has passed), as the library's loop gives them.
    fn take_sample(&mut self, time_s: f64, temps: &[f64], rpm: f64, feeds: [f64; 3]) {
        let (mean_rpm, mean_feeds) = if self.span_s > 0.0 {
            (
                self.rpm_s / self.span_s,
                self.feeds_s.map(|f| f / self.span_s),
            )
        } else {
            (rpm.abs(), feeds.map(f64::abs))
        };
        // The count was checked by the caller: this cannot be refused.
        if self.comp.try_on_readings(time_s, temps).is_ok() {
            self.comp.on_spindle_speed(time_s, mean_rpm);
            self.comp.on_axis_feeds(time_s, mean_feeds);
        }
        self.rpm_s = 0.0;
        self.feeds_s = [0.0; 3];
        self.span_s = 0.0;
    }
}

/// Zero corrections with `status`.
fn status_only(status: Status) -> Outputs {
    Outputs {
        status: status as i32,
        ..Outputs::default()
    }
}
