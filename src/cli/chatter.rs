//! Arguments of `chatter` (which cuts of a milling program will chatter).

use std::path::PathBuf;

use anyhow::Result;

use super::ForceArg;
use crate::commands::chatter::ChatterConfig;
use crate::files;
use crate::studies::chatter::stock_file::StockSpec;
use crate::studies::chatter::ChatterOptions;
use vmc_machine::milling::ToolDynamics;

/// Arguments of `chatter`.
#[derive(clap::Args)]
pub struct ChatterArgs {
    /// G-code milling program to check (coordinates as programmed).
    pub program: PathBuf,
    /// Stock file (TOML: the box `min_mm`, `max_mm` in the program's coordinates, optional
    /// `grid_mm`).
    #[arg(long)]
    pub stock: PathBuf,
    /// Tool file (TOML: teeth, diameter, cutting coefficients, tool-tip modes in X and Y);
    /// default: the one-degree-of-freedom benchmark (machines/benchmarks/insperger-1dof.toml).
    #[arg(long)]
    pub tool: Option<PathBuf>,
    /// Z-map grid spacing, mm (default: the stock file's grid_mm, else the tool diameter / 32).
    #[arg(long)]
    pub grid_mm: Option<f64>,
    /// Width of the a_e/D bins (each cut is judged at the top of its bin).
    #[arg(long, default_value_t = 0.025)]
    pub immersion_bin: f64,
    /// Write one row per cutting move as CSV.
    #[arg(long, value_name = "FILE.csv")]
    pub out: Option<PathBuf>,
    /// Write a Rerun recording: the stability lobes of the program's engagements with its cuts
    /// as points on them.
    #[arg(long, value_name = "FILE.rrd")]
    pub rrd: Option<PathBuf>,
    #[command(flatten)]
    pub force: ForceArg,
}

impl ChatterArgs {
    /// The validated config.
    ///
    /// # Errors
    /// An unreadable or invalid stock or tool file.
    pub fn config(self) -> Result<ChatterConfig> {
        let (tool, tool_source) = ToolDynamics::from_option(self.tool.as_deref())?;
        let stock_source = self.stock.display().to_string();
        let text = files::read_named(&self.stock, "stock file")?;
        let stock = StockSpec::from_toml_str(&text, &stock_source)?;
        if let Some(g) = self.grid_mm {
            anyhow::ensure!(
                g > 0.0 && g.is_finite(),
                "--grid-mm must be a positive number of mm, got {g}"
            );
        }
        anyhow::ensure!(
            (crate::dynamics::params::MIN_IMMERSION..=1.0).contains(&self.immersion_bin),
            "--immersion-bin must be in [0.01, 1], got {}",
            self.immersion_bin
        );
        let options = ChatterOptions {
            grid_mm: self.grid_mm.or(stock.grid_mm),
            immersion_bin: self.immersion_bin,
            ..ChatterOptions::default()
        };
        Ok(ChatterConfig {
            program: self.program,
            stock,
            stock_source,
            tool,
            tool_source,
            options,
            out: self.out,
            force: self.force.force,
            rrd: self.rrd,
        })
    }
}
