//! Arguments of `control` (controller design for the piezo-actuated blade) and the
//! `--controller` variants of `lobes` and `cut`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use super::ForceArg;
use crate::commands;
use crate::commands::control::Kind;
use crate::dynamics::Resolution;
use vmc_machine::blade::{ControllerFile, Plant};

/// Arguments of `control`.
#[derive(clap::Args)]
pub struct ControlArgs {
    /// What to do.
    #[command(subcommand)]
    pub action: ControlAction,
}

/// `control` subcommands.
#[derive(clap::Subcommand)]
pub enum ControlAction {
    /// Design an LQG or H∞ controller for a blade (plant file, TOML), print its closed-loop
    /// poles, the attenuation of each mode and the actuator effort, and write it (JSON).
    Design(DesignArgs),
}

/// Controller type of `control design --controller`.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum KindArg {
    /// LQR + Kalman filter.
    Lqg,
    /// Glover–Doyle H∞ (γ by bisection).
    Hinf,
}

/// Arguments of `control design`.
#[derive(clap::Args)]
pub struct DesignArgs {
    /// Plant file (TOML: blade, actuator, cutter, cut, weights), e.g.
    /// machines/benchmarks/blade.toml.
    #[arg(long)]
    pub plant: PathBuf,
    /// Controller type.
    #[arg(long, value_enum)]
    pub controller: KindArg,
    /// 1: design on the structure alone (cutting force as a disturbance); 2: on the structure
    /// coupled to the cut of the plant file's [strategy2] table, the delay by a Padé model.
    #[arg(long, default_value_t = 1)]
    pub strategy: u8,
    /// Low-pass filter on the controller output, Hz (overrides the plant file's; 0 = none).
    #[arg(long, allow_negative_numbers = true)]
    pub lowpass_hz: Option<f64>,
    /// Write the controller (JSON).
    #[arg(short = 'o', long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub force: ForceArg,
}

impl DesignArgs {
    /// The validated config.
    ///
    /// # Errors
    /// An unreadable or invalid plant file, a strategy other than 1 or 2, a negative corner.
    pub fn config(self) -> Result<commands::control::DesignConfig> {
        let plant = Plant::load(&self.plant)?;
        if !(1..=2).contains(&self.strategy) {
            bail!("--strategy must be 1 or 2, got {}", self.strategy);
        }
        let lowpass_hz = match self.lowpass_hz {
            None => None,
            Some(0.0) => Some(None),
            Some(v) if v > 0.0 && v.is_finite() => Some(Some(v)),
            Some(v) => bail!("--lowpass-hz must be >= 0 Hz, got {v}"),
        };
        Ok(commands::control::DesignConfig {
            plant,
            plant_source: self.plant.display().to_string(),
            kind: match self.controller {
                KindArg::Lqg => Kind::Lqg,
                KindArg::Hinf => Kind::Hinf,
            },
            strategy: self.strategy,
            lowpass_hz,
            out: self.out,
            force: self.force.force,
        })
    }
}

/// The config of `lobes --controller FILE`.
///
/// # Errors
/// An unreadable or invalid controller file, malformed speeds, too few steps.
pub fn lobes_config(
    path: &Path,
    rpm: Option<&str>,
    steps: Option<usize>,
    (out, rrd): (Option<PathBuf>, Option<PathBuf>),
    force: bool,
) -> Result<commands::control::ControlLobesConfig> {
    let file = ControllerFile::load(path)?;
    let speeds_rpm = match rpm {
        Some(r) => {
            vmc_machine::milling::parse_speeds(r).map_err(|e| anyhow::anyhow!("--rpm: {e}"))?
        }
        None => {
            let [lo, hi] = file.plant.speed_band_rpm;
            (0..200)
                .map(|i| lo + (hi - lo) * i as f64 / 199.0)
                .collect()
        }
    };
    let resolution = steps_resolution(steps)?.unwrap_or_else(commands::control::blade_resolution);
    Ok(commands::control::ControlLobesConfig {
        file,
        source: path.display().to_string(),
        speeds_rpm,
        resolution,
        out,
        rrd,
        force,
        shard: None,
    })
}

/// The fixed resolution of `--steps M` (at least 4); `None` without it.
///
/// # Errors
/// Fewer than 4 steps.
pub fn steps_resolution(steps: Option<usize>) -> Result<Option<Resolution>> {
    match steps {
        Some(m) if m < 4 => bail!("--steps must be >= 4, got {m}"),
        Some(m) => Ok(Some(Resolution::Fixed(m))),
        None => Ok(None),
    }
}
