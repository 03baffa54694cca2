//! Path geometry of one segment: a point (no motion), a straight line, or a circular arc/helix.
//!
//! Arcs are described in plane coordinates `(u, v, w)`: G17 `(X, Y, Z)`, G18 `(Z, X, Y)`,
//! G19 `(Y, Z, X)`. Each triple is right-handed (`u × v = w`), so a positive angle (measured from
//! `+u` towards `+v`) is counter-clockwise seen from `+w`: G3 has a positive sweep, G2 a negative
//! one. This is also why G18 runs Z→X: G2 in G18 is clockwise seen from +Y.
//!
//! At path fraction `f = s/L`: `θ = θ₀ + f·Δθ`, `r = r₀ + f·(r₁ − r₀)`, `w = w₀ + f·h`, and the
//! point is `(c_u + r·cos θ, c_v + r·sin θ, w)`. For a consistent arc `r₁ = r₀`; a small
//! start/end radius mismatch (within the interpreter's tolerance) is spread linearly (a spiral,
//! as LinuxCNC does) so the arc ends exactly on its programmed end point.
//! Path length: `L = √((r̄·|Δθ|)² + h²)` with `r̄ = (r₀ + r₁)/2` (exact for `r₁ = r₀`).

use std::f64::consts::{FRAC_PI_2, TAU};

use vmc_gcode::interp::Plane;

/// Radius below which an arc is rejected as degenerate (mm); 1 nm.
pub const MIN_ARC_RADIUS_MM: f64 = 1e-6;

/// In-plane chord below which an arc whose end equals its start is a full circle (mm); 1 nm.
const FULL_CIRCLE_CHORD_MM: f64 = 1e-6;

/// Indices of the `(u, v, w)` plane axes into `[x, y, z]`.
pub fn plane_axes(plane: Plane) -> [usize; 3] {
    match plane {
        Plane::Xy => [0, 1, 2],
        Plane::Zx => [2, 0, 1],
        Plane::Yz => [1, 2, 0],
    }
}

/// A circular arc or helix in one of the three principal planes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcGeometry {
    /// Arc plane (G17 / G18 / G19).
    pub plane: Plane,
    /// Centre in machine coordinates (mm); its plane-axis coordinate is the start's.
    pub center_mm: [f64; 3],
    /// Radius at the start point (mm).
    pub radius_mm: f64,
    /// Radius at the end point (mm); equals `radius_mm` for a consistent arc.
    pub end_radius_mm: f64,
    /// Angle of the start point from `+u` towards `+v` (rad).
    pub start_angle_rad: f64,
    /// Signed swept angle including extra turns (rad): positive counter-clockwise (G3).
    pub sweep_angle_rad: f64,
    /// Travel along the plane's axis `w` from start to end (mm); non-zero for a helix.
    pub axis_travel_mm: f64,
    /// Path length of the arc or helix (mm).
    pub length_mm: f64,
}

impl ArcGeometry {
    /// Arc from `start_mm` to `end_mm` around `center_mm`; `None` when a radius is degenerate.
    pub fn new(
        start_mm: [f64; 3],
        end_mm: [f64; 3],
        center_mm: [f64; 3],
        plane: Plane,
        clockwise: bool,
        extra_turns: u32,
    ) -> Option<Self> {
        let [iu, iv, iw] = plane_axes(plane);
        let (du0, dv0) = (start_mm[iu] - center_mm[iu], start_mm[iv] - center_mm[iv]);
        let (du1, dv1) = (end_mm[iu] - center_mm[iu], end_mm[iv] - center_mm[iv]);
        let radius_mm = du0.hypot(dv0);
        let end_radius_mm = du1.hypot(dv1);
        if !(radius_mm >= MIN_ARC_RADIUS_MM && end_radius_mm >= MIN_ARC_RADIUS_MM) {
            return None;
        }
        let start_angle_rad = dv0.atan2(du0);
        let delta_rad = dv1.atan2(du1) - start_angle_rad;
        let chord_mm = (end_mm[iu] - start_mm[iu]).hypot(end_mm[iv] - start_mm[iv]);
        // Within one turn: (0, 2π] counter-clockwise, [−2π, 0) clockwise; equal ends = full turn.
        let one_turn_rad = if chord_mm < FULL_CIRCLE_CHORD_MM {
            TAU
        } else if clockwise {
            (-delta_rad).rem_euclid(TAU)
        } else {
            delta_rad.rem_euclid(TAU)
        };
        let turns_rad = one_turn_rad + TAU * f64::from(extra_turns);
        let sweep_angle_rad = if clockwise { -turns_rad } else { turns_rad };
        let axis_travel_mm = end_mm[iw] - start_mm[iw];
        let mean_radius_mm = 0.5 * (radius_mm + end_radius_mm);
        let length_mm = (mean_radius_mm * turns_rad).hypot(axis_travel_mm);
        Some(Self {
            plane,
            center_mm: {
                let mut c = center_mm;
                c[iw] = start_mm[iw];
                c
            },
            radius_mm,
            end_radius_mm,
            start_angle_rad,
            sweep_angle_rad,
            axis_travel_mm,
            length_mm,
        })
    }

    /// Point at path fraction `f ∈ [0, 1]` (mm).
    pub fn point_at_fraction(&self, f: f64) -> [f64; 3] {
        let [iu, iv, iw] = plane_axes(self.plane);
        let theta = self.start_angle_rad + f * self.sweep_angle_rad;
        let r = self.radius_mm + f * (self.end_radius_mm - self.radius_mm);
        let mut p = [0.0; 3];
        p[iu] = self.center_mm[iu] + r * theta.cos();
        p[iv] = self.center_mm[iv] + r * theta.sin();
        p[iw] = self.center_mm[iw] + f * self.axis_travel_mm;
        p
    }

    /// Derivative of the position with respect to path fraction, `dp/df` (mm).
    pub fn derivative_at_fraction(&self, f: f64) -> [f64; 3] {
        let [iu, iv, iw] = plane_axes(self.plane);
        let theta = self.start_angle_rad + f * self.sweep_angle_rad;
        let dr = self.end_radius_mm - self.radius_mm;
        let r = self.radius_mm + f * dr;
        let (sin, cos) = theta.sin_cos();
        let mut d = [0.0; 3];
        d[iu] = dr * cos - r * sin * self.sweep_angle_rad;
        d[iv] = dr * sin + r * cos * self.sweep_angle_rad;
        d[iw] = self.axis_travel_mm;
        d
    }

    /// Path fractions strictly inside the arc where the angle crosses a multiple of π/2, i.e.
    /// where the `u` or `v` coordinate reaches an extreme (the arc's bulge points), in order.
    pub fn quadrant_crossings(&self) -> impl Iterator<Item = f64> + '_ {
        let sweep = self.sweep_angle_rad;
        let theta0 = self.start_angle_rad;
        let (k_first, k_last) = if sweep >= 0.0 {
            (
                (theta0 / FRAC_PI_2).floor() as i64 + 1,
                ((theta0 + sweep) / FRAC_PI_2).ceil() as i64 - 1,
            )
        } else {
            (
                (theta0 / FRAC_PI_2).ceil() as i64 - 1,
                ((theta0 + sweep) / FRAC_PI_2).floor() as i64 + 1,
            )
        };
        let step: i64 = if sweep >= 0.0 { 1 } else { -1 };
        let count = if sweep == 0.0 {
            0
        } else {
            ((k_last - k_first) * step + 1).max(0)
        };
        (0..count).map(move |i| {
            let k = k_first + i * step;
            ((k as f64 * FRAC_PI_2 - theta0) / sweep).clamp(0.0, 1.0)
        })
    }

    /// Axis-aligned bounding box of the arc, extreme (bulge) points included: `(min, max)` (mm).
    pub fn bounds_mm(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = self.point_at_fraction(0.0);
        let mut hi = lo;
        let mut include = |p: [f64; 3]| {
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        };
        include(self.point_at_fraction(1.0));
        for f in self.quadrant_crossings() {
            include(self.point_at_fraction(f));
        }
        (lo, hi)
    }
}

/// Shape of a segment's path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Geometry {
    /// No motion: the tool stays at the segment's start (dwell, tool change).
    Point,
    /// Straight line from the segment's start along a unit direction.
    Line {
        /// Unit direction from start to end; all zeros for a zero-length move.
        dir: [f64; 3],
        /// Length (mm).
        length_mm: f64,
    },
    /// Circular arc or helix.
    Arc(ArcGeometry),
}

impl Geometry {
    /// Straight line from `start_mm` to `end_mm`.
    pub fn line(start_mm: [f64; 3], end_mm: [f64; 3]) -> Self {
        let d = [
            end_mm[0] - start_mm[0],
            end_mm[1] - start_mm[1],
            end_mm[2] - start_mm[2],
        ];
        let length_mm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let dir = if length_mm > 0.0 {
            [d[0] / length_mm, d[1] / length_mm, d[2] / length_mm]
        } else {
            [0.0; 3]
        };
        Self::Line { dir, length_mm }
    }

    /// Path length (mm).
    pub fn length_mm(&self) -> f64 {
        match self {
            Self::Point => 0.0,
            Self::Line { length_mm, .. } => *length_mm,
            Self::Arc(arc) => arc.length_mm,
        }
    }

    /// Position after travelling `s_mm` along the path from `start_mm` (mm).
    pub fn point_at(&self, start_mm: [f64; 3], s_mm: f64) -> [f64; 3] {
        match self {
            Self::Point => start_mm,
            Self::Line { dir, .. } => [
                start_mm[0] + dir[0] * s_mm,
                start_mm[1] + dir[1] * s_mm,
                start_mm[2] + dir[2] * s_mm,
            ],
            Self::Arc(arc) => arc.point_at_fraction(s_mm / arc.length_mm),
        }
    }

    /// Unit tangent `dp/ds` at distance `s_mm` (dimensionless); zeros for a point.
    pub fn tangent_at(&self, s_mm: f64) -> [f64; 3] {
        match self {
            Self::Point => [0.0; 3],
            Self::Line { dir, .. } => *dir,
            Self::Arc(arc) => {
                let d = arc.derivative_at_fraction(s_mm / arc.length_mm);
                [
                    d[0] / arc.length_mm,
                    d[1] / arc.length_mm,
                    d[2] / arc.length_mm,
                ]
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn quarter_arc_g2_in_xy_sweeps_minus_half_pi() {
        // From (10,0) to (0,-10) around the origin, clockwise seen from +Z: −π/2.
        let arc = ArcGeometry::new(
            [10.0, 0.0, 0.0],
            [0.0, -10.0, 0.0],
            [0.0; 3],
            Plane::Xy,
            true,
            0,
        )
        .expect("valid arc");
        assert!((arc.sweep_angle_rad + PI / 2.0).abs() < 1e-12);
        assert!((arc.length_mm - 5.0 * PI).abs() < 1e-9);
    }

    #[test]
    fn same_start_and_end_is_a_full_circle_plus_extra_turns() {
        let arc = ArcGeometry::new(
            [10.0, 0.0, 0.0],
            [10.0, 0.0, 3.0],
            [0.0; 3],
            Plane::Xy,
            false,
            2,
        )
        .expect("valid arc");
        assert!((arc.sweep_angle_rad - 3.0 * TAU).abs() < 1e-12);
        assert_eq!(arc.axis_travel_mm, 3.0);
    }

    #[test]
    fn bounds_include_the_bulge_of_a_half_circle() {
        // Counter-clockwise half circle from (10,0) to (−10,0) passes through (0,10).
        let arc = ArcGeometry::new(
            [10.0, 0.0, 0.0],
            [-10.0, 0.0, 0.0],
            [0.0; 3],
            Plane::Xy,
            false,
            0,
        )
        .expect("valid arc");
        let (lo, hi) = arc.bounds_mm();
        assert!((hi[1] - 10.0).abs() < 1e-9, "max y = {}", hi[1]);
        assert!(lo[1].abs() < 1e-9, "min y = {}", lo[1]);
        let crossings: Vec<f64> = arc.quadrant_crossings().collect();
        assert_eq!(crossings.len(), 1);
        assert!((crossings[0] - 0.5).abs() < 1e-12);
    }

    #[test]
    fn zero_radius_arc_is_rejected() {
        assert!(
            ArcGeometry::new([0.0; 3], [1.0, 0.0, 0.0], [0.0; 3], Plane::Xy, true, 0).is_none()
        );
    }

    #[test]
    fn zero_length_line_has_zero_direction() {
        let g = Geometry::line([1.0, 2.0, 3.0], [1.0, 2.0, 3.0]);
        assert_eq!(
            g,
            Geometry::Line {
                dir: [0.0; 3],
                length_mm: 0.0
            }
        );
        assert_eq!(g.point_at([1.0, 2.0, 3.0], 0.0), [1.0, 2.0, 3.0]);
    }
}
