//! Thermal model of the machine: a lumped-capacitance (RC) network.
//!
//! Model, per node i (temperatures in °C, time in s):
//!
//! ```text
//! Cᵢ dTᵢ/dt = −Σⱼ Kᵢⱼ Tⱼ + qᵢ(t) + hAᵢ(t)·(T_amb(t) − Tᵢ)
//! ```
//!
//! - `C` heat capacities (J/K); `K` the conductance Laplacian of the conductive links (W/K),
//!   whose rows sum to zero so conduction only moves heat;
//! - `q` heat from what the program does ([`Activity`]): spindle bearing friction
//!   `H = 1.047e-4·n·M` (n rpm, M N·mm, M growing linearly with n), motor losses
//!   `P = M·n/(9550·η)·(1−η)` (kW, M N·m), ballscrew nut friction deposited into the screw segment
//!   under the nut at the current axis position (so the screw's temperature profile depends on the
//!   travel history), screw support bearings and guide friction ∝ feed speed;
//! - `hA` convection to ambient (W/K); on spindle nodes it grows with spindle speed,
//!   `hA = hA₀·(1 + g·n/1000)`, and coolant adds a conductance to ambient (coolant held at
//!   ambient);
//! - `T_amb` a prescribed [`AmbientProfile`] (a boundary, not a state).
//!
//! Assumptions: linear in temperature (constant properties, no radiation nonlinearity), activity
//! held constant over a step (callers pass the mean |v| over the step), the nut–carriage contact
//! is not modelled as a moving conductance (only the friction heat moves with the nut).
//!
//! Integration: implicit Euler, `(C/dt + K + H)·T⁺ = C/dt·T + q + H·T_amb`. It is L-stable, its
//! fixed point is the exact steady state, and summing its rows gives the exact discrete energy
//! balance `Σ C ΔT = dt·(Σ q − Σ H (T⁺ − T_amb))`, which [`ThermalNetwork`] accumulates. The
//! step matrix is factorised (Cholesky) and inverted once per distinct (dt, spindle speed, coolant)
//! state and cached, so a step is one n×n matrix–vector product with no allocation. Its time error
//! is first order in dt/τ: with dt = 1 s and the fastest node time constants of minutes, the lag
//! it adds is below 0.01 °C.
//!
//! The reference machine's network (39 nodes: the contract names plus `spindle_nose` and `z_support`) is in `machines/vmc-reference.toml`.

mod network;
mod sources;
mod spec;

pub use network::ThermalNetwork;
pub use spec::{
    AmbientProfile, Axis, HeatSourceSpec, LinkSpec, NodeSpec, ThermalError, ThermalSpec,
    AMBIENT_NODE,
};

use serde::{Deserialize, Serialize};

/// What the machine does during one thermal step: the heat sources' input.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Activity {
    /// Spindle speed (rpm); its sign (direction) is ignored (default `0.0`).
    pub spindle_rpm: f64,
    /// Axis positions X, Y, Z in machine coordinates (mm) (default `0.0`).
    pub axis_pos_mm: [f64; 3],
    /// Mean |v| of each axis over the step (mm/min) (default `0.0`).
    pub axis_speed_mm_per_min: [f64; 3],
    /// Flood coolant on (default `false`).
    #[serde(default)]
    pub coolant: bool,
}

#[cfg(test)]
mod reference_tests;
#[cfg(test)]
mod tests;
