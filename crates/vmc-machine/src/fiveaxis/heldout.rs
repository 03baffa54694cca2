//! The held-out judge: how much of the volumetric error an identified model removes on
//! configurations that were not probed.
//!
//! Poses are drawn at random (seeded): C and A uniform over their travels, a target point in the
//! workpiece frame uniform over the table's working cylinder (radius `radius_mm` about the C
//! axis, `height_mm` above the table at C = A = 0), kept when the linear axes stay in travel.
//! At each pose:
//! - before: the controller commands the nominal linear axes; the error is the real tool tip
//!   minus the target, in the workpiece frame (the exact model with the twin's truth);
//! - after: the controller solves the exact model with the *identified* errors for the linear
//!   axes, and the real tip is measured again.
//!
//! The share characterised is `1 − mean|after| / mean|before|`. The judge reads the twin's truth
//! (as the study judged on its virtual machine); the identified model never does.

use nalgebra::Vector3;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use serde::Serialize;

use super::spec::FiveAxisSpec;
use super::truth::TrueMachine;
use vmc_identify::chain::Pose;
use vmc_identify::errors::ErrorState;
use vmc_identify::htm::tip_in_workpiece_mm;
use vmc_identify::inverse::{linear_axes_for, nominal_linear_axes, HtmError};

/// Settings of the held-out judge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeldOutPlan {
    /// Number of poses (default 500).
    pub poses: usize,
    /// Seed of the poses.
    pub seed: u64,
    /// Radius of the working cylinder about the C axis, mm (default 150).
    pub radius_mm: f64,
    /// Height of the working cylinder above the table, mm (default 100).
    pub height_mm: f64,
}

impl Default for HeldOutPlan {
    fn default() -> Self {
        HeldOutPlan {
            poses: 500,
            seed: 7,
            radius_mm: 150.0,
            height_mm: 100.0,
        }
    }
}

/// The verdict, µm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HeldOut {
    /// Poses judged.
    pub poses: usize,
    /// Mean volumetric error without compensation, µm.
    pub before_mean_um: f64,
    /// Largest volumetric error without compensation, µm.
    pub before_max_um: f64,
    /// Mean residual with the identified model, µm.
    pub after_mean_um: f64,
    /// Largest residual with the identified model, µm.
    pub after_max_um: f64,
    /// `1 − after_mean / before_mean`.
    pub characterised_share: f64,
}

/// One judged pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JudgedPose {
    /// Rotary angles, degrees, in the geometry's order.
    pub rotary_deg: [f64; 2],
    /// The target point in the workpiece frame, mm.
    pub target_w_mm: [f64; 3],
    /// Error without compensation, workpiece frame, µm.
    pub before_um: [f64; 3],
    /// Error with the identified model, workpiece frame, µm.
    pub after_um: [f64; 3],
}

/// Judges the compensation model `model` (errors as a function of the pose) on held-out poses.
///
/// # Errors
/// [`HtmError`] when the compensation cannot be solved.
pub fn judge(
    spec: &FiveAxisSpec,
    machine: &TrueMachine,
    model: &dyn Fn(&Pose) -> ErrorState,
    plan: &HeldOutPlan,
) -> Result<HeldOut, HtmError> {
    judge_poses(spec, machine, model, plan).map(|(verdict, _)| verdict)
}

/// [`judge`], with the error before and after at every pose.
///
/// # Errors
/// [`HtmError`] when the compensation cannot be solved.
pub fn judge_poses(
    spec: &FiveAxisSpec,
    machine: &TrueMachine,
    model: &dyn Fn(&Pose) -> ErrorState,
    plan: &HeldOutPlan,
) -> Result<(HeldOut, Vec<JudgedPose>), HtmError> {
    let geom = machine.geometry();
    let lim = spec.rotary_limits_deg();
    let mut rng = StdRng::seed_from_u64(plan.seed ^ 0x4e1d_0007_0000_0000);
    let table = geom
        .rotary
        .iter()
        .find(|r| r.axis.letter() == 'C')
        .map_or([0.0; 3], |r| r.point_mm);
    let datum = Vector3::from(geom.datum_mm);
    let (mut before, mut after) = (Vec::new(), Vec::new());
    let mut poses = Vec::new();
    let mut attempts = 0;
    while before.len() < plan.poses && attempts < 100 * plan.poses {
        attempts += 1;
        let mut rot = [0.0; 2];
        for (r, &(lo, hi)) in lim.iter().enumerate().take(2) {
            rot[r] = rng.random_range(lo..hi);
        }
        let rho = plan.radius_mm * rng.random::<f64>().sqrt();
        let phi = rng.random_range(0.0..std::f64::consts::TAU);
        let h = rng.random_range(0.0..plan.height_mm);
        let p0 = Vector3::new(
            table[0] + rho * phi.cos(),
            table[1] + rho * phi.sin(),
            table[2] + h,
        );
        let target = p0 - datum;
        let q_nom = nominal_linear_axes(geom, rot, target);
        if !spec.within_travel(q_nom, 0.0) {
            continue;
        }
        let real_tip = |q: [f64; 3]| {
            let pose = Pose {
                linear_mm: q,
                rotary_deg: rot,
            };
            tip_in_workpiece_mm(geom, &pose, &machine.state_at(&pose))
        };
        let e_before = (real_tip(q_nom) - target) * 1e3;
        let q_comp = linear_axes_for(geom, rot, target, model)?;
        let e_after = (real_tip(q_comp) - target) * 1e3;
        before.push(e_before.norm());
        after.push(e_after.norm());
        poses.push(JudgedPose {
            rotary_deg: rot,
            target_w_mm: target.into(),
            before_um: e_before.into(),
            after_um: e_after.into(),
        });
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let verdict = HeldOut {
        poses: before.len(),
        before_mean_um: mean(&before),
        before_max_um: max(&before),
        after_mean_um: mean(&after),
        after_max_um: max(&after),
        characterised_share: 1.0 - mean(&after) / mean(&before).max(1e-300),
    };
    Ok((verdict, poses))
}
