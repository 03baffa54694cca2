//! First-order kinematic synthesis of the volumetric error from elementary errors
//!.
//!
//! The machine's nominal geometry (its [`Chain`] and the tool offset) is public knowledge, so it
//! lives here on the knowledge side; the twin's exact HTM product (`vmc_twin::kinematics`) uses the
//! same description and the same conventions, and is the truth this linearisation is tested
//! against.
//!
//! # Conventions (shared with the twin's `kinematics` module)
//!
//! Units: lengths in mm, angles in rad.
//!
//! - **Bed frame**: right-handed, axes along the nominal X, Y, Z travel directions, origin at the
//!   spindle gauge point when all axes are at zero ("machine zero").
//! - **Commanded positions** `q = (X, Y, Z)` (`axis_pos_mm`) are the motion of the tool relative
//!   to the workpiece (ISO 841). A tool-side carriage moves by `+q_k` along its axis relative to
//!   its parent; a workpiece-side carriage (table, saddle) physically moves by `−q_k`.
//! - **Workpiece frame**: fixed to the element carrying `w`, origin where the tool tip sits at
//!   machine zero (the work offset includes the tool length, as with G43). So with no errors the
//!   tool tip in the workpiece frame is exactly `q`, whatever the chain.
//! - **Tool offset** `T = (Tx, Ty, Tz)`: tool tip relative to the spindle gauge point, in the
//!   spindle frame; a vertical mill has `T = (0, 0, −L)` with `L` the gauge length.
//! - **Reference point of each axis** (where its error motion acts): the material point of its
//!   carriage that coincides with the bed origin at machine zero. For the carriage holding the
//!   spindle it is the gauge point itself. `δ_ik` (`axes[k].lin_mm[i]`) is the translation of that
//!   point along bed axis `i`, `ε_ik` (`axes[k].ang_rad[i]`) the carriage's rotation about bed axis
//!   `i` through that point (right-hand rule). These are *physical* motions of the carriage
//!   relative to its parent, so a table axis's positioning error `d` moves the table by `d` and
//!   the tool relative to the workpiece by `−d`. Exact form (twin):
//!   `parent_from_carriage = Trans(s_k·q_k·d_k + δ_k) · Rot(ε_k)`, `s_k = −1` workpiece side,
//!   `+1` tool side, `Rot(ε) = R_z(ε_z)·R_y(ε_y)·R_x(ε_x)`.
//! - **Squareness** tilts an axis's *direction of travel* `d_k` (in its parent's frame) and does
//!   not rotate the carriage, so it multiplies only that axis's position and has no Abbe arm.
//!   X is the reference direction: `d_X = e_x`, `d_Y = R_z(α_xy)·e_y ≈ (−α_xy, 1, 0)`,
//!   `d_Z = R_x(α_yz)·R_y(α_xz)·e_z ≈ (α_xz, −α_yz, 1)`: each α is a right-hand rotation of the
//!   later axis's line about the third axis (α_xy > 0 opens the X–Y angle beyond 90°).
//! - **Spindle drifts** (ISO 230-3) act at the gauge point, in the frame of the carriage holding
//!   the spindle: `δ_b = (δ_xb, δ_yb, δ_zb)` translates it, `ε_b = (ε_xb, ε_yb, 0)` tilts the tool
//!   axis about it. The tool tip is `T` from the gauge point in the tilted spindle frame.
//! - **Volumetric error** `E` = actual − nominal tool tip relative to the workpiece, expressed in
//!   the workpiece frame.
//!
//! # First-order synthesis (any chain)
//!
//! Dropping products of two errors (the rotation of one carriage acting on another's error):
//!
//! ```text
//! E = Σ_k s_k·(δ_k + ε_k × a_k) + δ_b + ε_b × T + Σ_k q_k·(d_k − e_k)
//! a_k = T + Σ_{i ∈ A_k} q_i·e_i          (Abbe arm: reference point of k → nominal tool tip)
//! ```
//!
//! where for a tool-side axis `A_k` = the axes `k` carries (further from `b` on the tool side),
//! and for a workpiece-side axis `A_k` = all axes except those `k` carries (the tip stays put in
//! the bed while `k`'s reference point moves with `k` and every axis beneath it). The rule is
//! derived from the chain at parse time ([`Chain::abbe_arm_mm`]); nothing is specific to one
//! layout. Neglected second-order terms are of size ε²·|a| and ε·δ: with angles ≤ 10″
//! (48 µrad), translations ≤ 50 µm and arms ≤ ~1 m they stay at the 10⁻⁶ mm level.
//!
//! # Explicit equations for `w X Y b Z t` (X table on Y saddle on the bed, Z head)
//!
//! Arms: X axis `(X + Tx, Y + Ty, Z + Tz)`, Y axis `(Tx, Y + Ty, Z + Tz)`, Z axis and spindle `T`.
//! Errors δ_ij / ε_ij: direction or rotation axis i, moving axis j; all 26 terms:
//!
//! ```text
//! E_x = −δ_xx − δ_xy + δ_xz + δ_xb
//!       − (Z + Tz)·(ε_yx + ε_yy) + (Y + Ty)·(ε_zx + ε_zy) + Tz·ε_yz − Ty·ε_zz + Tz·ε_yb
//!       − Y·α_xy + Z·α_xz
//! E_y = −δ_yx − δ_yy + δ_yz + δ_yb
//!       + (Z + Tz)·(ε_xx + ε_xy) − (X + Tx)·ε_zx − Tx·ε_zy + Tx·ε_zz − Tz·ε_xz − Tz·ε_xb
//!       − Z·α_yz
//! E_z = −δ_zx − δ_zy + δ_zz + δ_zb
//!       − (Y + Ty)·(ε_xx + ε_xy) + (X + Tx)·ε_yx + Tx·ε_yy + Ty·ε_xz − Tx·ε_yz
//!       + Ty·ε_xb − Tx·ε_yb
//! ```
//!
//! The study writes the table axes in the table's own physical displacement (`X_table = −X`,
//! `Y_table = −Y`), which turns the arms `X + Tx`, `Y + Ty` above into its `Tx − X`, `Ty − Y`;
//! `Z + Tz` is unchanged (Z moves the tool). Hand checks: a positioning error `d` of X gives
//! `E = (−d, 0, 0)`; a Z-axis pitch `ε_yz` with `T = (0, 0, −L)` gives `E_x = −L·ε_yz`;
//! `α_xy` gives `E_x = −Y·α_xy`.
//!
//! Cost: [`first_order_error_mm`] does ~70 flops, no allocation, no transcendental functions.

mod chain;
pub mod reference_cases;

pub use chain::{Chain, ChainError, LinearAxis, Side};

use nalgebra::Vector3;
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

/// Nominal geometry of a 3-axis machine: what a builder publishes, hence knowledge-side.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MachineGeometry {
    /// Workpiece-to-tool kinematic chain (ISO 10791-6), e.g. `"w X Y b Z t"`.
    pub chain: Chain,
    /// Tool tip relative to the spindle gauge point, mm, in the spindle frame
    /// (a vertical mill: `(0, 0, −L)` with `L` the gauge length).
    pub tool_offset_mm: [f64; 3],
}

/// `a × b` on plain arrays (kept local so the hot path never builds nalgebra temporaries).
#[inline(always)]
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// First-order volumetric error at axis positions `axis_pos_mm`: actual − nominal tool tip
/// relative to the workpiece, in the workpiece frame, mm (formula in the module doc).
#[inline]
#[must_use]
pub fn first_order_error_mm(
    geom: &MachineGeometry,
    axis_pos_mm: [f64; 3],
    e: &ElementaryErrors,
) -> Vector3<f64> {
    let t = geom.tool_offset_mm;
    let q = axis_pos_mm;
    let mut out = [0.0; 3];
    for axis in LinearAxis::ALL {
        let k = axis.index();
        let err = &e.axes[k];
        let s = geom.chain.side(axis).sign();
        let abbe = cross(err.ang_rad, geom.chain.abbe_arm_mm(axis, q, t));
        for i in 0..3 {
            out[i] += s * (err.lin_mm[i] + abbe[i]);
        }
    }
    let sp = &e.spindle;
    let tilt = cross([sp.tilt_rad[0], sp.tilt_rad[1], 0.0], t);
    let sq = &e.squareness;
    Vector3::new(
        out[0] + sp.lin_mm[0] + tilt[0] - q[1] * sq.xy_rad + q[2] * sq.xz_rad,
        out[1] + sp.lin_mm[1] + tilt[1] - q[2] * sq.yz_rad,
        out[2] + sp.lin_mm[2] + tilt[2],
    )
}

#[cfg(test)]
mod tests {
    use super::reference_cases::{
        single_error as only, SingleError as One, CASE_CHAIN, CASE_Q_MM, CASE_TOOL_MM,
        SINGLE_ERROR_CASES,
    };
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// 1e-12 mm: far below anything physical; only float rounding of sums of ~1 mm terms.
    const EXACT_MM: f64 = 1e-12;

    fn geometry(chain: &str, tool_offset_mm: [f64; 3]) -> MachineGeometry {
        MachineGeometry {
            chain: Chain::parse(chain).unwrap(),
            tool_offset_mm,
        }
    }

    /// The equations of the module doc for `w X Y b Z t`, written out term by term.
    fn hand_equations_wxybzt(q: [f64; 3], t: [f64; 3], e: &ElementaryErrors) -> [f64; 3] {
        let [x, y, z] = q;
        let [tx, ty, tz] = t;
        let [dxx, dyx, dzx] = e.axes[0].lin_mm;
        let [exx, eyx, ezx] = e.axes[0].ang_rad;
        let [dxy, dyy, dzy] = e.axes[1].lin_mm;
        let [exy, eyy, ezy] = e.axes[1].ang_rad;
        let [dxz, dyz, dzz] = e.axes[2].lin_mm;
        let [exz, eyz, ezz] = e.axes[2].ang_rad;
        let [dxb, dyb, dzb] = e.spindle.lin_mm;
        let [exb, eyb] = e.spindle.tilt_rad;
        let sq = e.squareness;
        let ex =
            -dxx - dxy + dxz + dxb - (z + tz) * (eyx + eyy) + (y + ty) * (ezx + ezy) + tz * eyz
                - ty * ezz
                + tz * eyb
                - y * sq.xy_rad
                + z * sq.xz_rad;
        let ey = -dyx - dyy + dyz + dyb + (z + tz) * (exx + exy) - (x + tx) * ezx - tx * ezy
            + tx * ezz
            - tz * exz
            - tz * exb
            - z * sq.yz_rad;
        let ez =
            -dzx - dzy + dzz + dzb - (y + ty) * (exx + exy) + (x + tx) * eyx + tx * eyy + ty * exz
                - tx * eyz
                + ty * exb
                - tx * eyb;
        [ex, ey, ez]
    }

    fn random_errors(rng: &mut StdRng) -> ElementaryErrors {
        let mut e = ElementaryErrors::default();
        for axis in &mut e.axes {
            axis.lin_mm = std::array::from_fn(|_| rng.random_range(-0.05..0.05));
            axis.ang_rad = std::array::from_fn(|_| rng.random_range(-5e-5..5e-5));
        }
        e.squareness = Squareness {
            xy_rad: rng.random_range(-2e-5..2e-5),
            xz_rad: rng.random_range(-2e-5..2e-5),
            yz_rad: rng.random_range(-2e-5..2e-5),
        };
        e.spindle.lin_mm = std::array::from_fn(|_| rng.random_range(-0.05..0.05));
        e.spindle.tilt_rad = std::array::from_fn(|_| rng.random_range(-5e-5..5e-5));
        e
    }

    #[test]
    fn generic_synthesis_equals_the_hand_written_wxybzt_equations() {
        let geom_chain = Chain::parse("w X Y b Z t").unwrap();
        let mut rng = StdRng::seed_from_u64(7);
        for _ in 0..1000 {
            let t = [
                rng.random_range(-20.0..20.0),
                rng.random_range(-20.0..20.0),
                rng.random_range(-200.0..-100.0),
            ];
            let q = [
                rng.random_range(0.0..560.0),
                rng.random_range(0.0..400.0),
                rng.random_range(-450.0..0.0),
            ];
            let e = random_errors(&mut rng);
            let geom = MachineGeometry {
                chain: geom_chain,
                tool_offset_mm: t,
            };
            let got = first_order_error_mm(&geom, q, &e);
            let want = hand_equations_wxybzt(q, t, &e);
            for i in 0..3 {
                assert!(
                    (got[i] - want[i]).abs() < EXACT_MM,
                    "{i}: {got} vs {want:?}"
                );
            }
        }
    }

    #[test]
    fn no_errors_give_no_volumetric_error() {
        let geom = geometry("w Y b X Z t", [0.0, 0.0, -150.0]);
        let e = ElementaryErrors::default();
        assert_eq!(
            first_order_error_mm(&geom, [300.0, 100.0, -20.0], &e),
            Vector3::zeros()
        );
    }

    #[test]
    fn each_of_the_26_errors_alone_gives_its_hand_derived_effect() {
        let geom = geometry(CASE_CHAIN, CASE_TOOL_MM);
        for (name, which, value, want) in SINGLE_ERROR_CASES {
            let got = first_order_error_mm(&geom, CASE_Q_MM, &only(which, value));
            for i in 0..3 {
                assert!(
                    (got[i] - want[i]).abs() < EXACT_MM,
                    "{name}: {got} vs {want:?}"
                );
            }
        }
    }

    #[test]
    fn four_arcsec_z_pitch_on_a_300_mm_tool_is_5_8_um() {
        let geom = geometry("w X Y b Z t", [0.0, 0.0, -300.0]);
        let four_arcsec_rad = 4.0 / 3600.0 * std::f64::consts::PI / 180.0;
        let e = only(One::Ang(2, 1), four_arcsec_rad);
        let got = first_order_error_mm(&geom, [250.0, 150.0, -100.0], &e);
        // |E_x| = 300 mm · 19.39 µrad = 5.818 µm; checked to 1 nm.
        assert!((got.x + 5.818e-3).abs() < 1e-6, "{got}");
        assert!(got.y.abs() < EXACT_MM && got.z.abs() < EXACT_MM);
    }

    #[test]
    fn moving_an_axis_to_the_other_side_of_the_bed_flips_its_translation_sign() {
        let e = only(One::Lin(0, 0), 0.002);
        let q = [100.0, 200.0, -300.0];
        let table = first_order_error_mm(&geometry("w X Y b Z t", [0.0; 3]), q, &e);
        let gantry = first_order_error_mm(&geometry("w Y b X Z t", [0.0; 3]), q, &e);
        assert!((table.x + 0.002).abs() < EXACT_MM);
        assert!((gantry.x - 0.002).abs() < EXACT_MM);
    }

    #[test]
    fn tool_side_x_yaw_sees_the_z_axis_it_carries() {
        // Chain "w Y b X Z t": X carries Z, so X's arm is T + Z·e_z = (0, 0, −300 − 150).
        // ε_yx = 1e-5 rad, tool side: E = +ε × a = (1e-5 · (−450), 0, 0).
        let geom = geometry("w Y b X Z t", [0.0, 0.0, -150.0]);
        let got = first_order_error_mm(&geom, [100.0, 200.0, -300.0], &only(One::Ang(0, 1), 1e-5));
        assert!(
            (got.x + 4.5e-3).abs() < EXACT_MM && got.y.abs() < EXACT_MM && got.z.abs() < EXACT_MM
        );
    }
}
