//! Arguments of `identify-thermal` (a grey-box thermal network of the spindle identified from a
//! user's measurements).

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use super::ForceArg;
use crate::commands::identify_thermal::IdentifyThermalConfig;
use crate::predict::rc_identify::RcSettings;
use crate::predict::thermal_fit::{Architecture, FitSettings};

/// Arguments of `identify-thermal`.
#[derive(clap::Args)]
pub struct IdentifyThermalArgs {
    /// Measurements (CSV: header of column names with units, one row per sample, a time column).
    #[arg(long)]
    pub data: PathBuf,
    /// Spindle speed column (rpm, ≥ 0): the heat input, and its rises from 0 start the cycles
    /// (the cross-validation folds).
    #[arg(long, default_value = "spindle_rpm")]
    pub rpm: String,
    /// Drift columns (comma-separated), e.g. ch1_um,ch2_um.
    #[arg(long, value_delimiter = ',', required = true)]
    pub drifts: Vec<String>,
    /// Measured temperatures (comma-separated) of the "with temperatures" prediction: their
    /// rises join the network's node rises as regressors of the drift.
    #[arg(long, value_delimiter = ',')]
    pub temps: Vec<String>,
    /// Temperatures (comma-separated) the network's nodes 0, 1, … are fitted to (their rises):
    /// they fix the scale of the node temperatures (e.g. the thermometer nearest the bearings
    /// for node 0).
    #[arg(long, value_delimiter = ',')]
    pub node_temps: Vec<String>,
    /// Ambient temperature column (default: constant ambient; the speed-only prediction then
    /// needs nothing but the speed).
    #[arg(long)]
    pub ambient: Option<String>,
    /// Nodes of the chain network: 1, 2 or 3.
    #[arg(long, default_value_t = 2)]
    pub nodes: usize,
    /// Do not fit the growth of node 0's convection with speed (γ = 0).
    #[arg(long)]
    pub no_speed_convection: bool,
    /// Capacity of node 0, J/K (fixed: it sets the scale of capacities, conductances and heat).
    #[arg(long, default_value_t = 20_000.0)]
    pub node0_capacity_j_per_k: f64,
    /// Levenberg–Marquardt iterations of the best start.
    #[arg(long, default_value_t = 300)]
    pub max_iter: usize,
    /// Start of the held-out part when the file has a single cycle (time split), s; default the
    /// last quarter of the time span.
    #[arg(long)]
    pub holdout_from_s: Option<f64>,
    /// Inputs of the black-box comparison (fit-thermal's selection and plain least squares on
    /// the same folds; comma-separated); default: --temps and the speed column.
    #[arg(long, value_delimiter = ',')]
    pub baseline_inputs: Vec<String>,
    /// Forms the black-box comparison may choose (as fit-thermal's --arch).
    #[arg(long, default_value = "linear-mlp")]
    pub baseline_arch: String,
    /// Skip the black-box comparison.
    #[arg(long)]
    pub no_baseline: bool,
    /// Seed of the black-box nets.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output machine-file fragment (TOML).
    #[arg(short = 'o', long, default_value = "spindle.toml")]
    pub out: PathBuf,
    #[command(flatten)]
    pub force: ForceArg,
    /// Time column; default: the only column whose name starts with "time".
    #[arg(long)]
    pub time: Option<String>,
    /// Write a Rerun recording of measured and predicted drifts over the whole file.
    #[arg(long, value_name = "FILE.rrd")]
    pub rrd: Option<PathBuf>,
}

impl IdentifyThermalArgs {
    /// The validated config.
    ///
    /// # Errors
    /// A node count outside 1…3, a non-positive capacity, an unknown --baseline-arch.
    pub fn config(self) -> Result<IdentifyThermalConfig> {
        if !(1..=3).contains(&self.nodes) {
            bail!("--nodes must be 1, 2 or 3, got {}", self.nodes);
        }
        if self.node_temps.len() > self.nodes {
            bail!(
                "--node-temps names {} columns for {} nodes (one per node at most)",
                self.node_temps.len(),
                self.nodes
            );
        }
        if !(self.node0_capacity_j_per_k.is_finite() && self.node0_capacity_j_per_k > 0.0) {
            bail!(
                "--node0-capacity-j-per-k must be > 0, got {}",
                self.node0_capacity_j_per_k
            );
        }
        let architecture = Architecture::parse(&self.baseline_arch).with_context(|| {
            format!(
                "--baseline-arch must be auto, linear-mlp, mlp or linear, got \"{}\"",
                self.baseline_arch
            )
        })?;
        let baseline_inputs = if self.baseline_inputs.is_empty() {
            self.temps
                .iter()
                .cloned()
                .chain(std::iter::once(self.rpm.clone()))
                .collect()
        } else {
            self.baseline_inputs
        };
        Ok(IdentifyThermalConfig {
            data: self.data,
            time: self.time,
            rpm: self.rpm,
            drifts: self.drifts,
            temps: self.temps,
            node_temps: self.node_temps,
            ambient: self.ambient,
            settings: RcSettings {
                nodes: self.nodes,
                speed_convection: !self.no_speed_convection,
                node0_capacity_j_per_k: self.node0_capacity_j_per_k,
                max_iter: self.max_iter,
                ..RcSettings::default()
            },
            holdout_from_s: self.holdout_from_s,
            baseline: (!self.no_baseline).then(|| {
                (
                    baseline_inputs,
                    FitSettings {
                        architecture,
                        seed: self.seed,
                        ..FitSettings::default()
                    },
                )
            }),
            out: self.out,
            force: self.force.force,
            rrd: self.rrd,
        })
    }
}
