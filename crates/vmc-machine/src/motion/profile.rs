//! Trapezoidal speed profile along a path of length `L`, starting and ending at rest.
//!
//! With path speed limit `v` (mm/s) and path acceleration `a` (mm/s²):
//! - trapezoid when `L ≥ v²/a`: accelerate for `t_a = v/a` (covering `v²/(2a)`), cruise for
//!   `t_c = (L − v²/a)/v`, decelerate for `t_a`; duration `T = 2·t_a + t_c`;
//! - triangle otherwise: peak speed `v_p = √(L·a) < v`, `t_a = v_p/a`, `t_c = 0`, `T = 2·t_a`.
//!
//! Distance along the path: `s(t) = a·t²/2` while accelerating, `s(t_a) + v_p·(t − t_a)` while
//! cruising and `L − a·(T − t)²/2` while decelerating — the last form makes `s(T) = L` exactly.

/// A trapezoidal (or triangular) speed profile along one segment's path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedProfile {
    /// Path length (mm).
    pub length_mm: f64,
    /// Commanded path speed limit (mm/s): feed or rapid speed after all caps.
    pub v_limit_mm_per_s: f64,
    /// Peak path speed actually reached (mm/s): `v_limit` for a trapezoid, `√(L·a)` for a triangle.
    pub v_peak_mm_per_s: f64,
    /// Path acceleration used for both speeding up and slowing down (mm/s²).
    pub accel_mm_per_s2: f64,
    /// Duration of the acceleration phase, equal to the deceleration phase (s).
    pub t_accel_s: f64,
    /// Duration of the constant-speed phase (s); 0 for a triangle.
    pub t_cruise_s: f64,
}

impl SpeedProfile {
    /// Profile for a path of `length_mm` with the given speed cap and acceleration.
    ///
    /// `v_limit_mm_per_s` and `accel_mm_per_s2` must be positive and finite (the planner checks
    /// them); a zero (or non-positive) length gives the zero-duration profile, never NaN.
    pub fn new(length_mm: f64, v_limit_mm_per_s: f64, accel_mm_per_s2: f64) -> Self {
        if length_mm <= 0.0 {
            return Self {
                length_mm: 0.0,
                v_limit_mm_per_s,
                v_peak_mm_per_s: 0.0,
                accel_mm_per_s2,
                t_accel_s: 0.0,
                t_cruise_s: 0.0,
            };
        }
        let ramp_pair_mm = v_limit_mm_per_s * v_limit_mm_per_s / accel_mm_per_s2;
        let (v_peak, t_cruise) = if length_mm >= ramp_pair_mm {
            (
                v_limit_mm_per_s,
                (length_mm - ramp_pair_mm) / v_limit_mm_per_s,
            )
        } else {
            ((length_mm * accel_mm_per_s2).sqrt(), 0.0)
        };
        Self {
            length_mm,
            v_limit_mm_per_s,
            v_peak_mm_per_s: v_peak,
            accel_mm_per_s2,
            t_accel_s: v_peak / accel_mm_per_s2,
            t_cruise_s: t_cruise,
        }
    }

    /// The profile of a segment without motion (dwell, tool change): zero length and speed.
    pub fn stationary() -> Self {
        Self {
            length_mm: 0.0,
            v_limit_mm_per_s: 0.0,
            v_peak_mm_per_s: 0.0,
            accel_mm_per_s2: 0.0,
            t_accel_s: 0.0,
            t_cruise_s: 0.0,
        }
    }

    /// Time to travel the whole path (s).
    pub fn duration_s(&self) -> f64 {
        2.0 * self.t_accel_s + self.t_cruise_s
    }

    /// True when the path is too short to reach the speed limit (no cruise phase).
    pub fn is_triangular(&self) -> bool {
        self.length_mm > 0.0 && self.v_peak_mm_per_s < self.v_limit_mm_per_s
    }

    /// Phase boundaries in local time: `[0, end of acceleration, end of cruise, end]` (s).
    pub fn phase_times_s(&self) -> [f64; 4] {
        let t_a = self.t_accel_s;
        let t_ac = t_a + self.t_cruise_s;
        [0.0, t_a, t_ac, t_ac + t_a]
    }

    /// Distance travelled along the path at local time `t_s` (mm), clamped to `[0, L]`.
    pub fn distance_at(&self, t_s: f64) -> f64 {
        let total_s = self.duration_s();
        if t_s <= 0.0 || self.length_mm <= 0.0 {
            return 0.0;
        }
        if t_s >= total_s {
            return self.length_mm;
        }
        let a = self.accel_mm_per_s2;
        let t_a = self.t_accel_s;
        if t_s <= t_a {
            0.5 * a * t_s * t_s
        } else if t_s <= t_a + self.t_cruise_s {
            0.5 * a * t_a * t_a + self.v_peak_mm_per_s * (t_s - t_a)
        } else {
            let left_s = total_s - t_s;
            self.length_mm - 0.5 * a * left_s * left_s
        }
    }

    /// Path speed at local time `t_s` (mm/s); 0 outside the segment.
    pub fn speed_at(&self, t_s: f64) -> f64 {
        let total_s = self.duration_s();
        if t_s <= 0.0 || t_s >= total_s {
            return 0.0;
        }
        let t_a = self.t_accel_s;
        if t_s <= t_a {
            self.accel_mm_per_s2 * t_s
        } else if t_s <= t_a + self.t_cruise_s {
            self.v_peak_mm_per_s
        } else {
            self.accel_mm_per_s2 * (total_s - t_s)
        }
    }

    /// Local time at which the distance `s_mm` is reached (s); inverse of [`Self::distance_at`].
    pub fn time_at_distance(&self, s_mm: f64) -> f64 {
        if s_mm <= 0.0 || self.length_mm <= 0.0 {
            return 0.0;
        }
        let total_s = self.duration_s();
        if s_mm >= self.length_mm {
            return total_s;
        }
        let a = self.accel_mm_per_s2;
        let t_a = self.t_accel_s;
        let ramp_mm = 0.5 * a * t_a * t_a;
        if s_mm <= ramp_mm {
            (2.0 * s_mm / a).sqrt()
        } else if s_mm <= self.length_mm - ramp_mm {
            t_a + (s_mm - ramp_mm) / self.v_peak_mm_per_s
        } else {
            total_s - (2.0 * (self.length_mm - s_mm) / a).sqrt()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_path_gives_a_trapezoid_with_hand_computed_phases() {
        // 100 mm at 100 mm/s with 2000 mm/s²: ramps of 0.05 s covering 2.5 mm each,
        // cruise 95 mm / 100 mm/s = 0.95 s, total 1.05 s.
        let p = SpeedProfile::new(100.0, 100.0, 2000.0);
        assert!(!p.is_triangular());
        assert!((p.t_accel_s - 0.05).abs() < 1e-12);
        assert!((p.t_cruise_s - 0.95).abs() < 1e-12);
        assert!((p.duration_s() - 1.05).abs() < 1e-12);
        assert!((p.distance_at(0.05) - 2.5).abs() < 1e-9);
        assert!((p.distance_at(0.55) - 52.5).abs() < 1e-9);
        assert_eq!(p.distance_at(1.05), 100.0);
    }

    #[test]
    fn short_path_gives_a_triangle_below_the_speed_limit() {
        // 1 mm at 100 mm/s with 2000 mm/s²: needs 5 mm to reach 100 mm/s, so the peak is
        // √(1·2000) = 44.72 mm/s, reached after 22.36 ms at mid-path.
        let p = SpeedProfile::new(1.0, 100.0, 2000.0);
        assert!(p.is_triangular());
        assert_eq!(p.t_cruise_s, 0.0);
        assert!((p.v_peak_mm_per_s - 2000f64.sqrt()).abs() < 1e-12);
        assert!((p.distance_at(p.t_accel_s) - 0.5).abs() < 1e-12);
        assert!((p.duration_s() - 2.0 * 2000f64.sqrt() / 2000.0).abs() < 1e-12);
    }

    #[test]
    fn time_at_distance_inverts_distance_at_in_every_phase() {
        let p = SpeedProfile::new(100.0, 100.0, 2000.0);
        for &t in &[0.0, 0.01, 0.05, 0.3, 1.0, 1.01, 1.049, 1.05] {
            let back = p.time_at_distance(p.distance_at(t));
            assert!((back - t).abs() < 1e-9, "t = {t}, back = {back}");
        }
    }

    #[test]
    fn zero_length_gives_zero_duration_without_nan() {
        let p = SpeedProfile::new(0.0, 100.0, 2000.0);
        assert_eq!(p.duration_s(), 0.0);
        assert_eq!(p.distance_at(0.0), 0.0);
        assert_eq!(p.speed_at(0.0), 0.0);
        assert_eq!(p.time_at_distance(0.0), 0.0);
    }
}
