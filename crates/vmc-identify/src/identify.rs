//! Weighted least-squares identification with an identifiability report, and its refinement
//! on the exact model.
//!
//! # Method
//! Each observation (one configuration) is the fitted centre of a sphere (the datum sphere,
//! another sphere of a calibrated artefact at a known offset from it, or a sphere relocated over
//! the table whose offset from its nominal placement is fitted with the machine's errors) in
//! linear-axis coordinates
//! `q_meas` with its covariance `Σ`; the nominal reading `q_nom` follows from the nominal
//! geometry. To first order `q_meas − q_nom = S·E + noise` ([`crate::sensitivity`]). Rows are
//! whitened by the Cholesky factor of `Σ` (`A = L⁻¹S`, `b = L⁻¹(q_meas − q_nom)`), columns
//! scaled to unit norm (so mm and rad compare), and the SVD of the stack tells the rank and the
//! condition number.
//!
//! **What the configurations cannot separate.** Parameters are taken in their set order; one
//! whose scaled column lies in the span of those already kept (residual below
//! [`IdentifyOptions::rank_tol`]) is *fixed* at 0, and its column is written as the combination
//! of kept columns that reproduces it — that relation is reported by name ("E_XT acts on the
//! readings as −1·E_Y0A: only E_Y0A − E_YT … is identified"). Kept parameters that share a
//! relation are *merged* (their value carries the combination); a parameter orthogonal to every
//! such relation is *identified*. Nothing unidentifiable is fitted to noise.
//!
//! **Uncertainty.** `cov = (AᵀA)⁻¹` over the kept parameters; the standard uncertainty is the
//! root of its diagonal. `χ² = |A·x − b|²` with `3n − p` degrees of freedom says whether the
//! residual is noise (≈ 1 per degree of freedom) or unmodelled error; in the latter case the
//! uncertainty scaled by `√(χ²/dof)` is the honest one (it treats the misfit as extra noise of
//! the same structure).
//!
//! **Refinement.** The first-order solution is refined by Gauss–Newton on the exact model
//! (readings recomputed by [`crate::inverse::linear_axes_for`], the first-order operator as the
//! Jacobian: a chord iteration, converging by a factor ~|ε| per step). The largest difference
//! between exact and first-order readings at the solution is the linearisation error.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use crate::chain::{Geometry, Pose};
use crate::errors::{Component, ParameterSet};
use crate::inverse::{linear_axes_for, HtmError};
use crate::sensitivity::probe_sensitivity;

/// One probed configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// Rotary angles, degrees ([`Geometry::rotary`] order).
    pub rotary_deg: [f64; 2],
    /// Nominal centre of the probed sphere in the workpiece frame, mm (zero for the datum
    /// sphere; another sphere of a calibrated artefact sits at its known offset).
    pub target_w_mm: [f64; 3],
    /// Nominal linear axes at the sphere centre, mm.
    pub nominal_mm: [f64; 3],
    /// Measured (fitted) sphere centre in linear-axis coordinates, mm.
    pub measured_mm: [f64; 3],
    /// Covariance of the measured centre, mm².
    pub cov_mm2: Matrix3<f64>,
    /// 0: a sphere of the calibrated artefact; k ≥ 1: the k-th placement of a relocated sphere,
    /// whose offset from `target_w_mm` is fitted with the parameters
    /// ([`crate::errors::Component::Placement`]).
    pub placement: usize,
}

/// The number of relocated-sphere placements the observations use (their highest index).
#[must_use]
pub fn placements_in(obs: &[Observation]) -> usize {
    obs.iter().map(|o| o.placement).max().unwrap_or(0)
}

/// The 3 × p sensitivity of one observation's reading: [`probe_sensitivity`] at its pose, with
/// the offsets of the other placements acting on nothing.
pub(crate) fn observation_sensitivity(
    geom: &Geometry,
    o: &Observation,
    set: &ParameterSet,
) -> DMatrix<f64> {
    let mut s = probe_sensitivity(geom, &pose_of(o), set);
    for (j, p) in set.params.iter().enumerate() {
        if let Component::Placement { placement, .. } = p.component {
            if placement != o.placement {
                s.column_mut(j).fill(0.0);
            }
        }
    }
    s
}

/// Settings of [`identify`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdentifyOptions {
    /// A scaled column whose part outside the kept columns' span is below this (relative) is
    /// not separable (default `1e-6`: a condition number beyond 10⁶ is treated as rank loss).
    pub rank_tol: f64,
    /// Gauss–Newton steps on the exact model (default 8; 0 = first order only).
    pub refine_steps: usize,
}

impl Default for IdentifyOptions {
    fn default() -> Self {
        IdentifyOptions {
            rank_tol: 1e-6,
            refine_steps: 8,
        }
    }
}

/// What became of a parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Separated from every other parameter: its value is its own.
    Identified,
    /// Kept, but its value also carries a fixed parameter's effect (see the relations).
    Merged,
    /// Not separable from the kept ones: fixed at 0.
    Fixed,
    /// No effect on any reading: fixed at 0.
    NoEffect,
}

/// One parameter's result. Values in mm or rad.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// ISO 230-7 style name.
    pub name: String,
    /// Whether the value is an angle (rad) rather than a length (mm).
    pub is_angle: bool,
    /// Estimated value (0 when fixed).
    pub value: f64,
    /// Standard uncertainty from the measurement noise (0 when fixed).
    pub std_uncertainty: f64,
    /// The same scaled by `√(χ²/dof)` when the residual exceeds the noise (unmodelled errors
    /// then dominate; the Birge ratio), else equal to it.
    pub std_uncertainty_scaled: f64,
    /// What became of it.
    pub status: Status,
}

/// A combination the configurations cannot separate: `fixed` acts on every reading exactly as
/// `Σ coefficient_k · kept_k`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Relation {
    /// The parameter fixed at 0.
    pub fixed: String,
    /// The kept parameters and coefficients that reproduce its effect.
    pub kept: Vec<(String, f64)>,
    /// The relation in words.
    pub message: String,
}

/// The result of an identification.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Identification {
    /// Number of configurations.
    pub n_configs: usize,
    /// Number of parameters asked.
    pub n_params: usize,
    /// Rank of the weighted sensitivity matrix.
    pub rank: usize,
    /// Condition number of the weighted, column-scaled S over the kept parameters.
    pub condition_number: f64,
    /// Singular values of the weighted, column-scaled S over all parameters, descending.
    pub singular_values: Vec<f64>,
    /// Every parameter, in set order.
    pub estimates: Vec<Estimate>,
    /// What cannot be separated, by name.
    pub relations: Vec<Relation>,
    /// χ² of the whitened residual (exact model after refinement).
    pub chi2: f64,
    /// Degrees of freedom `3n − rank`.
    pub dof: usize,
    /// Largest |exact − first-order| reading at the first-order solution, mm.
    pub linearisation_error_mm: f64,
    /// Largest change of a kept parameter during refinement, in units of its uncertainty.
    pub refinement_change_sigmas: f64,
    /// RMS of the reading residual after refinement, mm.
    pub rms_residual_mm: f64,
}

impl Identification {
    /// Parameter values in set order (0 for fixed ones).
    #[must_use]
    pub fn values(&self) -> Vec<f64> {
        self.estimates.iter().map(|e| e.value).collect()
    }
}

/// Why identification could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IdentifyError {
    /// Fewer readings than parameters.
    #[error("too few configurations: {n_configs} configurations give {} readings for {n_params} parameters (need at least {} configurations)", 3 * n_configs, n_params.div_ceil(3) + 1)]
    TooFewConfigurations {
        /// Configurations given.
        n_configs: usize,
        /// Parameters asked.
        n_params: usize,
    },
    /// Too few configurations to cross-validate even the smallest model.
    #[error("too few configurations to choose the model order: {n_configs} configurations in {folds} folds leave too few readings to fit the {n_params} parameters of the smallest model (need at least {needed} configurations, or a fixed order)")]
    TooFewToChooseOrder {
        /// Configurations given.
        n_configs: usize,
        /// Folds asked.
        folds: usize,
        /// Parameters of the smallest candidate.
        n_params: usize,
        /// Fewest configurations that would do.
        needed: usize,
    },
    /// A covariance that is not positive definite or a non-finite value.
    #[error("configuration {index}: {msg}")]
    BadObservation {
        /// 0-based index.
        index: usize,
        /// What is wrong.
        msg: String,
    },
    /// The exact model did not converge during refinement.
    #[error(transparent)]
    Model(#[from] HtmError),
}

/// The whitened, stacked first-order system `A·E ≈ b`.
pub(crate) struct System {
    pub a: DMatrix<f64>,
    pub b: DVector<f64>,
    /// Whitening factor `L⁻¹` of each observation.
    pub whiten: Vec<Matrix3<f64>>,
}

pub(crate) fn pose_of(o: &Observation) -> Pose {
    Pose {
        linear_mm: o.nominal_mm,
        rotary_deg: o.rotary_deg,
    }
}

pub(crate) fn build_system(
    geom: &Geometry,
    set: &ParameterSet,
    obs: &[Observation],
) -> Result<System, IdentifyError> {
    let n = obs.len();
    let p = set.len();
    let mut a = DMatrix::zeros(3 * n, p);
    let mut b = DVector::zeros(3 * n);
    let mut whiten = Vec::with_capacity(n);
    for (i, o) in obs.iter().enumerate() {
        let finite = o
            .rotary_deg
            .iter()
            .chain(&o.nominal_mm)
            .chain(&o.measured_mm)
            .all(|v| v.is_finite());
        if !finite {
            return Err(IdentifyError::BadObservation {
                index: i,
                msg: "a value is not finite".into(),
            });
        }
        let chol = o
            .cov_mm2
            .cholesky()
            .ok_or_else(|| IdentifyError::BadObservation {
                index: i,
                msg: "covariance is not positive definite".into(),
            })?;
        let l_inv = chol
            .l()
            .try_inverse()
            .ok_or_else(|| IdentifyError::BadObservation {
                index: i,
                msg: "covariance is singular".into(),
            })?;
        let s = observation_sensitivity(geom, o, set);
        a.view_mut((3 * i, 0), (3, p)).copy_from(&(l_inv * s));
        let y = Vector3::from(o.measured_mm) - Vector3::from(o.nominal_mm);
        b.fixed_rows_mut::<3>(3 * i).copy_from(&(l_inv * y));
        whiten.push(l_inv);
    }
    Ok(System { a, b, whiten })
}

/// Which parameters to keep (greedy, in set order) and the relations of the others.
pub(crate) struct Selection {
    pub kept: Vec<usize>,
    pub status: Vec<Status>,
    pub relations: Vec<Relation>,
    pub scale: Vec<f64>,
}

fn fmt_coef(c: f64) -> String {
    format!("{c:+.4}")
}

pub(crate) fn select(a: &DMatrix<f64>, set: &ParameterSet, tol: f64) -> Selection {
    let p = a.ncols();
    let names = set.names();
    let scale: Vec<f64> = (0..p).map(|j| a.column(j).norm()).collect();
    let max_scale = scale.iter().cloned().fold(0.0, f64::max);
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let mut kept = Vec::new();
    let mut status = vec![Status::Identified; p];
    let mut fixed = Vec::new();
    for j in 0..p {
        if scale[j] <= 1e-12 * max_scale.max(1e-300) {
            status[j] = Status::NoEffect;
            continue;
        }
        let mut r = a.column(j) / scale[j];
        for q in &basis {
            let d = q.dot(&r);
            r -= q * d;
        }
        // Second pass of Gram–Schmidt for accuracy.
        for q in &basis {
            let d = q.dot(&r);
            r -= q * d;
        }
        let nr = r.norm();
        if nr < tol {
            status[j] = Status::Fixed;
            fixed.push(j);
        } else {
            basis.push(r / nr);
            kept.push(j);
        }
    }
    let mut relations = Vec::new();
    if !fixed.is_empty() {
        let ak = DMatrix::from_fn(a.nrows(), kept.len(), |r, c| a[(r, kept[c])]);
        let svd = ak.svd(true, true);
        for &f in &fixed {
            let coef = svd
                .solve(&a.column(f).into_owned(), 1e-14)
                .unwrap_or_else(|_| DVector::zeros(kept.len()));
            let mut terms = Vec::new();
            for (c, &k) in kept.iter().enumerate() {
                // Ignore contributions below 1e-6 of the fixed column's effect.
                if (coef[c] * scale[k]).abs() > 1e-6 * scale[f] {
                    terms.push((names[k].clone(), coef[c]));
                    status[k] = Status::Merged;
                }
            }
            let message =
                relation_message(&names[f], set.params[f].component.is_angle(), &terms, set);
            relations.push(Relation {
                fixed: names[f].clone(),
                kept: terms,
                message,
            });
        }
    }
    Selection {
        kept,
        status,
        relations,
        scale,
    }
}

fn relation_message(
    fixed: &str,
    fixed_angle: bool,
    terms: &[(String, f64)],
    set: &ParameterSet,
) -> String {
    let unit = |name: &str| {
        let angle = set
            .params
            .iter()
            .find(|p| p.name() == name)
            .is_some_and(|p| p.component.is_angle());
        match (angle, fixed_angle) {
            (false, true) => " mm/rad",
            (true, false) => " rad/mm",
            _ => "",
        }
    };
    match terms {
        [] => format!("{fixed} has no effect that the kept parameters do not already have: fixed at 0"),
        [(k, c)] if (c.abs() - 1.0).abs() < 1e-6 => {
            let what = if *c > 0.0 { "sum" } else { "difference" };
            let op = if *c > 0.0 { "+" } else { "−" };
            format!("{k} and {fixed} move the readings together: only their {what} {k} {op} {fixed} is identified ({fixed} fixed at 0)")
        }
        [(k, c)] => format!(
            "{fixed} acts on the readings as {}{} · {k}: only {k} + ({}{}) · {fixed} is identified ({fixed} fixed at 0)",
            fmt_coef(*c),
            unit(k),
            fmt_coef(*c),
            unit(k),
        ),
        _ => {
            let parts: Vec<String> = terms
                .iter()
                .map(|(k, c)| format!("{}{} · {k}", fmt_coef(*c), unit(k)))
                .collect();
            format!(
                "{fixed} acts on the readings as {}: it cannot be separated from them ({fixed} fixed at 0, they carry its effect)",
                parts.join(" ")
            )
        }
    }
}

/// Identifies the parameters of `set` from the observations (see the module doc).
///
/// # Errors
/// [`IdentifyError`] for too few configurations, a bad covariance, or an exact model that does
/// not converge.
pub fn identify(
    geom: &Geometry,
    set: &ParameterSet,
    obs: &[Observation],
    opts: &IdentifyOptions,
) -> Result<Identification, IdentifyError> {
    let n = obs.len();
    let p = set.len();
    if 3 * n <= p {
        return Err(IdentifyError::TooFewConfigurations {
            n_configs: n,
            n_params: p,
        });
    }
    let sys = build_system(geom, set, obs)?;
    let sel = select(&sys.a, set, opts.rank_tol);
    let scaled_all = DMatrix::from_fn(sys.a.nrows(), p, |r, c| {
        if sel.scale[c] > 0.0 {
            sys.a[(r, c)] / sel.scale[c]
        } else {
            0.0
        }
    });
    let mut singular_values: Vec<f64> = scaled_all.singular_values().iter().copied().collect();
    singular_values.sort_by(|a, b| b.total_cmp(a));
    let k = sel.kept.len();
    let ak = DMatrix::from_fn(sys.a.nrows(), k, |r, c| {
        sys.a[(r, sel.kept[c])] / sel.scale[sel.kept[c]]
    });
    let svd = ak.clone().svd(true, true);
    let sv = &svd.singular_values;
    let (smax, smin) = sv
        .iter()
        .fold((0.0_f64, f64::INFINITY), |(a, b), &s| (a.max(s), b.min(s)));
    let v_t = svd.v_t.clone().expect("SVD asked with V");
    let u = svd.u.clone().expect("SVD asked with U");
    // Least squares in scaled coordinates: x_s = V Σ⁻¹ Uᵀ b; cov_s = V Σ⁻² Vᵀ.
    let solve = |rhs: &DVector<f64>| -> DVector<f64> {
        let mut t = u.transpose() * rhs;
        for i in 0..t.len() {
            t[i] /= sv[i];
        }
        v_t.transpose() * t
    };
    let mut cov_s = DMatrix::zeros(k, k);
    for i in 0..k {
        let vi = v_t.row(i).transpose();
        cov_s += &vi * vi.transpose() / (sv[i] * sv[i]);
    }
    let u_std: Vec<f64> = (0..k)
        .map(|c| cov_s[(c, c)].sqrt() / sel.scale[sel.kept[c]])
        .collect();
    let to_full = |xs: &DVector<f64>| -> Vec<f64> {
        let mut v = vec![0.0; p];
        for (c, &j) in sel.kept.iter().enumerate() {
            v[j] = xs[c] / sel.scale[j];
        }
        v
    };
    let x_lin = to_full(&solve(&sys.b));
    // Refinement on the exact model.
    let exact_readings = |values: &[f64]| -> Result<Vec<[f64; 3]>, HtmError> {
        obs.iter()
            .map(|o| {
                let offset = Vector3::from(set.placement_offset_mm(values, o.placement));
                linear_axes_for(
                    geom,
                    o.rotary_deg,
                    Vector3::from(o.target_w_mm) + offset,
                    &|pose: &Pose| set.state_at(values, pose),
                )
            })
            .collect()
    };
    let whitened_residual = |readings: &[[f64; 3]]| -> DVector<f64> {
        let mut r = DVector::zeros(3 * n);
        for (i, o) in obs.iter().enumerate() {
            let d = Vector3::from(o.measured_mm) - Vector3::from(readings[i]);
            r.fixed_rows_mut::<3>(3 * i).copy_from(&(sys.whiten[i] * d));
        }
        r
    };
    let first = exact_readings(&x_lin)?;
    let mut lin_err: f64 = 0.0;
    let x_vec = DVector::from_vec(x_lin.clone());
    for (i, o) in obs.iter().enumerate() {
        let s = observation_sensitivity(geom, o, set);
        let q1 = Vector3::from(o.nominal_mm) + s * &x_vec;
        lin_err = lin_err.max((Vector3::from(first[i]) - q1).norm());
    }
    let mut x = x_lin.clone();
    let mut readings = first;
    for _ in 0..opts.refine_steps {
        let r = whitened_residual(&readings);
        let step = to_full(&solve(&r));
        let small = step
            .iter()
            .zip(&x)
            .all(|(s, v)| s.abs() <= 1e-13 * v.abs().max(1e-9));
        for (v, s) in x.iter_mut().zip(&step) {
            *v += s;
        }
        readings = exact_readings(&x)?;
        if small {
            break;
        }
    }
    let r = whitened_residual(&readings);
    let chi2 = r.norm_squared();
    let mut change: f64 = 0.0;
    for (c, &j) in sel.kept.iter().enumerate() {
        if u_std[c] > 0.0 {
            change = change.max((x[j] - x_lin[j]).abs() / u_std[c]);
        }
    }
    let rms = (obs
        .iter()
        .zip(&readings)
        .map(|(o, q)| (Vector3::from(o.measured_mm) - Vector3::from(*q)).norm_squared())
        .sum::<f64>()
        / (3 * n) as f64)
        .sqrt();
    let mut ustd_full = vec![0.0; p];
    for (c, &j) in sel.kept.iter().enumerate() {
        ustd_full[j] = u_std[c];
    }
    let names = set.names();
    let dof = 3 * n - k;
    let birge = (chi2 / dof.max(1) as f64).sqrt().max(1.0);
    let estimates = (0..p)
        .map(|j| Estimate {
            name: names[j].clone(),
            is_angle: set.params[j].component.is_angle(),
            value: x[j],
            std_uncertainty: ustd_full[j],
            std_uncertainty_scaled: ustd_full[j] * birge,
            status: sel.status[j],
        })
        .collect();
    Ok(Identification {
        n_configs: n,
        n_params: p,
        rank: k,
        condition_number: if smin > 0.0 {
            smax / smin
        } else {
            f64::INFINITY
        },
        singular_values,
        estimates,
        relations: sel.relations,
        chi2,
        dof,
        linearisation_error_mm: lin_err,
        refinement_change_sigmas: change,
        rms_residual_mm: rms,
    })
}

#[cfg(test)]
#[path = "identify_tests.rs"]
pub(crate) mod tests;
