//! `vmc-twin campaign`, the main job: calibration, training of the three predictors, every
//! diagonal under held-out thermal states without and with compensation, the report.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};

use super::{wrote_recording, RrdOutput};
use crate::files;
use crate::machine::MachineSpec;
use crate::predict::predictor::Settings;
use crate::progress::Progress;
use crate::record;
use crate::study::{self, CampaignReport, ForMachine, TrainedModels, PREDICTORS};

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
}

/// Runs the campaign, prints the summary (and the runs if asked), writes the files.
///
/// # Errors
/// Outputs that may not be written, simulation or training errors.
pub fn campaign(cfg: &CampaignConfig, out: &mut dyn Write) -> Result<()> {
    let out_dir = match &cfg.out_dir {
        Some(dir) => {
            let mut names = vec!["report.json".to_string()];
            for s in &cfg.seeds {
                for k in PREDICTORS {
                    names.push(format!("model_{}_seed{s}.json", k.name()));
                }
            }
            files::prepare_output_folder(dir, &names, cfg.force)?;
            Some(dir.clone())
        }
        None => None,
    };
    if let Some(rrd) = &cfg.rrd {
        record::check_rrd_path(&rrd.path, cfg.force)?;
    }
    let mut settings = Settings::for_machine(&cfg.machine);
    if cfg.spindle_speed {
        settings = settings.with_spindle_speed_input();
    }
    let progress = Progress::new(0, "units");
    let (rep, models) =
        study::run_campaign_with_progress(&cfg.machine, &cfg.seeds, &settings, &progress)?;
    progress.finish();
    study::write_campaign_summary(&rep, out)?;
    if cfg.print_runs {
        study::write_run_table(&rep, out)?;
    }
    if let Some(rrd) = &cfg.rrd {
        write_recording(cfg, rrd, &rep, &models, out)?;
    }
    if let Some(dir) = out_dir {
        let path = dir.join("report.json");
        let json = serde_json::to_string_pretty(&rep)?;
        files::write_atomic(&path, json.as_bytes(), cfg.force)?;
        for m in &models {
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
                files::write_atomic(&file, text.as_bytes(), cfg.force)?;
            }
        }
        writeln!(out, "wrote {} and the trained models", path.display())?;
    }
    Ok(())
}

/// The recording of the campaign's representative hybrid run.
fn write_recording(
    cfg: &CampaignConfig,
    rrd: &RrdOutput,
    rep: &CampaignReport,
    models: &[TrainedModels],
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
    let bytes = file.finish()?;
    wrote_recording(
        out,
        &rrd.path,
        bytes,
        &format!("; representative run {}", pick.title()),
    )?;
    Ok(())
}
