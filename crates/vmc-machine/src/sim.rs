//! The simulation loop: one clock drives the thermal network, the planned motion,
//! the (optional) compensating controller and the measurement of where the tool really was.
//!
//! Time advances in thermal steps (default 1 s). Within a step the heat load is what the program
//! did during it: spindle speed in effect, mean |axis speed| and mean axis position (the ballscrew
//! nut deposits its heat where it runs). Sensor readings are sampled once per step and held, as a
//! controller sampling at 1 Hz would. Measurement points are taken either at the middle of every
//! dwell (diagonal tests: the machine dwells while the laser reads) or at every interpolation
//! cycle during motion as well.
//!
//! Before and after compensation are computed in the same pass: at each point the uncompensated
//! machine is commanded `q = p` and the compensated one `q = controller(p)` (computed under the
//! readings last given to the controller), in the same thermal state and with the same random
//! approach error, so they compare point by point.

use thiserror::Error;

use crate::motion::{Plan, SegmentKind};
use crate::sensors::SensorReadings;
use crate::thermal::Activity;
use crate::twin::{Twin, TwinError};

pub mod replay;

/// Where measurement points are taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SampleMode {
    /// At the middle of each dwell (G4): the measurement points of a diagonal test.
    Dwells,
    /// At every interpolation cycle during motion, plus the middle of each dwell.
    EveryCycle,
}

/// Settings of one simulated execution. The step and the cycle are checked once, when the
/// config is made ([`SimConfig::new`]); a config always holds usable values.
#[derive(Debug, Clone, Copy)]
pub struct SimConfig {
    /// Thermal integration and sensor sampling step, s (default 1 s).
    thermal_step_s: f64,
    /// Interpolation cycle for [`SampleMode::EveryCycle`], s (default 0.001 s).
    interp_cycle_s: f64,
    /// Where to measure (default: at dwells).
    pub sample_mode: SampleMode,
    /// Also compute each point's thermal part (error minus the cold-geometry error), for
    /// reports; costs a second error evaluation per point (default false).
    pub report_thermal_part: bool,
}

/// A step or cycle that cannot be simulated.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum SimConfigError {
    /// The thermal step is not a positive number.
    #[error("thermal step must be > 0 s, got {0}")]
    ThermalStep(f64),
    /// The interpolation cycle is not a positive number.
    #[error("interpolation cycle must be > 0 s, got {0}")]
    InterpCycle(f64),
}

impl SimConfig {
    /// A config with thermal step `thermal_step_s` and interpolation cycle `interp_cycle_s`
    /// (both s, finite and > 0), measuring at dwells, without thermal parts.
    ///
    /// # Errors
    /// A step or cycle that is not a positive number.
    pub fn new(thermal_step_s: f64, interp_cycle_s: f64) -> Result<Self, SimConfigError> {
        if !(thermal_step_s > 0.0 && thermal_step_s.is_finite()) {
            return Err(SimConfigError::ThermalStep(thermal_step_s));
        }
        if !(interp_cycle_s > 0.0 && interp_cycle_s.is_finite()) {
            return Err(SimConfigError::InterpCycle(interp_cycle_s));
        }
        Ok(Self {
            thermal_step_s,
            interp_cycle_s,
            ..Self::default()
        })
    }

    /// Thermal integration and sensor sampling step, s.
    pub fn thermal_step_s(&self) -> f64 {
        self.thermal_step_s
    }

    /// Interpolation cycle, s.
    pub fn interp_cycle_s(&self) -> f64 {
        self.interp_cycle_s
    }

    /// The same config measuring as `mode` says.
    #[must_use]
    pub fn sampling(mut self, mode: SampleMode) -> Self {
        self.sample_mode = mode;
        self
    }

    /// The same config, computing each point's thermal part if `on`.
    #[must_use]
    pub fn with_thermal_part(mut self, on: bool) -> Self {
        self.report_thermal_part = on;
        self
    }
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            thermal_step_s: 1.0,
            interp_cycle_s: 0.001,
            sample_mode: SampleMode::Dwells,
            report_thermal_part: false,
        }
    }
}

/// The controller in the loop (the compensation), from the knowledge side: it gets nothing of
/// the twin but the held sensor readings' values and time ([`Controller::on_readings`] at every
/// thermal step), the commanded spindle speed, the commanded motion and the commanded tool
/// positions.
pub use vmc_predict::controller::Controller;

/// One measurement point.
#[derive(Debug, Clone, PartialEq)]
pub struct PointRecord {
    /// Index of the point in this run (0-based).
    pub index: usize,
    /// Twin time, s.
    pub time_s: f64,
    /// Source line of the segment being executed.
    pub line: usize,
    /// Commanded tool position (workpiece coordinates), mm.
    pub commanded_mm: [f64; 3],
    /// True error without compensation, µm.
    pub error_before_um: [f64; 3],
    /// Thermal part of the uncompensated error (error now minus the same point with the machine
    /// at its reference temperature), µm, when [`SimConfig::report_thermal_part`] is set. Truth,
    /// for reports only.
    pub thermal_part_um: Option<[f64; 3]>,
    /// Axis command issued by the compensator, mm (None without compensation).
    pub compensated_command_mm: Option<[f64; 3]>,
    /// True error with compensation, µm (None without compensation).
    pub error_after_um: Option<[f64; 3]>,
    /// Whether the point is a dwell (measurement) point.
    pub at_dwell: bool,
}

/// The start of one executed program (or of a phase of a study, such as the thermal history
/// that leads to an evaluation state).
#[derive(Debug, Clone, PartialEq)]
pub struct RunStart {
    /// What runs, e.g. the program file name or `warm-up trajectories/warmup_4h_8000rpm.ngc`.
    pub label: String,
    /// Twin time at the start, s.
    pub time_s: f64,
    /// Expected duration, s.
    pub duration_s: f64,
    /// Whether measurement points are taken (false for warm-ups and thermal histories).
    pub measured: bool,
}

/// How notable an [`SimEvent`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventLevel {
    /// Information (phase changes, notes).
    Info,
    /// Something to look at (a near miss, a travel limit approached).
    Warning,
    /// A failure of the program on the machine (a collision, a contact).
    Error,
}

/// Something notable that happened at one instant: a contact found by a collision check, a
/// travel limit, a phase change. Observers draw or list it (the recorder shows a highlighted
/// point and a text-log entry).
#[derive(Debug, Clone, PartialEq)]
pub struct SimEvent {
    /// Twin time, s.
    pub time_s: f64,
    /// Severity.
    pub level: EventLevel,
    /// Short machine-readable kind, e.g. `contact`, `travel`.
    pub kind: String,
    /// Human-readable description.
    pub text: String,
    /// Where it happened, tool position in workpiece coordinates, mm (if it has a place).
    pub position_mm: Option<[f64; 3]>,
}

/// Receives what happens during a run (report, recorder, progress bar).
///
/// Observers are on the truth side (reports, visualisation): they may see node temperatures.
/// Controllers never do (they get only the readings' values and time, see [`Controller`]).
pub trait Observer {
    /// A program (or a phase) starts.
    fn on_run_start(&mut self, _start: &RunStart) {}
    /// A measurement point was taken.
    fn on_point(&mut self, _point: &PointRecord, _readings: &SensorReadings) {}
    /// A thermal step ended at `time_s` with these (new) readings.
    fn on_thermal_step(&mut self, _time_s: f64, _readings: &SensorReadings) {}
    /// Truth, for visualisation: the node temperatures (°C, in the thermal network's node
    /// order) after the thermal step that ended at `time_s`. Called right after
    /// [`Observer::on_thermal_step`].
    fn on_node_temps(&mut self, _time_s: f64, _node_temps_degc: &[f64]) {}
    /// The interval (s) at which this observer wants the commanded axis positions during the
    /// run ([`Observer::on_motion_sample`]); `None` (default) for none.
    fn motion_sample_interval_s(&self) -> Option<f64> {
        None
    }
    /// The commanded axis position `axis_mm` (machine coordinates, mm) at twin time `time_s`,
    /// every [`Observer::motion_sample_interval_s`] of plan time (dwells included).
    fn on_motion_sample(&mut self, _time_s: f64, _axis_mm: [f64; 3]) {}
    /// Something notable happened (see [`SimEvent`]).
    fn on_event(&mut self, _event: &SimEvent) {}
}

/// Passes everything to two observers in turn (e.g. the run log and a recorder).
pub struct Tee<'a>(pub &'a mut dyn Observer, pub &'a mut dyn Observer);

impl Observer for Tee<'_> {
    fn on_run_start(&mut self, start: &RunStart) {
        self.0.on_run_start(start);
        self.1.on_run_start(start);
    }
    fn on_point(&mut self, point: &PointRecord, readings: &SensorReadings) {
        self.0.on_point(point, readings);
        self.1.on_point(point, readings);
    }
    fn on_thermal_step(&mut self, time_s: f64, readings: &SensorReadings) {
        self.0.on_thermal_step(time_s, readings);
        self.1.on_thermal_step(time_s, readings);
    }
    fn on_node_temps(&mut self, time_s: f64, node_temps_degc: &[f64]) {
        self.0.on_node_temps(time_s, node_temps_degc);
        self.1.on_node_temps(time_s, node_temps_degc);
    }
    /// The finer of the two intervals.
    fn motion_sample_interval_s(&self) -> Option<f64> {
        match (
            self.0.motion_sample_interval_s(),
            self.1.motion_sample_interval_s(),
        ) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
    fn on_motion_sample(&mut self, time_s: f64, axis_mm: [f64; 3]) {
        self.0.on_motion_sample(time_s, axis_mm);
        self.1.on_motion_sample(time_s, axis_mm);
    }
    fn on_event(&mut self, event: &SimEvent) {
        self.0.on_event(event);
        self.1.on_event(event);
    }
}

/// An observer that ignores everything (warm-up programs).
#[derive(Debug, Default, Clone, Copy)]
pub struct NullObserver;

impl Observer for NullObserver {}

/// An observer that only counts points (benchmarks, long runs).
#[derive(Debug, Default, Clone, Copy)]
pub struct CountPoints {
    /// Points seen.
    pub points: usize,
}

impl Observer for CountPoints {
    fn on_point(&mut self, _point: &PointRecord, _readings: &SensorReadings) {
        self.points += 1;
    }
}

/// An observer that keeps every point.
#[derive(Debug, Default, Clone)]
pub struct CollectPoints {
    /// The points, in time order.
    pub points: Vec<PointRecord>,
}

impl Observer for CollectPoints {
    fn on_point(&mut self, point: &PointRecord, _readings: &SensorReadings) {
        self.points.push(point.clone());
    }
}

/// Why a run failed.
#[derive(Debug, Error)]
pub enum SimError {
    /// The twin rejected a step.
    #[error(transparent)]
    Twin(#[from] TwinError),
    /// Bad settings.
    #[error("simulation settings: {0}")]
    Config(#[from] SimConfigError),
    /// The compensation commanded the axes implausibly far from the programmed point.
    #[error(
        "line {line} (t = {time_s:.1} s): the compensation moves the axes {correction_mm:.4} mm \
         away from the programmed point ({:.3}, {:.3}, {:.3}) mm, above the limit of {} mm for a \
         geometric and thermal correction: the model does not fit this machine or is corrupt",
        p_mm[0], p_mm[1], p_mm[2], MAX_CORRECTION_MM
    )]
    Compensation {
        /// Program line of the point.
        line: usize,
        /// Twin time, s.
        time_s: f64,
        /// Programmed tool position, mm.
        p_mm: [f64; 3],
        /// Distance of the axis command from it, mm (NaN if not a number).
        correction_mm: f64,
    },
    /// A replayed sample is not later than the one before it.
    #[error("line {line}: time {time_s} s does not follow the previous sample's {previous_s} s")]
    TimeNotIncreasing {
        /// Log line of the sample.
        line: usize,
        /// Its time, s.
        time_s: f64,
        /// The previous sample's time, s.
        previous_s: f64,
    },
    /// The controller cannot compensate with the tool the program loads.
    #[error("line {line}: tool change: {message}")]
    ToolChange {
        /// Program line of the `M6`.
        line: usize,
        /// The controller's reason.
        message: String,
    },
}

/// Largest distance between the compensated axis command and the programmed point, mm. Geometric
/// and thermal errors of a machining centre are tens of µm; a correction above 1 mm is a model
/// that does not belong to the machine (or a corrupt file), and is refused, as a CNC limits its
/// compensation values.
pub const MAX_CORRECTION_MM: f64 = 1.0;

/// Executes `plan` on `twin` from its current state. Plan time 0 is the twin's current time.
pub fn execute(
    twin: &mut Twin,
    plan: &Plan,
    cfg: &SimConfig,
    mut compensator: Option<&mut dyn Controller>,
    observer: &mut dyn Observer,
) -> Result<(), SimError> {
    let motion_every_s = observer
        .motion_sample_interval_s()
        .filter(|dt| *dt > 0.0 && dt.is_finite());
    let mut clock = Clock {
        plan_t_s: 0.0,
        twin_t0_s: twin.time_s(),
        step_s: cfg.thermal_step_s,
        readings: hand_over(twin, reborrow(&mut compensator)),
        last_motion_segment: None,
        motion_every_s,
        next_motion_sample: 0,
    };
    let mut index = 0;
    for (si, seg) in plan.segments().iter().enumerate() {
        let moving = matches!(
            seg.kind,
            SegmentKind::Rapid | SegmentKind::Feed | SegmentKind::Arc
        );
        match (seg.kind, cfg.sample_mode) {
            (SegmentKind::Dwell, _) => {
                let t = seg.t_start_s + 0.5 * seg.duration_s;
                clock.run_until(twin, plan, t, observer, &mut compensator)?;
                clock.note_direction(twin, plan, si);
                let p = seg.end_mm;
                measure(
                    twin,
                    clock.twin_t0_s + t,
                    &clock.readings,
                    &mut compensator,
                    observer,
                    index,
                    seg.line,
                    p,
                    true,
                    cfg.report_thermal_part,
                )?;
                index += 1;
            }
            (_, SampleMode::EveryCycle) if moving && seg.duration_s > 0.0 => {
                let n = (seg.duration_s / cfg.interp_cycle_s).ceil() as usize;
                for k in 0..n {
                    let t = seg.t_start_s + k as f64 * cfg.interp_cycle_s;
                    clock.run_until(twin, plan, t, observer, &mut compensator)?;
                    twin.note_motion(plan.velocity_at(t));
                    let p = plan.position_at(t);
                    measure(
                        twin,
                        clock.twin_t0_s + t,
                        &clock.readings,
                        &mut compensator,
                        observer,
                        index,
                        seg.line,
                        p,
                        false,
                        cfg.report_thermal_part,
                    )?;
                    index += 1;
                }
            }
            (SegmentKind::ToolChange { tool }, _) => {
                let offset_mm = twin.change_tool(tool)?;
                if let Some(c) = compensator.as_mut() {
                    c.on_tool_change(offset_mm)
                        .map_err(|message| SimError::ToolChange {
                            line: seg.line,
                            message,
                        })?;
                }
            }
            _ => {}
        }
        if moving {
            clock.last_motion_segment = Some(si);
            if let Some(c) = compensator.as_mut() {
                c.on_commanded_motion(seg.start_mm, seg.end_mm);
            }
        }
    }
    clock.run_until(twin, plan, plan.duration_s(), observer, &mut compensator)?;
    // The twin ends exactly at the plan's end, ready for what follows.
    clock.finish_at(twin, plan, plan.duration_s(), observer)?;
    Ok(())
}

/// A shorter borrow of an optional controller (for a call that does not keep it).
/// `Option::as_deref_mut` does not do: it keeps the trait object's lifetime, which `&mut` makes
/// invariant, so the second call in a loop would conflict with the first.
pub fn reborrow<'s>(c: &'s mut Option<&mut dyn Controller>) -> Option<&'s mut dyn Controller> {
    match c {
        Some(c) => Some(&mut **c),
        None => None,
    }
}

/// The twin's present readings, given to `controller` (if any) as it takes over: the readings,
/// and the spindle and axes at rest up to now (a no-op for a controller that already followed the
/// machine up to now). With [`step`], the only path by which readings leave the twin for the
/// controller.
pub fn hand_over(twin: &Twin, controller: Option<&mut dyn Controller>) -> SensorReadings {
    let readings = twin.sensor_readings();
    if let Some(c) = controller {
        c.on_readings(readings.time_s, &readings.values_degc);
        c.on_spindle_speed(twin.time_s(), 0.0);
        c.on_axis_feeds(twin.time_s(), [0.0; 3]);
    }
    readings
}

/// Advances the twin by `dt_s` under `activity` and gives the new readings, the commanded
/// spindle speed and the axes' commanded mean speeds of the step to `controller` (if any), as a controller logging its sensors sees
/// them; returns the readings.
///
/// # Errors
/// The twin's (a bad step or activity).
pub fn step(
    twin: &mut Twin,
    dt_s: f64,
    activity: &Activity,
    controller: Option<&mut dyn Controller>,
) -> Result<SensorReadings, TwinError> {
    twin.advance(dt_s, activity)?;
    let readings = twin.sensor_readings();
    if let Some(c) = controller {
        c.on_readings(readings.time_s, &readings.values_degc);
        c.on_spindle_speed(twin.time_s(), activity.spindle_rpm);
        c.on_axis_feeds(twin.time_s(), activity.axis_speed_mm_per_min.map(f64::abs));
    }
    Ok(readings)
}

/// Keeps the thermal clock in step with plan time.
///
/// The thermal network advances in whole thermal steps only: a sample taken between two step
/// boundaries sees the state of the last boundary (temperatures move by millikelvin within a
/// 1 s step, µm-level errors need minutes). Why: stepping the network to every 1 ms
/// interpolation sample cost one 39-node solve per sample — half of a long run's time — for no
/// physical gain. Only the end of the plan takes a partial step, so the twin's time is exact
/// for what follows.
struct Clock {
    /// Plan time of the twin's thermal state, s.
    plan_t_s: f64,
    /// Twin time at plan time 0, s.
    twin_t0_s: f64,
    step_s: f64,
    readings: SensorReadings,
    last_motion_segment: Option<usize>,
    /// Interval of [`Observer::on_motion_sample`] calls, s of plan time (None: no calls).
    motion_every_s: Option<f64>,
    /// Index of the next motion sample (its plan time is index × interval).
    next_motion_sample: u64,
}

impl Clock {
    /// Advances the twin in whole thermal steps while a step ends at or before `t_s`.
    fn run_until(
        &mut self,
        twin: &mut Twin,
        plan: &Plan,
        t_s: f64,
        observer: &mut dyn Observer,
        controller: &mut Option<&mut dyn Controller>,
    ) -> Result<(), SimError> {
        while self.plan_t_s + self.step_s <= t_s + 1e-9 {
            self.advance(twin, plan, self.step_s, observer, controller)?;
        }
        Ok(())
    }

    /// Advances the twin by a last partial step so that its time equals plan time `t_s`.
    fn finish_at(
        &mut self,
        twin: &mut Twin,
        plan: &Plan,
        t_s: f64,
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        let dt = t_s - self.plan_t_s;
        if dt > 1e-12 {
            let activity = activity_over(plan, self.plan_t_s, t_s);
            twin.advance(dt, &activity)?;
            self.plan_t_s = t_s;
        }
        self.emit_motion_samples(plan, t_s, observer);
        Ok(())
    }

    /// One step of `dt_s` under the plan's activity; new readings at whole steps.
    fn advance(
        &mut self,
        twin: &mut Twin,
        plan: &Plan,
        dt_s: f64,
        observer: &mut dyn Observer,
        controller: &mut Option<&mut dyn Controller>,
    ) -> Result<(), SimError> {
        let activity = activity_over(plan, self.plan_t_s, self.plan_t_s + dt_s);
        self.readings = step(twin, dt_s, &activity, reborrow(controller))?;
        self.plan_t_s += dt_s;
        observer.on_thermal_step(twin.time_s(), &self.readings);
        observer.on_node_temps(twin.time_s(), twin.node_temps_degc());
        self.emit_motion_samples(plan, self.plan_t_s, observer);
        Ok(())
    }

    /// Emits the motion samples due up to plan time `t_s` (inclusive).
    fn emit_motion_samples(&mut self, plan: &Plan, t_s: f64, observer: &mut dyn Observer) {
        let Some(every_s) = self.motion_every_s else {
            return;
        };
        loop {
            let t = self.next_motion_sample as f64 * every_s;
            if t > t_s + 1e-9 || t > plan.duration_s() + 1e-9 {
                break;
            }
            observer.on_motion_sample(self.twin_t0_s + t, plan.position_at(t));
            self.next_motion_sample += 1;
        }
    }

    /// Tells the twin the direction of the last motion (reversal error) before a dwell point.
    fn note_direction(&mut self, twin: &mut Twin, plan: &Plan, _dwell_segment: usize) {
        if let Some(si) = self.last_motion_segment {
            let s = &plan.segments()[si];
            twin.note_motion([0, 1, 2].map(|a| s.end_mm[a] - s.start_mm[a]));
        }
    }
}

/// Mean spindle speed, mean |axis speed| and mean position over [t0, t1] (exact per axis, from
/// the planner), the spindle speed sampled at the interval's middle.
pub fn activity_over(plan: &Plan, t0_s: f64, t1_s: f64) -> Activity {
    let a = plan.axis_activity(t0_s, t1_s);
    Activity {
        spindle_rpm: plan.spindle_rpm_at(0.5 * (t0_s + t1_s)),
        axis_pos_mm: a.mean_pos_mm,
        axis_speed_mm_per_min: a.mean_abs_vel_mm_per_min,
        coolant: false,
    }
}

#[allow(clippy::too_many_arguments)]
fn measure(
    twin: &mut Twin,
    time_s: f64,
    readings: &SensorReadings,
    compensator: &mut Option<&mut dyn Controller>,
    observer: &mut dyn Observer,
    index: usize,
    line: usize,
    p_mm: [f64; 3],
    at_dwell: bool,
    report_thermal_part: bool,
) -> Result<(), SimError> {
    let approach = twin.draw_approach_mm();
    let before = twin.tool_error_mm(p_mm, p_mm, approach);
    let thermal_part_um = report_thermal_part.then(|| {
        let cold = twin.tool_error_at_ref_temp_mm(p_mm, p_mm, approach);
        [0, 1, 2].map(|a| (before[a] - cold[a]) * 1e3)
    });
    let (q, after) = match compensator {
        Some(c) => {
            // The readings given to the controller last are `readings` (`Clock::readings`).
            let q = c.axis_command_mm(p_mm);
            let correction_mm =
                ((q[0] - p_mm[0]).powi(2) + (q[1] - p_mm[1]).powi(2) + (q[2] - p_mm[2]).powi(2))
                    .sqrt();
            // Like a CNC's limit on compensation values: the machine does not follow a command
            // far from the programmed point (or not a number at all).
            if correction_mm.is_nan() || correction_mm > MAX_CORRECTION_MM {
                return Err(SimError::Compensation {
                    line,
                    time_s,
                    p_mm,
                    correction_mm,
                });
            }
            (Some(q), Some(twin.tool_error_mm(p_mm, q, approach)))
        }
        None => (None, None),
    };
    let point = PointRecord {
        index,
        time_s,
        line,
        commanded_mm: p_mm,
        error_before_um: [before.x * 1e3, before.y * 1e3, before.z * 1e3],
        thermal_part_um,
        compensated_command_mm: q,
        error_after_um: after.map(|e| [e.x * 1e3, e.y * 1e3, e.z * 1e3]),
        at_dwell,
    };
    observer.on_point(&point, readings);
    Ok(())
}

#[cfg(test)]
mod tests;
