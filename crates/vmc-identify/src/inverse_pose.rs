//! The five axes that put the tool tip at a target *and* the tool axis along a target direction,
//! both relative to the workpiece, under a model of the machine's errors: what a controller
//! that compensates its rotary axes as well as its linear ones commands.
//!
//! # Model
//! A five-axis machine has two rotary axes, so of the tool's orientation it can set the axis
//! direction (two degrees of freedom), not the turn about it (which a rotating tool does not
//! see). The unknowns are the rotary corrections `d` (rad, two) and the linear axes `q` (mm):
//! - for given rotary angles `θ + d`, `q` solves the position exactly
//!   ([`crate::inverse::linear_axes_for`]: `tip_w(q, θ + d; ê) = p`);
//! - `d` minimises `|r(d)|² + λ²·|d|²`, `r` the two components of the model's tool axis
//!   `a(q, θ + d; ê)` across the target axis `a*` (`r = [u₁·a, u₂·a]`, `u₁ ⊥ u₂ ⊥ a*`),
//!   by Gauss–Newton with the nominal chain's Jacobian `∂a/∂θ` (central differences).
//!
//! The damping `λ` ([`SINGULARITY_DAMPING`]) is the singularity-robust inverse of robot
//! control: where the Jacobian is well conditioned it changes the solution by a relative
//! `λ²/σ²` (4·10⁻⁶ at a singular value σ = 0.5), while near a kinematic singularity (a B/C
//! table at B = 0, where turning C does not move the tool axis) it keeps the correction of the
//! axis that cannot help small instead of sending it through large angles; the component of
//! the orientation error that no small move can correct there is left. Units: mm, rad inside,
//! degrees for commanded angles.

use nalgebra::{Matrix2, Vector2, Vector3};

use crate::chain::{Geometry, Pose};
use crate::errors::ErrorState;
use crate::htm::tool_axis_in_workpiece;
use crate::inverse::{linear_axes_for, HtmError};

/// Damping `λ` of the rotary correction (dimensionless: rad of tool-axis error per rad of
/// rotary angle); see the module documentation.
pub const SINGULARITY_DAMPING: f64 = 1e-3;

/// Step of the central differences of the nominal Jacobian, rad.
const JACOBIAN_STEP_RAD: f64 = 1e-4;

/// Two unit vectors across `axis` (unit), orthogonal to each other.
fn across(axis: Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if axis.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u1 = axis.cross(&helper).normalize();
    (u1, axis.cross(&u1))
}

/// The nominal tool axis at rotary angles `rotary_rad` (it does not depend on the linear axes).
fn nominal_axis(geom: &Geometry, rotary_rad: [f64; 2]) -> Vector3<f64> {
    let pose = Pose {
        linear_mm: [0.0; 3],
        rotary_deg: [rotary_rad[0].to_degrees(), rotary_rad[1].to_degrees()],
    };
    tool_axis_in_workpiece(geom, &pose, &ErrorState::default())
}

/// `∂(u₁·a, u₂·a)/∂θ` of the nominal chain at `rotary_rad`.
fn nominal_jacobian(
    geom: &Geometry,
    rotary_rad: [f64; 2],
    u: (Vector3<f64>, Vector3<f64>),
) -> Matrix2<f64> {
    let mut j = Matrix2::zeros();
    for k in 0..2 {
        let (mut plus, mut minus) = (rotary_rad, rotary_rad);
        plus[k] += JACOBIAN_STEP_RAD;
        minus[k] -= JACOBIAN_STEP_RAD;
        let da = (nominal_axis(geom, plus) - nominal_axis(geom, minus)) / (2.0 * JACOBIAN_STEP_RAD);
        j[(0, k)] = u.0.dot(&da);
        j[(1, k)] = u.1.dot(&da);
    }
    j
}

/// The pose (linear axes, rotary angles) at which, under the error model `errors`, the tool tip
/// sits at `target_w_mm` and the tool axis lies along `axis_w` (unit), both in the workpiece
/// frame, starting from the commanded angles `rotary_deg` (see the module documentation).
///
/// # Errors
/// [`HtmError::NoConvergence`] when the position cannot be solved at some angles, or the
/// rotary correction still moves after 30 steps.
pub fn axes_for_tool_pose(
    geom: &Geometry,
    rotary_deg: [f64; 2],
    target_w_mm: Vector3<f64>,
    axis_w: Vector3<f64>,
    errors: &dyn Fn(&Pose) -> ErrorState,
) -> Result<Pose, HtmError> {
    let u = across(axis_w);
    let theta0_rad = [rotary_deg[0].to_radians(), rotary_deg[1].to_radians()];
    let mut d_rad: Vector2<f64> = Vector2::zeros();
    let lambda2 = SINGULARITY_DAMPING * SINGULARITY_DAMPING;
    let mut step_rad = f64::INFINITY;
    for _ in 0..30 {
        let rot_rad = [theta0_rad[0] + d_rad[0], theta0_rad[1] + d_rad[1]];
        let rot_deg = [rot_rad[0].to_degrees(), rot_rad[1].to_degrees()];
        let q = linear_axes_for(geom, rot_deg, target_w_mm, errors)?;
        let pose = Pose {
            linear_mm: q,
            rotary_deg: rot_deg,
        };
        if step_rad < 1e-13 {
            return Ok(pose);
        }
        let a = tool_axis_in_workpiece(geom, &pose, &errors(&pose));
        let r = Vector2::new(u.0.dot(&a), u.1.dot(&a));
        let j = nominal_jacobian(geom, rot_rad, u);
        let lhs = j.transpose() * j + Matrix2::identity() * lambda2;
        let rhs = -(j.transpose() * r + d_rad * lambda2);
        // λ² > 0 keeps the matrix positive definite.
        let step = lhs.try_inverse().unwrap_or_else(Matrix2::zeros) * rhs;
        d_rad += step;
        step_rad = step.norm();
    }
    Err(HtmError::NoConvergence {
        rotary_deg,
        step_mm: step_rad,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::errors::tests_support::trunnion;
    use crate::htm::tip_in_workpiece_mm;

    fn angle_rad(a: Vector3<f64>, b: Vector3<f64>) -> f64 {
        a.cross(&b).norm().atan2(a.dot(&b))
    }

    /// Tilts of both rotary axes' average lines and an angular positioning error of each.
    fn tilted(_: &Pose) -> ErrorState {
        let mut s = ErrorState::default();
        s.rotary_location[0].ang_rad = [30e-6, -20e-6, 0.0];
        s.rotary_location[1].ang_rad = [0.0, 25e-6, -15e-6];
        s.rotary_motion[0].ang_rad[2] = 12e-6;
        s.rotary_motion[1].ang_rad[0] = -18e-6;
        s.rotary_location[0].lin_mm = [0.02, -0.01, 0.0];
        s
    }

    #[test]
    fn the_solved_pose_puts_tip_and_axis_where_the_nominal_machine_would() {
        let g = trunnion();
        let zero = ErrorState::default();
        for (c, a) in [(30.0, -40.0), (200.0, -75.0), (90.0, 20.0)] {
            let commanded = Pose {
                linear_mm: [20.0, -30.0, -150.0],
                rotary_deg: [c, a],
            };
            let p = tip_in_workpiece_mm(&g, &commanded, &zero);
            let axis = tool_axis_in_workpiece(&g, &commanded, &zero);
            let before = tool_axis_in_workpiece(&g, &commanded, &tilted(&commanded));
            assert!(angle_rad(before, axis) > 10e-6);
            let pose = axes_for_tool_pose(&g, [c, a], p, axis, &tilted).unwrap();
            let st = tilted(&pose);
            assert!((tip_in_workpiece_mm(&g, &pose, &st) - p).norm() < 1e-9);
            // Away from the singularity the damping leaves ~λ²/σ² of the error: < 1e-9 rad here.
            let after = angle_rad(tool_axis_in_workpiece(&g, &pose, &st), axis);
            assert!(after < 1e-9, "C{c} A{a}: {after:e} rad");
        }
    }

    #[test]
    fn at_the_singularity_the_axis_that_cannot_help_stays_put() {
        // A = 0: the tool axis is the C axis, turning C moves it nowhere. The solution keeps C
        // within a few hundredths of a degree of its command and corrects what A can.
        let g = trunnion();
        let zero = ErrorState::default();
        let commanded = Pose {
            linear_mm: [0.0, 0.0, -150.0],
            rotary_deg: [45.0, 0.0],
        };
        let p = tip_in_workpiece_mm(&g, &commanded, &zero);
        let axis = tool_axis_in_workpiece(&g, &commanded, &zero);
        let pose = axes_for_tool_pose(&g, [45.0, 0.0], p, axis, &tilted).unwrap();
        assert!((pose.rotary_deg[0] - 45.0).abs() < 0.05, "{pose:?}");
        let st = tilted(&pose);
        assert!((tip_in_workpiece_mm(&g, &pose, &st) - p).norm() < 1e-9);
        let before = angle_rad(
            tool_axis_in_workpiece(&g, &commanded, &tilted(&commanded)),
            axis,
        );
        let after = angle_rad(tool_axis_in_workpiece(&g, &pose, &st), axis);
        assert!(after < before, "{after:e} vs {before:e}");
    }
}
