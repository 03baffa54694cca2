//! The options `run` and `replay` share: the machine and its realisation, what runs before the
//! measured motion, where the results go and the model in the loop. One flattened group, so a
//! flag of both commands is declared, documented and checked once.

use std::path::PathBuf;

use anyhow::Result;

use super::{load_tool_table, ForceArg, MachineArg, SensorsArg};

/// The options of a measured run on the three-axis twin (`run` and `replay`).
#[derive(clap::Args)]
pub struct MachineRunArgs {
    #[command(flatten)]
    pub machine: MachineArg,
    #[command(flatten)]
    pub sensors: SensorsArg,
    /// Seed of the machine's random error parts and noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Thermal loading program(s) to run first (repeatable, run in order).
    #[arg(long)]
    pub warmup: Vec<PathBuf>,
    /// Tool table (TOML, `[[tool]]` with `number`, `length_mm`, `diameter_mm`): `M6` (in the
    /// program or a warm-up) loads the twin's tool from it; default: the machine's own tool for
    /// every number.
    #[arg(long)]
    pub tools: Option<PathBuf>,
    /// Folder for samples.csv and summary.json (created if missing).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub force: ForceArg,
    /// Thermal integration and sensor sampling step, s.
    #[arg(long, default_value_t = 1.0)]
    pub thermal_step_s: f64,
    /// Trained model (JSON, from `train` or `campaign --out`) for `--compensate`.
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Refuse the run (or replay) when a reading or command leaves the range the model was
    /// trained on.
    #[arg(long)]
    pub strict: bool,
    /// Use a model calibrated on another machine or realisation (a note says which).
    #[arg(long)]
    pub allow_other_machine: bool,
}

impl MachineRunArgs {
    /// The machine with the sensor set of `--sensors`.
    ///
    /// # Errors
    /// See [`crate::commands::load_machine`].
    pub fn load_machine(&self) -> Result<vmc_machine::machine::MachineSpec> {
        self.machine.load(Some(&self.sensors))
    }

    /// The tool table of `--tools` (empty without it).
    ///
    /// # Errors
    /// An unreadable or invalid tool table.
    pub fn tool_table(&self) -> Result<vmc_machine::tools::ToolTable> {
        load_tool_table(self.tools.as_deref())
    }
}
