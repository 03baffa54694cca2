//! Motion planner: canonical moves (from [`vmc_gcode::interp`]) → timed segments of machine motion.
//!
//! # Model
//! Every motion is an **exact stop** (like G61): each segment starts and ends at rest, with a
//! trapezoidal speed profile along its path length (triangular when the path is too short to
//! reach the speed cap; see [`SpeedProfile`]). This is the simplest honest model for measurement
//! programs (which stop at every point anyway) and makes every segment independent. There is no
//! look-ahead blending (G64), no jerk limit and no servo lag: the planned position *is* the
//! commanded setpoint.
//!
//! Speed caps (all speeds converted to mm/s internally):
//! - **Rapid (G0)**, straight line with unit direction `u`: path speed
//!   `v = min_i rapid_i / |u_i|`, so no axis exceeds its own rapid rate.
//! - **Feed (G1)**: `v = min(F, max_feed, min_i rapid_i / |u_i|)`; `F ≤ 0` is an error.
//! - **Lines**, acceleration: `a = min_i accel_i / |u_i|` (direction cosines), so no axis exceeds
//!   its own acceleration.
//! - **Arcs (G2/G3)**, with `a_min` the smallest axis acceleration: the tangential acceleration
//!   and the centripetal acceleration `v_plane² / r` are each held to `a_min / √2`, so their
//!   vector sum — and hence every axis's acceleration — stays within `a_min`. Speed is also
//!   capped by `min(F, max_feed)`, by the in-plane axes' rapid rates and, for a helix, by the
//!   axis rapid rate along the helix.
//!
//! Non-motion actions: **dwell (G4)** and **tool change (M6)** are zero-motion segments
//! (a tool change lasts [`MotionLimits::tool_change_s`]; the tool-change travel itself is not
//! modelled). **Spindle** commands take no time (no spindle run-up is modelled): they change the
//! spindle state attached to every following segment, so the thermal model sees the spindle
//! load over time. **Program end (M2/M30)** ends the plan; the spindle is off after it and moves
//! after it are ignored. A zero-length move is kept (its line stays in the plan) as a
//! zero-duration segment.
//!
//! Rotary axes A, B, C (see `rotary`): [`plan_with_rotary`] takes their limits; their angles
//! move in step with the XYZ path, or alone along the angle. [`plan`] is the 3-axis machine:
//! a move that turns a rotary axis is an error.
//!
//! Units: positions mm (machine coordinates), times s, speeds mm/s inside segments (limits and
//! activity reports use mm/min as G-code does), accelerations mm/s², angles rad; rotary axis
//! angles in degrees.

mod geometry;
mod limits;
mod profile;
mod rotary;
#[cfg(test)]
mod rotary_tests;
mod sampling;
mod travel;
pub use travel::travel_message;

#[cfg(test)]
mod limit_tests;
#[cfg(test)]
mod tests;

pub use geometry::{plane_axes, ArcGeometry, Geometry, MIN_ARC_RADIUS_MM};
pub use limits::MotionLimits;
pub use profile::SpeedProfile;
pub use rotary::{RotaryAxisLimits, RotaryLimits, ROTARY_AXES};
pub use sampling::{AxisActivity, DwellPoint, Sample, Samples, DEFAULT_INTERPOLATION_CYCLE_S};
pub use travel::{check_rotary_travel, check_travel, segment_travel_violations};

use thiserror::Error;

use vmc_gcode::interp::{CanonKind, CanonMove, LengthUnit, SpindleDir};

/// Errors of the motion planner.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MotionError {
    /// A field of [`MotionLimits`] is out of range.
    #[error("motion limit `{field}` = {value} is invalid: {reason}")]
    InvalidLimit {
        /// Field name, with the axis index for arrays (e.g. `rapid_mm_per_min[1]`).
        field: String,
        /// Offending value.
        value: f64,
        /// What the value must satisfy.
        reason: &'static str,
    },
    /// A feed move (G1/G2/G3) with a feed rate that is not positive and finite.
    #[error("line {line}: feed rate {feed_mm_per_min} mm/min must be positive")]
    NonPositiveFeed {
        /// Source line.
        line: usize,
        /// Programmed feed (mm/min).
        feed_mm_per_min: f64,
    },
    /// A dwell with a negative or non-finite duration.
    #[error("line {line}: dwell of {duration_s} s must be non-negative")]
    InvalidDwell {
        /// Source line.
        line: usize,
        /// Programmed dwell (s).
        duration_s: f64,
    },
    /// A spindle speed that is negative or non-finite.
    #[error("line {line}: spindle speed {rpm} rpm must be non-negative")]
    InvalidSpindleSpeed {
        /// Source line.
        line: usize,
        /// Programmed speed (rpm).
        rpm: f64,
    },
    /// A position (end point, centre or start) with a NaN or infinite coordinate.
    #[error("line {line}: {what} has a non-finite coordinate {pos_mm:?} mm")]
    NonFinitePosition {
        /// Source line (0 for the plan's start position).
        line: usize,
        /// Which position (`"end point"`, `"arc centre"`, `"start position"`).
        what: &'static str,
        /// The offending position (mm).
        pos_mm: [f64; 3],
    },
    /// An arc whose start or end lies on its centre.
    #[error("line {line}: arc radius below {min_radius_mm} mm")]
    DegenerateArc {
        /// Source line.
        line: usize,
        /// Smallest radius accepted (mm).
        min_radius_mm: f64,
    },
    /// A move turns a rotary axis the machine does not have.
    #[error("line {line}: the move turns the {axis} axis, which the machine does not have")]
    NoRotaryAxis {
        /// Source line.
        line: usize,
        /// `'A'`, `'B'` or `'C'`.
        axis: char,
    },
    /// An interpolation cycle that is not positive and finite.
    #[error("sampling period {dt_s} s must be positive and finite")]
    InvalidSamplePeriod {
        /// Requested period (s).
        dt_s: f64,
    },
    /// A spindle speed above the machine's maximum.
    #[error("line {line}: spindle speed {rpm} rpm is above the machine's maximum of {max_rpm} rpm (motion.max_spindle_rpm)")]
    SpindleSpeedAboveMax {
        /// Source line.
        line: usize,
        /// Programmed speed (rpm).
        rpm: f64,
        /// The machine's maximum (rpm).
        max_rpm: f64,
    },
    /// The program's machine time exceeds [`MAX_PLAN_DURATION_S`] (huge dwells, absurdly slow
    /// feeds or turn counts): refused rather than simulated for days.
    #[error("line {line}: the program reaches {duration_s:.0} s of machine time, above the limit of {max_s:.0} s ({max_days} days)", max_days = max_s / 86400.0)]
    ProgramTooLong {
        /// Source line of the move that crosses the limit.
        line: usize,
        /// Machine time at the end of that move (s).
        duration_s: f64,
        /// The limit (s).
        max_s: f64,
    },
    /// A travel range whose minimum is not below its maximum (or not finite).
    #[error("travel range of axis {axis} is invalid: [{min_mm}, {max_mm}] mm")]
    InvalidTravel {
        /// Axis letter.
        axis: char,
        /// Lower travel limit (mm).
        min_mm: f64,
        /// Upper travel limit (mm).
        max_mm: f64,
    },
    /// A move turns a rotary axis beyond its travel limits.
    #[error(
        "line {line}: rotary axis {axis} reaches {angle_deg}°, outside its travel [{min_deg}, {max_deg}]°"
    )]
    RotaryOutOfTravel {
        /// Source line of the offending move.
        line: usize,
        /// `'A'`, `'B'` or `'C'`.
        axis: char,
        /// The angle reached (degrees).
        angle_deg: f64,
        /// Lower travel limit (degrees).
        min_deg: f64,
        /// Upper travel limit (degrees).
        max_deg: f64,
    },
    /// A segment reaches outside an axis's travel.
    #[error("{}", travel_message(*.line, *.axis, [*.pos_mm, *.min_mm, *.max_mm], LengthUnit::Mm))]
    AxisOutOfTravel {
        /// Source line of the offending segment.
        line: usize,
        /// Axis letter (`'X'`, `'Y'`, `'Z'`).
        axis: char,
        /// The extreme position reached (mm).
        pos_mm: f64,
        /// Lower travel limit (mm).
        min_mm: f64,
        /// Upper travel limit (mm).
        max_mm: f64,
    },
}

/// Longest machine time a program may take (s): 7 days. Longer plans (a G4 of 10⁸ s, a feed
/// of 10⁻⁶ mm/min, 1000 turns of a slow helix) are refused with the line that crosses it, so
/// that no simulation of them can run for hours.
pub const MAX_PLAN_DURATION_S: f64 = 7.0 * 86_400.0;

/// What a segment does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SegmentKind {
    /// G0 straight-line rapid.
    Rapid,
    /// G1 straight feed move.
    Feed,
    /// G2/G3 arc or helix at feed.
    Arc,
    /// G4 dwell: no motion.
    Dwell,
    /// M6 tool change to `tool`: no modelled motion.
    ToolChange {
        /// Tool number loaded.
        tool: u32,
    },
}

/// One timed piece of the plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    /// Source line (1-based) of the canonical move.
    pub line: usize,
    /// What the segment does.
    pub kind: SegmentKind,
    /// Position at the segment's start (mm).
    pub start_mm: [f64; 3],
    /// Position at the segment's end (mm).
    pub end_mm: [f64; 3],
    /// Rotary axes A, B, C at the segment's start (degrees; 0 on a 3-axis machine).
    pub start_abc_deg: [f64; 3],
    /// Rotary axes A, B, C at the segment's end (degrees).
    pub end_abc_deg: [f64; 3],
    /// Time at which the segment starts, from the start of the plan (s).
    pub t_start_s: f64,
    /// Duration (s); 0 for a zero-length move.
    pub duration_s: f64,
    /// Path shape.
    pub geometry: Geometry,
    /// Speed along the path over time: along the XYZ path (mm), or along the rotary angle
    /// (degrees) for a move of the rotary axes alone.
    pub profile: SpeedProfile,
    /// Spindle direction in effect during the segment.
    pub spindle_dir: SpindleDir,
    /// Spindle speed in effect during the segment (rpm); 0 when the spindle is off.
    pub spindle_rpm: f64,
    /// A straight probe move (G38.2 … G38.5), planned as the feed move it is.
    pub probe: bool,
}

impl Segment {
    /// Time at which the segment ends (s).
    pub fn t_end_s(&self) -> f64 {
        self.t_start_s + self.duration_s
    }

    /// Position at local time `t_local_s` from the segment's start (clamped to the segment; mm).
    pub fn position_at_local(&self, t_local_s: f64) -> [f64; 3] {
        if t_local_s >= self.duration_s {
            return self.end_mm;
        }
        if t_local_s <= 0.0 {
            return self.start_mm;
        }
        self.geometry
            .point_at(self.start_mm, self.profile.distance_at(t_local_s))
    }

    /// Rotary angles A, B, C at local time `t_local_s` (degrees): they move in step with the
    /// profile's distance (clamped to the segment).
    pub fn abc_at_local(&self, t_local_s: f64) -> [f64; 3] {
        if self.start_abc_deg == self.end_abc_deg || t_local_s >= self.duration_s {
            return self.end_abc_deg;
        }
        if t_local_s <= 0.0 || self.profile.length_mm <= 0.0 {
            return self.start_abc_deg;
        }
        let f = self.profile.distance_at(t_local_s) / self.profile.length_mm;
        [0, 1, 2].map(|i| self.start_abc_deg[i] + f * (self.end_abc_deg[i] - self.start_abc_deg[i]))
    }

    /// Velocity at local time `t_local_s` (mm/s); zero outside the segment and at its ends.
    pub fn velocity_at_local(&self, t_local_s: f64) -> [f64; 3] {
        let speed = self.profile.speed_at(t_local_s);
        if speed == 0.0 {
            return [0.0; 3];
        }
        let tangent = self
            .geometry
            .tangent_at(self.profile.distance_at(t_local_s));
        tangent.map(|c| c * speed)
    }
}

/// A timed motion plan: consecutive segments from `start_mm`, beginning at time 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    segments: Vec<Segment>,
    start_mm: [f64; 3],
    program_end_line: Option<usize>,
    end: PlanStart,
}

/// Where a plan starts: the machine at rest at a position, with the spindle running as the
/// previous plan left it (a program planned in pieces continues from each piece's
/// [`Plan::end_state`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanStart {
    /// Position, machine coordinates (mm).
    pub pos_mm: [f64; 3],
    /// Rotary axes A, B, C (degrees).
    pub abc_deg: [f64; 3],
    /// Spindle direction.
    pub spindle_dir: SpindleDir,
    /// Spindle speed (rpm); 0 when off.
    pub spindle_rpm: f64,
}

impl PlanStart {
    /// At rest at `pos_mm`, rotary axes at 0, spindle off.
    pub fn at_rest(pos_mm: [f64; 3]) -> Self {
        PlanStart {
            pos_mm,
            abc_deg: [0.0; 3],
            spindle_dir: SpindleDir::Off,
            spindle_rpm: 0.0,
        }
    }
}

/// Builds the timed plan of `moves`, starting at rest at `start_mm` (machine coordinates, mm),
/// on a machine without rotary axes (a move that turns A, B or C is an error).
pub fn plan(
    moves: &[CanonMove],
    start_mm: [f64; 3],
    limits: &MotionLimits,
) -> Result<Plan, MotionError> {
    plan_with_rotary(moves, start_mm, [0.0; 3], limits, &RotaryLimits::default())
}

/// Builds the timed plan of `moves` on a machine with the rotary axes of `rotary`, starting at
/// rest at `start_mm` (mm) with the rotary axes at `start_abc_deg` (degrees).
pub fn plan_with_rotary(
    moves: &[CanonMove],
    start_mm: [f64; 3],
    start_abc_deg: [f64; 3],
    limits: &MotionLimits,
    rotary: &RotaryLimits,
) -> Result<Plan, MotionError> {
    let start = PlanStart {
        abc_deg: start_abc_deg,
        ..PlanStart::at_rest(start_mm)
    };
    plan_from(moves, start, limits, rotary)
}

/// Builds the timed plan of `moves` from `start` (a position at rest and the spindle's state),
/// on a machine with the rotary axes of `rotary`.
pub fn plan_from(
    moves: &[CanonMove],
    start: PlanStart,
    limits: &MotionLimits,
    rotary: &RotaryLimits,
) -> Result<Plan, MotionError> {
    limits.validate()?;
    rotary.validate()?;
    let start_mm = start.pos_mm;
    check_finite(0, "start position", start_mm)?;
    check_finite(0, "start rotary angles", start.abc_deg)?;
    let mut builder = PlanBuilder {
        limits,
        rotary,
        abc_deg: start.abc_deg,
        pos_mm: start_mm,
        t_s: 0.0,
        spindle_dir: start.spindle_dir,
        spindle_rpm: start.spindle_rpm,
        segments: Vec::with_capacity(moves.len()),
    };
    let mut program_end_line = None;
    for mv in moves {
        let end = builder.apply(mv)?;
        if builder.t_s > MAX_PLAN_DURATION_S {
            return Err(MotionError::ProgramTooLong {
                line: mv.line,
                duration_s: builder.t_s,
                max_s: MAX_PLAN_DURATION_S,
            });
        }
        if end {
            program_end_line = Some(mv.line);
            break;
        }
    }
    let end = PlanStart {
        pos_mm: builder.pos_mm,
        abc_deg: builder.abc_deg,
        spindle_dir: builder.spindle_dir,
        spindle_rpm: builder.spindle_rpm,
    };
    Ok(Plan {
        segments: builder.segments,
        start_mm,
        program_end_line,
        end,
    })
}

fn check_finite(line: usize, what: &'static str, pos_mm: [f64; 3]) -> Result<(), MotionError> {
    if pos_mm.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(MotionError::NonFinitePosition { line, what, pos_mm })
    }
}

/// Running state while the plan is built.
struct PlanBuilder<'a> {
    limits: &'a MotionLimits,
    rotary: &'a RotaryLimits,
    /// Current A, B, C (degrees).
    abc_deg: [f64; 3],
    pos_mm: [f64; 3],
    t_s: f64,
    spindle_dir: SpindleDir,
    spindle_rpm: f64,
    segments: Vec<Segment>,
}

impl PlanBuilder<'_> {
    /// Applies one canonical move; returns true at program end.
    fn apply(&mut self, mv: &CanonMove) -> Result<bool, MotionError> {
        let line = mv.line;
        match mv.kind {
            CanonKind::Traverse {
                end_mm,
                end_abc_deg,
            } => {
                check_finite(line, "end point", end_mm)?;
                self.rotary.check_move(line, self.abc_deg, end_abc_deg)?;
                if self.turns_rotary_only(end_mm, end_abc_deg) {
                    self.push_rotary(line, SegmentKind::Rapid, end_mm, end_abc_deg, f64::INFINITY);
                    return Ok(false);
                }
                let geometry = Geometry::line(self.pos_mm, end_mm);
                let (speed, accel) = self.line_caps(&geometry, f64::INFINITY);
                let end = (end_mm, end_abc_deg);
                self.push(line, SegmentKind::Rapid, end, geometry, speed, accel);
            }
            // A probe move is planned as the feed it is, to where the machine's answer left the
            // axes (stand-alone, the interpreter takes it to the target, as LinuxCNC's `rs274`
            // does); the segment is marked as a probe move.
            CanonKind::Feed {
                end_mm,
                end_abc_deg,
                feed_mm_per_min,
            }
            | CanonKind::Probe {
                end_mm,
                end_abc_deg,
                feed_mm_per_min,
                ..
            } => {
                check_finite(line, "end point", end_mm)?;
                self.rotary.check_move(line, self.abc_deg, end_abc_deg)?;
                if self.turns_rotary_only(end_mm, end_abc_deg) {
                    if !(feed_mm_per_min.is_finite() && feed_mm_per_min > 0.0) {
                        return Err(MotionError::NonPositiveFeed {
                            line,
                            feed_mm_per_min,
                        });
                    }
                    // The feed is in deg/min here (see `rotary`).
                    let feed_deg_per_s = feed_mm_per_min / 60.0;
                    self.push_rotary(line, SegmentKind::Feed, end_mm, end_abc_deg, feed_deg_per_s);
                    return Ok(false);
                }
                let feed_mm_per_s = self.feed_mm_per_s(line, feed_mm_per_min)?;
                let geometry = Geometry::line(self.pos_mm, end_mm);
                let (speed, accel) = self.line_caps(&geometry, feed_mm_per_s);
                let end = (end_mm, end_abc_deg);
                self.push(line, SegmentKind::Feed, end, geometry, speed, accel);
                if let (CanonKind::Probe { .. }, Some(seg)) = (&mv.kind, self.segments.last_mut()) {
                    seg.probe = true;
                }
            }
            CanonKind::Arc {
                end_mm,
                end_abc_deg,
                center_mm,
                plane,
                clockwise,
                extra_turns,
                feed_mm_per_min,
            } => {
                check_finite(line, "end point", end_mm)?;
                check_finite(line, "arc centre", center_mm)?;
                self.rotary.check_move(line, self.abc_deg, end_abc_deg)?;
                let feed_mm_per_s = self.feed_mm_per_s(line, feed_mm_per_min)?;
                let arc = ArcGeometry::new(
                    self.pos_mm,
                    end_mm,
                    center_mm,
                    plane,
                    clockwise,
                    extra_turns,
                )
                .ok_or(MotionError::DegenerateArc {
                    line,
                    min_radius_mm: MIN_ARC_RADIUS_MM,
                })?;
                let (speed, accel) = self.arc_caps(&arc, feed_mm_per_s);
                self.push(
                    line,
                    SegmentKind::Arc,
                    (end_mm, end_abc_deg),
                    Geometry::Arc(arc),
                    speed,
                    accel,
                );
            }
            CanonKind::Dwell { duration_s } => {
                if !(duration_s.is_finite() && duration_s >= 0.0) {
                    return Err(MotionError::InvalidDwell { line, duration_s });
                }
                self.push_stationary(line, SegmentKind::Dwell, duration_s);
            }
            CanonKind::ToolChange { tool } => {
                let duration_s = self.limits.tool_change_s;
                self.push_stationary(line, SegmentKind::ToolChange { tool }, duration_s);
            }
            CanonKind::Spindle { dir, rpm } => {
                if !(rpm.is_finite() && rpm >= 0.0) {
                    return Err(MotionError::InvalidSpindleSpeed { line, rpm });
                }
                if rpm > self.limits.max_spindle_rpm {
                    return Err(MotionError::SpindleSpeedAboveMax {
                        line,
                        rpm,
                        max_rpm: self.limits.max_spindle_rpm,
                    });
                }
                self.spindle_dir = dir;
                self.spindle_rpm = if dir == SpindleDir::Off { 0.0 } else { rpm };
            }
            // Orientation: the spindle stops (its time is not modelled).
            CanonKind::SpindleOrient { .. } => {
                self.spindle_dir = SpindleDir::Off;
                self.spindle_rpm = 0.0;
            }
            // Messages, coolant and operator pauses take no machine time here.
            CanonKind::Message(_)
            | CanonKind::Coolant { .. }
            | CanonKind::Pause(_)
            | CanonKind::Io { .. } => {}
            CanonKind::ProgramEnd => {
                self.spindle_dir = SpindleDir::Off;
                self.spindle_rpm = 0.0;
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// Programmed feed in mm/s, capped by the machine's max feed; errors if not positive.
    fn feed_mm_per_s(&self, line: usize, feed_mm_per_min: f64) -> Result<f64, MotionError> {
        if !(feed_mm_per_min.is_finite() && feed_mm_per_min > 0.0) {
            return Err(MotionError::NonPositiveFeed {
                line,
                feed_mm_per_min,
            });
        }
        Ok(feed_mm_per_min.min(self.limits.max_feed_mm_per_min) / 60.0)
    }

    /// Path speed and acceleration caps of a straight line (mm/s, mm/s²), given the path speed
    /// requested (`∞` for a rapid).
    fn line_caps(&self, geometry: &Geometry, requested_mm_per_s: f64) -> (f64, f64) {
        let dir = match geometry {
            Geometry::Line { dir, .. } => *dir,
            _ => [0.0; 3],
        };
        let rapid = self.limits.rapid_mm_per_s();
        let mut speed = requested_mm_per_s;
        let mut accel = f64::INFINITY;
        for i in 0..3 {
            let cos = dir[i].abs();
            if cos > 0.0 {
                speed = speed.min(rapid[i] / cos);
                accel = accel.min(self.limits.max_accel_mm_per_s2[i] / cos);
            }
        }
        // A zero-length line has no direction: any finite caps give the zero-duration profile.
        if !accel.is_finite() {
            accel = self.limits.min_accel_mm_per_s2();
        }
        if !speed.is_finite() {
            speed = rapid[0];
        }
        (speed, accel)
    }

    /// Path speed and acceleration caps of an arc or helix (mm/s, mm/s²).
    fn arc_caps(&self, arc: &ArcGeometry, feed_mm_per_s: f64) -> (f64, f64) {
        let [iu, iv, iw] = plane_axes(arc.plane);
        let rapid = self.limits.rapid_mm_per_s();
        // Half the acceleration budget each way: |a_t e_t + a_c e_n| ≤ a_min (e_t ⟂ e_n).
        let a_budget = self.limits.min_accel_mm_per_s2() / std::f64::consts::SQRT_2;
        let turns_rad = arc.sweep_angle_rad.abs();
        let min_radius_mm = arc.radius_mm.min(arc.end_radius_mm);
        // In-plane share of the path speed (1 for a flat arc) and axis share (helix).
        let plane_share =
            (arc.radius_mm.max(arc.end_radius_mm) * turns_rad / arc.length_mm).min(1.0);
        let axis_share = arc.axis_travel_mm.abs() / arc.length_mm;
        let mut speed = feed_mm_per_s.min(rapid[iu]).min(rapid[iv]);
        if axis_share > 0.0 {
            speed = speed.min(rapid[iw] / axis_share);
        }
        if plane_share > 0.0 {
            speed = speed.min((a_budget * min_radius_mm).sqrt() / plane_share);
        }
        (speed, a_budget)
    }

    /// True if the move to (`end_mm`, `end_abc_deg`) turns rotary axes and leaves X, Y, Z
    /// (the interpreter's rule for its feed).
    fn turns_rotary_only(&self, end_mm: [f64; 3], end_abc_deg: [f64; 3]) -> bool {
        vmc_gcode::interp::rotary_only(self.pos_mm, end_mm, self.abc_deg, end_abc_deg)
    }

    /// A move of the rotary axes alone: its profile runs along the angle (degrees) at
    /// `requested_deg_per_s` (`∞`: a rapid), within every turning axis's limits.
    fn push_rotary(
        &mut self,
        line: usize,
        kind: SegmentKind,
        end_mm: [f64; 3],
        end_abc_deg: [f64; 3],
        requested_deg_per_s: f64,
    ) {
        let angle_deg = rotary::angle_deg(self.abc_deg, end_abc_deg);
        let delta = rotary::delta_deg(self.abc_deg, end_abc_deg);
        let (speed, accel) =
            self.rotary
                .cap(angle_deg, delta, (requested_deg_per_s, f64::INFINITY));
        let profile = SpeedProfile::new(angle_deg, speed, accel);
        let end = (end_mm, end_abc_deg);
        self.push_profile(line, kind, end, Geometry::Point, profile);
    }

    fn push(
        &mut self,
        line: usize,
        kind: SegmentKind,
        end: ([f64; 3], [f64; 3]),
        geometry: Geometry,
        speed_mm_per_s: f64,
        accel_mm_per_s2: f64,
    ) {
        let length_mm = geometry.length_mm();
        let (speed_mm_per_s, accel_mm_per_s2) = if end.1 == self.abc_deg {
            (speed_mm_per_s, accel_mm_per_s2)
        } else {
            let delta = rotary::delta_deg(self.abc_deg, end.1);
            self.rotary
                .cap(length_mm, delta, (speed_mm_per_s, accel_mm_per_s2))
        };
        let profile = SpeedProfile::new(length_mm, speed_mm_per_s, accel_mm_per_s2);
        self.push_profile(line, kind, end, geometry, profile);
    }

    /// Appends a segment to `(end_mm, end_abc_deg)` with its profile.
    fn push_profile(
        &mut self,
        line: usize,
        kind: SegmentKind,
        (end_mm, end_abc_deg): ([f64; 3], [f64; 3]),
        geometry: Geometry,
        profile: SpeedProfile,
    ) {
        let duration_s = profile.duration_s();
        self.segments.push(Segment {
            line,
            kind,
            start_mm: self.pos_mm,
            end_mm,
            start_abc_deg: self.abc_deg,
            end_abc_deg,
            t_start_s: self.t_s,
            duration_s,
            geometry,
            profile,
            spindle_dir: self.spindle_dir,
            spindle_rpm: self.spindle_rpm,
            probe: false,
        });
        self.pos_mm = end_mm;
        self.abc_deg = end_abc_deg;
        self.t_s += duration_s;
    }

    fn push_stationary(&mut self, line: usize, kind: SegmentKind, duration_s: f64) {
        self.segments.push(Segment {
            line,
            kind,
            start_mm: self.pos_mm,
            end_mm: self.pos_mm,
            start_abc_deg: self.abc_deg,
            end_abc_deg: self.abc_deg,
            t_start_s: self.t_s,
            duration_s,
            geometry: Geometry::Point,
            profile: SpeedProfile::stationary(),
            spindle_dir: self.spindle_dir,
            spindle_rpm: self.spindle_rpm,
            probe: false,
        });
        self.t_s += duration_s;
    }
}

impl Plan {
    /// The timed segments, in execution order.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// Position at time 0 (mm).
    pub fn start_mm(&self) -> [f64; 3] {
        self.start_mm
    }

    /// Position at the end of the plan (mm).
    pub fn end_mm(&self) -> [f64; 3] {
        self.segments.last().map_or(self.start_mm, |s| s.end_mm)
    }

    /// The state the plan leaves the machine in: at rest at its end, the spindle as the last
    /// move set it (where the next piece of a program planned in pieces starts).
    pub fn end_state(&self) -> PlanStart {
        self.end
    }

    /// Line of the M2/M30 that ended the plan, if the program had one.
    pub fn program_end_line(&self) -> Option<usize> {
        self.program_end_line
    }

    /// Total duration of the plan (s).
    pub fn duration_s(&self) -> f64 {
        self.segments.last().map_or(0.0, Segment::t_end_s)
    }
}
