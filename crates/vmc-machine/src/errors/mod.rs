//! The twin's geometric error field: the 18 motion errors, 3 squareness errors
//! and 5 spindle drifts of the machine as functions of axis position and thermal-node temperature.
//!
//! Each motion error of axis j at normalised position `u = (pos − min)/(max − min)` is
//!
//! ```text
//! e(u, T) = Σ_k poly_k u^k + Σ_h A_h sin(2π c_h u + φ_h)          (static, deterministic)
//!         + spline(u; random knots ~ N(0, σ²))                    (static, seeded)
//!         + a_f [sin(2π pos/λ + φ₁) + 0.5 sin(2π pos/(0.61 λ) + φ₂)] (fine ripple, seeded)
//!         + Σ_terms gain · ΔT_eff(T) · shape(u)                   (thermal)
//! ```
//!
//! with `ΔT_eff = Σ_i w_i (T_i − T_ref)` over named thermal nodes, and `shape` constant, linear,
//! a bow `4u(1−u)`, or the ballscrew integral `∫ (T_seg(s) − T_ref) ds` from the fixed end.
//! Squareness and spindle drifts are a static value (plus a seeded offset) plus constant-shape
//! thermal terms. Values are written in µm (translations) and µrad (rotations) in the machine
//! file and converted here to the model units, mm and rad ([`ElementaryErrors`]).
//!
//! Non-repeatability and reversal are random, approach-dependent parts handled by
//! [`ApproachErrors`]; they enter as extra positioning error of each axis.
//!
//! This module is truth: only the twin and its virtual instruments read it.

pub mod spec;

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};
use thiserror::Error;

use spec::{ConstantErrorSpec, FixedEnd, ProfileSpec, ThermalShape, ThermalTermSpec, ValueUnit};
pub use spec::{ErrorFieldSpec, MOTION_NAMES, SPINDLE_NAMES, SQUARENESS_NAMES};
use vmc_predict::synthesis::{AxisErrors, ElementaryErrors};

/// A problem in the error-field part of a machine description.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ErrorSpecError {
    /// A field is missing or has a bad value.
    #[error("{field}: {msg}")]
    Field {
        /// Dotted path of the field, e.g. `errors.motion.EXX.poly[2]`.
        field: String,
        /// What is wrong.
        msg: String,
    },
}

/// A compiled thermal term.
#[derive(Debug, Clone)]
enum ThermalTerm {
    /// `gain · Σ w_i (T_i − T_ref) · shape(u)`.
    Weighted {
        shape: ThermalShape,
        gain: f64,
        nodes: Vec<(usize, f64)>,
    },
    /// Ballscrew: `sign · gain · 1e-3 · ∫ (T_seg − T_ref) ds` (gain µm/(K·m), s in mm).
    Screw {
        gain: f64,
        segments: Vec<usize>,
        fixed_end: FixedEnd,
    },
}

impl ThermalTerm {
    fn compile(spec: &ThermalTermSpec, node_index: &dyn Fn(&str) -> Option<usize>) -> Self {
        // Validation ran first, so every name resolves; a missing one is skipped defensively.
        if spec.shape == ThermalShape::Screw {
            ThermalTerm::Screw {
                gain: spec.gain(),
                segments: spec.nodes.iter().filter_map(|n| node_index(n)).collect(),
                fixed_end: spec.fixed_end,
            }
        } else {
            ThermalTerm::Weighted {
                shape: spec.shape,
                gain: spec.gain(),
                nodes: spec
                    .weights
                    .iter()
                    .filter_map(|(n, w)| node_index(n).map(|i| (i, *w)))
                    .collect(),
            }
        }
    }

    /// Value in the profile's unit at normalised position `u` over a travel of `span_mm`.
    fn eval(&self, u: f64, span_mm: f64, temps: &[f64], t_ref: f64) -> f64 {
        match self {
            ThermalTerm::Weighted { shape, gain, nodes } => {
                let dt: f64 = nodes.iter().map(|(i, w)| w * (temps[*i] - t_ref)).sum();
                let s = match shape {
                    ThermalShape::Constant => 1.0,
                    ThermalShape::Linear => u,
                    ThermalShape::Bow => 4.0 * u * (1.0 - u),
                    ThermalShape::Screw => 0.0,
                };
                gain * dt * s
            }
            ThermalTerm::Screw {
                gain,
                segments,
                fixed_end,
            } => {
                let n = segments.len() as f64;
                let seg_len_mm = span_mm / n;
                // ∫ from the travel minimum to u, segment by segment (piecewise constant).
                let integral_to = |u: f64| -> f64 {
                    let mut acc = 0.0;
                    for (k, &i) in segments.iter().enumerate() {
                        let a = k as f64 / n;
                        let b = (k + 1) as f64 / n;
                        let covered = ((u.min(b) - a) * n).clamp(0.0, 1.0);
                        acc += covered * seg_len_mm * (temps[i] - t_ref);
                    }
                    acc
                };
                match fixed_end {
                    FixedEnd::Min => gain * 1e-3 * integral_to(u),
                    // Fixed at the maximum: the nut is pushed towards the minimum.
                    FixedEnd::Max => -gain * 1e-3 * (integral_to(1.0) - integral_to(u)),
                }
            }
        }
    }
}

/// A compiled position-dependent error profile (values in its file unit, µm or µrad).
#[derive(Debug, Clone)]
struct Profile {
    scale_to_model: f64,
    poly: Vec<f64>,
    harmonics: Vec<(f64, f64, f64)>,
    knots: Vec<f64>,
    fine: Option<(f64, f64, f64, f64)>,
    thermal: Vec<ThermalTerm>,
}

fn unit_scale(unit: ValueUnit) -> f64 {
    // µm → mm and µrad → rad are both 1e-3 and 1e-6 respectively.
    match unit {
        ValueUnit::Um => 1e-3,
        ValueUnit::Urad => 1e-6,
    }
}

impl Profile {
    fn compile(
        spec: &ProfileSpec,
        node_index: &dyn Fn(&str) -> Option<usize>,
        rng: &mut StdRng,
    ) -> Self {
        // Always draw the same number of values per profile so that one profile's settings do
        // not shift the random stream of the others.
        let knots: Vec<f64> = (0..spec.random_knots.max(2))
            .map(|_| gauss(rng) * spec.random_sigma)
            .collect();
        let phases = (
            rng.random::<f64>() * std::f64::consts::TAU,
            rng.random::<f64>() * std::f64::consts::TAU,
        );
        Profile {
            scale_to_model: unit_scale(spec.unit),
            poly: spec.poly.clone(),
            harmonics: spec
                .harmonics
                .iter()
                .map(|h| (h.amplitude, h.cycles, h.phase_rad))
                .collect(),
            knots: if spec.random_sigma > 0.0 {
                knots
            } else {
                Vec::new()
            },
            fine: (spec.fine_amplitude > 0.0).then_some((
                spec.fine_amplitude,
                spec.fine_wavelength_mm,
                phases.0,
                phases.1,
            )),
            thermal: spec
                .thermal
                .iter()
                .map(|t| ThermalTerm::compile(t, node_index))
                .collect(),
        }
    }

    /// Static part in file units at normalised position u (pos_mm for the fine ripple).
    fn static_value(&self, u: f64, pos_mm: f64) -> f64 {
        let mut v = 0.0;
        for c in self.poly.iter().rev() {
            v = v * u + c;
        }
        for (a, c, p) in &self.harmonics {
            v += a * (std::f64::consts::TAU * c * u + p).sin();
        }
        if !self.knots.is_empty() {
            v += catmull_rom(&self.knots, u);
        }
        if let Some((a, lambda, p1, p2)) = self.fine {
            let w = std::f64::consts::TAU * pos_mm / lambda;
            v += a * ((w + p1).sin() + 0.5 * (w / 0.61 + p2).sin());
        }
        v
    }

    /// Full value in model units (mm or rad).
    fn eval(&self, u: f64, pos_mm: f64, span_mm: f64, temps: &[f64], t_ref: f64) -> f64 {
        let th: f64 = self
            .thermal
            .iter()
            .map(|t| t.eval(u, span_mm, temps, t_ref))
            .sum();
        (self.static_value(u, pos_mm) + th) * self.scale_to_model
    }
}

/// A compiled position-independent error (squareness or spindle drift).
#[derive(Debug, Clone)]
struct ConstantError {
    scale_to_model: f64,
    value: f64,
    thermal: Vec<ThermalTerm>,
}

impl ConstantError {
    fn compile(
        spec: &ConstantErrorSpec,
        node_index: &dyn Fn(&str) -> Option<usize>,
        rng: &mut StdRng,
    ) -> Self {
        let offset = gauss(rng) * spec.random_sigma;
        ConstantError {
            scale_to_model: unit_scale(spec.unit),
            value: spec.value + offset,
            thermal: spec
                .thermal
                .iter()
                .map(|t| ThermalTerm::compile(t, node_index))
                .collect(),
        }
    }

    fn eval(&self, temps: &[f64], t_ref: f64) -> f64 {
        let th: f64 = self
            .thermal
            .iter()
            .map(|t| t.eval(0.0, 1.0, temps, t_ref))
            .sum();
        (self.value + th) * self.scale_to_model
    }
}

fn gauss(rng: &mut StdRng) -> f64 {
    // Normal(0, 1) cannot fail to construct.
    Normal::new(0.0, 1.0).map(|n| n.sample(rng)).unwrap_or(0.0)
}

/// Uniform Catmull–Rom spline through `knots` at u = k/(n−1), clamped at the ends.
fn catmull_rom(knots: &[f64], u: f64) -> f64 {
    let n = knots.len();
    let x = u.clamp(0.0, 1.0) * (n - 1) as f64;
    let k = (x.floor() as usize).min(n - 2);
    let t = x - k as f64;
    let p = |i: isize| knots[i.clamp(0, n as isize - 1) as usize];
    let (p0, p1, p2, p3) = (
        p(k as isize - 1),
        p(k as isize),
        p(k as isize + 1),
        p(k as isize + 2),
    );
    0.5 * ((2.0 * p1)
        + (-p0 + p2) * t
        + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t * t
        + (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * t * t * t)
}

/// The compiled error field of one machine realisation (one seed).
#[derive(Debug, Clone)]
pub struct ErrorField {
    t_ref_degc: f64,
    travel_min_mm: [f64; 3],
    travel_span_mm: [f64; 3],
    motion: [[Profile; 6]; 3],
    squareness: [ConstantError; 3],
    spindle: [ConstantError; 5],
}

impl ErrorField {
    /// Compiles a validated spec for the given travels, resolving node names with `node_index`
    /// and drawing the random parts from `seed`.
    pub fn new(
        spec: &ErrorFieldSpec,
        travel_min_mm: [f64; 3],
        travel_max_mm: [f64; 3],
        node_index: &dyn Fn(&str) -> Option<usize>,
        seed: u64,
    ) -> Result<Self, ErrorSpecError> {
        spec.validate(&|n| node_index(n).is_some())?;
        let mut rng = StdRng::seed_from_u64(seed ^ 0x5eed_e770_f1e1_d000);
        let mut profile = |name: &str| -> Profile {
            // validate() guarantees presence.
            Profile::compile(&spec.motion[name], node_index, &mut rng)
        };
        let motion = MOTION_NAMES.map(|axis| axis.map(&mut profile));
        let squareness = SQUARENESS_NAMES
            .map(|n| ConstantError::compile(&spec.squareness[n], node_index, &mut rng));
        let spindle =
            SPINDLE_NAMES.map(|n| ConstantError::compile(&spec.spindle[n], node_index, &mut rng));
        let mut travel_span_mm = [0.0; 3];
        for a in 0..3 {
            travel_span_mm[a] = travel_max_mm[a] - travel_min_mm[a];
            // Also refuses NaN spans.
            if travel_span_mm[a].partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                return Err(ErrorSpecError::Field {
                    field: format!("axes.travel_max_mm[{a}]"),
                    msg: "must be greater than travel_min_mm".into(),
                });
            }
        }
        Ok(ErrorField {
            t_ref_degc: spec.ref_temp_degc,
            travel_min_mm,
            travel_span_mm,
            motion,
            squareness,
            spindle,
        })
    }

    /// Reference temperature of the static profiles, °C.
    pub fn ref_temp_degc(&self) -> f64 {
        self.t_ref_degc
    }

    /// The elementary errors of one axis at its position `pos_mm`, given node temperatures.
    pub fn axis_errors(&self, axis: usize, pos_mm: f64, temps_degc: &[f64]) -> AxisErrors {
        let span = self.travel_span_mm[axis];
        let u = ((pos_mm - self.travel_min_mm[axis]) / span).clamp(0.0, 1.0);
        let v = |c: usize| self.motion[axis][c].eval(u, pos_mm, span, temps_degc, self.t_ref_degc);
        AxisErrors {
            lin_mm: [v(0), v(1), v(2)],
            ang_rad: [v(3), v(4), v(5)],
        }
    }

    /// All 26 elementary errors at a pose, given node temperatures (no random parts).
    pub fn elementary(&self, axis_pos_mm: [f64; 3], temps_degc: &[f64]) -> ElementaryErrors {
        let t = self.t_ref_degc;
        let mut e = ElementaryErrors::default();
        for (a, &pos_mm) in axis_pos_mm.iter().enumerate() {
            e.axes[a] = self.axis_errors(a, pos_mm, temps_degc);
        }
        e.squareness.xy_rad = self.squareness[0].eval(temps_degc, t);
        e.squareness.xz_rad = self.squareness[1].eval(temps_degc, t);
        e.squareness.yz_rad = self.squareness[2].eval(temps_degc, t);
        for k in 0..3 {
            e.spindle.lin_mm[k] = self.spindle[k].eval(temps_degc, t);
        }
        e.spindle.tilt_rad = [
            self.spindle[3].eval(temps_degc, t),
            self.spindle[4].eval(temps_degc, t),
        ];
        e
    }
}

/// Approach-dependent random errors: non-repeatability and reversal, per axis.
///
/// Tracks the direction of each axis's last motion; [`ApproachErrors::positioning_mm`] gives the
/// extra positioning error (δ_jj) for a new approach, drawn from the generator it owns.
#[derive(Debug)]
pub struct ApproachErrors {
    sigma_mm: [f64; 3],
    half_reversal_mm: [f64; 3],
    last_dir: [f64; 3],
    rng: StdRng,
}

impl ApproachErrors {
    /// From the spec's per-axis random parts and a seed.
    pub fn new(spec: &ErrorFieldSpec, seed: u64) -> Self {
        ApproachErrors {
            sigma_mm: spec.random.map(|r| r.repeatability_sigma_um * 1e-3),
            half_reversal_mm: spec.random.map(|r| 0.5 * r.reversal_um * 1e-3),
            last_dir: [1.0; 3],
            rng: StdRng::seed_from_u64(seed ^ 0xa99_0ac4),
        }
    }

    /// Records motion of each axis (sign of its velocity; 0 keeps the last direction).
    pub fn note_motion(&mut self, vel: [f64; 3]) {
        for (dir, &v) in self.last_dir.iter_mut().zip(&vel) {
            if v > 0.0 {
                *dir = 1.0;
            } else if v < 0.0 {
                *dir = -1.0;
            }
        }
    }

    /// The reversal part only (no random draw), mm per axis.
    pub fn reversal_mm(&self) -> [f64; 3] {
        [0, 1, 2].map(|a| self.last_dir[a] * self.half_reversal_mm[a])
    }

    /// Draws the extra positioning error of each axis for one approach: reversal + N(0, σ²), mm.
    pub fn positioning_mm(&mut self) -> [f64; 3] {
        let rev = self.reversal_mm();
        [0, 1, 2].map(|a| rev[a] + gauss(&mut self.rng) * self.sigma_mm[a])
    }
}

#[cfg(test)]
mod tests;
