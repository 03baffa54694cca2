//! Arguments of `probe-campaign` and `identify` (five-axis machines).

use std::path::PathBuf;

use anyhow::Result;

use super::ForceArg;
use crate::commands::identify::IdentifyConfig;
use crate::commands::probe_campaign::ProbeCampaignConfig;
use crate::fiveaxis::FiveAxisSpec;

/// Arguments of `probe-campaign`.
#[derive(clap::Args)]
pub struct ProbeCampaignArgs {
    /// Five-axis machine file (e.g. machines/trunnion-ac.toml).
    #[arg(long)]
    pub machine: PathBuf,
    /// Number of configurations to probe (spread over the rotary travels).
    #[arg(long, default_value_t = 50)]
    pub configs: usize,
    /// Machine realisation (seed of its random error parts and of the trigger noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Trigger noise at 2σ, µm (default: the machine file's probe, 0.25).
    #[arg(long)]
    pub noise_2sigma_um: Option<f64>,
    /// Output probing file.
    #[arg(short = 'o', long, default_value = "probing.csv")]
    pub out: PathBuf,
    #[command(flatten)]
    pub force: ForceArg,
}

impl ProbeCampaignArgs {
    /// The validated config.
    ///
    /// # Errors
    /// An unreadable or invalid machine file, no configurations, a negative noise.
    pub fn config(self) -> Result<ProbeCampaignConfig> {
        let machine = FiveAxisSpec::load(&self.machine)?;
        anyhow::ensure!(self.configs >= 1, "--configs must be at least 1");
        if let Some(n) = self.noise_2sigma_um {
            anyhow::ensure!(
                n >= 0.0 && n.is_finite(),
                "--noise-2sigma-um must be ≥ 0, got {n}"
            );
        }
        Ok(ProbeCampaignConfig {
            machine,
            configs: self.configs,
            seed: self.seed,
            noise_2sigma_um: self.noise_2sigma_um,
            out: self.out,
            force: self.force.force,
        })
    }
}

/// Arguments of `identify`.
#[derive(clap::Args)]
pub struct IdentifyArgs {
    /// Probing file from `probe-campaign`.
    #[arg(long)]
    pub data: PathBuf,
    /// Five-axis machine file (its nominal geometry is all identification uses).
    #[arg(long)]
    pub machine: PathBuf,
    /// Output file (JSON).
    #[arg(short = 'o', long, default_value = "identified.json")]
    pub out: PathBuf,
    /// Identify from K configurations of the file chosen D-optimally (from the nominal
    /// sensitivity only, before looking at the measurements).
    #[arg(long)]
    pub design_configs: Option<usize>,
    /// Also fit the rotary motion errors' harmonics of orders 2..=N (0: location and
    /// assembly errors only).
    #[arg(long, default_value_t = 0)]
    pub harmonics: u32,
    /// Held-out poses for the judge.
    #[arg(long, default_value_t = 500)]
    pub heldout_poses: usize,
    /// Machine realisation the held-out judge compares with (default: the probing file's
    /// `# seed:`); never used by the identification.
    #[arg(long)]
    pub seed: Option<u64>,
    #[command(flatten)]
    pub force: ForceArg,
}

impl IdentifyArgs {
    /// The validated config.
    ///
    /// # Errors
    /// An unreadable or invalid machine file; a bad K or harmonic order.
    pub fn config(self) -> Result<IdentifyConfig> {
        let machine = FiveAxisSpec::load(&self.machine)?;
        if let Some(k) = self.design_configs {
            anyhow::ensure!(k >= 1, "--design-configs must be at least 1");
        }
        anyhow::ensure!(
            self.harmonics <= 8,
            "--harmonics must be 0 to 8, got {}",
            self.harmonics
        );
        Ok(IdentifyConfig {
            data: self.data,
            machine,
            out: self.out,
            design_configs: self.design_configs,
            harmonics: self.harmonics,
            heldout_poses: self.heldout_poses,
            seed: self.seed,
            force: self.force.force,
        })
    }
}
