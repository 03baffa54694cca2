//! The campaign recording: every held-out hybrid run's error series, one representative run
//! replayed in full (machine, paths, arrows, thermal history), and the report.
//!
//! Structure:
//! - `runs/seed<s>/<state>/<diagonal>/{before,after}`: |E| (µm) of every held-out run of the
//!   hybrid predictor at its measurement points, on `sample`, `diagonal_mm` and `sim_time`
//!   (sent as columns: one chunk per series);
//! - the representative run under the same entities as a single run's recording (`machine/**`,
//!   `paths/**`, `errors/**`, `thermal/**`, `events`): the first seed's PPP body diagonal at the
//!   held-out state where it is worst before compensation, with the thermal history leading to
//!   that state (sensors and nodes every [`super::RecordSettings::history_sample_s`]). It is
//!   re-executed with the seed's trained hybrid model and must reproduce the evaluated run's
//!   points exactly (checked);
//! - `report`: the campaign summary and the table of hybrid runs (markdown).

use crate::predict::controller::Compensator;
use crate::predict::predictor::ModelKind;
use crate::report::norm;
use crate::studies::calibration::{evaluation_states, run_at_state_observed};
use crate::studies::campaign::{
    diagonal_plans, eval_noise_seed, headline, CampaignReport, RunReport, TrainedModels, PREDICTORS,
};
use vmc_machine::machine::MachineSpec;
use vmc_machine::sim::CollectPoints;

use super::{Diagonal, RecordError, RecordSettings, Recorder, RrdFile};

/// The run shown in full in a campaign recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Representative {
    /// Machine seed.
    pub seed: u64,
    /// Diagonal name (`PPP`, …).
    pub diagonal: String,
    /// Thermal state name.
    pub state: String,
}

impl Representative {
    /// Short title, e.g. `seed 1, PPP at eval_ambient_swing@4h`.
    pub fn title(&self) -> String {
        format!("seed {}, {} at {}", self.seed, self.diagonal, self.state)
    }
}

/// Picks the representative run: first seed, hybrid, body diagonal PPP (or the first diagonal),
/// the state with the largest RMS |E| before compensation.
pub fn pick_representative(rep: &CampaignReport) -> Option<Representative> {
    let seed = rep.runs.first()?.seed;
    let hybrid: Vec<&RunReport> = rep
        .runs
        .iter()
        .filter(|r| r.seed == seed && r.predictor == ModelKind::Hybrid)
        .collect();
    let diag = if hybrid.iter().any(|r| r.diagonal == "PPP") {
        "PPP".to_string()
    } else {
        hybrid.first()?.diagonal.clone()
    };
    let best = hybrid
        .iter()
        .filter(|r| r.diagonal == diag)
        .max_by(|a, b| a.rms_before_um.total_cmp(&b.rms_before_um))?;
    Some(Representative {
        seed,
        diagonal: diag,
        state: best.thermal_state.clone(),
    })
}

/// An entity path part from a free name: letters, digits, `_`, `-` kept, the rest `_`.
fn part(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Writes the campaign recording into `file`. Returns the representative run.
pub fn record_campaign(
    file: &RrdFile,
    spec: &MachineSpec,
    rep: &CampaignReport,
    models: &[TrainedModels],
    settings: RecordSettings,
) -> Result<Representative, RecordError> {
    let rec = file.stream();
    let plans = diagonal_plans(spec).map_err(|e| RecordError::Replay(e.to_string()))?;
    let diagonals: Vec<(&str, Option<Diagonal>)> = plans
        .iter()
        .map(|(n, p)| (*n, Diagonal::of_plan(p)))
        .collect();
    // Every held-out hybrid run: |E| before and after.
    rec.reset_time();
    for r in rep.runs.iter().filter(|r| r.predictor == ModelKind::Hybrid) {
        let base = format!(
            "runs/seed{}/{}/{}",
            r.seed,
            part(&r.thermal_state),
            part(&r.diagonal)
        );
        let diag = diagonals
            .iter()
            .find(|(n, _)| *n == r.diagonal)
            .and_then(|(_, d)| *d);
        let pts = &r.samples;
        if pts.is_empty() {
            continue;
        }
        let mut index = vec![
            rerun::TimeColumn::new_duration_secs("sim_time", pts.iter().map(|p| p.time_s)),
            rerun::TimeColumn::new_sequence("sample", (0..pts.len()).map(|i| i as i64)),
        ];
        if let Some(d) = diag {
            index.push(rerun::TimeColumn::new_sequence(
                "diagonal_mm",
                pts.iter()
                    .map(|p| d.position_mm(p.commanded_mm).round() as i64),
            ));
        }
        let before: Vec<f64> = pts.iter().map(|p| norm(p.error_before_um)).collect();
        let after: Vec<f64> = pts
            .iter()
            .map(|p| p.error_after_um.map(norm).unwrap_or(f64::NAN))
            .collect();
        for (sub, vals, label, rgb) in [
            ("before", before, "before (every run)", [235, 70, 55]),
            ("after", after, "after (every run)", [60, 210, 100]),
        ] {
            let entity = format!("{base}/{sub}");
            // One legend entry per group: every series of a group has the same name.
            rec.log_static(
                entity.clone(),
                &rerun::SeriesLines::new()
                    .with_names([label])
                    .with_colors([rerun::Color::from_rgb(rgb[0], rgb[1], rgb[2])])
                    .with_widths([1.0]),
            )
            .map_err(|e| file.err(e))?;
            let cols = rerun::Scalars::new(vals)
                .columns_of_unit_batches()
                .map_err(|e| file.err(e))?;
            rec.send_columns(entity, index.clone(), cols)
                .map_err(|e| file.err(e))?;
        }
    }

    // The representative run, replayed in full.
    let pick = pick_representative(rep)
        .ok_or_else(|| RecordError::Replay("the campaign has no hybrid runs".into()))?;
    let states = evaluation_states(spec, pick.seed);
    let si = states
        .iter()
        .position(|s| s.name == pick.state)
        .ok_or_else(|| RecordError::Replay(format!("unknown state {}", pick.state)))?;
    let di = plans
        .iter()
        .position(|(n, _)| *n == pick.diagonal)
        .ok_or_else(|| RecordError::Replay(format!("unknown diagonal {}", pick.diagonal)))?;
    let model = models
        .iter()
        .find(|m| m.seed == pick.seed)
        .ok_or_else(|| RecordError::Replay(format!("no model for seed {}", pick.seed)))?;
    let names: Vec<String> = spec.sensors.iter().map(|s| s.name.clone()).collect();
    let mut ctrl = Compensator::for_machine(model.hybrid.clone(), &names)
        .map_err(|e| RecordError::Replay(e.to_string()))?;
    let mut recorder = Recorder::new(file, spec, settings, diagonals[di].1)?;
    let mut collect = CollectPoints::default();
    run_at_state_observed(
        spec,
        pick.seed,
        eval_noise_seed(pick.seed, si, di),
        &states[si],
        &plans[di].1,
        Some(&mut ctrl),
        &mut vmc_machine::sim::Tee(&mut recorder, &mut collect),
        Some(settings.history_sample_s),
    )
    .map_err(|e| RecordError::Replay(e.to_string()))?;
    let evaluated = rep
        .runs
        .iter()
        .find(|r| {
            r.predictor == ModelKind::Hybrid
                && r.seed == pick.seed
                && r.diagonal == pick.diagonal
                && r.thermal_state == pick.state
        })
        .map(|r| &r.samples);
    if evaluated != Some(&collect.points) {
        return Err(RecordError::Replay(format!(
            "the replay of {} did not reproduce the evaluated run's points",
            pick.title()
        )));
    }
    recorder.finish(Some(&campaign_markdown(rep, &pick, settings.magnify)))?;
    Ok(pick)
}

/// The campaign report as markdown: headline per predictor and the hybrid runs.
pub fn campaign_markdown(rep: &CampaignReport, pick: &Representative, magnify: f64) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "# vmc-twin campaign on {}\n\nCalibrated on {}; evaluated on the held-out states {}.\n\n",
        rep.machine,
        rep.calibration_cycles.join(", "),
        rep.evaluation_states.join(", ")
    ));
    s.push_str(&format!(
        "3-D view: **{}**, hybrid predictor in the loop, errors magnified ×{magnify:.0}. \
         Time series: |E| of every held-out hybrid run before (red) and after (green) \
         compensation along the diagonal (timeline `diagonal_mm`; switch to `sim_time` to \
         see the thermal history).\n\n",
        pick.title()
    ));
    s.push_str("| predictor | runs | median reduction of RMS abs E | worst run | max residual abs E (µm) | mean prediction RMSE (µm) |\n|---|---|---|---|---|---|\n");
    for p in PREDICTORS {
        if let Some(h) = headline(&rep.runs, p) {
            s.push_str(&format!(
                "| {} | {} | {:.1} % | {:.1} % | {:.2} | {:.2} |\n",
                p.name(),
                h.runs,
                h.median_reduction * 100.0,
                h.worst_reduction * 100.0,
                h.max_after_um,
                h.mean_rmse_um
            ));
        }
    }
    s.push_str("\n## Hybrid predictor, every held-out run (µm)\n\n| seed | state | diagonal | RMS abs E before | after | reduction | max abs E after |\n|---|---|---|---|---|---|---|\n");
    for r in rep.runs.iter().filter(|r| r.predictor == ModelKind::Hybrid) {
        s.push_str(&format!(
            "| {} | {} | {} | {:.2} | {:.2} | {:.1} % | {:.2} |\n",
            r.seed,
            r.thermal_state,
            r.diagonal,
            r.rms_before_um,
            r.rms_after_um,
            r.reduction * 100.0,
            r.max_after_um
        ));
    }
    s
}
