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
use vmc_identify::identify::{
    identify as fit, placements_in, Identification, IdentifyOptions, Observation, Relation, Status,
};
use vmc_identify::order::{choose_order, parameter_set, OrderChoice, OrderOptions};
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
    /// Highest harmonic order of rotary motion errors to fit on every axis (0 or 1: none);
    /// `None`: chosen per axis from the data by cross-validation.
    pub harmonics: Option<u32>,
    /// How the order is chosen when `harmonics` is `None`.
    pub order: OrderOptions,
    /// Held-out poses.
    pub heldout_poses: usize,
    /// Radius of the judged region, mm (default: from the machine's travel).
    pub judge_radius_mm: Option<f64>,
    /// Height of the judged region, mm (default: from the machine's travel).
    pub judge_height_mm: Option<f64>,
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
    harmonic_orders: Vec<u32>,
    order_choice: Option<OrderChoice>,
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
    heldout: HeldOut,
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
    let mut obs: Vec<Observation> = file.observations.clone();
    for o in &mut obs {
        o.cov_mm2 += Matrix3::identity() * COV_FLOOR_MM2;
    }
    let mut chosen = None;
    if let Some(k) = cfg.design_configs {
        // The design sees the nominal sensitivity only; with the order still to be chosen it
        // designs for the second harmonics on every axis.
        let design_set = parameter_set(&geom, &vec![cfg.harmonics.unwrap_or(2); geom.rotary.len()])
            .with_placements(placements_in(&obs));
        let d = d_optimal(&geom, &design_set, &obs, k).with_context(|| name.clone())?;
        obs = d.chosen.iter().map(|&i| obs[i]).collect();
        chosen = Some(d.chosen);
    }
    let t0 = Instant::now();
    let (order_choice, orders) = model_orders(cfg, &geom, &obs).with_context(|| name.clone())?;
    // The relocated sphere's offsets are fitted with the machine's errors and written with
    // them; they never enter a compensation.
    let set = parameter_set(&geom, &orders).with_placements(placements_in(&obs));
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
        radius_mm: cfg.judge_radius_mm,
        height_mm: cfg.judge_height_mm,
        ..HeldOutPlan::default()
    };
    let (held, judged) = judge_poses(spec, &truth, &model, &plan)?;
    let mut text = Vec::new();
    print_report(&mut text, spec, &name, &id, &chosen, time_ms, &held, seed)?;
    let text = order_report(&order_choice, &orders, &geom, text)?;
    out.write_all(&text)?;
    let result = IdentifiedFile {
        machine: spec.machine.name.clone(),
        data: name,
        configurations_used: obs.len(),
        design_chosen_rows: chosen,
        harmonic_orders: orders.clone(),
        order_choice,
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
        heldout: held.clone(),
    };
    let json = serde_json::to_string_pretty(&result)?;
    files::write_atomic(&cfg.out, json.as_bytes(), cfg.force)?;
    writeln!(out, "→ {}", cfg.out.display())?;
    if let Some(rrd) = &cfg.rrd {
        let id = format!(
            "vmc-twin identify {} on {} harmonics {:?} design {:?} held-out seed {seed}",
            result.data, spec.machine.name, orders, cfg.design_configs
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
    writeln!(
        out,
        "  over the cylinder r ≤ {:.0} mm, h ≤ {:.0} mm on the table, where the axes reach:",
        held.region_mm[0], held.region_mm[1]
    )?;
    for r in &held.regions {
        writeln!(
            out,
            "    {:<6} {:>4} poses: {:.1} µm → {:.2} µm mean, {:.2} µm max; {:.1} % characterised",
            r.region.name(),
            r.poses,
            r.before_mean_um,
            r.after_mean_um,
            r.after_max_um,
            r.characterised_share * 100.0
        )?;
    }
    Ok(())
}

/// The harmonic orders per rotary axis: fixed by `--harmonics`, or chosen from the data (with
/// the candidates' scores).
fn model_orders(
    cfg: &IdentifyConfig,
    geom: &vmc_identify::chain::Geometry,
    obs: &[Observation],
) -> Result<(Option<OrderChoice>, Vec<u32>)> {
    Ok(match cfg.harmonics {
        Some(h) => (None, vec![h; geom.rotary.len()]),
        None => {
            let c = choose_order(geom, obs, &cfg.order)?;
            let orders = c.orders.clone();
            (Some(c), orders)
        }
    })
}

/// Puts the model-order lines in front of the report `text`.
fn order_report(
    choice: &Option<OrderChoice>,
    orders: &[u32],
    geom: &vmc_identify::chain::Geometry,
    text: Vec<u8>,
) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    let axes: Vec<String> = geom
        .rotary
        .iter()
        .zip(orders)
        .map(|(r, h)| format!("{} {}", r.axis.letter(), h))
        .collect();
    match choice {
        None => writeln!(
            out,
            "model order fixed by --harmonics: highest harmonic per rotary axis {}",
            axes.join(", ")
        )?,
        Some(c) => {
            writeln!(
                out,
                "model order from the data ({}-fold cross-validation over configurations, seed {}): highest harmonic per rotary axis {} (0: location errors only)",
                c.folds,
                c.seed,
                axes.join(", ")
            )?;
            writeln!(
                out,
                "  candidates (score: mean squared whitened prediction error per held-out reading; chosen: fewest parameters within one standard error of the best):"
            )?;
            for (i, cand) in c.candidates.iter().enumerate() {
                let mark = match (i == c.chosen, i == c.best) {
                    (true, true) => " ← chosen, best",
                    (true, false) => " ← chosen",
                    (false, true) => " ← best",
                    _ => "",
                };
                let score = match (cand.cv_score, cand.cv_std_error) {
                    (Some(s), Some(e)) => format!("{s:>10.1} ± {e:<8.1}"),
                    _ => format!("{:>21}", "too few readings"),
                };
                writeln!(
                    out,
                    "    orders {:?} {:>3} parameters {score}{mark}",
                    cand.orders, cand.n_params
                )?;
            }
        }
    }
    out.extend(text);
    Ok(out)
}
