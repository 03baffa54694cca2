//! First-order kinematic synthesis of the volumetric error from elementary errors.

use serde::{Deserialize, Serialize};

/// The 21 geometric + 5 spindle elementary errors at one pose.
///
/// Lengths in mm, angles in rad (small angles). For an axis moving along j:
/// `lin_mm[i]` is δ_ij (translation error along machine axis i = x, y, z) and
/// `ang_rad[i]` is ε_ij (rotation about machine axis i, right-hand rule).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct AxisErrors {
    /// δ_xj, δ_yj, δ_zj in mm (ISO 230-1: EXJ, EYJ, EZJ).
    pub lin_mm: [f64; 3],
    /// ε_xj, ε_yj, ε_zj in rad (ISO 230-1: EAJ, EBJ, ECJ).
    pub ang_rad: [f64; 3],
}

/// Squareness errors in rad: α_xy (EC0Y), α_xz (EB0Z), α_yz (EA0Z).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Squareness {
    /// EC0Y: squareness of X to Y, rad.
    pub xy_rad: f64,
    /// EB0Z: squareness of X to Z, rad.
    pub xz_rad: f64,
    /// EA0Z: squareness of Y to Z, rad.
    pub yz_rad: f64,
}

/// The 5 spindle thermal drifts (ISO 230-3): translations δ_xb, δ_yb, δ_zb (mm) and tilts ε_xb, ε_yb (rad).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct SpindleDrift {
    /// δ_xb, δ_yb, δ_zb in mm.
    pub lin_mm: [f64; 3],
    /// ε_xb, ε_yb in rad.
    pub tilt_rad: [f64; 2],
}

/// All elementary errors that act at one machine pose.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ElementaryErrors {
    /// Motion errors of the X, Y, Z axes (index 0, 1, 2), each evaluated at that axis's position.
    pub axes: [AxisErrors; 3],
    /// The three squareness errors.
    pub squareness: Squareness,
    /// The spindle's thermal drifts.
    pub spindle: SpindleDrift,
}
