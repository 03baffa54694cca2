//! Arguments of `lobes`: a tool's stability lobes, or with `--controller` the blade's without
//! and with the controller; with `--shard I/N --shard-dir DIR` one shard of the speeds.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use super::{control, ForceArg, MillingArg};
use crate::commands;
use crate::shard::{InputFingerprint, Shard};
use vmc_machine::milling::DEFAULT_TOOL_TOML;

/// Stability method of `lobes --method`.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum MethodArg {
    /// First-order semi-discretisation (Insperger–Stépán).
    Sdm,
    /// Zero-order analytic solution (Altintas–Budak).
    Zoa,
    /// Time-domain cutting simulation with bisection on the depth.
    Time,
}

/// Arguments of `lobes`.
#[derive(clap::Args)]
pub struct LobesArgs {
    /// Tool file (TOML: teeth, diameter, cutting coefficients, tool-tip modes); default: the
    /// one-degree-of-freedom benchmark of the field (machines/benchmarks/insperger-1dof.toml).
    #[arg(long)]
    pub tool: Option<PathBuf>,
    /// Stability method.
    #[arg(long, value_enum, default_value = "sdm")]
    pub method: MethodArg,
    /// Radial immersion a_e/D, in [0.01, 1] (1 = slotting).
    #[arg(long, default_value_t = 1.0)]
    pub immersion: f64,
    /// Milling direction.
    #[arg(long, value_enum, default_value = "down")]
    pub milling: MillingArg,
    /// Spindle speeds, rpm: first:last:count (e.g. 5000:25000:201) or a comma-separated list;
    /// default 5000:25000:201, or 200 speeds over the plant's speed band with --controller.
    #[arg(long)]
    pub rpm: Option<String>,
    /// Write the lobes as CSV (spindle_rpm, critical_depth_mm, chatter_frequency_hz, kind;
    /// with --controller: spindle_rpm, open_depth_mm, closed_depth_mm).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// A controller file from `control design`: the lobes of its blade without and with the
    /// controller in the loop (closed-loop semi-discretisation; --tool, --method, --immersion
    /// and --milling do not apply: the blade's cut is in the file).
    #[arg(long, conflicts_with = "tool")]
    pub controller: Option<PathBuf>,
    /// With --controller: judge the controller on this plant file's blade, cutter and cut
    /// (TOML, as for `control design`) instead of the plant it was designed on; the sampling
    /// stays the controller's.
    #[arg(long, requires = "controller", conflicts_with = "shard")]
    pub plant: Option<PathBuf>,
    /// Semi-discretisation steps per tooth period, the same at every speed and not checked
    /// (--method sdm or --controller). Default: chosen per speed and checked (converged; with
    /// --controller at most 640).
    #[arg(long, value_name = "M")]
    pub steps: Option<usize>,
    /// Write a Rerun recording of the lobe diagram (depth against speed, Hopf and flip lobes;
    /// with --controller: the open- and closed-loop lobes).
    #[arg(long, value_name = "FILE.rrd")]
    pub rrd: Option<PathBuf>,
    #[command(flatten)]
    pub force: ForceArg,
    /// Compute only shard I of N of the speeds (1-based, e.g. 2/4) and write its points under
    /// --shard-dir for `vmc-twin merge`, which prints the report and writes the CSV (named as
    /// --out, else lobes.csv) and with its own --rrd the recording.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Folder of a shard's results (shard.json, lobes.jsonl); with --shard.
    #[arg(long, value_name = "DIR")]
    pub shard_dir: Option<PathBuf>,
}

impl LobesArgs {
    /// The config of `lobes --controller`, when given.
    ///
    /// # Errors
    /// An unreadable or invalid controller file, malformed speeds, too few steps.
    pub fn controller_config(&self) -> Result<Option<commands::control::ControlLobesConfig>> {
        let Some(path) = self.controller.as_deref() else {
            return Ok(None);
        };
        let mut cfg = control::lobes_config(
            path,
            self.plant.as_deref(),
            self.rpm.as_deref(),
            self.steps,
            (self.out.clone(), self.rrd.clone()),
            self.force.force,
        )?;
        cfg.shard = self.shard_output(|| {
            Ok(InputFingerprint::of(
                "controller",
                &path.display().to_string(),
                &std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?,
            ))
        })?;
        Ok(Some(cfg))
    }

    /// Where a shard writes (`--shard` and `--shard-dir`), with the fingerprint of the input
    /// file that `file` gives; `None` without `--shard`.
    ///
    /// # Errors
    /// A bad `--shard`, one of `--shard` and `--shard-dir` without the other, `--rrd` with
    /// `--shard`, an `--out` without a file name, an unreadable input file.
    fn shard_output(
        &self,
        file: impl FnOnce() -> Result<InputFingerprint>,
    ) -> Result<Option<commands::lobes::ShardOutput>> {
        let shard = self.shard.as_deref().map(str::parse::<Shard>).transpose()?;
        let (shard, dir) = match (shard, &self.shard_dir) {
            (None, None) => return Ok(None),
            (Some(s), None) => bail!("--shard {s} needs --shard-dir DIR for the shard's results"),
            (None, Some(_)) => {
                bail!("--shard-dir is the folder of a shard's results: give --shard I/N too")
            }
            (Some(s), Some(dir)) => (s, dir.clone()),
        };
        if self.rrd.is_some() {
            bail!("--rrd records the whole lobe diagram: pass it to `vmc-twin merge`");
        }
        if let Some(out) = self.out.as_deref().filter(|o| o.file_name().is_none()) {
            bail!(
                "--out {}: with --shard, --out names the CSV that `vmc-twin merge` writes; give a file name",
                out.display()
            );
        }
        Ok(Some(commands::lobes::ShardOutput {
            shard,
            dir,
            command_line: std::env::args().collect(),
            file: file()?,
        }))
    }

    /// The validated config.
    ///
    /// # Errors
    /// An unreadable or invalid tool file, an immersion outside [0.01, 1], malformed speeds.
    pub fn config(self) -> Result<commands::lobes::LobesConfig> {
        let (tool, tool_source) =
            vmc_machine::milling::ToolDynamics::from_option(self.tool.as_deref())?;
        let shard = self.shard_output(|| {
            Ok(match self.tool.as_deref() {
                Some(path) => InputFingerprint::of(
                    "tool",
                    &path.display().to_string(),
                    &std::fs::read(path)
                        .with_context(|| format!("{}: cannot read", path.display()))?,
                ),
                None => InputFingerprint::of("tool", "embedded", DEFAULT_TOOL_TOML.as_bytes()),
            })
        })?;
        let method = match self.method {
            MethodArg::Sdm => crate::dynamics::Method::Sdm,
            MethodArg::Zoa => crate::dynamics::Method::Zoa,
            MethodArg::Time => crate::dynamics::Method::Time,
        };
        if self.steps.is_some() && method != crate::dynamics::Method::Sdm {
            bail!("--steps sets the semi-discretisation's resolution: it applies to --method sdm (and --controller) only");
        }
        let resolution = control::steps_resolution(self.steps)?.unwrap_or_default();
        crate::dynamics::params::validate_immersion(self.immersion)
            .map_err(|e| anyhow::anyhow!("--immersion: {e}"))?;
        let rpm = self.rpm.as_deref().unwrap_or("5000:25000:201");
        let speeds_rpm =
            vmc_machine::milling::parse_speeds(rpm).map_err(|e| anyhow::anyhow!("--rpm: {e}"))?;
        Ok(commands::lobes::LobesConfig {
            tool,
            tool_source,
            method,
            resolution,
            immersion: self.immersion,
            milling: match self.milling {
                MillingArg::Up => crate::dynamics::Milling::Up,
                MillingArg::Down => crate::dynamics::Milling::Down,
            },
            speeds_rpm,
            out: self.out,
            rrd: self.rrd,
            force: self.force.force,
            shard,
        })
    }
}
