//! The held-out judge: how much of the volumetric error an identified model removes on
//! configurations that were not probed, over the machine's working volume.
//!
//! Poses are drawn at random (seeded): each rotary axis uniform over its travel, a target point
//! in the workpiece frame uniform over a cylinder on the table (radius `radius_mm` about the
//! table's axis, `height_mm` above the table surface at zero rotary angles), kept when the
//! linear axes stay in travel — so the judged region is the part of that cylinder the machine
//! reaches at the drawn angles. By default the cylinder is the machine's: its radius is the
//! larger half stroke of X and Y and its height half the Z stroke (a user may give another).
//! At each pose:
//! - before: the controller commands the nominal linear axes; the error is the real tool tip
//!   minus the target, in the workpiece frame (the exact model with the twin's truth);
//! - after: the controller solves the exact model with the *identified* errors for the linear
//!   axes, and the real tip is measured again.
//!
//! The share characterised is `1 − mean|after| / mean|before|`, over all poses and by region:
//! *centre* (radius ≤ half the cylinder's, lower half), *edge* (radius beyond half, lower half)
//! and *top* (upper half of the height). The judge reads the twin's truth (as the study judged on
//! its virtual machine); the identified model never does.

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
    /// Radius of the judged cylinder about the table's axis, mm (default `None`: the larger
    /// half stroke of X and Y).
    pub radius_mm: Option<f64>,
    /// Height of the judged cylinder above the table, mm (default `None`: half the Z stroke).
    pub height_mm: Option<f64>,
}

impl HeldOutPlan {
    /// The cylinder judged on `spec`: (radius, height), mm.
    #[must_use]
    pub fn region_mm(&self, spec: &FiveAxisSpec) -> (f64, f64) {
        let stroke = |i: usize| spec.axes.travel_max_mm[i] - spec.axes.travel_min_mm[i];
        (
            self.radius_mm
                .unwrap_or_else(|| 0.5 * stroke(0).max(stroke(1))),
            self.height_mm.unwrap_or_else(|| 0.5 * stroke(2)),
        )
    }
}

impl Default for HeldOutPlan {
    fn default() -> Self {
        HeldOutPlan {
            poses: 500,
            seed: 7,
            radius_mm: None,
            height_mm: None,
        }
    }
}

/// Where in the judged cylinder a pose lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Region {
    /// Radius ≤ half the cylinder's, lower half of the height.
    Centre,
    /// Radius beyond half the cylinder's, lower half of the height.
    Edge,
    /// Upper half of the height.
    Top,
}

impl Region {
    /// Every region, in report order.
    pub const ALL: [Region; 3] = [Region::Centre, Region::Edge, Region::Top];

    /// Its name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Region::Centre => "centre",
            Region::Edge => "edge",
            Region::Top => "top",
        }
    }

    fn of(rho_mm: f64, h_mm: f64, radius_mm: f64, height_mm: f64) -> Region {
        if h_mm > 0.5 * height_mm {
            Region::Top
        } else if rho_mm > 0.5 * radius_mm {
            Region::Edge
        } else {
            Region::Centre
        }
    }
}

/// The verdict over one region, µm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RegionVerdict {
    /// The region.
    pub region: Region,
    /// Poses judged in it.
    pub poses: usize,
    /// Mean volumetric error without compensation, µm.
    pub before_mean_um: f64,
    /// Mean residual with the identified model, µm.
    pub after_mean_um: f64,
    /// Largest residual with the identified model, µm.
    pub after_max_um: f64,
    /// `1 − after_mean / before_mean` (0 with no pose).
    pub characterised_share: f64,
}

/// The verdict, µm.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeldOut {
    /// The judged cylinder: radius and height, mm.
    pub region_mm: [f64; 2],
    /// By region.
    pub regions: Vec<RegionVerdict>,
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
    /// Where in the judged cylinder it lies.
    pub region: Region,
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
    let (radius_mm, height_mm) = plan.region_mm(spec);
    let (mut before, mut after) = (Vec::new(), Vec::new());
    let mut poses = Vec::new();
    let mut attempts = 0;
    while before.len() < plan.poses && attempts < 100 * plan.poses {
        attempts += 1;
        let mut rot = [0.0; 2];
        for (r, &(lo, hi)) in lim.iter().enumerate().take(2) {
            rot[r] = rng.random_range(lo..hi);
        }
        let rho = radius_mm * rng.random::<f64>().sqrt();
        let phi = rng.random_range(0.0..std::f64::consts::TAU);
        let h = rng.random_range(0.0..height_mm);
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
            region: Region::of(rho, h, radius_mm, height_mm),
        });
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let regions = Region::ALL
        .iter()
        .map(|&region| {
            let (b, a): (Vec<f64>, Vec<f64>) = poses
                .iter()
                .zip(before.iter().zip(&after))
                .filter(|(p, _)| p.region == region)
                .map(|(_, (b, a))| (*b, *a))
                .unzip();
            RegionVerdict {
                region,
                poses: b.len(),
                before_mean_um: mean(&b),
                after_mean_um: mean(&a),
                after_max_um: max(&a),
                characterised_share: if b.is_empty() {
                    0.0
                } else {
                    1.0 - mean(&a) / mean(&b).max(1e-300)
                },
            }
        })
        .collect();
    let verdict = HeldOut {
        region_mm: [radius_mm, height_mm],
        regions,
        poses: before.len(),
        before_mean_um: mean(&before),
        before_max_um: max(&before),
        after_mean_um: mean(&after),
        after_max_um: max(&after),
        characterised_share: 1.0 - mean(&after) / mean(&before).max(1e-300),
    };
    Ok((verdict, poses))
}
