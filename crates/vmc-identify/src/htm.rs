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
//! The linear axes at which the tip sits at a target (what a probe reads) are solved in
//! [`crate::inverse`], with this model and the nominal Jacobian.

use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};

use crate::chain::{Axis, Geometry, LinearAxis, Pose};
use crate::errors::ErrorState;

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

/// The tool's axis (the spindle direction, unit vector from the tip towards the gauge point)
/// relative to the workpiece, in the workpiece frame (exact).
#[must_use]
pub fn tool_axis_in_workpiece(geom: &Geometry, pose: &Pose, state: &ErrorState) -> Vector3<f64> {
    let w = bed_from_workpiece(geom, pose, state);
    let t = bed_from_tip(geom, pose, state);
    (w.inverse() * t).rotation * Vector3::z()
}
