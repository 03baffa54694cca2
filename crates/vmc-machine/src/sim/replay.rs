//! Replay of a logged trajectory: the servo samples of a real controller (commanded axis
//! positions, optionally the corrections it added and the spindle speed) played on the twin,
//! with the thermal network evolving as in [`super::execute`].
//!
//! Model: between two samples the axes move on a straight line at constant speed and the
//! spindle keeps the speed logged at the first sample (zero-order hold). Time advances in whole
//! thermal steps as in a run; a step's heat load is the time average over the step of the
//! spindle speed, of each axis's |speed| and of its position, integrated exactly over that
//! piecewise-linear motion. A sample sees the thermal state (and the held readings) of the last
//! step boundary at or before it, as a run's interpolation-cycle points do.
//!
//! At each measured sample the uncompensated machine is commanded `q = p` (the logged position)
//! and the compensated one either `q = p + c` (the correction `c` the controller logged) or
//! `q = controller(p)` (a compensator in the twin's own loop); both in the same thermal state
//! with the same random approach error (see [`super::measure`]). Samples are pushed one at a
//! time, so a log of millions of samples never needs to be held.
//!
//! Units: s, mm, rpm; errors in µm in the [`PointRecord`]s.

use crate::sensors::SensorReadings;
use crate::thermal::Activity;
use crate::twin::Twin;

use super::{hand_over, measure, reborrow, step, Controller, Observer, SimConfig, SimError};

/// One servo sample of a log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoggedSample {
    /// Time of the sample in the log, s (strictly increasing from sample to sample).
    pub time_s: f64,
    /// Line of the log file the sample comes from (reported as the point's line).
    pub line: usize,
    /// Commanded axis positions before compensation, mm.
    pub commanded_mm: [f64; 3],
    /// Correction the controller added to the command (the drive followed
    /// `commanded_mm + correction_mm`), mm; None if the log has none.
    pub correction_mm: Option<[f64; 3]>,
    /// Commanded spindle speed, rpm (its sign, the direction, is ignored).
    pub spindle_rpm: f64,
}

/// A trajectory being replayed on a twin: push the samples in time order, then
/// [`Replay::finish`].
#[derive(Debug)]
pub struct Replay {
    cfg: SimConfig,
    /// Measure every `every`-th sample (the first one included).
    every: usize,
    /// Log time of the first sample, s (None before it).
    log_t0_s: Option<f64>,
    /// Twin time at the first sample, s.
    twin_t0_s: f64,
    /// Replay time (s since the first sample) of the thermal state's last step boundary.
    step_start_s: f64,
    /// Integrals over the current step so far.
    acc: StepIntegral,
    /// The previous sample: replay time, position, spindle speed.
    prev: Option<(f64, [f64; 3], f64)>,
    readings: SensorReadings,
    samples: usize,
    points: usize,
    /// Interval of [`Observer::on_motion_sample`] calls, s (None: no calls).
    motion_every_s: Option<f64>,
    next_motion_s: f64,
}

/// Time integrals of the heat-load inputs over part of a thermal step.
#[derive(Debug, Clone, Copy, Default)]
struct StepIntegral {
    pos_mm_s: [f64; 3],
    abs_vel_mm_per_min_s: [f64; 3],
    rpm_s: f64,
}

/// Logged corrections as the compensated command: `q = p + c`. It learns nothing and predicts
/// nothing; it only replays what the controller did.
struct LoggedCorrection([f64; 3]);

impl Controller for LoggedCorrection {
    fn on_readings(&mut self, _time_s: f64, _values_degc: &[f64]) {}
    fn on_spindle_speed(&mut self, _time_s: f64, _rpm: f64) {}
    fn on_axis_feeds(&mut self, _time_s: f64, _feeds_mm_per_min: [f64; 3]) {}
    fn axis_command_mm(&mut self, p_mm: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|k| p_mm[k] + self.0[k])
    }
}

impl Replay {
    /// Starts a replay on `twin` at its present time and thermal state, measuring every
    /// `every`-th sample (0 counts as 1) with `cfg`'s thermal step and thermal-part setting;
    /// `controller` (a compensator in the loop, if any) takes over the twin's readings.
    pub fn start(
        twin: &Twin,
        cfg: &SimConfig,
        every: usize,
        controller: Option<&mut dyn Controller>,
        observer: &dyn Observer,
    ) -> Self {
        Replay {
            cfg: *cfg,
            every: every.max(1),
            log_t0_s: None,
            twin_t0_s: twin.time_s(),
            step_start_s: 0.0,
            acc: StepIntegral::default(),
            prev: None,
            readings: hand_over(twin, controller),
            samples: 0,
            points: 0,
            motion_every_s: observer
                .motion_sample_interval_s()
                .filter(|dt| *dt > 0.0 && dt.is_finite()),
            next_motion_s: 0.0,
        }
    }

    /// Samples pushed so far.
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Measurement points taken so far.
    pub fn points(&self) -> usize {
        self.points
    }

    /// Plays the motion up to `sample`, then measures at it if it is due. A sample with logged
    /// corrections is measured with them as the compensated command; otherwise `controller`
    /// (if any) computes the command.
    ///
    /// # Errors
    /// The twin's (a bad step), a correction beyond [`super::MAX_CORRECTION_MM`] or not a
    /// number, a sample not later than the previous one.
    pub fn push(
        &mut self,
        twin: &mut Twin,
        sample: &LoggedSample,
        mut controller: Option<&mut dyn Controller>,
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        let log_t0 = *self.log_t0_s.get_or_insert(sample.time_s);
        let t_s = sample.time_s - log_t0;
        let p = sample.commanded_mm;
        let rpm = sample.spindle_rpm.abs();
        if let Some((ta, pa, rpm_a)) = self.prev {
            let dt = t_s - ta;
            if dt.is_nan() || dt <= 0.0 {
                return Err(SimError::TimeNotIncreasing {
                    line: sample.line,
                    time_s: sample.time_s,
                    previous_s: ta + log_t0,
                });
            }
            let vel_mm_s = [0, 1, 2].map(|k| (p[k] - pa[k]) / dt);
            let seg = Segment {
                ta,
                pa,
                vel_mm_s,
                rpm: rpm_a,
            };
            while self.step_start_s + self.cfg.thermal_step_s() <= t_s + 1e-9 {
                let end = self.step_start_s + self.cfg.thermal_step_s();
                self.acc.add(&seg, ta.max(self.step_start_s), end);
                self.advance(twin, self.cfg.thermal_step_s(), observer, &mut controller)?;
            }
            self.acc.add(&seg, ta.max(self.step_start_s), t_s);
            self.emit_motion_samples(&seg, t_s, observer);
            // The direction each axis last moved in (reversal error), as the planner's
            // velocity tells a run.
            twin.note_motion(vel_mm_s);
            if let Some(c) = controller.as_mut() {
                c.on_commanded_motion(pa, p);
            }
        } else if self.motion_every_s.is_some() {
            observer.on_motion_sample(self.twin_t0_s, p);
            self.next_motion_s = self.motion_every_s.unwrap_or(f64::INFINITY);
        }
        if self.samples.is_multiple_of(self.every) {
            let mut logged = sample.correction_mm.map(LoggedCorrection);
            let mut ctrl: Option<&mut dyn Controller> = match logged.as_mut() {
                Some(l) => Some(l),
                None => reborrow(&mut controller),
            };
            measure(
                twin,
                self.twin_t0_s + t_s,
                &self.readings,
                &mut ctrl,
                observer,
                self.points,
                sample.line,
                p,
                false,
                self.cfg.report_thermal_part,
            )?;
            self.points += 1;
        }
        self.prev = Some((t_s, p, rpm));
        self.samples += 1;
        Ok(())
    }

    /// Ends the replay: the twin advances by the last partial step to the last sample's time.
    ///
    /// # Errors
    /// The twin's (a bad step).
    pub fn finish(mut self, twin: &mut Twin) -> Result<(), SimError> {
        let Some((t_end, _, _)) = self.prev else {
            return Ok(());
        };
        let dt = t_end - self.step_start_s;
        if dt > 1e-12 {
            let activity = self.acc.activity(dt);
            twin.advance(dt, &activity)?;
            self.step_start_s = t_end;
        }
        Ok(())
    }

    /// One whole thermal step of `dt_s` under the integrated load; new readings.
    fn advance(
        &mut self,
        twin: &mut Twin,
        dt_s: f64,
        observer: &mut dyn Observer,
        controller: &mut Option<&mut dyn Controller>,
    ) -> Result<(), SimError> {
        let activity = self.acc.activity(dt_s);
        self.readings = step(twin, dt_s, &activity, reborrow(controller))?;
        self.acc = StepIntegral::default();
        self.step_start_s += dt_s;
        observer.on_thermal_step(twin.time_s(), &self.readings);
        observer.on_node_temps(twin.time_s(), twin.node_temps_degc());
        Ok(())
    }

    /// The commanded positions the observer wants, up to replay time `t_s`, on `seg`.
    fn emit_motion_samples(&mut self, seg: &Segment, t_s: f64, observer: &mut dyn Observer) {
        let Some(every_s) = self.motion_every_s else {
            return;
        };
        while self.next_motion_s <= t_s + 1e-9 {
            let t = self.next_motion_s;
            observer.on_motion_sample(self.twin_t0_s + t, seg.position_mm(t));
            self.next_motion_s += every_s;
        }
    }
}

/// The motion between two samples: from `pa` at replay time `ta` at constant velocity.
struct Segment {
    ta: f64,
    pa: [f64; 3],
    vel_mm_s: [f64; 3],
    rpm: f64,
}

impl Segment {
    fn position_mm(&self, t_s: f64) -> [f64; 3] {
        [0, 1, 2].map(|k| self.pa[k] + self.vel_mm_s[k] * (t_s - self.ta))
    }
}

impl StepIntegral {
    /// Adds `seg` over replay times [t0, t1] (nothing if empty).
    fn add(&mut self, seg: &Segment, t0_s: f64, t1_s: f64) {
        let dt = t1_s - t0_s;
        if dt <= 0.0 {
            return;
        }
        let (p0, p1) = (seg.position_mm(t0_s), seg.position_mm(t1_s));
        for k in 0..3 {
            self.pos_mm_s[k] += 0.5 * (p0[k] + p1[k]) * dt;
            self.abs_vel_mm_per_min_s[k] += seg.vel_mm_s[k].abs() * 60.0 * dt;
        }
        self.rpm_s += seg.rpm * dt;
    }

    /// The mean load over a step of `dt_s`.
    fn activity(&self, dt_s: f64) -> Activity {
        Activity {
            spindle_rpm: self.rpm_s / dt_s,
            axis_pos_mm: self.pos_mm_s.map(|v| v / dt_s),
            axis_speed_mm_per_min: self.abs_vel_mm_per_min_s.map(|v| v / dt_s),
            coolant: false,
        }
    }
}

#[cfg(test)]
#[path = "replay_tests.rs"]
mod tests;
