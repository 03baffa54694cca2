//! Arguments of `modal-fit` (tool-tip modes from a measured receptance FRF).

use std::path::PathBuf;

use anyhow::{Context, Result};

use super::ForceArg;
use crate::commands::modal_fit::ModalFitConfig;
use crate::dynamics::modal_fit::{FitOptions, Frf};
use crate::files;
use vmc_machine::milling::ToolDynamics;

/// Arguments of `modal-fit`.
#[derive(clap::Args)]
pub struct ModalFitArgs {
    /// The measured FRF (CSV: frequency_hz and, per direction x and y, the real and imaginary
    /// receptance x_re_m_per_n, x_im_m_per_n, y_re_m_per_n, y_im_m_per_n in m/N; see
    /// docs/file-formats.md).
    pub frf: PathBuf,
    /// Write the fitted modes as a tool file (TOML) that `lobes`, `cut` and `chatter` take.
    #[arg(long, short = 'o', value_name = "FILE.toml")]
    pub out: Option<PathBuf>,
    /// Tool file whose cutter ([tool]: teeth, diameter, cutting coefficients) the written file
    /// takes (an FRF does not know them); its modes are replaced by the fitted ones. Default:
    /// the benchmark tool (machines/benchmarks/insperger-1dof.toml).
    #[arg(long, value_name = "FILE.toml")]
    pub tool: Option<PathBuf>,
    /// Name of the written tool (default: the template's name with the FRF file's).
    #[arg(long)]
    pub name: Option<String>,
    /// Highest denominator order of the stabilisation diagram (even, at least 4).
    #[arg(long, default_value_t = FitOptions::default().max_order)]
    pub max_order: usize,
    /// Orders below the highest through which a pole must stay to count as a mode.
    #[arg(long, default_value_t = FitOptions::default().stable_orders)]
    pub stable_orders: usize,
    /// Write a Rerun recording of the measured and fitted receptance (magnitude and phase per
    /// direction).
    #[arg(long, value_name = "FILE.rrd")]
    pub rrd: Option<PathBuf>,
    #[command(flatten)]
    pub force: ForceArg,
}

impl ModalFitArgs {
    /// The validated config: the FRF read and parsed, the template tool loaded.
    ///
    /// # Errors
    /// An unreadable or malformed FRF file (one line naming the file and the line), an
    /// unreadable or invalid template tool file.
    pub fn config(self) -> Result<ModalFitConfig> {
        let text = files::read_named(&self.frf, "FRF file")?;
        let frf_source = self.frf.display().to_string();
        let frf = Frf::parse(&text).with_context(|| frf_source.clone())?;
        let (template, template_source) = ToolDynamics::from_option(self.tool.as_deref())?;
        let options = FitOptions {
            max_order: self.max_order,
            stable_orders: self.stable_orders,
            ..FitOptions::default()
        };
        Ok(ModalFitConfig {
            frf,
            frf_source,
            template,
            template_source,
            name: self.name,
            options,
            out: self.out,
            rrd: self.rrd,
            force: self.force.force,
        })
    }
}
