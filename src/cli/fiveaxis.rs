//! Arguments of `probe-campaign` and `identify`, and `run`'s config on a five-axis machine.

use std::path::PathBuf;

use anyhow::Result;

use super::{ForceArg, RrdArgs};
use crate::commands::identify::IdentifyConfig;
use crate::commands::probe_campaign::ProbeCampaignConfig;
use crate::commands::run_fiveaxis::FiveAxisRunConfig;
use vmc_machine::fiveaxis::run::Sampling;
use vmc_machine::fiveaxis::FiveAxisSpec;

/// Whether the compensating controller of a five-axis `run` corrects the rotary axes too.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum RotaryComp {
    /// Linear and rotary axes: position and tool-axis errors.
    On,
    /// Linear axes only: position errors.
    Off,
}

/// Arguments of `probe-campaign`.
#[derive(clap::Args)]
pub struct ProbeCampaignArgs {
    /// Five-axis machine file (e.g. machines/trunnion-ac.toml).
    #[arg(long)]
    pub machine: PathBuf,
    /// Number of configurations to probe (spread over the rotary travels and the targets).
    #[arg(long, default_value_t = 80)]
    pub configs: usize,
    /// Placements of a relocated sphere probed besides the artefact: the first N of the
    /// machine file's `[sphere] placements_mm`, or of a layout spread over the working volume
    /// when the file has none (at most 8). Default: all of the file's, or 4. 0: the artefact
    /// only.
    #[arg(long)]
    pub placements: Option<usize>,
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
    #[command(flatten)]
    pub rrd: RrdArgs,
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
        let placements =
            vmc_machine::fiveaxis::campaign::placements_w_mm(&machine, self.placements)
                .map_err(|e| anyhow::anyhow!("--placements: {e}"))?;
        Ok(ProbeCampaignConfig {
            machine,
            configs: self.configs,
            placements,
            seed: self.seed,
            noise_2sigma_um: self.noise_2sigma_um,
            out: self.out,
            force: self.force.force,
            rrd: self.rrd.checked()?,
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
    /// Fix the model: fit the rotary motion errors' harmonics up to order N on every rotary
    /// axis (orders 2..=N of translations and tilts, 1..=N of the angular positioning errors;
    /// 0: location and assembly errors only). Default: the orders per axis are chosen from the
    /// probing data by cross-validation over configurations.
    #[arg(long)]
    pub harmonics: Option<u32>,
    /// Highest harmonic order per axis tried when choosing the order from the data.
    #[arg(long, default_value_t = 4)]
    pub max_harmonics: u32,
    /// Cross-validation folds when choosing the order from the data.
    #[arg(long, default_value_t = 5)]
    pub order_folds: usize,
    /// Seed of the shuffle of configurations into folds.
    #[arg(long, default_value_t = 1)]
    pub order_seed: u64,
    /// Held-out poses for the judge.
    #[arg(long, default_value_t = 500)]
    pub heldout_poses: usize,
    /// Radius of the judged region about the table's axis, mm (default: the larger half
    /// stroke of X and Y).
    #[arg(long)]
    pub judge_radius_mm: Option<f64>,
    /// Height of the judged region above the table, mm (default: half the Z stroke).
    #[arg(long)]
    pub judge_height_mm: Option<f64>,
    /// Machine realisation the held-out judge compares with (default: the probing file's
    /// `# seed:`); never used by the identification.
    #[arg(long)]
    pub seed: Option<u64>,
    #[command(flatten)]
    pub force: ForceArg,
    #[command(flatten)]
    pub rrd: RrdArgs,
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
        if let Some(h) = self.harmonics {
            anyhow::ensure!(h <= 8, "--harmonics must be 0 to 8, got {h}");
        }
        anyhow::ensure!(
            (2..=8).contains(&self.max_harmonics),
            "--max-harmonics must be 2 to 8, got {}",
            self.max_harmonics
        );
        anyhow::ensure!(
            self.order_folds >= 2,
            "--order-folds must be at least 2, got {}",
            self.order_folds
        );
        for (v, flag) in [
            (self.judge_radius_mm, "--judge-radius-mm"),
            (self.judge_height_mm, "--judge-height-mm"),
        ] {
            if let Some(v) = v {
                anyhow::ensure!(v.is_finite() && v > 0.0, "{flag} must be > 0, got {v}");
            }
        }
        Ok(IdentifyConfig {
            data: self.data,
            machine,
            out: self.out,
            design_configs: self.design_configs,
            harmonics: self.harmonics,
            order: vmc_identify::order::OrderOptions {
                max_order: self.max_harmonics,
                folds: self.order_folds,
                seed: self.order_seed,
                ..Default::default()
            },
            heldout_poses: self.heldout_poses,
            judge_radius_mm: self.judge_radius_mm,
            judge_height_mm: self.judge_height_mm,
            seed: self.seed,
            force: self.force.force,
            rrd: self.rrd.checked()?,
        })
    }
}

/// The config of `run` on a five-axis machine (the machine file is one); options of the
/// three-axis thermal twin are refused, each with what to do.
///
/// # Errors
/// An invalid machine file, an option this machine does not take, a non-positive cycle, a bad
/// recording path or magnification.
pub(super) fn run_config(args: super::RunArgs) -> Result<FiveAxisRunConfig> {
    let path = args.run.machine.machine.clone().unwrap_or_default();
    let machine = FiveAxisSpec::load(&path)?;
    let name = &machine.machine.name;
    let refused: [(bool, &str, &str); 7] = [
        (
            args.run.sensors.sensors.is_some(),
            "--sensors",
            "it has no thermal model, hence no sensors",
        ),
        (
            !args.run.warmup.is_empty(),
            "--warmup",
            "it has no thermal model",
        ),
        (
            args.run.thermal_step_s != 1.0,
            "--thermal-step-s",
            "it has no thermal model",
        ),
        (
            args.run.tools.is_some(),
            "--tools",
            "it carries one tool (the machine file's [tool])",
        ),
        (
            args.run.model.is_some(),
            "--model",
            "compensate with the identified model of `identify` (--identified)",
        ),
        (
            args.run.strict,
            "--strict",
            "it applies to a trained --model",
        ),
        (
            args.run.allow_other_machine,
            "--allow-other-machine",
            "it applies to a trained --model",
        ),
    ];
    if let Some((_, option, why)) = refused.iter().find(|r| r.0) {
        anyhow::bail!("{option} does not apply to the five-axis machine {name}: {why}");
    }
    let interp_cycle_ms = args.interp_cycle_ms.unwrap_or(1.0);
    anyhow::ensure!(
        interp_cycle_ms.is_finite() && interp_cycle_ms > 0.0,
        "--interp-cycle-ms must be > 0, got {interp_cycle_ms}"
    );
    let p = &args.placement;
    if p.setup.is_some() || !p.work_offset.is_empty() || !p.subroutines.is_empty() {
        anyhow::bail!(
            "--setup, --work-offset and --subroutines do not apply to the five-axis machine {name} yet: its work offsets come from the machine file"
        );
    }
    let sampling = if args.every_cycle {
        Sampling::EveryCycle(interp_cycle_ms * 1e-3)
    } else {
        Sampling::Dwells
    };
    Ok(FiveAxisRunConfig {
        program: args.program,
        machine,
        machine_file: path.display().to_string(),
        seed: args.run.seed,
        out_dir: args.run.out,
        force: args.run.force.force,
        sampling,
        identified: args.identified,
        rotary_comp: args.rotary_comp != Some(RotaryComp::Off),
        rrd: args.rrd.checked()?,
    })
}
