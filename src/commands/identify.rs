//! `vmc-twin identify`: identify the geometric errors of a five-axis machine from a probing
//! file, print the identifiability report and the parameters, judge the identified model on
//! held-out poses and write it all (JSON).

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use nalgebra::Matrix3;
use serde::Serialize;

use crate::files;
use vmc_identify::chain::Pose;
use vmc_identify::design::d_optimal;
use vmc_identify::errors::ParameterSet;
use vmc_identify::identify::{
    identify as fit, Identification, IdentifyOptions, Observation, Relation, Status,
};
use vmc_machine::fiveaxis::campaign::parse_csv;
use vmc_machine::fiveaxis::heldout::{judge_poses, HeldOut, HeldOutPlan};
use vmc_machine::fiveaxis::{FiveAxisSpec, TrueMachine};

/// What to identify, validated.
pub struct IdentifyConfig {
    /// Probing file.
    pub data: PathBuf,
    /// The machine (nominal geometry for identification; truth for the judge only).
    pub machine: FiveAxisSpec,
    /// Output JSON.
    pub out: PathBuf,
    /// Choose K configurations D-optimally.
    pub design_configs: Option<usize>,
    /// Highest harmonic order of rotary motion errors to fit (0 or 1: none).
    pub harmonics: u32,
    /// Held-out poses.
    pub heldout_poses: usize,
    /// Realisation for the judge (default: the file's).
    pub seed: Option<u64>,
    /// Overwrite.
    pub force: bool,
    /// A Rerun recording of the held-out error field to write.
    pub rrd: Option<super::RrdOutput>,
}

/// One parameter in the output, in µm or µrad.
#[derive(Debug, Serialize)]
struct ParameterOut {
    name: String,
    unit: &'static str,
    value: f64,
    std_uncertainty: f64,
    std_uncertainty_scaled: f64,
    status: Status,
}

/// The output file.
#[derive(Debug, Serialize)]
struct IdentifiedFile {
    machine: String,
    data: String,
    configurations_used: usize,
    design_chosen_rows: Option<Vec<usize>>,
    n_params: usize,
    rank: usize,
    condition_number: f64,
    relations: Vec<Relation>,
    parameters: Vec<ParameterOut>,
    chi2: f64,
    dof: usize,
    rms_residual_um: f64,
    linearisation_error_um: f64,
    identification_time_ms: f64,
    heldout_seed: u64,
    heldout_poses: usize,
    heldout_before_mean_um: f64,
    heldout_before_max_um: f64,
    heldout_characterised_share: f64,
    heldout_mean_residual_um: f64,
    heldout_max_residual_um: f64,
}

/// A tiny variance added to each centre covariance (0.01 µm)², so that noise-free files stay
/// usable (their covariance is zero).
const COV_FLOOR_MM2: f64 = 1e-10;

/// Runs the identification and the judge, prints the report, writes the JSON.
///
/// # Errors
/// Unreadable or mismatched probing file, too few configurations, an output that may not be
/// written, a held-out judge without a seed.
pub fn identify(cfg: &IdentifyConfig, out: &mut dyn Write) -> Result<()> {
    files::check_writable(&cfg.out, cfg.force)?;
    if let Some(rrd) = &cfg.rrd {
        crate::record::check_rrd_path(&rrd.path, cfg.force)?;
    }
    let spec = &cfg.machine;
    let name = cfg.data.display().to_string();
    let text = files::read_named(&cfg.data, "probing file")?;
    let file = parse_csv(&text, spec).with_context(|| name.clone())?;
    if let Some(m) = &file.machine {
        anyhow::ensure!(
            m == &spec.machine.name,
            "{name}: probed on machine {m}, not {}: its configurations do not match this machine",
            spec.machine.name
        );
    }
    let geom = spec.geometry();
    let mut set = ParameterSet::location_and_assembly(&geom);
    if cfg.harmonics >= 2 {
        set = set.with_motion_harmonics(&geom, cfg.harmonics);
    }
    let mut obs: Vec<Observation> = file.observations.clone();
    for o in &mut obs {
        o.cov_mm2 += Matrix3::identity() * COV_FLOOR_MM2;
    }
    let mut chosen = None;
    if let Some(k) = cfg.design_configs {
        let d = d_optimal(&geom, &set, &obs, k).with_context(|| name.clone())?;
        obs = d.chosen.iter().map(|&i| obs[i]).collect();
        chosen = Some(d.chosen);
    }
    let t0 = Instant::now();
    let id = fit(&geom, &set, &obs, &IdentifyOptions::default()).with_context(|| name.clone())?;
    let time_ms = t0.elapsed().as_secs_f64() * 1e3;
    let seed = cfg.seed.or(file.seed).with_context(|| {
        format!("{name}: no `# seed:` line; give --seed for the held-out judge")
    })?;
    let truth = TrueMachine::new(spec, seed)?;
    let values = id.values();
    let model = |pose: &Pose| set.state_at(&values, pose);
    let plan = HeldOutPlan {
        poses: cfg.heldout_poses,
        ..HeldOutPlan::default()
    };
    let (held, judged) = judge_poses(spec, &truth, &model, &plan)?;
    let mut text = Vec::new();
    print_report(&mut text, spec, &name, &id, &chosen, time_ms, &held, seed)?;
    out.write_all(&text)?;
    let result = IdentifiedFile {
        machine: spec.machine.name.clone(),
        data: name,
        configurations_used: obs.len(),
        design_chosen_rows: chosen,
        n_params: id.n_params,
        rank: id.rank,
        condition_number: id.condition_number,
        relations: id.relations.clone(),
        parameters: id
            .estimates
            .iter()
            .map(|e| {
                let (unit, k) = if e.is_angle {
                    ("urad", 1e6)
                } else {
                    ("um", 1e3)
                };
                ParameterOut {
                    name: e.name.clone(),
                    unit,
                    value: e.value * k,
                    std_uncertainty: e.std_uncertainty * k,
                    std_uncertainty_scaled: e.std_uncertainty_scaled * k,
                    status: e.status,
                }
            })
            .collect(),
        chi2: id.chi2,
        dof: id.dof,
        rms_residual_um: id.rms_residual_mm * 1e3,
        linearisation_error_um: id.linearisation_error_mm * 1e3,
        identification_time_ms: time_ms,
        heldout_seed: seed,
        heldout_poses: held.poses,
        heldout_before_mean_um: held.before_mean_um,
        heldout_before_max_um: held.before_max_um,
        heldout_characterised_share: held.characterised_share,
        heldout_mean_residual_um: held.after_mean_um,
        heldout_max_residual_um: held.after_max_um,
    };
    let json = serde_json::to_string_pretty(&result)?;
    files::write_atomic(&cfg.out, json.as_bytes(), cfg.force)?;
    writeln!(out, "→ {}", cfg.out.display())?;
    if let Some(rrd) = &cfg.rrd {
        let id = format!(
            "vmc-twin identify {} on {} harmonics {} design {:?} held-out seed {seed}",
            result.data, spec.machine.name, cfg.harmonics, cfg.design_configs
        );
        let bytes = crate::record::fiveaxis::record_heldout(
            &rrd.path,
            cfg.force,
            &id,
            rrd.settings.magnify,
            spec,
            &judged,
            &String::from_utf8_lossy(&text),
        )?;
        super::wrote_recording(out, &rrd.path, bytes, "")?;
    }
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn print_report(
    out: &mut dyn Write,
    spec: &FiveAxisSpec,
    name: &str,
    id: &Identification,
    chosen: &Option<Vec<usize>>,
    time_ms: f64,
    held: &HeldOut,
    seed: u64,
) -> Result<()> {
    writeln!(
        out,
        "identification on {} from {name}: {} configurations",
        spec.machine.name, id.n_configs
    )?;
    if let Some(rows) = chosen {
        writeln!(
            out,
            "  D-optimal choice of {} configurations: rows {rows:?}",
            rows.len()
        )?;
    }
    writeln!(
        out,
        "identifiability: rank {} of {} parameters; condition number of the weighted, column-scaled S: {:.3e}",
        id.rank, id.n_params, id.condition_number
    )?;
    if id.relations.is_empty() {
        writeln!(
            out,
            "  every parameter is separated by these configurations"
        )?;
    }
    for r in &id.relations {
        writeln!(out, "  - {}", r.message)?;
    }
    writeln!(
        out,
        "parameters (standard uncertainty from the probe noise; in brackets scaled by √(χ²/dof)):"
    )?;
    for e in &id.estimates {
        let (unit, k) = if e.is_angle {
            ("µrad", 1e6)
        } else {
            ("µm", 1e3)
        };
        let status = match e.status {
            Status::Identified => "identified",
            Status::Merged => "merged (carries a combination)",
            Status::Fixed => "fixed at 0 (not separable)",
            Status::NoEffect => "fixed at 0 (no effect)",
        };
        writeln!(
            out,
            "  {:<14} {:>10.3} ± {:<6.3} [{:<6.3}] {unit:<5} {status}",
            e.name,
            e.value * k,
            e.std_uncertainty * k,
            e.std_uncertainty_scaled * k
        )?;
    }
    writeln!(
        out,
        "residual: χ² = {:.1} for {} degrees of freedom (χ²/dof = {:.2}; 1 = noise only), RMS {:.3} µm",
        id.chi2,
        id.dof,
        id.chi2 / id.dof.max(1) as f64,
        id.rms_residual_mm * 1e3
    )?;
    writeln!(
        out,
        "exact-model refinement: linearisation error {:.4} µm, parameters moved by at most {:.3} σ; identification {:.1} ms",
        id.linearisation_error_mm * 1e3,
        id.refinement_change_sigmas,
        time_ms
    )?;
    writeln!(
        out,
        "held-out judge ({} poses, realisation {seed}): volumetric error {:.1} µm mean, {:.1} µm max → {:.2} µm mean, {:.2} µm max with the identified model; {:.1} % characterised",
        held.poses,
        held.before_mean_um,
        held.before_max_um,
        held.after_mean_um,
        held.after_max_um,
        held.characterised_share * 100.0
    )?;
    Ok(())
}
