//! The RC network state and its implicit-Euler integrator.

use super::sources::Source;
use super::spec::{invalid, positive, AmbientProfile, ThermalError, ThermalSpec};
use super::Activity;
use nalgebra::DMatrix;
use std::collections::HashMap;

/// Most distinct (dt, spindle speed, coolant) factorisations kept; beyond it the oldest is
/// dropped. Programs use a handful of S values, so 32 is ample; the bound keeps memory flat when
/// a caller feeds a continuously varying speed.
const CACHE_CAPACITY: usize = 32;

/// One factorised step operator: `(C/dt + K + H)⁻¹` for one convection state.
#[derive(Debug, Clone)]
struct StepOperator {
    dt_bits: u64,
    rpm_bits: u64,
    coolant: bool,
    /// Conductance to ambient per node for this state (W/K).
    ha_w_per_k: Vec<f64>,
    /// Row-major inverse of the (symmetric positive definite) step matrix.
    inverse: Vec<f64>,
}

/// A lumped RC thermal network, integrated with implicit Euler.
#[derive(Debug, Clone)]
pub struct ThermalNetwork {
    names: Vec<String>,
    index: HashMap<String, usize>,
    capacity_j_per_k: Vec<f64>,
    ha0_w_per_k: Vec<f64>,
    ha_gain_per_krpm: Vec<f64>,
    coolant_ha_w_per_k: Vec<f64>,
    /// Conductance Laplacian K (row-major, n×n): rows sum to zero.
    conductance_w_per_k: Vec<f64>,
    sources: Vec<Source>,
    ambient: AmbientProfile,
    step_s: f64,
    temps_degc: Vec<f64>,
    heat_input_w: Vec<f64>,
    rhs: Vec<f64>,
    cache: Vec<StepOperator>,
    time_s: f64,
    heat_in_j: f64,
    heat_out_j: f64,
}

impl ThermalNetwork {
    /// Builds the network from a spec (validated here) with every node at `initial_temp_degc`.
    pub fn new(spec: &ThermalSpec, initial_temp_degc: f64) -> Result<Self, ThermalError> {
        spec.validate()?;
        if !initial_temp_degc.is_finite() {
            return Err(invalid(
                "initial_temp_degc",
                "finite",
                initial_temp_degc.to_string(),
            ));
        }
        let n = spec.nodes.len();
        let map = spec.node_map()?;
        let mut k = vec![0.0; n * n];
        for l in &spec.links {
            let (a, b) = (map[l.a.as_str()], map[l.b.as_str()]);
            let g = l.conductance_w_per_k;
            k[a * n + a] += g;
            k[b * n + b] += g;
            k[a * n + b] -= g;
            k[b * n + a] -= g;
        }
        let mut sources = Vec::with_capacity(spec.sources.len());
        for (i, s) in spec.sources.iter().enumerate() {
            let compiled = Source::compile(s, &map).ok_or_else(|| ThermalError::UnknownNode {
                field: format!("thermal.sources[{i}]"),
                node: String::new(),
            })?;
            sources.push(compiled);
        }
        Ok(Self {
            names: spec.nodes.iter().map(|n| n.name.clone()).collect(),
            index: map.iter().map(|(k, v)| ((*k).to_owned(), *v)).collect(),
            capacity_j_per_k: spec.nodes.iter().map(|n| n.capacity_j_per_k).collect(),
            ha0_w_per_k: spec.nodes.iter().map(|n| n.ha_w_per_k).collect(),
            ha_gain_per_krpm: spec.nodes.iter().map(|n| n.ha_gain_per_krpm).collect(),
            coolant_ha_w_per_k: spec.nodes.iter().map(|n| n.coolant_ha_w_per_k).collect(),
            conductance_w_per_k: k,
            sources,
            ambient: spec.ambient.clone(),
            step_s: spec.step_s,
            temps_degc: vec![initial_temp_degc; n],
            heat_input_w: vec![0.0; n],
            rhs: vec![0.0; n],
            cache: Vec::new(),
            time_s: 0.0,
            heat_in_j: 0.0,
            heat_out_j: 0.0,
        })
    }

    /// Node temperatures (°C), in the order of [`Self::node_names`].
    #[must_use]
    pub fn temps_degc(&self) -> &[f64] {
        &self.temps_degc
    }

    /// Temperature (°C) of the named node, if it exists.
    #[must_use]
    pub fn temp_degc(&self, name: &str) -> Option<f64> {
        self.node_index(name).map(|i| self.temps_degc[i])
    }

    /// Index of the named node.
    #[must_use]
    pub fn node_index(&self, name: &str) -> Option<usize> {
        self.index.get(name).copied()
    }

    /// Node names, in state order.
    #[must_use]
    pub fn node_names(&self) -> &[String] {
        &self.names
    }

    /// Simulated time since construction (s).
    #[must_use]
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// Default integration step (s) used by [`Self::advance`].
    #[must_use]
    pub fn step_s(&self) -> f64 {
        self.step_s
    }

    /// Ambient profile used by [`Self::advance`].
    #[must_use]
    pub fn ambient(&self) -> &AmbientProfile {
        &self.ambient
    }

    /// Replaces the ambient profile (e.g. an atypical cycle with an ambient swing).
    pub fn set_ambient(&mut self, profile: AmbientProfile) -> Result<(), ThermalError> {
        profile.validate("ambient")?;
        self.ambient = profile;
        Ok(())
    }

    /// Ambient temperature (°C) of the profile at the current time.
    #[must_use]
    pub fn ambient_degc(&self) -> f64 {
        self.ambient.temp_degc(self.time_s)
    }

    /// Overwrites the node temperatures (°C) (e.g. a warm start); energy counters are kept.
    pub fn set_temps_degc(&mut self, temps_degc: &[f64]) -> Result<(), ThermalError> {
        if temps_degc.len() != self.temps_degc.len() {
            return Err(invalid(
                "temps_degc.len()",
                "equal to the node count",
                temps_degc.len().to_string(),
            ));
        }
        if let Some(i) = temps_degc.iter().position(|t| !t.is_finite()) {
            return Err(invalid(
                &format!("temps_degc[{i}]"),
                "finite",
                temps_degc[i].to_string(),
            ));
        }
        self.temps_degc.copy_from_slice(temps_degc);
        Ok(())
    }

    /// Heat input per node during the last step (W).
    #[must_use]
    pub fn heat_input_w(&self) -> &[f64] {
        &self.heat_input_w
    }

    /// Stored energy Σ Cᵢ·Tᵢ relative to 0 °C (J).
    #[must_use]
    pub fn stored_energy_j(&self) -> f64 {
        self.capacity_j_per_k
            .iter()
            .zip(&self.temps_degc)
            .map(|(c, t)| c * t)
            .sum()
    }

    /// Cumulative heat generated by the sources (J).
    #[must_use]
    pub fn heat_in_j(&self) -> f64 {
        self.heat_in_j
    }

    /// Cumulative heat lost to ambient by convection (J); negative if ambient heated the machine.
    #[must_use]
    pub fn heat_out_j(&self) -> f64 {
        self.heat_out_j
    }

    /// Total source power (W) each node would receive under `activity` (no state change).
    #[must_use]
    pub fn source_power_w(&self, activity: &Activity) -> Vec<f64> {
        let mut q = vec![0.0; self.names.len()];
        for s in &self.sources {
            s.add_power_w(activity, &mut q);
        }
        q
    }

    /// Advances by `duration_s` under a constant `activity`, in steps of [`Self::step_s`] (the
    /// last one shorter if needed), with ambient from the network's profile at each step's end.
    pub fn advance(&mut self, duration_s: f64, activity: &Activity) -> Result<(), ThermalError> {
        if !(duration_s.is_finite() && duration_s >= 0.0) {
            return Err(invalid("duration_s", ">= 0", duration_s.to_string()));
        }
        let end_s = self.time_s + duration_s;
        // A remainder under 1 µs is rounding, not a step worth its own factorisation.
        while end_s - self.time_s > 1e-6 {
            let dt_s = self.step_s.min(end_s - self.time_s);
            let dt_s = if end_s - self.time_s - dt_s < 1e-6 {
                end_s - self.time_s
            } else {
                dt_s
            };
            let amb = self.ambient.temp_degc(self.time_s + dt_s);
            self.step(dt_s, activity, amb)?;
        }
        Ok(())
    }

    /// One implicit-Euler step of `dt_s` with `activity` held over the step and ambient
    /// `ambient_degc`: (C/dt + K + H)·T⁺ = C/dt·T + q + H·T_amb.
    pub fn step(
        &mut self,
        dt_s: f64,
        activity: &Activity,
        ambient_degc: f64,
    ) -> Result<(), ThermalError> {
        positive("dt_s", dt_s)?;
        check_activity(activity)?;
        if !ambient_degc.is_finite() {
            return Err(invalid("ambient_degc", "finite", ambient_degc.to_string()));
        }
        self.heat_input_w.iter_mut().for_each(|q| *q = 0.0);
        for s in &self.sources {
            s.add_power_w(activity, &mut self.heat_input_w);
        }
        let op = self.operator(dt_s, activity.spindle_rpm.abs(), activity.coolant)?;
        let op = &self.cache[op];
        let n = self.names.len();
        for i in 0..n {
            self.rhs[i] = self.capacity_j_per_k[i] / dt_s * self.temps_degc[i]
                + self.heat_input_w[i]
                + op.ha_w_per_k[i] * ambient_degc;
        }
        let mut q_in_w = 0.0;
        let mut q_out_w = 0.0;
        for i in 0..n {
            let row = &op.inverse[i * n..(i + 1) * n];
            let t = dot(row, &self.rhs);
            self.temps_degc[i] = t;
            q_in_w += self.heat_input_w[i];
            q_out_w += op.ha_w_per_k[i] * (t - ambient_degc);
        }
        self.heat_in_j += q_in_w * dt_s;
        self.heat_out_j += q_out_w * dt_s;
        self.time_s += dt_s;
        Ok(())
    }

    /// Steady state (°C) under a constant `activity` and ambient: (K + H)·T = q + H·T_amb.
    pub fn steady_state_degc(
        &self,
        activity: &Activity,
        ambient_degc: f64,
    ) -> Result<Vec<f64>, ThermalError> {
        check_activity(activity)?;
        let n = self.names.len();
        let ha = self.ha_w_per_k(activity.spindle_rpm.abs(), activity.coolant);
        let q = self.source_power_w(activity);
        let mut a = DMatrix::from_row_slice(n, n, &self.conductance_w_per_k);
        let mut b = nalgebra::DVector::zeros(n);
        for i in 0..n {
            a[(i, i)] += ha[i];
            b[i] = q[i] + ha[i] * ambient_degc;
        }
        let lu = a.lu();
        lu.solve(&b)
            .map(|t| t.iter().copied().collect())
            .ok_or(ThermalError::Singular {
                dt_s: f64::INFINITY,
            })
    }

    /// Convective conductance to ambient per node (W/K) at spindle speed `rpm`.
    fn ha_w_per_k(&self, rpm: f64, coolant: bool) -> Vec<f64> {
        (0..self.names.len())
            .map(|i| {
                let forced = self.ha0_w_per_k[i] * (1.0 + self.ha_gain_per_krpm[i] * rpm / 1000.0);
                forced
                    + if coolant {
                        self.coolant_ha_w_per_k[i]
                    } else {
                        0.0
                    }
            })
            .collect()
    }

    /// Number of factorised step operators held (tests check there is no per-step factorisation).
    #[cfg(test)]
    pub(super) fn cached_operator_count(&self) -> usize {
        self.cache.len()
    }

    /// Index into the cache of the step operator for this state, factorising it if new.
    fn operator(&mut self, dt_s: f64, rpm: f64, coolant: bool) -> Result<usize, ThermalError> {
        let (dt_bits, rpm_bits) = (dt_s.to_bits(), rpm.to_bits());
        if let Some(i) = self
            .cache
            .iter()
            .position(|o| o.dt_bits == dt_bits && o.rpm_bits == rpm_bits && o.coolant == coolant)
        {
            return Ok(i);
        }
        let n = self.names.len();
        let ha = self.ha_w_per_k(rpm, coolant);
        let mut a = DMatrix::from_row_slice(n, n, &self.conductance_w_per_k);
        for i in 0..n {
            a[(i, i)] += self.capacity_j_per_k[i] / dt_s + ha[i];
        }
        // SPD: C/dt > 0 on the diagonal plus a conductance Laplacian and H ≥ 0.
        let inv = a
            .cholesky()
            .ok_or(ThermalError::Singular { dt_s })?
            .inverse();
        if self.cache.len() >= CACHE_CAPACITY {
            self.cache.remove(0);
        }
        self.cache.push(StepOperator {
            dt_bits,
            rpm_bits,
            coolant,
            ha_w_per_k: ha,
            inverse: inv.transpose().as_slice().to_vec(), // column-major → row-major
        });
        Ok(self.cache.len() - 1)
    }
}

/// Rejects non-finite activity inputs (a NaN would poison every node through the inverse).
fn check_activity(a: &Activity) -> Result<(), ThermalError> {
    if !a.spindle_rpm.is_finite() {
        return Err(invalid(
            "activity.spindle_rpm",
            "finite",
            a.spindle_rpm.to_string(),
        ));
    }
    for i in 0..3 {
        if !a.axis_pos_mm[i].is_finite() {
            return Err(invalid(
                &format!("activity.axis_pos_mm[{i}]"),
                "finite",
                a.axis_pos_mm[i].to_string(),
            ));
        }
        if !a.axis_speed_mm_per_min[i].is_finite() {
            return Err(invalid(
                &format!("activity.axis_speed_mm_per_min[{i}]"),
                "finite",
                a.axis_speed_mm_per_min[i].to_string(),
            ));
        }
    }
    Ok(())
}

/// Dot product with four independent partial sums, so the compiler can vectorise it (a plain
/// iterator sum must keep the sequential order); the order is fixed, so results are
/// deterministic.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    let mut acc = [0.0; 4];
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}
