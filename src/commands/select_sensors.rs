//! `vmc-twin select-sensors`: where to put the thermometers — the placement study, its report
//! and the chosen sensor set (TOML).

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;

use crate::files;
use crate::shard::{InputFingerprint, Shard};
use crate::studies::placement;
use vmc_machine::machine::MachineSpec;
use vmc_machine::sensors::SensorSpec;
use vmc_machine::thermal::AMBIENT_NODE;

/// What to select, validated.
pub struct SelectConfig {
    /// The machine.
    pub machine: MachineSpec,
    /// Candidate nodes (None: every thermal node and ambient).
    pub only: Option<Vec<String>>,
    /// Sensors to select besides ambient.
    pub count: usize,
    /// Machine realisation of the selection campaign.
    pub seed: u64,
    /// Machine seeds of the comparison on held-out runs (empty: no comparison).
    pub compare_seeds: Vec<u64>,
    /// Random sets of K locations in the comparison.
    pub random_draws: usize,
    /// Output sensor set (TOML).
    pub out: PathBuf,
    /// Also write the study as JSON.
    pub json: Option<PathBuf>,
    /// Overwrite existing output files.
    pub force: bool,
    /// Run only this shard of the compare seeds and write its results for `merge` in
    /// `shard_dir`.
    pub shard: Option<Shard>,
    /// Folder of a shard's results (with `shard`).
    pub shard_dir: Option<PathBuf>,
    /// Fingerprints of the input files (the machine), for a shard's manifest.
    pub inputs: Vec<InputFingerprint>,
    /// The command line, for a shard's manifest.
    pub command_line: Vec<String>,
}

/// `--candidates`: `all`, or node names of `machine` (each once).
///
/// # Errors
/// An empty name, a name given twice, a name that is not a thermal node.
pub fn parse_candidates(text: &str, machine: &MachineSpec) -> Result<Option<Vec<String>>> {
    if text == "all" {
        return Ok(None);
    }
    let wanted: Vec<String> = text.split(',').map(|w| w.trim().to_string()).collect();
    for (i, w) in wanted.iter().enumerate() {
        if w.is_empty() {
            anyhow::bail!("--candidates: an empty name in `{text}`");
        }
        if wanted[..i].contains(w) {
            anyhow::bail!("--candidates: `{w}` is named twice");
        }
        if w != "ambient" && !machine.thermal.nodes.iter().any(|n| &n.name == w) {
            let nodes: Vec<&str> = machine
                .thermal
                .nodes
                .iter()
                .map(|n| n.name.as_str())
                .collect();
            anyhow::bail!(
                "--candidates: `{w}` is not a thermal node of {}; use `all` or some of: {}",
                machine.machine.name,
                nodes.join(", ")
            );
        }
    }
    Ok(Some(wanted))
}

/// Runs the study, prints it and writes the sensor set (and the JSON study if asked); one shard
/// of it: [`super::select_shard::select_shard`].
///
/// # Errors
/// A count of 0 or above the candidates, outputs that may not be written, study errors.
pub fn select_sensors(cfg: &SelectConfig, out: &mut dyn Write) -> Result<()> {
    check_count(cfg)?;
    files::check_writable(&cfg.out, cfg.force)?;
    if let Some(j) = &cfg.json {
        files::check_writable(j, cfg.force)?;
    }
    let machine = &cfg.machine;
    let study = placement_config(cfg);
    let rep = placement::study_among(machine, &study, cfg.only.as_deref())?;
    placement::write_report(&rep, machine, &study, out)?;
    let toml = sensor_set_toml(cfg, &rep.selected_sensors);
    files::write_atomic(&cfg.out, toml.as_bytes(), cfg.force)?;
    writeln!(out, "wrote {}", cfg.out.display())?;
    if let Some(j) = &cfg.json {
        files::write_atomic(j, placement::report_json(&rep)?.as_bytes(), cfg.force)?;
        writeln!(out, "wrote {}", j.display())?;
    }
    Ok(())
}

/// Refuses a count of 0 or above the candidates besides ambient.
pub(super) fn check_count(cfg: &SelectConfig) -> Result<()> {
    if cfg.count == 0 {
        anyhow::bail!("--count must be at least 1");
    }
    let candidates = placement::candidates_among(&cfg.machine, cfg.only.as_deref())?
        .iter()
        .filter(|c| c.node != AMBIENT_NODE)
        .count();
    if cfg.count > candidates {
        anyhow::bail!(
            "--count {}: there are only {candidates} candidate locations besides ambient",
            cfg.count
        );
    }
    Ok(())
}

/// The study's settings: the defaults with the command's seed, compare seeds, draws and count.
pub(super) fn placement_config(cfg: &SelectConfig) -> placement::PlacementConfig {
    let mut study = placement::PlacementConfig {
        seed: cfg.seed,
        compare_seeds: cfg.compare_seeds.clone(),
        random_draws: cfg.random_draws,
        ..Default::default()
    };
    study.selection.count = cfg.count;
    study
}

/// The sensor set file's text: a header saying how it was chosen and how to use it (naming the
/// file as given to `--out`), then the sensors.
pub(super) fn sensor_set_toml(cfg: &SelectConfig, sensors: &[SensorSpec]) -> String {
    let set = placement::SensorSet {
        sensors: sensors.to_vec(),
    };
    let header = format!(
        "Sensor set chosen by `vmc-twin select-sensors --count {}` on {} (seed {}).\n\
         Use it with `--sensors {}` (run, calibrate, train, campaign) or paste it into a machine file.",
        cfg.count,
        cfg.machine.machine.name,
        cfg.seed,
        cfg.out.display()
    );
    set.to_toml(&header)
}
