//! `vmc-twin campaign`, the main job: calibration, training of the three predictors, every
//! diagonal under held-out thermal states without and with compensation, the report.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};

use super::{wrote_recording, RrdOutput, VERSION};
use crate::files;
use crate::predict::predictor::Settings;
use crate::progress::Progress;
use crate::record;
use crate::shard::{InputFingerprint, Shard, ShardManifest, MANIFEST_FILE, MANIFEST_FORMAT};
use crate::studies::calibration::ThermalCycle;
use crate::studies::campaign::{self, CampaignReport, ForMachine, TrainedModels, PREDICTORS};
use crate::studies::probing::Probing;
use vmc_machine::machine::MachineSpec;

/// Name of a campaign shard's per-seed results (one JSON object per line,
/// [`campaign::SeedResults`]).
pub const SEED_RESULTS_FILE: &str = "seeds.jsonl";

/// What to run, validated.
pub struct CampaignConfig {
    /// The machine (with its sensor set).
    pub machine: MachineSpec,
    /// Machine realisations (distinct, at least one).
    pub seeds: Vec<u64>,
    /// Folder for `report.json` and the trained models.
    pub out_dir: Option<PathBuf>,
    /// Overwrite existing output files.
    pub force: bool,
    /// The hybrid's spindle part also takes the commanded spindle speed (opt-in).
    pub spindle_speed: bool,
    /// Print the per-run table too.
    pub print_runs: bool,
    /// A Rerun recording of a representative run.
    pub rrd: Option<RrdOutput>,
    /// Run only this shard of the seeds and write its results for `merge` (needs `out_dir`).
    pub shard: Option<Shard>,
    /// Probe a reference sphere every this many minutes of every held-out run (None: no probing).
    pub probe_every_min: Option<f64>,
    /// Fingerprints of the input files (machine, sensor set), for a shard's manifest.
    pub inputs: Vec<InputFingerprint>,
    /// The command line, for a shard's manifest.
    pub command_line: Vec<String>,
}

/// The file names of the trained models of `seeds`.
pub fn model_file_names(seeds: &[u64]) -> Vec<String> {
    let mut names = Vec::new();
    for s in seeds {
        for k in PREDICTORS {
            names.push(format!("model_{}_seed{s}.json", k.name()));
        }
    }
    names
}

/// Runs the campaign, prints the summary (and the runs if asked), writes the files.
///
/// # Errors
/// Outputs that may not be written, simulation or training errors.
pub fn campaign(cfg: &CampaignConfig, out: &mut dyn Write) -> Result<()> {
    if let Some(shard) = cfg.shard {
        return campaign_shard(cfg, shard, out);
    }
    let out_dir = match &cfg.out_dir {
        Some(dir) => {
            let mut names = vec!["report.json".to_string()];
            names.extend(model_file_names(&cfg.seeds));
            files::prepare_output_folder(dir, &names, cfg.force)?;
            Some(dir.clone())
        }
        None => None,
    };
    if let Some(rrd) = &cfg.rrd {
        record::check_rrd_path(&rrd.path, cfg.force)?;
    }
    let settings = settings_of(cfg);
    let progress = Progress::new(0, "units");
    let probing = cfg.probe_every_min.map(|m| Probing::every(&cfg.machine, m));
    let (rep, models) = campaign::run_campaign_probed(
        &cfg.machine,
        &cfg.seeds,
        &settings,
        &ThermalCycle::calibration_plan(&cfg.machine),
        probing.as_ref(),
        &progress,
    )?;
    progress.finish();
    let summary = campaign::Summary::of(rep.header(), &rep.runs);
    campaign::write_summary(&summary, out)?;
    if let Some(p) = &probing {
        write_probing(p, out)?;
    }
    if cfg.print_runs {
        campaign::write_run_table(&rep, out)?;
    }
    if let Some(rrd) = &cfg.rrd {
        write_recording(cfg, rrd, &rep, &models, &summary.fleet, out)?;
    }
    if let Some(dir) = out_dir {
        let path = dir.join("report.json");
        files::write_atomic_with(&path, cfg.force, |w| {
            campaign::write_report_json(&rep.header(), &rep.training, &rep.runs, w)
                .map_err(std::io::Error::other)
        })?;
        write_models(&dir, &models, cfg.force)?;
        writeln!(out, "wrote {} and the trained models", path.display())?;
    }
    Ok(())
}

/// The probing line of a campaign with probing: artefacts, interval, cycle and its cost.
fn write_probing(p: &Probing, out: &mut dyn Write) -> Result<()> {
    let at: Vec<String> = p
        .sphere_centres_mm
        .iter()
        .map(|c| format!("({:.0}, {:.0}, {:.0})", c[0], c[1], c[2]))
        .collect();
    let model = if p.gradient {
        format!(
            "drift offset and gradient per component, walks {:.1} µm/√h and {:.1} µm/m/√h",
            p.field.walk_offset_um_per_sqrt_h, p.field.walk_gradient_um_per_m_sqrt_h
        )
    } else {
        format!(
            "drift offset per axis, walk {:.1} µm/√h",
            p.field.walk_offset_um_per_sqrt_h
        )
    };
    writeln!(
        out,
        "probing: {} Ø{:.0} mm reference sphere(s) at {} mm, {} touches every {:.0} min from the \
         start of each run (and right before the diagonal), {:.0} s per cycle: {:.2} machine min \
         per hour; probe {:.1} µm 2σ, pre-travel {:.1} µm; {model}",
        p.sphere_centres_mm.len(),
        2.0 * p.sphere_radius_mm,
        at.join(" "),
        p.touches_per_cycle(),
        p.every_s / 60.0,
        p.cycle_s(),
        p.cost_min_per_h(),
        p.probe.repeatability_2sigma_um,
        p.probe.pretravel_mm() * 1e3,
    )?;
    Ok(())
}

/// The predictor settings of the campaign.
fn settings_of(cfg: &CampaignConfig) -> Settings {
    let settings = Settings::for_machine(&cfg.machine);
    if cfg.spindle_speed {
        settings.with_spindle_speed_input()
    } else {
        settings
    }
}

/// Writes each seed's three trained models in `dir`.
fn write_models(dir: &std::path::Path, models: &[TrainedModels], force: bool) -> Result<()> {
    for m in models {
        for (k, text) in [
            (
                PREDICTORS[0],
                m.hybrid.to_json_string_with(Some(&m.trained_on[0]))?,
            ),
            (
                PREDICTORS[1],
                m.volumetric.to_json_string_with(Some(&m.trained_on[1]))?,
            ),
            (
                PREDICTORS[2],
                m.linear.to_json_string_with(Some(&m.trained_on[2]))?,
            ),
        ] {
            let file = dir.join(format!("model_{}_seed{}.json", k.name(), m.seed));
            files::write_atomic(&file, text.as_bytes(), force)?;
        }
    }
    Ok(())
}

/// One shard of the campaign: its block of the seeds, calibrated, trained and evaluated, written
/// as `seeds.jsonl` (one line per seed), the trained models and `shard.json`. A shard with no
/// seed writes its manifest and an empty result file.
fn campaign_shard(cfg: &CampaignConfig, shard: Shard, out: &mut dyn Write) -> Result<()> {
    let dir = cfg
        .out_dir
        .as_ref()
        .context("--shard needs --out DIR for the shard's results")?;
    let seeds = &cfg.seeds[shard.block(cfg.seeds.len())];
    let mut names = vec![MANIFEST_FILE.to_string(), SEED_RESULTS_FILE.to_string()];
    names.extend(model_file_names(seeds));
    files::prepare_output_folder(dir, &names, cfg.force)?;
    let settings = settings_of(cfg);
    let cal_cycles = ThermalCycle::calibration_plan(&cfg.machine);
    let header = campaign::campaign_header(&cfg.machine, &cfg.seeds, &settings, &cal_cycles);
    let manifest = ShardManifest {
        format: MANIFEST_FORMAT,
        command: "campaign".into(),
        shard,
        work_ids: seeds.iter().map(|s| format!("seed {s}")).collect(),
        work_total: cfg.seeds.len(),
        command_line: cfg.command_line.clone(),
        version: VERSION.into(),
        inputs: campaign_inputs(cfg, &settings)?,
        header: serde_json::to_value(&header)?,
        results: Vec::new(),
    };
    let progress = Progress::new(0, "units");
    let (rep, models) =
        campaign::run_campaign_with_progress(&cfg.machine, seeds, &settings, &progress)?;
    progress.finish();
    files::write_atomic_with(&dir.join(SEED_RESULTS_FILE), cfg.force, |w| {
        for r in rep.by_seed(seeds) {
            serde_json::to_writer(&mut *w, &r)?;
            w.write_all(b"\n")?;
        }
        Ok(())
    })?;
    write_models(dir, &models, cfg.force)?;
    let path = crate::shard::integrity::write_manifest(dir, manifest, &names[1..], cfg.force)?;
    let list: Vec<String> = seeds.iter().map(|s| s.to_string()).collect();
    writeln!(
        out,
        "campaign shard {shard}: {} of {} machines (seeds {}); wrote {}, {SEED_RESULTS_FILE} and the trained models",
        seeds.len(),
        cfg.seeds.len(),
        if list.is_empty() { "none".to_string() } else { list.join(", ") },
        path.display()
    )?;
    Ok(())
}

/// The fingerprints of everything the campaign's results depend on: the input files, the
/// diagonal programs, the predictor settings, the calibration plan and the seed list.
fn campaign_inputs(cfg: &CampaignConfig, settings: &Settings) -> Result<Vec<InputFingerprint>> {
    let mut inputs = cfg.inputs.clone();
    inputs.extend(super::embedded_fingerprints(&cfg.machine));
    inputs.push(InputFingerprint::of(
        "settings",
        "arguments",
        &serde_json::to_vec(settings)?,
    ));
    let seeds: Vec<String> = cfg.seeds.iter().map(|s| s.to_string()).collect();
    inputs.push(InputFingerprint::of(
        "seeds",
        "arguments",
        seeds.join(",").as_bytes(),
    ));
    Ok(inputs)
}

/// The recording of the campaign's representative hybrid run.
fn write_recording(
    cfg: &CampaignConfig,
    rrd: &RrdOutput,
    rep: &CampaignReport,
    models: &[TrainedModels],
    fleet: &campaign::fleet::FleetSummary,
    out: &mut dyn Write,
) -> Result<()> {
    let seeds: Vec<String> = cfg.seeds.iter().map(|s| s.to_string()).collect();
    let id = format!(
        "vmc-twin campaign on {} seeds {}",
        cfg.machine.machine.name,
        seeds.join(",")
    );
    let pick = record::campaign::pick_representative(rep)
        .context("the campaign produced no hybrid runs to record")?;
    let file = record::RrdFile::create(
        &rrd.path,
        cfg.force,
        &id,
        record::layout::campaign_blueprint(rrd.settings.magnify, &pick.title()),
    )?;
    record::campaign::record_campaign(&file, &cfg.machine, rep, models, rrd.settings)?;
    record::fleet::log_fleet(&file, fleet)?;
    let bytes = file.finish()?;
    wrote_recording(
        out,
        &rrd.path,
        bytes,
        &format!("; representative run {}", pick.title()),
    )?;
    Ok(())
}
