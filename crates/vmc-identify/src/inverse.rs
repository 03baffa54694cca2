//! The linear axes that bring the tool tip to a target, with the rotary axes given: what a
//! probe touching the reference sphere (the datum) at rotary angles θ reads — the `q` at which
//! `tip_in_workpiece(q, θ) = target` in the exact model ([`crate::htm`]) — and what a
//! compensating controller commands. Newton iteration with the nominal Jacobian
//! `J_q = ∂tip_w/∂q` of the first-order model ([`crate::sensitivity::Frames::jq`]). Units: mm,
//! degrees for the commanded angles.

use nalgebra::{Matrix3, Vector3};

use crate::chain::{Geometry, Pose};
use crate::errors::ErrorState;
use crate::htm::tip_in_workpiece_mm;
use crate::sensitivity::Frames;

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
