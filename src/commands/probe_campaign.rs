//! `vmc-twin probe-campaign`: probe the reference sphere of a five-axis machine in N
//! configurations and write the probing file (CSV).

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;
use nalgebra::Vector3;

use crate::files;
use vmc_machine::fiveaxis::probe::VirtualProbe;
use vmc_machine::fiveaxis::{campaign, FiveAxisSpec, TrueMachine};

/// What to probe, validated.
pub struct ProbeCampaignConfig {
    /// The machine.
    pub machine: FiveAxisSpec,
    /// Configurations.
    pub configs: usize,
    /// Nominal centres of the relocated sphere's placements, workpiece frame, mm.
    pub placements: Vec<[f64; 3]>,
    /// Machine realisation and trigger-noise seed.
    pub seed: u64,
    /// Trigger noise override, µm at 2σ.
    pub noise_2sigma_um: Option<f64>,
    /// Output file.
    pub out: PathBuf,
    /// Overwrite.
    pub force: bool,
    /// A Rerun recording to write.
    pub rrd: Option<super::RrdOutput>,
}

/// Runs the campaign and writes the file.
///
/// # Errors
/// An output that may not be written, too few reachable configurations, a failed probing.
pub fn probe_campaign(cfg: &ProbeCampaignConfig, out: &mut dyn Write) -> Result<()> {
    files::check_writable(&cfg.out, cfg.force)?;
    if let Some(rrd) = &cfg.rrd {
        crate::record::check_rrd_path(&rrd.path, cfg.force)?;
    }
    let spec = &cfg.machine;
    let machine = TrueMachine::new(spec, cfg.seed)?;
    let probe = VirtualProbe::of(spec, cfg.noise_2sigma_um);
    let configs = campaign::spread_configurations(spec, &probe, cfg.configs, &cfg.placements);
    anyhow::ensure!(
        configs.len() == cfg.configs,
        "only {} of {} configurations keep the probe within the travels of machine {}",
        configs.len(),
        cfg.configs,
        spec.machine.name
    );
    let rows = campaign::run(&machine, &probe, &configs, cfg.seed)?;
    files::write_atomic(
        &cfg.out,
        campaign::to_csv(spec, cfg.seed, &probe, &rows).as_bytes(),
        cfg.force,
    )?;
    let bias_um: Vec<f64> = rows
        .iter()
        .map(|r| (r.fit.centre_mm - Vector3::from(r.nominal_mm)).norm() * 1e3)
        .collect();
    let mean = bias_um.iter().sum::<f64>() / bias_um.len() as f64;
    let max = bias_um.iter().copied().fold(0.0, f64::max);
    let mut text = Vec::new();
    writeln!(
        text,
        "probing campaign on {} (seed {}): {} configurations × {} points on the artefact and {} placement(s) of a relocated sphere, trigger noise {} µm (2σ) → {}",
        spec.machine.name,
        cfg.seed,
        rows.len(),
        probe.points,
        cfg.placements.len(),
        probe.noise_sigma_mm * 2e3,
        cfg.out.display()
    )?;
    writeln!(
        text,
        "sphere-centre bias (measured − nominal): mean {mean:.1} µm, max {max:.1} µm"
    )?;
    out.write_all(&text)?;
    if let Some(rrd) = &cfg.rrd {
        let id = format!(
            "vmc-twin probe-campaign on {} seed {} configs {}",
            spec.machine.name, cfg.seed, cfg.configs
        );
        let bytes = crate::record::fiveaxis::record_probing(
            &rrd.path,
            cfg.force,
            &id,
            rrd.settings.magnify,
            spec,
            &rows,
            &String::from_utf8_lossy(&text),
        )?;
        super::wrote_recording(out, &rrd.path, bytes, "")?;
    }
    Ok(())
}
