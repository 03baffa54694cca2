//! The machine's kinematic limits of X, Y, Z as the machine description gives them.

use serde::{Deserialize, Serialize};

use super::MotionError;

/// Kinematic limits of the machine's axes, as given in the machine description.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionLimits {
    /// Rapid (G0) rate per axis X, Y, Z (mm/min); typical `[30000.0; 3]`.
    pub rapid_mm_per_min: [f64; 3],
    /// Largest programmable path feed (mm/min); typical `10000.0`. Higher F words are capped.
    pub max_feed_mm_per_min: f64,
    /// Maximum acceleration per axis X, Y, Z (mm/s²); typical `[2000.0; 3]`.
    pub max_accel_mm_per_s2: [f64; 3],
    /// Duration of an M6 tool change (s); optional, default `5.0` (a typical VMC carousel).
    #[serde(default = "default_tool_change_s")]
    pub tool_change_s: f64,
    /// Highest spindle speed (rpm); an S word above it is an error. Optional, default
    /// `12000.0` (a typical BT40 VMC spindle).
    #[serde(default = "default_max_spindle_rpm")]
    pub max_spindle_rpm: f64,
}

fn default_tool_change_s() -> f64 {
    5.0
}

fn default_max_spindle_rpm() -> f64 {
    12_000.0
}

impl Default for MotionLimits {
    /// A mid-size VMC: 30 m/min rapids, 10 m/min max feed, 2 m/s² on every axis, 5 s tool change.
    fn default() -> Self {
        Self {
            rapid_mm_per_min: [30_000.0; 3],
            max_feed_mm_per_min: 10_000.0,
            max_accel_mm_per_s2: [2_000.0; 3],
            tool_change_s: default_tool_change_s(),
            max_spindle_rpm: default_max_spindle_rpm(),
        }
    }
}

impl MotionLimits {
    /// Checks every field is finite and positive (`tool_change_s` may be 0), naming the bad one.
    pub fn validate(&self) -> Result<(), MotionError> {
        fn positive(field: String, value: f64) -> Result<(), MotionError> {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(MotionError::InvalidLimit {
                    field,
                    value,
                    reason: "must be positive and finite",
                })
            }
        }
        for (i, &v) in self.rapid_mm_per_min.iter().enumerate() {
            positive(format!("rapid_mm_per_min[{i}]"), v)?;
        }
        positive("max_feed_mm_per_min".into(), self.max_feed_mm_per_min)?;
        positive("max_spindle_rpm".into(), self.max_spindle_rpm)?;
        for (i, &v) in self.max_accel_mm_per_s2.iter().enumerate() {
            positive(format!("max_accel_mm_per_s2[{i}]"), v)?;
        }
        if !(self.tool_change_s.is_finite() && self.tool_change_s >= 0.0) {
            return Err(MotionError::InvalidLimit {
                field: "tool_change_s".into(),
                value: self.tool_change_s,
                reason: "must be non-negative and finite",
            });
        }
        Ok(())
    }

    /// Rapid rates per axis in mm/s.
    pub(super) fn rapid_mm_per_s(&self) -> [f64; 3] {
        self.rapid_mm_per_min.map(|v| v / 60.0)
    }

    /// Smallest axis acceleration (mm/s²).
    pub(super) fn min_accel_mm_per_s2(&self) -> f64 {
        self.max_accel_mm_per_s2
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }
}
