//! The exact homogeneous-transform model of a five-axis chain (no small-angle linearisation).
//!
//! Each element contributes its pose relative to its parent (conventions in [`crate::chain`]):
//! - linear axis k: `Trans(s·q_k·d_k + δ_k) · Rot(ε_k)`, `d_k` its travel direction tilted by
//!   the squareness errors (`d_Y = (−sin α_xy, cos α_xy, 0)`, `d_Z` from α_xz, α_yz), `s = −1` on
//!   the workpiece side;
//! - rotary axis through point `p` with direction `u` at commanded angle θ:
//!   `Trans(p) · Trans(δ_loc) · Rot(ε_loc) · Trans(δ_m(θ)) · Rot(ε_m(θ)) · Rot(u, s·θ) · Trans(−p)`
//!   (location errors of the average line, then the motion errors at θ, then the nominal turn);
//! - the workpiece frame on the element carrying `w`: `Trans(datum + δ_W)`;
//! - the tool tip on the last tool-side element: `Trans(T + δ_T)`.
//!
//! `Rot(ε) = R_z(ε_z)·R_y(ε_y)·R_x(ε_x)`. The tool tip relative to the workpiece is
//! `workpiece_from_bed · bed_from_tip`, read in the workpiece frame.
//!
//! A probe touching the reference sphere (the datum) at rotary angles θ reads the linear axes
//! `q` at which the tip sits at the sphere centre: `tip_in_workpiece(q, θ) = 0`, solved by
//! Newton iteration with the nominal Jacobian ([`linear_axes_for`]).

use nalgebra::{Isometry3, Matrix3, Translation3, Unit, UnitQuaternion, Vector3};

use crate::chain::{Axis, Geometry, LinearAxis, Pose};
use crate::errors::ErrorState;
use crate::sensitivity::Frames;

/// Exact rotation `R_z(ε_z)·R_y(ε_y)·R_x(ε_x)` from three angles (rad).
#[must_use]
pub fn error_rotation(ang_rad: [f64; 3]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(ang_rad[0], ang_rad[1], ang_rad[2])
}

/// Exact unit direction of travel of `axis` tilted by the squareness errors (rad: α_xy, α_xz, α_yz).
#[must_use]
pub fn travel_direction(axis: LinearAxis, squareness_rad: [f64; 3]) -> Vector3<f64> {
    match axis {
        LinearAxis::X => Vector3::x(),
        LinearAxis::Y => {
            let (s, c) = squareness_rad[0].sin_cos();
            Vector3::new(-s, c, 0.0)
        }
        LinearAxis::Z => {
            let (sa, ca) = squareness_rad[1].sin_cos();
            let (sb, cb) = squareness_rad[2].sin_cos();
            Vector3::new(sa, -ca * sb, ca * cb)
        }
    }
}

fn six(e: &crate::errors::SixErrors) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(Vector3::from(e.lin_mm)),
        error_rotation(e.ang_rad),
    )
}

/// Pose of chain element `index` relative to its parent at `pose`, with `state`'s errors.
#[must_use]
pub fn parent_from_element(
    geom: &Geometry,
    index: usize,
    pose: &Pose,
    state: &ErrorState,
) -> Isometry3<f64> {
    let s = geom.chain.side_of(index).sign();
    match geom.chain.elements()[index] {
        Axis::Linear(axis) => {
            let k = axis.index();
            let travel = travel_direction(axis, state.squareness_rad) * (s * pose.linear_mm[k]);
            let e = &state.linear[k];
            Isometry3::from_parts(
                Translation3::from(travel + Vector3::from(e.lin_mm)),
                error_rotation(e.ang_rad),
            )
        }
        Axis::Rotary(axis) => {
            let r = rotary_index(geom, index);
            let p = Vector3::from(geom.rotary[r].point_mm);
            let turn = UnitQuaternion::from_axis_angle(
                &Unit::new_unchecked(axis.nominal_direction()),
                s * pose.rotary_deg[r].to_radians(),
            );
            let mut loc = state.rotary_location[r];
            // The offset along the axis itself moves nothing (not an error of the line).
            loc.lin_mm[axis.index()] = 0.0;
            Translation3::from(p)
                * six(&loc)
                * six(&state.rotary_motion[r])
                * turn
                * Translation3::from(-p)
        }
    }
}

/// Index in [`Geometry::rotary`] of the rotary element at chain index `index`.
#[must_use]
pub(crate) fn rotary_index(geom: &Geometry, index: usize) -> usize {
    geom.chain.elements()[..index]
        .iter()
        .filter(|e| matches!(e, Axis::Rotary(_)))
        .count()
}

/// The workpiece frame in the bed at `pose`.
#[must_use]
pub fn bed_from_workpiece(geom: &Geometry, pose: &Pose, state: &ErrorState) -> Isometry3<f64> {
    let mut m = Isometry3::identity();
    for i in (0..geom.chain.n_workpiece_side()).rev() {
        m *= parent_from_element(geom, i, pose, state);
    }
    m * Translation3::from(Vector3::from(geom.datum_mm) + Vector3::from(state.workpiece_mm))
}

/// The tool tip frame (spindle orientation, origin at the tip) in the bed at `pose`.
#[must_use]
pub fn bed_from_tip(geom: &Geometry, pose: &Pose, state: &ErrorState) -> Isometry3<f64> {
    let mut m = Isometry3::identity();
    for i in geom.chain.n_workpiece_side()..geom.chain.elements().len() {
        m *= parent_from_element(geom, i, pose, state);
    }
    m * Translation3::from(Vector3::from(geom.tool_offset_mm) + Vector3::from(state.tool_mm))
}

/// The tool tip relative to the workpiece, in the workpiece frame, mm (exact).
#[must_use]
pub fn tip_in_workpiece_mm(geom: &Geometry, pose: &Pose, state: &ErrorState) -> Vector3<f64> {
    let w = bed_from_workpiece(geom, pose, state);
    let t = bed_from_tip(geom, pose, state);
    (w.inverse() * t).translation.vector
}

/// Why the exact model could not be solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HtmError {
    /// Newton iteration did not converge (errors far too large, or a singular configuration).
    #[error("the linear axes for rotary angles {rotary_deg:?} did not converge (last step {step_mm:e} mm)")]
    NoConvergence {
        /// The rotary angles, degrees.
        rotary_deg: [f64; 2],
        /// Size of the last Newton step, mm.
        step_mm: f64,
    },
}

/// Linear axes at which the tip sits at `target_w_mm` (workpiece frame) with the rotary axes at
/// `rotary_deg`, under the pose-dependent error state `errors` (exact model, Newton iteration
/// with the nominal Jacobian; converges to 1e-10 mm in a few steps for errors of machine size).
///
/// # Errors
/// [`HtmError::NoConvergence`] after 30 steps.
pub fn linear_axes_for(
    geom: &Geometry,
    rotary_deg: [f64; 2],
    target_w_mm: Vector3<f64>,
    errors: &dyn Fn(&Pose) -> ErrorState,
) -> Result<[f64; 3], HtmError> {
    let mut pose = Pose {
        linear_mm: [0.0; 3],
        rotary_deg,
    };
    let jq = Frames::new(geom, &pose).jq();
    let jq_inv = jq.try_inverse().unwrap_or_else(Matrix3::identity);
    let mut step_mm = f64::INFINITY;
    for _ in 0..30 {
        let tip = tip_in_workpiece_mm(geom, &pose, &errors(&pose));
        let dq = jq_inv * (target_w_mm - tip);
        for k in 0..3 {
            pose.linear_mm[k] += dq[k];
        }
        step_mm = dq.norm();
        if step_mm < 1e-10 {
            return Ok(pose.linear_mm);
        }
    }
    Err(HtmError::NoConvergence {
        rotary_deg,
        step_mm,
    })
}

/// Nominal linear axes that bring the tip to `target_w_mm` at `rotary_deg` (no errors).
#[must_use]
pub fn nominal_linear_axes(
    geom: &Geometry,
    rotary_deg: [f64; 2],
    target_w_mm: Vector3<f64>,
) -> [f64; 3] {
    let pose = Pose {
        linear_mm: [0.0; 3],
        rotary_deg,
    };
    let zero = ErrorState::default();
    let tip0 = tip_in_workpiece_mm(geom, &pose, &zero);
    let jq = Frames::new(geom, &pose).jq();
    // The nominal model is affine in q: one step is exact.
    let dq = jq.try_inverse().unwrap_or_else(Matrix3::identity) * (target_w_mm - tip0);
    [dq[0], dq[1], dq[2]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::errors::tests_support::trunnion;

    const NM: f64 = 1e-6;

    #[test]
    fn without_errors_the_probe_reads_the_nominal_centre() {
        let g = trunnion();
        let zero = |_: &Pose| ErrorState::default();
        for (c, a) in [(0.0, 0.0), (90.0, -30.0), (215.0, -90.0)] {
            let q = linear_axes_for(&g, [c, a], Vector3::zeros(), &zero).unwrap();
            let n = nominal_linear_axes(&g, [c, a], Vector3::zeros());
            for k in 0..3 {
                assert!((q[k] - n[k]).abs() < NM);
            }
        }
        // At A = C = 0 the tip meets the datum at q = datum − T.
        let q = nominal_linear_axes(&g, [0.0, 0.0], Vector3::zeros());
        assert!((q[0] - 150.0).abs() < NM && q[1].abs() < NM && (q[2] + 200.0).abs() < NM);
    }

    #[test]
    fn a_table_turned_by_c_90_carries_the_sphere_a_quarter_turn_clockwise() {
        // Workpiece-side C turns the table by −90° about z: the sphere at (150, 0) from the C
        // axis goes to (0, −150).
        let g = trunnion();
        let q = nominal_linear_axes(&g, [90.0, 0.0], Vector3::zeros());
        assert!(
            q[0].abs() < NM && (q[1] + 150.0).abs() < NM && (q[2] + 200.0).abs() < NM,
            "{q:?}"
        );
        // A = −90 turns the trunnion by +90° about x through z = −500: the sphere 150 mm above
        // the A axis goes to y = −150, z = −500.
        let q = nominal_linear_axes(&g, [0.0, -90.0], Vector3::zeros());
        assert!(
            (q[0] - 150.0).abs() < NM && (q[1] + 150.0).abs() < NM && (q[2] + 350.0).abs() < NM,
            "{q:?}"
        );
    }
}
