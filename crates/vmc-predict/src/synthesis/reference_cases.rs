//! Hand-derived reference cases: each of the 26 elementary errors alone on a `w X Y b Z t`
//! machine and the volumetric error it must give at one pose.
//!
//! Worked by hand from the conventions of [`super`], not computed by any code of this project,
//! so that every implementation of the chain — the first-order synthesis here, the twin's exact
//! HTM product — is checked against the same independent table.
//!
//! The pose: axis positions [`CASE_Q_MM`] = (100, 200, −300) mm, tool offset [`CASE_TOOL_MM`] =
//! (10, 20, −150) mm. Translations 0.002 mm, motion angles 1e-5 rad, squareness 2e-5 rad.
//! Arms: X (110, 220, −450), Y (10, 220, −450), Z and spindle (10, 20, −150); the table and the
//! saddle (workpiece side) enter as −(δ + ε × a), the head and the spindle (tool side) as
//! +(δ + ε × a); squareness as −Y·α_xy, +Z·α_xz in E_x and −Z·α_yz in E_y.

use super::ElementaryErrors;

/// Chain of the cases.
pub const CASE_CHAIN: &str = "w X Y b Z t";
/// Axis positions of the cases, mm.
pub const CASE_Q_MM: [f64; 3] = [100.0, 200.0, -300.0];
/// Tool offset of the cases, mm.
pub const CASE_TOOL_MM: [f64; 3] = [10.0, 20.0, -150.0];

/// Which single elementary error a case sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SingleError {
    /// Translation `δ_i` (second index) of axis `k` (first index).
    Lin(usize, usize),
    /// Rotation `ε_i` (second index) of axis `k` (first index).
    Ang(usize, usize),
    /// Squareness α_xy.
    SqXy,
    /// Squareness α_xz.
    SqXz,
    /// Squareness α_yz.
    SqYz,
    /// Spindle translation `δ_i`.
    SpLin(usize),
    /// Spindle tilt `ε_i` (x or y).
    SpTilt(usize),
}

/// Elementary errors with only `which` set, to `value` (mm or rad); indices beyond the arrays
/// set nothing.
pub fn single_error(which: SingleError, value: f64) -> ElementaryErrors {
    let mut e = ElementaryErrors::default();
    let set = |slot: Option<&mut f64>| {
        if let Some(s) = slot {
            *s = value;
        }
    };
    match which {
        SingleError::Lin(axis, i) => set(e.axes.get_mut(axis).and_then(|a| a.lin_mm.get_mut(i))),
        SingleError::Ang(axis, i) => set(e.axes.get_mut(axis).and_then(|a| a.ang_rad.get_mut(i))),
        SingleError::SqXy => e.squareness.xy_rad = value,
        SingleError::SqXz => e.squareness.xz_rad = value,
        SingleError::SqYz => e.squareness.yz_rad = value,
        SingleError::SpLin(i) => set(e.spindle.lin_mm.get_mut(i)),
        SingleError::SpTilt(i) => set(e.spindle.tilt_rad.get_mut(i)),
    }
    e
}

/// The 26 cases: name, error, value (mm or rad), expected volumetric error (mm) at
/// [`CASE_Q_MM`] with [`CASE_TOOL_MM`] on [`CASE_CHAIN`].
pub const SINGLE_ERROR_CASES: [(&str, SingleError, f64, [f64; 3]); 26] = {
    use SingleError::*;
    [
        ("δ_xx", Lin(0, 0), 0.002, [-0.002, 0.0, 0.0]),
        ("δ_yx", Lin(0, 1), 0.002, [0.0, -0.002, 0.0]),
        ("δ_zx", Lin(0, 2), 0.002, [0.0, 0.0, -0.002]),
        ("ε_xx", Ang(0, 0), 1e-5, [0.0, -4.5e-3, -2.2e-3]),
        ("ε_yx", Ang(0, 1), 1e-5, [4.5e-3, 0.0, 1.1e-3]),
        ("ε_zx", Ang(0, 2), 1e-5, [2.2e-3, -1.1e-3, 0.0]),
        ("δ_xy", Lin(1, 0), 0.002, [-0.002, 0.0, 0.0]),
        ("δ_yy", Lin(1, 1), 0.002, [0.0, -0.002, 0.0]),
        ("δ_zy", Lin(1, 2), 0.002, [0.0, 0.0, -0.002]),
        ("ε_xy", Ang(1, 0), 1e-5, [0.0, -4.5e-3, -2.2e-3]),
        ("ε_yy", Ang(1, 1), 1e-5, [4.5e-3, 0.0, 1e-4]),
        ("ε_zy", Ang(1, 2), 1e-5, [2.2e-3, -1e-4, 0.0]),
        ("δ_xz", Lin(2, 0), 0.002, [0.002, 0.0, 0.0]),
        ("δ_yz", Lin(2, 1), 0.002, [0.0, 0.002, 0.0]),
        ("δ_zz", Lin(2, 2), 0.002, [0.0, 0.0, 0.002]),
        ("ε_xz", Ang(2, 0), 1e-5, [0.0, 1.5e-3, 2e-4]),
        ("ε_yz", Ang(2, 1), 1e-5, [-1.5e-3, 0.0, -1e-4]),
        ("ε_zz", Ang(2, 2), 1e-5, [-2e-4, 1e-4, 0.0]),
        ("α_xy", SqXy, 2e-5, [-4e-3, 0.0, 0.0]),
        ("α_xz", SqXz, 2e-5, [-6e-3, 0.0, 0.0]),
        ("α_yz", SqYz, 2e-5, [0.0, 6e-3, 0.0]),
        ("δ_xb", SpLin(0), 0.002, [0.002, 0.0, 0.0]),
        ("δ_yb", SpLin(1), 0.002, [0.0, 0.002, 0.0]),
        ("δ_zb", SpLin(2), 0.002, [0.0, 0.0, 0.002]),
        ("ε_xb", SpTilt(0), 1e-5, [0.0, 1.5e-3, 2e-4]),
        ("ε_yb", SpTilt(1), 1e-5, [-1.5e-3, 0.0, -1e-4]),
    ]
};
