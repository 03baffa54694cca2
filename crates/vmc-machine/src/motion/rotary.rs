//! Rotary axes A, B, C in the planner: their limits and how they cap a segment's profile.
//!
//! A segment's rotary angles move in step with its path (LinuxCNC's rule, the one the
//! interpreter's feeds follow, see [`vmc_gcode::interp::rotary_only`]):
//! - **X, Y or Z moves** (line or arc of length `L` mm): the profile runs along the XYZ path
//!   at the feed (mm/min); each angle changes linearly with the path, `dθᵢ/ds = Δθᵢ / L`, so
//!   the path speed and acceleration are also capped by `ωᵢ · L / |Δθᵢ|` and
//!   `αᵢ · L / |Δθᵢ|` (ωᵢ, αᵢ: the axis's speed and acceleration limits).
//! - **Only rotary axes move**: the profile runs along the angle `Θ = √(ΔA² + ΔB² + ΔC²)` in
//!   degrees at the feed in deg/min (a rapid at the axes' limits), capped by `ωᵢ · Θ / |Δθᵢ|`
//!   and `αᵢ · Θ / |Δθᵢ|`; X, Y, Z stay. The segment's [`super::SpeedProfile`] then measures
//!   degrees, not mm.
//!
//! So no rotary axis exceeds its own speed or acceleration. A machine without rotary axes
//! ([`RotaryLimits::default`]) refuses any move that turns one; on moves that do not turn them
//! the planner does exactly what it does without this module.
//!
//! Units: degrees, deg/s, deg/s².

use serde::{Deserialize, Serialize};

use super::MotionError;

/// Speed and acceleration limits of one rotary axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotaryAxisLimits {
    /// Largest angular speed (deg/s), rapids included; no default (typical of a trunnion
    /// table: `180.0`, i.e. 30 rev/min).
    pub max_speed_deg_per_s: f64,
    /// Largest angular acceleration (deg/s²); no default (typical: `720.0`).
    pub max_accel_deg_per_s2: f64,
}

/// The rotary axes A, B, C a machine has, with their limits (`None`: no such axis).
/// Default: none (a 3-axis machine).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotaryLimits {
    /// A, B, C.
    pub axes: [Option<RotaryAxisLimits>; 3],
}

/// The axis letters, in index order.
pub const ROTARY_AXES: [char; 3] = ['A', 'B', 'C'];

impl RotaryLimits {
    /// Checks every limit given is positive and finite, naming the bad one.
    pub fn validate(&self) -> Result<(), MotionError> {
        for (i, axis) in self.axes.iter().enumerate() {
            let Some(l) = axis else { continue };
            for (name, value) in [
                ("max_speed_deg_per_s", l.max_speed_deg_per_s),
                ("max_accel_deg_per_s2", l.max_accel_deg_per_s2),
            ] {
                if !(value.is_finite() && value > 0.0) {
                    return Err(MotionError::InvalidLimit {
                        field: format!("rotary.{}.{name}", ROTARY_AXES[i]),
                        value,
                        reason: "must be positive and finite",
                    });
                }
            }
        }
        Ok(())
    }

    /// Refuses a move from `start_deg` to `end_deg` that turns an axis the machine lacks, or
    /// has a non-finite angle.
    pub(super) fn check_move(
        &self,
        line: usize,
        start_deg: [f64; 3],
        end_deg: [f64; 3],
    ) -> Result<(), MotionError> {
        for i in 0..3 {
            if !end_deg[i].is_finite() {
                return Err(MotionError::NonFinitePosition {
                    line,
                    what: "rotary end angle",
                    pos_mm: end_deg,
                });
            }
            if end_deg[i] != start_deg[i] && self.axes[i].is_none() {
                return Err(MotionError::NoRotaryAxis {
                    line,
                    axis: ROTARY_AXES[i],
                });
            }
        }
        Ok(())
    }

    /// Caps `(speed, accel)` of a path of `length` (mm, or degrees for a rotary-only move)
    /// along which the angles change by `delta_deg`: no axis beyond its limits. Axes that do
    /// not turn leave the caps as they are.
    pub(super) fn cap(
        &self,
        length: f64,
        delta_deg: [f64; 3],
        (mut speed, mut accel): (f64, f64),
    ) -> (f64, f64) {
        if length <= 0.0 {
            return (speed, accel);
        }
        for (axis, d) in self.axes.iter().zip(delta_deg) {
            if let (Some(l), true) = (axis, d != 0.0) {
                let per_unit = d.abs() / length;
                speed = speed.min(l.max_speed_deg_per_s / per_unit);
                accel = accel.min(l.max_accel_deg_per_s2 / per_unit);
            }
        }
        (speed, accel)
    }
}

/// Length of the angle vector `√(ΔA² + ΔB² + ΔC²)`, degrees.
pub(super) fn angle_deg(start_deg: [f64; 3], end_deg: [f64; 3]) -> f64 {
    (0..3)
        .map(|i| (end_deg[i] - start_deg[i]).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// `end − start`, degrees.
pub(super) fn delta_deg(start_deg: [f64; 3], end_deg: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| end_deg[i] - start_deg[i])
}
