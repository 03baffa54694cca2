//! The five-axis machine's truth: every error as a function of the pose, drawn once per seed.
//!
//! Linear axes: the three-axis error field ([`crate::errors::ErrorField`], static part only).
//! Rotary axes: each motion error is `Σ_k (a_k cos kθ + b_k sin kθ)` over deterministic and
//! seeded harmonics (orders ≥ 2, and ≥ 1 for the angular positioning error), θ the commanded
//! angle. Location and assembly errors: value + seeded offset. Units converted from µm/µrad to
//! mm/rad. The exact model that turns this state into a tool-tip position is the knowledge
//! side's [`vmc_identify::htm`], as the three-axis twin uses `vmc_predict::synthesis`.
//!
//! This module is truth: only the twin's virtual instruments and the held-out judge read it.

use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

use super::spec::{
    location_names, motion_names, ConstantSpec, FiveAxisSpec, RotaryProfileSpec, ASSEMBLY_NAMES,
};
use crate::errors::spec::ValueUnit;
use crate::errors::ErrorField;
use crate::machine::MachineError;
use vmc_identify::chain::{Geometry, Pose};
use vmc_identify::errors::{ErrorState, SixErrors};

fn to_model(unit: ValueUnit) -> f64 {
    match unit {
        ValueUnit::Um => 1e-3,
        ValueUnit::Urad => 1e-6,
    }
}

/// One rotary motion error: harmonic coefficients in model units.
#[derive(Debug, Clone, PartialEq)]
struct RotaryProfile {
    /// `(order, cos coefficient, sin coefficient)`.
    terms: Vec<(u32, f64, f64)>,
}

impl RotaryProfile {
    fn compile(spec: &RotaryProfileSpec, first_order: u32, rng: &mut StdRng) -> Self {
        let k = to_model(spec.unit);
        let mut terms: Vec<(u32, f64, f64)> = spec
            .harmonics
            .iter()
            .map(|h| {
                (
                    h.order,
                    k * h.amplitude * h.phase_rad.cos(),
                    k * h.amplitude * h.phase_rad.sin(),
                )
            })
            .collect();
        if spec.random_sigma > 0.0 {
            let n = Normal::new(0.0, spec.random_sigma * k).expect("σ validated");
            for order in first_order..=spec.random_orders {
                terms.push((order, n.sample(rng), n.sample(rng)));
            }
        }
        RotaryProfile { terms }
    }

    fn eval(&self, theta_rad: f64) -> f64 {
        self.terms
            .iter()
            .map(|&(k, a, b)| {
                let (s, c) = (f64::from(k) * theta_rad).sin_cos();
                a * c + b * s
            })
            .sum()
    }
}

fn constant(c: &ConstantSpec, rng: &mut StdRng) -> f64 {
    let k = to_model(c.unit);
    let offset = if c.random_sigma > 0.0 {
        Normal::new(0.0, c.random_sigma)
            .expect("σ validated")
            .sample(rng)
    } else {
        0.0
    };
    k * (c.value + offset)
}

/// One realisation of a five-axis machine (its errors drawn from `seed`).
#[derive(Debug, Clone)]
pub struct TrueMachine {
    geom: Geometry,
    linear: ErrorField,
    rotary_motion: Vec<[RotaryProfile; 6]>,
    location: Vec<SixErrors>,
    workpiece_mm: [f64; 3],
    tool_mm: [f64; 3],
    seed: u64,
}

/// How far (σ per axis) a relocated sphere really sits from where it was meant to be put, mm:
/// a sphere bolted down by eye on a stem of nominal length.
pub const PLACEMENT_SIGMA_MM: f64 = 0.2;

impl TrueMachine {
    /// Compiles a validated spec with the random parts drawn from `seed`.
    ///
    /// # Errors
    /// An invalid linear error field (already checked by validation).
    pub fn new(spec: &FiveAxisSpec, seed: u64) -> Result<Self, MachineError> {
        let geom = spec.geometry();
        let linear = ErrorField::new(
            &spec.linear_errors,
            spec.axes.travel_min_mm,
            spec.axes.travel_max_mm,
            &|_| None,
            seed,
        )
        .map_err(|e| MachineError::Invalid {
            path: spec.machine.name.clone(),
            field: "linear_errors".into(),
            msg: e.to_string(),
        })?;
        let mut rng = StdRng::seed_from_u64(seed ^ 0x0f1e_a715_7a61_e000);
        let mut rotary_motion = Vec::new();
        let mut location = Vec::new();
        for r in &geom.rotary {
            let l = r.axis.letter();
            let errs = &spec.rotary_errors[&l.to_string()];
            let names = motion_names(l);
            let profiles = std::array::from_fn(|c| {
                let first = if c == 3 + r.axis.index() { 1 } else { 2 };
                RotaryProfile::compile(&errs.motion[&names[c]], first, &mut rng)
            });
            rotary_motion.push(profiles);
            let mut loc = SixErrors::default();
            for (c, n) in location_names(r.axis) {
                *loc.get_mut(c) = constant(&errs.location[&n], &mut rng);
            }
            location.push(loc);
        }
        let asm: Vec<f64> = ASSEMBLY_NAMES
            .iter()
            .map(|n| constant(&spec.assembly[*n], &mut rng))
            .collect();
        Ok(TrueMachine {
            geom,
            linear,
            rotary_motion,
            location,
            workpiece_mm: [asm[0], asm[1], asm[2]],
            tool_mm: [asm[3], asm[4], asm[5]],
            seed,
        })
    }

    /// Where the sphere of placement `placement` really sits relative to its nominal centre, in
    /// the workpiece frame, mm: zero for placement 0 (the calibrated artefact), else drawn with
    /// σ = [`PLACEMENT_SIGMA_MM`] from the realisation's seed and the placement alone (so adding
    /// placements changes no other draw).
    #[must_use]
    pub fn placement_offset_mm(&self, placement: usize) -> [f64; 3] {
        if placement == 0 {
            return [0.0; 3];
        }
        let mut rng = StdRng::seed_from_u64(
            self.seed ^ 0x0005_1ace_0000_0000 ^ (placement as u64).wrapping_mul(0x9e37_79b9),
        );
        let n = Normal::new(0.0, PLACEMENT_SIGMA_MM).expect("σ > 0");
        [n.sample(&mut rng), n.sample(&mut rng), n.sample(&mut rng)]
    }

    /// The nominal geometry.
    #[must_use]
    pub fn geometry(&self) -> &Geometry {
        &self.geom
    }

    /// Every error acting at `pose`.
    #[must_use]
    pub fn state_at(&self, pose: &Pose) -> ErrorState {
        let lin = self.linear.elementary(pose.linear_mm, &[]);
        let mut s = ErrorState::default();
        for k in 0..3 {
            s.linear[k] = SixErrors {
                lin_mm: lin.axes[k].lin_mm,
                ang_rad: lin.axes[k].ang_rad,
            };
        }
        s.squareness_rad = [
            lin.squareness.xy_rad,
            lin.squareness.xz_rad,
            lin.squareness.yz_rad,
        ];
        for (r, profiles) in self.rotary_motion.iter().enumerate() {
            let th = pose.rotary_deg[r].to_radians();
            for (c, p) in profiles.iter().enumerate() {
                *s.rotary_motion[r].get_mut(c) = p.eval(th);
            }
            s.rotary_location[r] = self.location[r];
        }
        s.workpiece_mm = self.workpiece_mm;
        s.tool_mm = self.tool_mm;
        s
    }
}
