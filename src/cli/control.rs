//! Arguments of `control` (controller design for the piezo-actuated blade) and the
//! `--controller` variants of `lobes` and `cut`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use super::ForceArg;
use crate::commands;
use crate::commands::control::{JudgedOn, Kind};
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
    /// Robust H∞: the H∞ weights with a weighted input-multiplicative uncertainty and a
    /// second-order roll-off (the plant file's [robust_hinf] table).
    RobustHinf,
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
    /// Judge the design on perturbed blades: frequencies ×0.90–1.10, mass ×0.80–1.20, damping
    /// ×0.5 and ×2; per case the loop's stability without cutting, the attenuation and the
    /// open- and closed-loop minimum critical depths.
    #[arg(long)]
    pub robustness: bool,
    /// Speeds of the robustness sweep's lobes, rpm (first:last:count or a list); default: 200
    /// over the plant's speed band; `none`: stability and attenuation only.
    #[arg(long, requires = "robustness")]
    pub rpm: Option<String>,
    /// Steps per tooth period of the robustness sweep's lobes (fixed, not checked); default:
    /// converged as `lobes --controller`.
    #[arg(long, value_name = "M", requires = "robustness")]
    pub steps: Option<usize>,
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
        let robustness = if self.robustness {
            let speeds_rpm = match self.rpm.as_deref() {
                Some("none") => Vec::new(),
                r => speeds(r, plant.speed_band_rpm)?,
            };
            Some(commands::control_robust::SweepConfig {
                cases: crate::dynamics::control::robust::sweep_cases(),
                speeds_rpm,
                resolution: steps_resolution(self.steps)?
                    .unwrap_or_else(commands::control::blade_resolution),
            })
        } else {
            None
        };
        Ok(commands::control::DesignConfig {
            plant,
            plant_source: self.plant.display().to_string(),
            kind: match self.controller {
                KindArg::Lqg => Kind::Lqg,
                KindArg::Hinf => Kind::Hinf,
                KindArg::RobustHinf => Kind::RobustHinf,
            },
            strategy: self.strategy,
            lowpass_hz,
            out: self.out,
            force: self.force.force,
            robustness,
        })
    }
}

/// The speeds of `--rpm`, or 200 over the band.
fn speeds(rpm: Option<&str>, [lo, hi]: [f64; 2]) -> Result<Vec<f64>> {
    Ok(match rpm {
        Some(r) => {
            vmc_machine::milling::parse_speeds(r).map_err(|e| anyhow::anyhow!("--rpm: {e}"))?
        }
        None => (0..200)
            .map(|i| lo + (hi - lo) * i as f64 / 199.0)
            .collect(),
    })
}

/// The structure a controller is judged on: `--plant FILE` or the controller file's own.
///
/// # Errors
/// An unreadable or invalid plant file.
pub fn judged_on(file: &ControllerFile, plant: Option<&Path>) -> Result<JudgedOn> {
    Ok(match plant {
        None => JudgedOn::own(file),
        Some(path) => JudgedOn {
            plant: Plant::load(path)?,
            source: Some(path.display().to_string()),
        },
    })
}

/// The config of `lobes --controller FILE [--plant FILE]`.
///
/// # Errors
/// An unreadable or invalid controller or plant file, malformed speeds, too few steps.
pub fn lobes_config(
    path: &Path,
    plant: Option<&Path>,
    rpm: Option<&str>,
    steps: Option<usize>,
    (out, rrd): (Option<PathBuf>, Option<PathBuf>),
    force: bool,
) -> Result<commands::control::ControlLobesConfig> {
    let file = ControllerFile::load(path)?;
    let judged = judged_on(&file, plant)?;
    let speeds_rpm = speeds(rpm, judged.plant.speed_band_rpm)?;
    let resolution = steps_resolution(steps)?.unwrap_or_else(commands::control::blade_resolution);
    Ok(commands::control::ControlLobesConfig {
        file,
        source: path.display().to_string(),
        judged,
        speeds_rpm,
        resolution,
        out,
        rrd,
        force,
        shard: None,
    })
}

/// Most steps per tooth period `--steps` accepts.
pub const MAX_STEPS: usize = 20_000;

/// The fixed resolution of `--steps M` (4 to [`MAX_STEPS`]); `None` without it.
///
/// # Errors
/// Fewer than 4 steps or more than [`MAX_STEPS`].
pub fn steps_resolution(steps: Option<usize>) -> Result<Option<Resolution>> {
    match steps {
        Some(m) if m < 4 => bail!("--steps must be >= 4, got {m}"),
        // Memory and time grow with the steps (10⁹ steps asked for 120 GB); the converged
        // resolution settles in the hundreds.
        Some(m) if m > MAX_STEPS => bail!("--steps must be <= {MAX_STEPS}, got {m}"),
        Some(m) => Ok(Some(Resolution::Fixed(m))),
        None => Ok(None),
    }
}
