//! Serde description of a thermal network (the `[thermal]` table of a machine file) and its
//! validation.
//!
//! Every field carries its unit in its name. [`ThermalSpec::validate`] checks the whole
//! description once and reports the first bad field by its path in the machine file, e.g.
//! `thermal.nodes[3].capacity_j_per_k must be > 0, got -5`.

use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use thiserror::Error;

/// Name a sensor uses to read the prescribed ambient temperature; reserved, not a node name.
pub const AMBIENT_NODE: &str = "ambient";

/// Errors found while validating or building a thermal network.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ThermalError {
    /// A numeric field is out of its allowed range.
    #[error("{field} must be {requirement}, got {got}")]
    InvalidValue {
        /// Path of the field in the machine file, e.g. `thermal.nodes[3].capacity_j_per_k`.
        field: String,
        /// What the value must satisfy, e.g. `> 0`.
        requirement: &'static str,
        /// The offending value, formatted.
        got: String,
    },
    /// A field names a node that the network does not define.
    #[error("{field} names unknown node `{node}`")]
    UnknownNode {
        /// Path of the field in the machine file.
        field: String,
        /// The unknown node name.
        node: String,
    },
    /// Two nodes share one name (or a node uses the reserved name `ambient`).
    #[error("{field} = `{name}` is a duplicate or reserved node name")]
    DuplicateNode {
        /// Path of the second occurrence.
        field: String,
        /// The repeated name.
        name: String,
    },
    /// More nodes than the work limit (see [`max_nodes`]).
    #[error(
        "thermal.nodes: {nodes} nodes, more than the limit of {limit} (the work of a thermal \
         step grows with the cube of the node count: 1,000 nodes simulate a 1-minute program in \
         about a second, 3,000 in over a minute); merge nodes, or set the environment variable \
         {MAX_NODES_ENV} to a larger limit"
    )]
    TooManyNodes {
        /// Nodes in the file.
        nodes: usize,
        /// The limit in force.
        limit: usize,
    },
    /// The network matrix could not be factorised (should not happen for a validated spec).
    #[error("thermal network matrix is not positive definite (dt_s = {dt_s})")]
    Singular {
        /// Step for which the factorisation failed.
        dt_s: f64,
    },
}

/// Default bound of the nodes of a thermal network (see [`max_nodes`]).
pub const DEFAULT_MAX_NODES: usize = 1000;

/// Environment variable that raises (or lowers) the node bound.
pub const MAX_NODES_ENV: &str = "VMC_TWIN_MAX_THERMAL_NODES";

/// The node bound in force: [`MAX_NODES_ENV`] if it holds a whole number, else
/// [`DEFAULT_MAX_NODES`].
pub fn max_nodes() -> usize {
    std::env::var(MAX_NODES_ENV)
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(DEFAULT_MAX_NODES)
}

/// One lumped thermal mass.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeSpec {
    /// Node name; the contract by which errors and sensors refer to the node.
    pub name: String,
    /// Heat capacity m·c (J/K), > 0.
    pub capacity_j_per_k: f64,
    /// Convective conductance to ambient at rest, h·A (W/K), ≥ 0 (default `0.0`).
    #[serde(default)]
    pub ha_w_per_k: f64,
    /// Forced-convection gain with spindle speed: hA(n) = hA0·(1 + gain·n/1000) (per 1000 rpm),
    /// ≥ 0 (default `0.0`: no dependence on spindle speed).
    #[serde(default)]
    pub ha_gain_per_krpm: f64,
    /// Extra conductance to ambient while coolant flows (coolant held at ambient) (W/K), ≥ 0
    /// (default `0.0`).
    #[serde(default)]
    pub coolant_ha_w_per_k: f64,
}

/// A conductive link between two nodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkSpec {
    /// First node name.
    pub a: String,
    /// Second node name.
    pub b: String,
    /// Thermal conductance k·A/L (W/K), > 0.
    pub conductance_w_per_k: f64,
}

/// Linear machine axis, the index into [`super::Activity`] arrays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// X axis (index 0).
    X,
    /// Y axis (index 1).
    Y,
    /// Z axis (index 2).
    Z,
}

impl Axis {
    /// Index of the axis in `[x, y, z]` arrays.
    #[must_use]
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// A heat source, driven by what the program does (spindle speed, axis feeds).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum HeatSourceSpec {
    /// Spindle bearing friction H = 1.047e-4·n·M (W), M = torque_n_mm + torque_per_krpm_n_mm·n/1000.
    SpindleBearing {
        /// Node receiving the heat.
        node: String,
        /// Load-independent friction torque M0 (N·mm), ≥ 0.
        torque_n_mm: f64,
        /// Viscous growth of the friction torque per 1000 rpm (N·mm), ≥ 0 (default `0.0`).
        #[serde(default)]
        torque_per_krpm_n_mm: f64,
    },
    /// Spindle motor losses P = 1000·M·n/(9550·η)·(1−η) (W), M = torque_n_m + torque_per_krpm_n_m·n/1000.
    SpindleMotor {
        /// Node receiving the heat.
        node: String,
        /// Shaft torque at zero speed (N·m), ≥ 0.
        torque_n_m: f64,
        /// Growth of the shaft torque (drag) per 1000 rpm (N·m), ≥ 0 (default `0.0`).
        #[serde(default)]
        torque_per_krpm_n_m: f64,
        /// Motor efficiency η, in (0, 1].
        efficiency: f64,
    },
    /// Axis servo-motor losses P = standstill + 1000·M·n/(9550·η)·(1−η) (W), n = |v|/lead (rpm).
    AxisMotor {
        /// Node receiving the heat.
        node: String,
        /// Driven axis.
        axis: Axis,
        /// Ballscrew lead (mm/rev), > 0.
        lead_mm: f64,
        /// Friction torque the motor works against (N·m), ≥ 0.
        torque_n_m: f64,
        /// Motor efficiency η, in (0, 1].
        efficiency: f64,
        /// Holding losses while the axis is enabled and still (W), ≥ 0 (default `0.0`).
        #[serde(default)]
        standstill_w: f64,
    },
    /// Screw support (end) bearing friction H = 1.047e-4·n·M (W), n = |v|/lead (rpm).
    ScrewBearing {
        /// Node receiving the heat.
        node: String,
        /// Driven axis.
        axis: Axis,
        /// Ballscrew lead (mm/rev), > 0.
        lead_mm: f64,
        /// Bearing friction torque (N·mm), ≥ 0.
        torque_n_mm: f64,
    },
    /// Ballscrew nut friction H = 1.047e-4·n·M (W), n = |v|/lead, deposited into the screw
    /// segment under the nut at the current axis position (segments listed from `travel_min_mm`
    /// to `travel_max_mm`, equal lengths).
    BallscrewNut {
        /// Driven axis.
        axis: Axis,
        /// Screw segment nodes, ordered along the travel.
        segments: Vec<String>,
        /// Axis position at the start of the first segment (mm).
        travel_min_mm: f64,
        /// Axis position at the end of the last segment (mm), > `travel_min_mm`.
        travel_max_mm: f64,
        /// Ballscrew lead (mm/rev), > 0.
        lead_mm: f64,
        /// Nut preload friction torque (N·mm), ≥ 0.
        torque_n_mm: f64,
    },
    /// Guideway friction P = F·|v| (W), v converted from mm/min to m/s.
    GuideFriction {
        /// Node receiving the heat.
        node: String,
        /// Driven axis.
        axis: Axis,
        /// Friction force of the carriages (N), ≥ 0.
        friction_force_n: f64,
    },
    /// Constant heat input (electronics, hydraulics) (W).
    Constant {
        /// Node receiving the heat.
        node: String,
        /// Power (W), ≥ 0.
        power_w: f64,
    },
}

/// Prescribed ambient temperature as a function of time (a boundary, not a state).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum AmbientProfile {
    /// Constant temperature.
    Constant {
        /// Temperature (°C).
        temp_degc: f64,
    },
    /// T(t) = mean + amplitude·sin(2π·t/period + phase).
    Sinusoid {
        /// Mean temperature (°C).
        mean_degc: f64,
        /// Amplitude of the swing (°C), ≥ 0.
        amplitude_degc: f64,
        /// Period (s), > 0 (a day is 86400).
        period_s: f64,
        /// Phase (rad) (default `0.0`).
        #[serde(default)]
        phase_rad: f64,
    },
    /// Piecewise-linear through `(time_s, temp_degc)` points with strictly increasing times;
    /// held constant before the first and after the last point.
    Table {
        /// The `[time_s, temp_degc]` points.
        points: Vec<[f64; 2]>,
    },
}

impl Default for AmbientProfile {
    fn default() -> Self {
        AmbientProfile::Constant { temp_degc: 20.0 }
    }
}

impl AmbientProfile {
    /// Ambient temperature (°C) at simulation time `time_s`.
    #[must_use]
    pub fn temp_degc(&self, time_s: f64) -> f64 {
        match self {
            AmbientProfile::Constant { temp_degc } => *temp_degc,
            AmbientProfile::Sinusoid {
                mean_degc,
                amplitude_degc,
                period_s,
                phase_rad,
            } => {
                mean_degc
                    + amplitude_degc * (std::f64::consts::TAU * time_s / period_s + phase_rad).sin()
            }
            AmbientProfile::Table { points } => table_lookup(points, time_s),
        }
    }

    /// Checks the profile; `field` is its path in the machine file.
    pub fn validate(&self, field: &str) -> Result<(), ThermalError> {
        match self {
            AmbientProfile::Constant { temp_degc } => {
                finite(&format!("{field}.temp_degc"), *temp_degc)
            }
            AmbientProfile::Sinusoid {
                mean_degc,
                amplitude_degc,
                period_s,
                phase_rad,
            } => {
                finite(&format!("{field}.mean_degc"), *mean_degc)?;
                non_negative(&format!("{field}.amplitude_degc"), *amplitude_degc)?;
                positive(&format!("{field}.period_s"), *period_s)?;
                finite(&format!("{field}.phase_rad"), *phase_rad)
            }
            AmbientProfile::Table { points } => {
                if points.is_empty() {
                    return Err(invalid(
                        &format!("{field}.points"),
                        "non-empty",
                        "[]".into(),
                    ));
                }
                for (i, p) in points.iter().enumerate() {
                    finite(&format!("{field}.points[{i}][0]"), p[0])?;
                    finite(&format!("{field}.points[{i}][1]"), p[1])?;
                    if i > 0 && p[0] <= points[i - 1][0] {
                        return Err(invalid(
                            &format!("{field}.points[{i}][0]"),
                            "> the previous point's time",
                            p[0].to_string(),
                        ));
                    }
                }
                Ok(())
            }
        }
    }
}

fn table_lookup(points: &[[f64; 2]], time_s: f64) -> f64 {
    let (Some(first), Some(last)) = (points.first(), points.last()) else {
        return f64::NAN;
    };
    if time_s <= first[0] {
        return first[1];
    }
    if time_s >= last[0] {
        return last[1];
    }
    let i = points.partition_point(|p| p[0] <= time_s);
    let (p0, p1) = (points[i - 1], points[i]);
    p0[1] + (p1[1] - p0[1]) * (time_s - p0[0]) / (p1[0] - p0[0])
}

fn default_step_s() -> f64 {
    1.0
}

/// The whole thermal network: nodes, conductive links, heat sources, ambient and time step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalSpec {
    /// Integration step (s), > 0 (default `1.0`: far below the fastest time constant of interest).
    #[serde(default = "default_step_s")]
    pub step_s: f64,
    /// Ambient profile used by [`super::ThermalNetwork::advance`] (default constant 20 °C).
    #[serde(default)]
    pub ambient: AmbientProfile,
    /// Thermal masses.
    pub nodes: Vec<NodeSpec>,
    /// Conductive links between nodes.
    #[serde(default)]
    pub links: Vec<LinkSpec>,
    /// Heat sources.
    #[serde(default)]
    pub sources: Vec<HeatSourceSpec>,
}

impl ThermalSpec {
    /// Checks every field; the error names the first bad one by its path under `thermal.`.
    pub fn validate(&self) -> Result<(), ThermalError> {
        // Bounded so that no thermal advance loops for ever (1e-300 s) or skips the dynamics.
        if !(self.step_s.is_finite() && (1e-3..=3600.0).contains(&self.step_s)) {
            return Err(invalid(
                "thermal.step_s",
                "in [0.001, 3600] s",
                format!("{:e}", self.step_s),
            ));
        }
        self.ambient.validate("thermal.ambient")?;
        if self.nodes.is_empty() {
            return Err(invalid("thermal.nodes", "non-empty", "[]".into()));
        }
        let limit = max_nodes();
        if self.nodes.len() > limit {
            return Err(ThermalError::TooManyNodes {
                nodes: self.nodes.len(),
                limit,
            });
        }
        let index = self.node_map()?;
        for (i, n) in self.nodes.iter().enumerate() {
            let f = format!("thermal.nodes[{i}]");
            positive(&format!("{f}.capacity_j_per_k"), n.capacity_j_per_k)?;
            non_negative(&format!("{f}.ha_w_per_k"), n.ha_w_per_k)?;
            non_negative(&format!("{f}.ha_gain_per_krpm"), n.ha_gain_per_krpm)?;
            non_negative(&format!("{f}.coolant_ha_w_per_k"), n.coolant_ha_w_per_k)?;
        }
        for (i, l) in self.links.iter().enumerate() {
            let f = format!("thermal.links[{i}]");
            known(&index, &format!("{f}.a"), &l.a)?;
            known(&index, &format!("{f}.b"), &l.b)?;
            if l.a == l.b {
                return Err(invalid(
                    &format!("{f}.b"),
                    "a node other than `a`",
                    l.b.clone(),
                ));
            }
            positive(&format!("{f}.conductance_w_per_k"), l.conductance_w_per_k)?;
        }
        for (i, s) in self.sources.iter().enumerate() {
            validate_source(&index, &format!("thermal.sources[{i}]"), s)?;
        }
        Ok(())
    }

    /// Map from node name to index; fails on duplicate or reserved names.
    pub(crate) fn node_map(&self) -> Result<HashMap<&str, usize>, ThermalError> {
        let mut map = HashMap::with_capacity(self.nodes.len());
        for (i, n) in self.nodes.iter().enumerate() {
            if n.name == AMBIENT_NODE || map.insert(n.name.as_str(), i).is_some() {
                return Err(ThermalError::DuplicateNode {
                    field: format!("thermal.nodes[{i}].name"),
                    name: n.name.clone(),
                });
            }
        }
        Ok(map)
    }
}

fn validate_source(
    index: &HashMap<&str, usize>,
    f: &str,
    s: &HeatSourceSpec,
) -> Result<(), ThermalError> {
    match s {
        HeatSourceSpec::SpindleBearing {
            node,
            torque_n_mm,
            torque_per_krpm_n_mm,
        } => {
            known(index, &format!("{f}.node"), node)?;
            non_negative(&format!("{f}.torque_n_mm"), *torque_n_mm)?;
            non_negative(&format!("{f}.torque_per_krpm_n_mm"), *torque_per_krpm_n_mm)
        }
        HeatSourceSpec::SpindleMotor {
            node,
            torque_n_m,
            torque_per_krpm_n_m,
            efficiency,
        } => {
            known(index, &format!("{f}.node"), node)?;
            non_negative(&format!("{f}.torque_n_m"), *torque_n_m)?;
            non_negative(&format!("{f}.torque_per_krpm_n_m"), *torque_per_krpm_n_m)?;
            efficiency_ok(&format!("{f}.efficiency"), *efficiency)
        }
        HeatSourceSpec::AxisMotor {
            node,
            lead_mm,
            torque_n_m,
            efficiency,
            standstill_w,
            ..
        } => {
            known(index, &format!("{f}.node"), node)?;
            positive(&format!("{f}.lead_mm"), *lead_mm)?;
            non_negative(&format!("{f}.torque_n_m"), *torque_n_m)?;
            efficiency_ok(&format!("{f}.efficiency"), *efficiency)?;
            non_negative(&format!("{f}.standstill_w"), *standstill_w)
        }
        HeatSourceSpec::ScrewBearing {
            node,
            lead_mm,
            torque_n_mm,
            ..
        } => {
            known(index, &format!("{f}.node"), node)?;
            positive(&format!("{f}.lead_mm"), *lead_mm)?;
            non_negative(&format!("{f}.torque_n_mm"), *torque_n_mm)
        }
        HeatSourceSpec::BallscrewNut {
            segments,
            travel_min_mm,
            travel_max_mm,
            lead_mm,
            torque_n_mm,
            ..
        } => {
            if segments.is_empty() {
                return Err(invalid(&format!("{f}.segments"), "non-empty", "[]".into()));
            }
            for (j, seg) in segments.iter().enumerate() {
                known(index, &format!("{f}.segments[{j}]"), seg)?;
            }
            finite(&format!("{f}.travel_min_mm"), *travel_min_mm)?;
            if !(travel_max_mm.is_finite() && travel_max_mm > travel_min_mm) {
                return Err(invalid(
                    &format!("{f}.travel_max_mm"),
                    "finite and > travel_min_mm",
                    travel_max_mm.to_string(),
                ));
            }
            positive(&format!("{f}.lead_mm"), *lead_mm)?;
            non_negative(&format!("{f}.torque_n_mm"), *torque_n_mm)
        }
        HeatSourceSpec::GuideFriction {
            node,
            friction_force_n,
            ..
        } => {
            known(index, &format!("{f}.node"), node)?;
            non_negative(&format!("{f}.friction_force_n"), *friction_force_n)
        }
        HeatSourceSpec::Constant { node, power_w } => {
            known(index, &format!("{f}.node"), node)?;
            non_negative(&format!("{f}.power_w"), *power_w)
        }
    }
}

pub(crate) fn invalid(field: &str, requirement: &'static str, got: String) -> ThermalError {
    ThermalError::InvalidValue {
        field: field.to_owned(),
        requirement,
        got,
    }
}

fn known(index: &HashMap<&str, usize>, field: &str, node: &str) -> Result<(), ThermalError> {
    if index.contains_key(node) {
        Ok(())
    } else {
        Err(ThermalError::UnknownNode {
            field: field.to_owned(),
            node: node.to_owned(),
        })
    }
}

fn finite(field: &str, v: f64) -> Result<(), ThermalError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(invalid(field, "finite", v.to_string()))
    }
}

pub(crate) fn positive(field: &str, v: f64) -> Result<(), ThermalError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(invalid(field, "> 0", v.to_string()))
    }
}

fn non_negative(field: &str, v: f64) -> Result<(), ThermalError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(invalid(field, ">= 0", v.to_string()))
    }
}

fn efficiency_ok(field: &str, v: f64) -> Result<(), ThermalError> {
    if v.is_finite() && v > 0.0 && v <= 1.0 {
        Ok(())
    } else {
        Err(invalid(field, "in (0, 1]", v.to_string()))
    }
}
