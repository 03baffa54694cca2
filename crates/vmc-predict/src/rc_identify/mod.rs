//! Grey-box identification of a small thermal RC network and its drift gains from a spindle
//! thermal test (numerical core only: no files, no printing).
//!
//! **Network** ([`RcNetwork`]): a chain of 1 to 3 nodes. Node 0 (the spindle's bearings)
//! receives the heat input of the spindle speed `n` (rpm), `q(n) = a·k + b·k²` W with
//! `k = |n|/1000` (the twin's bearing friction `H = 2π/60 000·n·(M₀ + M₁·n/1000)`, i.e.
//! `a = 2π/60·M₀`, `b = 2π/60·M₁`); node `i` is linked to node `i + 1` by `Gᵢ`; each node is
//! linked to the ambient by `Hᵢ`, node 0's growing with speed as the twin's forced convection,
//! `H₀(n) = H₀·(1 + γ·k)`:
//!
//! ```text
//! Cᵢ·dTᵢ/dt = δᵢ₀·q(n) + Gᵢ₋₁·(Tᵢ₋₁ − Tᵢ) + Gᵢ·(Tᵢ₊₁ − Tᵢ) − Hᵢ(n)·(Tᵢ − T_a)
//! ```
//!
//! integrated as the twin integrates its own network (implicit Euler, on the data's time
//! steps, the speed of the step's first row, the ambient of its last), from every node at the
//! first ambient reading (the machine at rest when the file starts). The ambient `T_a` is a
//! measured column or, without one, constant.
//!
//! **Drift** of channel `k`, two modes ([`Mode`]):
//! - [`Mode::SpeedOnly`]: `d_k = c_k0 + Σᵢ c_ki·(Tᵢ − T_a(0)) [+ c_ka·(T_a − T_a(0))]`: from the
//!   speed profile alone (and the ambient column when one is given);
//! - [`Mode::WithTemps`]: the same plus `Σⱼ e_kj·(θⱼ − θⱼ(0))`, the rises of measured
//!   temperatures `θⱼ` since the first row: the network's node rises and the thermometers
//!   together, as when the model runs on a machine with its thermometers.
//!
//! The gains are solved by least squares for given network parameters (variable projection).
//!
//! **Fit**: the network parameters are fitted by Levenberg–Marquardt on the drift residuals,
//! each channel scaled by its standard deviation on the fitting rows, and, for a node given a
//! measured temperature ([`RcData::node_temps`]), on the residual of its rise against the
//! measured rise. Capacities and conductances are fitted as logarithms (positive), the heat
//! coefficients and γ as themselves; every parameter is kept within [`RcBounds`] (projected
//! steps: a step that leaves the box is cut back to its face, and the parameter is reported).
//!
//! **What is identified.** Temperatures depend on heat only through `q/G` and `C/G`: scaling
//! every capacity, conductance and the heat input together changes nothing measured. Node 0's
//! capacity is therefore fixed ([`RcSettings::node0_capacity_j_per_k`]); the other parameters
//! are relative to it. Without a measured temperature of a node, the scale of the temperatures
//! (heat input against drift gains) is not identified either: only the products are, and the
//! fit returns one member of that family.
//!
//! Several starting points (time constants of about 10 min, 30 min and 1.5 h at node 0, and,
//! for two nodes or more, the fit with one node fewer extended by a weakly linked node) are
//! fitted a few iterations each; the best is then fitted to convergence. Deterministic.

mod fit;
mod network;

#[cfg(test)]
mod tests;

pub use fit::identify;
pub use network::{RcNetwork, BEARING_W_PER_KRPM_N_MM};

/// How the drift is predicted (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// From the speed profile alone (plus the ambient column, if given).
    SpeedOnly,
    /// From the speed profile and the measured temperatures.
    WithTemps,
}

impl Mode {
    /// Short name for reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Mode::SpeedOnly => "speed only",
            Mode::WithTemps => "with temperatures",
        }
    }
}

/// Box bounds of the fitted parameters (the fit never leaves them; see [`RcFit::at_bounds`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RcBounds {
    /// Capacities, J/K (default `[10, 1e9]`).
    pub capacity_j_per_k: [f64; 2],
    /// Conductances of links and to ambient, W/K (default `[1e-4, 1e4]`).
    pub conductance_w_per_k: [f64; 2],
    /// Heat coefficients `a` (W per 1000 rpm) and `b` (W per (1000 rpm)²) (default `[0, 1e5]`).
    pub heat_w: [f64; 2],
    /// γ, per 1000 rpm (default `[0, 10]`).
    pub ha_gain_per_krpm: [f64; 2],
}

impl Default for RcBounds {
    fn default() -> Self {
        Self {
            capacity_j_per_k: [10.0, 1e9],
            conductance_w_per_k: [1e-4, 1e4],
            heat_w: [0.0, 1e5],
            ha_gain_per_krpm: [0.0, 10.0],
        }
    }
}

/// What to fit.
#[derive(Debug, Clone, PartialEq)]
pub struct RcSettings {
    /// Nodes of the chain, 1…3 (default `2`).
    pub nodes: usize,
    /// Fit γ, node 0's growth of convection with speed (default `true`; `false`: γ = 0).
    pub speed_convection: bool,
    /// Capacity of node 0, J/K, fixed: it sets the scale of every capacity, conductance and
    /// heat input (default `20 000`: a spindle cartridge's bearings and shaft).
    pub node0_capacity_j_per_k: f64,
    /// Levenberg–Marquardt iterations of the best start (default `300`).
    pub max_iter: usize,
    /// Iterations of each start before the best is chosen (default `25`).
    pub start_iter: usize,
    /// Parameter bounds.
    pub bounds: RcBounds,
}

impl Default for RcSettings {
    fn default() -> Self {
        Self {
            nodes: 2,
            speed_convection: true,
            node0_capacity_j_per_k: 20_000.0,
            max_iter: 300,
            start_iter: 25,
            bounds: RcBounds::default(),
        }
    }
}

/// The measurements the identification fits (columns of equal length, one entry per row).
#[derive(Debug, Clone, Copy)]
pub struct RcData<'a> {
    /// Time of each row, s (strictly increasing).
    pub time_s: &'a [f64],
    /// Spindle speed, rpm (≥ 0).
    pub rpm: &'a [f64],
    /// Ambient temperature, °C (None: constant).
    pub ambient_degc: Option<&'a [f64]>,
    /// Drift channels, one column each.
    pub drifts: &'a [Vec<f64>],
    /// Per node (at most as many as nodes), a measured temperature its rise is fitted to.
    pub node_temps: &'a [Option<&'a [f64]>],
    /// Measured temperatures (°C) whose rises join the regressors in [`Mode::WithTemps`].
    pub temps: &'a [&'a [f64]],
}

/// An identified network with its drift gains.
#[derive(Debug, Clone, PartialEq)]
pub struct RcFit {
    /// The network.
    pub network: RcNetwork,
    /// The mode it was fitted in.
    pub mode: Mode,
    /// Whether the ambient column was a regressor.
    pub with_ambient: bool,
    /// Per channel, the gains in the order of [`RcFit::regressor_names`]: offset (the drift's
    /// unit), per K of each node's rise, of the ambient's rise (with an ambient column), of each
    /// measured temperature's rise ([`Mode::WithTemps`]).
    pub gains: Vec<Vec<f64>>,
    /// Levenberg–Marquardt iterations taken by the kept start.
    pub iterations: usize,
    /// Final cost: sum of squared scaled residuals over the fitting rows.
    pub cost: f64,
    /// Parameters that end on a bound of [`RcBounds`] (e.g. `"G01"`, `"b"`): a value the data
    /// pushed out of the physical range, held at it.
    pub at_bounds: Vec<String>,
    /// Parameters a step of the fit was cut back to a bound at some iteration.
    pub hit_bounds: Vec<String>,
}

impl RcFit {
    /// Names of the regressors (see [`RcFit::gains`]); measured temperatures as `θ0`, `θ1`, ….
    #[must_use]
    pub fn regressor_names(&self) -> Vec<String> {
        let mut v = vec!["offset".to_string()];
        v.extend((0..self.network.nodes()).map(|i| format!("node{i}")));
        if self.with_ambient {
            v.push("ambient".into());
        }
        if self.mode == Mode::WithTemps {
            v.extend(
                (0..self
                    .gains
                    .first()
                    .map_or(0, Vec::len)
                    .saturating_sub(v.len()))
                    .map(|j| format!("θ{j}")),
            );
        }
        v
    }

    /// Predicted drifts (one column per channel) of every row of `data` (its drift columns are
    /// not used; its temperatures must be the ones fitted, in the same order).
    ///
    /// # Errors
    /// [`RcError::BadData`] if `data` is inconsistent or does not match the fit.
    pub fn predict(&self, data: &RcData) -> Result<Vec<Vec<f64>>, RcError> {
        fit::check_rows(data, None)?;
        let x = fit::regressors(&self.network, data, self.mode);
        if x.cols.len() != self.gains.first().map_or(0, Vec::len) {
            return Err(RcError::BadData(format!(
                "{} regressors, the fit has {}",
                x.cols.len(),
                self.gains.first().map_or(0, Vec::len)
            )));
        }
        Ok(self
            .gains
            .iter()
            .map(|g| {
                (0..data.time_s.len())
                    .map(|r| x.cols.iter().zip(g).map(|(c, g)| c[r] * g).sum())
                    .collect()
            })
            .collect())
    }
}

/// Why the identification failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RcError {
    /// Columns of different lengths, too few rows, no drift channel, non-finite values.
    #[error("identify: {0}")]
    BadData(String),
    /// A negative spindle speed (0-based row).
    #[error("identify: row {row}: negative spindle speed {rpm} rpm (speeds must be ≥ 0)")]
    NegativeSpeed {
        /// 0-based row.
        row: usize,
        /// The value.
        rpm: f64,
    },
    /// A setting out of range.
    #[error("identify: invalid setting {field}: {reason}")]
    BadSettings {
        /// The setting.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// Every starting point gives non-finite residuals.
    #[error("identify: the fit diverged (non-finite residuals from every starting point)")]
    Diverged,
}
