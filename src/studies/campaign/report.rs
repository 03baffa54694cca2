//! The campaign's report: one [`RunReport`] per run, the whole [`CampaignReport`] (written as
//! `report.json`), headline figures and the per-run table (the summary is in `summary`).

use std::io::Write;

use serde::{Deserialize, Serialize};

use crate::predict::metrics::Metrics;
use crate::predict::predictor::{ModelKind, TrainSummary};
use crate::report::error_stats;
use vmc_machine::sim::PointRecord;

use super::order_stats::{median_of_middle, Selector, StreamChanged, Wanted};

/// The predictors of a campaign, in report order.
pub const PREDICTORS: [ModelKind; 3] =
    [ModelKind::Hybrid, ModelKind::Volumetric, ModelKind::Linear];

/// One evaluated run: one predictor, one diagonal, one thermal state, one seed.
#[derive(Debug, Clone, Serialize, Deserialize)]
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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

/// Median of a list (in f64's total order; the mean of the two middle values of an even
/// number); None if empty.
pub fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    Some(median_of_middle(n, v[(n - 1) / 2], v[n / 2]))
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
        let runs: Vec<&RunReport> = runs.into_iter().collect();
        let mut h = HeadlineBuilder::default();
        // The same runs in the same order: the passes agree.
        replay(&mut h, runs.iter().copied()).ok()?;
        h.finish()
    }
}

/// Figures built from a campaign's runs fed in passes over the same runs in the same order:
/// [`RunPasses::push`] every run, then [`RunPasses::end_pass`], until it says done (see
/// [`replay`]).
pub trait RunPasses {
    /// Adds a run of the current pass.
    fn push(&mut self, r: &RunReport);

    /// Ends a pass; true when the figures are complete.
    ///
    /// # Errors
    /// A pass over other runs than the first one.
    fn end_pass(&mut self) -> Result<bool, StreamChanged>;
}

/// Feeds `runs` to `builder` pass after pass until it is done; gives the number of passes.
///
/// # Errors
/// The iterator gave other runs in a later pass.
pub fn replay<'a, B: RunPasses>(
    builder: &mut B,
    runs: impl Iterator<Item = &'a RunReport> + Clone,
) -> Result<u32, StreamChanged> {
    let mut passes = 0;
    loop {
        runs.clone().for_each(|r| builder.push(r));
        passes += 1;
        if builder.end_pass()? {
            return Ok(passes);
        }
    }
}

/// Builds a [`Headline`] from runs fed in passes ([`RunPasses`]): the sums and extremes in the first pass, the exact median in as many as it takes
/// (one for at most [`super::order_stats::KEEP_MAX`] runs), in memory that does not grow with
/// the runs.
#[derive(Debug, Clone)]
pub struct HeadlineBuilder {
    /// Passes ended.
    passes: u32,
    runs: usize,
    worst_reduction: f64,
    max_after_um: f64,
    /// Sum of the runs' RMSE in run order (from −0, as `Iterator::sum`).
    rmse_sum_um: f64,
    worst_residual_share: Option<f64>,
    median: Selector,
}

impl Default for HeadlineBuilder {
    fn default() -> Self {
        Self::with_keep_max(super::order_stats::KEEP_MAX)
    }
}

impl HeadlineBuilder {
    /// A builder whose median keeps at most `keep_max` values per search.
    pub fn with_keep_max(keep_max: usize) -> Self {
        Self {
            passes: 0,
            runs: 0,
            worst_reduction: f64::INFINITY,
            max_after_um: 0.0,
            rmse_sum_um: -0.0,
            worst_residual_share: None,
            median: Selector::with_keep_max(Wanted::Median, keep_max),
        }
    }

    /// The figures (after the pass that said done); None without runs.
    pub fn finish(&self) -> Option<Headline> {
        Some(Headline {
            runs: self.runs,
            median_reduction: self.median.median()?,
            worst_reduction: self.worst_reduction,
            max_after_um: self.max_after_um,
            mean_rmse_um: self.rmse_sum_um / self.runs as f64,
            worst_residual_share: self.worst_residual_share,
        })
    }
}

impl RunPasses for HeadlineBuilder {
    fn push(&mut self, r: &RunReport) {
        self.median.push(r.reduction);
        if self.passes > 0 {
            return;
        }
        self.runs += 1;
        self.worst_reduction = self.worst_reduction.min(r.reduction);
        self.max_after_um = self.max_after_um.max(r.max_after_um);
        self.rmse_sum_um += r.rmse_um;
        if let Some(s) = r.residual_share_of_thermal {
            self.worst_residual_share = Some(match self.worst_residual_share {
                Some(w) if w.total_cmp(&s).is_gt() => w,
                _ => s,
            });
        }
    }

    fn end_pass(&mut self) -> Result<bool, StreamChanged> {
        self.passes += 1;
        self.median.end_pass()
    }
}

/// The headline figures of one predictor over all runs.
pub fn headline(runs: &[RunReport], predictor: ModelKind) -> Option<Headline> {
    Headline::of(runs.iter().filter(|r| r.predictor == predictor))
}

/// Writes every run as one row: errors before and after compensation, reduction and prediction
/// metrics.
///
/// # Errors
/// The writer's.
pub fn write_run_table(rep: &CampaignReport, out: &mut dyn Write) -> std::io::Result<()> {
    write_run_table_head(out)?;
    for r in &rep.runs {
        write_run_row(r, out)?;
    }
    write_run_table_foot(out)
}

/// The run table's column heads.
///
/// # Errors
/// The writer's.
pub fn write_run_table_head(out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "{:<10} {:<5} {:<24} {:>4} | {:>7} {:>7} {:>7} {:>7} | {:>7} {:>7} {:>7} {:>7} | {:>6} | {:>6} {:>7} | {:>6} {:>6} {:>6} {:>6}",
        "predictor", "diag", "thermal state", "seed",
        "rmsEx", "rmsEy", "rmsEz", "rms|E|", "rmsEx'", "rmsEy'", "rmsEz'", "rms|E'|", "red%", "rmsTh", "res/th%", "MAD", "MAPE%", "RMSE", "R2")?;
    Ok(())
}

/// One row of the run table.
///
/// # Errors
/// The writer's.
pub fn write_run_row(r: &RunReport, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "{:<10} {:<5} {:<24} {:>4} | {:>7.2} {:>7.2} {:>7.2} {:>7.2} | {:>7.2} {:>7.2} {:>7.2} {:>7.2} | {:>6.1} | {:>6.2} {:>7.1} | {:>6.2} {:>6.1} {:>6.2} {:>6.3}",
            r.predictor.name(), r.diagonal, r.thermal_state, r.seed,
            r.rms_before_xyz_um[0], r.rms_before_xyz_um[1], r.rms_before_xyz_um[2], r.rms_before_um,
            r.rms_after_xyz_um[0], r.rms_after_xyz_um[1], r.rms_after_xyz_um[2], r.rms_after_um,
            r.reduction * 100.0, r.rms_thermal_um.unwrap_or(f64::NAN),
            r.residual_share_of_thermal.unwrap_or(f64::NAN) * 100.0, r.mad_um, r.mape.unwrap_or(f64::NAN) * 100.0, r.rmse_um, r.r2.unwrap_or(f64::NAN))
}

/// The run table's legend.
///
/// # Errors
/// The writer's.
pub fn write_run_table_foot(out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "(µm; primed = compensated; red% = 1 − RMS|E'|/RMS|E|; rmsTh = RMS of the error's thermal part; res/th% = RMS|E'|/rmsTh on warm runs; MAD/MAPE/RMSE/R2 of the predicted vs true error, components pooled; MAPE = mean|e|/mean|y|)")?;
    Ok(())
}
