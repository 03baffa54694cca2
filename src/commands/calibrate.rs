//! `vmc-twin calibrate`: the virtual calibration campaign, written as a dataset (CSV).

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;

use crate::files;
use crate::studies::calibration::{self, ThermalCycle};
use vmc_machine::machine::MachineSpec;

/// What to calibrate, validated.
pub struct CalibrateConfig {
    /// The machine (with its sensor set).
    pub machine: MachineSpec,
    /// Machine realisation (seed of its random error parts).
    pub seed: u64,
    /// Output dataset file.
    pub out: PathBuf,
    /// Overwrite an existing output file.
    pub force: bool,
    /// Time between measurement blocks, s (≥ 60).
    pub measure_every_s: f64,
}

/// Runs the calibration cycles on the twin and writes the dataset.
///
/// # Errors
/// An output that may not be written, simulation errors.
pub fn calibrate(cfg: &CalibrateConfig, out: &mut dyn Write) -> Result<()> {
    files::check_writable(&cfg.out, cfg.force)?;
    let cycles = ThermalCycle::calibration_plan(&cfg.machine);
    let mut campaign = calibration::CampaignConfig::new(cfg.seed);
    campaign.measure_every_s = cfg.measure_every_s;
    let data = calibration::calibrate(&cfg.machine, &cycles, &campaign)?;
    files::write_atomic(&cfg.out, data.to_csv().as_bytes(), cfg.force)?;
    let names: Vec<&str> = cycles.iter().map(|c| c.name.as_str()).collect();
    writeln!(
        out,
        "calibration campaign on {} (seed {}): cycles {}; {} records, {} sensors → {}",
        cfg.machine.machine.name,
        cfg.seed,
        names.join(", "),
        data.records.len(),
        data.sensor_names.len(),
        cfg.out.display()
    )?;
    Ok(())
}
