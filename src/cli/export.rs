//! Arguments of `export`: compensation tables for a real controller.

use std::path::PathBuf;

use anyhow::Result;

use super::{ForceArg, MachineArg, SensorsArg};
use crate::commands::export::{ExportConfig, ExportFormat, ThermalState};

/// A controller's table format (`export --format`).
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FormatArg {
    /// LinuxCNC per-joint `COMP_FILE`s and the INI lines that load them.
    Linuxcnc,
    /// Siemens 840D sl interpolatory compensation (`%_N_NC_CEC_INI`), own-axis and cross tables.
    SiemensCec,
}

/// Arguments of `export`.
#[derive(clap::Args)]
pub struct ExportArgs {
    /// Trained model (JSON, from `train` or `campaign --out`).
    #[arg(long)]
    pub model: PathBuf,
    /// The table formats to write (comma-separated or repeated).
    #[arg(long, value_enum, value_delimiter = ',', required = true)]
    pub format: Vec<FormatArg>,
    /// The thermal state as sensor readings, °C: `NAME=VALUE` for every sensor of the model
    /// (commas or spaces between), or a file holding them; taken as a steady state.
    #[arg(long, conflicts_with = "warmup", required_unless_present = "warmup")]
    pub readings: Option<String>,
    /// The thermal state as warm-up program(s) run on the twin first (repeatable, in order); the
    /// model follows the readings and the commanded motion throughout, as in `run`.
    #[arg(long)]
    pub warmup: Vec<PathBuf>,
    #[command(flatten)]
    pub machine: MachineArg,
    #[command(flatten)]
    pub sensors: SensorsArg,
    /// Seed of the twin's realisation (for `--warmup`, and the model's machine check).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Use a model calibrated on another machine or realisation (a note says which).
    #[arg(long)]
    pub allow_other_machine: bool,
    /// Largest distance between table points, mm (at most 256 points per table).
    #[arg(long, default_value_t = 10.0)]
    pub step_mm: f64,
    /// LinuxCNC `COMP_FILE_TYPE`: 1 (trims, the default) or 0 (measured positions).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(0..=1))]
    pub comp_file_type: u8,
    /// Siemens CEC: write the own-axis tables only (no cross tables).
    #[arg(long)]
    pub no_cross_tables: bool,
    /// Folder for the tables and `tables-report.txt` (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub force: ForceArg,
}

impl ExportArgs {
    /// The validated config.
    ///
    /// # Errors
    /// An unreadable machine or sensor set, an unreadable readings file, a step that is not a
    /// positive number.
    pub fn config(self) -> Result<ExportConfig> {
        let machine = self.machine.load(Some(&self.sensors))?;
        if !(self.step_mm.is_finite() && self.step_mm > 0.0) {
            anyhow::bail!("--step-mm must be a positive number, got {}", self.step_mm);
        }
        let thermal = match self.readings {
            Some(r) => {
                let path = std::path::Path::new(&r);
                if !r.contains('=') && path.is_file() {
                    ThermalState::Readings {
                        text: crate::files::read_named(path, "readings")?,
                        source: path.display().to_string(),
                    }
                } else if !r.contains('=') {
                    anyhow::bail!(
                        "--readings {r}: neither NAME=VALUE readings nor a readable file"
                    );
                } else {
                    ThermalState::Readings {
                        source: r.clone(),
                        text: r,
                    }
                }
            }
            None => ThermalState::Warmup(self.warmup),
        };
        let formats = self
            .format
            .iter()
            .map(|f| match f {
                FormatArg::Linuxcnc => ExportFormat::Linuxcnc,
                FormatArg::SiemensCec => ExportFormat::SiemensCec,
            })
            .collect();
        Ok(ExportConfig {
            model: self.model,
            machine,
            seed: self.seed,
            allow_other_machine: self.allow_other_machine,
            thermal,
            formats,
            step_mm: self.step_mm,
            comp_file_type: self.comp_file_type,
            cross_tables: !self.no_cross_tables,
            out_dir: self.out,
            force: self.force.force,
        })
    }
}
