//! The campaign's report: one [`RunReport`] per run, the whole [`CampaignReport`] (written as
//! `report.json`), headline figures and the terminal tables — the summary and aggregates first,
//! the per-run table on request.

use std::io::Write;

use serde::Serialize;

use crate::predict::metrics::Metrics;
use crate::predict::predictor::{ModelKind, TrainSummary};
use crate::report::error_stats;
use crate::sim::PointRecord;

/// The predictors of a campaign, in report order.
pub const PREDICTORS: [ModelKind; 3] =
    [ModelKind::Hybrid, ModelKind::Volumetric, ModelKind::Linear];

/// One evaluated run: one predictor, one diagonal, one thermal state, one seed.
#[derive(Debug, Clone, Serialize)]
pub struct RunReport {
    /// The predictor's model class (`hybrid`, `volumetric` or `linear` in the file).
    pub predictor: ModelKind,
    /// `XY`, `YZ`, `XZ`, `PPP`, `NPP`, `PNP`, `PPN`.
    pub diagonal: String,
    /// Thermal state (`cold`, `<cycle>@<h>h`).
    pub thermal_state: String,
    /// Machine seed.
    pub seed: u64,
    /// Measurement points.
    pub points: usize,
    /// RMS of |E| without compensation, µm.
    pub rms_before_um: f64,
    /// RMS of |E| with compensation, µm.
    pub rms_after_um: f64,
    /// Max |E| without compensation, µm.
    pub max_before_um: f64,
    /// Max |E| with compensation, µm.
    pub max_after_um: f64,
    /// 1 − RMS after / RMS before, of |E| (fraction).
    pub reduction: f64,
    /// 1 − max after / max before, of |E| (fraction).
    pub max_reduction: f64,
    /// RMS of Ex, Ey, Ez before, µm.
    pub rms_before_xyz_um: [f64; 3],
    /// RMS of Ex, Ey, Ez after, µm.
    pub rms_after_xyz_um: [f64; 3],
    /// Max |Ex|, |Ey|, |Ez| before, µm.
    pub max_before_xyz_um: [f64; 3],
    /// Max |Ex|, |Ey|, |Ez| after, µm.
    pub max_after_xyz_um: [f64; 3],
    /// RMS of the thermal part of |E| (truth: the error minus the same point's error with the
    /// machine at its reference temperature), µm; absent when the points do not carry it.
    pub rms_thermal_um: Option<f64>,
    /// RMS |E| after compensation as a share of [`Self::rms_thermal_um`] (fraction) for a warm
    /// run (thermal part RMS ≥ [`WARM_RUN_MIN_THERMAL_UM`]); absent for a cold one. Above 1,
    /// compensating left more error than a perfect cold-geometry model would.
    pub residual_share_of_thermal: Option<f64>,
    /// Prediction: mean absolute deviation, µm.
    pub mad_um: f64,
    /// Prediction: mean|e| / mean|y| (fraction).
    pub mape: Option<f64>,
    /// Prediction: RMSE, µm.
    pub rmse_um: f64,
    /// Prediction: coefficient of determination.
    pub r2: Option<f64>,
    /// The measurement points of the run (for recordings; not written to report.json).
    #[serde(skip)]
    pub samples: Vec<PointRecord>,
}

/// One cycle of the calibration plan.
#[derive(Debug, Clone, Serialize)]
pub struct PlannedCycle {
    /// Cycle name.
    pub name: String,
    /// Machine time, h (measurement blocks included).
    pub hours: f64,
    /// What the cycle is for.
    pub purpose: String,
}

/// The whole campaign's result.
#[derive(Debug, Clone, Serialize)]
pub struct CampaignReport {
    /// Machine name.
    pub machine: String,
    /// Calibration cycles (used for training).
    pub calibration_cycles: Vec<String>,
    /// The calibration plan: each cycle's machine time and purpose.
    pub calibration_plan: Vec<PlannedCycle>,
    /// Held-out evaluation states.
    pub evaluation_states: Vec<String>,
    /// Training summaries, per seed and predictor.
    pub training: Vec<(u64, TrainSummary)>,
    /// Every evaluated run.
    pub runs: Vec<RunReport>,
    /// Whether the hybrid used the commanded spindle speed (`--spindle-speed`, opt-in; absent
    /// from the file when not).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub hybrid_uses_spindle_speed: bool,
}

/// A run is warm when the RMS of its error's thermal part is at least this, µm: below it the
/// residual is the cold geometry's and the noise's, and a share of the thermal part says
/// nothing.
pub const WARM_RUN_MIN_THERMAL_UM: f64 = 1.0;

/// Summarises a compensated run.
pub fn run_report(
    predictor: ModelKind,
    diagonal: &str,
    state: &str,
    seed: u64,
    points: &[PointRecord],
) -> Option<RunReport> {
    let before: Vec<[f64; 3]> = points.iter().map(|p| p.error_before_um).collect();
    let after: Vec<[f64; 3]> = points.iter().filter_map(|p| p.error_after_um).collect();
    let b = error_stats(&before)?;
    let a = error_stats(&after)?;
    let mut y = Vec::with_capacity(3 * points.len());
    let mut yhat = Vec::with_capacity(3 * points.len());
    for p in points {
        let q = p.compensated_command_mm?;
        for ((e, c), qk) in p.error_before_um.iter().zip(&p.commanded_mm).zip(&q) {
            y.push(*e);
            yhat.push((c - qk) * 1e3);
        }
    }
    let m = Metrics::of(&y, &yhat).ok()?;
    let thermal: Vec<[f64; 3]> = points.iter().filter_map(|p| p.thermal_part_um).collect();
    let rms_thermal_um = (thermal.len() == points.len())
        .then(|| error_stats(&thermal).map(|s| s.rms_um[3]))
        .flatten();
    Some(RunReport {
        predictor,
        diagonal: diagonal.into(),
        thermal_state: state.into(),
        seed,
        points: points.len(),
        rms_before_um: b.rms_um[3],
        rms_after_um: a.rms_um[3],
        max_before_um: b.max_abs_um[3],
        max_after_um: a.max_abs_um[3],
        reduction: 1.0 - a.rms_um[3] / b.rms_um[3],
        max_reduction: 1.0 - a.max_abs_um[3] / b.max_abs_um[3],
        rms_before_xyz_um: [b.rms_um[0], b.rms_um[1], b.rms_um[2]],
        rms_after_xyz_um: [a.rms_um[0], a.rms_um[1], a.rms_um[2]],
        max_before_xyz_um: [b.max_abs_um[0], b.max_abs_um[1], b.max_abs_um[2]],
        max_after_xyz_um: [a.max_abs_um[0], a.max_abs_um[1], a.max_abs_um[2]],
        rms_thermal_um,
        residual_share_of_thermal: rms_thermal_um
            .filter(|t| *t >= WARM_RUN_MIN_THERMAL_UM)
            .map(|t| a.rms_um[3] / t),
        mad_um: m.mad,
        mape: m.mape,
        rmse_um: m.rmse,
        r2: m.r2,
        samples: points.to_vec(),
    })
}

/// Median of a list (NaN-free); None if empty.
pub fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

/// Headline figures of a set of runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Headline {
    /// Runs in the set.
    pub runs: usize,
    /// Median of the runs' reductions of RMS |E| (fraction).
    pub median_reduction: f64,
    /// Smallest reduction of a run (fraction).
    pub worst_reduction: f64,
    /// Largest |E| after compensation over all runs, µm.
    pub max_after_um: f64,
    /// Mean of the runs' prediction RMSE, µm.
    pub mean_rmse_um: f64,
    /// Largest residual share of the thermal part over the warm runs (fraction; None without
    /// a warm run).
    pub worst_residual_share: Option<f64>,
}

impl Headline {
    /// The figures of `runs`; None if there are none.
    pub fn of<'a>(runs: impl IntoIterator<Item = &'a RunReport>) -> Option<Self> {
        let r: Vec<&RunReport> = runs.into_iter().collect();
        if r.is_empty() {
            return None;
        }
        let mut red: Vec<f64> = r.iter().map(|r| r.reduction).collect();
        let worst = red.iter().cloned().fold(f64::INFINITY, f64::min);
        Some(Self {
            runs: r.len(),
            median_reduction: median(&mut red)?,
            worst_reduction: worst,
            max_after_um: r.iter().map(|r| r.max_after_um).fold(0.0, f64::max),
            mean_rmse_um: r.iter().map(|r| r.rmse_um).sum::<f64>() / r.len() as f64,
            worst_residual_share: r
                .iter()
                .filter_map(|r| r.residual_share_of_thermal)
                .max_by(f64::total_cmp),
        })
    }
}

/// The headline figures of one predictor over all runs.
pub fn headline(runs: &[RunReport], predictor: ModelKind) -> Option<Headline> {
    Headline::of(runs.iter().filter(|r| r.predictor == predictor))
}

/// Writes what a person reads first: the campaign's set-up, the headline figures per predictor,
/// then median reduction and max residual per predictor × diagonal and per predictor × thermal
/// state.
///
/// # Errors
/// The writer's.
pub fn write_campaign_summary(rep: &CampaignReport, out: &mut dyn Write) -> std::io::Result<()> {
    let hours: f64 = rep.calibration_plan.iter().map(|c| c.hours).sum();
    writeln!(
        out,
        "vmc-twin campaign on {}: calibration plan of {} cycles, {hours:.0} machine hours per machine:",
        rep.machine,
        rep.calibration_plan.len(),
    )?;
    for c in &rep.calibration_plan {
        writeln!(out, "  {:<20} {:>4.1} h  {}", c.name, c.hours, c.purpose)?;
    }
    writeln!(
        out,
        "evaluated on held-out states {}",
        rep.evaluation_states.join(", ")
    )?;
    if rep.hybrid_uses_spindle_speed {
        writeln!(
            out,
            "hybrid: with the commanded spindle speed as heat input (--spindle-speed, opt-in)"
        )?;
    }
    writeln!(out, "summary over all diagonals, states and seeds:")?;
    for p in PREDICTORS {
        if let Some(h) = headline(&rep.runs, p) {
            writeln!(out, "  {:<10} runs {:>4}  median reduction {:>5.1} %  worst run {:>5.1} %  max residual |E| {:>5.2} µm  worst residual/thermal part {:>5.1} %  mean prediction RMSE {:>5.2} µm",
                p.name(), h.runs, h.median_reduction * 100.0, h.worst_reduction * 100.0, h.max_after_um,
                h.worst_residual_share.unwrap_or(f64::NAN) * 100.0, h.mean_rmse_um)?;
        }
    }
    let mut diagonals: Vec<&str> = Vec::new();
    for r in &rep.runs {
        if !diagonals.contains(&r.diagonal.as_str()) {
            diagonals.push(&r.diagonal);
        }
    }
    let states: Vec<&str> = rep.evaluation_states.iter().map(String::as_str).collect();
    writeln!(out, "by diagonal: median reduction % / max residual |E| µm")?;
    write_aggregate(rep, out, &diagonals, |r, d| r.diagonal == d)?;
    writeln!(
        out,
        "by thermal state: median reduction % / max residual |E| µm / worst residual share of the thermal part %"
    )?;
    write_aggregate(rep, out, &states, |r, s| r.thermal_state == s)?;
    writeln!(out, "(reduction = 1 − RMS|E'|/RMS|E| of a run, E' compensated; residual share = RMS|E'| / RMS of the error's thermal part, on warm runs (thermal part ≥ {WARM_RUN_MIN_THERMAL_UM} µm RMS); every run: --runs, or report.json)")?;
    Ok(())
}

/// One table: a row per group, a column per predictor, each cell `median red % / max |E'| µm`
/// over the runs of the group.
fn write_aggregate(
    rep: &CampaignReport,
    out: &mut dyn Write,
    groups: &[&str],
    in_group: impl Fn(&RunReport, &str) -> bool,
) -> std::io::Result<()> {
    let label = groups.iter().map(|g| g.len()).max().unwrap_or(0);
    let predictors: Vec<ModelKind> = PREDICTORS
        .into_iter()
        .filter(|p| rep.runs.iter().any(|r| r.predictor == *p))
        .collect();
    write!(out, "  {:<label$}", "")?;
    for p in &predictors {
        write!(out, " {:>19}", p.name())?;
    }
    writeln!(out)?;
    for g in groups {
        write!(out, "  {g:<label$}")?;
        for p in &predictors {
            let cell = Headline::of(
                rep.runs
                    .iter()
                    .filter(|r| r.predictor == *p && in_group(r, g)),
            )
            .map(|h| match h.worst_residual_share {
                Some(s) => format!(
                    "{:.1} / {:.2} / {:.0}",
                    h.median_reduction * 100.0,
                    h.max_after_um,
                    s * 100.0
                ),
                None => format!("{:.1} / {:.2}", h.median_reduction * 100.0, h.max_after_um),
            })
            .unwrap_or_else(|| "-".into());
            write!(out, " {cell:>19}")?;
        }
        writeln!(out)?;
    }
    Ok(())
}

/// Writes every run as one row: errors before and after compensation, reduction and prediction
/// metrics.
///
/// # Errors
/// The writer's.
pub fn write_run_table(rep: &CampaignReport, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "{:<10} {:<5} {:<24} {:>4} | {:>7} {:>7} {:>7} {:>7} | {:>7} {:>7} {:>7} {:>7} | {:>6} | {:>6} {:>7} | {:>6} {:>6} {:>6} {:>6}",
        "predictor", "diag", "thermal state", "seed",
        "rmsEx", "rmsEy", "rmsEz", "rms|E|", "rmsEx'", "rmsEy'", "rmsEz'", "rms|E'|", "red%", "rmsTh", "res/th%", "MAD", "MAPE%", "RMSE", "R2")?;
    for r in &rep.runs {
        writeln!(out, "{:<10} {:<5} {:<24} {:>4} | {:>7.2} {:>7.2} {:>7.2} {:>7.2} | {:>7.2} {:>7.2} {:>7.2} {:>7.2} | {:>6.1} | {:>6.2} {:>7.1} | {:>6.2} {:>6.1} {:>6.2} {:>6.3}",
            r.predictor.name(), r.diagonal, r.thermal_state, r.seed,
            r.rms_before_xyz_um[0], r.rms_before_xyz_um[1], r.rms_before_xyz_um[2], r.rms_before_um,
            r.rms_after_xyz_um[0], r.rms_after_xyz_um[1], r.rms_after_xyz_um[2], r.rms_after_um,
            r.reduction * 100.0, r.rms_thermal_um.unwrap_or(f64::NAN),
            r.residual_share_of_thermal.unwrap_or(f64::NAN) * 100.0, r.mad_um, r.mape.unwrap_or(f64::NAN) * 100.0, r.rmse_um, r.r2.unwrap_or(f64::NAN))?;
    }
    writeln!(out, "(µm; primed = compensated; red% = 1 − RMS|E'|/RMS|E|; rmsTh = RMS of the error's thermal part; res/th% = RMS|E'|/rmsTh on warm runs; MAD/MAPE/RMSE/R2 of the predicted vs true error, components pooled; MAPE = mean|e|/mean|y|)")?;
    Ok(())
}
