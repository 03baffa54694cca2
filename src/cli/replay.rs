//! Arguments of `replay`: a controller's servo log played on the twin.

use std::path::PathBuf;

use anyhow::Result;

use super::{MachineRunArgs, RrdArgs};
use crate::commands::replay::log::LogFormat;
use crate::commands::replay::ReplayConfig;
use vmc_machine::sim::SimConfig;

/// The format of a log (`replay --format`).
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LogFormatArg {
    /// CSV with a header: `time_s,x_mm,y_mm,z_mm` and optional `corr_x_mm,corr_y_mm,corr_z_mm`,
    /// `spindle_rpm`, `<sensor>_degc`.
    Csv,
    /// LinuxCNC `halsampler` output: whitespace-separated numbers, columns named by
    /// `--columns`, time from `--period-ms`.
    Halsampler,
}

/// Arguments of `replay`.
#[derive(clap::Args)]
pub struct ReplayArgs {
    /// Servo-rate log of the commanded axis positions (CSV or halsampler output).
    pub log: PathBuf,
    /// The log's format; default: `csv` for a `.csv` file (else give it).
    #[arg(long, value_enum)]
    pub format: Option<LogFormatArg>,
    /// halsampler: the columns in order, comma-separated: `n` (sample number of
    /// `halsampler -t`), `x,y,z` (commanded joint positions, mm), `cx,cy,cz` (the corrections
    /// the controller added, mm), `s` (spindle speed, rpm), `<sensor>_degc`, `_` (skip).
    #[arg(long, value_name = "NAMES")]
    pub columns: Option<String>,
    /// halsampler: the servo period, ms (the time of a sample is `n` × period, or its row ×
    /// period without `n`).
    #[arg(long)]
    pub period_ms: Option<f64>,
    /// Measure every N-th sample (the first included).
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub every: usize,
    /// Spindle speed, rpm, when the log has no spindle column.
    #[arg(long, default_value_t = 0.0)]
    pub spindle_rpm: f64,
    #[command(flatten)]
    pub run: MachineRunArgs,
    /// Compute the corrections with a model in the twin's loop (`--compensate MODEL`, or
    /// `--model MODEL --compensate` as in `run`); for a log without correction columns.
    #[arg(long, value_name = "MODEL", num_args = 0..=1)]
    pub compensate: Option<Option<PathBuf>>,
    #[command(flatten)]
    pub rrd: RrdArgs,
}

impl ReplayArgs {
    /// The validated config.
    ///
    /// # Errors
    /// A format that cannot be told, options of the other format, a bad period, step or
    /// spindle speed, `--every 0`, a model without `--compensate` (or the reverse), an
    /// unreadable machine, sensor set or tool table, a bad recording path.
    pub fn config(self) -> Result<ReplayConfig> {
        let format = self.format()?;
        anyhow::ensure!(self.every >= 1, "--every must be at least 1");
        anyhow::ensure!(
            self.spindle_rpm.is_finite() && self.spindle_rpm >= 0.0,
            "--spindle-rpm must be a number ≥ 0, got {}",
            self.spindle_rpm
        );
        let model = match (self.compensate, self.run.model.clone()) {
            (Some(Some(_)), Some(m)) => anyhow::bail!(
                "{}: a model given twice (--model and --compensate MODEL): give one",
                m.display()
            ),
            (Some(Some(m)), None) | (Some(None), Some(m)) => Some(m),
            (Some(None), None) => {
                anyhow::bail!("--compensate needs a model: --compensate MODEL")
            }
            (None, Some(m)) => anyhow::bail!(
                "{}: a model was given without --compensate; add --compensate to put it in the loop",
                m.display()
            ),
            (None, None) => None,
        };
        if model.is_none() && (self.run.strict || self.run.allow_other_machine) {
            anyhow::bail!(
                "--strict and --allow-other-machine apply to a model: add --compensate MODEL"
            );
        }
        let thermal_step_s = self.run.thermal_step_s;
        let sim = SimConfig::new(thermal_step_s, 1e-3)
            .map_err(|_| anyhow::anyhow!("--thermal-step-s must be > 0, got {thermal_step_s}"))?;
        let machine = self.run.load_machine()?;
        Ok(ReplayConfig {
            rrd: self.rrd.checked()?,
            log: self.log,
            format,
            machine,
            seed: self.run.seed,
            tools: self.run.tool_table()?,
            warmups: self.run.warmup,
            out_dir: self.run.out,
            force: self.run.force.force,
            sim,
            every: self.every,
            spindle_rpm: self.spindle_rpm,
            model,
            strict: self.run.strict,
            allow_other_machine: self.run.allow_other_machine,
        })
    }

    /// The log's format: as given, or `csv` for a `.csv` file, or `halsampler` when its columns
    /// are named.
    fn format(&self) -> Result<LogFormat> {
        let is_csv = self
            .log
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
        let kind = match (self.format, is_csv, &self.columns) {
            (Some(f), _, _) => f,
            (None, true, _) => LogFormatArg::Csv,
            (None, false, Some(_)) => LogFormatArg::Halsampler,
            (None, false, None) => anyhow::bail!(
                "{}: cannot tell the log's format from its name: give --format csv, or --format \
                 halsampler with --columns and --period-ms",
                self.log.display()
            ),
        };
        match kind {
            LogFormatArg::Csv => {
                anyhow::ensure!(
                    self.columns.is_none() && self.period_ms.is_none(),
                    "--columns and --period-ms are for halsampler logs; a CSV log names its columns in its header and gives time_s"
                );
                Ok(LogFormat::Csv)
            }
            LogFormatArg::Halsampler => {
                let Some(columns) = &self.columns else {
                    anyhow::bail!(
                        "--format halsampler: name the columns with --columns (e.g. n,x,y,z,cx,cy,cz,s)"
                    );
                };
                if let Some(ms) = self.period_ms {
                    anyhow::ensure!(
                        ms > 0.0 && ms.is_finite(),
                        "--period-ms must be > 0, got {ms}"
                    );
                }
                Ok(LogFormat::Halsampler {
                    columns: columns.split(',').map(|c| c.trim().to_string()).collect(),
                    period_s: self.period_ms.map(|ms| ms * 1e-3),
                })
            }
        }
    }
}
